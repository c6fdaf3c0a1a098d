r"""The cup task: cups as the goals, and a preference from a top grasp to a side grasp.

Cups stand on a table (the goals G: two in the paper's scenes, as many as a registered
robot's scene has, :func:`lasa.world.robot.load_robot`). At any cup the user may want any grasp on
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
assistance of Eq. M2 lives in joint space, as in the paper. :class:`CupTask` is a
:class:`lasa.world.goals.GoalTask`, as the eating task is.
"""

from __future__ import annotations

import dataclasses

import mink
import numpy as np

from lasa.base.config import check_range
from lasa.base.errors import ConfigError
from lasa.world.goals import GoalTask
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
    cup = robot.goal_positions()[goal]
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
class CupTask(GoalTask):
    """The cup task for one robot: a goal task whose goals are cups and whose preference
    runs from a top grasp (theta = 0) to a side grasp (theta = 1).

    Everything it holds is a :class:`lasa.world.goals.GoalTask`'s: the robot, the cups'
    names (``goal_names``), the IK grid ``theta_grid``, the grasp curves s*(g, theta)
    (``curves``, shape (G, K, n)), the goals g = s*(g, 0.5) and the start pose. What makes
    it the cup task is how :func:`make_cup_task` solves the curves (:func:`grasp_frame`);
    new cups are added by :func:`lasa.method.newgoals.extend_task`.
    """


def make_cup_task(robot: Robot, n_grid: int = 41) -> CupTask:
    """Solve IK along each cup's preference curve and build the task.

    Starting from the robot's per-goal IK guess at the top grasp (theta = 0), solve along the
    grid to the side grasp, each solve warm-started (and posture-regularised) by the
    previous one, so neighbouring grasps get neighbouring joint configurations.

    Args:
        robot: The robot.
        n_grid: Number of preferences solved per cup (odd, so 0.5 is on the grid).

    Raises:
        ConfigError: if ``n_grid`` is not an odd integer >= 5, or the robot's spec does not
            give one IK guess per cup.
        IKError: if a grasp is out of reach from its guess; the message names the cup and theta.
    """
    if n_grid < 5 or n_grid % 2 == 0:
        raise ConfigError(f"n_grid must be an odd integer >= 5, got {n_grid}")
    if len(robot.spec.ik_guesses) != len(robot.spec.goal_sites):
        raise ConfigError(
            f"robot {robot.name!r} has {len(robot.spec.goal_sites)} goal sites but "
            f"{len(robot.spec.ik_guesses)} IK guesses (RobotSpec.ik_guesses): one guess per goal site"
        )
    grid = np.linspace(0.0, 1.0, n_grid)
    mid = n_grid // 2
    curves = np.empty((len(robot.spec.goal_sites), n_grid, robot.n_joints))
    for g, guess in enumerate(robot.spec.ik_guesses):
        q = np.asarray(guess, dtype=float)
        for k in range(n_grid):
            label = f"cup {robot.spec.goal_sites[g]!r}, theta = {grid[k]:.3f}"
            q = solve_grasp_ik(robot, *grasp_frame(robot, g, grid[k]), q, label=label)
            curves[g, k] = q
    names = tuple(name.removeprefix("cup_") for name in robot.spec.goal_sites)
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
    cups = task.robot.goal_positions()
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
