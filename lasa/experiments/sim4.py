"""Fig. sim4: goals never seen in training, through the context map h (Secs. IV-C, V-D).

Users reach for a new cup with and without the map; the grasp error is fitted against the cup's distance
(both over the farthest cup's) through the origin, uncentred R^2, as the paper does. Readings:
``@joint_space``, ``@intercept``, ``@ee_line``. Notebook ``07_new_goals``.
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from mpl_toolkits.axes_grid1 import make_axes_locatable
from scipy import stats

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
from lasa.evidence.claims import Claim
from lasa.evidence.metrics import confidence, normalized_error
from lasa.evidence.plots import paper_slope, robots_present, users_text, wrap_to
from lasa.experiments import sweep
from lasa.method.context_map import MAP_KINDS, ContextMap, MappedDecoder, context_map, extend_task
from lasa.method.decoder import ActionDecoder
from lasa.method.step import METHOD_DECODER, METHODS, method_alpha
from lasa.people.rollout import Trajectories, rollout
from lasa.people.users import UserPopulation
from lasa.world.fork import angle_between
from lasa.world.robot import Robot
from lasa.world.task import CupTask

__all__ = [
    "NAME",
    "COLUMNS",
    "EPISODE_COLUMNS",
    "new_cup_positions",
    "map_geometry",
    "CUP_COLUMNS",
    "Config",
    "run",
    "fit_line",
    "fit_origin",
    "FORMS",
    "fits",
    "with_cup_columns",
    "medians_sentence",
    "no_map_check",
    "end_shares",
    "by_preference",
    "grasp_error",
    "MEASURES",
    "claims",
    "boot_values",
    "identity_sentence",
    "map_sentences",
    "plot",
    "other_share_text",
]

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

# the measures: (distance column, error column); "table" is the headline, the others are
# readings whose claims carry ``@<measure>`` ids
MEASURES = {"table": ("distance", "error"), "joint_space": ("distance_joint", "error_joint")}
HEADLINE = "table"
# the fits' forms, each with its reading (None: the headline): the paper's lines, y = 0.11x and
# y = x, go through the origin; the line with an intercept is the reading ``@intercept``
FORMS: dict[str, str | None] = {"origin": None, "intercept": "intercept"}
HEADLINE_FORM = "origin"
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
            len(self.direction) != 2
            or not np.isfinite(self.direction).all()
            or np.hypot(*self.direction) < 1e-9
        ):
            raise ConfigError(f"direction must be a non-zero (dx, dy) on the table, got {self.direction!r}")
        check_choice("method", self.method, METHODS)
        sweep.check_names("maps", self.maps, MAP_KINDS)
        sweep.check_needed("maps", tuple(self.maps), CLAIM_MAPS, "notebook 07's sentences and video")


@dataclasses.dataclass(frozen=True)
class NewGoalRun:
    """The episodes at one new cup: its distance from the reference cup [m], the task grown by it, and the
    trajectories with each kind of map (belief over G + 1 goals) and without (training goals only).
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

    Every member's users share one batch per (cup, map) and are the same users (paired). Returns one
    row per episode (:data:`EPISODE_COLUMNS`) and the runs per new cup under ``control.assistance``.
    """
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
    if assistance is None:
        assistance = sweep.swept_assistance(control, config.assistance)
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
    and the angle between their approach axes (the site's +z) [deg].
    """
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
            "robot": robot.name,
            "mapping": "with" if mapped else "without",
            "distance": at["distance"] / cup_scale,
            verdicts.USER: at[verdicts.USER],
            "error": err_m / cup_scale,
            "h": kind,
            "offset_m": at["offset_m"],
            "theta": at["theta"],
            "confidence": conf,
            "reference": ref_m / cup_scale,
            "assistance": at["assistance"],
            "look": at["look"],
            "angle_error_deg": angle,
            "distance_joint": at["distance_joint"] / scale,
            "error_joint": normalized_error(traj.states[-1], users.target, scale),
            "reference_joint": normalized_error(held, users.target, scale),
            "end_goal": end_goal,
        }
        frames.append(pd.DataFrame(row))
    return frames


