"""Retargeting (the user study's baseline R): joystick modes -> twist -> joint velocity by mink."""

from __future__ import annotations

import mink
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lasa.base.errors import ConfigError
from lasa.method.retarget import MODES, RetargetConfig, Retargeting, next_mode, twist
from lasa.world.robot import Robot, load_robot

DT = 0.02  # control period of the finite-difference checks [s]
CONFIG = RetargetConfig()
SPEEDS = np.array([CONFIG.linear_speed] * 3 + [CONFIG.angular_speed] * 3)


@pytest.fixture(scope="module")
def robot() -> Robot:
    """The Panda (overrides the session's planar5 ``robot`` in this module)."""
    return load_robot("panda")


@pytest.fixture(scope="module")
def retarget(robot: Robot) -> Retargeting:
    return Retargeting(robot, DT)


def poses(robot: Robot) -> list[np.ndarray]:
    """The home pose and three seeded random poses around it, well inside the joint limits."""
    rng = np.random.default_rng(0)
    margin, n = 0.2, robot.n_joints
    randoms = [
        np.clip(robot.home + rng.uniform(-0.4, 0.4, n), robot.lower + margin, robot.upper - margin)
        for _ in range(3)
    ]
    return [robot.home, *randoms]


def realised_twist(retarget: Retargeting, q: np.ndarray, xi: np.ndarray, dt: float) -> np.ndarray:
    """The site's twist measured by finite differences over one step q -> q + dt * qdot."""
    p, rot = retarget.robot.grasp_pose(q)
    q_next = q + dt * retarget.joint_velocity(q, xi)
    p_next, rot_next = retarget.robot.grasp_pose(q_next)
    w = mink.SO3.from_matrix(rot_next @ rot.T).log() / dt  # world-frame rotation vector
    return np.concatenate([(p_next - p) / dt, w])


def directions() -> list[np.ndarray]:
    """Six unit-twist directions at full speed, and a seeded random combination of all six."""
    units = [np.eye(6)[k] * SPEEDS[k] for k in range(6)]
    mixed = np.random.default_rng(1).uniform(-1.0, 1.0, 6) * SPEEDS
    return [*units, mixed]


def test_finite_differences_match_the_twist(robot: Robot, retarget: Retargeting) -> None:
    for q in poses(robot):
        for xi in directions():
            got = realised_twist(retarget, q, xi, DT)
            v, w = xi[:3], xi[3:]
            # A few percent (LM damping biases the answer by ~2%) plus a small absolute slack;
            # the off-axis components are held to the same bound, so they are small too.
            lin_tol = 0.04 * np.linalg.norm(v) + 0.005  # [m/s]
            ang_tol = 0.04 * np.linalg.norm(w) + 0.01  # [rad/s]
            assert np.all(np.abs(got[:3] - v) <= lin_tol), (q, xi, got)
            assert np.all(np.abs(got[3:] - w) <= ang_tol), (q, xi, got)


def test_twist_by_hand() -> None:
    np.testing.assert_allclose(twist(0, np.array([1.0, -0.5])), [0.15, -0.075, 0, 0, 0, 0])
    np.testing.assert_allclose(twist(1, np.array([0.5, 1.0])), [0, 0, 0.075, 0, 0, 0.6])
    np.testing.assert_allclose(twist(2, np.array([-1.0, 0.5])), [0, 0, 0, -0.6, 0.3, 0])
    fast = RetargetConfig(linear_speed=0.3, angular_speed=1.0)
    np.testing.assert_allclose(twist(1, np.array([1.0, 1.0]), fast), [0, 0, 0.3, 0, 0, 1.0])


def test_twist_clips_vectorises_and_zeroes_nan_rows() -> None:
    np.testing.assert_allclose(twist(0, np.array([3.0, -2.0])), [0.15, -0.15, 0, 0, 0, 0])
    z = np.array([[1.0, 0.0], [np.nan, 0.5], [0.0, np.inf], [0.5, 0.5]])
    out = twist(np.array([0, 1, 2, 2]), z)
    assert out.shape == (4, 6)
    np.testing.assert_allclose(out[0], [0.15, 0, 0, 0, 0, 0])
    np.testing.assert_array_equal(out[1:3], 0.0)
    np.testing.assert_allclose(out[3], [0, 0, 0, 0.3, 0.3, 0])
    # One mode broadcast over a batch of inputs, and a batch of modes over one input.
    assert twist(1, np.zeros((5, 2))).shape == (5, 6)
    assert twist(np.array([0, 1, 2]), np.array([1.0, 1.0])).shape == (3, 6)


@pytest.mark.parametrize("mode", [-1, 3, 1.5, "x", True, np.array([0, 7])])
def test_bad_mode_is_refused(mode: object) -> None:
    with pytest.raises(ConfigError, match="mode"):
        twist(mode, np.zeros(2))  # type: ignore[arg-type]


