"""The verdict map: every sim1-sim3 claim under each reading and setting (notebook ``08_claims_robustness``).

A verdict of the claims table rests on conventions the paper leaves open: which member
of the shared-autonomy family acts (:mod:`lasa.assistance`), the blend weight alpha
(Eq. M1), the action scale sigma_h (the bound on ||phi||, Eq. T4), and the simulated
user (Eq. S1's Boltzmann user, or the laggy and noisy pilots of the shared-autonomy
literature, :data:`lasa.users.PILOTS`). This module re-runs the sims of Figs. sim1-sim3
in every cell of a grid over those settings and evaluates each claim in each cell, on
each independent draw of users and on all draws pooled.

The grid is one factor at a time around the default setting: every alpha (at the
default sigma_h, Boltzmann users), every sigma_h (default alpha), every pilot (default
alpha and sigma_h); every member of the family runs in every cell, the members' users
sharing one batch (and LA, which no member touches, running once). A full factorial
grows as the product of the axes; ``configs/large.yaml`` asks for one (``design:
factorial``) for a cluster.

Changing sigma_h at run time scales the learned decoder's output (:class:`ScaledDecoder`):
the same learned directions at another speed, as a joystick's gain would, and the
assistance and belief use the new sigma_h too (``ControlConfig.action_scale``). The
decoder is not retrained.

Cells are independent and seeded; they run through :func:`lasa.scaleout.run_jobs`,
locally or on a Dask cluster, with identical results.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Mapping
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from lasa.claims import VERDICTS, Claim
from lasa.config import ASSISTANCE, ControlConfig, check_choice, check_range
from lasa.decoder import ActionDecoder
from lasa.errors import ConfigError
from lasa.plots import robots_present
from lasa.scaleout import run_jobs
from lasa.sims import sim1, sim2, sim3
from lasa.sims.common import as_decoders, check_members, check_positive_int
from lasa.task import CupTask
from lasa.users import PILOTS
from lasa.verdicts import member_frame

__all__ = [
    "NAME",
    "COLUMNS",
    "DESIGNS",
    "Config",
    "Cell",
    "Grid",
    "ScaledDecoder",
    "cells",
    "run_cell",
    "run",
    "verdict_table",
    "summary",
    "describe",
    "plot",
]

NAME = "claims_robustness"
# the contract's columns first: ``seed`` is the draw of users (-1: all draws pooled) and
# ``measured`` the number the claim's verdict rests on (``lasa.claims.Claim.value``)
COLUMNS = (
    "id",
    "robot",
    "assistance",
    "alpha",
    "action_scale",
    "seed",
    "measured",
    "reproduced",
    "pilot",
    "setting",
    "users",
)
DPI = 130
DESIGNS = ("one_at_a_time", "factorial")
POOLED = -1  # ``seed`` of the rows measured on every draw together


@dataclasses.dataclass(frozen=True)
class Config:
    """The robustness grid of notebook 08, and the sweep run in each of its cells."""

    assistance: tuple[str, ...] = ASSISTANCE  # members of the shared-autonomy family
    alphas: tuple[float, ...] = (0.1, 0.2, 0.5)  # blend weights of Eq. M1 [-]
    action_scales: tuple[float, ...] = (0.25, 0.375, 0.5)  # sigma_h, the human's speed bound [rad/s]
    pilots: tuple[str, ...] = PILOTS  # simulated users (lasa.users.PILOTS)
    lag_prob: float = 0.85  # laggy pilot: probability of repeating the last input [-]
    noise_prob: float = 0.3  # noisy pilot: probability of a uniformly random input [-]
    design: str = "one_at_a_time"  # "one_at_a_time" around the defaults, or "factorial"
    betas: tuple[float, ...] = (1.0, 10.0, 75.0, 1000.0)  # sim1 rationalities [1/rad^2]
    change_steps: tuple[int, ...] = (0, 120)  # sim2 change steps N (its claims read the ends) [steps]
    horizon: int = 200  # control steps of the sim1 and sim3 episodes [-]
    settle: int = 150  # sim2: steps after the largest N [-]
    n_seeds: int = 2  # users per point in each draw (x n_draws = 10 per point) [-]
    n_draws: int = 5  # independent draws of users per cell [-]
    seed: int = 0  # seed of the users (the same users in every cell: paired) [-]
    n_jobs: int = 1  # local worker processes for the cells [-]
    scheduler: str | None = None  # Dask scheduler address; None: $LASA_SCHEDULER, else local

    def __post_init__(self) -> None:
        for name in ("alphas", "action_scales", "betas"):
            values = tuple(float(v) for v in getattr(self, name))
            if not values:
                raise ConfigError(f"{name} must not be empty")
            object.__setattr__(self, name, values)
        for a in self.alphas:
            check_range("alpha", a, 0.0, 1.0, low_open=True)
        for s in self.action_scales:
            check_range("action_scale", s, 0.0, low_open=True)
        if not {75.0, 1000.0} <= set(self.betas):
            raise ConfigError("betas must hold 75 and 1000 (the sim1 claims read them)")
        check_members(self.assistance)
        if not self.pilots:
            raise ConfigError("pilots must not be empty")
        for p in self.pilots:
            check_choice("pilot", p, PILOTS)
        check_range("lag_prob", self.lag_prob, 0.0, 1.0)
        check_range("noise_prob", self.noise_prob, 0.0, 1.0)
        check_choice("design", self.design, DESIGNS)
        if len(self.change_steps) < 2:
            raise ConfigError("change_steps needs at least two N (the sim2 claims compare the ends)")
        check_positive_int("horizon", self.horizon)
        check_positive_int("settle", self.settle)
        check_positive_int("n_seeds", self.n_seeds)
        check_positive_int("n_draws", self.n_draws)
        check_positive_int("n_jobs", self.n_jobs)


@dataclasses.dataclass(frozen=True)
class Cell:
    """One setting of the grid; every member of the family runs in it, in shared batches."""

    alpha: float  # blend weight [-]
    action_scale: float  # sigma_h [rad/s]
    pilot: str  # the simulated user
    setting: str  # what this cell varies from the default: "default", "alpha", "action_scale", "pilot", "all"


class ScaledDecoder:
    """A decoder whose actions are scaled by ``factor``: the same directions at another speed.

    ``ScaledDecoder(model, new_sigma_h / trained_sigma_h)`` runs a decoder trained with
    one action scale at another, keeping the bound ||phi|| <= sigma_h of Eq. T4.
    """

    def __init__(self, model: ActionDecoder, factor: float) -> None:
        self.model = model
        self.factor = check_range("factor", factor, 0.0, low_open=True)
        self.robot, self.n_goals, self.z_dim = model.robot, model.n_goals, model.z_dim

    def decode_numpy(self, z: np.ndarray, state: np.ndarray, belief: np.ndarray) -> np.ndarray:
        """factor * phi(z, s, b)."""
        out = self.model.decode_numpy(z, state, belief)
        return out if self.factor == 1.0 else self.factor * out


def cells(config: Config, control: ControlConfig) -> list[Cell]:
    """The grid's settings, in a fixed order: the default, then each alpha, sigma_h, pilot.

    Every member of ``config.assistance`` runs in every cell (:func:`run_cell`).

    Raises:
        ConfigError: if the defaults (``control.alpha``, ``control.action_scale``,
            Boltzmann users) are not on the grid's axes (one-at-a-time needs them).
    """
    alpha0, scale0, pilot0 = float(control.alpha), float(control.action_scale), "boltzmann"
    if config.design == "factorial":
        return [
            Cell(a, s, p, "all")
            for a, s, p in itertools.product(config.alphas, config.action_scales, config.pilots)
        ]
    if alpha0 not in config.alphas or scale0 not in config.action_scales or pilot0 not in config.pilots:
        raise ConfigError(
            f"a one-at-a-time grid needs the defaults on its axes: alpha {alpha0}, "
            f"action_scale {scale0}, pilot {pilot0!r}"
        )
    out = [Cell(alpha0, scale0, pilot0, "default")]
    out += [Cell(a, scale0, pilot0, "alpha") for a in config.alphas if a != alpha0]
    out += [Cell(alpha0, s, pilot0, "action_scale") for s in config.action_scales if s != scale0]
    out += [Cell(alpha0, scale0, p, "pilot") for p in config.pilots if p != pilot0]
    return out


@dataclasses.dataclass(frozen=True)
class Grid:
    """What every cell of a grid shares: sent to each worker once (:func:`lasa.scaleout.run_jobs`)."""

    decoders: Mapping[str, ActionDecoder]  # notebook 03's pair
    task: CupTask
    control: ControlConfig  # the defaults the grid is centred on
    config: Config


def _pilot_prob(config: Config, pilot: str) -> float:
    return {"boltzmann": 0.0, "laggy": config.lag_prob, "noisy": config.noise_prob}[pilot]


def _rows(
    claims_by_seed: dict[int, list[Claim]], cell: Cell, member: str, robot: str, users: int
) -> pd.DataFrame:
    rows = [
        {
            "id": c.id,
            "robot": robot,
            "assistance": member,
            "alpha": cell.alpha,
            "action_scale": cell.action_scale,
            "seed": seed,
            "measured": c.value,
            "reproduced": c.reproduced,
            "pilot": cell.pilot,
            "setting": cell.setting,
            "users": users,
        }
        for seed, claims in claims_by_seed.items()
        for c in claims
    ]
    return pd.DataFrame(rows, columns=list(COLUMNS))


def run_cell(grid: Grid, cell: Cell) -> pd.DataFrame:
    """Run sims 1-3 in one cell, every member in the same batches, and judge each claim.

    Each claim is evaluated per member, on each draw of users and on all draws pooled.
    """
    config, control = grid.config, grid.control
    ctrl = dataclasses.replace(
        control, alpha=cell.alpha, action_scale=cell.action_scale, assistance=config.assistance[0]
    )
    factor = cell.action_scale / control.action_scale
    decoders = {k: ScaledDecoder(d, factor) for k, d in grid.decoders.items()}
    pilot: dict[str, Any] = {"pilot": cell.pilot, "pilot_prob": _pilot_prob(config, cell.pilot)}
    common: dict[str, Any] = {
        "n_seeds": config.n_seeds,
        "n_draws": config.n_draws,
        "assistance": config.assistance,
        "seed": config.seed,
    }
    runs = [
        (sim1, sim1.Config(betas=config.betas, horizon=config.horizon, **common, **pilot), lambda f: f),
        (
            sim2,
            sim2.Config(change_steps=config.change_steps, settle=config.settle, **common, **pilot),
            lambda f: f,
        ),
        (sim3, sim3.Config(horizon=config.horizon, **common, **pilot), sim3.episode_means),
    ]
    parts = []
    robot = grid.task.robot.name
    for module, sim_config, reduce in runs:
        frame = reduce(module.run(decoders, grid.task, ctrl, sim_config)[0])
        for member in config.assistance:
            rows = member_frame(frame, member)
            by_seed = {POOLED: module.claims(rows)}
            for d in range(config.n_draws):
                by_seed[d] = module.claims(rows[rows.draw == d])
            parts.append(_rows(by_seed, cell, member, robot, config.n_seeds))
    return pd.concat(parts, ignore_index=True)


def run(
    decoders: Mapping[str, ActionDecoder] | ActionDecoder,
    task: CupTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = False,
) -> pd.DataFrame:
    """Every cell of the grid (:func:`cells`), locally or on a Dask cluster.

    Args:
        decoders: ``{"base": ..., "entropy": ...}``: notebook 03's pair.
        task: The cup task.
        control: The default control units (alpha, sigma_h) the grid is centred on.
        config: The grid.
        progress: A progress bar over finished cells.

    Returns:
        One row per (claim, cell, draw) and per (claim, cell) pooled (``seed == -1``),
        with the columns of :data:`COLUMNS`, cells in :func:`cells` order.
    """
    decoders = as_decoders(decoders)
    grid = Grid(decoders, task, control, config)
    frames = run_jobs(
        run_cell, cells(config, control), config.scheduler, config.n_jobs, progress, "grid cells", shared=grid
    )
    return pd.concat(frames, ignore_index=True)


def verdict_table(frame: pd.DataFrame) -> pd.DataFrame:
    """Per (robot, claim, cell): the pooled verdict and how many draws agree with it."""
    keys = ["robot", "id", "assistance", "setting", "alpha", "action_scale", "pilot"]
    pooled = frame[frame.seed == POOLED].set_index(keys)
    draws = frame[frame.seed != POOLED].copy()
    draws["agrees"] = (
        draws.reproduced.to_numpy()
        == pooled.reproduced.reindex(pd.MultiIndex.from_frame(draws[keys])).to_numpy()
    )
    agree = draws.groupby(keys).agg(agree=("agrees", "sum"), draws=("agrees", "size"))
    out = pooled[["reproduced", "measured"]].join(agree).reset_index()
    out["agree"] = out.agree.astype(int)
    return out


def summary(verdicts: pd.DataFrame) -> pd.DataFrame:
    """Per (robot, claim, member): cells with each pooled verdict, and whether the default holds.

    Args:
        verdicts: :func:`verdict_table`'s rows.

    Returns:
        Columns ``yes``, ``partly``, ``no`` (cell counts), ``default`` (the verdict of the
        default cell, empty if the grid has none), ``stable`` (every cell of the member
        gives the default's verdict) and ``min_agree`` (the lowest draw agreement, as
        ``k/n``).
    """
    rows = []
    for (robot, claim, member), part in verdicts.groupby(["robot", "id", "assistance"], sort=True):
        counts = part.reproduced.value_counts()
        default = part.loc[part.setting == "default", "reproduced"]
        head = str(default.iloc[0]) if len(default) else ""
        worst = part.loc[part.agree.idxmin()]
        rows.append(
            {
                "robot": robot,
                "id": claim,
                "assistance": member,
                **{v: int(counts.get(v, 0)) for v in VERDICTS},
                "default": head,
                "stable": bool(head) and bool((part.reproduced == head).all()),
                "min_agree": f"{int(worst.agree)}/{int(worst.draws)}",
            }
        )
    return pd.DataFrame(rows)


def describe(table: pd.DataFrame) -> list[str]:
    """One sentence per claim from :func:`summary`: does its verdict depend on a convention?"""
    lines = []
    for (robot, claim), part in table.groupby(["robot", "id"], sort=True):
        defaults = dict(zip(part.assistance, part.default, strict=True))
        same_member = len(set(defaults.values())) == 1
        stable = part.loc[part.stable, "assistance"].tolist()
        moving = part.loc[~part.stable, "assistance"].tolist()
        head = (
            f"{robot} {claim}: default-cell verdict '{next(iter(defaults.values()))}' under every member"
            if same_member
            else f"{robot} {claim}: default-cell verdict depends on the member ("
            + ", ".join(f"{m} {v}" for m, v in defaults.items())
            + ")"
        )
        tail = (
            "; it holds in every cell of the grid."
            if not moving and same_member
            else f"; alpha, sigma_h or the pilot change it under {', '.join(moving)}."
            if moving
            else f"; within each member it holds in every cell ({', '.join(stable)})."
        )
        lines.append(head + tail)
    return lines


def _label(row: pd.Series) -> str:
    if row.setting == "default":
        return "default"
    if row.setting == "alpha":
        return f"alpha={row.alpha:g}"
    if row.setting == "action_scale":
        return f"sigma_h={row.action_scale:g}"
    if row.setting == "pilot":
        return f"{row.pilot} pilot"
    return f"a={row.alpha:g} s={row.action_scale:g} {row.pilot}"


def plot(table: pd.DataFrame) -> Figure:
    """The verdict map: claims (rows) x settings (columns), one panel per (robot, member).

    Colour is the pooled verdict (yes / partly / no); the text is how many independent
    draws of users agree with it.
    """
    verdicts = verdict_table(table)
    verdicts["column"] = verdicts.apply(_label, axis=1)
    robots = robots_present(verdicts)
    members = list(dict.fromkeys(verdicts.assistance))
    order_cols = list(dict.fromkeys(verdicts.column))
    ids = sorted(dict.fromkeys(verdicts.id))
    cmap = ListedColormap(["#1b9e77", "#e6ab02", "#d95f02"])
    code = {v: i for i, v in enumerate(VERDICTS)}
    fig, axes = plt.subplots(
        len(robots),
        len(members),
        figsize=(2.3 + 0.42 * len(order_cols) * len(members), 0.9 + 0.36 * len(ids) * len(robots)),
        squeeze=False,
        sharex=True,
        sharey=True,
    )
    for i, robot in enumerate(robots):
        for j, member in enumerate(members):
            ax = axes[i, j]
            part = verdicts[(verdicts.robot == robot) & (verdicts.assistance == member)]
            grid = np.full((len(ids), len(order_cols)), np.nan)
            for _, row in part.iterrows():
                r, c = ids.index(row.id), order_cols.index(row.column)
                grid[r, c] = code[row.reproduced]
                ax.text(c, r, f"{row.agree}/{row.draws}", ha="center", va="center", fontsize=6)
            ax.imshow(np.ma.masked_invalid(grid), cmap=cmap, vmin=-0.5, vmax=2.5, aspect="auto")
            ax.set_title(f"{robot}: {member}", fontsize=9)
            ax.set_xticks(range(len(order_cols)), order_cols, rotation=60, ha="right", fontsize=7)
            ax.set_yticks(range(len(ids)), ids, fontsize=7)
    handles = [plt.Rectangle((0, 0), 1, 1, color=cmap(code[v])) for v in VERDICTS]
    fig.legend(handles, VERDICTS, loc="upper right", ncol=3, frameon=False, fontsize=8)
    n = int(table.users.max()) if len(table) else 0
    draws = int(table[table.seed != POOLED].seed.nunique()) if len(table) else 0
    fig.suptitle(
        f"Claims robustness: pooled verdict per setting; text = draws agreeing ({draws} draws x {n} "
        "users per point)",
        fontsize=10,
    )
    fig.tight_layout()
    return fig