def fit_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Least-squares line y = slope x + intercept; returns (slope, intercept, R^2)."""
    res = stats.linregress(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    return float(res.slope), float(res.intercept), float(res.rvalue**2)


def fit_origin(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Least-squares line through the origin, y = slope x, the paper's form; returns (slope, R^2), the
    uncentred R^2 as numpy's ``lstsq`` and statsmodels report without a constant (``docs/method-notes.md``).
    """
    slope, r2 = _lines(np.asarray(x, dtype=float), np.asarray(y, dtype=float)[None], "origin")
    return float(slope[0]), float(r2[0])


def _fit(x: np.ndarray, y: np.ndarray, form: str) -> tuple[float, float, float]:
    """(slope, intercept, R^2) of the fit of ``form`` (:data:`FORMS`); the origin's intercept is 0."""
    if form == "intercept":
        return fit_line(x, y)
    slope, r2 = fit_origin(x, y)
    return slope, 0.0, r2


def fits(frame: pd.DataFrame, measure: str = HEADLINE, form: str = HEADLINE_FORM) -> pd.DataFrame:
    """Least-squares lines of the mean error per new cup against its distance, per kind of map ``h``.

    ``measure`` picks the distance and error (:data:`MEASURES`), ``form`` the line (:data:`FORMS`). Returns
    ``slope``, ``intercept`` (0 through the origin), ``r2`` (of the cups' means) and ``r2_episodes``.
    """
    if form not in FORMS:
        raise ConfigError(f"form must be one of {sorted(FORMS)}, got {form!r}")
    x, y = MEASURES[measure]
    out = []
    for kind, part in frame.groupby("h"):
        means = part.groupby(x)[y].mean()
        slope, intercept, r2 = _fit(means.index.to_numpy(), means.to_numpy(), form)
        _, _, r2_ep = _fit(part[x].to_numpy(), part[y].to_numpy(), form)
        out.append({"h": kind, "slope": slope, "intercept": intercept, "r2": r2, "r2_episodes": r2_ep})
    return pd.DataFrame(out).set_index("h")


# per kind of map: the claim it is judged under, the reading it is (None: the claim's own map) and its
# name; the paper's straight line "between the start and g", in the gripper's space, is ``@ee_line``
_LINE = "the paper's straight-line context map"
_KIND_CLAIMS = {
    "straight_line": ("straight_line", None, _LINE),
    "grasp": ("grasp", None, "the grasp-to-grasp context map (ours)"),
    "straight_line_ee": ("straight_line", "ee_line", f"{_LINE}, the line in the gripper's space"),
}


def _claim_id(name: str, *readings: str | None) -> str:
    """``sim4.<name>``, or ``sim4.<name>@<reading>+<reading>`` for the readings given."""
    parts = [r for r in readings if r]
    return f"sim4.{name}" + (f"@{'+'.join(parts)}" if parts else "")


def _measures(frame: pd.DataFrame) -> list[str]:
    """The measures a frame holds, the headline first (the joint-space reading needs its columns)."""
    return [m for m, cols in MEASURES.items() if set(cols) <= set(frame.columns)]


def _reading(measure: str) -> str | None:
    return None if measure == HEADLINE else measure


def claims(frame: pd.DataFrame) -> list[Claim]:
    """Fig. sim4's claims on one robot's frame, under every measure it holds and both forms of fit."""
    robot, out = str(frame.robot.iloc[0]), []
    for measure, form in itertools.product(_measures(frame), FORMS):
        x, y = MEASURES[measure]
        table, n_cups = fits(frame, measure, form), frame[x].nunique()
        means = frame.groupby(["h", x])[y].mean()
        angles = None
        if measure == HEADLINE and "angle_error_deg" in frame:
            angles = frame.groupby(["h", x]).angle_error_deg.mean()
        readings = (_reading(measure), FORMS[form])
        for kind in [k for k in _KIND_CLAIMS if k in table.index]:
            name, kind_reading, words = _KIND_CLAIMS[kind]
            f, below = table.loc[kind], means[kind] < means["none"]
            above = int((~below).sum())
            note = f"Above the no-map error at {above} of {n_cups} cups." if above else ""
            out.append(
                sweep.sim_claim(
                    _claim_id(f"{name}_linear", kind_reading, *readings),
                    robot,
                    {"slope": float(f.slope), "r2": float(f.r2), "share_below": float(below.mean())},
                    claim=f"with {words}, the error at a new goal grows linearly with its distance",
                    paper="y = 0.11x, R^2 = 0.98",
                    measured=_line(f, n_cups) + " (the interval is for the slope)",
                    note=" ".join(t for t in (note, _angle_note(angles, kind)) if t),
                )
            )
        wo = table.loc["none"]
        out.append(
            sweep.sim_claim(
                _claim_id("no_map_training_goal", *readings),
                robot,
                {"slope": float(wo.slope), "r2": float(wo.r2)},
                claim="without the map, the robot only reaches for the training goal",
                paper="y = x",
                measured=_line(wo, n_cups) + " (the interval is for the slope)",
                note=_angle_note(angles, "none"),
            )
        )
    return out


