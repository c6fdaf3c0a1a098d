r"""Demonstrations D = {(s, a, b)}: reaches to each goal, then adjustments of the preference there.

Motions (from home, or home perturbed, to :math:`s^*(g, \theta)`, then along the preference curve) run
under a saturated proportional speed law :math:`a = \min(k, v/\|e\|)\, e`, each followed by a hold;
beliefs are the robot's online ones; noisy copies teach the decoder to return to the demonstrations."""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from typing import Annotated

import annotated_types as at
import numpy as np
import pandas as pd

from lasa.base.config import (
    ControlConfig,
    NonNegative,
    NonNegativeInt,
    Number,
    Positive,
    PositiveInt,
    Seed,
    check_choice,
    validate,
)
from lasa.method.belief import belief_targets, confident_belief, online_beliefs
from lasa.method.dataset import ADJUST, HOLD, PHASE_NAMES, REACH, STROKE, Demonstrations, add_noisy_copies
from lasa.world.eating import EatingTask
from lasa.world.goals import GoalTask

Segment = tuple[np.ndarray, float, int]  # a motion of a demonstration: its states, preference and phase
Stroke = Callable[[int, float], list[Segment]]


@dataclasses.dataclass(frozen=True)
class DemoConfig:
    """How many demonstrations, and how they move."""

    n_theta: PositiveInt = 9  # preferences demonstrated per cup, evenly spaced on [0, 1]
    n_starts: PositiveInt = 3  # reaches per (cup, theta): one from home, the rest from perturbed homes
    start_noise: NonNegative = 0.3  # std of the start-pose perturbation [rad]
    n_adjust: NonNegativeInt = 3  # grasp adjustments (moves along the preference curve) per demo
    speed: Annotated[Number, at.Gt(0.0), at.Le(1.0)] = 0.8  # cruise speed, a fraction of sigma_h [-]
    gain: Positive = 2.0  # proportional gain of the slow-down near each target [1/s]
    tolerance: Positive = 0.01  # a motion ends this close to its target [rad]
    hold_steps: NonNegativeInt = 3  # steps held still after each motion [-]
    n_perturb: NonNegativeInt = 2  # noisy copies of every tuple [-]
    perturb_std: NonNegative = 0.05  # std of the state perturbation of a copy [rad]
    perturb_gain: NonNegative = 2.0  # gain of a copy's corrective action [1/s]
    max_steps: PositiveInt = 400  # cap on the length of one motion [steps]
    seed: Seed = 0  # seed of the start perturbations, new preferences and copies

    def __post_init__(self) -> None:
        validate(self)


def demonstration_summary(task: GoalTask, demos: Demonstrations) -> pd.DataFrame:
    """One row per (demonstration, phase): ``robot``, ``demo``, ``goal`` (its name), ``phase``,
    ``steps``, and the belief in the goal, ``belief_min`` and ``belief_end``."""
    clean = demos.clean()
    frame = pd.DataFrame(
        {
            "robot": demos.robot,
            "demo": clean.demo,
            "goal": np.asarray(task.goal_names)[clean.goal],
            "phase": np.asarray(PHASE_NAMES)[clean.phase],
            "belief": clean.beliefs[np.arange(len(clean)), clean.goal],
        }
    )
    per_phase = frame.groupby(["robot", "demo", "goal", "phase"], as_index=False)["belief"]
    return per_phase.agg(steps="size", belief_min="min", belief_end="last")


class _Collector:
    """A collection under way: its random stream, its tuples so far, and the demonstrator's motions."""

    def __init__(self, task: GoalTask, control: ControlConfig, config: DemoConfig) -> None:
        self.task, self.control, self.config = task, control, config
        self.rng = np.random.default_rng(config.seed)
        self.rows: list[tuple[np.ndarray, ...]] = []  # (s, a, demo, goal, theta, phase) of each segment
        self.beliefs: list[np.ndarray] = []
        self.cruise = config.speed * control.action_scale
        self.goal_sets = belief_targets(task, control.likelihood)
        self.n_demos = 0

    def _progress(self, span: float) -> np.ndarray:
        """Distance travelled along a path of length ``span`` at each step: u' = min(gain (span - u), v)."""
        config, dt = self.config, self.control.dt
        u = [0.0]
        while span - u[-1] > config.tolerance and len(u) <= config.max_steps:
            u.append(u[-1] + dt * min(config.gain * (span - u[-1]), self.cruise))
        return np.asarray(u)

    def perturbed(self, q: np.ndarray) -> np.ndarray:
        """``q`` plus the start perturbation, clipped to the joint limits."""
        return self.task.robot.clip(q + self.rng.normal(0.0, self.config.start_noise, q.shape))

    def line(self, start: np.ndarray, target: np.ndarray) -> np.ndarray:
        """States along the joint-space line from ``start`` to ``target`` under the speed law."""
        span = float(np.linalg.norm(target - start))
        return start + (self._progress(span) / max(span, 1e-12))[:, None] * (target - start)

    def curve(self, curve: Callable[[np.ndarray], np.ndarray], start: float, end: float) -> np.ndarray:
        """States along ``curve(x)`` (x from ``start`` to ``end``) under the speed law, by arc length."""
        grid = np.linspace(start, end, 64)
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve(grid), axis=0), axis=1))])
        return curve(np.interp(self._progress(float(arc[-1])), arc, grid))

    def adjust(
        self, g: int, theta: float, segments: list[Segment], stroke: Stroke | None = None
    ) -> list[Segment]:
        """``segments`` and ``n_adjust`` moves along goal g's curve to random preferences (each stroked)."""
        current = theta
        for _ in range(self.config.n_adjust):
            new = float(self.rng.uniform(0.0, 1.0))
            segments.append((self.curve(functools.partial(self.task.target, g), current, new), new, ADJUST))
            if stroke is not None:
                segments += stroke(g, new)
            current = new
        return segments

    def append(self, segments: list[Segment], goal: int, start_belief: np.ndarray | None = None) -> None:
        """Append one demonstration: each (path, preference, phase)'s finite differences, then a hold,
        with the online belief along the whole of it from ``start_belief`` (default uniform)."""
        control, hold = self.control, self.config.hold_steps
        rows = []
        for path, th, phase in segments:
            s = np.concatenate([path[:-1], np.repeat(path[-1:], hold, 0)])
            still = np.zeros((hold, self.task.robot.n_joints))
            a = np.concatenate([np.diff(path, axis=0) / control.dt, still])
            n = len(s)
            ph = np.full(n, phase)
            ph[len(path) - 1 :] = HOLD
            rows.append((s, a, np.full(n, self.n_demos), np.full(n, goal), np.full(n, th), ph))
        states, actions = (np.concatenate([row[i] for row in rows]) for i in (0, 1))
        log_b0 = None if start_belief is None else np.log(start_belief)
        self.beliefs.append(online_beliefs(self.goal_sets, control, states, actions, log_b0))
        self.rows += rows
        self.n_demos += 1

    def dataset(self) -> Demonstrations:
        """The tuples and ``n_perturb`` noisy copies of each (:func:`.add_noisy_copies`)."""
        config = self.config
        states, actions, *labels = map(np.concatenate, zip(*self.rows, strict=True))
        demo, goal, theta, phase = labels
        beliefs = np.concatenate(self.beliefs)
        robot, none = self.task.robot, np.zeros(len(states), bool)
        clean = Demonstrations(robot.name, states, actions, beliefs, demo, goal, theta, phase, none)
        copies = (config.n_perturb, config.perturb_std, config.perturb_gain)
        return add_noisy_copies(clean, robot, self.control.action_scale, copies, self.rng)


