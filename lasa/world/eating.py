r"""The eating task of the paper's user study (Sec. VI): the Panda's fork over three bowls and a plate.

A preference is a tilt :math:`\theta \in [0, 1]`: the fork turns by :math:`\psi = \theta\,\psi_{max}`
from pointing down towards a sideways r; strokes run 5 cm along m(theta), ending 1 cm into the food
(:func:`fork_frame`). Tasks are phases, each with its waypoints. Why: ``docs/method-notes.md``."""

from __future__ import annotations

import dataclasses
import functools

import mink
import numpy as np
from scipy.interpolate import CubicSpline

from lasa.base.config import ControlConfig, check_choice, check_range
from lasa.base.errors import ConfigError
from lasa.world.goals import GoalTask
from lasa.world.ik import solve_grasp_ik
from lasa.world.robot import ASSETS, ROBOTS, Robot

# goal names, in goal order: the robot's left, middle and right bowl, then the plate (the words a participant
# reads, where the picture mirrors left and right: lasa.world.instructions)
GOALS = ("rice", "middle", "icing", "plate")
STUDY_BELIEF_CAP = 0.99  # Javdani et al.'s cap on any goal's belief (max_prob_any_goal) [-]
TILT_MAX = np.pi / 3  # psi_max: the tilt of a scoop from pointing straight down [rad]
STROKE = 0.05  # length of a stroke through the food [m]
INTO_FOOD = 0.01  # a stroke ends this far below the food's surface [m]

EATING = dataclasses.replace(  # the cup task's Panda (its name, joints, home; hand, so fork, pointing down)
    ROBOTS["panda"],
    scene=ASSETS / "panda" / "eating.xml",
    grasp_site="fork_tip",
    goal_sites=("bowl_left", "bowl_middle", "bowl_right", "plate"),
    camera="table",
    side_azimuth=0.0,  # unused: the eating task tilts the fork sideways (lasa.world.eating._sideways)
    ik_guesses=(ROBOTS["panda"].ik_guesses[0],) * 4,
    # the cup sims' units, with the paper's study's hindsight optimisation and Javdani et al.'s belief cap
    control=ControlConfig(assistance="hindsight", belief_cap=STUDY_BELIEF_CAP),
    tool=ASSETS / "panda" / "fork.xml",
)


# the fine-grained motions at a goal, each the fork's tilt theta in [0, 1] (a fraction of TILT_MAX) [-]
PREFERENCES: dict[str, float] = {"stab": 0.0, "cut": 0.5, "scoop": 1.0, "dip": 0.0, "place": 0.0}


@dataclasses.dataclass(frozen=True)
class Phase:
    """One phase of a task: a preference carried out at a goal, or a reach to it (preference None)."""

    name: str  # e.g. "stab"; the CSVs' phase column
    goal: str  # one of GOALS
    preference: str | None  # a key of PREFERENCES; None: reach the goal's stab entry


TASKS: dict[str, tuple[Phase, ...]] = {
    "Entree": (
        Phase("reach", "middle", None),
        Phase("cut", "middle", "cut"),
        Phase("stab", "middle", "stab"),
        Phase("plate", "plate", "place"),
    ),
    "Dessert": (
        Phase("stab", "middle", "stab"),
        Phase("scoop", "icing", "scoop"),
        Phase("dip", "rice", "dip"),
        Phase("plate", "plate", "place"),
    ),
}
TASK_NAMES = tuple(TASKS)  # the study's tasks, in their order


@dataclasses.dataclass(frozen=True)
class Waypoint:
    """A pose the user must reach, in the order of the task."""

    phase: int  # index of its phase in the task
    goal: int  # goal index
    theta: float  # the preference's tilt [-]
    depth: float  # u: 0 the stroke's entry, 1 its end [-]


@functools.cache
def load_eating_robot() -> Robot:
    """The Panda with its fork in the eating scene (built once per process; do not mutate)."""
    return Robot(EATING)


def _sideways(robot: Robot, goal: int) -> np.ndarray:
    """r at ``goal``, unit (3,): base-to-goal turned a quarter turn to the robot's left (the Panda's
    wrist tilts the fork ~40 degrees at most outward or inward, 60 sideways)."""
    return np.cross([0.0, 0.0, 1.0], robot.radial(goal))


def fork_direction(robot: Robot, goal: int, theta: float | np.ndarray) -> np.ndarray:
    """d(theta): the fork's pointing direction that preference theta needs at ``goal``, (..., 3)."""
    psi = np.asarray(theta, dtype=float)[..., None] * TILT_MAX
    return np.cos(psi) * np.array([0.0, 0.0, -1.0]) + np.sin(psi) * _sideways(robot, goal)


def stroke_direction(robot: Robot, goal: int, theta: float | np.ndarray) -> np.ndarray:
    """m(theta): the direction the tines travel through the food at ``goal``, (..., 3)."""
    th = np.asarray(theta, dtype=float)[..., None]
    m = (1.0 - th) * np.array([0.0, 0.0, -1.0]) + th * _sideways(robot, goal)
    return m / np.linalg.norm(m, axis=-1, keepdims=True)


