"""The assistance family (lasa.method.assistance): each member against a hand-computed two-goal case."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose

from lasa.base.config import ControlConfig
from lasa.base.errors import ConfigError
from lasa.method.assistance import ASSISTANCE, assist, nearest_grasps

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


def test_hindsight_is_the_belief_weighted_distance_gradient_at_sigma_h():
    # both goals are sqrt(1.25) away: a_r = 0.5 (0.75 (1, -0.5) + 0.25 (-1, -0.5)) / sqrt(1.25)
    a_r, w = run("hindsight")
    assert_allclose(a_r, 0.5 * np.array([[0.5, -0.5]]) / np.sqrt(1.25))
    assert_allclose(w, [1.0])
    # within delta = 0.05 of the goal the cost is quadratic: a_r = sigma_h (g - s) / delta
    a_r, _ = run("hindsight", belief=np.array([[1.0, 0.0]]), state=np.array([[1.0, 0.02]]))
    assert_allclose(a_r, 0.5 * np.array([[0.0, -0.02]]) / 0.05)
    assert np.linalg.norm(run("hindsight", state=np.array([[40.0, -7.0]]))[0]) <= SPEED + 1e-12


def test_every_member_is_batched_and_names_are_checked():
    rng = np.random.default_rng(0)
    states = rng.normal(size=(7, 2))
    beliefs = rng.dirichlet(np.ones(2), 7)
    for name in ASSISTANCE:
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

    assert tuple(assistance._MEMBERS) == ASSISTANCE  # each named member is implemented, and no other
    assert ControlConfig().assistance == "point"
    for name in ASSISTANCE:
        assert dataclasses.replace(ControlConfig(), assistance=name).assistance == name


@pytest.mark.parametrize("name", ASSISTANCE)
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
        stream=np.arange(n),
    )
    noise = np.random.default_rng(0).random((n, 15, control.n_z))
    traj = rollout(model, task, users, np.array([0.0, 0.2, 0.5, 1.0]), control, 15, noise)
    robot = task.robot
    assert np.all(traj.states >= robot.lower) and np.all(traj.states <= robot.upper)
    assert np.all(np.abs(np.diff(traj.states, axis=0)) <= control.dt * control.max_joint_speed + 1e-12)
    assert_allclose(traj.actions[:, 0], traj.human_actions[:, 0])  # LA: a = a_h whatever the member