def _angle_note(angles: pd.Series | None, kind: str) -> str:
    """The mean approach-axis error at the nearest and the farthest cup, as a sentence of numbers."""
    if angles is None or kind not in angles.index.get_level_values(0):
        return ""
    per_cup = angles[kind]
    return (
        f"Mean approach-axis error {per_cup.iloc[0]:.1f}° at the nearest cup, "
        f"{per_cup.iloc[-1]:.1f}° at the farthest."
    )


def no_map_check(frame: pd.DataFrame, form: str = HEADLINE_FORM) -> pd.DataFrame:
    """The paper's "without the map ... y = x", taken apart: per part of the no-map episodes, the line
    of ``form`` through the cups' means (NaN with fewer than two cups), ``mean_error`` and ``share``.
    """
    none = frame[frame.h == "none"]
    parts = {"held at the training cup": none.assign(error=none.reference), "without the map": none}
    if "end_goal" in none:
        parts["without the map, belief ends on the training cup"] = none[none.end_goal == "reference"]
        parts["without the map, belief ends on another cup"] = none[none.end_goal == "other"]
    rows = []
    for name, part in parts.items():
        means = part.groupby("distance").error.mean()
        enough = len(means) >= 2
        line = _fit(means.index.to_numpy(), means.to_numpy(), form) if enough else (np.nan,) * 3
        rows.append(
            {
                "line": name,
                "slope": line[0],
                "intercept": line[1],
                "r2": line[2],
                "mean_error": float(part.error.mean()) if len(part) else np.nan,
                "share": len(part) / max(len(none), 1),
            }
        )
    return pd.DataFrame(rows).set_index("line")


def end_shares(frame: pd.DataFrame) -> pd.DataFrame:
    """Per (``h``, ``distance``): the share of episodes whose belief ends on another training cup
    (``other``), the ``mean`` and ``median`` error, the mean of those episodes (``mean_left``) and of
    the rest (``mean_stayed``), and ``n``.
    """
    rows = []
    for (kind, d), part in frame.groupby(["h", "distance"]):
        left = part.end_goal == "other"
        rows.append(
            {
                "h": kind,
                "distance": d,
                "other": float(left.mean()),
                "mean": float(part.error.mean()),
                "median": float(part.error.median()),
                "mean_left": float(part.error[left].mean()) if left.any() else np.nan,
                "mean_stayed": float(part.error[~left].mean()) if (~left).any() else np.nan,
                "n": len(part),
            }
        )
    return pd.DataFrame(rows).set_index(["h", "distance"])


_CUP_KEYS = ["robot", "assistance", "h", "distance"]


