"""Simulated participants: counterbalancing, learning, the measures by hand, and a small study."""

import dataclasses
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from stand_ins import LinearDecoder

from lasa.base.conditions import CONDITIONS
from lasa.base.config import NO_ASSISTANCE
from lasa.base.errors import ConfigError
from lasa.people.cohort import ParticipantConfig, draw_cohort, williams_square
from lasa.people.design import StudyConfig
from lasa.people.measures import alignment, goal_error, idle_time, measures
from lasa.people.participants import simulate
from lasa.world.eating import make_eating_task


@pytest.fixture(scope="module")
def eating():
    return make_eating_task()


@pytest.fixture(scope="module")
def small_study(eating):
    cohort = draw_cohort(2, seed=1)
    config = StudyConfig(horizon=40, members=("hindsight", "grasp_set"))
    return simulate(eating, LinearDecoder(), cohort, eating.robot.control, config, seed=2, progress=False)


def test_williams_square_balances_positions_and_carry_over():
    square = williams_square(4)
    for line in (*square, *square.T):
        assert sorted(line) == [0, 1, 2, 3]
    follows = [(a, b) for row in square for a, b in itertools.pairwise(row)]
    assert sorted(follows) == sorted(p for p in itertools.permutations(range(4), 2))  # each pair once
    with pytest.raises(ConfigError, match="even"):
        williams_square(3)


def test_a_participant_is_the_same_whatever_the_cohort_size():
    small, large = draw_cohort(3, seed=5), draw_cohort(9, seed=5)
    assert_array_equal(small.beta, large.beta[:3])
    assert_array_equal(small.practice, large.practice[:3])
    assert_array_equal(large.order[4], williams_square(4)[0])  # participant i runs row i mod 4
    config = ParticipantConfig()
    assert np.all((large.practice >= config.practice_min) & (large.practice <= config.practice_max))


def test_experience_carries_half_of_earlier_practice_by_hand():
    cohort = draw_cohort(1)
    cohort = dataclasses.replace(
        cohort, practice=np.array([[100.0, 200.0, 300.0, 400.0]]), order=np.array([[2, 0, 3, 1]])
    )
    # order: LA (300), R (100), LA+SA (400), R+SA (200); transfer 0.5 of everything before
    expected = {2: 300.0, 0: 100.0 + 0.5 * 300, 3: 400.0 + 0.5 * 400, 1: 200.0 + 0.5 * 800}
    assert_allclose(cohort.experience()[0], [expected[c] for c in range(4)])


def test_measures_by_hand():
    dt = 0.5
    goals = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    tip = np.array([[[0.2, 0.0, 0.0]], [[0.7, 0.0, 0.0]], [[0.0, 3.0, 0.0]]])  # (T=3, E=1, 3)
    active = np.array([[True], [True], [False]])
    # distances to the closest goal: 0.2, 0.3 (the last step does not count) -> (0.2 + 0.3) * 0.5
    assert_allclose(goal_error(tip, goals, active, dt), [0.25])
    idle = np.array([[True], [False], [True]])
    assert_allclose(idle_time(idle, active, dt), [0.5])
    down = np.array([0.0, 0.0, -1.0])
    tilted = np.array([np.sin(0.3), 0.0, -np.cos(0.3)])
    direction = np.stack([down, tilted, down])[:, None, :]
    mask = np.array([[True], [True], [False]])
    assert_allclose(alignment(direction, down[None], mask), [(1.0 + np.cos(0.3)) / 2])
    assert np.isnan(alignment(direction, down[None], np.zeros((3, 1), bool)))[0]


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-2, 2), min_size=3, max_size=3), st.floats(0.01, 1.0))
def test_goal_error_is_at_most_the_distance_to_any_goal(point, dt):
    goals = np.array([[0.5, 0.0, 0.1], [0.5, -0.25, 0.1], [0.3, 0.4, 0.0]])
    tip = np.asarray(point)[None, None, :]
    error = goal_error(tip, goals, np.ones((1, 1), bool), dt)[0]
    assert error <= dt * np.linalg.norm(goals - tip[0, 0], axis=1).min() + 1e-12
    assert error >= 0


