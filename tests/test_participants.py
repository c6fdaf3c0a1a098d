"""Simulated participants: counterbalancing, learning, the measures by hand, and a small study."""

import dataclasses
import itertools
import math

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from stand_ins import LinearDecoder

from lasa.base.conditions import CONDITIONS, williams_square
from lasa.base.config import NO_ASSISTANCE
from lasa.base.errors import ConfigError
from lasa.people.cohort import ParticipantConfig, draw_cohort
from lasa.people.design import StudyConfig
from lasa.people.participants import simulate
from lasa.world.eating import make_eating_task
from lasa.world.fork import tip_frames, tip_motion
from lasa.world.measures import alignment, goal_error, idle_time, measures


@pytest.fixture(scope="module")
def eating():
    return make_eating_task()


@pytest.fixture(scope="module")
def small_study(eating):
    cohort = draw_cohort(2, seed=1)
    config = StudyConfig(horizon=40, assistance=("hindsight", "grasp_set"))
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
        StudyConfig(horizon=40, assistance=("hindsight", "grasp_set")),
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
    # Goal Error of a few episodes by hand, a step at a time: the tip's distance to the closest of the
    # four goals (and of the three bowls: rice, middle, icing), over the steps the episode ran, times dt
    goals = eating.robot.goal_positions()
    for e in (0, 7, len(small_study.end) - 1):
        steps = range(int(small_study.end[e]))
        tips = [small_study.tip[t, e] for t in steps]
        every = sum(min(math.dist(tip, goal) for goal in goals) for tip in tips) * small_study.dt
        bowls = sum(min(math.dist(tip, goal) for goal in goals[:3]) for tip in tips) * small_study.dt
        assert frames["goal_error"].goal_error[e] == pytest.approx(every, rel=1e-12)
        assert frames["goal_error"].goal_error_bowls[e] == pytest.approx(bowls, rel=1e-12)


def test_goal_error_on_a_small_case_by_hand():
    """Two goals 1 m apart; episode 0 runs three steps, episode 1 two (its third is not counted)."""
    goals = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    tip = np.array(
        [
            [[0.1, 0.0, 0.0], [2.0, 0.0, 0.0]],  # 0.1 from goal 0; 1.0 from goal 1
            [[0.3, 0.4, 0.0], [1.0, 0.6, 0.8]],  # 0.5 from goal 0 (3-4-5); 1.0 from goal 1
            [[1.0, 0.0, 0.2], [0.5, 0.0, 0.0]],  # 0.2 from goal 1; 0.5 from either, after the end
        ]
    )
    active = np.array([[True, True], [True, True], [True, False]])
    assert_allclose(goal_error(tip, goals, active, dt=0.1), [(0.1 + 0.5 + 0.2) * 0.1, (1.0 + 1.0) * 0.1])


def test_tip_motion_is_the_first_order_motion_of_the_kinematics(eating):
    """tip_motion predicts, from the Jacobians, the fork tip's displacement and new direction for a
    joint step dq; finite differences of the kinematics (tip_frames at q + dq) must agree to second
    order in the step, and the miss must shrink four-fold when the step halves.

    Tolerance, for steps of h = 1e-4 rad along unit joint directions u: the tip's second derivative
    along u is at most (sum |u_i|)^2 R <= n R, R the largest distance from the tip to a joint axis
    (under 1.5 m on the Panda with its fork), so the first-order displacement misses by at most
    n R h^2 / 2 = 5.3e-8 m; the direction, a unit vector that turns at most sum |u_i| <= sqrt(n)
    radians per radian, by at most n h^2 = 7e-8 (the turn's second order and the renormalisation).
    A wrong Jacobian column would miss by the order of h = 1e-4."""
    robot = eating.robot
    data = mujoco.MjData(robot.model)
    rng = np.random.default_rng(0)
    qs = rng.uniform(robot.lower + 0.2, robot.upper - 0.2, (5, robot.n_joints))
    units = rng.normal(size=(5, 6, robot.n_joints))
    units /= np.linalg.norm(units, axis=-1, keepdims=True)
    pos, axis, jp, jr = tip_frames(robot, data, qs)

    def misses(h: float) -> tuple[float, float]:
        dp, new_dir = tip_motion(jp, jr, axis, h * units)
        moved = (qs[:, None, :] + h * units).reshape(-1, robot.n_joints)
        pos_h, axis_h, _, _ = tip_frames(robot, data, moved)
        dp_fd = pos_h.reshape(dp.shape) - pos[:, None, :]
        return np.abs(dp_fd - dp).max(), np.abs(axis_h.reshape(new_dir.shape) - new_dir).max()

    n, reach, h = robot.n_joints, 1.5, 1e-4
    position_miss, direction_miss = misses(h)
    assert position_miss <= n * reach * h**2 / 2
    assert direction_miss <= n * h**2
    coarse, half = misses(1e-2), misses(5e-3)  # second order: halving the step quarters the miss
    assert 3.0 < coarse[0] / half[0] < 5.0 and 3.0 < coarse[1] / half[1] < 5.0