def with_cup_columns(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` with :data:`CUP_COLUMNS`, each cup's numbers on every one of its episodes' rows."""
    keys = [k for k in _CUP_KEYS if k in frame]
    other = (frame.end_goal == "other").astype(float) if "end_goal" in frame else np.nan
    groups = frame.assign(other_=other).groupby(keys, sort=False)
    return frame.assign(
        cup_mean_error=groups.error.transform("mean"),
        cup_median_error=groups.error.transform("median"),
        cup_other_share=groups.other_.transform("mean"),
    )


def _listed(values: np.ndarray, fmt: str) -> str:
    """``a, b and c`` of ``values`` formatted by ``fmt``."""
    text = [format(float(v), fmt) for v in values]
    return text[0] if len(text) == 1 else ", ".join(text[:-1]) + " and " + text[-1]


def medians_sentence(frame: pd.DataFrame) -> str:
    """What the no-map medians and the share of beliefs on the other cup say of y = x, from
    :func:`end_shares` of one robot's headline rows (with ``end_goal``).
    """
    table = end_shares(frame).loc["none"]
    far = table.iloc[-1]
    text = (
        f"{frame.robot.iloc[0]}, without the map, new cups at {_listed(table.index, '.2f')} D: the median "
        f"error is {_listed(table['median'], '.2f')} D, the mean {_listed(table['mean'], '.2f')} D "
        f"(y = x gives the distance). The belief of {_listed(100 * table.other, '.0f')}% of the users "
        f"ends on the other training cup"
    )
    if not far.other > 0:
        return text + "."
    return text + (
        f"; at the farthest cup those users end {far.mean_left:.2f} D from the wanted grasp on average, "
        f"the others {far.mean_stayed:.2f} D."
    )


# the grasps the users want, in three bands of the preference theta (0: top, 1: side)
BANDS = {"top (θ < 1/3)": (0.0, 1 / 3), "middle": (1 / 3, 2 / 3), "side (θ ≥ 2/3)": (2 / 3, 1.0 + 1e-9)}


def by_preference(frame: pd.DataFrame) -> pd.DataFrame:
    """Mean error, approach-axis error and the share of beliefs that end on another cup (``other``),
    and ``n``, per (``h``, ``band`` of the wanted grasp, :data:`BANDS`, ``distance``).
    """
    edges = [lo for lo, _ in BANDS.values()] + [1.0 + 1e-9]
    band = pd.cut(frame.theta, edges, right=False, labels=list(BANDS))
    # every band appears, empty ones with NaN numbers and n = 0 (a small run may draw no middle grasp)
    grouped = frame.assign(band=band, other=frame.end_goal == "other").groupby(
        ["h", "band", "distance"], observed=False
    )
    return grouped.agg(
        error=("error", "mean"),
        angle_error_deg=("angle_error_deg", "mean"),
        other=("other", "mean"),
        n=("error", "size"),
    )


def identity_sentence(frame: pd.DataFrame) -> str:
    """What :func:`no_map_check` and :func:`end_shares` say of y = x on one robot's headline rows
    (the lines through the origin, R² uncentred).
    """
    check, share = no_map_check(frame), end_shares(frame).loc["none", "other"]
    held, every = check.loc["held at the training cup"], check.loc["without the map"]
    stay = check.loc["without the map, belief ends on the training cup"]
    left = check.loc["without the map, belief ends on another cup"]
    text = (
        f"{frame.robot.iloc[0]}, {frame[verdicts.USER].nunique()} users per cup, "
        "lines through the origin: held at "
        f"the training cup, the error is {_equation(held)} (R² = {held.r2:.3f}). Without the map it "
        f"is {_equation(every, 2)} (R² = {every.r2:.2f}); over the {100 * stay.share:.0f}% of episodes "
        f"whose belief ends on the training cup, {_equation(stay, 2)} (R² = {stay.r2:.2f}). "
    )
    if not left.share > 0:
        return text + "No episode's belief ends on the other training cup."
    return text + (
        f"The belief ends on the other training cup in {100 * share.iloc[0]:.0f}% of the episodes at "
        f"the nearest new cup and {100 * share.iloc[-1]:.0f}% at the farthest, and those episodes end "
        f"{left.mean_error:.2f} D from the wanted grasp on average."
    )


def map_sentences(frame: pd.DataFrame, geometry: pd.DataFrame) -> list[str]:
    """Why the straight-line map errs, from one robot's headline rows and its :func:`map_geometry`: its
    sentence, then the gripper's-space map's if the frame has it.
    """
    g, bands = geometry, by_preference(frame[frame.h != "none"])
    far = g.xs(g.index.get_level_values("offset_m").max(), level="offset_m")
    line = far.loc["straight_line"]
    top, middle, side = (bands.loc["straight_line"].xs(name, level="band") for name in BANDS)
    out = [
        f"{frame.robot.iloc[0]}: the new cups' grasps differ from the training cup's by at most "
        f"{g.joint1_rad.max():.2f} rad in joint 1 and {g.joint_last_rad.max():.2f} rad in the last joint, "
        f"and that difference changes by at most {g.branch_rad.max():.3f} rad between neighbouring "
        f"preferences: no branch switch. The mapped grasps keep at least {g.margin_rad.min():.2f} rad "
        f"from every joint limit, and the map stretches progress along the line by {g.stretch.min():.2f} "
        f"to {g.stretch.max():.2f}. At the farthest cup the straight-line map sends the new cup's grasps "
        f"up to {line.misfit_rad:.3f} rad from the training cup's same grasps ({100 * line.misfit_m:.1f} cm "
        f"and {line.misfit_deg:.1f}° at the gripper; the grasp-to-grasp map "
        f"{100 * far.loc['grasp', 'misfit_m']:.1f} cm). With the straight-line map, users who want a top "
        f"grasp end {top.error.min():.2f} to {top.error.max():.2f} D off (approach error up to "
        f"{top.angle_error_deg.max():.0f}°; belief on the other training cup in up to "
        f"{100 * top.other.max():.0f}% of them), middle grasps {middle.error.min():.3f} to "
        f"{middle.error.max():.3f} D, side grasps {side.error.min():.3f} to {side.error.max():.3f} D."
    ]
    if "straight_line_ee" in bands.index.get_level_values("h"):
        ee, ends = bands.loc["straight_line_ee"], end_shares(frame).loc["straight_line_ee"]
        ee_top, ee_side = (ee.xs(name, level="band").error.max() for name in (*BANDS,)[::2])
        out.append(
            f"The same line in the gripper's space (@ee_line) sends the farthest cup's grasps "
            f"{100 * far.loc['straight_line_ee', 'misfit_m']:.2f} cm from the training cup's; its users "
            f"end {ee_top:.3f} D off at most for top grasps, {ee_side:.3f} D for side grasps, with a median "
            f"error of {ends['median'].min():.3f} to {ends['median'].max():.3f} D over the cups."
        )
    return out


def _equation(f: pd.Series, digits: int = 3) -> str:
    """``y = 0.110x`` through the origin (intercept 0), ``y = 0.110x +0.010`` with an intercept."""
    line = f"y = {f.slope:.{digits}f}x"
    return line if f.intercept == 0.0 else f"{line} {f.intercept:+.{digits}f}"


def _line(f: pd.Series, n_cups: int) -> str:
    """A fit's line, its R^2 over the cups' means and over the episodes (uncentred through the origin)."""
    kind = " (uncentred)" if f.intercept == 0.0 else ""
    return (
        f"{_equation(f)}, R^2{kind} = {f.r2:.3f} over the {n_cups} cups' means "
        f"({f.r2_episodes:.2f} over episodes)"
    )


def _lines(x: np.ndarray, ys: np.ndarray, form: str) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares slope and R^2 of each row of ``ys`` (R, K) against ``x`` (K,), lines of ``form``.

    Through the origin: slope = sum(x y) / sum(x^2) and the uncentred R^2, 1 - SSE / sum(y^2), which is
    sum(x y)^2 / (sum(x^2) sum(y^2)); with an intercept, the same of x and y less their means.
    """
    if form == "intercept":
        x, ys = x - x.mean(), ys - ys.mean(axis=1, keepdims=True)
    sxy, sxx, syy = ys @ x, float(x @ x), (ys**2).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return sxy / sxx, sxy**2 / (sxx * syy)


def boot_values(frame: pd.DataFrame, counts: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """:func:`claims`' numbers in every resample of users (``counts``, :mod:`lasa.evidence.verdicts`),
    under the same ids (every measure's and both forms' of fit).
    """
    out: dict[str, dict[str, np.ndarray]] = {}
    for measure in _measures(frame):
        x, y = MEASURES[measure]
        means = verdicts.group_means(frame, ["h", x], y, counts)
        dist = np.array(sorted({d for _, d in means}))
        curve = {k: np.stack([means[(k, d)] for d in dist], axis=1) for k in {h for h, _ in means}}
        for form, form_reading in FORMS.items():
            readings = (_reading(measure), form_reading)
            for kind in [k for k in _KIND_CLAIMS if k in curve]:
                name, kind_reading, _ = _KIND_CLAIMS[kind]
                slope, r2 = _lines(dist, curve[kind], form)
                share = (curve[kind] < curve["none"]).mean(axis=1)
                cid = _claim_id(f"{name}_linear", kind_reading, *readings)
                out[cid] = {"slope": slope, "r2": r2, "share_below": share}
            slope, r2 = _lines(dist, curve["none"], form)
            out[_claim_id("no_map_training_goal", *readings)] = {"slope": slope, "r2": r2}
    return out


# per kind of map: colour, name, marker, line dashes and x offset of its markers: near-equal lines and
# means of two maps (the grasp-to-grasp and the gripper's-space maps, within 0.01 D) stay visible
H_STYLES: dict[str, tuple[str, str, str, tuple[float, ...], float]] = {
    "none": ("#d95f02", "without the map", "o", (), -0.015),
    "straight_line": ("#7570b3", "straight-line h (paper)", "s", (), -0.005),
    "grasp": ("#1b9e77", "grasp-to-grasp h (ours)", "^", (5.0, 2.0), 0.005),
    "straight_line_ee": ("#e7298a", "straight-line h, gripper's space", "D", (1.5, 1.5), 0.015),
}

# the paper's lines (Sec. V-D): slope -> (legend label, line style); drawn above ours
PAPER_LINES = {0.11: ("paper, with the map: y = 0.11x", ":"), 1.0: ("paper, without the map: y = x", "--")}
PAPER_UNITS = (
    "(both axes ÷ D, the farthest new cup's distance, as the paper's; the grasp error at the gripper)"
)
N_BOOT_PLOT = 1000  # resamples of users of each cup's mean's error bar, at the verdicts' level
MEAN_STYLE: dict[str, Any] = {"ms": 4, "capsize": 2}  # a cup's mean and its interval
MEDIAN_STYLE: dict[str, Any] = {"s": 22, "facecolors": "none", "lw": 0.9}  # a cup's median, hollow


def _cup_means(part: pd.DataFrame, y: str = "error") -> pd.DataFrame:
    """Each cup's mean of ``y``, its bootstrap interval at the verdicts' level (users resampled), median."""
    rng = np.random.default_rng(0)
    rows = []
    for d, cup in part.groupby("distance"):
        v = cup[y].to_numpy(dtype=float)
        boot = v[rng.integers(0, len(v), (N_BOOT_PLOT, len(v)))].mean(axis=1)
        tail = 50.0 * (1.0 - sweep.LEVEL)
        lo, hi = np.percentile(boot, [tail, 100.0 - tail])
        rows.append({"distance": d, "mean": v.mean(), "low": lo, "high": hi, "median": np.median(v)})
    return pd.DataFrame(rows)


def plot_robot(frame: pd.DataFrame, ax: Axes | None = None) -> Axes:
    """One robot's panel: grasp error at new cups against their distance, per kind of map."""
    ax = plt.gca() if ax is None else ax
    table = fits(frame)
    xs = np.array([float(frame.distance.min()), 1.0])  # the fits over the cups measured
    tops, bottoms = [1.05], [0.0]  # the paper's y = x, drawn to x = 1.05
    angles = frame.groupby(["h", "distance"]).angle_error_deg.mean() if "angle_error_deg" in frame else None
    for kind, (color, name, marker, dashes, dx) in H_STYLES.items():
        if kind not in table.index:
            continue
        cups = _cup_means(frame[frame.h == kind])
        bars = [cups["mean"] - cups.low, cups.high - cups["mean"]]
        ax.errorbar(
            cups.distance + dx, cups["mean"], yerr=bars, fmt=marker, color=color, zorder=3, **MEAN_STYLE
        )
        ax.scatter(
            cups.distance + dx, cups["median"], marker=marker, edgecolors=color, zorder=4, **MEDIAN_STYLE
        )
        f = table.loc[kind]
        label = f"{name}: {_equation(f, 2)}, R² = {f.r2:.2f}"
        if angles is not None:
            per_cup = angles[kind]
            label += f"; approach error {per_cup.iloc[0]:.1f}° → {per_cup.iloc[-1]:.1f}°"
        fitted = f.slope * xs + f.intercept
        line = ax.plot(xs, fitted, color=color, lw=1.5, label=label, zorder=2)[0]
        if dashes:  # () keeps the solid line
            line.set_dashes(dashes)
        tops += [float(cups.high.max()), float(cups["median"].max()), float(max(fitted))]
        bottoms += [float(cups.low.min()), float(cups["median"].min()), float(min(fitted))]
    label = f"mean per cup, bars: {100 * sweep.LEVEL:.4g}% bootstrap interval (the verdicts' level)"
    ax.errorbar([], [], yerr=[], fmt="o", color="0.4", label=label, **MEAN_STYLE)
    ax.scatter([], [], marker="o", edgecolors="0.4", label="median per cup", **MEDIAN_STYLE)
    share = other_share_text(frame)
    if share:
        ax.text(0.02, 0.98, share, transform=ax.transAxes, va="top", fontsize=7, wrap=True)
    for slope, (label, ls) in PAPER_LINES.items():
        paper_slope(ax, slope, label, x_max=1.05, ls=ls, lw=1.8, zorder=6)
    ax.set_xlim(0, 1.05)
    ax.set_ylim(min(bottoms) - 0.02 * max(tops), max(1.1, max(tops) * 1.08))
    ax.set_xlabel(f"distance of the new cup from the training cup (normalised)\n{PAPER_UNITS}", fontsize=8)
    ax.set_ylabel("grasp error at the gripper (normalised)")
    ax.legend(frameon=False, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.2))
    _episodes_panel(ax, frame, table)
    return ax


def other_share_text(frame: pd.DataFrame) -> str:
    """The figure's note: the share of no-map users whose belief ends on the other training cup, at
    the nearest and the farthest cup (:func:`end_shares`); empty without ``end_goal`` or no-map rows.
    """
    if "end_goal" not in frame or not (frame.h == "none").any():
        return ""
    other = end_shares(frame).loc["none", "other"]
    return (
        f"without the map, belief ends on the other training cup:\n{100 * other.iloc[0]:.0f}% of users at "
        f"the nearest cup, {100 * other.iloc[-1]:.0f}% at the farthest"
    )


def _episodes_panel(ax: Axes, frame: pd.DataFrame, table: pd.DataFrame) -> Axes:
    """Every episode's error, in a panel beside ``ax`` whose y-axis reaches the largest of them."""
    side = make_axes_locatable(ax).append_axes("right", size="38%", pad=0.6)
    for kind, (color, name, *_) in H_STYLES.items():
        if kind in table.index:
            part = frame[frame.h == kind]
            side.scatter(part.distance, part.error, s=5, color=color, alpha=0.35, lw=0, label=name)
    side.set_xlim(0, 1.05)
    side.set_ylim(0, max(1.1, float(frame.error.max()) * 1.05))
    side.set_title("every episode", fontsize=8)
    side.set_ylabel("grasp error of each episode (normalised)", fontsize=7)
    legend = side.legend(
        frameon=False, fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.12), markerscale=2.5
    )
    for handle in legend.legend_handles:
        if handle is not None:
            handle.set_alpha(1.0)
    side.tick_params(labelsize=7)
    return side


def plot(table: pd.DataFrame, assistance: str = "point") -> Figure:
    """Fig. sim4: one panel per robot present (:func:`plot_robot`), under one assistance member."""
    table = verdicts.member_frame(table, assistance)
    present = robots_present(table)
    fig, axes = plt.subplots(1, len(present), figsize=(7.6 * len(present), 6.6), squeeze=False)
    for name, ax in zip(present, axes[0], strict=True):
        plot_robot(table[table.robot == name], ax=ax)
        ax.set_title(name)
    n = users_text(table, ["h", "distance"])  # per (map, new cup)
    title = f"Fig. sim4: new goals, near-optimal users, {n}, assistance: {assistance}"
    fig.suptitle(wrap_to(title, fig.get_figwidth()))
    fig.tight_layout()
    return fig
