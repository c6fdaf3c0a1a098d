"""lasa.world.chain: the batched site kinematics against MuJoCo's, one configuration at a time."""

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from reference_step import site_frame

from lasa.world.chain import SerialChain
from lasa.world.robot import load_robot


@pytest.mark.parametrize("name", ["panda", "planar5"])
@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_the_chain_is_mujocos_kinematics(name, seed):
    robot = load_robot(name)
    chain = SerialChain.of(robot.model, robot.model.site(robot.spec.grasp_site).id, robot.qpos_adr)
    assert chain is not None
    rng = np.random.default_rng(seed)
    qs = rng.uniform(robot.lower, robot.upper, (4, robot.n_joints))
    pos, rot, jac = chain.site_jacobians(qs)
    frames = chain.site_frames(qs)
    for i, q in enumerate(qs):
        p, r, j = site_frame(robot, q)
        np.testing.assert_allclose(pos[i], p, atol=1e-12)
        np.testing.assert_allclose(rot[i], r, atol=1e-12)
        np.testing.assert_allclose(jac[i], j, atol=1e-12)
        np.testing.assert_array_equal(frames[0][i], pos[i])


def test_a_chain_with_a_joint_that_is_not_the_arms_is_not_covered():
    robot = load_robot("panda")
    site = robot.model.site(robot.spec.grasp_site).id
    assert SerialChain.of(robot.model, site, robot.qpos_adr[:-1]) is None  # joint7 not an arm joint


def test_mujocos_loop_is_the_fallback_and_writes_the_data_it_is_given():
    robot = load_robot("panda")
    qs = np.random.default_rng(1).uniform(robot.lower, robot.upper, (5, robot.n_joints))
    batched = robot.grasp_jacobians(qs)
    loop = load_robot("panda")
    loop._chain = None  # an arm that is not a chain of hinges goes through MuJoCo, one at a time
    data = mujoco.MjData(loop.model)
    looped = loop.grasp_jacobians(qs, data)
    for a, b in zip(batched, looped, strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)
    np.testing.assert_array_equal(data.qpos[loop.qpos_adr], qs[-1])  # the given data, not the robot's
    for a, b in zip(robot.grasp_frames(qs), loop.grasp_frames(qs), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)


def test_rot_z_of_many_angles_is_each_angles_rotation():
    from lasa.world.chain import rot_z

    angles = np.random.default_rng(2).uniform(-np.pi, np.pi, 50)
    many = rot_z(angles)
    assert many.shape == (50, 3, 3)
    np.testing.assert_array_equal(many, np.stack([rot_z(float(a)) for a in angles]))
    np.testing.assert_allclose(rot_z(np.pi / 2), [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(
        many @ many.transpose(0, 2, 1), np.broadcast_to(np.eye(3), (50, 3, 3)), atol=1e-15
    )
