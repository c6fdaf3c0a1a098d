"""The assistance family (lasa.method.assistance): each member against a hand-computed two-goal case."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.testing import assert_allclose

from lasa.base.config import BUILT_IN_ASSISTANCE, ControlConfig
from lasa.base.errors import ConfigError
from lasa.method.assistance import assist, hindsight_value, nearest_grasps

# Two goals in a 2-D joint space. Goal 0 is the point (1, 0), its grasps the segment from
# (1, -1) to (1, 1); goal 1 the point (-1, 0), its grasps the segment from (-1, -1) to (-1, 1).
GOALS = np.array([[1.0, 0.0], [-1.0, 0.0]])
SETS = np.array([[[1.0, -1.0], [1.0, 0.0], [1.0, 1.0]], [[-1.0, -1.0], [-1.0, 0.0], [-1.0, 1.0]]])
STATE = np.array([[0.0, 0.5]])
BELIEF = np.array([[0.75, 0.25]])
DT, SPEED = 0.1, 0.5  # delta = DT * SPEED = 0.05


def run(name, belief=BELIEF, state=STATE):
    return assist(name, belief, state, GOALS, SETS, DT, SPEED)


def test_point_is_eq_m2():
    # a_r = 0.75 ((1, 0) - (0, 0.5)) + 0.25 ((-1, 0) - (0, 0.5)) = (0.5, -0.5)
    a_r, w = run("point")
    assert_allclose(a_r, [[0.5, -0.5]])
    assert_allclose(w, [1.0])


def test_grasp_set_pulls_onto_the_nearest_grasp_of_each_goal():
    # nearest grasps of (0, 0.5): (1, 0.5) and (-1, 0.5); a_r = 0.75 (1, 0) + 0.25 (-1, 0) = (0.5, 0)
    assert_allclose(nearest_grasps(STATE, SETS), [[[1.0, 0.5], [-1.0, 0.5]]])
    a_r, w = run("grasp_set")
    assert_allclose(a_r, [[0.5, 0.0]])
    assert_allclose(w, [1.0])
    # a state on a goal's curve, believed for sure, is a fixed point: any grasp can be held
    a_r, _ = run("grasp_set", belief=np.array([[1.0, 0.0]]), state=np.array([[1.0, 0.8]]))
    assert_allclose(a_r, [[0.0, 0.0]], atol=1e-12)
    # ... while point pulls it back to the mid-preference pose
    a_r, _ = run("point", belief=np.array([[1.0, 0.0]]), state=np.array([[1.0, 0.8]]))
    assert_allclose(a_r, [[0.0, -0.8]])


def test_nearest_grasps_clip_to_the_ends_of_the_curve():
    far = np.array([[3.0, 5.0]])
    assert_allclose(nearest_grasps(far, SETS), [[[1.0, 1.0], [-1.0, 1.0]]])


def test_arbitrated_pulls_to_the_likeliest_goal_with_confidence_weight():
    # g_hat = goal 0: a_r = (1, 0) - (0, 0.5) = (1, -0.5); w = (0.75 - 0.5) / (1 - 0.5) = 0.5
    a_r, w = run("arbitrated")
    assert_allclose(a_r, [[1.0, -0.5]])
    assert_allclose(w, [0.5])
    _, w = run("arbitrated", belief=np.array([[0.5, 0.5]]))
    assert_allclose(w, [0.0])  # no say while the belief is uniform
    _, w = run("arbitrated", belief=np.array([[0.0, 1.0]]))
    assert_allclose(w, [1.0])


def test_hindsight_point_is_the_belief_weighted_distance_gradient_at_sigma_h():
    # both goal poses are sqrt(1.25) away: a_r = 0.5 (0.75 (1, -0.5) + 0.25 (-1, -0.5)) / sqrt(1.25)
    a_r, w = run("hindsight_point")
    assert_allclose(a_r, 0.5 * np.array([[0.5, -0.5]]) / np.sqrt(1.25))
    assert_allclose(w, [1.0])
    # within delta = 0.05 of the goal the cost is quadratic: a_r = sigma_h (g - s) / delta
    a_r, _ = run("hindsight_point", belief=np.array([[1.0, 0.0]]), state=np.array([[1.0, 0.02]]))
    assert_allclose(a_r, 0.5 * np.array([[0.0, -0.02]]) / 0.05)
    assert np.linalg.norm(run("hindsight_point", state=np.array([[40.0, -7.0]]))[0]) <= SPEED + 1e-12


def test_hindsight_pulls_to_the_nearest_target_of_each_goal_by_hand():
    # nearest targets of (0, 0.5): (1, 0.5) and (-1, 0.5), each 1 away (> delta):
    # a_r = 0.5 (0.75 (1, 0) / 1 + 0.25 (-1, 0) / 1) = (0.25, 0)
    a_r, w = run("hindsight")
    assert_allclose(a_r, [[0.25, 0.0]])
    assert_allclose(w, [1.0])
    # within delta of goal 0's set, (1.03, 0.9): the quadratic part, sigma_h (c - s) / delta
    a_r, _ = run("hindsight", belief=np.array([[1.0, 0.0]]), state=np.array([[1.03, 0.9]]))
    assert_allclose(a_r, 0.5 * np.array([[-0.03, 0.0]]) / 0.05)
    # V of goal 0 at (0, 0.5): distance 1; of goal 1 at (-1.02, 0): 0.02^2 / 0.1 + 0.025 = 0.029
    assert_allclose(hindsight_value(np.array([[0.0, 0.5], [-1.02, 0.0]]), SETS, 0.05)[:, 0][0], 1.0)
    assert_allclose(hindsight_value(np.array([[-1.02, 0.0]]), SETS, 0.05)[0, 1], 0.029)


@settings(max_examples=80, deadline=None)
@given(
    far=arrays(np.float64, (1, 2), elements=st.floats(-3, 3)),
    near=st.tuples(st.sampled_from([-1.0, 1.0]), st.floats(-0.1, 0.1), st.floats(-1.05, 1.05)),
    at_set=st.booleans(),
    b0=st.floats(0.0, 1.0),
)
def test_hindsight_is_minus_sigma_h_times_the_gradient_of_the_expected_cost(far, near, at_set, b0):
    """a_r = -sigma_h grad_s sum_g b(g) V_g(s), checked by central differences of V.

    Half the states lie within 0.1 of a goal's set, where the Huber radius (0.05) matters.
    """
    state = np.array([[near[0] + near[1], near[2]]]) if at_set else far
    belief = np.array([[b0, 1.0 - b0]])
    delta, h = DT * SPEED, 1e-6
    near = nearest_grasps(state, SETS)[0]  # the distance to a set is not differentiable where
    # two nearest points tie or at a target (within h of one), so keep away from such states
    ties = np.linalg.norm(near - state[0], axis=-1)
    assume(np.all(ties > 10 * h) and np.all(np.abs(np.abs(state[0, 1]) - 1.0) > 1e-3))
    assume(np.all(np.abs(ties - delta) > 1e-4))

    def expected(s):
        return float(hindsight_value(s[None], SETS, delta)[0] @ belief[0])

    grad = np.array([(expected(state[0] + h * e) - expected(state[0] - h * e)) / (2 * h) for e in np.eye(2)])
    a_r, _ = run("hindsight", belief=belief, state=state)
    assert_allclose(a_r[0], -SPEED * grad, atol=1e-5)


@settings(max_examples=40, deadline=None)
@given(y=st.floats(-1.0, 1.0), goal=st.sampled_from([0, 1]))
def test_hindsight_holds_any_target_of_a_confident_goal(y, goal):
    """With a confident belief, every pose on the goal's set is a fixed point (a_r = 0)..."""
    belief = np.eye(2)[[goal]]
    on_set = np.array([[1.0 if goal == 0 else -1.0, y]])
    a_r, _ = run("hindsight", belief=belief, state=on_set)
    assert_allclose(a_r, 0.0, atol=1e-12)
    # ... while the one-target reading pulls back to the goal's mid pose, unless it is there
    pulled, _ = run("hindsight_point", belief=belief, state=on_set)
    assert np.linalg.norm(pulled) > 0 or abs(y) < 1e-12


