"""Fig. sim4's episodes: near-optimal users want a grasp at new cups, reached through each kind of context
map h and without it; and where each map sends the new cups' grasps."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pandas as pd

from lasa.base.config import (
    ControlConfig,
    NonNegative,
    NonNegativeInt,
    Number,
    Positive,
    PositiveInt,
    check_choice,
    check_list,
)
from lasa.base.errors import ConfigError
from lasa.evidence import verdicts
from lasa.evidence.metrics import confidence, normalized_error
from lasa.experiments import sweep
from lasa.method.context_map import MAP_KINDS, ContextMap, MappedDecoder, context_map, extend_task
from lasa.method.decoder import ActionDecoder
from lasa.method.step import METHOD_DECODER, METHODS, method_alpha
from lasa.people.rollout import Trajectories, rollout
from lasa.people.users import UserPopulation
from lasa.world.fork import angle_between
from lasa.world.robot import Robot
from lasa.world.task import CupTask

NAME = "sim4_new_goals"
EPISODE_COLUMNS = (  # what :func:`run` returns, one row per episode
    "robot",
    "mapping",
    "distance",
    verdicts.USER,
    "error",
    "h",
    "offset_m",
    "theta",
    "confidence",
    "reference",
    "assistance",
    "look",
    "angle_error_deg",
    "distance_joint",
    "error_joint",
    "reference_joint",
    "end_goal",
)
# per (robot, assistance, h, distance), on each of its episodes' rows (:func:`with_cup_columns`): the
# mean and the median error, and the share of episodes whose belief ends on another training cup
CUP_COLUMNS = ("cup_mean_error", "cup_median_error", "cup_other_share")
COLUMNS = EPISODE_COLUMNS + CUP_COLUMNS  # the CSV's
# the kinds of map notebook 07 reads by name (map_sentences, and its video's grasp-to-grasp map), so
# every run holds them; straight_line_ee, the reading @ee_line, may be left out
CLAIM_MAPS = ("grasp", "straight_line")


@dataclasses.dataclass(frozen=True)
class Config(sweep.LooksConfig):
    """Fig. sim4: users who reach for new cups, with and without the context map h."""

    # new cups' distances from the reference cup [m]
    offsets: tuple[Positive, ...] = (0.08, 0.11, 0.14, 0.17, 0.20)
    direction: tuple[Number, Number] | None = None  # on the table; None: from the other training cup to ref
    ref_goal: NonNegativeInt = 1  # the training cup the new ones are referred to [-]
    beta: NonNegative = 1000.0  # near-optimal users [1/rad^2]
    horizon: PositiveInt = 200  # control steps per episode [-]
    method: str = "LA+SA"  # the method compared with and without the map (its decoder is given)
    # kinds of h run "with" the map (lasa.method.context_map); straight_line_ee, the paper's line read in
    # the gripper's space, is the reading @ee_line of the straight-line claim (one IK per user and step)
    maps: tuple[str, ...] = ("grasp", "straight_line", "straight_line_ee")

    def __post_init__(self) -> None:
        super().__post_init__()
        why = "a line fitted to two points has R^2 = 1 whatever the errors"
        offsets = check_list("offsets", self.offsets, at_least=3, ascending=True, why=why)
        object.__setattr__(self, "offsets", tuple(float(o) for o in offsets))
        if self.direction is not None and (
            not np.isfinite(self.direction).all() or np.hypot(*self.direction) < 1e-9
        ):
            raise ConfigError(f"direction must be a non-zero (dx, dy) on the table, got {self.direction!r}")
        check_choice("method", self.method, METHODS)
        sweep.check_names("maps", self.maps, MAP_KINDS)
        sweep.check_needed("maps", tuple(self.maps), CLAIM_MAPS, "notebook 07's sentences and video")


@dataclasses.dataclass(frozen=True)
class NewGoalRun:
    """The episodes at one new cup (``offset`` [m] from the reference cup), with each kind of map and not."""

    offset: float
    task: CupTask
    with_map: dict[str, Trajectories]
    without_map: Trajectories


def new_cup_positions(task: CupTask, config: Config) -> np.ndarray:
    """Grasp centres of the new cups, shape (len(offsets), 3) [m]."""
    cups = task.robot.goal_positions()
    ref = cups[config.ref_goal]
    if config.direction is None:  # from the other training cup to the reference one
        direction = (ref - cups[(config.ref_goal + 1) % task.n_goals])[:2]
    else:
        direction = np.asarray(config.direction, dtype=float)
    direction = np.r_[direction / np.linalg.norm(direction), 0.0]
    return ref + np.asarray(config.offsets)[:, None] * direction


def map_geometry(task: CupTask, config: Config) -> pd.DataFrame:
    """Where each kind of context map sends the new cups' grasps, one row per (``offset_m``, ``h``)."""
    robot, ref = task.robot, config.ref_goal
    cups = new_cup_positions(task, config)
    scale = float(np.linalg.norm(cups - robot.goal_positions()[ref], axis=1).max())
    rows = []
    for offset, pos in zip(config.offsets, cups, strict=True):
        big = extend_task(task, pos, ref)
        new, old = big.curves[-1], task.curves[ref]
        diff = new - old
        per_cup = {
            "offset_m": float(offset),
            "distance": float(np.linalg.norm(pos - robot.goal_positions()[ref])) / scale,
            "joint1_rad": float(np.abs(diff[:, 0]).max()),
            "joint_last_rad": float(np.abs(diff[:, -1]).max()),
            "branch_rad": float(np.linalg.norm(np.diff(diff, axis=0), axis=1).max()),
            "grasp_margin_rad": float(np.minimum(new - robot.lower, robot.upper - new).min()),
        }
        for kind in config.maps:
            cmap = context_map(big, task.n_goals, ref, kind)
            mapped = cmap.state(new)
            misfit_m, misfit_deg = grasp_error(robot, mapped, old)
            line = cmap.new_goal - cmap.start
            shift = np.nan  # the joint-space line's stretch; the gripper's line (TaskSpaceMap) has none here
            if isinstance(cmap, ContextMap):
                shift = float(line @ (task.goals[ref] - cmap.new_goal)) / (
                    float(line @ line) * cmap.saturation
                )
            rows.append(
                {
                    **per_cup,
                    "h": kind,
                    "misfit_rad": float(np.linalg.norm(mapped - old, axis=1).max()),
                    "misfit_m": float(misfit_m.max()),
                    "misfit_deg": float(misfit_deg.max()),
                    "margin_rad": float(np.minimum(mapped - robot.lower, robot.upper - mapped).min()),
                    "stretch": 1.0 + shift,
                }
            )
    return pd.DataFrame(rows).set_index(["offset_m", "h"])


