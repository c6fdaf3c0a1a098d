"""Config validation: ranges, choices, unknown keys."""

import math

import pytest

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
    with pytest.raises(ConfigError, match="unknown ControlConfig parameter.*'alhpa'"):
        from_dict(ControlConfig, {"alhpa": 0.3})


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
    from lasa.figures import sim1

    cfg = from_dict(sim1.Config, {"betas": [1, 75, 1000], "users": 2})
    assert cfg.betas == (1.0, 75.0, 1000.0) and cfg.users == 2
    assert from_dict(sim1.Config, None) == sim1.Config()
    with pytest.raises(ConfigError, match="mapping"):
        from_dict(sim1.Config, [("users", 2)])  # type: ignore[arg-type]
