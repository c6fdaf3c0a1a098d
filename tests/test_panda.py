"""The Panda speaks Franka's joint convention: FK against the DH table, limits, the ready pose."""

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_allclose

from lasa.world.franka import (
    LOWER,
    PACKAGED_OFFSETS,
    READY,
    UPPER,
    check_against_dh,
    dh_frames,
    packaged_chain,
)
from lasa.world.robot import load_robot


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def test_dh_reference_by_hand():
    # All joints at zero: the arm is straight up with the known offsets. Frame 7 sits at
    # x = a4 + a5... = 0.0825 - 0.0825 + 0.088, z = 0.333 + 0.316 + 0.384 (rotated down by alpha).
    f = dh_frames(np.zeros(7))
    assert_allclose(f["link4"][:3, 3], [0.0825, 0.0, 0.649], atol=1e-12)
    assert_allclose(f["link7"][:3, 3], [0.088, 0.0, 1.033], atol=1e-12)
    assert_allclose(f["flange"][:3, 3], [0.088, 0.0, 1.033 - 0.107], atol=1e-12)


def test_ready_pose_matches_frankas_published_tcp(panda):
    # Franka's ready pose puts the TCP at (0.3069, 0, 0.4869), pointing down.
    pos, rot = panda.grasp_pose(READY)
    assert_allclose(pos, [0.30689, 0.0, 0.48688], atol=2e-5)
    assert_allclose(rot, np.diag([1.0, -1.0, -1.0]), atol=1e-6)
    assert_allclose(panda.home, READY, atol=1e-4)


def test_joint_limits_are_frankas(panda):
    assert_allclose(panda.lower, LOWER)
    assert_allclose(panda.upper, UPPER)


def test_forward_kinematics_agree_with_the_dh_table(panda):
    rng = np.random.default_rng(0)
    data = mujoco.MjData(panda.model)
    site = panda.model.site("grasp").id
    for q in rng.uniform(LOWER, UPPER, size=(100, 7)):
        ref = dh_frames(q)
        data.qpos[panda.qpos_adr] = q
        mujoco.mj_kinematics(panda.model, data)
        for i in range(1, 8):
            assert_allclose(data.body(f"link{i}").xpos, ref[f"link{i}"][:3, 3], atol=1e-9)
            assert_allclose(data.body(f"link{i}").xmat.reshape(3, 3), ref[f"link{i}"][:3, :3], atol=1e-6)
        assert_allclose(data.site_xpos[site], ref["tcp"][:3, 3], atol=1e-9)
        assert_allclose(data.site_xmat[site].reshape(3, 3), ref["tcp"][:3, :3], atol=1e-6)


def test_packaged_model_departs_and_the_offsets_explain_it():
    table = check_against_dh(load_robot("panda"), n=50).set_index("model")
    assert table.loc["lasa panda", "max_tcp_position_error_m"] < 1e-9
    assert table.loc["packaged, same q", "max_tcp_position_error_m"] > 0.1  # re-framed joints 6, 7
    # with its offsets undone it agrees to its own rounding (1.57 for pi/2, 0.210 m for 0.2104 m)
    assert table.loc["packaged, q - offsets", "max_tcp_position_error_m"] < 1e-3
    assert packaged_chain().nq == 9
    assert PACKAGED_OFFSETS[5] == pytest.approx(1.57)


def test_grasps_reach_every_pose_within_limits(panda):
    from lasa.world.ik import pose_error
    from lasa.world.task import grasp_frame, make_cup_task

    task = make_cup_task(panda)
    for g in range(task.n_goals):
        for theta in np.linspace(0, 1, 17):
            q = task.target(g, theta)
            pos_err, rot_err = pose_error(panda, q, *grasp_frame(panda, g, theta))
            assert pos_err < 2e-3 and rot_err < np.deg2rad(1.0), (g, theta, pos_err, rot_err)
            assert np.all(q >= panda.lower) and np.all(q <= panda.upper)
    # top grasps point down, side grasps are horizontal
    for g in range(task.n_goals):
        assert_allclose(panda.grasp_axes(task.target(g, 0.0)), [0, 0, -1], atol=1e-2)
        assert abs(panda.grasp_axes(task.target(g, 1.0))[2]) < 1e-2
    # the two cups are mirror images: the grasp sites mirror across y = 0
    p_left = panda.grasp_positions(task.curves[0])
    p_right = panda.grasp_positions(task.curves[1])
    assert_allclose(p_left * [1, -1, 1], p_right, atol=2e-3)
