r"""The property latent actions rest on (Sec. III), measured for any decoder.

Sec. III: while the robot is unsure of the goal, the joystick input z chooses *which goal*;
"once the robot is confident about the human's goal, the latent actions change to convey
the preferred manipulation". Shared autonomy (Sec. IV) then holds the tool near the likely
goal, and the user's input fine-tunes *how* to act there. A decoder without this property
makes the method's assistance fight its user. It is measured here in two contexts, with
latent actions alone (alpha = 0), every input held for a while:

- **Confident at goal g**: start at g's mid-preference pose :math:`s^*(g, 1/2)` with the
  belief all but the floor on g, held fixed. An input *stays* when the tool tip's distance
  to g's **preference set** (the tip positions of every preference at g: the grasp curve
  :math:`\theta \mapsto s^*(g, \theta)` of a cup, the stroke surface
  :math:`(\theta, u) \mapsto s^*(g, \theta, u)` of a bowl) grows more slowly than
  ``drift_speed``: :math:`d(t) \le v\,t` at every step of the hold. Reported: the share of
  the ring's inputs that stay, and the range of preference the staying inputs reach (the
  preference coordinates of the nearest preference pose at the end of the hold, by tip
  position and direction, the direction weighted by ``rotation_weight`` metres per radian).
- **Uncertain**: start at home with a uniform belief, updated online as in Algorithm 1;
  after ``uncertain_hold`` seconds an input has *reached* the goal whose preference set
  the tip is nearest, if it is within ``reach_distance``. Reported: which goal each input
  reaches, and whether every goal is reached by some input.

The inputs are a dense ring of full stick deflections: ``n_inputs`` angles on the unit
circle for a 2-axis stick, ``n_inputs`` evenly spaced deflections of [-1, 1] (rest left out)
for a 1-axis stick.

**The rule** (:func:`has_property`, :func:`choose`), written before any eating decoder's
property was measured and before any participant ran: a decoder has the property at a goal
when at least :data:`STAY_SHARE` of the inputs stay there and the staying inputs reach a
range of tilt (theta) of at least :data:`TILT_RANGE` of [0, 1]. Among several decoders of
one task, the one chosen is the best by, in order: every goal reached from home; the number
of goals with the property; the smallest share that stays at any goal; the smallest tilt
range at any goal.
"""

from __future__ import annotations

import dataclasses

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.figure import Figure

from lasa.base.config import AtLeastTwo, ControlConfig, check_range, validate
from lasa.base.errors import ConfigError
from lasa.method.belief import belief as to_belief
from lasa.method.blend import safe_step
from lasa.method.decoder import ActionDecoder
from lasa.method.step import shared_autonomy_step
from lasa.world.goals import GoalTask

__all__ = [
    "NAME",
    "COLUMNS",
    "KEY",
    "STAY_SHARE",
    "TILT_RANGE",
    "PropertyConfig",
    "PreferenceSet",
    "preference_set",
    "ring",
    "held_input_paths",
    "measure",
    "summary",
    "has_property",
    "choose",
    "plot",
]

NAME = "latent_property"
KEY = "source"  # the CSV's rows are replaced per source (one notebook run's decoders)
COLUMNS = (
    "source",
    "robot",
    "task",
    "decoder",
    "context",
    "goal",
    "z1",
    "z2",
    "drift",
    "stays",
    "theta",
    "stroke",
    "reached",
    "distance",
)
STAY_SHARE = 0.5  # share of the ring's inputs that must stay at a goal [-]
TILT_RANGE = 0.5  # tilt range the staying inputs must reach, as a share of [0, 1] [-]
DPI = 130