def fork_frame(robot: Robot, goal: int, theta: float, depth: float) -> tuple[np.ndarray, np.ndarray]:
    """Fork-tip position (3,) and rotation (3, 3) at ``goal``, tilt ``theta`` and stroke depth u in [0, 1]:
    p(g, theta, u) = c_g - 0.01 d_up + (u - 1) 0.05 m(theta)."""
    check_range("theta", theta, 0.0, 1.0)
    check_range("depth", depth, 0.0, 1.0)
    down = np.array([0.0, 0.0, -1.0])
    axis = np.cross(down, _sideways(robot, goal))  # rotating down about it by psi turns it towards r
    rotation = mink.SO3.exp(axis * theta * TILT_MAX).as_matrix() @ robot.top_rotation
    surface = robot.goal_positions()[goal]
    position = surface + INTO_FOOD * down + (depth - 1.0) * STROKE * stroke_direction(robot, goal, theta)
    return position, rotation


@dataclasses.dataclass(frozen=True)
class EatingTask(GoalTask):
    """The eating task: a goal task whose ``curves`` (G, K, n) are the stroke entries s*(g, theta, 0)
    and ``goals`` the mid-tilt ones, plus ``strokes`` s*(g, theta, u), (G, K, D, n) [rad], on
    ``theta_grid`` and ``depth_grid`` (D,)."""

    depth_grid: np.ndarray
    strokes: np.ndarray

    def pose(self, goal: int, theta: float | np.ndarray, depth: float | np.ndarray) -> np.ndarray:
        """s*(g, theta, u), shape (..., n): cubic in theta (as :meth:`target`), linear in depth
        between the solved depths; ``theta`` and ``depth`` broadcast."""
        theta_arr, depth_arr = np.broadcast_arrays(np.asarray(theta, float), np.asarray(depth, float))
        if not np.all((depth_arr >= 0.0) & (depth_arr <= 1.0)):  # NaN too
            raise ConfigError(f"depth must be in [0, 1], got {depth}")
        th, u = theta_arr.ravel(), depth_arr.ravel()
        grid = self.depth_grid
        k = np.clip(np.searchsorted(grid, u, side="right") - 1, 0, len(grid) - 2)
        w = (u - grid[k]) / (grid[k + 1] - grid[k])
        splines = self._stroke_splines[goal]
        out = np.empty((len(th), self.curves.shape[-1]))
        for seg in np.unique(k):  # one stretch of depth at a time: at most len(grid) - 1 calls
            m = k == seg
            out[m] = (1.0 - w[m])[:, None] * splines[seg](th[m]) + w[m][:, None] * splines[seg + 1](th[m])
        return out.reshape(*theta_arr.shape, -1)

    @functools.cached_property
    def _stroke_splines(self) -> list[list[CubicSpline]]:
        return [
            [CubicSpline(self.theta_grid, s, axis=0) for s in goal.transpose(1, 0, 2)]
            for goal in self.strokes
        ]

    @property
    def preference_sets(self) -> np.ndarray:
        """Each goal's stroke surface as one polyline (G, K', n): along the entries and back along the
        ends, so that carrying out a stroke is not evidence against its goal."""
        return np.concatenate([self.strokes[:, :, 0], self.strokes[:, ::-1, -1]], axis=1)


@functools.cache
def make_eating_task(n_theta: int = 9, depths: int = 3) -> EatingTask:
    """Solve mink IK over every goal's ``n_theta`` tilts (odd) and ``depths`` stroke depths (>= 2), once
    per process (the task is immutable and shared)."""
    robot = load_eating_robot()
    if n_theta < 3 or n_theta % 2 == 0:
        raise ConfigError(f"n_theta must be an odd integer >= 3, got {n_theta}")
    check_range("depths", depths, 2)
    thetas, us = np.linspace(0.0, 1.0, n_theta), np.linspace(0.0, 1.0, depths)
    strokes = np.empty((len(GOALS), n_theta, depths, robot.n_joints))
    for g, guess in enumerate(robot.spec.ik_guesses):
        q = np.asarray(guess, dtype=float)  # each solve starts from its neighbour's (theta, then depth)
        for k, theta in enumerate(thetas):
            label = f"goal {GOALS[g]!r}, theta = {theta:.3f}"
            for d, u in enumerate(us):
                where = f"{label}, depth u = {u:.3f}" if d else label
                q = strokes[g, k, d] = solve_grasp_ik(robot, *fork_frame(robot, g, theta, u), q, label=where)
            q = strokes[g, k, 0]
    curves = strokes[:, :, 0].copy()
    return EatingTask(robot, GOALS, thetas, curves, curves[:, n_theta // 2].copy(), robot.home, us, strokes)


def waypoints(task: str) -> list[Waypoint]:
    """The poses a user reaches, in order, to complete ``task`` ("Entree" or "Dessert")."""
    check_choice("task", task, tuple(TASKS))
    return [
        Waypoint(i, GOALS.index(phase.goal), PREFERENCES[phase.preference or "stab"], depth)
        for i, phase in enumerate(TASKS[task])
        for depth in ((0.0,) if phase.preference is None else (0.0, 1.0))
    ]
