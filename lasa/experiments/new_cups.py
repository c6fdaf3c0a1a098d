"""Fig. sim4's episodes (:mod:`lasa.experiments.sim4`): new cups, and users who reach for them."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from lasa.base.config import ControlConfig
from lasa.base.errors import ConfigError
from lasa.evidence.verdicts import NO_ASSISTANCE, Design, block_seed, block_users
from lasa.experiments.sweep import Decoders, as_decoders, episodes, swept_assistance
from lasa.method.decoder import ActionDecoder
from lasa.method.newgoals import ContextMap, MappedDecoder, context_map, extend_task
from lasa.method.step import METHOD_DECODER, method_alpha
from lasa.people.rollout import Trajectories, rollout
from lasa.people.users import UserPopulation
from lasa.world.task import CupTask

if TYPE_CHECKING:
    from lasa.experiments.sim4 import Config

__all__ = ["NewGoalRun", "new_cup_positions", "map_geometry", "Sweep", "CupEpisodes", "episodes_at"]


@dataclasses.dataclass(frozen=True)
class NewGoalRun:
    """The episodes at one new cup.

    Attributes:
        offset: Distance of the new cup from the reference cup on the table [m].
        task: The task grown by the new cup (its robot's scene shows it).
        with_map: Trajectories with each kind of context map (belief over G + 1 goals).
        without_map: Trajectories of the unchanged method (training goals only).
    """

    offset: float
    task: CupTask
    with_map: dict[str, Trajectories]
    without_map: Trajectories


def new_cup_positions(task: CupTask, config: Config) -> np.ndarray:
    """Grasp centres of the new cups, shape (len(offsets), 3) [m]."""
    cups = task.robot.goal_positions()
    ref = cups[config.ref_goal]
    if config.direction is None:
        other = cups[(config.ref_goal + 1) % task.n_goals]
        direction = (ref - other)[:2]
    else:
        direction = np.asarray(config.direction, dtype=float)
    direction = np.r_[direction / np.linalg.norm(direction), 0.0]
    return ref + np.asarray(config.offsets)[:, None] * direction


def map_geometry(task: CupTask, config: Config) -> pd.DataFrame:
    """Where each kind of context map sends the new cups' grasps, and how their IK compares.

    Returns:
        One row per (``offset_m``, ``h``), with ``distance`` (on the table, over the farthest).
    """
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
            pos_m, rot_m = robot.grasp_frames(np.stack([mapped, old]))
            cosine = np.clip(np.einsum("ki,ki->k", rot_m[0][:, :, 2], rot_m[1][:, :, 2]), -1.0, 1.0)
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
                    "misfit_m": float(np.linalg.norm(pos_m[0] - pos_m[1], axis=1).max()),
                    "misfit_deg": float(np.degrees(np.arccos(cosine)).max()),
                    "margin_rad": float(np.minimum(mapped - robot.lower, robot.upper - mapped).min()),
                    "stretch": 1.0 + shift,
                }
            )
    return pd.DataFrame(rows).set_index(["offset_m", "h"])


@dataclasses.dataclass(frozen=True)
class Sweep:
    """What the episodes at every new cup share: the method, one look's users, the new cups.

    Attributes:
        decoder: The method's decoder; task: the training task; control, config, progress and
            look: as :func:`lasa.experiments.sim4.run` has them.
        alpha: The method's blend weight; noise: the users' noise, as
            :func:`lasa.experiments.sweep.episodes` draws it.
        assistance: The members the method's assistance runs under (``none`` alone without it).
        n_users: Users per member; first: the look's first user.
        users: Each row's user (0 ... n_users - 1), (members x users,); theta: its preference;
            assistance_rows: its member; assisted: ``assistance_rows``, or None when the method has
            no assistance.
        grown: The task grown by each new cup; distances: each new cup's distance from the
            reference goal (joint space, between mid-preference goals) [rad]; scale: the
            largest of them; cup_distances: each new cup's distance from the reference cup on
            the table [m]; cup_scale: D, the largest of them (the farthest new cup's).
    """

    decoder: ActionDecoder
    task: CupTask
    control: ControlConfig
    config: Config
    progress: bool
    look: int
    alpha: float
    noise: np.ndarray
    assistance: tuple[str, ...]
    n_users: int
    first: int
    users: np.ndarray
    theta: np.ndarray
    assistance_rows: np.ndarray
    assisted: np.ndarray | None
    grown: list[CupTask]
    distances: np.ndarray
    scale: float
    cup_distances: np.ndarray
    cup_scale: float

    @classmethod
    def of(
        cls,
        decoders: Decoders,
        task: CupTask,
        control: ControlConfig,
        config: Config,
        progress: bool = False,
        look: int = 0,
        assistance: tuple[str, ...] | None = None,
    ) -> Sweep:
        """The sweep of :func:`lasa.experiments.sim4.run` (its arguments).

        Raises:
            ConfigError: if ``config.ref_goal`` is not a goal of ``task``, or the method's
                decoder is not among ``decoders``.
        """
        decoder = _method_decoder(decoders, task, config)
        first, n_users = block_users(Design(config.users, config.block, config.cap), look)
        _, theta, noise = episodes(
            decoder, task, control, n_users, config.horizon, block_seed(config.seed, look)
        )
        alpha = method_alpha(config.method, control)
        if assistance is None:
            assistance = swept_assistance(control, config.assistance)
        assistance = assistance if alpha > 0 else (NO_ASSISTANCE,)
        cups = new_cup_positions(task, config)
        grown = [extend_task(task, p, config.ref_goal) for p in cups]
        dist = np.array([np.linalg.norm(t.goals[-1] - task.goals[config.ref_goal]) for t in grown])
        on_table = np.linalg.norm(cups - task.robot.goal_positions()[config.ref_goal], axis=1)
        assistance_rows = np.repeat(assistance, n_users)
        return cls(
            decoder,
            task,
            control,
            config,
            progress,
            look,
            alpha,
            noise,
            assistance,
            n_users,
            first,
            users=np.tile(np.arange(n_users), len(assistance)),
            theta=np.tile(theta, len(assistance)),
            assistance_rows=assistance_rows,
            assisted=None if assistance == (NO_ASSISTANCE,) else assistance_rows,
            grown=grown,
            distances=dist,
            scale=float(dist.max()),
            cup_distances=on_table,
            cup_scale=float(on_table.max()),
        )


def _method_decoder(decoders: Decoders, task: CupTask, config: Config) -> ActionDecoder:
    """The decoder of ``config.method`` among ``decoders``, after checking ``config.ref_goal``."""
    if not 0 <= config.ref_goal < task.n_goals:
        raise ConfigError(f"ref_goal must be in [0, {task.n_goals}), got {config.ref_goal}")
    key = METHOD_DECODER[config.method]
    decoder = as_decoders(decoders).get(key)
    if decoder is None:
        raise ConfigError(f"method {config.method!r} needs the {key!r} decoder; pass decoders[{key!r}]")
    return decoder


@dataclasses.dataclass(frozen=True)
class CupEpisodes:
    """Every user's episodes at one new cup.

    Attributes:
        users: The users, who want a grasp at the new cup (goal G, the grown task's last).
        with_map: Their trajectories with each kind of context map.
        without: Their trajectories of the unchanged method.
    """

    users: UserPopulation
    with_map: dict[str, Trajectories]
    without: Trajectories


def episodes_at(sweep: Sweep, offset: float, big: CupTask) -> tuple[NewGoalRun, CupEpisodes]:
    """The episodes at the new cup ``offset`` [m] from the reference cup (``big``'s last goal).

    Returns:
        The headline member's run (its users alone), and every user's episodes.
    """
    config, task, n = sweep.config, sweep.task, len(sweep.users)
    new = big.n_goals - 1
    users = UserPopulation(
        goal=np.full(n, new),
        theta=sweep.theta,
        target=big.target(np.full(n, new), sweep.theta),
        beta0=np.full(n, config.beta),
        slope=np.zeros(n),
        stream=sweep.users,
    )
    with_map = {}
    for kind in config.maps:
        mapped = MappedDecoder(sweep.decoder, context_map(big, task.n_goals, config.ref_goal, kind))
        with_map[kind] = _rollout(sweep, mapped, big, users)
    plain = dataclasses.replace(users, goal=np.full(n, config.ref_goal))
    without = _rollout(sweep, sweep.decoder, task, plain)
    head = slice(0, sweep.n_users)
    at_cup = NewGoalRun(
        offset, big, {k: _users_of(t, head) for k, t in with_map.items()}, _users_of(without, head)
    )
    return at_cup, CupEpisodes(users, with_map, without)


def _rollout(sweep: Sweep, decoder: ActionDecoder, task: CupTask, users: UserPopulation) -> Trajectories:
    """The method's rollout of ``users`` on ``task`` through ``decoder``, every member in one batch."""
    return rollout(
        decoder,
        task,
        users,
        sweep.alpha,
        sweep.control,
        sweep.config.horizon,
        sweep.noise,
        sweep.progress,
        assistance=sweep.assisted,
    )


def _users_of(traj: Trajectories, users: slice) -> Trajectories:
    """The trajectories of some users (axis 1 of every field)."""
    return Trajectories(**{f.name: getattr(traj, f.name)[:, users] for f in dataclasses.fields(traj)})
