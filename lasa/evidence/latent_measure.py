r"""Measuring the latent-action property of a decoder (Secs. III, IV-B): each input of a ring of
full stick deflections is held confident at goal g (does it *stay*), uncertain at home (which goal
does it *reach*), and from each phase end at g (which other goal does it *leave* for, how soon).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

from lasa.base.config import AtLeastTwo, ControlConfig, NonNegative, Positive, validate
from lasa.base.errors import ConfigError
from lasa.evidence.latent_property import COLUMNS, CONDITIONS
from lasa.method.belief import confident_belief
from lasa.method.decoder import ActionDecoder
from lasa.method.runner import Runner, held_input
from lasa.method.step import Assist
from lasa.world.eating import TASKS, EatingTask, waypoints
from lasa.world.goals import GoalTask


@dataclasses.dataclass(frozen=True)
class PropertyConfig:
    """How the property is measured; every value is set from what it means (a 4 s hold sweeps half
    the longest preference curve at cruise speed), not from a result."""

    n_inputs: AtLeastTwo = 64  # stick inputs on the ring [-]
    hold: Positive = 4.0  # seconds each input is held at a goal, the belief held confident [s]
    drift_speed: Positive = 0.02  # v: an input stays when d(t) <= v t through the hold [m/s]
    uncertain_hold: Positive = 10.0  # seconds each input is held from home, the belief updated online [s]
    reach_distance: Positive = 0.05  # an input reaches a goal when the tip ends this close to its set [m]
    rotation_weight: NonNegative = 0.125  # metres per radian of direction when matching a preference [m/rad]
    n_grid: AtLeastTwo = 41  # preference grid per coordinate of the preference set [-]
    leave_hold: Positive = 10.0  # seconds each input is held from a confident goal's phase end [s]

    def __post_init__(self) -> None:
        validate(self)


@dataclasses.dataclass(frozen=True)
class PreferenceSet:
    """The preferences at one goal, sampled: coordinates and the tool tip's pose at each."""

    theta: np.ndarray  # tilt (cups: top 0 to side 1; bowls: straight down 0 to a scoop's 60 deg 1), (P,)
    stroke: np.ndarray  # depth u along the stroke (bowls), 0 where the task has no strokes, (P,)
    positions: np.ndarray  # tip positions, (P, 3) [m]
    axes: np.ndarray  # tip directions (unit), (P, 3)


