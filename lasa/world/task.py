r"""The cup task: two goals, and a preference from a top grasp to a side grasp.

Two cups stand on a table (the goals G). At either cup the user may want any grasp on
a continuum theta in [0, 1]: theta = 0 approaches from the top (fingers pointing
down), theta = 1 from the side (fingers horizontal). The side direction is the
horizontal direction from the robot's base to the cup, turned towards the midline by
the robot's ``side_azimuth`` (0 for the planar arm; a quarter turn for the Panda,
whose wrist cannot point radially outward at table height). In between, the approach
direction turns by :math:`\psi = \theta \pi / 2`, and the grasp site sits at a fixed
standoff :math:`\rho` from the cup centre c along it:

.. math::

    d(\theta) = \cos\psi \, d_{top} + \sin\psi \, d_{side}, \qquad
    p(\theta) = c - \rho \, d(\theta).

The desired final pose :math:`s^*(g, \theta)` is the joint configuration that puts the
grasp site there, solved with mink on a grid of theta, warm-starting each solve from
its neighbour so the curve is smooth, and interpolated between grid points with a
cubic spline. A goal g is the mid-preference pose :math:`s^*(g, 0.5)`, so that the
assistance of Eq. M2 lives in joint space, as in the paper.
"""

from __future__ import annotations

import dataclasses

import mink
import numpy as np
from scipy.interpolate import CubicSpline

from lasa.base.config import check_range
from lasa.base.errors import ConfigError
from lasa.world.ik import solve_grasp_ik
from lasa.world.robot import Robot

__all__ = ["CupTask", "make_cup_task", "grasp_frame", "cup_axis", "grasp_preference"]


