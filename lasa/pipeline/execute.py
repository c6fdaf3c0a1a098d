"""Execution: run a figure notebook headless with papermill, with checked parameters (``make figures``).
A config's ``common`` and stem sections are its parameters; the copy is written atomically, a failed
one kept as ``<name>.failed.ipynb`` and its writes to the figures undone."""

from __future__ import annotations

if __name__ == "__main__":  # the CLI: renderer and kernels pinned before the notebooks start
    from lasa.runtime import pin

    pin()

import argparse
import contextlib
import datetime
import os
import signal
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

# jsonschema's optional IRI format checker costs 1.3 s of import per run, for a format notebooks never use
sys.modules.setdefault("rfc3987_syntax", None)  # type: ignore[arg-type]

import papermill as pm  # noqa: E402
import yaml  # noqa: E402
from traitlets.config import Config  # noqa: E402

from lasa.base import journal  # noqa: E402
from lasa.base.errors import ArtifactError, ConfigError, NotebookError  # noqa: E402
from lasa.base.io import atomic_path, require_file  # noqa: E402
from lasa.base.paths import resolve  # noqa: E402
from lasa.pipeline.timings import append_run  # noqa: E402


def notebook_parameters(notebook: str | os.PathLike[str]) -> dict[str, Any]:
    """Names and default values of a notebook's ``parameters`` cell (ConfigError if it has none)."""
    if not (params := pm.inspect_notebook(str(notebook))):
        raise ConfigError(f"{notebook} has no cell tagged 'parameters'")
    return {name: info["default"] for name, info in params.items()}


