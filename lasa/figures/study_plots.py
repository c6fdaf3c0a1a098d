"""The eating study's three figures (notebook 11): Goal Error, Total and Idle Time, Preference Alignment.

Each is a :class:`FigureSpec` (:data:`GOAL_ERROR`, :data:`TIME`, :data:`ALIGNMENT`), the shape
:func:`lasa.evidence.publish.publish` takes: its file stem, the columns of its CSV (the tidy
tables of :func:`lasa.figures.study.run`) and its plot, which draws one reading
(:func:`lasa.figures.study.for_member`) with the paper's result beside it (:data:`PAPER_H`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import matplotlib.patches as mpatches
import matplotlib.pyplot as plt
import pandas as pd
import seaborn as sns
from matplotlib.figure import Figure

from lasa.base.conditions import CONDITIONS
from lasa.evidence.plots import wrap_to
from lasa.figures.study import for_member

__all__ = [
    "FigureSpec",
    "ROW_KEYS",
    "GOAL_ERROR",
    "TIME",
    "ALIGNMENT",
    "PAPER_H",
    "plot_goal_error",
    "plot_time",
    "plot_alignment",
]

PALETTE = {"R": "#8c8c8c", "R+SA": "#4c72b0", "LA": "#dd8452", "LA+SA": "#55a868"}


@dataclasses.dataclass(frozen=True)
class FigureSpec:
    """One of the study's figures, in the shape :func:`lasa.evidence.publish.publish` takes."""

    NAME: str
    COLUMNS: tuple[str, ...]
    plot: Callable[..., Figure]


# every interval the study's figures draw: a 95% bootstrap CI, seeded so the PNG is the same run after run
CI = {"errorbar": ("ci", 95), "seed": 0}


# what the paper reports for each hypothesis (Sec. VI), as the figures label their reference
PAPER_H = {
    "h1": "paper: F(1,18) = 29.9, p < .001 (H1: the SA conditions lower Goal Error, R+SA < R and LA+SA < LA)",
    "h2": "paper (H2): in the scoop phase LA+SA's alignment is above R+SA's",
    "h3": "paper (H3): LA+SA fastest, Total and Idle Time (p < .05)",
}


def _reading(member: str, decoder: str | None) -> str:
    """The figures' caption of what they show: the SA member, and the decoder reading if named."""
    return f"SA = {member}" + (f"; decoder = {decoder}" if decoder else "")


def plot_goal_error(
    frame: pd.DataFrame, member: str = "hindsight", decoder: str | None = None, model: str | None = None
) -> Figure:
    """Fig. error: Goal Error per condition and task (bars: mean, 95% CI; dots: participants).

    The title's second line is the paper's H1 result and ordering (:data:`PAPER_H`).
    """
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member, decoder=decoder, model=model)
    fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
    sns.barplot(
        data=data,
        x="task",
        y="goal_error",
        hue="condition",
        hue_order=CONDITIONS,
        palette=PALETTE,
        **CI,
        ax=ax,
        alpha=0.85,
    )
    sns.stripplot(
        data=data,
        x="task",
        y="goal_error",
        hue="condition",
        hue_order=CONDITIONS,
        palette=PALETTE,
        dodge=True,
        size=2.5,
        jitter=False,  # seaborn jitters with an unseeded generator: the PNG would change run to run
        color="k",
        ax=ax,
        legend=False,
        alpha=0.5,
    )
    ax.set_ylabel("Goal Error [m s]")
    what = f"Goal Error ({data.participant.nunique()} simulated participants; {_reading(member, decoder)})"
    ax.set_title(f"{wrap_to(what, 5.0, 10)}\n{wrap_to(PAPER_H['h1'], 5.0, 10)}", fontsize=10)
    return fig


