"""The connected arm's kinematics against the package's Panda: the shared limits, the FR3's limits as
franky-sim models them, the comparison (it must fail on a wrong joint offset) and, against franky-sim, the
check itself."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from lasa.base.errors import ConfigError
from lasa.live.guard import Guard
from lasa.world.eating import make_eating_task
from lasa.world.franka import (
    DH,
    FLANGE_D,
    FR3_LOWER,
    FR3_UPPER,
    LOWER,
    SHARED_LOWER,
    SHARED_UPPER,
    TCP_D,
    UPPER,
    dh_frames,
    fk_errors,
    rotation_angle,
    shared_configurations,
)
from lasa.world.robot import load_robot

# franky-sim packs the robot state as float32 (unit roundoff u = 2**-24), so a (q_d, O_T_EE_d) pair that is
# exactly one FK apart arrives up to: |dq_i| <= u |q_i| <= u * 4.52 rad (the largest shared limit); a joint
# turned by dq moves the TCP by at most REACH * dq (REACH: every DH length, flange and TCP added, bounds the
# distance from any joint axis to the TCP) and turns it by dq; the pose's own entries round by u each.
U32 = 2.0**-24
REACH = sum(abs(a) + abs(d) for a, d, _ in DH) + FLANGE_D + TCP_D  # 1.4964 m
DQ32 = U32 * float(np.abs(np.r_[SHARED_LOWER, SHARED_UPPER]).max())
# The package Panda's hand quaternion has 7 digits (panda.xml: 0.9238795 0 0 -0.3826834): its yaw is -pi/4 to
# 3.5e-8 rad, so its orientation is Franka's to that much.
HAND_QUAT = 5e-8  # [rad]
POSITION_TOL = 7 * REACH * DQ32 + 3 * U32 * REACH  # 3.1e-6 m
ORIENTATION_TOL = 7 * DQ32 + 9 * U32 + HAND_QUAT  # 2.5e-6 rad


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def _fr3_xml_ranges() -> np.ndarray:
    import franky_sim

    root = ET.parse(Path(franky_sim.__file__).parent / "assets" / "fr3.xml").getroot()
    joints = {j.get("name"): j.get("range") for j in root.iter("joint")}
    return np.array([[float(v) for v in joints[f"fr3_joint{i}"].split()] for i in range(1, 8)])


def test_shared_limits_are_the_intersection_by_hand():
    # joint 1: Panda +-2.8973, FR3 +-2.7437 -> the FR3's; joint 6: Panda [-0.0175, 3.7525], FR3
    # [0.5445, 4.5169] -> the FR3's lower, the Panda's upper; joint 4: Panda [-3.0718, -0.0698], FR3
    # [-3.0421, -0.1518] -> the FR3's both
    assert (SHARED_LOWER[0], SHARED_UPPER[0]) == (-2.7437, 2.7437)
    assert (SHARED_LOWER[5], SHARED_UPPER[5]) == (0.5445, 3.7525)
    assert (SHARED_LOWER[3], SHARED_UPPER[3]) == (-3.0421, -0.1518)
    assert np.all((SHARED_LOWER >= LOWER) & (SHARED_LOWER >= FR3_LOWER) & (SHARED_UPPER <= UPPER))
    assert np.all(SHARED_UPPER <= FR3_UPPER) and np.all(SHARED_LOWER < SHARED_UPPER)


def test_eating_start_is_inside_the_shared_limits():
    task = make_eating_task()
    assert np.all((task.start > SHARED_LOWER) & (task.start < SHARED_UPPER))
    guard = Guard.around(task.robot, task.start)
    assert guard.within_limits(task.start)  # and the guard's margin inside them


def test_fr3_limits_are_franky_sims_model():
    ranges = _fr3_xml_ranges()
    assert_array_equal(ranges[:, 0], FR3_LOWER)
    assert_array_equal(ranges[:, 1], FR3_UPPER)


def test_shared_configurations_stay_inside_and_off_the_table():
    q = shared_configurations(50, seed=3, margin=0.2, floor=0.1)
    assert q.shape == (50, 7)
    assert np.all(q >= SHARED_LOWER + 0.2) and np.all(q <= SHARED_UPPER - 0.2)
    assert min(dh_frames(qq)["tcp"][2, 3] for qq in q) >= 0.1
    assert_array_equal(q, shared_configurations(50, seed=3, margin=0.2, floor=0.1))
    with pytest.raises(ConfigError, match="margin"):
        shared_configurations(1, seed=0, margin=1.5)
    with pytest.raises(ConfigError, match="lower the floor"):
        shared_configurations(1, seed=0, floor=5.0)


def test_rotation_angle_by_hand():
    a = np.eye(3)
    b = dh_frames(np.zeros(7))["link1"][:3, :3]  # identity
    c = np.array([[np.cos(0.3), -np.sin(0.3), 0], [np.sin(0.3), np.cos(0.3), 0], [0, 0, 1]])
    assert_allclose(rotation_angle(np.stack([a, a]), np.stack([b, c])), [0.0, 0.3], atol=1e-15)
    flip = np.diag([1.0, -1.0, -1.0])
    assert_allclose(rotation_angle(a, flip), np.pi, atol=1e-15)


@pytest.mark.parametrize("scene", ["panda", "eating"])
def test_fk_errors_match_the_dh_table_and_catch_a_wrong_offset(panda, scene):
    robot = panda if scene == "panda" else make_eating_task().robot
    q = shared_configurations(20, seed=0)
    poses = np.array([dh_frames(qq)["tcp"] for qq in q])
    table = fk_errors(robot, q, poses)
    assert list(table.columns[:7]) == [f"q{i}" for i in range(7)] and len(table) == 20
    assert table["position_error_m"].max() < 1e-12 and table["orientation_error_rad"].max() < HAND_QUAT
    # joint 4 read 0.01 rad off: the elbow's lever moves the TCP by millimetres, the hand turns by 0.01 rad
    wrong = fk_errors(robot, q + np.eye(7)[3] * 0.01, poses)
    assert wrong["position_error_m"].min() > 1e-3
    assert_allclose(wrong["orientation_error_rad"], 0.01, atol=HAND_QUAT)
    with pytest.raises(ConfigError, match="one row per pose"):
        fk_errors(robot, q[:3], poses)


@pytest.fixture(scope="module")
def franky_sim_fields(panda):
    """Five configurations measured on franky-sim (JointMotion at 0.9 of the dynamics limits)."""
    from lasa.live.franka import connect, simulator  # franky and franky-sim are pinned: never skipped
    from lasa.live.kinematics import measure

    with simulator() as address:
        arm = connect(address)
        targets = shared_configurations(5, seed=0)
        fields = measure(arm, targets, speed=0.9)
    return targets, fields


def test_franky_sim_agrees_with_the_package_panda(panda, franky_sim_fields):
    from lasa.live.kinematics import compare

    targets, fields = franky_sim_fields
    table = compare(panda, fields)
    # the desired pair: the motion ended at its target (ruckig's last sample, microradians off), and the pose
    # is the package Panda's up to float32
    assert_allclose(fields["q_d"], targets, atol=1e-4)
    assert table["position_error_m"].max() < POSITION_TOL
    assert table["orientation_error_rad"].max() < ORIENTATION_TOL
    # the measured pair (franky-sim: O_T_EE at q_d, see lasa.live.kinematics) is off by the tracking alone
    tracking = table["tracking_error_rad"]
    assert np.all(table["measured_position_error_m"] <= REACH * tracking + POSITION_TOL)
    assert np.all(table["measured_orientation_error_rad"] <= tracking + ORIENTATION_TOL)


def test_franky_sim_check_fails_with_a_wrong_joint_offset(panda, franky_sim_fields):
    from lasa.live.kinematics import compare

    _, fields = franky_sim_fields
    offset = np.zeros(7)
    offset[5] = 0.01  # joint 6 read 0.01 rad off
    table = compare(panda, {**fields, "q_d": fields["q_d"] + offset})
    assert table["position_error_m"].min() > POSITION_TOL * 100
    assert table["orientation_error_rad"].min() > 0.009