def test_simulation_is_deterministic_and_safe(eating, small_study):
    again = simulate(
        eating,
        LinearDecoder(),
        draw_cohort(2, seed=1),
        eating.robot.control,
        StudyConfig(horizon=40, members=("hindsight", "grasp_set")),
        seed=2,
        progress=False,
    )
    for field in ("states", "tip", "idle", "switch", "end", "phase"):
        assert_array_equal(getattr(small_study, field), getattr(again, field))
    robot = eating.robot
    assert np.all(small_study.states >= robot.lower - 1e-12) and np.all(
        small_study.states <= robot.upper + 1e-12
    )
    steps = np.diff(small_study.states, axis=0)
    assert np.all(np.abs(steps) <= robot.control.dt * robot.control.max_joint_speed + 1e-12)
    # a press of the mode button is not idle, and only Retargeting has modes
    assert not np.any(small_study.idle & small_study.switch)
    latent = np.char.startswith(small_study.condition.astype(str), "LA")
    assert not small_study.switch[:, latent].any()
    # unassisted conditions run once, assisted ones under each member
    arms = set(zip(small_study.condition, small_study.assistance, strict=True))
    assert arms == {("R", NO_ASSISTANCE), ("LA", NO_ASSISTANCE)} | {
        (c, m) for c in ("R+SA", "LA+SA") for m in ("hindsight", "grasp_set")
    }


def test_a_retargeting_participant_heads_for_the_first_waypoint(eating, small_study):
    from lasa.world.eating import fork_frame, waypoints

    first = waypoints("Dessert")[0]
    target = fork_frame(eating.robot, first.goal, first.theta, first.depth)[0]
    cols = np.flatnonzero((small_study.condition == "R") & (small_study.task == "Dessert"))
    start = np.linalg.norm(small_study.tip[0, cols] - target, axis=1)
    later = np.linalg.norm(small_study.tip[30, cols] - target, axis=1)
    assert np.all(later < start - 0.1)  # 3 s at up to 0.15 m/s: well on the way


def test_measures_tables(eating, small_study):
    frames = measures(eating, small_study)
    episodes = 2 * (2 + 2 * 2) * 2  # participants x arms x tasks
    for name in ("goal_error", "time"):
        assert len(frames[name]) == episodes
        assert {"participant", "condition", "assistance", "task"} <= set(frames[name].columns)
    assert len(frames["alignment"]) == episodes * 4  # four phases per task
    time = frames["time"]
    assert (time.total_time <= 40 * eating.robot.control.dt + 1e-9).all()
    assert (time.idle_time <= time.total_time + 1e-9).all()
    assert set(time.condition) == set(CONDITIONS)
    # Goal Error by hand from the logged tip: the distance to the closest of all four goals (and of
    # the three bowls), summed over the steps each episode ran, times dt
    goals = eating.robot.cup_positions()
    dist = np.linalg.norm(small_study.tip[:-1, :, None, :] - goals[None, None], axis=-1)  # (T, E, G)
    active = small_study.active()
    dt = small_study.dt
    assert_allclose(frames["goal_error"].goal_error, (dist.min(axis=-1) * active).sum(axis=0) * dt)
    assert_allclose(
        frames["goal_error"].goal_error_bowls, (dist[..., :3].min(axis=-1) * active).sum(axis=0) * dt
    )


def test_bad_settings_are_errors(eating):
    with pytest.raises(ConfigError, match="n_z"):
        StudyConfig(n_z=4)
    with pytest.raises(ConfigError, match="assistance"):
        StudyConfig(members=("telepathy",))
    with pytest.raises(ConfigError, match="transfer"):
        ParticipantConfig(transfer=1.5)
    with pytest.raises(ConfigError, match="participants"):
        draw_cohort(0)

    class OneAxis(LinearDecoder):
        z_dim = 1

    with pytest.raises(ConfigError, match="2 axes"):
        simulate(
            eating, OneAxis(), draw_cohort(1), eating.robot.control, StudyConfig(horizon=2), progress=False
        )


def test_an_la_only_run_repeats_the_full_runs_la_episodes(eating, small_study):
    """Another decoder reading runs LA and LA+SA only; with the same decoder, the full run's episodes."""
    cohort = draw_cohort(2, seed=1)
    config = StudyConfig(horizon=40, members=("hindsight",))
    la = simulate(
        eating,
        LinearDecoder(),
        cohort,
        eating.robot.control,
        config,
        seed=2,
        progress=False,
        interfaces=("LA",),
    )
    assert set(la.condition) == {"LA", "LA+SA"}
    full = [
        (p, c, a, t)
        for p, c, a, t in zip(
            small_study.participant,
            small_study.condition,
            small_study.assistance,
            small_study.task,
            strict=True,
        )
    ]
    for e, key in enumerate(zip(la.participant, la.condition, la.assistance, la.task, strict=True)):
        f = full.index(key)
        assert la.end[e] == small_study.end[f]
        np.testing.assert_allclose(la.states[:, e], small_study.states[:, f])
    assert la.belief.shape == la.states.shape[:2] + (eating.n_goals,)
    assert np.allclose(la.belief.sum(axis=-1), 1.0)
    with pytest.raises(ConfigError, match="interfaces"):
        simulate(eating, LinearDecoder(), cohort, eating.robot.control, config, progress=False, interfaces=())
