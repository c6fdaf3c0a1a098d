"""The verdict map: every sim1-sim3 claim under each member and setting (notebook 08).

The sims re-run in every cell of a grid over the member, alpha, sigma_h and the pilot (:func:`cells`),
each claim judged as the claims table does; design and reuse: ``docs/method-notes.md``.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping
from typing import Annotated, Any

import annotated_types as at
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from lasa.base.config import (
    ASSISTANCE,
    ControlConfig,
    NonNegativeInt,
    Number,
    Positive,
    PositiveInt,
    Rationality,
    Seed,
    UnitInterval,
    check_choice,
    check_list,
    check_range,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.evidence.claims import criteria
from lasa.evidence.decision import UNDECIDED, WORDS
from lasa.evidence.plots import robots_present
from lasa.evidence.verdicts import MIN_USERS, N_BOOT, USER, Looks, assess, member_frame
from lasa.experiments import sim1, sim2, sim3
from lasa.experiments.sweep import as_decoders, check_assistance, check_names, check_needed
from lasa.method.decoder import ActionDecoder
from lasa.people.users import PILOTS
from lasa.pipeline.scaleout import run_jobs
from lasa.world.goals import GoalTask

NAME = "claims_robustness"
# the contract's columns first: ``seed`` is the seed of the cell's users and ``measured`` the
# number the claim's verdict rests on (``lasa.evidence.claims.Claim.value``), with its interval at
# ``level`` (:data:`LEVEL`); ``effect`` is the word the map colours
COLUMNS = tuple(
    "id robot assistance alpha action_scale seed measured reproduced settled ci_low ci_high pilot setting "
    "users effect number level".split()
)
DPI = 130
DESIGNS = ("one_at_a_time", "factorial")
SIMS = (("sim1", sim1), ("sim2", sim2), ("sim3", sim3))  # the sims each cell runs
# every cell's interval level: the claims table's, each look's 1 - ALPHA / K of the sequential
# design (lasa.evidence.verdicts.Looks), so a cell and its claims-table row read alike [-]
LEVEL = Looks().level
# each effect word's colour (lasa.evidence.decision.WORDS, in order); an undecided cell is also hatched
COLOURS = dict(zip(WORDS, ("#1b9e77", "#e6ab02", "#d95f02", "#d9d9d9", "#ffffff"), strict=True))


@dataclasses.dataclass(frozen=True)
class Config:
    """The robustness grid of notebook 08, and the sweep run in each of its cells."""

    assistance: tuple[str, ...] = ASSISTANCE  # members of the shared-autonomy family
    alphas: tuple[Annotated[Number, at.Gt(0.0), at.Le(1.0)], ...] = (0.1, 0.2, 0.5)  # Eq. M1's weights [-]
    action_scales: tuple[Positive, ...] = (0.25, 0.375, 0.5)  # sigma_h, the human's speed bound [rad/s]
    pilots: tuple[str, ...] = PILOTS  # simulated users (lasa.people.users.PILOTS)
    lag_prob: UnitInterval = 0.85  # laggy pilot: probability of repeating the last input [-]
    noise_prob: UnitInterval = 0.3  # noisy pilot: probability of a uniformly random input [-]
    design: str = "one_at_a_time"  # "one_at_a_time" around the defaults, or "factorial"
    betas: tuple[Rationality, ...] = (1.0, 10.0, 75.0, 1000.0)  # sim1 rationalities [1/rad^2]
    change_steps: tuple[NonNegativeInt, ...] = (0, 120)  # sim2 change steps N (its claims read the ends)
    horizon: PositiveInt = 200  # control steps of the sim1 and sim3 episodes: notebook 04's and 06's [-]
    settle: PositiveInt = 150  # sim2: steps after the largest N: notebook 05's [-]
    users: PositiveInt = MIN_USERS  # users per point in every cell: the first look of notebooks 04-06 [-]
    n_boot: PositiveInt = N_BOOT  # bootstrap resamples of each cell's intervals: the claims table's [-]
    seed: Seed = 0  # seed of the users (the same users in every cell: paired) [-]
    n_jobs: PositiveInt = 1  # local worker processes for the cells [-]
    scheduler: str | None = None  # Dask scheduler address; None: $LASA_SCHEDULER, else local

    def __post_init__(self) -> None:
        validate(self)
        for name in ("alphas", "action_scales", "betas"):  # grids: distinct, ascending
            values = check_list(name, getattr(self, name), ascending=True)
            object.__setattr__(self, name, tuple(float(v) for v in values))
        check_needed("betas", self.betas, sim1.CLAIM_BETAS, "the sim1 claims")
        check_assistance(self.assistance)
        check_names("pilots", self.pilots, PILOTS)
        check_choice("design", self.design, DESIGNS)
        why = "the sim2 claims compare the smallest N with the largest"
        check_list("change_steps", self.change_steps, at_least=2, ascending=True, why=why)
        if self.horizon % (every := sim3.Config.record_every):  # sim3 records every this many steps
            raise ConfigError(
                f"horizon must be a multiple of sim3's record_every ({every}), got {self.horizon}"
            )


@dataclasses.dataclass(frozen=True)
class Cell:
    """One setting of the grid; every member of the family runs in it, in shared batches."""

    alpha: float  # blend weight [-]
    action_scale: float  # sigma_h [rad/s]
    pilot: str  # the simulated user
    setting: str  # what this cell varies from the default: "default", "alpha", "action_scale", "pilot", "all"
    assistance: tuple[str, ...] = ()  # members judged (the default cell: all; others: the headline one)


class ScaledDecoder:
    """A decoder whose actions are scaled by ``factor``: the same directions at another speed."""

    def __init__(self, model: ActionDecoder, factor: float) -> None:
        self.model = model
        self.factor = check_range("factor", factor, 0.0, low_open=True)
        self.robot, self.n_goals, self.z_dim = model.robot, model.n_goals, model.z_dim

    def decode_numpy(self, z: np.ndarray, state: np.ndarray, belief: np.ndarray) -> np.ndarray:
        """factor * phi(z, s, b)."""
        out = self.model.decode_numpy(z, state, belief)
        return out if self.factor == 1.0 else self.factor * out


def cells(config: Config, control: ControlConfig) -> list[Cell]:
    """The grid's settings, in a fixed order: the default, then each alpha, sigma_h, pilot; ConfigError
    if the defaults (``control``'s alpha and sigma_h, Boltzmann users) are off a one-at-a-time grid's axes."""
    alpha0, scale0, pilot0 = float(control.alpha), float(control.action_scale), "boltzmann"
    head = (control.assistance,)
    if control.assistance not in config.assistance:
        raise ConfigError(f"the headline member {control.assistance!r} must be among {config.assistance}")
    if config.design == "factorial":
        return [
            Cell(a, s, p, "all", tuple(config.assistance))
            for a, s, p in itertools.product(config.alphas, config.action_scales, config.pilots)
        ]
    if alpha0 not in config.alphas or scale0 not in config.action_scales or pilot0 not in config.pilots:
        raise ConfigError(
            f"a one-at-a-time grid needs the defaults on its axes: alpha {alpha0}, "
            f"action_scale {scale0}, pilot {pilot0!r}"
        )
    out = [Cell(alpha0, scale0, pilot0, "default", tuple(config.assistance))]
    out += [Cell(a, scale0, pilot0, "alpha", head) for a in config.alphas if a != alpha0]
    out += [Cell(alpha0, s, pilot0, "action_scale", head) for s in config.action_scales if s != scale0]
    out += [Cell(alpha0, scale0, p, "pilot", head) for p in config.pilots if p != pilot0]
    return out


@dataclasses.dataclass(frozen=True)
class Grid:
    """What every cell of a grid shares, sent to each worker once (:func:`lasa.pipeline.scaleout.run_jobs`)"""

    decoders: Mapping[str, ActionDecoder]  # notebook 03's pair
    task: GoalTask
    control: ControlConfig  # the defaults the grid is centred on
    config: Config


def _sim_configs(config: Config, pilot: dict[str, Any]) -> list[tuple[Any, Any, Any]]:
    """(module, config, reduce) of sims 1-3 at the map's sizes: one look of ``users`` users."""
    common: dict[str, Any] = {"users": config.users, "cap": config.users, "seed": config.seed}
    return [
        (sim1, sim1.Config(betas=config.betas, horizon=config.horizon, **common, **pilot), None),
        (sim2, sim2.Config(change_steps=config.change_steps, settle=config.settle, **common, **pilot), None),
        (sim3, sim3.Config(horizon=config.horizon, **common, **pilot), sim3.episode_means),
    ]


def _judge(module: Any, frame: pd.DataFrame, cell: Cell, robot: str, config: Config) -> pd.DataFrame:
    """Every member's claims of one sim in one cell, each with its intervals at :data:`LEVEL`."""
    parts = []
    for assistance in cell.assistance:
        frame_m = member_frame(frame, assistance)
        fast = getattr(module, "boot_values", None)
        claims = assess(module.claims, frame_m, config.n_boot, config.seed, level=LEVEL, fast=fast)
        rows = [
            (c.id, robot, assistance, cell.alpha, cell.action_scale, config.seed, c.value, w["reproduced"])
            + (c.settled, c.ci_low, c.ci_high, cell.pilot, cell.setting, c.n_users)
            + (w["effect"], w["number"], LEVEL)  # the claims table's one word, and its two
            for c, w in zip(claims, [criteria(c) for c in claims], strict=True)
        ]
        parts.append(pd.DataFrame(rows, columns=list(COLUMNS)))
    return pd.concat(parts, ignore_index=True)


def run_cell(grid: Grid, cell: Cell) -> pd.DataFrame:
    """Run sims 1-3 in one cell under its members, in the same batches, and judge each claim."""
    config, control = grid.config, grid.control
    ctrl = dataclasses.replace(control, alpha=cell.alpha, action_scale=cell.action_scale)
    factor = cell.action_scale / control.action_scale
    decoders = {k: ScaledDecoder(d, factor) for k, d in grid.decoders.items()}
    prob = {"boltzmann": 0.0, "laggy": config.lag_prob, "noisy": config.noise_prob}[cell.pilot]
    pilot: dict[str, Any] = {"pilot": cell.pilot, "pilot_prob": prob}
    parts = []
    robot = grid.task.robot.name
    for module, sim_config, reduce in _sim_configs(config, pilot):
        frame = module.run(decoders, grid.task, ctrl, sim_config, assistance=cell.assistance)[0]
        frame = frame if reduce is None else reduce(frame)
        parts.append(_judge(module, frame, cell, robot, config))
    return pd.concat(parts, ignore_index=True)


def default_frames(
    config: Config, sim1_rows: pd.DataFrame, sim2_rows: pd.DataFrame, sim3_rows: pd.DataFrame
) -> dict[str, pd.DataFrame]:
    """The default cell's rows from notebooks 04-06: their first look, at the map's sizes; ConfigError
    if a frame lacks a beta or change step of the map, or holds fewer users."""
    out = {}
    for name, rows, column, values in (
        ("sim1", sim1_rows, "beta", config.betas),
        ("sim2", sim2_rows, "change_step", config.change_steps),
        ("sim3", sim3_rows, None, ()),
    ):
        part = rows[rows[USER] < config.users]
        if part[USER].nunique() < config.users:
            raise ConfigError(
                f"{name}'s rows hold {part[USER].nunique()} users; the map's cells need {config.users} "
                f"(set the sims' `users` to at least the map's)"
            )
        if column is not None:
            if missing := sorted(set(values) - set(part[column])):
                raise ConfigError(f"{name}'s rows lack {column} {missing}, which the map judges")
            part = part[part[column].isin(values)]
        out[name] = sim3.episode_means(part) if name == "sim3" else part
    return out


def run(
    decoders: Mapping[str, ActionDecoder] | ActionDecoder,
    task: GoalTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = False,
    defaults: Mapping[str, pd.DataFrame] | None = None,
) -> pd.DataFrame:
    """Every cell of the grid (:func:`cells`) around ``control``, locally or on a Dask cluster, with
    notebook 03's pair: one row per (claim, cell, member), cells in order; ``defaults``
    (:func:`default_frames`) are judged as the default cell instead of running it again."""
    grid = Grid(as_decoders(decoders), task, control, config)
    todo = cells(config, control)
    done: list[pd.DataFrame] = []
    if defaults is not None and todo and todo[0].setting == "default":
        parts = [_judge(m, defaults[key], todo[0], task.robot.name, config) for key, m in SIMS]
        done = [pd.concat(parts, ignore_index=True)]
        todo = todo[1:]
    frames = run_jobs(run_cell, todo, config.scheduler, config.n_jobs, progress, "grid cells", shared=grid)
    return pd.concat([*done, *frames], ignore_index=True)


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per (robot, claim) of :func:`run`'s rows: cells with each effect word (over the members' and the
    settings' cells), ``default`` (the headline member's effect in the default cell, empty if the grid
    has none), ``stable`` (every settled cell gives it) and ``moves`` (the settled cells that differ)."""
    rows = []
    for (robot, claim), part in table.groupby(["robot", "id"], sort=True):
        part = part.assign(column=part.apply(_label, axis=1))
        counts = part.effect.value_counts()
        default = part.loc[part.column == "default", "effect"]
        head = str(default.iloc[0]) if len(default) else ""
        settled = part[part.settled.astype(bool) & (part.column != "default")]
        moves = settled.loc[settled.effect != head, ["column", "effect"]]
        stable = bool(head) and head != UNDECIDED and moves.empty
        said = ", ".join(f"{c} {v}" for c, v in moves.itertuples(index=False))
        rows.append((robot, claim, *(int(counts.get(v, 0)) for v in WORDS), head, stable, said))
    return pd.DataFrame(rows, columns=["robot", "id", *WORDS, "default", "stable", "moves"])


def describe(table: pd.DataFrame) -> list[str]:
    """One sentence per claim from :func:`summary`: does its verdict depend on a convention?"""
    lines = []
    for row in table.itertuples(index=False):
        undecided = int(row.undecided)
        tail = f" ({undecided} undecided cell{'s' if undecided != 1 else ''})" if undecided else ""
        if row.default == UNDECIDED:
            elsewhere = f"; settled elsewhere: {row.moves}" if row.moves else ""
            said = "undecided in the default cell" + elsewhere
        elif row.stable:
            said = f"'{row.default}' in every settled cell"
        else:
            said = f"'{row.default}' by default; settled otherwise in {row.moves}"
        lines.append(f"{row.robot} {row.id}: {said}{tail}.")
    return lines


def _label(row: Any) -> str:
    return {
        "default": "default" if row.assistance == "point" else f"{row.assistance}",
        "alpha": f"alpha={row.alpha:g}",
        "action_scale": f"sigma_h={row.action_scale:g}",
        "pilot": f"{row.pilot} pilot",
    }.get(row.setting, f"a={row.alpha:g} s={row.action_scale:g} {row.pilot}")


def plot(table: pd.DataFrame, headline: str = "point") -> Figure:
    """The verdict map: claims (rows) x members and settings (columns), one panel per robot; ConfigError
    if the table has no single interval level (no ``level`` column: a table from before it was written),
    or a word outside ``WORDS``."""
    if "level" not in table.columns:
        raise ConfigError("the verdict map's table has no `level` column: run notebook 08 again")
    levels = sorted(set(table.level.astype(float)))
    if len(levels) != 1:
        raise ConfigError(f"the verdict map's cells must share one interval level, got {levels}")
    if unknown := sorted(set(table.effect) - set(WORDS)):
        raise ConfigError(f"effect words must be among {WORDS}, got {unknown}")
    default = (table.assistance == headline) & (table.setting == "default")
    table = table.assign(column=table.apply(_label, axis=1).where(~default, "default"))
    robots = robots_present(table)
    order_cols = list(dict.fromkeys(table.column))
    ids = sorted(dict.fromkeys(table.id))
    cmap = ListedColormap([COLOURS[v] for v in WORDS])
    code = {v: i for i, v in enumerate(WORDS)}
    size = (2.6 + 0.5 * len(order_cols) * len(robots), 1.4 + 0.36 * len(ids))
    fig, axes = plt.subplots(1, len(robots), figsize=size, squeeze=False, sharey=True)
    for ax, robot in zip(axes[0], robots, strict=True):
        grid = np.full((len(ids), len(order_cols)), np.nan)
        for row in table[table.robot == robot].itertuples(index=False):
            r, c = ids.index(row.id), order_cols.index(row.column)
            grid[r, c] = code[row.effect]
            undecided = row.effect == UNDECIDED
            if undecided:  # hatched, its number with a "?"
                xy = (c - 0.5, r - 0.5)
                ax.add_patch(plt.Rectangle(xy, 1, 1, fill=False, hatch="///", lw=0, color="0.5"))
            number = f"{float(row.measured):.2g}" + ("?" if undecided else "")
            ax.text(c, r, number, ha="center", va="center", fontsize=6)
        ax.imshow(np.ma.masked_invalid(grid), cmap=cmap, vmin=-0.5, vmax=len(WORDS) - 0.5, aspect="auto")
        ax.set_title(robot, fontsize=9)
        ax.set_xticks(range(len(order_cols)), order_cols, rotation=60, ha="right", fontsize=7)
        ax.set_yticks(range(len(ids)), ids, fontsize=7)
    handles = [plt.Rectangle((0, 0), 1, 1, facecolor=COLOURS[v], edgecolor="0.6", lw=0.5) for v in WORDS]
    n = int(table.users.min()) if len(table) else 0
    source = ", the claims table's level" if math.isclose(levels[0], LEVEL) else ""
    fig.suptitle(
        f"Claims robustness: the effect per reading and setting, at least {n} users per point\n"
        f"({100 * levels[0]:.4g}% intervals{source}; grey and hatched: undecided; "
        "text: the number the verdict rests on)",
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.legend(handles, WORDS, loc="lower center", ncol=len(WORDS), frameon=False, fontsize=8)
    return fig
