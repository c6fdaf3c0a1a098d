r"""The latent-action property (Sec. III): unsure, z chooses *which goal*; confident, *how* to act.

It holds at goal g when (**stay**) :data:`STAY_SHARE` of the inputs stay at g reaching a tilt range of
:data:`TILT_RANGE`, (**leave**) :data:`LEAVE_COUNT` of 64 inputs reach every other goal from each phase
end under LA+SA, and every goal is reached from home; a decoder meets the rule at every goal.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.figure import Figure

from lasa.base.errors import ConfigError

NAME = "latent_property"
KEY = "source"  # the CSV's rows are replaced per source (one notebook run's decoders)
COLUMNS = tuple(
    "source robot task decoder context goal z1 z2 drift stays theta stroke reached distance start "
    "condition target exit_time".split()
)
STAY_SHARE = 0.5  # share of the ring's inputs that must stay at a goal [-]
TILT_RANGE = 0.5  # tilt range the staying inputs must reach, as a share of [0, 1] [-]
LEAVE_COUNT = 7  # inputs of the ring's 64 (about 10%) that must reach each other goal, LA+SA [-]
CONDITIONS = ("LA", "LA+SA")  # the leave half's conditions: alpha = 0, and the control's alpha
DPI = 130
_KEYS = ("source", "robot", "task", "decoder")  # a decoder's rows
_SUMMARY = _KEYS + tuple(  # summary's columns but the three it derives from them
    "goal n_inputs stay_share theta_min theta_max theta_range stroke_range from_home all_reached "
    "leave_min leave_la_min".split()
)
# tasks whose decoders are one recipe at several settings, not alternatives: no choice (★) marked
SWEEP_TASKS = ("eating_caps",)
_HEATMAP = dict(
    annot=True, annot_kws={"fontsize": 8}, cbar_kws={"shrink": 0.8}, linewidths=0.5, linecolor="white"
)


def summary(frame: pd.DataFrame) -> pd.DataFrame:
    """One row per (source, robot, task, decoder, goal) of the measured rows: the share that stays,
    the staying inputs' tilt and stroke ranges, the share reached from home, the fewest inputs that
    leave (``leave_min`` under LA+SA, ``leave_la_min`` under LA), and whether each half holds."""
    rows = []
    for key, part in frame.groupby(list(_KEYS), sort=False):
        conf, home = (part[part.context == context] for context in ("confident", "uncertain"))
        counts = leave_table(part)
        goals = list(dict.fromkeys(conf.goal))
        all_reached = set(goals) <= set(home.reached)
        for goal in goals:
            at = conf[conf.goal == goal]
            stay = at[at.stays.astype(bool)]
            mine = counts[counts.goal == goal]
            least = [float(mine[mine.condition == c].inputs.min()) for c in CONDITIONS]  # NaN: none
            theta = [float(stay.theta.min()), float(stay.theta.max())] if len(stay) else [np.nan, np.nan]
            ranges = [float(np.ptp(stay.theta)), float(np.ptp(stay.stroke))] if len(stay) else [0.0, 0.0]
            home_share = float((home.reached == goal).mean()) if len(home) else np.nan
            stays = [len(at), float(at.stays.astype(bool).mean()), *theta, *ranges]
            rows.append([*key, goal, *stays, home_share, bool(all_reached), *least[::-1]])
    table = pd.DataFrame(rows, columns=list(_SUMMARY))  # no rows: the columns all the same
    table["stay_holds"] = stay_holds(table)
    table["leave_holds"] = table.leave_min >= LEAVE_COUNT * table.n_inputs / 64
    table["has_property"] = has_property(table)
    return table


def leave_table(frame: pd.DataFrame) -> pd.DataFrame:
    """The leave half, one row per (decoder, goal, phase end, condition, other goal): ``inputs`` that
    reach the other goal's set within the hold, ``exit_time`` their median first arrival [s]."""
    leave = frame[frame.context == "leave"]
    if leave.empty:
        return pd.DataFrame(columns=[*_KEYS, "goal", "start", "condition", "target", "inputs", "exit_time"])
    arrived = leave.assign(arrived=leave.reached == leave.target)
    return (
        arrived.groupby([*_KEYS, "goal", "start", "condition", "target"], sort=False)
        .agg(inputs=("arrived", "sum"), exit_time=("exit_time", "median"))
        .reset_index()
    )


def stay_holds(table: pd.DataFrame) -> pd.Series:
    """The stay half, per row of :func:`summary`: STAY_SHARE of the inputs stay and reach TILT_RANGE."""
    return (table.stay_share >= STAY_SHARE) & (table.theta_range >= TILT_RANGE)


def has_property(table: pd.DataFrame) -> pd.Series:
    """Per row of :func:`summary`: both halves hold at the goal, and every goal is reached from home."""
    return table.stay_holds & table.leave_holds & table.all_reached.astype(bool)


