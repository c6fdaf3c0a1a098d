"""The cup task: IK reaches every grasp pose; the preference curves are smooth."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from lasa.base.errors import ConfigError, IKError
from lasa.world.ik import pose_error, solve_grasp_ik
from lasa.world.task import grasp_frame

POS_TOL = 2e-3  # m
ROT_TOL = np.deg2rad(1.0)  # rad


def test_ik_reaches_grasp_poses_on_grid(task):
    robot = task.robot
    for g in range(task.n_goals):
        for k, theta in enumerate(task.theta_grid):
            q = task.curves[g, k]
            pos_err, rot_err = pose_error(robot, q, *grasp_frame(robot, g, theta))
            assert pos_err < 1e-3 and rot_err < 1e-2, (g, theta, pos_err, rot_err)
            assert np.all(q >= robot.lower) and np.all(q <= robot.upper)


def test_interpolated_targets_reach_grasp_poses(task):
    robot = task.robot
    rng = np.random.default_rng(0)
    for g in range(task.n_goals):
        for theta in rng.uniform(0, 1, 25):
            pos_err, rot_err = pose_error(robot, task.target(g, theta), *grasp_frame(robot, g, theta))
            assert pos_err < POS_TOL and rot_err < ROT_TOL


def test_top_and_side_grasps_point_the_right_way(task):
    robot = task.robot
    for g, sign in ((0, -1.0), (1, 1.0)):
        _, rot_top = robot.grasp_pose(task.target(g, 0.0))
        _, rot_side = robot.grasp_pose(task.target(g, 1.0))
        assert_allclose(rot_top[:, 2], [0, 0, -1], atol=1e-2)  # fingers down
        assert_allclose(rot_side[:, 2], [sign, 0, 0], atol=1e-2)  # horizontal, away from base


def test_goals_are_mid_preference_and_mirror_symmetric(task):
    robot = task.robot
    for g in range(2):  # each goal's joints put the gripper at its cup's mid-preference grasp frame
        pos_err, rot_err = pose_error(robot, task.goals[g], *grasp_frame(robot, g, 0.5))
        assert pos_err < POS_TOL and rot_err < ROT_TOL
    # the scene is symmetric about x = 0, so the left cup's curve mirrors the right's
    assert_allclose(task.curves[0], -task.curves[1], atol=1e-3)


def test_curves_are_smooth(task):
    steps = np.linalg.norm(np.diff(task.curves, axis=1), axis=-1)
    assert steps.max() < 3 * np.median(steps)


def test_target_is_vectorised(task):
    goal = np.array([0, 1, 1])
    theta = np.array([0.1, 0.2, 0.9])
    batched = task.target(goal, theta)
    single = np.stack([task.target(g, t) for g, t in zip(goal, theta, strict=True)])
    assert_allclose(batched, single)


@pytest.mark.parametrize("theta", [-0.1, 1.1, np.nan])
def test_bad_theta_is_a_clear_error(task, theta):
    with pytest.raises(ConfigError, match="theta"):
        task.target(0, theta)


def test_bad_goal_is_a_clear_error(task):
    with pytest.raises(ConfigError, match="goal index"):
        task.target(2, 0.5)


def test_unreachable_pose_raises_ik_error(robot):
    far = np.array([3.0, 0.0, 0.5])
    with pytest.raises(IKError, match="did not converge"):
        solve_grasp_ik(robot, far, np.eye(3), robot.home, max_iters=50)


def test_a_solve_after_others_equals_a_solve_with_fresh_mink_objects(robot):
    """solve_grasp_ik reuses mink's objects per robot: no solve may carry state into the next."""
    from lasa.world import ik  # noqa: PLC0415

    rng = np.random.default_rng(3)
    qs = [robot.clip(robot.home + rng.normal(0.0, 0.3, robot.n_joints)) for _ in range(3)]
    poses = [robot.grasp_pose(q) for q in qs]
    seed = robot.clip(robot.home + 0.05)
    after_others = []
    for pose in poses:
        with pytest.raises(IKError):  # a failed solve before each: it leaves the objects mid-iteration
            solve_grasp_ik(robot, np.array([3.0, 0.0, 0.5]), np.eye(3), robot.home, max_iters=5)
        after_others.append(solve_grasp_ik(robot, *pose, seed, position_tol=1e-5))
    for pose, expected in zip(poses, after_others, strict=True):
        ik._SOLVERS.clear()  # fresh objects, as every solve made them before they were reused
        assert np.array_equal(solve_grasp_ik(robot, *pose, seed, position_tol=1e-5), expected)