def run(
    decoders: sweep.Decoders,
    task: CupTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = False,
    look: int = 0,
    assistance: tuple[str, ...] | None = None,
) -> tuple[pd.DataFrame, list[NewGoalRun]]:
    """Fig. sim4: near-optimal users want a grasp at each new cup, through each kind of map and without.

    Every member's users (the same, paired) share one batch per (cup, map). Returns one row per episode
    (:data:`EPISODE_COLUMNS`) and the runs per new cup under ``control.assistance``."""
    ref = config.ref_goal
    if not 0 <= ref < task.n_goals:
        raise ConfigError(f"ref_goal must be in [0, {task.n_goals}), got {ref}")
    key = METHOD_DECODER[config.method]
    decoder = sweep.as_decoders(decoders).get(key)
    if decoder is None:
        raise ConfigError(f"method {config.method!r} needs the {key!r} decoder; pass decoders[{key!r}]")
    first, n_users = verdicts.block_users(verdicts.Looks(config.users, config.block, config.cap), look)
    _, theta, noise = sweep.episodes(
        decoder, task, control, n_users, config.horizon, verdicts.block_seed(config.seed, look)
    )
    alpha = method_alpha(config.method, control)
    assistance = sweep.swept_assistance(control, config.assistance) if assistance is None else assistance
    assistance = assistance if alpha > 0 else (verdicts.NO_ASSISTANCE,)
    cups = new_cup_positions(task, config)
    grown = [extend_task(task, p, ref) for p in cups]
    dist = np.array([np.linalg.norm(t.goals[-1] - task.goals[ref]) for t in grown])  # joint space [rad]
    on_table = np.linalg.norm(cups - task.robot.goal_positions()[ref], axis=1)  # [m]
    member = np.repeat(assistance, n_users)  # member i's users are rows i * n_users ... (i + 1) * n_users - 1
    assisted = None if assistance == (verdicts.NO_ASSISTANCE,) else member
    user, theta = np.tile(np.arange(n_users), len(assistance)), np.tile(theta, len(assistance))
    n, head = len(user), slice(0, n_users)
    shared = {verdicts.USER: first + user, "theta": theta, "assistance": member, "look": look}
    scales = (float(on_table.max()), float(dist.max()))

    def roll(dec: ActionDecoder, on: CupTask, users: UserPopulation) -> Trajectories:
        return rollout(dec, on, users, alpha, control, config.horizon, noise, progress, assistance=assisted)

    runs, rows = [], []
    for i, (offset, big) in enumerate(zip(config.offsets, grown, strict=True)):
        new = np.full(n, big.n_goals - 1)
        users = UserPopulation(
            goal=new,
            theta=theta,
            target=big.target(new, theta),
            beta0=np.full(n, config.beta),
            slope=np.zeros(n),
            user=user,
        )
        with_map = {
            kind: roll(MappedDecoder(decoder, context_map(big, task.n_goals, ref, kind)), big, users)
            for kind in config.maps
        }
        without = roll(decoder, task, dataclasses.replace(users, goal=np.full(n, ref)))
        mine = {k: _users_of(t, head) for k, t in with_map.items()}
        runs.append(NewGoalRun(float(offset), big, mine, _users_of(without, head)))
        at = {"offset_m": float(offset), "distance": float(on_table[i]), "distance_joint": float(dist[i])}
        rows += _rows(task, config, users, {**with_map, "none": without}, {**shared, **at}, scales)
    frame = pd.concat(rows, ignore_index=True)
    # rows by member, then cup and map, as the members' runs came out before they shared batches
    order = np.argsort(pd.Categorical(frame.assistance, categories=list(assistance)).codes, kind="stable")
    return frame.iloc[order].reset_index(drop=True), runs