def load_config(
    config: str | os.PathLike[str], notebook: str | os.PathLike[str], known: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The parameters a YAML config passes to ``notebook``: ``common`` plus its section, each in its cell
    (``known``: the cell's :func:`notebook_parameters`, if the caller has read them already)."""
    path = require_file(config, "it ships with the repository under configs/")
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        where = getattr(exc, "problem_mark", None)
        at = f" (line {where.line + 1})" if where is not None else ""
        raise ConfigError(f"{path} is not a YAML file{at}: {getattr(exc, 'problem', None) or exc}") from None
    if not isinstance(data, dict) or not all(isinstance(v, dict) for v in data.values()):
        raise ConfigError(f"{path} must map section names to parameter mappings")
    params = {**data.get("common", {}), **data.get(Path(notebook).stem, {})}
    known = notebook_parameters(notebook) if known is None else known
    if unknown := sorted(set(params) - set(known)):
        raise ConfigError(
            f"{path} passes unknown parameter(s) {unknown} to {Path(notebook).name}; "
            f"its parameters cell defines {sorted(known)}"
        )
    return params


def execute(
    notebook: str | os.PathLike[str],
    out: str | os.PathLike[str],
    parameters: dict[str, Any],
    cwd: str | os.PathLike[str],
    progress: bool = True,
) -> None:
    """papermill's run of ``notebook`` into ``out``, its kernel in ``cwd`` on Unix sockets in a folder
    of its own. Over TCP, jupyter_client picks free ports that the kernel binds a moment later, and
    kernels started side by side (``make figures``, the tests) now and then take each other's
    ("Address already in use", "Kernel died before replying to kernel_info")."""
    with tempfile.TemporaryDirectory(prefix="lasa-kernel-") as folder:
        sockets = Config({"KernelManager": {"transport": "ipc", "ip": os.path.join(folder, "kernel")}})
        pm.execute_notebook(
            str(notebook),
            str(out),
            parameters=parameters,
            kernel_name="python3",
            cwd=str(cwd),
            progress_bar=progress,
            config=sockets,
        )


def run_notebook(
    notebook: str | os.PathLike[str],
    config: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    overrides: dict[str, Any] | None = None,
    progress: bool = True,
) -> Path:
    """Run ``notebook`` with ``config``'s parameters and ``overrides`` into ``out_dir`` (``<stem>-<robot>``
    for a ``robot``); return its path. A failed run's writes are undone (:mod:`lasa.base.journal`)."""
    defaults = notebook_parameters(notebook)  # papermill reads the notebook once
    params = load_config(config, notebook, defaults)
    overrides = overrides or {}
    if unknown := sorted(set(overrides) - set(defaults)):
        raise ConfigError(f"unknown parameter(s) {unknown} for {Path(notebook).name}")
    params.update(overrides)
    robot = f"-{overrides['robot']}" if "robot" in overrides else ""
    out = Path(out_dir) / f"{Path(notebook).stem}{robot}.ipynb"
    failed = out.with_suffix(".failed.ipynb")
    figures = params.get("figures_dir", defaults.get("figures_dir"))
    with atomic_path(out) as tmp, _journaled(out, figures) as undo:
        try:
            execute(notebook, tmp, params, Path.cwd(), progress)
        except pm.PapermillExecutionError as exc:
            os.replace(tmp, failed)  # the partial run, under a name no Make rule takes for done
            raise NotebookError(str(notebook), exc.ename, str(exc.evalue), str(failed), undo()) from None
    failed.unlink(missing_ok=True)
    return out


@contextlib.contextmanager
def _journaled(out: Path, figures: Any) -> Iterator[Callable[[], str]]:
    """Journal the run's writes to its figures; yield their undo (what it restored); any exception runs it."""
    if not isinstance(figures, str | os.PathLike):  # a notebook without a figures folder
        yield lambda: ""
        return
    folder = out.with_name(f".{out.stem}.journal")
    undone: list[str] = []

    def undo() -> str:
        if not undone:
            undone.append(f"{journal.restore(folder)}")
            journal.discard(folder)
        return undone[0]

    try:
        with journal.recording(folder, resolve(figures)):
            yield undo
    except BaseException as exc:
        if not undone and folder.exists():
            exc.add_note(undo())
        raise
    journal.discard(folder)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point: run one notebook and report its wall time."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebook", help="the notebook to run, e.g. notebooks/04_fixed_expertise.ipynb")
    parser.add_argument("--config", required=True, help="the YAML config: configs/paper.yaml, quick.yaml ...")
    parser.add_argument("--out", required=True, help="folder of the executed copy")
    parser.add_argument("--robot", help="run for this robot (the notebook's `robot` parameter)")
    parser.add_argument(
        "--param", "-p", action="append", default=[], metavar="NAME=VALUE", help="a parameter, VALUE as YAML"
    )
    parser.add_argument("--timings", help="append {notebook, robot, seconds, start, end} (UTC) to this file")
    parser.add_argument("--no-progress", action="store_true", help="no cell progress bar")
    args = parser.parse_args(argv)
    # SIGTERM leaves by an exception, as Ctrl-C does: a killed run's writes are undone on the way out
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    started = datetime.datetime.now(datetime.UTC)
    start = time.perf_counter()
    try:
        overrides = {**parse_params(args.param), **({"robot": args.robot} if args.robot else {})}
        out = run_notebook(args.notebook, args.config, args.out, overrides, progress=not args.no_progress)
    except (ConfigError, ArtifactError, NotebookError) as exc:  # a cell's cause: traceback in the partial run
        print(f"error: {exc}", file=sys.stderr)
        return 1 if isinstance(exc, NotebookError) else 2
    except (KeyboardInterrupt, SystemExit) as exc:
        for note in getattr(exc, "__notes__", []):  # what the undo restored
            print(f"interrupted: {note}", file=sys.stderr)
        raise
    seconds = time.perf_counter() - start
    if args.timings:  # lasa.pipeline.timings reads them into benchmarks/results.json
        ended = datetime.datetime.now(datetime.UTC)
        append_run(args.timings, Path(args.notebook).stem, args.robot, seconds, started, ended)
    print(f"{out} ({seconds:.1f} s)")
    return 0


def parse_params(items: list[str]) -> dict[str, Any]:
    """``["name=value", ...]`` -> ``{name: yaml(value)}``; ConfigError for an item without a name."""
    out: dict[str, Any] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ConfigError(f"--param expects NAME=VALUE, got {item!r}")
        out[name.strip()] = yaml.safe_load(value)
    return out


if __name__ == "__main__":
    raise SystemExit(main())
