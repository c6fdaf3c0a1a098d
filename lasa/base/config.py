"""Frozen configuration records, each field commented with its unit, validated when built: a bad
parameter fails at once, naming its allowed range; :func:`from_dict` refuses unknown keys."""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import os
import types
import typing
from collections.abc import Mapping, Sequence
from typing import Annotated, Any, TypeVar

import annotated_types as at
import pydantic
from typing_extensions import TypedDict

from lasa.base.errors import ConfigError

T = TypeVar("T")


def _not_text(value: Any) -> Any:
    """A number field never takes text (pydantic's lax mode would parse '3', kept as a string)."""
    if isinstance(value, str | bytes):
        raise ConfigError("text is not a number")
    return value


# A record's own range: Annotated[Number, at.Gt(0.0), at.Le(1.0)] (the bounds are read for the error).
Number = Annotated[float, pydantic.BeforeValidator(_not_text)]
Integer = Annotated[int, pydantic.BeforeValidator(_not_text)]
PositiveInt = Annotated[Integer, at.Ge(1)]  # an integer >= 1 (counts, steps, sizes)
NonNegativeInt = Annotated[Integer, at.Ge(0)]  # an integer >= 0
AtLeastTwo = Annotated[Integer, at.Ge(2)]  # an integer >= 2 (grids that hold both ends)
Positive = Annotated[Number, at.Gt(0.0)]  # a number > 0
NonNegative = Annotated[Number, at.Ge(0.0)]  # a number >= 0
UnitInterval = Annotated[Number, at.Ge(0.0), at.Le(1.0)]  # a number in [0, 1] (a probability, a weight)
Seed = Annotated[Integer, at.Ge(0)]  # a random generator's seed: an integer >= 0 (what NumPy accepts)


# a simulated user's rationality (Eq. S1); a type's at.doc, why it has its bounds, follows a range error
_LOG_AXIS = "the figures' beta axis is logarithmic and Eq. S1's Boltzmann user needs 0 < beta < inf"
Rationality = Annotated[Number, at.Gt(0.0), at.Lt(math.inf), at.doc(_LOG_AXIS)]
# the most belief any goal may keep (lasa.method.belief.cap_log_belief), or None (cap_setting: "none")
BeliefCap = Annotated[Number, at.Gt(0.5), at.Lt(1.0)] | None


def cap_setting(value: Any) -> Any:
    """A belief cap as a record keeps it: the word ``"none"`` (any case) is None, else as given."""
    return None if isinstance(value, str) and value.strip().lower() == "none" else value


def validate_caps(config: Any) -> None:
    """:func:`validate` a config's ``belief_cap`` and ``cap_sweep`` (:func:`cap_setting`), no cap twice."""
    object.__setattr__(config, "belief_cap", cap_setting(config.belief_cap))
    object.__setattr__(config, "cap_sweep", tuple(cap_setting(c) for c in config.cap_sweep))
    validate(config)
    if len(set(config.cap_sweep)) != len(config.cap_sweep):
        raise ConfigError(f"cap_sweep must not repeat a cap, got {config.cap_sweep}")


_SIDES = {at.Ge: (0, False), at.Gt: (0, True), at.Le: (1, False), at.Lt: (1, True)}  # bound: (side, open)


def interval(low: float, high: float, low_open: bool = False, high_open: bool = False) -> str:
    """An interval in words, ``[0, 1]`` or ``(0, inf]``: how every range error states its bounds."""
    return f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"


def expects(annotation: Any) -> str:
    """What a field of this type accepts, in words: ``an integer >= 1``, ``a number in [0, 1]``."""
    origin = typing.get_origin(annotation)
    if origin is Annotated:
        ends = [-math.inf, math.inf]
        opens = [False, False]
        base = typing.get_args(annotation)[0]
        for bound in (m for m in annotation.__metadata__ if type(m) in _SIDES):
            side, opens[side] = _SIDES[type(bound)]
            ends[side] = float(getattr(bound, type(bound).__name__.lower()))  # Ge(1).ge, Lt(1).lt ...
        if base is int and ends[1] == math.inf:
            return f"an integer >= {ends[0] + 1 if opens[0] else ends[0]:g}"
        return f"{'an integer' if base is int else 'a number'} in {interval(ends[0], ends[1], *opens)}"
    if origin is tuple:
        return f"a list, each {expects(typing.get_args(annotation)[0])}"
    if origin in (typing.Union, types.UnionType):
        return " or ".join(expects(a) for a in typing.get_args(annotation))
    return _WORDS.get(annotation, f"a {getattr(annotation, '__name__', annotation)}")