@settings(max_examples=40, deadline=None)
@given(state=arrays(np.float64, (1, 2), elements=st.floats(-3, 3)), goal=st.sampled_from([0, 1]))
def test_hindsight_and_grasp_set_agree_in_direction_for_a_confident_belief(state, goal):
    """Both pull towards the nearest target of the believed goal; they differ only in size."""
    belief = np.eye(2)[[goal]]
    h, _ = run("hindsight", belief=belief, state=state)
    g, _ = run("grasp_set", belief=belief, state=state)
    dist = np.linalg.norm(g)
    assert_allclose(h, SPEED * g / max(dist, DT * SPEED), atol=1e-12)


def test_every_member_is_batched_and_names_are_checked():
    rng = np.random.default_rng(0)
    states = rng.normal(size=(7, 2))
    beliefs = rng.dirichlet(np.ones(2), 7)
    for name in BUILT_IN_ASSISTANCE:
        a_r, w = assist(name, beliefs, states, GOALS, SETS, DT, SPEED)
        one = [assist(name, beliefs[i : i + 1], states[i : i + 1], GOALS, SETS, DT, SPEED) for i in range(7)]
        assert_allclose(a_r, np.concatenate([o[0] for o in one]))
        assert_allclose(w, np.concatenate([o[1] for o in one]))
        assert a_r.shape == (7, 2) and w.shape == (7,) and np.all((w >= 0) & (w <= 1))
    with pytest.raises(ConfigError, match="unknown assistance 'nearest'"):
        assist("nearest", BELIEF, STATE, GOALS, SETS, DT, SPEED)
    with pytest.raises(ConfigError, match="assistance"):
        ControlConfig(assistance="nearest")