@dataclasses.dataclass(frozen=True)
class PropertyConfig:
    """How the property is measured; every value is set from what it means, not from a result.

    The hold at a goal (4 s) is the time a decoder moving at the demonstrators' cruise speed
    (0.8 sigma_h = 0.3 rad/s) needs to sweep half of the longest preference curve of our
    tasks in joint space (1.1 rad, from theta = 1/2 to an end of the Panda's cup curve; the
    bowls' tilt curves are 0.85-1.06 rad from the middle to an end), so a decoder that conveys
    the preference can reach either end of it from the middle. A drift of 2 cm/s is the
    issue's example; with ``d(t) <= v t`` at every step it is a bound on the tip's mean speed
    away from the goal's preferences over every stretch of the hold from its start. From
    home, 10 s at sigma_h covers the 2-3 rad to the farthest goal.
    """

    n_inputs: AtLeastTwo = 64  # stick inputs on the ring [-]
    hold: float = 4.0  # seconds each input is held at a goal, the belief held confident [s]
    drift_speed: float = 0.02  # v: an input stays when d(t) <= v t through the hold [m/s]
    uncertain_hold: float = 10.0  # seconds each input is held from home, the belief updated online [s]
    reach_distance: float = 0.05  # an input reaches a goal when the tip ends this close to its set [m]
    rotation_weight: float = 0.125  # metres per radian of direction when matching a preference [m/rad]
    n_grid: AtLeastTwo = 41  # preference grid per coordinate of the preference set [-]

    def __post_init__(self) -> None:
        validate(self)
        for name in ("hold", "drift_speed", "uncertain_hold", "reach_distance"):
            check_range(name, getattr(self, name), 0.0, low_open=True)
        check_range("rotation_weight", self.rotation_weight, 0.0)


@dataclasses.dataclass(frozen=True)
class PreferenceSet:
    """The preferences at one goal, sampled: coordinates and the tool tip's pose at each.

    Attributes:
        theta: Tilt (cups: top 0 to side 1; bowls: straight down 0 to a scoop's 60 deg 1), (P,).
        stroke: Depth u along the stroke (bowls), 0 where the task has no strokes, (P,).
        positions: Tip positions, (P, 3) [m].
        axes: Tip directions (unit), (P, 3).
    """

    theta: np.ndarray
    stroke: np.ndarray
    positions: np.ndarray
    axes: np.ndarray


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
    robot = task.robot
    return PreferenceSet(theta, stroke, robot.grasp_positions(states), robot.grasp_axes(states))


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
    """States reached by holding each joystick input for ``steps`` steps (LA, alpha = 0).

    All inputs advance together in one batch: each step makes one decoder call.

    Args:
        decoder: The decoder.
        task: The task (for the joint limits).
        control: Control-loop units.
        start: Start state, shape (n,).
        belief: The initial belief, shape (G,).
        z_values: Joystick inputs, shape (K,) or (K, d).
        steps: Number of steps each input is held.
        update_belief: Update the belief online with each decoded action (Algorithm 1);
            otherwise hold it fixed.

    Returns:
        States, shape (K, steps + 1, n).
    """
    if steps < 1:
        raise ConfigError(f"steps must be >= 1, got {steps}")
    belief = np.asarray(belief, dtype=float)
    if belief.shape != (task.n_goals,) or not np.isclose(belief.sum(), 1.0) or belief.min() < 0:
        raise ConfigError(f"belief must be a distribution over {task.n_goals} goals, got {belief}")
    z = np.asarray(z_values, dtype=float).reshape(len(z_values), -1)
    robot = task.robot
    s = np.broadcast_to(start, (len(z), robot.n_joints)).copy()
    log_b = np.log(np.broadcast_to(np.maximum(belief, 1e-300), (len(z), task.n_goals)))
    out = [s]
    for _ in range(steps):
        if update_belief:  # Algorithm 1 with alpha = 0: the method LA
            step = shared_autonomy_step(decoder, task, control, s, log_b, z, 0.0)
            s, log_b = step.state, step.log_belief
        else:
            a = decoder.decode_numpy(z, s, to_belief(log_b))
            s = safe_step(s, a, control.dt, robot.lower, robot.upper, control.max_joint_speed)
        out.append(s)
    return np.stack(out, axis=1)


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
    """The property of ``decoder`` on ``task``, one row per (context, goal, input) (:data:`COLUMNS`).

    ``confident`` rows: ``drift`` is the largest d(t)/t over the hold [m/s], ``stays``
    whether it is at most ``drift_speed``, ``theta``/``stroke`` the preference reached,
    ``reached`` the goal whose set the tip ends nearest (this goal's name when it stays).
    ``uncertain`` rows (goal ``home``): ``reached`` the goal reached (``-`` for none) and
    ``distance`` the tip's distance to that goal's set at the end [m].
    """
    robot, dt = task.robot, control.dt
    z = ring(config.n_inputs, decoder.z_dim)
    sets = [preference_set(task, g, config.n_grid) for g in range(task.n_goals)]
    names = list(task.goal_names)
    floor = control.belief_floor
    hold = max(1, round(config.hold / dt))
    rows = []
    base = {"source": source, "robot": robot.name, "task": task_name, "decoder": decoder_name}
    z2 = z[:, 1] if z.shape[1] > 1 else np.full(len(z), np.nan)
    for g, pset in enumerate(sets):
        b = np.full(task.n_goals, floor)
        b[g] = 1.0 - (task.n_goals - 1) * floor
        paths = held_input_paths(decoder, task, control, task.target(g, 0.5), b, z, hold)  # (K, H+1, n)
        pos, axis = robot.grasp_positions(paths[:, 1:]), robot.grasp_axes(paths[:, 1:])
        dist, _ = _nearest(pset, pos, axis, config.rotation_weight)  # (K, H)
        drift = (dist / (dt * np.arange(1, hold + 1))).max(axis=1)
        _, idx = _nearest(pset, pos[:, -1], axis[:, -1], config.rotation_weight)
        ends = np.stack([_nearest(s, pos[:, -1], axis[:, -1], 0.0)[0] for s in sets], axis=1)  # (K, G)
        stays = drift <= config.drift_speed
        rows.append(
            pd.DataFrame(
                {
                    **base,
                    "context": "confident",
                    "goal": names[g],
                    "z1": z[:, 0],
                    "z2": z2,
                    "drift": drift,
                    "stays": stays,
                    "theta": pset.theta[idx],
                    "stroke": pset.stroke[idx],
                    "reached": np.where(stays, names[g], np.asarray(names)[ends.argmin(axis=1)]),
                    "distance": ends[:, g],
                }
            )
        )
    steps = max(1, round(config.uncertain_hold / dt))
    uniform = np.full(task.n_goals, 1.0 / task.n_goals)
    end = held_input_paths(decoder, task, control, task.start, uniform, z, steps, update_belief=True)[:, -1]
    pos, axis = robot.grasp_positions(end), robot.grasp_axes(end)
    dist = np.stack([_nearest(s, pos, axis, 0.0)[0] for s in sets], axis=1)  # (K, G)
    near = dist.argmin(axis=1)
    best = dist[np.arange(len(z)), near]
    rows.append(
        pd.DataFrame(
            {
                **base,
                "context": "uncertain",
                "goal": "home",
                "z1": z[:, 0],
                "z2": z2,
                "drift": np.nan,
                "stays": False,
                "theta": np.nan,
                "stroke": np.nan,
                "reached": np.where(best <= config.reach_distance, np.asarray(names)[near], "-"),
                "distance": best,
            }
        )
    )
    return pd.concat(rows, ignore_index=True)


