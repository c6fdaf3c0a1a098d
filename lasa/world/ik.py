"""Inverse kinematics of grasp poses with mink's differential IK: a frame task on the grasp site, a
light posture task that picks one solution out of the arm's redundancy, the joint ranges as limits."""

from __future__ import annotations

import weakref

import mink
import numpy as np

from lasa.base.errors import IKError
from lasa.world.robot import Robot

_Solver = tuple[mink.Configuration, mink.FrameTask, mink.PostureTask, list[mink.ConfigurationLimit]]
_SOLVERS: weakref.WeakKeyDictionary[Robot, _Solver] = weakref.WeakKeyDictionary()
DT, DAMPING = 0.05, 1e-4  # each iteration's step [s] and Levenberg-Marquardt damping


def pose_error(
    robot: Robot, q: np.ndarray, position: np.ndarray, rotation: np.ndarray
) -> tuple[float, float]:
    """Position error [m] and orientation error [rad] of the grasp site at ``q``."""
    pos, rot = robot.grasp_pose(q)
    cos = (np.trace(rotation.T @ rot) - 1.0) / 2.0
    return float(np.linalg.norm(pos - position)), float(np.arccos(np.clip(cos, -1.0, 1.0)))


def solve_grasp_ik(
    robot: Robot,
    position: np.ndarray,
    rotation: np.ndarray,
    seed: np.ndarray,
    *,
    position_tol: float = 5e-4,
    rotation_tol: float = 5e-3,
    max_iters: int = 400,
    label: str = "",
) -> np.ndarray:
    """Joint positions (n,), within the limits, that put the grasp site at ``position`` (3,) [m] with
    ``rotation`` (3, 3), the posture task pulling towards ``seed`` (n,) [rad]: accepted within
    ``position_tol`` [m] and ``rotation_tol`` [rad] after at most ``max_iters`` iterations, else IKError,
    its message naming the pose by ``label`` (``"cup 'cup_left', theta = 0.250"``)."""
    # mink's objects, made once per robot (they cost more than a solve); reuse changes no result: a
    # solve sets every joint (from qpos0) and each task's target first
    if robot not in _SOLVERS:
        _SOLVERS[robot] = (
            mink.Configuration(robot.model),
            mink.FrameTask(robot.spec.grasp_site, "site", position_cost=1.0, orientation_cost=1.0),
            mink.PostureTask(robot.model, cost=1e-3),  # light, relative to the frame task
            [mink.ConfigurationLimit(robot.model)],
        )
    configuration, frame, posture_task, limits = _SOLVERS[robot]
    q_full = robot.model.qpos0.copy()  # no state of the last solve
    adr = robot.qpos_adr
    q_full[adr] = robot.clip(np.asarray(seed, dtype=float))
    configuration.update(q_full)
    rotation_so3 = mink.SO3.from_matrix(np.asarray(rotation, dtype=float))
    frame.set_target(mink.SE3.from_rotation_and_translation(rotation_so3, np.asarray(position, dtype=float)))
    target = q_full.copy()
    target[adr] = seed
    posture_task.set_target(target)
    for _ in range(max_iters):
        velocity = mink.solve_ik(
            configuration, [frame, posture_task], DT, "daqp", damping=DAMPING, limits=limits
        )
        configuration.integrate_inplace(velocity, DT)
        q = configuration.q[adr].copy()
        pos_err, rot_err = pose_error(robot, q, position, rotation)
        if pos_err < position_tol and rot_err < rotation_tol:
            return robot.clip(q)
    where = f" ({label})" if label else ""
    raise IKError(
        f"IK for {robot.name}{where} did not converge: position error {pos_err:.2e} m "
        f"(tol {position_tol:g}), orientation error {rot_err:.2e} rad (tol {rotation_tol:g}) "
        f"after {max_iters} iterations. Is the pose reachable? Try another seed."
    )
