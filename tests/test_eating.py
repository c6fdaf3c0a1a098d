"""The eating scene, its preferences, the IK of its strokes, its phases and its demonstrations."""

import warnings

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_allclose

from lasa.base.errors import ConfigError
from lasa.method.belief import confidence_threshold
from lasa.method.dataset import REACH
from lasa.people.demos import DemoConfig, collect_eating_demonstrations
from lasa.world.eating import (
    EATING,
    GOALS,
    PREFERENCES,
    STROKE,
    TILT_MAX,
    fork_direction,
    fork_frame,
    load_eating_robot,
    make_eating_task,
    stroke_direction,
    waypoints,
)
from lasa.world.fork import tip_frames
from lasa.world.robot import Robot


@pytest.fixture(scope="module")
def eating():
    return make_eating_task()


def test_scene_compiles_and_steps_without_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an attach without a prefix, for one, warns
        robot = Robot(EATING)
    data = mujoco.MjData(robot.model)
    mujoco.mj_resetDataKeyframe(robot.model, data, robot.model.key("home").id)
    for _ in range(50):
        mujoco.mj_step(robot.model, data)
    assert all(w.number == 0 for w in data.warning), [w.number for w in data.warning]


def test_every_object_is_named():
    model = load_eating_robot().model
    for body in ("bowl_left", "bowl_middle", "bowl_right", "plate", "fork_body"):
        model.body(body)
    for geom in ("table", "rice", "tofu", "icing", "plate", "fork_handle", "fork_tine_1", "fork_tine_4"):
        model.geom(geom)
    for i in (1, 2, 3):
        model.geom(f"marshmallow_{i}")
    for site in ("bowl_left", "bowl_middle", "bowl_right", "plate", "fork_tip", "grasp"):
        model.site(site)
    model.camera("table")


def test_the_fork_tip_is_its_length_beyond_the_tcp_along_the_hand():
    robot = load_eating_robot()
    data = mujoco.MjData(robot.model)
    data.qpos[robot.qpos_adr] = robot.home
    mujoco.mj_kinematics(robot.model, data)
    tcp, tip = data.site("grasp"), data.site("fork_tip")
    assert_allclose(tip.xpos, tcp.xpos + 0.125 * tcp.xmat.reshape(3, 3)[:, 2], atol=1e-9)
    assert_allclose(tip.xmat, tcp.xmat, atol=1e-9)  # the fork's axes are the hand's


def test_preference_directions_by_hand():
    robot = load_eating_robot()
    down = np.array([0.0, 0.0, -1.0])
    for g in range(len(GOALS)):
        assert_allclose(fork_direction(robot, g, PREFERENCES["stab"]), down, atol=1e-12)
        scoop = fork_direction(robot, g, PREFERENCES["scoop"])
        assert np.isclose(np.linalg.norm(scoop), 1.0)
        assert np.isclose(np.arccos(-scoop[2]), TILT_MAX)  # 60 degrees from straight down
        cut = fork_direction(robot, g, PREFERENCES["cut"])
        assert np.isclose(np.arccos(-cut[2]), TILT_MAX / 2)
        assert_allclose(stroke_direction(robot, g, 0.0), down, atol=1e-12)
        assert np.isclose(stroke_direction(robot, g, 1.0)[2], 0.0)  # a scoop drags horizontally
    # the directions are vectorised over theta
    assert fork_direction(robot, 0, np.linspace(0, 1, 5)).shape == (5, 3)


def test_stroke_geometry():
    robot = load_eating_robot()
    for g in range(len(GOALS)):
        entry, _ = fork_frame(robot, g, 0.0, 0.0)
        end, rot = fork_frame(robot, g, 0.0, 1.0)
        surface = robot.goal_positions()[g]
        assert np.isclose(np.linalg.norm(end - entry), STROKE)
        assert np.isclose(end[2], surface[2] - 0.01)  # ends 1 cm into the food
        assert_allclose(rot[:, 2], fork_direction(robot, g, 0.0), atol=1e-12)
    with pytest.raises(ConfigError, match="theta"):
        fork_frame(robot, 0, 1.5, 0.0)
    with pytest.raises(ConfigError, match="depth"):
        fork_frame(robot, 0, 0.5, -0.1)


