"""Conditions and methods, named once (lasa.base.conditions): the table, the errors, their users."""

import pytest

from lasa.base import conditions
from lasa.base.config import ControlConfig
from lasa.base.errors import ConfigError


def test_the_table_by_hand():
    got = {n: (c.interface, c.assisted, c.decoder) for n in conditions.ALL for c in [conditions.parse(n)]}
    assert got == {
        "R": ("R", False, None),
        "R+SA": ("R", True, None),
        "LA": ("LA", False, "base"),
        "LA+SA": ("LA", True, "base"),
        "LA+SA+Entropy": ("LA", True, "entropy"),
    }
    assert set(conditions.METHODS) | set(conditions.CONDITIONS) == set(conditions.ALL)


def test_a_name_outside_what_the_caller_accepts_is_an_error():
    with pytest.raises(ConfigError, match=r"unknown method 'R'; choose one of 'LA', 'LA\+SA'"):
        conditions.parse("R", conditions.METHODS, "method")
    with pytest.raises(ConfigError, match=r"unknown condition 'LA\+SA\+Entropy'"):
        conditions.parse("LA+SA+Entropy", conditions.CONDITIONS)
    with pytest.raises(ConfigError, match="unknown condition 'la'"):
        conditions.parse("la")


def test_every_loop_reads_the_same_table():
    from lasa.live.station import SessionConfig
    from lasa.method.step import METHOD_DECODER, METHODS, method_alpha
    from lasa.people.design import interface_of

    control = ControlConfig(alpha=0.4)
    assert METHODS == conditions.METHODS
    for name in conditions.ALL:  # a live session runs every condition of the table, and no other
        assert SessionConfig(task="cups", condition=name).condition == name
    with pytest.raises(ConfigError, match="unknown condition"):
        SessionConfig(task="cups", condition="LA+Entropy")
    assert METHOD_DECODER == {"LA": "base", "LA+SA": "base", "LA+SA+Entropy": "entropy"}
    assert [method_alpha(m, control) for m in METHODS] == [0.0, 0.4, 0.4]
    assert [conditions.alpha_of(c, 0.4) for c in conditions.CONDITIONS] == [0.0, 0.4, 0.0, 0.4]
    assert [interface_of(c) for c in conditions.CONDITIONS] == ["R", "R", "LA", "LA"]
    with pytest.raises(ConfigError, match="unknown method"):
        method_alpha("R+SA", control)
