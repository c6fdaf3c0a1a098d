"""The fork's tip in the eating tasks: its frames, how a joint step moves it, and its waypoints,
tracked for simulated participants (:mod:`lasa.people`) and real ones (:mod:`lasa.live`) alike."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from lasa.world.eating import TASK_NAMES, fork_frame, waypoints
from lasa.world.robot import Robot

POSITION_TOL = 0.015  # a waypoint is reached this close to it (the tines' width) [m]
ANGLE_TOL = 0.2  # ... with the fork's direction this close (~11 degrees) [rad]


def tip_frames(
    robot: Robot, data: mujoco.MjData, qs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The grasp site's position and direction (+z), (B, 3) each, and translational and rotational
    Jacobians (B, 3, n) at joints ``qs`` (B, n) (:meth:`lasa.world.robot.Robot.grasp_jacobians`)."""
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
    """The tip's displacements (A, K, 3) [m] and new unit directions (A, K, 3) for joint steps ``dq``
    (A, K, n) [rad], to first order, from Jacobians ``jp``, ``jr`` (A, 3, n) and direction ``axis`` (A, 3)."""
    dp = np.einsum("aij,akj->aki", jp, dq)
    rot = np.einsum("aij,akj->aki", jr, dq)
    return dp, normalise(axis[:, None, :] + np.cross(rot, axis[:, None, :]))


@dataclasses.dataclass(frozen=True)
class WaypointTracker:
    """Every task's waypoints (padded) and when one counts as reached: the one tracker of a phase's
    progress, for simulated participants and real ones (:class:`lasa.live.station.Station`).

    Attributes:
        position, direction: The waypoints' tip positions [m] and fork directions, (T, W, 3) each.
        phase: Each waypoint's phase, (T, W); count: each task's waypoints, (T,).
        position_tol, angle_tol: Reached this close [m] with the fork's direction this close [rad]."""

    position: np.ndarray
    direction: np.ndarray
    phase: np.ndarray
    count: np.ndarray
    position_tol: float = POSITION_TOL
    angle_tol: float = ANGLE_TOL

    @classmethod
    def of(
        cls, robot: Robot, position_tol: float = POSITION_TOL, angle_tol: float = ANGLE_TOL
    ) -> WaypointTracker:
        """The tracker of every task of :data:`lasa.world.eating.TASK_NAMES` on ``robot``."""
        plans = [waypoints(name) for name in TASK_NAMES]
        count = np.array([len(p) for p in plans])
        position, direction = np.zeros((2, len(plans), count.max(), 3))
        phase = np.zeros((len(plans), count.max()), dtype=int)
        for k, plan in enumerate(plans):
            for j, wp in enumerate(plan):
                pos, rot = fork_frame(robot, wp.goal, wp.theta, wp.depth)
                position[k, j], direction[k, j], phase[k, j] = pos, rot[:, 2], wp.phase
        return cls(position, direction, phase, count, position_tol, angle_tol)

    def advance(
        self,
        task: np.ndarray,
        w: np.ndarray,
        tip: np.ndarray,
        axis: np.ndarray,
        running: np.ndarray | bool = True,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The waypoint each episode of tasks ``task`` works towards now and whether it has finished,
        (E,) each, from waypoints ``w`` (E,) and the fork's ``tip`` and ``axis`` (E, 3) (:func:`tip_frames`):
        past a reached waypoint the next one, past the last finished (``w`` stays at the last)."""
        close = np.linalg.norm(tip - self.position[task, w], axis=-1) < self.position_tol
        reached = running & close & (angle_between(axis, self.direction[task, w]) < self.angle_tol)
        w = np.where(reached, w + 1, w)
        finished = reached & (w >= self.count[task])
        return np.minimum(w, self.count[task] - 1), finished