_WORDS = {int: "an integer", float: "a number", str: "a string", bool: "true or false", type(None): "null"}


@functools.cache
def _schema(cls: type) -> tuple[pydantic.TypeAdapter[Any], dict[str, Any]]:
    """A pydantic validator of ``cls``'s fields (their annotated types), and the types by name."""
    hints = typing.get_type_hints(cls, include_extras=True)
    fields = {f.name: hints[f.name] for f in dataclasses.fields(cls) if f.init}
    record = TypedDict(cls.__name__, fields)  # type: ignore[misc, operator]
    record.__pydantic_config__ = pydantic.ConfigDict(arbitrary_types_allowed=True)  # type: ignore[attr-defined]
    return pydantic.TypeAdapter(record), fields


def validate(record: Any) -> None:
    """Check every field of a config record against its annotated type (pydantic), converting none;
    ConfigError names the field (and item), what it expects and got: ``betas[0] must be ..., got 'x'``."""
    adapter, fields = _schema(type(record))  # type: ignore[arg-type]
    try:
        adapter.validate_python({name: getattr(record, name) for name in fields})
    except pydantic.ValidationError as exc:
        err = exc.errors()[0]
        loc = [str(x) for x in err["loc"]]
        name = loc[0] + "".join(f"[{x}]" for x in loc[1:])
        annotation = fields[loc[0]]
        item = typing.get_args(annotation)[0] if typing.get_origin(annotation) is tuple else annotation
        expected = expects(item if len(loc) > 1 else annotation)
        if isinstance(err["input"], int | float) and expected.startswith("a number in "):
            expected = expected.removeprefix("a number ")  # it is a number: only the range is wrong
        reasons = [m.documentation for m in getattr(item, "__metadata__", ()) if isinstance(m, at.DocInfo)]
        why = f": {reasons[0]}" if reasons else ""
        raise ConfigError(f"{name} must be {expected}, got {err['input']!r}{why}") from None


LIKELIHOODS = ("preferences", "goal")  # the belief models (lasa.method.belief.belief_targets)
# members' names (lasa.method.assistance.MEMBERS): the figures' defaults, and the study's hindsight_point
ASSISTANCE = ("point", "grasp_set", "arbitrated", "hindsight")
BUILT_IN_ASSISTANCE = (*ASSISTANCE, "hindsight_point")
NO_ASSISTANCE = "none"  # the assistance label of rows and episodes with none (alpha = 0: LA, R)
# One trial limit for people and simulated participants [s]: the simulated study's horizon (notebook 11's
# `session.horizon`, lasa.people.design.StudyConfig), the web server's `--trial-s` default, and the limit
# of a session whose sidecar records none (lasa.evidence.sessions.session_limit).
TRIAL_LIMIT_S = 150.0