def plot_time(
    frame: pd.DataFrame,
    member: str = "hindsight",
    decoder: str | None = None,
    model: str | None = None,
    horizon: float | None = None,
) -> Figure:
    """Fig. time: Total Time (solid) and Idle Time (light) per condition and task, means with 95% CI.

    A bar whose episodes did not all finish within the horizon is hatched (censored: cut at
    the horizon), and every bar says which share finished. ``horizon`` [s] names the horizon
    (default: the longest unfinished episode's time); the last line is the paper's H3 (:data:`PAPER_H`).
    """
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member, decoder=decoder, model=model)
    if horizon is None:
        cut = data.total_time[~data.completed.astype(bool)]
        horizon = float(cut.max()) if len(cut) else math.nan
    fig, axes = plt.subplots(1, 2, figsize=(9, 4.6), sharey=True, layout="constrained")
    for ax, task in zip(axes, ("Entree", "Dessert"), strict=True):
        _time_bars(ax, data[data.task == task])
        ax.set_title(f"{task}: total (solid) and idle (light)", fontsize=10)
        ax.set_ylabel("time [s]")
    axes[0].set_ylim(top=1.08 * axes[0].get_ylim()[1])  # room for the labels above the tallest bar
    censored = mpatches.Patch(facecolor="white", edgecolor="0.3", hatch="///", label="")
    when = "" if math.isnan(horizon) else f" {horizon:g} s"
    fig.legend(
        [censored],
        [f"hatched: censored at the{when} horizon (not every episode finished); text: share finished"],
        loc="outside lower center",
        frameon=False,
        fontsize=8,
    )
    what = _reading(member, decoder) + (f"; participant model = {model}" if model else "")
    title = wrap_to(f"{data.participant.nunique()} simulated participants; {what}", 9, 10)
    fig.suptitle(f"{title}\n{wrap_to(PAPER_H['h3'], 9, 10)}", fontsize=10)
    return fig


def _time_bars(ax: plt.Axes, part: pd.DataFrame) -> None:
    """One task's bars: Total Time per condition (hatched where censored), Idle Time over it."""
    sns.barplot(
        data=part,
        x="condition",
        y="total_time",
        order=CONDITIONS,
        palette=PALETTE,
        hue="condition",
        **CI,
        ax=ax,
        legend=False,
    )
    _mark_censored(ax, part.groupby("condition").completed.mean())
    sns.barplot(
        data=part,
        x="condition",
        y="idle_time",
        order=CONDITIONS,
        color="white",
        **CI,
        ax=ax,
        alpha=0.6,
    )


def _mark_censored(ax: plt.Axes, done: pd.Series) -> None:
    """Hatch each bar (the axes' patches, one per condition) whose share finished is below 1; label each."""
    for bar in [p for p in ax.patches if isinstance(p, mpatches.Rectangle)]:
        i = round(bar.get_x() + bar.get_width() / 2)
        if math.isnan(bar.get_height()) or not 0 <= i < len(CONDITIONS) or CONDITIONS[i] not in done:
            continue
        share = float(done[CONDITIONS[i]])
        if share < 1:
            bar.set_hatch("///")
            bar.set_edgecolor("0.3")
        ax.annotate(
            f"{100 * share:.0f}% done",
            (bar.get_x() + bar.get_width() / 2, bar.get_height()),
            xytext=(0, 2),
            textcoords="offset points",
            ha="center",
            va="bottom",
            fontsize=7,
        )


def plot_alignment(
    frame: pd.DataFrame, member: str = "hindsight", decoder: str | None = None, model: str | None = None
) -> Figure:
    """Fig. dessert (left): Preference Alignment per Dessert phase, every condition (the paper: 2 of them).

    The shaded scoop phase is labelled with the paper's H2 ordering there (:data:`PAPER_H`).
    """
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member, decoder=decoder, model=model)
    data = data[(data.task == "Dessert") & data.phase.isin(["stab", "scoop", "dip"])]
    fig, ax = plt.subplots(figsize=(7.6, 4.0), layout="constrained")
    sns.pointplot(
        data=data,
        x="phase",
        y="alignment",
        hue="condition",
        hue_order=CONDITIONS,
        order=["stab", "scoop", "dip"],
        palette=PALETTE,
        **CI,
        dodge=0.3,
        ax=ax,
    )
    ax.set_ylabel("Preference Alignment (d · d*)")
    ax.axvspan(0.6, 1.4, color="0.92", zorder=0, label=wrap_to(PAPER_H["h2"], 1.8, 8))  # the scoop phase
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    what = f"Dessert: alignment with each phase's preference ({_reading(member, decoder)})"
    ax.set_title(wrap_to(what, 4.5, 10), fontsize=10)
    return fig


# every table's keys: who, under which condition, SA member, decoder reading and participant model, which task
ROW_KEYS = ("robot", "participant", "condition", "assistance", "decoder", "model", "task")
GOAL_ERROR = FigureSpec(
    "study_goal_error",
    (*ROW_KEYS, "order", "goal_error", "goal_error_bowls", "mean_distance"),
    plot_goal_error,
)
TIME = FigureSpec(
    "study_time", (*ROW_KEYS, "order", "total_time", "idle_time", "mode_switches", "completed"), plot_time
)
ALIGNMENT = FigureSpec(
    "study_alignment", (*ROW_KEYS, "phase", "preference", "alignment", "steps"), plot_alignment
)
