r"""The goal task: a robot, G >= 2 goals, and at each goal the desired final poses :math:`s^*(g, \theta)`,
solved by IK on a grid of preferences theta in [0, 1] and interpolated by cubic splines. Subclasses:
:class:`lasa.world.task.CupTask`, :class:`lasa.world.eating.EatingTask`, a new task's."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
from scipy.interpolate import CubicSpline

from lasa.base.errors import ConfigError
from lasa.world.robot import Robot


@dataclasses.dataclass(frozen=True)
class GoalTask:
    """Goals, preference curves and the start pose of a task for one robot.

    Attributes:
        goal_names: Names of the goals, in goal order.
        theta_grid: Preferences at which IK was solved, shape (K,); ``curves`` s*(g, theta) on it, (G, K, n).
        goals: The goals g in joint space, the mid-preference poses (what Eq. M2 pulls towards), (G, n).
        start: Start pose of every episode, shape (n,) [rad]."""

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
        return float(np.linalg.norm(self.goals[:, None, :] - self.goals[None, :, :], axis=-1).max())

    @property
    def preference_sets(self) -> np.ndarray:
        """Each goal's preferred poses s*(g, theta) on the IK grid, a polyline, shape (G, K, n)."""
        return self.curves

    def target(self, goal: np.ndarray | int, theta: np.ndarray | float) -> np.ndarray:
        """Desired final poses s*(g, theta), shape (..., n), for goal indices and preferences in [0, 1]
        that broadcast."""
        goal_arr, theta_arr = np.broadcast_arrays(np.asarray(goal), np.asarray(theta, float))
        if not np.all((goal_arr >= 0) & (goal_arr < self.n_goals)):
            raise ConfigError(f"goal index must be in [0, {self.n_goals}), got {goal}")
        if not np.all((theta_arr >= 0) & (theta_arr <= 1)):  # NaN too
            raise ConfigError(f"theta must be in [0, 1], got {theta}")
        out = np.empty((*goal_arr.shape, self.robot.n_joints))
        for g in range(self.n_goals):
            mask = goal_arr == g
            out[mask] = self._splines[g](theta_arr[mask])
        return out

    @functools.cached_property
    def _splines(self) -> list[CubicSpline]:
        return [CubicSpline(self.theta_grid, c, axis=0) for c in self.curves]