def check_range(
    name: str,
    value: float,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """``value`` as a float if in [low, high] (``low_open``, ``high_open``: bound excluded), never NaN."""
    allowed = interval(low, high, low_open, high_open)
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number in {allowed}, got {value!r}") from None
    if not ((low < v if low_open else low <= v) and (v < high if high_open else v <= high)):  # NaN too
        raise ConfigError(f"{name} must be in {allowed}, got {value!r}")
    return v


def check_choice(name: str, value: str, choices: tuple[str, ...] | list[str]) -> str:
    """Return ``value`` if it is one of ``choices``, else raise ConfigError listing them."""
    if value not in choices:
        raise ConfigError(f"unknown {name} {value!r}; choose one of {', '.join(map(repr, choices))}")
    return value


def check_list(
    name: str, values: Sequence[Any], *, at_least: int = 1, ascending: bool = False, why: str = ""
) -> tuple[Any, ...]:
    """A list setting as a tuple of ``at_least`` values, none twice (1 and 1.0 repeat), ascending if asked."""
    given = tuple(values)
    if len(given) < at_least:
        what = "a value" if at_least == 1 else f"at least {at_least} distinct values"
        raise ConfigError(f"{name} must hold {what}{f' ({why})' if why else ''}, got {list(given)}")
    if repeated := [v for i, v in enumerate(given) if v in given[:i]]:
        raise ConfigError(f"{name} must not repeat a value, got {list(given)} ({repeated[0]!r} twice)")
    if ascending and any(b < a for a, b in itertools.pairwise(given)):
        raise ConfigError(f"{name} must be in ascending order, got {list(given)}; sorted: {sorted(given)}")
    return given


@dataclasses.dataclass(frozen=True)
class ControlConfig:
    """The units of the control loop (s' = s + dt a, Sec. V): the free parameters that give beta
    its meaning. The defaults are both robots', chosen so that the paper's regimes exist (notebook 04)."""

    dt: Annotated[Number, at.Gt(0.0), at.Le(1.0)] = 0.1  # control period Delta [s]
    action_scale: Positive = 0.375  # sigma_h: the decoder's bound on ||phi(z, s, b)|| [rad/s]
    max_joint_speed: Positive = 2.0  # per-joint bound on the commanded velocity [rad/s]
    belief_beta: NonNegative = 20.0  # beta_b, temperature of the goal likelihood [1/rad]
    belief_floor: Annotated[Number, at.Ge(0.0), at.Lt(0.5)] = 1e-6  # least belief a goal keeps [-]
    # the most belief any goal keeps after an update (Javdani et al.'s max_prob_any_goal); None: no
    # cap, Algorithm 1's belief, which the sims keep; the eating study's is 0.99 [-]
    belief_cap: BeliefCap = None
    alpha: UnitInterval = 0.2  # blend weight of the assistance in LA+SA (Eq. M1) [-]
    n_z: AtLeastTwo = 21  # joystick candidates per latent axis the simulated user weighs [-]
    likelihood: str = "preferences"  # belief model: "preferences" (regret to preference sets) or "goal"
    # the built-in shared-autonomy member (lasa.method.assistance.MEMBERS): Eq. M2 towards g = s*(g, 0.5)
    assistance: str = "point"

    @property
    def likelihood_step(self) -> float | None:
        """The best step the belief's normaliser assumes, dt * sigma_h, or None."""
        return self.dt * self.action_scale if self.likelihood == "preferences" else None

    def __post_init__(self) -> None:
        object.__setattr__(self, "belief_cap", cap_setting(self.belief_cap))
        validate(self)
        check_choice("likelihood", self.likelihood, LIKELIHOODS)
        check_choice("assistance", self.assistance, BUILT_IN_ASSISTANCE)


to_dict = dataclasses.asdict  # a plain dict of a config record (safe for JSON and torch checkpoints)


def from_dict(cls: type[T], values: Mapping[str, Any] | None, where: str | None = None) -> T:
    """Build ``cls`` from a YAML section (missing keys keep their defaults, ``train: {steps: 200}``
    changes a nested record's field); ConfigError ``<where> settings: <setting> must be ..., got ...``."""
    owner = where or cls.__name__
    values = {} if values is None else values
    if not isinstance(values, Mapping):
        raise ConfigError(f"{owner} settings must be a mapping of names to values, got {values!r}")
    try:
        return cls(**_changes("", cls, values))
    except ConfigError as exc:
        raise ConfigError(f"{owner} settings: {exc}") from None


def _changes(prefix: str, record: Any, values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` as ``record``'s fields take them (nested records, tuples); errors name the whole path."""
    known = {f.name: f for f in dataclasses.fields(record)}
    if unknown := sorted(set(values) - set(known)):
        raise ConfigError(f"unknown setting(s) {[prefix + u for u in unknown]}; known: {sorted(known)}")
    changes = {}
    for key, value in values.items():
        default = known[key].default if isinstance(record, type) else getattr(record, key)
        if isinstance(value, Mapping) and dataclasses.is_dataclass(default):
            nested = _changes(f"{prefix}{key}.", default, value)
            try:
                value = dataclasses.replace(default, **nested)  # type: ignore[type-var]
            except ConfigError as exc:
                raise ConfigError(f"{prefix}{key}.{exc}") from None
        elif isinstance(value, list) and "tuple" in str(known[key].type):
            value = tuple(value)
        changes[key] = value
    return changes


def set_threads(default: int = 1) -> int:
    """Set torch's intra-op threads from ``LASA_THREADS``, else ``default`` (one: a reduction split over
    threads rounds differently, and training amplifies that); return it."""
    import torch  # noqa: PLC0415 (config stays importable without torch's start-up cost)

    value = os.environ.get("LASA_THREADS")
    threads = int(value) if value else default
    if threads < 1:
        raise ConfigError(f"LASA_THREADS must be a positive integer, got {value!r}")
    torch.set_num_threads(threads)
    return threads
