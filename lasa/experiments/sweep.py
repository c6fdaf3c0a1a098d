"""What the simulated-user sweeps share: drawing episodes, rolling out mixed methods, claim rows, figures.

One batched population covers every condition; user i (the CSVs' ``seed``) is the same in each (paired)."""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from lasa.base.config import (
    ASSISTANCE,
    BUILT_IN_ASSISTANCE,
    NO_ASSISTANCE,
    ControlConfig,
    PositiveInt,
    Seed,
    UnitInterval,
    check_choice,
    check_list,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.evidence import verdicts
from lasa.evidence.claims import Claim, numbers_of
from lasa.evidence.plots import robot_rows, users_text, wrap_to
from lasa.evidence.rules import rule
from lasa.method.decoder import ActionDecoder
from lasa.method.step import METHOD_DECODER, METHODS, latent_grid, method_alpha
from lasa.people.rollout import Trajectories, rollout
from lasa.people.users import PILOTS, UserPopulation
from lasa.world.goals import GoalTask

LEVEL = verdicts.Looks().level  # the verdicts' interval level (1 - 0.05 / looks: 98.75%), of every band [-]


Decoders = Mapping[str, ActionDecoder] | ActionDecoder


def as_decoders(decoders: Decoders) -> Mapping[str, ActionDecoder]:
    """``{"base": ..., "entropy": ...}``; a single decoder is the ``base`` one."""
    return {"base": decoders} if isinstance(decoders, ActionDecoder) else decoders


def check_names(name: str, values: tuple[str, ...], choices: tuple[str, ...]) -> None:
    """A list setting of names: at least one, each one of ``choices``, none twice."""
    if not values:
        raise ConfigError(f"{name} must name at least one of {', '.join(map(repr, choices))}")
    for value in values:
        check_choice(name, value, choices)
    check_list(name, values)


def check_assistance(assistance: tuple[str, ...]) -> None:
    """Every name a built-in member (:data:`lasa.base.config.BUILT_IN_ASSISTANCE`), at least one."""
    check_names("assistance", assistance, BUILT_IN_ASSISTANCE)


def check_needed(name: str, given: tuple[Any, ...], needed: tuple[Any, ...], reader: str) -> None:
    """``given`` (a list setting) holds every value of ``needed``, which ``reader`` reads."""
    missing = [v for v in needed if v not in given]
    if missing:
        listed = ", ".join(f"{v:g}" if isinstance(v, float) else repr(v) for v in missing)
        raise ConfigError(f"{name} must include {listed} ({reader} read them), got {list(given)}")


def check_record_every(record_every: int, horizon: int, divides: bool = True) -> None:
    """``record_every`` is at most ``horizon`` and, if ``divides``, divides it."""
    if record_every > horizon:
        raise ConfigError(f"record_every must be at most horizon ({horizon}), got {record_every}")
    if divides and horizon % record_every:
        raise ConfigError(
            f"record_every must divide horizon ({horizon}) so that the last step is recorded, "
            f"got {record_every}"
        )


def swept_assistance(control: ControlConfig, assistance: tuple[str, ...]) -> tuple[str, ...]:
    """The members a sweep runs: the headline one (``control.assistance``) first, then the rest."""
    return tuple(dict.fromkeys((control.assistance, *assistance)))


def pairs(methods: tuple[str, ...], assistance: tuple[str, ...]) -> list[tuple[str, str]]:
    """(method, member) pairs of a sweep: LA once (member ``none``), each assisted method under each one."""
    out = [(m, NO_ASSISTANCE) for m in methods if m == "LA"]
    return out + [(m, a) for a in assistance for m in methods if m != "LA"]


@dataclasses.dataclass(frozen=True)
class LooksConfig:
    """How a sweep's verdicts get their users: the sequential looks, the bootstrap, the members."""

    users: PositiveInt = verdicts.Looks.first  # users per point at the first look, every member (Looks) [-]
    block: PositiveInt = verdicts.Looks.block  # users added per later look, the headline member only [-]
    cap: PositiveInt = verdicts.Looks.cap  # most users per point [-]
    n_boot: PositiveInt = verdicts.N_BOOT  # bootstrap resamples of each claim's intervals [-]
    assistance: tuple[str, ...] = ASSISTANCE  # members the assisted methods run under
    seed: Seed = 0  # seed of the users' cups, preferences and random streams [-]

    def __post_init__(self) -> None:
        validate(self)
        verdicts.check_looks(self.users, self.block, self.cap)
        check_assistance(self.assistance)


@dataclasses.dataclass(frozen=True)
class SweepConfig(LooksConfig):
    """The settings sims 1-3 share: :class:`LooksConfig`'s, the pilot and the methods their claims compare."""

    pilot: str = "boltzmann"  # the simulated user: Eq. S1, or a laggy or noisy pilot (lasa.people.users)
    pilot_prob: UnitInterval = 0.0  # p of the laggy or noisy pilot [-]
    methods: tuple[str, ...] = METHODS  # methods compared

    def __post_init__(self) -> None:
        super().__post_init__()
        check_choice("pilot", self.pilot, PILOTS)
        check_names("methods", self.methods, METHODS)
        # sims 1-3's claims and sentences compare all three (LA+SA+Entropy against LA+SA, both
        # against LA): a subset would run the whole sweep and fail in its claims
        check_needed("methods", self.methods, METHODS, "the claims of sims 1-3")


def draw_episodes(
    task: GoalTask, n_users: int, horizon: int, n_candidates: int, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each user's cup, preference theta (uniform on [0, 1]) and uniforms (n_users, horizon, n_candidates)."""
    rng = np.random.default_rng(seed)
    goal = rng.integers(0, task.n_goals, n_users)
    theta = rng.uniform(0.0, 1.0, n_users)
    noise = rng.random((n_users, horizon, n_candidates))
    return goal, theta, noise


def episodes(
    decoders: Decoders, task: GoalTask, control: ControlConfig, n_users: int, horizon: int, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`draw_episodes` sized for the decoders' joystick grid."""
    first = next(iter(as_decoders(decoders).values()))
    n_candidates = len(latent_grid(control.n_z, first.z_dim))
    return draw_episodes(task, n_users, horizon, n_candidates, seed)


def run_population(
    decoders: Decoders,
    task: GoalTask,
    control: ControlConfig,
    users: UserPopulation,
    methods: np.ndarray,
    horizon: int,
    noise: np.ndarray,
    progress: bool,
    assistance: np.ndarray,
    pilot_seed: int,
) -> Trajectories:
    """Roll out users of different methods and members (``methods``, ``assistance``: (U,), ``none`` for LA);
    ``pilot_seed`` seeds the laggy and noisy pilots' own stream (``[pilot_seed, 1]``)."""
    decoders = as_decoders(decoders)
    methods = np.asarray(methods)
    alpha = np.array([method_alpha(m, control) for m in methods])
    assistance = np.where(np.asarray(assistance) == NO_ASSISTANCE, control.assistance, assistance)
    keys = np.array([METHOD_DECODER[m] for m in methods])
    pilot_noise = None
    if users.pilot_prob > 0:
        pilot_noise = np.random.default_rng([pilot_seed, 1]).random((int(np.max(users.user)) + 1, horizon, 2))
    parts: list[tuple[np.ndarray, Trajectories]] = []
    for key in dict.fromkeys(keys.tolist()):  # plain str, first-seen order: deterministic
        if key not in decoders:
            needing = sorted({str(m) for m in methods[keys == key]})
            raise ConfigError(f"methods {needing} need the {key!r} decoder; pass decoders[{key!r}]")
        idx = np.flatnonzero(keys == key)
        group, member = users.subset(idx), assistance[idx]
        traj = rollout(
            decoders[key], task, group, alpha[idx], control, horizon, noise, progress, pilot_noise, member
        )
        parts.append((idx, traj))
    order = np.argsort(np.concatenate([idx for idx, _ in parts]))  # the users' rows back in their order
    fields = [f.name for f in dataclasses.fields(Trajectories)]
    return Trajectories(
        **{f: np.concatenate([getattr(t, f) for _, t in parts], axis=1)[:, order] for f in fields}
    )


@dataclasses.dataclass(frozen=True)
class Look:
    """One look's episodes of a sims 1-3 sweep, one per (pair, condition, user); ``user`` spans all looks."""

    method: np.ndarray
    member: np.ndarray
    condition: list[Any]
    user: np.ndarray
    users: UserPopulation
    traj: Trajectories


def run_look(
    decoders: Decoders,
    task: GoalTask,
    control: ControlConfig,
    config: Any,
    conditions: Sequence[Any],
    population: Callable[[list[Any], np.ndarray, np.ndarray], dict[str, Any]],
    progress: bool = False,
    look: int = 0,
    assistance: tuple[str, ...] | None = None,
) -> Look:
    """Roll out one look's new users (:func:`lasa.evidence.verdicts.block_users`) of a sims 1-3 sweep.

    ``population`` maps the conditions, goals and preferences to the users' other fields (``beta0``, ...);
    ``assistance``: default every member of ``config.assistance``, the headline one first."""
    start, n_users = verdicts.block_users(verdicts.Looks(config.users, config.block, config.cap), look)
    seed = verdicts.block_seed(config.seed, look)
    goal, theta, noise = episodes(decoders, task, control, n_users, config.horizon, seed)
    assistance = swept_assistance(control, config.assistance) if assistance is None else assistance
    grid = list(itertools.product(pairs(config.methods, assistance), conditions, range(n_users)))
    method, member = np.array([m for (m, _), _, _ in grid]), np.array([a for (_, a), _, _ in grid])
    condition, user = [c for _, c, _ in grid], np.array([u for _, _, u in grid])
    goal, theta = goal[user], theta[user]
    users = UserPopulation(
        goal=goal,
        theta=theta,
        target=task.target(goal, theta),
        user=user,
        pilot=config.pilot,
        pilot_prob=config.pilot_prob,
        **population(condition, goal, theta),
    )
    traj = run_population(
        decoders, task, control, users, method, config.horizon, noise, progress, member, seed
    )
    return Look(method, member, condition, start + user, users, traj)


def judge(
    module: Any,
    decoders: Decoders,
    task: GoalTask,
    control: ControlConfig,
    config: Any,
    progress: bool = False,
    reduce: Any = None,
) -> tuple[Any, verdicts.Sequential, Any]:
    """Run a figure's sweep (``module.run``) in looks until its headline verdicts are settled (or the cap).

    ``reduce`` maps a look's rows to the claims' rows (sim3: one per episode). Returns every look's rows,
    the :class:`lasa.evidence.verdicts.Sequential` outcome and the first look's trajectories or runs."""
    full: list[Any] = []
    first: list[Any] = []

    def block(look: int, assistance: tuple[str, ...]) -> Any:
        frame, extra = module.run(decoders, task, control, config, progress, look=look, assistance=assistance)
        full.append(frame)
        if look == 0:
            first.append(extra)
        return frame if reduce is None else reduce(frame)

    looks = verdicts.Looks(config.users, config.block, config.cap)
    assistance = swept_assistance(control, config.assistance)
    fast = getattr(module, "boot_values", None)
    outcome = verdicts.sequential(
        block, module.claims, assistance, control.assistance, looks, config.n_boot, fast=fast
    )
    return pd.concat(full, ignore_index=True), outcome, first[0]


def sim_figure(
    table: pd.DataFrame,
    assistance: str,
    title: str,
    panels: tuple[int, tuple[float, float], Callable[[str, pd.DataFrame, np.ndarray], None]],
    keys: list[str],
    per: str = "point",
) -> Figure:
    """A sims 1-3 figure under one member: one row of panels per robot, ``panels`` = (panels per row, a
    row's size, what draws a robot's row from (name, rows, axes))."""
    table = verdicts.member_frame(table, assistance)
    n_cols, size, draw = panels
    fig, rows = robot_rows(table, n_cols, size)
    for name, part, row in rows:
        draw(name, part, row)
    n = users_text(table, keys, per=per)
    fig.suptitle(wrap_to(f"{title}, {n}, assistance: {assistance}", fig.get_figwidth()))
    fig.tight_layout()
    return fig


def headline_claim(claims: list[Claim], claim_id: str, head: pd.DataFrame) -> Claim:
    """The ``claim_id`` row of ``head``'s robot and member (the member of its assisted rows)."""
    robot = str(head.robot.iloc[0])
    member = str(head[head.method != "LA"].assistance.iloc[0])
    rows = [c for c in claims if c.id == claim_id and c.robot == robot and c.assistance == member]
    if len(rows) != 1:
        raise ConfigError(f"expected one {claim_id} row for {robot} under {member!r}, got {len(rows)}")
    return rows[0]


def sim_claim(
    claim_id: str, robot: str, values: dict[str, Any], claim: str, paper: str, measured: str, note: str = ""
) -> Claim:
    """A sim's claim row on ``robot``: its figure from its id, its verdict by its rule on ``values``."""
    return Claim(
        id=claim_id,
        claim=claim,
        figure=claim_id.split(".")[0],
        paper=paper,
        values=values,
        measured=measured,
        reproduced=rule(claim_id).verdict(values),
        note=note,
        robot=robot,
    )


def number(claim: Claim, name: str) -> tuple[float, float, float]:
    """(value, low, high) of the number ``name`` of a claim row (:func:`~lasa.evidence.claims.numbers_of`)."""
    found = numbers_of(claim).get(name)
    if found is None:
        raise ConfigError(f"{claim.id} has no number {name!r}; it has {sorted(claim.values)}")
    return found.value, found.low, found.high


def interval_text(value: float, low: float, high: float, fmt: str = "{:.3f}") -> str:
    """``value [low, high]`` in ``fmt``, with a typographic minus."""
    return f"{fmt.format(value)} [{fmt.format(low)}, {fmt.format(high)}]".replace("-", "−")