def collect_demonstrations(
    task: GoalTask, control: ControlConfig, config: DemoConfig = DemoConfig()
) -> Demonstrations:
    """The demonstrations of ``task``, noisy copies included (:meth:`Demonstrations.clean`), under
    ``control``'s dt, sigma_h (the speed scale) and belief model."""
    c = _Collector(task, control, config)
    for g in range(task.n_goals):
        for theta in np.linspace(0.0, 1.0, config.n_theta):
            for j in range(config.n_starts):
                start = c.perturbed(task.start) if j > 0 else task.start.copy()
                c.append(c.adjust(g, theta, [(c.line(start, task.target(g, theta)), theta, REACH)]), g)
    return c.dataset()


# Five tilts per goal, stroked, adjusted once and stroked again: about the paper's 20 minutes.
EATING_DEMOS = DemoConfig(n_theta=5, n_starts=1, n_adjust=1)
SEGMENTATIONS = ("continuous", "home", "transfers", "leaves")  # how the eating demonstrations are cut


def collect_eating_demonstrations(
    task: EatingTask,
    control: ControlConfig,
    config: DemoConfig = EATING_DEMOS,
    segmentation: str = "continuous",
) -> Demonstrations:
    """Kinesthetic-style demonstrations of the eating task (the paper's D of Sec. VI): per goal, tilt and
    start, **reach** the stroke's entry s*(g, theta, 0), **stroke** to s*(g, theta, 1) and back, then
    ``n_adjust`` times **adjust** the tilt and stroke there.

    ``segmentation`` (:data:`SEGMENTATIONS`), how a teacher cuts them, decides each tuple's belief:
    ``continuous`` (moves between goals start from the belief settled there), ``home`` (all from
    (perturbed) home, uniform), ``transfers`` (plus separate moves between goals' entries, uniform)
    or ``leaves`` (those moves leave a stroke's end, confident: Sec. IV-B; ``docs/method-notes.md``)."""
    check_choice("segmentation", segmentation, SEGMENTATIONS)
    c = _Collector(task, control, config)

    def stroke(g: int, theta: float) -> list[Segment]:
        down = c.curve(functools.partial(task.pose, g, theta), 0.0, 1.0)
        return [(down, theta, STROKE), (down[::-1], theta, STROKE)]

    home, leave, transfers = (segmentation == name for name in ("home", "leaves", "transfers"))
    n_home = config.n_starts + (task.n_goals - 1 if home else 0)
    for g in range(task.n_goals):
        for theta in np.linspace(0.0, 1.0, config.n_theta):
            # home and perturbed homes, uniform (None) and manipulating; then, unless ``home``, each other
            # goal's entry at a random tilt (``leaves``: its stroke's end), from the belief settled there
            # (uniform for ``transfers``), manipulating for ``continuous`` only; all drawn before the moves
            homes = [task.start.copy()] + [c.perturbed(task.start) for _ in range(n_home - 1)]
            starts: list[tuple[np.ndarray, np.ndarray | None, bool]] = [(q, None, True) for q in homes]
            for other in [] if home else [o for o in range(task.n_goals) if o != g]:
                tilt = float(c.rng.uniform())
                entry = task.pose(other, tilt, 1.0) if leave else task.target(other, tilt)
                settled = confident_belief(task.n_goals, other, control.belief_floor, control.belief_cap)
                starts.append((entry, None if transfers else settled, segmentation == "continuous"))
            for start, b0, work in starts:
                segments = [(c.line(start, task.target(g, theta)), float(theta), REACH)]
                if work:  # else a separate transfer: the reach, and its hold, only
                    segments = c.adjust(g, float(theta), segments + stroke(g, float(theta)), stroke)
                c.append(segments, g, b0)
    return c.dataset()
