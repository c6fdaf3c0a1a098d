"""The Sec. IV-A ball (lasa.experiments.convergence): hand-computed radii, measured rates, the sweep."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.experiments import convergence

SMALL = convergence.Config(
    betas=(75.0, 1000.0), assistance=("point", "hindsight"), users=2, horizon=12, record_every=1
)


def toy():
    """Two goals in the plane, one user of goal 0, two steps (the second hits the clip)."""
    goals = np.array([[0.0, 0.0], [4.0, 0.0]])
    states = np.array([[[3.0, 0.0]], [[2.9, 0.0]], [[2.9, 0.0]]])  # (T+1, U, n)
    beliefs = np.array([[[0.5, 0.5]], [[0.8, 0.2]], [[0.9, 0.1]]])
    actions = np.array([[[-1.0, 0.0]], [[-3.0, 0.0]]])  # the second step was clipped away
    target = np.array([[0.0, 1.0]])
    m = convergence.measure(states, beliefs, actions, np.array([0]), goals, target, 0.1, 0.5, 0.2)
    return m


def test_radius_by_hand():
    # alpha = 0.5: sigma_h + (1 - b) sigma_r = 0.5 + 0.25 * 2 = 1.0
    assert convergence.radius(0.75, 2.0, 0.5) == pytest.approx(1.0)
    # alpha = 0.2: (0.8 / 0.2) 0.5 + 0.25 * 2 = 2.5
    assert convergence.radius(0.75, 2.0, 0.5, 0.2) == pytest.approx(2.5)
    with pytest.raises(ConfigError, match="alpha"):
        convergence.radius(0.75, 2.0, 0.5, 0.0)


def test_alpha_general_radius_is_the_papers_at_one_half():
    rng = np.random.default_rng(0)
    b, sigma_r = rng.uniform(0, 1, 50), rng.uniform(0, 5, 50)
    paper = 0.375 + (1 - b) * sigma_r  # Eq. T4's delta
    np.testing.assert_allclose(convergence.radius(b, sigma_r, 0.375, 0.5), paper)
    np.testing.assert_allclose(convergence.radius(b, sigma_r, 0.375, 0.2), paper + 3 * 0.375)


def test_measure_on_a_two_goal_toy():
    m = toy()
    np.testing.assert_allclose(m["error"][:, 0], [3.0, 2.9, 2.9])
    np.testing.assert_allclose(m["sigma_r"][:, 0], [1.0, 1.1, 1.1])  # distance to the other goal
    np.testing.assert_allclose(m["belief"][:, 0], [0.5, 0.8, 0.9])
    np.testing.assert_allclose(m["delta"][:, 0], [0.5 + 0.5 * 1.0, 0.5 + 0.2 * 1.1, 0.5 + 0.1 * 1.1])
    np.testing.assert_allclose(m["delta_alpha"][:, 0], m["delta"][:, 0] + 1.5)  # (0.8/0.2 - 1) 0.5
    # b* ||e|| = 1.5, 2.32, 2.61 against delta_alpha = 2.5, 2.22, 2.11
    assert m["bound_holds"][:, 0].tolist() == [False, True, True]
    assert m["bound_holds_half"][:, 0].tolist() == [True, True, True]
    v = 0.5 * np.array([3.0, 2.9, 2.9]) ** 2
    np.testing.assert_allclose(m["v"][:, 0], v)
    np.testing.assert_allclose(m["v_dot"][:2, 0], np.diff(v) / 0.1)
    assert np.isnan(m["v_dot"][2, 0]) and np.isnan(m["slack"][2, 0])
    np.testing.assert_allclose(m["slack"][:2, 0], [0.1 * 1.0 / 2, 0.1 * 9.0 / 2])
    assert m["clipped"][:, 0].tolist() == [False, True, False]
    np.testing.assert_allclose(m["error_target"][:, 0], np.hypot([3.0, 2.9, 2.9], 1.0))


def test_window_counts():
    m = toy()
    # V fell on step 0 (bound not held), held still on step 1 (bound held, no rise)
    counts = convergence._window_counts(m, np.array([0, 2]))
    assert counts["steps"][:, 0].tolist() == [2, 0]
    assert counts["bound_steps"][:, 0].tolist() == [1, 0]
    assert counts["bound_steps_half"][:, 0].tolist() == [2, 0]
    assert counts["rises"][:, 0].tolist() == [0, 0]


@pytest.fixture(scope="module")
def frame(model, task):
    return convergence.run(model, task, task.robot.control, SMALL)


def test_columns_order_and_size(frame):
    assert tuple(frame.columns) == convergence.COLUMNS
    assert convergence.COLUMNS[:8] == ("robot", "assistance", "beta", "seed", "t", "error", "delta", "v_dot")
    assert len(frame) == 2 * 2 * 2 * (SMALL.horizon + 1)
    assert list(dict.fromkeys(frame.assistance)) == ["point", "hindsight"]
    # every step is counted once per user
    assert frame.groupby(["assistance", "beta", "seed"]).steps.sum().eq(SMALL.horizon).all()


def test_v_dot_is_the_measured_rate(frame, task):
    control_dt = task.robot.control.dt
    for _, user in frame.groupby(["assistance", "beta", "seed"]):
        v = user.v.to_numpy()
        np.testing.assert_allclose(v, 0.5 * user.error.to_numpy() ** 2)
        np.testing.assert_allclose(user.v_dot.to_numpy()[:-1], np.diff(v) / control_dt)
        assert np.isnan(user.v_dot.iloc[-1])


def test_point_obeys_the_continuous_time_bound(frame):
    """Where T4 (alpha-general) holds and the clip did not act, -e.a < 0: V rises by less than the slack."""
    point = frame[(frame.assistance == "point") & frame.bound_holds & ~frame.clipped & frame.v_dot.notna()]
    assert len(point) > 0  # not vacuous at this size
    assert (point.v_dot <= point.slack + 1e-12).all()


def test_same_config_gives_identical_frames(model, task, frame):
    again = convergence.run(model, task, task.robot.control, SMALL)
    pd.testing.assert_frame_equal(frame, again)


def test_record_every_keeps_the_counts(model, task, frame):
    sparse = convergence.run(model, task, task.robot.control, dataclasses.replace(SMALL, record_every=5))
    assert sorted(sparse.t.unique()) == [0, 5, 10, 12]
    keys = ["assistance", "beta", "seed"]
    for column in ("steps", "bound_steps", "rises", "bound_steps_half", "rises_half"):
        pd.testing.assert_series_equal(frame.groupby(keys)[column].sum(), sparse.groupby(keys)[column].sum())


def test_summary_and_plot(frame):
    table = convergence.summary(frame)
    assert len(table) == 4
    assert table.bound_share.between(0, 1).all() and table.steps.eq(2 * SMALL.horizon).all()
    fig = convergence.plot(frame)
    assert len(fig.axes) == 4


def test_zero_alpha_is_refused(model, task):
    control = dataclasses.replace(task.robot.control, alpha=0.0)
    with pytest.raises(ConfigError, match="alpha"):
        convergence.run(model, task, control, SMALL)


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"betas": ()}, "betas"),
        ({"betas": (-1.0,)}, "beta"),
        ({"betas": (float("inf"),)}, "beta"),
        ({"betas": (75.0, 75.0)}, "repeat"),
        ({"assistance": ()}, "assistance"),
        ({"assistance": ("blend",)}, "unknown assistance"),
        ({"users": 0}, "users"),
        ({"horizon": 1.5}, "horizon"),
        ({"record_every": 0}, "record_every"),
        ({"horizon": 10, "record_every": 20}, "record_every"),
    ],
)
def test_bad_config_is_a_clear_error(kw, match):
    with pytest.raises(ConfigError, match=match):
        convergence.Config(**kw)