def preference_set(task: GoalTask, goal: int, n_grid: int = 41) -> PreferenceSet:
    """Goal ``goal``'s preference set: the curve s*(g, theta), or a bowl's surface s*(g, theta, u)."""
    thetas = np.linspace(0.0, 1.0, n_grid)
    pose = getattr(task, "pose", None)
    if pose is None or not len(getattr(task, "depth_grid", ())):
        states = task.target(goal, thetas)
        theta, stroke = thetas, np.zeros_like(thetas)
    else:
        us = np.linspace(0.0, 1.0, max(2, n_grid // 4 + 1))
        tt, uu = np.meshgrid(thetas, us, indexing="ij")
        theta, stroke = tt.ravel(), uu.ravel()
        states = pose(goal, theta, stroke)
    return PreferenceSet(theta, stroke, task.robot.grasp_positions(states), task.robot.grasp_axes(states))


def ring(n: int, z_dim: int) -> np.ndarray:
    """``n`` full stick deflections, shape (n, z_dim): the unit circle (2 axes) or [-1, 1] (1 axis)."""
    if z_dim == 1:
        return np.linspace(-1.0, 1.0, n + n % 2)[:, None]  # an even count: rest is not among them
    if z_dim == 2:
        angles = 2 * np.pi * np.arange(n) / n
        return np.round(np.stack([np.cos(angles), np.sin(angles)], axis=1), 12)
    raise ConfigError(f"the property is measured for 1- or 2-axis sticks, not z_dim={z_dim}")


def held_input_paths(
    decoder: ActionDecoder,
    task: GoalTask,
    control: ControlConfig,
    start: np.ndarray,
    belief: np.ndarray,
    z_values: np.ndarray,
    steps: int,
    update_belief: bool = False,
) -> np.ndarray:
    """States (K, steps + 1, n) reached by holding each input of ``z_values`` (K,) or (K, d) for
    ``steps`` steps from ``start`` (n,) and ``belief`` (G,), with latent actions alone (alpha = 0),
    one decoder call per step; ``update_belief``: update it online (Algorithm 1), else hold it."""
    belief = np.asarray(belief, dtype=float)
    if belief.shape != (task.n_goals,) or not np.isclose(belief.sum(), 1.0) or belief.min() < 0:
        raise ConfigError(f"belief must be a distribution over {task.n_goals} goals, got {belief}")
    z = np.asarray(z_values, dtype=float).reshape(len(z_values), -1)
    starts = np.broadcast_to(start, (len(z), task.robot.n_joints))
    beliefs = np.broadcast_to(belief, (len(z), task.n_goals))
    return leave_paths(
        decoder, task, control, starts, beliefs, z, np.zeros(len(z)), steps, "decode", update_belief
    )


def phase_ends(task: GoalTask, goal: int) -> list[tuple[str, np.ndarray]]:
    """(label, joint positions (n,)) where each phase at ``goal`` ends: each eating stroke's end at
    depth 1, labelled by its preference; for the cups, s*(g, 1/2) labelled ``grasp``."""
    if not isinstance(task, EatingTask):
        return [("grasp", task.target(goal, 0.5))]
    ends: dict[str, float] = {}
    for name, phases in TASKS.items():
        for wp in waypoints(name):
            preference = phases[wp.phase].preference
            if wp.goal == goal and wp.depth == 1.0 and preference is not None:
                ends.setdefault(preference, wp.theta)
    return [(label, task.pose(goal, np.array([theta]), np.array([1.0]))[0]) for label, theta in ends.items()]


def leave_paths(
    decoder: ActionDecoder,
    task: GoalTask,
    control: ControlConfig,
    starts: np.ndarray,
    beliefs: np.ndarray,
    z_values: np.ndarray,
    alphas: np.ndarray,
    steps: int,
    rest: str = "zero",
    update_belief: bool = True,
) -> np.ndarray:
    """States (R, steps + 1, n) reached by holding input ``z_values[i]`` from ``starts[i]`` and
    ``beliefs[i]`` under Algorithm 1's step with blend weight ``alphas[i]``, one decoder call per step."""
    if steps < 1:
        raise ConfigError(f"steps must be >= 1, got {steps}")
    log_b = np.log(np.maximum(np.asarray(beliefs, dtype=float), 1e-300))
    runner = Runner(Assist(task, control, np.asarray(alphas, dtype=float)), starts, log_b, update_belief)
    z = np.asarray(z_values, dtype=float)
    return runner.run(held_input(decoder, z, rest), steps).states.swapaxes(0, 1)


def _nearest(
    pset: PreferenceSet, pos: np.ndarray, axis: np.ndarray, weight: float
) -> tuple[np.ndarray, np.ndarray]:
    """Per point: the distance to the set's positions (...,), and the index of the nearest preference pose."""
    d_pos = np.linalg.norm(pos[..., None, :] - pset.positions, axis=-1)  # (..., P)
    angle = np.arccos(np.clip(axis @ pset.axes.T, -1.0, 1.0))
    return d_pos.min(axis=-1), (d_pos + weight * angle).argmin(axis=-1)


def measure(
    task: GoalTask,
    decoder: ActionDecoder,
    control: ControlConfig,
    config: PropertyConfig = PropertyConfig(),
    *,
    source: str,
    task_name: str,
    decoder_name: str,
) -> pd.DataFrame:
    """The property of ``decoder`` on ``task``, one row per (context, goal, input) (``COLUMNS``):
    ``confident`` rows with ``drift`` (largest d(t)/t [m/s]) and ``stays``, ``uncertain`` (goal
    ``home``) and ``leave`` rows with the goal ``reached`` (``-`` for none) and ``distance`` [m]."""
    base = {"source": source, "robot": task.robot.name, "task": task_name, "decoder": decoder_name}
    psets = [preference_set(task, g, config.n_grid) for g in range(task.n_goals)]
    run = _Run(task, decoder, control, config, ring(config.n_inputs, decoder.z_dim), psets, base)
    rows = [_confident_rows(run, g) for g in range(task.n_goals)]
    return pd.concat([*rows, _uncertain_rows(run), _leave_rows(run)], ignore_index=True)


@dataclasses.dataclass(frozen=True)
class _Run:
    task: GoalTask
    decoder: ActionDecoder
    control: ControlConfig
    config: PropertyConfig
    z: np.ndarray  # the ring's inputs, (K, d)
    preference_sets: list[PreferenceSet]  # each goal's
    base: dict[str, str]  # the rows' source, robot, task and decoder columns


def _confident_rows(run: _Run, g: int) -> pd.DataFrame:
    task, config, z, preference_sets = run.task, run.config, run.z, run.preference_sets
    robot = task.robot
    dt = run.control.dt
    names = task.goal_names
    hold = max(1, round(config.hold / dt))
    pset = preference_sets[g]
    b = confident_belief(task.n_goals, g, run.control.belief_floor, run.control.belief_cap)
    paths = held_input_paths(run.decoder, task, run.control, task.target(g, 0.5), b, z, hold)  # (K, H+1, n)
    pos, axis = robot.grasp_positions(paths[:, 1:]), robot.grasp_axes(paths[:, 1:])
    dist, _ = _nearest(pset, pos, axis, config.rotation_weight)  # (K, H)
    drift = (dist / (dt * np.arange(1, hold + 1))).max(axis=1)
    _, idx = _nearest(pset, pos[:, -1], axis[:, -1], config.rotation_weight)
    ends = np.stack([_nearest(s, pos[:, -1], axis[:, -1], 0.0)[0] for s in preference_sets], axis=1)  # (K, G)
    stays = drift <= config.drift_speed
    reached = np.where(stays, names[g], np.asarray(names)[ends.argmin(axis=1)])
    columns = dict(drift=drift, stays=stays, theta=pset.theta[idx], stroke=pset.stroke[idx], reached=reached)
    return _rows(run.base, "confident", names[g], z, **columns, distance=ends[:, g])


def _uncertain_rows(run: _Run) -> pd.DataFrame:
    task = run.task
    z = run.z
    robot = run.task.robot
    steps = max(1, round(run.config.uncertain_hold / run.control.dt))
    flat = np.full(task.n_goals, 1.0 / task.n_goals)  # the uniform belief
    paths = held_input_paths(run.decoder, task, run.control, task.start, flat, z, steps, update_belief=True)
    end = paths[:, -1]
    pos, axis = robot.grasp_positions(end), robot.grasp_axes(end)
    dist = np.stack([_nearest(s, pos, axis, 0.0)[0] for s in run.preference_sets], axis=1)  # (K, G)
    near = dist.argmin(axis=1)
    best = dist[np.arange(len(z)), near]
    reached = np.where(best <= run.config.reach_distance, np.asarray(task.goal_names)[near], "-")
    return _rows(run.base, "uncertain", "home", z, reached=reached, distance=best)


def _rows(base: dict[str, str], context: str, goal: str, z: np.ndarray, **cols: object) -> pd.DataFrame:
    none = {"drift": np.nan, "stays": False, "theta": np.nan, "stroke": np.nan}
    z2 = z[:, 1] if z.shape[1] > 1 else np.full(len(z), np.nan)
    frame = pd.DataFrame({**base, "context": context, "goal": goal, "z1": z[:, 0], "z2": z2, **none, **cols})
    return frame.reindex(columns=list(COLUMNS))


def _leave_rows(run: _Run) -> pd.DataFrame:
    """The leave rows, per (goal, phase end, condition, input, other goal), in one batch."""
    task = run.task
    control = run.control
    z = run.z
    names = run.task.goal_names
    alphas = {"LA": 0.0, "LA+SA": control.alpha}
    runs = [
        (g, label, state, cond)
        for g in range(task.n_goals)
        for label, state in phase_ends(task, g)
        for cond in CONDITIONS
    ]
    k = len(z)
    starts = np.concatenate([np.broadcast_to(state, (k, len(state))) for _, _, state, _ in runs])
    confident = [
        confident_belief(task.n_goals, g, control.belief_floor, control.belief_cap) for g, *_ in runs
    ]
    beliefs = np.repeat(np.stack(confident), k, axis=0)
    alpha = np.repeat([alphas[cond] for *_, cond in runs], k)
    steps = max(1, round(run.config.leave_hold / control.dt))
    paths = leave_paths(run.decoder, task, control, starts, beliefs, np.tile(z, (len(runs), 1)), alpha, steps)
    pos = task.robot.grasp_positions(paths[:, 1:])  # (R, T, 3)
    trees = [cKDTree(pset.positions) for pset in run.preference_sets]  # dist: (R, G, T)
    dist = np.stack([t.query(pos.reshape(-1, 3))[0].reshape(pos.shape[:2]) for t in trees], axis=1)
    near = dist <= run.config.reach_distance
    first = np.where(near.any(axis=2), near.argmax(axis=2) + 1, -1)  # first step within reach, (R, G)
    frames = []
    for i, (g, label, _, cond) in enumerate(runs):
        rows = slice(i * k, (i + 1) * k)
        for h in [h for h in range(task.n_goals) if h != g]:
            arrived = first[rows, h] > 0
            exit_time = np.where(arrived, first[rows, h] * control.dt, np.nan)
            leave = dict(start=label, condition=cond, target=names[h], exit_time=exit_time)
            reached, distance = np.where(arrived, names[h], "-"), dist[rows, h].min(axis=1)
            frames.append(_rows(run.base, "leave", names[g], z, reached=reached, distance=distance, **leave))
    return pd.concat(frames, ignore_index=True)
