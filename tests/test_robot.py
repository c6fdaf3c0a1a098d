"""The planar5 model: compiles and steps without warnings; named quantities."""

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_allclose

from lasa.base.errors import ConfigError
from lasa.world.robot import ROBOTS, load_robot


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_scene_compiles_and_steps_without_warnings(name):
    robot = load_robot(name)
    data = mujoco.MjData(robot.model)
    mujoco.mj_resetDataKeyframe(robot.model, data, robot.model.key(robot.spec.home_key).id)
    for _ in range(200):
        mujoco.mj_step(robot.model, data)
    assert all(w.number == 0 for w in data.warning), [w.number for w in data.warning]
    assert np.all(np.isfinite(data.qpos))


def test_unknown_robot_is_a_clear_error():
    with pytest.raises(ConfigError, match="unknown robot 'ur5'.*planar5.*panda"):
        load_robot("ur5")


def test_missing_mesh_package_is_a_clear_error():
    import dataclasses

    from lasa.base.errors import ArtifactError
    from lasa.world.robot import Robot

    spec = dataclasses.replace(ROBOTS["panda"], mesh_package=("no_such_package_xyz", "meshes"))
    with pytest.raises(ArtifactError, match="not installed; run: make setup"):
        Robot(spec)


def test_planar5_named_quantities(robot):
    assert robot.n_joints == 5
    assert np.all(robot.lower < 0) and np.all(robot.upper > 0)
    assert_allclose(robot.home, np.zeros(5))
    # straight up at home: grasp site above the base, pointing up
    pos, rot = robot.grasp_pose(robot.home)
    assert_allclose(pos[[0, 1]], [0.0, 0.0], atol=1e-12)
    assert_allclose(pos[2], 0.12 + 0.30 + 0.25 + 0.15 + 0.10 + 0.09)
    assert_allclose(rot[:, 2], [0.0, 0.0, 1.0], atol=1e-12)
    cups = robot.goal_positions()
    assert_allclose(cups[:, 0], [-0.45, 0.45])


def test_planar_arm_stays_in_its_plane(robot):
    rng = np.random.default_rng(0)
    qs = rng.uniform(robot.lower, robot.upper, size=(50, robot.n_joints))
    assert_allclose(robot.grasp_positions(qs)[:, 1], 0.0, atol=1e-12)
    assert_allclose(robot.grasp_axes(qs)[:, 1], 0.0, atol=1e-12)


def test_clip_respects_limits(robot):
    q = robot.clip(np.full(robot.n_joints, 100.0))
    assert_allclose(q, robot.upper)


@pytest.mark.parametrize("name", ["planar5", "panda", "eating"])
def test_the_package_scenes_meet_the_naming_contract_load_robot_checks(name):
    from lasa.world.eating import EATING
    from lasa.world.robot import scene_problems

    spec = EATING if name == "eating" else ROBOTS[name]
    assert scene_problems(spec) == []  # angles in radians too
    if name != "eating":
        assert load_robot(spec).name == name  # the package's own spec, passed as an object
    assert len(spec.ik_guesses) == len(spec.goal_sites)
