"""Every settings record in `lasa` refuses text for a number, NaN, negatives and unknown keys.

The records are found, not listed: every frozen dataclass named ``*Config`` defined in a module
of the package. Each number field (and each number in a tuple field) is tried with the text of its
default, NaN and a negative value, built directly and through :func:`lasa.base.config.from_dict`
(the path a notebook's YAML settings take); each must fail with one line that names the setting.
"""

import dataclasses
import importlib
import inspect
import math
import pkgutil

import pytest

import lasa
from lasa.base.config import from_dict
from lasa.base.errors import ConfigError

# Fields a record needs besides its defaults (a decoder's shape).
REQUIRED = {
    "DecoderConfig": {"robot": "planar5", "n_joints": 5, "n_goals": 3},
    "WebConfig": {"sessions": "sessions"},
}
# Number fields where a negative value means something: none today.
NEGATIVE_ALLOWED: dict[str, str] = {}
# The records the discovery must find (so that it cannot pass by finding nothing).
KNOWN = {
    "ControlConfig",
    "DecoderConfig",
    "TrainConfig",
    "RetargetConfig",
    "SessionConfig",
    "ParticipantConfig",
    "StudyConfig",
    "PlanConfig",
    "DemoConfig",
    "PropertyConfig",
    "SweepConfig",
    "WebConfig",
}


def _records() -> list[type]:
    found = {}
    for info in pkgutil.walk_packages(lasa.__path__, "lasa."):
        module = importlib.import_module(info.name)
        for name, obj in vars(module).items():
            if (
                inspect.isclass(obj)
                and obj.__module__ == module.__name__
                and name.endswith("Config")
                and dataclasses.is_dataclass(obj)
            ):
                found[f"{obj.__module__}.{obj.__qualname__}"] = obj
    return [found[k] for k in sorted(found)]


RECORDS = _records()


def _label(cls: type) -> str:
    """``sim4.Config``, ``ControlConfig``: the record's module where its name alone is ambiguous."""
    return f"{cls.__module__.rsplit('.', 1)[-1]}.{cls.__name__}" if cls.__name__ == "Config" else cls.__name__


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _number_fields(cls: type) -> list[tuple[str, object]]:
    """(field, default) of every number field, and of every tuple field holding numbers."""
    out = []
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        default = f.default
        if default is dataclasses.MISSING:
            default = REQUIRED.get(cls.__name__, {}).get(f.name, dataclasses.MISSING)
        if _is_number(default) or (isinstance(default, tuple) and default and all(map(_is_number, default))):
            out.append((f.name, default))
    return out


def _bad_values(default: object) -> dict[str, object]:
    """Text, NaN and a negative value in place of ``default`` (in its first item, for a tuple)."""
    first = default[0] if isinstance(default, tuple) else default
    bad = {"text": str(first), "nan": math.nan, "negative": -abs(float(first)) - 1.0}
    if isinstance(default, tuple):
        return {k: (v, *default[1:]) for k, v in bad.items()}
    return bad


CASES = [
    pytest.param(cls, name, kind, value, id=f"{_label(cls)}.{name}-{kind}")
    for cls in RECORDS
    for name, default in _number_fields(cls)
    for kind, value in _bad_values(default).items()
    if not (kind == "negative" and f"{cls.__name__}.{name}" in NEGATIVE_ALLOWED)
]


def test_the_discovery_finds_every_known_record():
    names = {cls.__name__ for cls in RECORDS}
    assert KNOWN <= names, f"not found: {sorted(KNOWN - names)}"
    assert len(CASES) > 100


@pytest.mark.parametrize("cls,name,kind,value", CASES)
def test_a_bad_number_is_refused_in_one_line_naming_the_setting(cls, name, kind, value):
    base = REQUIRED.get(cls.__name__, {})
    with pytest.raises(ConfigError) as direct:
        cls(**(base | {name: value}))
    with pytest.raises(ConfigError) as loaded:
        from_dict(cls, base | {name: list(value) if isinstance(value, tuple) else value})
    for err in (direct, loaded):
        message = str(err.value)
        assert name in message and "\n" not in message, message


@pytest.mark.parametrize("cls", RECORDS, ids=_label)
def test_an_unknown_key_is_refused_naming_it(cls):
    with pytest.raises(ConfigError, match="not_a_setting"):
        from_dict(cls, REQUIRED.get(cls.__name__, {}) | {"not_a_setting": 1})


@pytest.mark.parametrize("cls", RECORDS, ids=_label)
def test_the_defaults_build(cls):
    record = cls(**REQUIRED.get(cls.__name__, {}))
    assert from_dict(cls, REQUIRED.get(cls.__name__, {})) == record
