r"""Kinesthetic demonstrations of the eating task: a recorded joint stream (a person guiding the arm, sampled
every Delta) cut into reaches and strokes, labelled, and turned into the dataset D (Sec. VI: the study's
decoder learned from 20 minutes of them).

The fork tip's position and direction at each sample (:func:`lasa.world.fork.tip_frames`) decide its label:

- **rest**: the joints move slower than ``rest_speed``; dropped, as is the last sample (no action);
- **stroke** at goal g: the tip within ``radius`` of g's stroke surface, the segments from the stroke's
  entry p(g, theta, 0) to its end p(g, theta, 1) over the task's tilt grid (:func:`lasa.world.eating.
  fork_frame`), the nearest goal if several;
- **reach** to g: any other moving sample; g is the goal of the next sample near one (the reach ends where
  the tip arrives at g's stroke surface); moving samples that arrive nowhere (the recording ends) are dropped.

A demonstration is a reach and the strokes at its goal: a new one starts where the goal changes or a
reach follows a stroke. theta, a stroke sample's tilt, is the fork's direction's angle psi from pointing down
towards g's sideways r (:func:`lasa.world.eating.fork_direction`), theta = psi / psi_max clipped to [0, 1]
(a tilt away from r reads 0); a reach's is the median tilt of the samples near the goal it arrives at
(before the tip leaves it: the strokes there). Actions are finite differences,
a_t = (s_{t+1} - s_t) / Delta; beliefs are the online update's along the kept samples in order from a
uniform belief (:func:`lasa.method.belief.online_beliefs`), carried across demonstrations as the station
carries it through a session (the synthetic ``continuous`` reading); noisy copies as the synthetic
demonstrations make them (:func:`lasa.method.dataset.add_noisy_copies`)."""

from __future__ import annotations

import dataclasses
import os

import mujoco
import numpy as np

from lasa.base.config import ControlConfig, NonNegative, NonNegativeInt, Positive, Seed, validate
from lasa.base.errors import ArtifactError
from lasa.method.belief import belief_targets, online_beliefs
from lasa.method.dataset import REACH, STROKE, Demonstrations, add_noisy_copies, load_demonstrations
from lasa.world.eating import TILT_MAX, EatingTask, fork_direction, fork_frame
from lasa.world.fork import tip_frames

RECORD_HINT = "python -m lasa.live.teleop demos --franka ADDRESS --out FILE.npz"


@dataclasses.dataclass(frozen=True)
class SegmentConfig:
    """How a recording is cut, and the noisy copies of its tuples (the synthetic demonstrations' defaults,
    :data:`lasa.people.demos.EATING_DEMOS`)."""

    rest_speed: Positive = 0.01  # joint speed ||a|| [rad/s] below which a sample is at rest (dropped)
    radius: Positive = 0.03  # a stroke is the tip this close to a goal's stroke surface (2x the tines) [m]
    n_perturb: NonNegativeInt = 2  # noisy copies of every tuple [-]
    perturb_std: NonNegative = 0.05  # std of the state perturbation of a copy [rad]
    perturb_gain: NonNegative = 2.0  # gain of a copy's corrective action [1/s]
    seed: Seed = 0  # seed of the copies

    def __post_init__(self) -> None:
        validate(self)


@dataclasses.dataclass(frozen=True)
class Segmentation:
    """Labels of a recording's T - 1 samples that have an action (the last has none)."""

    keep: np.ndarray  # moving and labelled with a goal, (T-1,) bool
    goal: np.ndarray  # the goal a sample is at or reaches, -1 none, (T-1,)
    phase: np.ndarray  # REACH or STROKE, (T-1,)
    theta: np.ndarray  # the tilt [-], (T-1,)
    demo: np.ndarray  # the demonstration of each kept sample, -1 for the dropped, (T-1,)