def test_ik_puts_the_fork_where_each_preference_needs_it(eating):
    robot = eating.robot
    data = mujoco.MjData(robot.model)
    for g in range(eating.n_goals):
        for theta in (0.0, 0.5, 1.0):
            for depth in (0.0, 0.5, 1.0):
                pos, rot = fork_frame(robot, g, theta, depth)
                tip, axis, _, _ = tip_frames(robot, data, eating.pose(g, theta, depth)[None])
                assert np.linalg.norm(tip[0] - pos) < 2e-3
                assert np.arccos(np.clip(axis[0] @ rot[:, 2], -1, 1)) < 0.01
    assert_allclose(eating.goals, eating.strokes[:, eating.strokes.shape[1] // 2, 0])  # mid-tilt entries
    assert eating.preference_sets.shape == (4, 2 * len(eating.theta_grid), 7)
    assert np.all(eating.strokes >= robot.lower) and np.all(eating.strokes <= robot.upper)


def test_phases_visit_the_goals_in_the_papers_order():
    dessert = waypoints("Dessert")
    assert [GOALS[w.goal] for w in dessert] == ["middle"] * 2 + ["icing"] * 2 + ["rice"] * 2 + ["plate"] * 2
    assert [w.theta for w in dessert] == [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0]
    assert [w.depth for w in dessert] == [0.0, 1.0] * 4
    entree = waypoints("Entree")
    assert [GOALS[w.goal] for w in entree] == ["middle"] * 5 + ["plate"] * 2
    assert [w.theta for w in entree[:3]] == [0.0, 0.5, 0.5]  # the reach, then the cut's stroke
    with pytest.raises(ConfigError, match="task"):
        waypoints("Breakfast")


def test_a_demonstration_reaches_each_bowl(eating):
    control = eating.robot.control
    config = DemoConfig(n_theta=2, n_starts=1, n_adjust=0, n_perturb=0, seed=3)
    demos = collect_eating_demonstrations(eating, control, config)
    data = mujoco.MjData(eating.robot.model)
    reached = set()
    for d in np.unique(demos.demo):
        rows = np.flatnonzero((demos.demo == d) & (demos.phase == REACH))
        last = rows[-1] + 1  # the state after the reach's last step
        g, theta = int(demos.goal[rows[0]]), float(demos.theta[rows[0]])
        tip = tip_frames(eating.robot, data, demos.states[last][None])[0][0]
        assert np.linalg.norm(tip - fork_frame(eating.robot, g, theta, 0.0)[0]) < 0.01
        end = np.flatnonzero(demos.demo == d)[-1]
        assert demos.beliefs[end, g] > 0.9  # the online belief found the demonstrated goal
        reached.add(g)
    assert reached == set(range(len(GOALS)))
    # a move from another goal starts from the belief held there, not from a uniform one
    starts = np.r_[0, np.flatnonzero(np.diff(demos.demo)) + 1]
    confident = demos.beliefs[starts].max(axis=1) > confidence_threshold(control.belief_cap)
    assert confident.sum() == len(starts) - len(np.unique(demos.goal)) * 2


def test_poses_of_many_tilts_and_depths_are_each_ones_pose(eating):
    """pose() on arrays is pose() on each (theta, u): the same numbers, bit for bit, any depth stretch."""
    rng = np.random.default_rng(3)
    thetas, depths = rng.uniform(0, 1, 40), np.r_[rng.uniform(0, 1, 37), 0.0, 0.5, 1.0]
    many = eating.pose(2, thetas, depths)
    assert many.shape == (40, eating.robot.n_joints)
    one = np.stack([eating.pose(2, float(t), float(u)) for t, u in zip(thetas, depths, strict=True)])
    np.testing.assert_array_equal(many, one)
    assert eating.pose(2, 0.5, np.array([0.0, 1.0])).shape == (2, eating.robot.n_joints)  # broadcast
    with pytest.raises(ConfigError, match="depth"):
        eating.pose(2, thetas[:2], np.array([0.5, 1.2]))