def summary(frame: pd.DataFrame) -> pd.DataFrame:
    """One row per (source, robot, task, decoder, goal) of :func:`measure`'s rows.

    Columns: ``stay_share``; the tilt and stroke the staying inputs reach (``theta_min``,
    ``theta_max``, ``theta_range``, ``stroke_range``; the range is 0 when none stays);
    ``from_home``, the share of the ring's inputs that reach this goal from home under the
    uncertain belief; ``all_reached``, whether every goal of the decoder's task is reached
    from home by some input; ``has_property`` (:func:`has_property`).
    """
    keys = ["source", "robot", "task", "decoder"]
    rows = []
    for key, part in frame.groupby(keys, sort=False):
        conf = part[part.context == "confident"]
        home = part[part.context == "uncertain"]
        goals = list(dict.fromkeys(conf.goal))
        all_reached = set(goals) <= set(home.reached)
        for goal in goals:
            at = conf[conf.goal == goal]
            stay = at[at.stays.astype(bool)]
            rows.append(
                {
                    **dict(zip(keys, key, strict=True)),
                    "goal": goal,
                    "stay_share": float(at.stays.astype(bool).mean()),
                    "theta_min": float(stay.theta.min()) if len(stay) else np.nan,
                    "theta_max": float(stay.theta.max()) if len(stay) else np.nan,
                    "theta_range": float(np.ptp(stay.theta)) if len(stay) else 0.0,
                    "stroke_range": float(np.ptp(stay.stroke)) if len(stay) else 0.0,
                    "from_home": float((home.reached == goal).mean()) if len(home) else np.nan,
                    "all_reached": bool(all_reached),
                }
            )
    table = pd.DataFrame(rows)
    table["has_property"] = has_property(table)
    return table