def grasp_frame(robot: Robot, goal: int, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """Grasp-site position (3,) and rotation (3, 3) for cup ``goal`` at preference theta.

    Args:
        robot: The robot (its spec gives the cups, top-grasp rotation and standoff).
        goal: Index of the cup in goal order.
        theta: Preference in [0, 1]; 0 is a top grasp, 1 a side grasp.
    """
    check_range("theta", theta, 0.0, 1.0)
    cup = robot.cup_positions()[goal]
    radial = cup - robot.base_position()
    radial[2] = 0.0
    norm = np.linalg.norm(radial)
    if norm < 1e-6:
        raise ConfigError(f"cup {goal} stands above the robot's base: no side direction")
    radial /= norm
    # turn the radial direction by side_azimuth towards the midline (y = 0)
    turn = -np.sign(cup[1]) * robot.spec.side_azimuth if cup[1] != 0 else 0.0
    c, s = np.cos(turn), np.sin(turn)
    side = np.array([c * radial[0] - s * radial[1], s * radial[0] + c * radial[1], 0.0])
    top = np.array([0.0, 0.0, -1.0])
    psi = theta * np.pi / 2
    approach = np.cos(psi) * top + np.sin(psi) * side
    axis = np.cross(top, side)
    r_top = np.asarray(robot.spec.top_grasp_rotation, dtype=float).reshape(3, 3)
    rotation = mink.SO3.exp(axis * psi).as_matrix() @ r_top
    position = cup - robot.spec.grasp_standoff * approach
    return position, rotation


@dataclasses.dataclass(frozen=True)
class CupTask:
    """Goals, preference curves and the start pose of the cup task for one robot.

    Attributes:
        robot: The robot.
        goal_names: Names of the cups, in goal order.
        theta_grid: Preferences at which IK was solved, shape (K,).
        curves: s*(g, theta) on the grid, shape (G, K, n) [rad].
        goals: The goals g = s*(g, 0.5), shape (G, n) [rad].
        start: Start pose of every episode, shape (n,) [rad].
    """

    robot: Robot
    goal_names: tuple[str, ...]
    theta_grid: np.ndarray
    curves: np.ndarray
    goals: np.ndarray
    start: np.ndarray

    @property
    def n_goals(self) -> int:
        """Number of goals G."""
        return len(self.goal_names)

    @property
    def goal_distance(self) -> float:
        """Largest joint-space distance between two goals: the paper's error normaliser."""
        diff = self.goals[:, None, :] - self.goals[None, :, :]
        return float(np.linalg.norm(diff, axis=-1).max())

    def belief_targets(self, likelihood: str) -> np.ndarray:
        """What the belief measures progress towards, shape (G, K, n).

        ``"goal"``: the goal points g (K = 1). ``"grasp_set"``: each goal's grasps
        s*(g, theta) on the IK grid, a polyline (see :mod:`lasa.method.belief`).
        """
        if likelihood == "goal":
            return self.goals[:, None, :]
        if likelihood == "grasp_set":
            return self.curves
        raise ConfigError(f"unknown likelihood {likelihood!r}; choose 'grasp_set' or 'goal'")

    def target(self, goal: np.ndarray | int, theta: np.ndarray | float) -> np.ndarray:
        """Desired final poses s*(g, theta), shape (..., n), vectorised over both arguments.

        Args:
            goal: Goal indices (integers in [0, G)).
            theta: Preferences in [0, 1], broadcastable against ``goal``.
        """
        goal_arr, theta_arr = np.broadcast_arrays(np.asarray(goal), np.asarray(theta, float))
        if goal_arr.size and (goal_arr.min() < 0 or goal_arr.max() >= self.n_goals):
            raise ConfigError(f"goal index must be in [0, {self.n_goals}), got {goal}")
        if theta_arr.size and (
            not np.all(np.isfinite(theta_arr)) or theta_arr.min() < 0 or theta_arr.max() > 1
        ):
            raise ConfigError(f"theta must be in [0, 1], got {theta}")
        out = np.empty((*goal_arr.shape, self.robot.n_joints))
        for g in range(self.n_goals):  # G is 2: a loop over goals, not over users
            mask = goal_arr == g
            out[mask] = self._splines[g](theta_arr[mask])
        return out

    def tangent(self, goal: int, theta: np.ndarray | float) -> np.ndarray:
        """ds*/dtheta along the preference curve of ``goal``, shape (..., n)."""
        return self._splines[goal](np.asarray(theta, float), 1)

    @property
    def _splines(self) -> list[CubicSpline]:
        cache = self.__dict__.get("_spline_cache")
        if cache is None:
            cache = [CubicSpline(self.theta_grid, c, axis=0) for c in self.curves]
            object.__setattr__(self, "_spline_cache", cache)
        return cache


def make_cup_task(robot: Robot, n_grid: int = 41) -> CupTask:
    """Solve IK along each cup's preference curve and build the task.

    Starting from the robot's per-cup seed at the top grasp (theta = 0), solve along the
    grid to the side grasp, each solve warm-started (and posture-regularised) by the
    previous one, so neighbouring grasps get neighbouring joint configurations.

    Args:
        robot: The robot.
        n_grid: Number of preferences solved per cup (odd, so 0.5 is on the grid).
    """
    if n_grid < 5 or n_grid % 2 == 0:
        raise ConfigError(f"n_grid must be an odd integer >= 5, got {n_grid}")
    grid = np.linspace(0.0, 1.0, n_grid)
    mid = n_grid // 2
    curves = np.empty((len(robot.spec.cups), n_grid, robot.n_joints))
    for g, seed in enumerate(robot.spec.ik_seeds):
        q = np.asarray(seed, dtype=float)
        for k in range(n_grid):
            q = solve_grasp_ik(robot, *grasp_frame(robot, g, grid[k]), q)
            curves[g, k] = q
    names = tuple(name.removeprefix("cup_") for name in robot.spec.cups)
    return CupTask(
        robot=robot,
        goal_names=names,
        theta_grid=grid,
        curves=curves,
        goals=curves[:, mid].copy(),
        start=robot.home,
    )


def cup_axis(task: CupTask, points: np.ndarray) -> np.ndarray:
    """Signed position along the axis from the left cup to the right cup [m], (...).

    Zero midway between the cups; the sign says which cup a point is closer to.
    """
    cups = task.robot.cup_positions()
    axis = cups[-1] - cups[0]
    axis[2] = 0.0
    axis /= np.linalg.norm(axis)
    return (np.asarray(points) - cups.mean(axis=0)) @ axis


def grasp_preference(task: CupTask, states: np.ndarray) -> np.ndarray:
    """The grasp preference theta that the gripper's direction shows, shape (...).

    0 when the fingers point straight down, 1 when they point horizontally (the angle
    of the approach axis from vertical, divided by pi/2).
    """
    axes = task.robot.grasp_axes(states)
    horizontal = np.linalg.norm(axes[..., :2], axis=-1)
    return np.arctan2(horizontal, -axes[..., 2]) / (np.pi / 2)