def holds(table: pd.DataFrame) -> pd.Series:
    """Per decoder of a :func:`summary`: whether the property holds at every goal (the rule)."""
    return table.groupby("decoder", sort=False).has_property.all()


def ranking(table: pd.DataFrame) -> pd.DataFrame:
    """The decoders of one task's :func:`summary`, best first: meeting the rule, every goal reached
    from home, goals with the property, goals with the stay half, the least leave count, the least
    share that stays, the least tilt range."""
    if table.empty:
        raise ConfigError("no decoders to choose from")
    if table.task.nunique() != 1:
        raise ConfigError(f"choose among the decoders of one task, got tasks {sorted(table.task.unique())}")
    per = table.groupby("decoder", sort=False).agg(
        meets=("has_property", "all"),
        all_reached=("all_reached", "all"),
        goals=("has_property", "sum"),
        stay_goals=("stay_holds", "sum"),
        leave=("leave_min", "min"),
        stay=("stay_share", "min"),
        tilt=("theta_range", "min"),
    )
    return per.sort_values(list(per.columns), ascending=False, kind="stable")  # by each column in turn


def choose(table: pd.DataFrame) -> str:
    """The decoder :func:`ranking` puts first (a tie: the one listed first), meeting the rule or not."""
    return str(ranking(table).index[0])


def plot(frame: pd.DataFrame) -> Figure:
    """Per decoder (rows) and goal (columns) four heatmaps: the share that stays, the staying tilt
    range, the fewest inputs that leave (LA+SA), the share reaching the goal from home. Red frames
    where a half holds, ★ the rule's choice among a task's decoders, ✓ a decoder meeting the rule."""
    table = summary(frame)
    table["row"] = table.task + " · " + table.robot + " · " + table.decoder
    meets = holds(table) if not table.empty else pd.Series(dtype=bool)
    table.loc[table.decoder.map(meets).fillna(False).astype(bool), "row"] += " ✓"
    for name, part in table.groupby("task"):
        if part.decoder.nunique() > 1 and name not in SWEEP_TASKS:
            star = (table.task == name) & (table.decoder == choose(part))
            table.loc[star, "row"] = table.loc[star, "row"] + " ★"
    tasks = list(dict.fromkeys(table.task))
    heights = [table[table.task == t].row.nunique() + 1.4 for t in tasks]
    n_goals = max(table[table.task == t].goal.nunique() for t in tasks)
    sns.set_theme(style="white")
    size = (5.0 + 4 * 0.9 * n_goals, 1.3 + 0.38 * sum(heights))
    ratios = {"height_ratios": heights}
    fig, axes = plt.subplots(len(tasks), 4, figsize=size, gridspec_kw=ratios, squeeze=False)
    for row_axes, name in zip(axes, tasks, strict=True):
        _plot_task(row_axes, table[table.task == name], name)
    fig.suptitle(
        "The latent-action property, both halves (Sec. III, IV-B). Red frame: the half holds at that goal\n"
        f"stay: at least {STAY_SHARE:.0%} of inputs stay, reaching a tilt range of at least {TILT_RANGE}; "
        f"leave: at least {LEAVE_COUNT} of 64 inputs reach every other goal within 10 s under LA+SA\n"
        "✓: the property holds at every goal (the rule); ★: the rule's choice among a task's decoders",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def _plot_task(row_axes: np.ndarray, part: pd.DataFrame, name: str) -> None:
    rows, goals = (list(dict.fromkeys(part[column])) for column in ("row", "goal"))
    n = int(part.n_inputs.max())
    stay, leave = "share of inputs that stay\n(confident belief)", f"fewest of {n} inputs that leave\n"
    tilt, home = "tilt range the staying inputs\nreach (confident belief)", "share of inputs that reach\n"
    panels = (
        ("stay_share", stay, "viridis", 1.0, ".2f", "stay_holds"),
        ("theta_range", tilt, "magma", 1.0, ".2f", "stay_holds"),
        ("leave_min", leave + "for another goal (LA+SA, 10 s)", "crest", n, ".0f", "leave_holds"),
        ("from_home", home + "the goal from home (uncertain)", "cividis", 1.0, ".2f", None),
    )
    for ax, (column, title, cmap, vmax, fmt, frame_by) in zip(row_axes, panels, strict=True):
        grid = part.pivot(index="row", columns="goal", values=column).reindex(index=rows, columns=goals)
        sns.heatmap(grid.astype(float), ax=ax, vmin=0.0, vmax=vmax, cmap=cmap, fmt=fmt, **_HEATMAP)
        ax.set_title(title, fontsize=9)
        ax.set(xlabel=f"goal ({name})", ylabel="")
        if frame_by is not None:
            ok = part.pivot(index="row", columns="goal", values=frame_by).reindex(index=rows, columns=goals)
            for i, j in np.argwhere(ok.to_numpy() == 1):
                ax.add_patch(plt.Rectangle((int(j), int(i)), 1, 1, fill=False, edgecolor="red", lw=2))
        if column != "stay_share":
            ax.set_yticklabels([])