def test_bad_settings_are_errors(eating):
    with pytest.raises(ConfigError, match="n_z"):
        StudyConfig(n_z=4)
    for assistance in [("telepathy",), (), ("point", "point")]:
        with pytest.raises(ConfigError, match="assistance"):
            StudyConfig(assistance=assistance)
    with pytest.raises(ConfigError, match=r"practice_max must be in \[100, inf\]"):
        ParticipantConfig(practice_min=100.0, practice_max=50.0)
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
    config = StudyConfig(horizon=40, assistance=("hindsight",))
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


def test_the_one_step_chooser_is_the_jacobian_foresight_argmax_by_hand(eating):
    """A near-deterministic one-step participant (beta ~ 1e7) under LA: the first input is the
    candidate whose first-order tip motion (MuJoCo's site Jacobian, one candidate at a time) most
    lowers ||p - p*|| + l angle(d, d*), and the robot moves by it (alpha = 0: a = a_h)."""
    from reference_step import site_frame

    from lasa.world.eating import waypoints
    from lasa.world.fork import WaypointTracker

    participant = ParticipantConfig(beta_median=1e7, beta_spread=0.0)
    config = StudyConfig(horizon=1, participant=participant)
    decoder, control = LinearDecoder(seed=3), eating.robot.control
    record = simulate(
        eating, decoder, draw_cohort(1, participant, seed=4), control, config, 0, False, ("LA",)
    )
    robot, s0 = eating.robot, eating.start
    pos, rot, jac = site_frame(robot, s0)
    jp, jr, axis = jac[:3], jac[3:], rot[:, 2]
    tracker = WaypointTracker.of(robot)
    wp_pos, wp_dir = tracker.position, tracker.direction
    axis_grid = np.linspace(-1.0, 1.0, config.n_z)
    grid = [np.array([a, b]) for a in axis_grid for b in axis_grid]
    unit, weight = control.dt * config.retarget.linear_speed, participant.rotation_weight

    def cost(p, d, p_star, d_star):
        return np.linalg.norm(p - p_star) + weight * math.acos(np.clip(d @ d_star, -1.0, 1.0))

    la = np.flatnonzero(record.condition == "LA")
    assert len(la) == 2 and all(waypoints(t) for t in ("Entree", "Dessert"))
    for e in la:
        k = ["Entree", "Dessert"].index(record.task[e])
        p_star, d_star = wp_pos[k, 0], wp_dir[k, 0]
        best, best_phi = -math.inf, np.zeros(7)
        for z in grid:
            if not z.any():
                continue  # rest moves nothing
            phi = decoder.decode_numpy(z[None], s0[None], np.full((1, 4), 0.25))[0]
            dq = control.dt * phi
            new_dir = axis + np.cross(jr @ dq, axis)
            new_dir /= np.linalg.norm(new_dir)
            gain = (cost(pos, axis, p_star, d_star) - cost(pos + jp @ dq, new_dir, p_star, d_star)) / unit
            if gain > best:
                best, best_phi = gain, phi
        assert best >= participant.idle_threshold  # worth a push: not idle
        assert not record.idle[0, e]
        expected = np.clip(
            s0 + control.dt * np.clip(best_phi, -control.max_joint_speed, control.max_joint_speed),
            robot.lower,
            robot.upper,
        )
        assert_allclose(record.states[1, e], expected, atol=1e-12)
