"""The conditions and methods, named once and parsed in one place. A name gives the **interface** (``R``,
Retargeting by IK; ``LA``, latent actions a_h = phi(z, s, b)), whether it is **assisted** (``+SA``, Eq. M1;
else alpha = 0) and the **decoder** (``+Entropy``: Eq. T6)."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from lasa.base.errors import ConfigError

METHODS = ("LA", "LA+SA", "LA+SA+Entropy")  # the simulations' methods (sims 1-4)
CONDITIONS = ("R", "R+SA", "LA", "LA+SA")  # the study's 2x2 design (interface x assistance)


@dataclasses.dataclass(frozen=True)
class Condition:
    """A condition, parsed: its name, interface, whether it is assisted, and its decoder (or None)."""

    name: str
    interface: str
    assisted: bool
    decoder: str | None


ALL = ("R", "R+SA", "LA", "LA+SA", "LA+SA+Entropy")  # every condition a person can drive


def parse(name: str, allowed: tuple[str, ...] = ALL, what: str = "condition") -> Condition:
    """The :class:`Condition` a name stands for; ConfigError (calling it ``what``) unless ``allowed``."""
    if not isinstance(name, str) or name not in allowed:
        raise ConfigError(f"unknown {what} {name!r}; choose one of {', '.join(map(repr, allowed))}")
    interface, *parts = name.split("+")
    decoder = None if interface == "R" else "entropy" if "Entropy" in parts else "base"
    return Condition(name, interface, "SA" in parts, decoder)


def alpha_of(name: str, alpha: float, allowed: tuple[str, ...] = ALL, what: str = "condition") -> float:
    """The blend weight of a condition: ``alpha`` if it is assisted, else 0 (LA and R: alpha = 0)."""
    return alpha if parse(name, allowed, what).assisted else 0.0


def williams_square(n: int) -> np.ndarray:
    """A Williams design, (n, n) for n even: each condition once in every position, after every other once."""
    if n < 2 or n % 2:
        raise ConfigError(f"a Williams square needs an even number of conditions >= 2, got {n}")
    first = [0, *itertools.chain.from_iterable((k, n - k) for k in range(1, n // 2)), n // 2]
    return (np.asarray(first)[None, :] + np.arange(n)[:, None]) % n