def _users_of(traj: Trajectories, users: slice) -> Trajectories:
    """The trajectories of some users (axis 1 of every field)."""
    return Trajectories(**{f.name: getattr(traj, f.name)[:, users] for f in dataclasses.fields(traj)})


def grasp_error(robot: Robot, states: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distance [m] between the grasp sites at ``states`` and ``targets`` (joint vectors, (..., n)),
    and the angle between their approach axes (the site's +z) [deg]."""
    states = np.asarray(states, dtype=float)
    targets = np.broadcast_to(np.asarray(targets, dtype=float), states.shape)
    pos, rot = robot.grasp_frames(np.stack([states, targets]))
    angle = angle_between(rot[0][..., :, 2], rot[1][..., :, 2])
    return np.linalg.norm(pos[0] - pos[1], axis=-1), np.degrees(angle)


def _rows(
    task: CupTask,
    config: Config,
    users: UserPopulation,
    runs: dict[str, Trajectories],
    at: dict[str, Any],
    scales: tuple[float, float],
) -> list[pd.DataFrame]:
    """The rows at one new cup of each kind of map's episodes and the no-map ones (``none``); ``scales``:
    the farthest cup's distance on the table [m] and in joint space [rad]."""
    robot, (cup_scale, scale) = task.robot, scales
    held = task.target(config.ref_goal, users.theta)  # the wanted grasp, held at the training cup
    ref_m, _ = grasp_error(robot, held, users.target)
    frames = []
    for kind, traj in runs.items():
        mapped = kind != "none"
        conf = confidence(traj.beliefs[-1], users.goal) if mapped else np.full(len(users.goal), np.nan)
        err_m, angle = grasp_error(robot, traj.states[-1], users.target)
        end = traj.beliefs[-1].argmax(axis=-1)
        end_goal = np.where(
            end == task.n_goals, "new", np.where(end == config.ref_goal, "reference", "other")
        )
        row = {
            **at,
            "robot": robot.name,
            "mapping": "with" if mapped else "without",
            "distance": at["distance"] / cup_scale,
            "error": err_m / cup_scale,
            "h": kind,
            "confidence": conf,
            "reference": ref_m / cup_scale,
            "angle_error_deg": angle,
            "distance_joint": at["distance_joint"] / scale,
            "error_joint": normalized_error(traj.states[-1], users.target, scale),
            "reference_joint": normalized_error(held, users.target, scale),
            "end_goal": end_goal,
        }
        frames.append(pd.DataFrame(row)[list(EPISODE_COLUMNS)])
    return frames