def has_property(table: pd.DataFrame) -> pd.Series:
    """Per row of :func:`summary`: at least STAY_SHARE of the inputs stay and reach TILT_RANGE of tilt."""
    return (table.stay_share >= STAY_SHARE) & (table.theta_range >= TILT_RANGE)


def choose(table: pd.DataFrame) -> str:
    """The decoder the rule picks among ``table``'s (one task's :func:`summary`), by name.

    In order: every goal reached from home; the most goals with the property; the largest
    smallest share staying at a goal; the largest smallest tilt range. A tie keeps the
    decoder listed first.
    """
    if table.empty:
        raise ConfigError("no decoders to choose from")
    if table.task.nunique() != 1:
        raise ConfigError(f"choose among the decoders of one task, got tasks {sorted(table.task.unique())}")
    per = table.groupby("decoder", sort=False).agg(
        all_reached=("all_reached", "all"),
        goals=("has_property", "sum"),
        stay=("stay_share", "min"),
        tilt=("theta_range", "min"),
    )
    order = per.sort_values(["all_reached", "goals", "stay", "tilt"], ascending=False, kind="stable")
    return str(order.index[0])


def plot(frame: pd.DataFrame) -> Figure:
    """Per decoder (rows) and goal (columns): the share of inputs that stay, and the tilt they reach.

    Left, the share of the ring's inputs that stay at each goal with a confident belief;
    middle, the range of tilt the staying inputs reach; right, the share of inputs that
    reach each goal from home with an uncertain belief. Cells where the decoder has the
    property are framed in red. Where a task has several decoders, the one :func:`choose`
    picks is starred.
    """
    table = summary(frame)
    table["row"] = table.task + " · " + table.robot + " · " + table.decoder
    for name, part in table.groupby("task"):
        if part.decoder.nunique() > 1:
            star = (table.task == name) & (table.decoder == choose(part))
            table.loc[star, "row"] = table.loc[star, "row"] + " ★"
    tasks = list(dict.fromkeys(table.task))
    heights = [table[table.task == t].row.nunique() + 1.2 for t in tasks]
    n_goals = max(table[table.task == t].goal.nunique() for t in tasks)
    sns.set_theme(style="white")
    fig, axes = plt.subplots(
        len(tasks),
        3,
        figsize=(4.2 + 3 * 0.9 * n_goals, 0.9 + 0.38 * sum(heights)),
        gridspec_kw={"height_ratios": heights},
        squeeze=False,
    )
    panels = (
        ("stay_share", "share of inputs that stay\n(confident belief)", "viridis"),
        ("theta_range", "tilt range the staying inputs reach\n(confident belief)", "magma"),
        ("from_home", "share of inputs that reach the goal\nfrom home (uncertain belief)", "cividis"),
    )
    for row_axes, name in zip(axes, tasks, strict=True):
        part = table[table.task == name]
        rows = list(dict.fromkeys(part.row))
        goals = list(dict.fromkeys(part.goal))
        ok = part.pivot(index="row", columns="goal", values="has_property").reindex(index=rows, columns=goals)
        for ax, (column, title, cmap) in zip(row_axes, panels, strict=True):
            grid = part.pivot(index="row", columns="goal", values=column).reindex(index=rows, columns=goals)
            sns.heatmap(
                grid.astype(float),
                ax=ax,
                vmin=0.0,
                vmax=1.0,
                cmap=cmap,
                annot=True,
                fmt=".2f",
                cbar=False,
                linewidths=0.5,
                linecolor="white",
                annot_kws={"fontsize": 8},
            )
            ax.set_title(title, fontsize=9)
            ax.set_xlabel(f"goal ({name})")
            ax.set_ylabel("")
            if column != "from_home":
                for i, r in enumerate(rows):
                    for j, g in enumerate(goals):
                        if ok.loc[r, g] is True or ok.loc[r, g] == 1:
                            ax.add_patch(plt.Rectangle((j, i), 1, 1, fill=False, edgecolor="red", lw=2))
            if column != "stay_share":
                ax.set_yticklabels([])
    fig.suptitle(
        f"The latent-action property (Sec. III). Red frame: the decoder has it at that goal (at least "
        f"{STAY_SHARE:.0%} of inputs stay, reaching a tilt range of at least {TILT_RANGE}); "
        "★: the rule's choice",
        fontsize=10,
    )
    fig.tight_layout()
    return fig
