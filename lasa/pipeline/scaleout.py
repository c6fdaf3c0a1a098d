"""Independent jobs by joblib or on a Dask cluster: pure, seeded, one torch thread each, results in order."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any, TypeVar

from tqdm.auto import tqdm

from lasa.base.errors import ConfigError

SCHEDULER_ENV = "LASA_SCHEDULER"
T = TypeVar("T")
R = TypeVar("R")


def scheduler_address(configured: str | None = None) -> str | None:
    """``configured``, else ``$LASA_SCHEDULER``, else None; ConfigError unless ``scheme://host:port``."""
    address = configured or os.environ.get(SCHEDULER_ENV) or None
    if address is not None and "://" not in address:
        raise ConfigError(
            f"Dask scheduler address must look like tcp://host:8786, got {address!r} "
            f"(from {'the config' if configured else SCHEDULER_ENV})"
        )
    return address


def _threaded(fn: Callable[..., R], item: Any, shared: Any) -> R:
    """Run one job with one torch thread (the worker may be a fresh process)."""
    from lasa.base.config import set_threads  # noqa: PLC0415 (torch loads in the worker)

    set_threads()
    return fn(item) if shared is None else fn(shared, item)


def run_jobs(
    fn: Callable[..., R],
    items: Sequence[T] | Iterable[T],
    scheduler: str | None = None,
    n_jobs: int = 1,
    progress: bool = False,
    desc: str = "jobs",
    timeout: str = "20s",
    shared: Any = None,
) -> list[R]:
    """``[fn(item) for item in items]`` (``fn(shared, item)`` with ``shared``, sent to each worker once) by
    joblib: ``n_jobs`` processes, or the Dask ``scheduler``'s workers (:func:`scheduler_address`)."""
    from joblib import Parallel, delayed, parallel_config  # noqa: PLC0415

    if int(n_jobs) != n_jobs or n_jobs < 1:
        raise ConfigError(f"n_jobs must be a positive integer, got {n_jobs!r}")
    jobs = [delayed(_threaded)(fn, item, shared) for item in items]
    address = scheduler_address(scheduler)

    def collect(parallel: Any) -> list[R]:
        return list(tqdm(parallel(jobs), total=len(jobs), desc=desc, disable=not progress))

    if address is None:
        return collect(Parallel(n_jobs=n_jobs, return_as="generator"))
    from dask.distributed import Client  # noqa: PLC0415 (only when a cluster is asked for)

    try:
        client = Client(address, timeout=timeout)
    except OSError as err:
        raise ConfigError(f"cannot reach the Dask scheduler at {address}: {err}") from err
    scatter = None if shared is None else [shared]
    with client, parallel_config(backend="dask", scatter=scatter):
        return collect(Parallel(n_jobs=-1, return_as="generator"))