def stroke_distances(task: EatingTask, tips: np.ndarray) -> np.ndarray:
    """Distance from fork tips (T, 3) to each goal's stroke surface, (T, G) [m]: to the nearest of the
    segments p(g, theta, 0) -> p(g, theta, 1) over ``task.theta_grid``."""
    ends = [
        [[fork_frame(task.robot, g, th, u)[0] for u in (0.0, 1.0)] for th in task.theta_grid]
        for g in range(task.n_goals)
    ]
    a, b = np.moveaxis(np.asarray(ends), 2, 0)  # (G, K, 3) each
    ab = b - a
    p = tips[:, None, None, :]
    t = np.clip(((p - a) * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1).min(axis=-1)


def tilts(task: EatingTask, axes: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """theta of fork directions ``axes`` (T, 3) at goals ``goal`` (T,): psi / psi_max in [0, 1], psi the
    angle from pointing down towards the goal's sideways r."""
    down = np.array([0.0, 0.0, -1.0])
    full = np.stack([fork_direction(task.robot, g, 1.0) for g in range(task.n_goals)])  # d(1), (G, 3)
    sideways = (full - np.cos(TILT_MAX) * down) / np.sin(TILT_MAX)  # d(1) = cos psi_max down + sin psi_max r
    psi = np.arctan2(np.einsum("ti,ti->t", axes, sideways[goal]), axes @ down)
    return np.clip(psi / TILT_MAX, 0.0, 1.0)


def _median_sample(runs: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Per sample, the sample holding the (lower) median of ``values`` in its run of equal ``runs``."""
    run = np.cumsum(np.r_[True, runs[1:] != runs[:-1]]) - 1
    order = np.lexsort((values, run))  # by run, then value
    counts = np.bincount(run)
    starts = np.cumsum(counts) - counts
    return order[starts + (counts - 1) // 2][run]


def segment(
    task: EatingTask, states: np.ndarray, dt: float, config: SegmentConfig = SegmentConfig()
) -> Segmentation:
    """Label a recording ``states`` (T, n) sampled every ``dt`` [s] (the module's rules)."""
    actions = np.diff(states, axis=0) / dt
    tips, axes, _, _ = tip_frames(task.robot, mujoco.MjData(task.robot.model), states[:-1])
    dist = stroke_distances(task, tips)
    near = dist.min(axis=1) < config.radius
    at = np.where(near, dist.argmin(axis=1), -1)
    arrivals = np.flatnonzero(near)
    nxt = np.searchsorted(arrivals, np.arange(len(at)))  # the next sample near a goal (len: none)
    arrived = arrivals[np.minimum(nxt, len(arrivals) - 1)] if len(arrivals) else np.zeros(len(at), int)
    goal = np.where(nxt < len(arrivals), at[arrived], -1)  # a sample near a goal arrives at itself
    keep = (np.linalg.norm(actions, axis=1) > config.rest_speed) & (goal >= 0)
    phase = np.where(near, STROKE, REACH)
    tilt = tilts(task, axes, np.maximum(goal, 0))
    theta = np.where(near, tilt, tilt[_median_sample(at, tilt)[arrived]])
    g, ph = goal[keep], phase[keep]
    new = np.r_[True, (g[1:] != g[:-1]) | ((ph[1:] == REACH) & (ph[:-1] == STROKE))][: len(g)]
    demo = np.full(len(at), -1)
    demo[keep] = np.cumsum(new) - 1
    return Segmentation(keep, goal, phase, theta, demo)


def recorded_demonstrations(
    task: EatingTask,
    control: ControlConfig,
    states: np.ndarray,
    config: SegmentConfig = SegmentConfig(),
) -> tuple[Demonstrations, Segmentation]:
    """The dataset D of a recording ``states`` (T, n) sampled every ``control.dt``: its kept samples' tuples
    (beliefs by ``control``'s online update) and their noisy copies; and the segmentation."""
    states = np.asarray(states, dtype=float)
    seg = segment(task, states, control.dt, config)
    keep = seg.keep
    s, a = states[:-1][keep], (np.diff(states, axis=0) / control.dt)[keep]
    beliefs = online_beliefs(belief_targets(task, control.likelihood), control, s, a)
    labels = (seg.demo[keep], seg.goal[keep], seg.theta[keep], seg.phase[keep])
    clean = Demonstrations(task.robot.name, s, a, beliefs, *labels, np.zeros(len(s), bool))
    copies = (config.n_perturb, config.perturb_std, config.perturb_gain)
    rng = np.random.default_rng(config.seed)
    return add_noisy_copies(clean, task.robot, control.action_scale, copies, rng), seg


def relabel_beliefs(demos: Demonstrations, task: EatingTask, control: ControlConfig) -> Demonstrations:
    """``demos`` (clean tuples first, then whole copies of them) with the beliefs ``control``'s online
    update computes along the clean tuples, repeated for the copies (e.g. under another belief cap)."""
    clean = demos.clean()
    beliefs = online_beliefs(belief_targets(task, control.likelihood), control, clean.states, clean.actions)
    return dataclasses.replace(demos, beliefs=np.tile(beliefs, (len(demos) // max(len(clean), 1), 1)))


def load_recorded(path: str | os.PathLike[str], task: EatingTask) -> Demonstrations:
    """Recorded demonstrations saved by the recorder, checked against ``task``: the robot, the goal count
    (beliefs (N, G), goals in range), the shapes, clean tuples first and whole copies; else ArtifactError."""
    demos = load_demonstrations(path, robot=task.robot.name, make_hint=RECORD_HINT)
    n, joints, goals = len(demos), task.robot.n_joints, task.n_goals
    problems = [
        f"{name} has shape {getattr(demos, name).shape}, not {shape}"
        for name, shape in [("states", (n, joints)), ("actions", (n, joints)), ("beliefs", (n, goals))]
        + [(f, (n,)) for f in ("demo", "goal", "theta", "phase", "perturbed")]
        if getattr(demos, name).shape != shape
    ]
    if not problems:
        clean = int((~demos.perturbed).sum())
        if n == 0 or clean == 0 or demos.perturbed[:clean].any() or n % clean:
            problems.append("it holds no clean tuples, or its noisy copies are not whole copies after them")
        elif demos.goal.min() < 0 or demos.goal.max() >= goals:
            problems.append(f"its goals are not all among the task's {goals}")
    if problems:
        raise ArtifactError(
            f"{path} is not a recording of the eating task: {'; '.join(problems)}; "
            f"re-record it with: {RECORD_HINT}"
        )
    return demos