def test_next_mode_cycles() -> None:
    assert [next_mode(m) for m in range(len(MODES))] == [1, 2, 0]
    assert next_mode(2, 2) == 1
    assert next_mode(0, -1) == 2
    assert next_mode(1, 3) == 1
    np.testing.assert_array_equal(next_mode(np.array([0, 1, 2])), [1, 2, 0])
    assert isinstance(next_mode(0), int)
    with pytest.raises(ConfigError):
        next_mode(3)


def test_config_is_validated(robot: Robot) -> None:
    for bad in ({"linear_speed": 0.0}, {"angular_speed": -1.0}, {"damping": 0.0}, {"posture_cost": np.nan}):
        with pytest.raises(ConfigError):
            RetargetConfig(**bad)
    with pytest.raises(ConfigError, match="dt"):
        Retargeting(robot, 0.0)


def test_zero_and_nan_twists_give_zero_velocity(robot: Robot, retarget: Retargeting) -> None:
    zero = retarget.joint_velocity(robot.home, np.zeros(6))
    assert zero.shape == (robot.n_joints,)
    np.testing.assert_array_equal(zero, 0.0)
    nan = np.array([0.1, np.nan, 0, 0, 0, 0])
    np.testing.assert_array_equal(retarget.joint_velocity(robot.home, nan), 0.0)


def test_nan_q_is_refused(robot: Robot, retarget: Retargeting) -> None:
    q = robot.home.copy()
    q[2] = np.nan
    with pytest.raises(ValueError, match="finite"):
        retarget.joint_velocity(q, np.zeros(6))
    with pytest.raises(ValueError, match="shape"):
        retarget.joint_velocity(robot.home[:3], np.zeros(6))
    with pytest.raises(ValueError, match="shape"):
        retarget.joint_velocity(robot.home, np.zeros(5))


def test_mink_site_frame_matches_the_robot(robot: Robot, retarget: Retargeting) -> None:
    for q in poses(robot):
        retarget._set(q)  # the configuration joint_velocity's QP reads the site's frame from
        pose = retarget._configuration.get_transform_frame_to_world(robot.spec.grasp_site, "site")
        ref_pos, ref_rot = robot.grasp_pose(q)
        np.testing.assert_allclose(pose.translation(), ref_pos, atol=1e-12)
        np.testing.assert_allclose(pose.rotation().as_matrix(), ref_rot, atol=1e-9)


@pytest.mark.parametrize(("joint", "side"), [(0, "lower"), (3, "upper"), (5, "lower")])
def test_next_state_stays_within_limits(robot: Robot, joint: int, side: str) -> None:
    dt = robot.control.dt  # the study's control period: the larger step is the harder case
    retarget = Retargeting(robot, dt)
    sign = -1.0 if side == "lower" else 1.0
    # The full-speed unit twist that drives this joint hardest towards that limit from home.
    candidates = [s * np.eye(6)[k] * SPEEDS[k] for k in range(6) for s in (-1.0, 1.0)]
    pushes = [sign * retarget.joint_velocity(robot.home, xi)[joint] for xi in candidates]
    xi = candidates[int(np.argmax(pushes))]
    assert max(pushes) * dt > 1e-3  # unconstrained, one step would cross the limit
    q = robot.home.copy()
    q[joint] = robot.lower[joint] + 1e-3 if side == "lower" else robot.upper[joint] - 1e-3
    q_next = q + dt * retarget.joint_velocity(q, xi)
    assert np.all(q_next >= robot.lower - 1e-9) and np.all(q_next <= robot.upper + 1e-9)


def test_batch_equals_rows(robot: Robot, retarget: Retargeting) -> None:
    qs = np.stack(poses(robot))
    rng = np.random.default_rng(2)
    xis = rng.uniform(-1.0, 1.0, (len(qs), 6)) * SPEEDS
    xis[1] = 0.0
    xis[2, 4] = np.nan
    batch = retarget.joint_velocity(qs, xis)
    assert batch.shape == qs.shape
    rows = np.stack([retarget.joint_velocity(q, xi) for q, xi in zip(qs, xis, strict=True)])
    np.testing.assert_allclose(batch, rows, rtol=0.0, atol=1e-12)
    np.testing.assert_array_equal(batch[1:3], 0.0)
    # One twist broadcast over a batch of configurations.
    shared = retarget.joint_velocity(qs, xis[0])
    np.testing.assert_allclose(shared[0], rows[0], rtol=0.0, atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(
    mode=st.integers(0, len(MODES) - 1),
    z=st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)),
)
def test_twist_is_bounded_by_the_speeds(mode: int, z: tuple[float, float]) -> None:
    xi = twist(mode, np.array(z))
    assert xi.shape == (6,)
    assert np.all(np.abs(xi) <= SPEEDS + 1e-15)
    assert np.count_nonzero(xi) <= 2
