"""Config validation: ranges, choices, unknown keys."""

import dataclasses
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lasa.base.config import ControlConfig, check_range, from_dict, to_dict
from lasa.base.errors import ConfigError


def test_check_range():
    assert check_range("x", 0.5, 0, 1) == 0.5
    assert check_range("beta", math.inf, 0) == math.inf
    for bad in (-1, 2, math.nan, "a"):
        with pytest.raises(ConfigError, match="x must be"):
            check_range("x", bad, 0, 1)
    with pytest.raises(ConfigError, match=r"\(0, 1\]"):
        check_range("x", 0.0, 0, 1, low_open=True)


@pytest.mark.parametrize(
    "field,value",
    [
        ("dt", 0.0),
        ("action_scale", -1.0),
        ("alpha", 1.2),
        ("alpha", -0.1),
        ("belief_beta", -2.0),
        ("n_z", 1),
        ("likelihood", "cosine"),
    ],
)
def test_control_config_rejects_bad_values(field, value):
    with pytest.raises(ConfigError, match=field):
        ControlConfig(**{field: value})


def test_from_dict_refuses_unknown_keys():
    assert from_dict(ControlConfig, {"alpha": 0.3}).alpha == 0.3
    with pytest.raises(
        ConfigError, match=r"ControlConfig settings: unknown setting\(s\) \['alhpa'\]; known: "
    ):
        from_dict(ControlConfig, {"alhpa": 0.3})
    with pytest.raises(ConfigError, match=r"^notebook 04 settings: unknown setting"):
        from_dict(ControlConfig, {"alhpa": 0.3}, where="notebook 04")


def test_a_bad_setting_names_the_notebook_the_setting_what_it_got_and_what_it_expects():
    with pytest.raises(ConfigError) as err:
        from_dict(ControlConfig, {"alpha": "x"}, where="notebook 04_fixed_expertise")
    assert str(err.value) == "notebook 04_fixed_expertise settings: alpha must be a number in [0, 1], got 'x'"
    with pytest.raises(ConfigError) as err:
        from_dict(ControlConfig, {"n_z": 1.5})
    assert str(err.value) == "ControlConfig settings: n_z must be an integer >= 2, got 1.5"


@settings(max_examples=60, deadline=None)
@given(value=st.floats(allow_nan=True, allow_infinity=True) | st.integers(-5, 5) | st.text(max_size=3))
def test_alpha_is_accepted_exactly_on_the_unit_interval_and_kept_as_given(value):
    ok = isinstance(value, int | float) and 0.0 <= value <= 1.0  # NaN compares False
    if ok:
        cfg = ControlConfig(alpha=value)
        assert cfg.alpha is value or cfg.alpha == value  # validation converts nothing
        assert type(cfg.alpha) is type(value)
    else:
        with pytest.raises(ConfigError, match=r"^alpha must be (a number )?in \[0, 1\], got "):
            ControlConfig(alpha=value)


def test_round_trip():
    cfg = ControlConfig(alpha=0.4)
    assert from_dict(ControlConfig, to_dict(cfg)) == cfg


def test_defaults_are_the_robots_units():
    """ControlConfig's defaults are the values both robots use, not numbers of their own."""
    from lasa.world.robot import ROBOTS

    assert all(spec.control == ControlConfig() for spec in ROBOTS.values())
    cfg = ControlConfig()
    assert (cfg.dt, cfg.action_scale, cfg.belief_beta, cfg.alpha) == (0.1, 0.375, 20.0, 0.2)


def test_from_dict_turns_yaml_lists_into_tuples_and_refuses_non_mappings():
    from lasa.experiments import sim1

    cfg = from_dict(sim1.Config, {"betas": [1, 75, 1000], "users": 2})
    assert cfg.betas == (1.0, 75.0, 1000.0) and cfg.users == 2
    assert from_dict(sim1.Config, None) == sim1.Config()
    with pytest.raises(ConfigError, match="mapping"):
        from_dict(sim1.Config, [("users", 2)])  # type: ignore[arg-type]


def _positive_int_fields(cls):
    import typing

    from lasa.base.config import PositiveInt

    hints = typing.get_type_hints(cls, include_extras=True)
    return [f.name for f in dataclasses.fields(cls) if hints[f.name] == PositiveInt]


@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_every_positive_int_setting_refuses_zero_and_below_and_keeps_what_it_accepts(data):
    """One type (lasa.base.config.PositiveInt) checks every count of the training and demo settings."""
    from lasa.method.train import TrainConfig
    from lasa.people.demos import DemoConfig

    cls = data.draw(st.sampled_from([TrainConfig, DemoConfig]))
    names = _positive_int_fields(cls)
    assert len(names) >= 2
    name = data.draw(st.sampled_from(names))
    bad = data.draw(st.integers(-5, 0) | st.floats(0.5, 3.5).filter(lambda x: x != int(x)))
    with pytest.raises(ConfigError, match=rf"^{name} must be an integer >= 1, got {bad!r}$"):
        cls(**{name: bad})
    good = data.draw(st.integers(1, 50))
    assert getattr(from_dict(cls, to_dict(cls(**{name: good}))), name) == good


@pytest.mark.parametrize("module", ["lasa.experiments.eating_task", "lasa.experiments.study.run"])
def test_both_cap_sweeps_read_none_and_refuse_a_repeated_cap(module):
    import importlib

    config_class = importlib.import_module(module).Config
    read = config_class(belief_cap="None", cap_sweep=(0.9, "none"))
    assert read.belief_cap is None and read.cap_sweep == (0.9, None)
    with pytest.raises(ConfigError, match=r"cap_sweep must not repeat a cap, got \(0.9, None, None\)"):
        config_class(cap_sweep=(0.9, None, "none"))
    with pytest.raises(ConfigError, match=r"cap_sweep\[0\] must be in \(0.5, 1\)"):  # checked before repeats
        config_class(cap_sweep=(1.5, 1.5))
