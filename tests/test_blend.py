"""Eqs. M1 and M2 (the member ``point``) against hand-computed cases, and the safety invariants of a step."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from lasa.base.errors import ConfigError
from lasa.method.assistance import point
from lasa.method.step import blend, safe_step, sanitize

GOALS = np.array([[1.0, 0.0], [-1.0, 2.0]])


def test_assistance_m2_by_hand():
    # a_r = 0.75 (g1 - s) + 0.25 (g2 - s) with s = (0, 1): 0.75 (1, -1) + 0.25 (-1, 1) = (0.5, -0.5)
    a_r = point(np.array([0.75, 0.25]), np.array([0.0, 1.0]), GOALS, None, 0.0, 0.0)[0]
    assert_allclose(a_r, [0.5, -0.5])
    # a confident belief points straight at that goal
    assert_allclose(point(np.array([0.0, 1.0]), np.zeros(2), GOALS, None, 0.0, 0.0)[0], GOALS[1])


def test_assistance_is_batched():
    rng = np.random.default_rng(1)
    b = rng.dirichlet([1, 1], size=(4, 3))
    s = rng.normal(size=(4, 3, 2))
    expected = np.einsum("...g,gn->...n", b, GOALS) - s
    assert_allclose(point(b, s, GOALS, None, 0.0, 0.0)[0], expected)


def test_blend_m1_by_hand():
    a_h, a_r = np.array([2.0, 0.0]), np.array([0.0, 4.0])
    assert_allclose(blend(a_h, a_r, 0.25), [1.5, 1.0])
    assert_allclose(blend(a_h, a_r, 0.0), a_h)
    assert_allclose(blend(a_h, a_r, 1.0), a_r)
    per_row = blend(np.stack([a_h, a_h]), np.stack([a_r, a_r]), np.array([0.0, 1.0]))
    assert_allclose(per_row, [a_h, a_r])


@pytest.mark.parametrize("alpha", [-0.1, 1.5, np.nan])
def test_alpha_outside_unit_interval_is_an_error(alpha):
    with pytest.raises(ConfigError, match="alpha"):
        blend(np.zeros(2), np.zeros(2), alpha)
    with pytest.raises(ConfigError, match="alpha"):
        blend(np.zeros((2, 2)), np.zeros((2, 2)), np.array([0.5, alpha]))


def test_sanitize_zeroes_non_finite_rows():
    a = np.array([[1.0, 2.0], [np.nan, 1.0], [np.inf, 0.0]])
    assert_allclose(sanitize(a), [[1.0, 2.0], [0.0, 0.0], [0.0, 0.0]])


def test_safe_step_invariants_under_random_huge_and_nan_actions(robot):
    rng = np.random.default_rng(0)
    n = robot.n_joints
    dt, vmax = 0.1, 2.0
    s = rng.uniform(robot.lower, robot.upper, size=(500, n))
    actions = np.concatenate(
        [
            rng.normal(size=(100, n)),
            rng.normal(scale=1e9, size=(100, n)),
            np.full((100, n), np.nan),
            np.where(rng.random((100, n)) < 0.3, np.inf, 1.0),
            -np.full((100, n), np.inf),
        ]
    )
    nxt = safe_step(s, actions, dt, robot.lower, robot.upper, vmax)
    assert np.all(np.isfinite(nxt))
    assert np.all(nxt >= robot.lower) and np.all(nxt <= robot.upper)
    assert np.all(np.abs(nxt - s) <= dt * vmax + 1e-12)
    # rows with a non-finite entry hold still
    assert_allclose(nxt[200:300], s[200:300])


def test_safe_step_refuses_non_finite_state(robot):
    s = np.zeros(robot.n_joints)
    s[2] = np.nan
    with pytest.raises(ValueError, match="state"):
        safe_step(s, np.zeros_like(s), 0.1, robot.lower, robot.upper, 1.0)


def test_state_outside_limits_is_brought_back(robot):
    s = robot.upper + 5.0
    nxt = safe_step(s, np.zeros_like(s), 0.1, robot.lower, robot.upper, 1.0)
    assert_allclose(nxt, robot.upper)
