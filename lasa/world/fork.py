"""The fork's tip in the eating tasks: its frames, how a joint step moves it, and its waypoints.

Simulated participants (:mod:`lasa.people`) and real ones (:mod:`lasa.live`) read the fork's pose
through :func:`tip_frames` and test a waypoint with :func:`waypoint_reached`, so both finish a
phase by the same rule.
"""

from __future__ import annotations

import mujoco
import numpy as np

from lasa.world.eating import TASK_NAMES, fork_frame, waypoints
from lasa.world.robot import Robot

POSITION_TOL = 0.015  # a waypoint is reached this close to it (the tines' width) [m]
ANGLE_TOL = 0.2  # ... with the fork's direction this close (~11 degrees) [rad]

__all__ = [
    "POSITION_TOL",
    "ANGLE_TOL",
    "tip_frames",
    "angle_between",
    "normalise",
    "tip_motion",
    "waypoint_arrays",
    "waypoint_reached",
    "next_waypoint",
]


def tip_frames(
    robot: Robot, data: mujoco.MjData, qs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The grasp site's position, direction (+z) and Jacobians at joint vectors ``qs`` (B, n).

    :meth:`lasa.world.robot.Robot.grasp_jacobians`, split: ``data`` is the MjData it writes where
    the arm is not a chain of hinges (a chain's batch needs none).

    Returns:
        position (B, 3), direction (B, 3), translational Jacobian (B, 3, n) and rotational
        Jacobian (B, 3, n) with respect to the arm joints.
    """
    pos, rot, jac = robot.grasp_jacobians(qs, data)
    return pos, rot[:, :, 2], jac[:, :3], jac[:, 3:]


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between unit vectors along the last axis [rad]."""
    return np.arccos(np.clip(np.einsum("...i,...i->...", a, b), -1.0, 1.0))


def normalise(v: np.ndarray) -> np.ndarray:
    """Vectors ``v`` scaled to unit length along the last axis (a zero vector stays zero)."""
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def tip_motion(
    jp: np.ndarray, jr: np.ndarray, axis: np.ndarray, dq: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The tip's displacement and new direction for joint steps ``dq`` (A, K, n), to first order.

    Args:
        jp, jr: Translational and rotational Jacobians, (A, 3, n).
        axis: The fork's direction now, (A, 3).
        dq: Candidate joint steps, (A, K, n) [rad].

    Returns:
        Displacements (A, K, 3) [m] and unit directions (A, K, 3).
    """
    dp = np.einsum("aij,akj->aki", jp, dq)
    rot = np.einsum("aij,akj->aki", jr, dq)
    return dp, normalise(axis[:, None, :] + np.cross(rot, axis[:, None, :]))


def waypoint_arrays(robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every task's waypoints, padded: positions (T, W, 3), directions (T, W, 3), phases (T, W),
    counts (T,)."""
    plans = [waypoints(name) for name in TASK_NAMES]
    n_wp = np.array([len(p) for p in plans])
    w_max, n_t = int(n_wp.max()), len(plans)
    wp_pos, wp_dir = np.zeros((n_t, w_max, 3)), np.zeros((n_t, w_max, 3))
    wp_phase = np.zeros((n_t, w_max), dtype=int)
    for k, plan in enumerate(plans):
        for j, wp in enumerate(plan):
            pos, rot = fork_frame(robot, wp.goal, wp.theta, wp.depth)
            wp_pos[k, j], wp_dir[k, j], wp_phase[k, j] = pos, rot[:, 2], wp.phase
    return wp_pos, wp_dir, wp_phase, n_wp


def waypoint_reached(
    tip: np.ndarray,
    direction: np.ndarray,
    target: np.ndarray,
    target_direction: np.ndarray,
    position_tol: float = POSITION_TOL,
    angle_tol: float = ANGLE_TOL,
) -> np.ndarray:
    """Whether the fork tip is within ``position_tol`` [m] of its waypoint and its direction within
    ``angle_tol`` [rad] of the waypoint's, vectorised over leading dimensions."""
    close = np.linalg.norm(tip - target, axis=-1) < position_tol
    return close & (angle_between(direction, target_direction) < angle_tol)


def next_waypoint(reached: np.ndarray, w: np.ndarray, n_wp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Past a reached waypoint, the next one; past the last, finished (and ``w`` stays at the last).

    Returns:
        The waypoint each task works towards now, and whether it has finished (shapes of ``w``).
    """
    w = np.where(reached, w + 1, w)
    finished = reached & (w >= n_wp)
    return np.minimum(w, n_wp - 1), finished
