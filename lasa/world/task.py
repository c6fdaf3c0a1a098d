r"""The cup task: cups as the goals, and a preference from a top grasp (theta = 0) to a side grasp (1,
from the base towards the cup, turned towards the midline by ``RobotSpec.side_azimuth``):
:math:`d(\theta) = \cos\psi \, d_{top} + \sin\psi \, d_{side}`, :math:`\psi = \theta \pi / 2`, the site at
:math:`p(\theta) = c - \rho \, d(\theta)` (standoff :math:`\rho`)."""

from __future__ import annotations

import dataclasses

import mink
import numpy as np

from lasa.base.config import check_range
from lasa.base.errors import ConfigError
from lasa.world.goals import GoalTask
from lasa.world.ik import solve_grasp_ik
from lasa.world.robot import Robot


def grasp_frame(robot: Robot, goal: int, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """Grasp-site position (3,) and rotation (3, 3) for cup ``goal`` at preference ``theta`` in [0, 1]."""
    check_range("theta", theta, 0.0, 1.0)
    cup = robot.goal_positions()[goal]
    radial = robot.radial(goal)
    # turn the radial direction by side_azimuth towards the midline (y = 0)
    turn = -np.sign(cup[1]) * robot.spec.side_azimuth if cup[1] != 0 else 0.0
    c, s = np.cos(turn), np.sin(turn)
    side = np.array([c * radial[0] - s * radial[1], s * radial[0] + c * radial[1], 0.0])
    top = np.array([0.0, 0.0, -1.0])
    psi = theta * np.pi / 2
    approach = np.cos(psi) * top + np.sin(psi) * side
    axis = np.cross(top, side)
    rotation = mink.SO3.exp(axis * psi).as_matrix() @ robot.top_rotation
    return cup - robot.spec.grasp_standoff * approach, rotation


@dataclasses.dataclass(frozen=True)
class CupTask(GoalTask):
    """A goal task whose goals are cups, its curves solved by :func:`make_cup_task` (new cups:
    :func:`lasa.method.context_map.extend_task`)."""


def make_cup_task(robot: Robot, n_grid: int = 41) -> CupTask:
    """Solve IK along each cup's preference curve on ``n_grid`` (odd, >= 5) preferences, each solve
    warm-started by the previous one from the robot's IK guess at the top grasp (so neighbouring grasps
    get neighbouring joint configurations); IKError names a grasp out of reach."""
    if n_grid < 5 or n_grid % 2 == 0:
        raise ConfigError(f"n_grid must be an odd integer >= 5, got {n_grid}")
    if len(robot.spec.ik_guesses) != len(robot.spec.goal_sites):
        raise ConfigError(
            f"robot {robot.name!r} has {len(robot.spec.goal_sites)} goal sites but "
            f"{len(robot.spec.ik_guesses)} IK guesses (RobotSpec.ik_guesses): one guess per goal site"
        )
    grid = np.linspace(0.0, 1.0, n_grid)
    curves = np.empty((len(robot.spec.goal_sites), n_grid, robot.n_joints))
    for g, guess in enumerate(robot.spec.ik_guesses):
        q = np.asarray(guess, dtype=float)
        for k, theta in enumerate(grid):
            label = f"cup {robot.spec.goal_sites[g]!r}, theta = {theta:.3f}"
            q = curves[g, k] = solve_grasp_ik(robot, *grasp_frame(robot, g, theta), q, label=label)
    names = tuple(name.removeprefix("cup_") for name in robot.spec.goal_sites)
    return CupTask(robot, names, grid, curves, curves[:, n_grid // 2].copy(), robot.home)


def cup_axis(task: CupTask, points: np.ndarray) -> np.ndarray:
    """Signed position along the axis from the left cup to the right cup [m], (...), 0 midway."""
    cups = task.robot.goal_positions()
    axis = cups[-1] - cups[0]
    axis[2] = 0.0
    axis /= np.linalg.norm(axis)
    return (np.asarray(points) - cups.mean(axis=0)) @ axis


def grasp_preference(task: CupTask, states: np.ndarray) -> np.ndarray:
    """The grasp preference theta the approach axis shows: its angle from straight down over pi/2, (...)."""
    axes = task.robot.grasp_axes(states)
    return np.arctan2(np.linalg.norm(axes[..., :2], axis=-1), -axes[..., 2]) / (np.pi / 2)