def test_the_config_knows_every_member_and_defaults_to_point():
    from lasa.method import assistance

    assert tuple(assistance.MEMBERS) == BUILT_IN_ASSISTANCE  # each named member is implemented, no other
    assert ControlConfig().assistance == "point"
    for name in BUILT_IN_ASSISTANCE:
        assert dataclasses.replace(ControlConfig(), assistance=name).assistance == name


@pytest.mark.parametrize("name", BUILT_IN_ASSISTANCE)
def test_each_member_drives_the_rollout_safely(name, model, task):
    """LA+SA with each member: limits, step bound, and alpha = 0 still ignores the assistance."""
    from lasa.people.rollout import rollout
    from lasa.people.users import UserPopulation

    control = dataclasses.replace(task.robot.control, assistance=name)
    n = 4
    users = UserPopulation(
        goal=np.arange(n) % 2,
        theta=np.linspace(0, 1, n),
        target=task.target(np.arange(n) % 2, np.linspace(0, 1, n)),
        beta0=np.full(n, 300.0),
        slope=np.zeros(n),
        user=np.arange(n),
    )
    noise = np.random.default_rng(0).random((n, 15, control.n_z))
    traj = rollout(model, task, users, np.array([0.0, 0.2, 0.5, 1.0]), control, 15, noise)
    robot = task.robot
    assert np.all(traj.states >= robot.lower) and np.all(traj.states <= robot.upper)
    assert np.all(np.abs(np.diff(traj.states, axis=0)) <= control.dt * control.max_joint_speed + 1e-12)
    assert_allclose(traj.actions[:, 0], traj.human_actions[:, 0])  # LA: a = a_h whatever the member


def _nearest_by_every_segment(state, goal_sets):
    """The reference: every segment's nearest point and distance, the first nearest per goal."""
    a, ab = goal_sets[:, :-1], np.diff(goal_sets, axis=1)
    rel = state[:, None, None, :] - a[None]
    den = np.maximum(np.einsum("gkn,gkn->gk", ab, ab), 1e-12)
    t = np.clip(np.einsum("ugkn,gkn->ugk", rel, ab) / den, 0, 1)
    closest = a[None] + t[..., None] * ab[None]
    k = np.linalg.norm(state[:, None, None, :] - closest, axis=-1).argmin(axis=-1)
    return np.take_along_axis(closest, k[..., None, None], axis=2)[:, :, 0]


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), on_set=st.booleans())
def test_nearest_grasps_is_every_segments_nearest(seed, on_set):
    rng = np.random.default_rng(seed)
    sets = np.cumsum(rng.normal(0, 0.3, (3, 6, 4)), axis=1)  # folded polylines in 4-D
    state = rng.normal(0, 1.0, (50, 4))
    if on_set:  # on the polylines, and at their vertices: where segments tie
        k, t = rng.integers(0, 5, 50), rng.choice([0.0, 1.0, rng.uniform()], 50)
        g = rng.integers(0, 3, 50)
        state = sets[g, k] + t[:, None] * (sets[g, k + 1] - sets[g, k])
    np.testing.assert_array_equal(nearest_grasps(state, sets), _nearest_by_every_segment(state, sets))
