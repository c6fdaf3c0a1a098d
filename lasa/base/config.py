"""Frozen configuration records and their validation.

A config is a frozen dataclass whose every field has a comment with its unit. Values are
checked when the record is built, so a bad parameter fails at once with a message that
names it and its allowed range, not deep inside a rollout. :func:`from_dict` refuses
unknown keys: a misspelt knob must not silently fall back to its default.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from typing import Any, TypeVar

from lasa.base.errors import ConfigError

__all__ = [
    "ASSISTANCE",
    "ControlConfig",
    "check_range",
    "check_choice",
    "from_dict",
    "to_dict",
]

T = TypeVar("T")

# The members of the shared-autonomy family, named once; lasa.method.assistance implements them.
ASSISTANCE = ("point", "grasp_set", "arbitrated", "hindsight")
# Members added from outside the package (lasa.method.assistance.register_member, the only writer),
# which ControlConfig accepts too; the figures' default members stay ASSISTANCE.
REGISTERED_ASSISTANCE: list[str] = []
# The assistance label of rows and episodes with none (alpha = 0: LA, R), named once.
NO_ASSISTANCE = "none"


def check_range(
    name: str,
    value: float,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """Return ``value`` as a float if it lies within [low, high], else raise ConfigError.

    NaN is always refused; infinity only passes where the bound on that side is infinite.

    Args:
        name: Parameter name, used in the message.
        value: The value to check.
        low: Lower bound.
        high: Upper bound.
        low_open: Exclude ``low`` itself.
        high_open: Exclude ``high`` itself.
    """
    lo = "(" if low_open else "["
    hi = ")" if high_open else "]"
    allowed = f"{lo}{low:g}, {high:g}{hi}"
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number in {allowed}, got {value!r}") from None
    bad = math.isnan(v) or v < low or v > high
    bad = bad or (low_open and v == low) or (high_open and v == high)
    if bad:
        raise ConfigError(f"{name} must be in {allowed}, got {value!r}")
    return v


def check_choice(name: str, value: str, choices: tuple[str, ...] | list[str]) -> str:
    """Return ``value`` if it is one of ``choices``, else raise ConfigError listing them."""
    if value not in choices:
        raise ConfigError(f"unknown {name} {value!r}; choose one of {', '.join(map(repr, choices))}")
    return value


@dataclasses.dataclass(frozen=True)
class ControlConfig:
    """The units of the control loop: the free parameters that give beta its meaning.

    The paper's transition is s' = s + dt * a with a a joint velocity (Sec. V). These
    values set how far one step moves, how hard the user can push (sigma_h, Eq. T4),
    and how quickly the belief commits. The defaults are the values both robots use
    (``lasa.world.robot.ROBOTS``), chosen so that the paper's regimes exist (beta = 75 noisy,
    beta = 1000 near optimal); notebook 04 states them and why.
    """

    dt: float = 0.1  # control period Delta [s]
    action_scale: float = 0.375  # sigma_h: the decoder's bound on ||phi(z, s, b)|| [rad/s]
    max_joint_speed: float = 2.0  # per-joint bound on the commanded velocity [rad/s]
    belief_beta: float = 20.0  # beta_b, temperature of the goal likelihood [1/rad]
    belief_floor: float = 1e-6  # smallest belief any goal keeps after an update [-]
    alpha: float = 0.2  # blend weight of the assistance in LA+SA (Eq. M1) [-]
    n_z: int = 21  # joystick candidates per latent axis the simulated user weighs [-]
    likelihood: str = "grasp_set"  # belief model: "grasp_set" (regret to grasp sets) or "goal"
    assistance: str = (
        "point"  # the shared-autonomy reading (lasa.method.assistance): Eq. M2 towards g = s*(g, 0.5)
    )

    @property
    def likelihood_step(self) -> float | None:
        """The best step the belief's normaliser assumes, dt * sigma_h, or None."""
        return self.dt * self.action_scale if self.likelihood == "grasp_set" else None

    def __post_init__(self) -> None:
        check_range("dt", self.dt, 0.0, 1.0, low_open=True)
        check_range("action_scale", self.action_scale, 0.0, low_open=True)
        check_range("max_joint_speed", self.max_joint_speed, 0.0, low_open=True)
        check_range("belief_beta", self.belief_beta, 0.0)
        check_range("belief_floor", self.belief_floor, 0.0, 0.5, high_open=True)
        check_range("alpha", self.alpha, 0.0, 1.0)
        check_choice("likelihood", self.likelihood, ("grasp_set", "goal"))
        check_choice("assistance", self.assistance, (*ASSISTANCE, *REGISTERED_ASSISTANCE))
        if int(self.n_z) != self.n_z or self.n_z < 2:
            raise ConfigError(f"n_z must be an integer >= 2, got {self.n_z!r}")


def to_dict(config: Any) -> dict[str, Any]:
    """A plain ``dict`` of a config dataclass (safe for JSON and torch checkpoints)."""
    return dataclasses.asdict(config)


def from_dict(cls: type[T], values: Mapping[str, Any] | None) -> T:
    """Build ``cls`` from a mapping, refusing keys that ``cls`` does not have.

    This is the one place where a YAML section (``configs/*.yaml``, passed to a notebook
    as its ``settings`` parameter) becomes a config: a missing key keeps the dataclass
    default, a list becomes a tuple where the field is a tuple.

    Raises:
        ConfigError: if ``values`` is not a mapping or a key is unknown, naming it and the
            known ones.
    """
    if values is None:
        values = {}
    if not isinstance(values, Mapping):
        raise ConfigError(f"{cls.__name__} settings must be a mapping of names to values, got {values!r}")
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(values) - set(fields))
    if unknown:
        raise ConfigError(f"unknown {cls.__name__} parameter(s) {unknown}; known: {sorted(fields)}")
    kwargs = {
        name: tuple(value) if isinstance(value, list) and "tuple" in str(fields[name].type) else value
        for name, value in values.items()
    }
    return cls(**kwargs)


def set_threads(default: int = 1) -> int:
    """Set torch's intra-op threads from ``LASA_THREADS``, else ``default`` (one).

    One thread by default, everywhere: a float reduction split over more threads rounds
    differently in the last bits, and training amplifies that into other decoders and
    other figures. With one thread, a notebook run by hand, ``make figures`` and CI give
    the same numbers on any machine, and the committed figures are reproduced byte for
    byte. ``make figures`` gets its parallelism from running the robots' notebooks side
    by side instead. Set ``LASA_THREADS`` for speed when exactness does not matter.

    Returns:
        The number of threads set.
    """
    import torch  # noqa: PLC0415 (config stays importable without torch's start-up cost)

    value = os.environ.get("LASA_THREADS")
    threads = int(value) if value else default
    if threads < 1:
        raise ConfigError(f"LASA_THREADS must be a positive integer, got {value!r}")
    torch.set_num_threads(threads)
    return threads
