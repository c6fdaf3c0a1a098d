"""The eating study's figures (notebook 11) for :func:`lasa.evidence.publish.publish`: Goal Error, Total and
Idle Time, Preference Alignment of one member, decoder and model; the first :data:`PAPER_N` participants and
the cohort beside them, each panel with our result (``stats``); a censored bar hatched (a lower bound)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Hashable, Iterable, Mapping, Sequence
from typing import Any

import matplotlib.patches as mpatches
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure, SubFigure
from matplotlib.lines import Line2D

from lasa.base.conditions import CONDITIONS
from lasa.base.config import NO_ASSISTANCE
from lasa.base.errors import ConfigError
from lasa.evidence.hypotheses import for_member
from lasa.evidence.plots import wrap_to
from lasa.experiments.study.run import PAPER_N
from lasa.world.record import Episodes

PALETTE = {"R": "#8c8c8c", "R+SA": "#4c72b0", "LA": "#dd8452", "LA+SA": "#55a868"}
TASKS = ("Entree", "Dessert")
PHASES = ("stab", "scoop", "dip")  # the Dessert phases the alignment figure draws (the paper's three)

HEADLINE = "headline"  # the main panel, and its key in a plot's ``stats``: the first PAPER_N participants
COHORT = "cohort"  # the second panel, and its key in ``stats``: every participant of the table
PANELS = (HEADLINE, COHORT)
HATCH = "///"  # a censored bar's hatch
CUT = "hatched: some episodes cut at the horizon"
CENSORED = f"{CUT} (a lower bound)"  # what the legend says HATCH means
# Fig. time's whiskers, dodged so a bar's two intervals never merge: (offset [slot widths], colour)
WHISKERS = {"total_time": (-0.15, "0.15"), "idle_time": (0.15, "0.5")}
Stats = Mapping[str, str] | None  # our result per panel (HEADLINE, COHORT), a short line each
Bars = dict[Hashable, mpatches.Rectangle]  # a drawn bar by its group (a condition, or a (x level, condition))


@dataclasses.dataclass(frozen=True)
class FigureSpec:
    """One of the study's figures, in the shape :func:`lasa.evidence.publish.publish` takes."""

    NAME: str
    COLUMNS: tuple[str, ...]
    plot: Callable[..., Figure]


# every interval the study's figures draw: a 95% bootstrap CI, seeded so the PNG is the same run after run
CI_LEVEL = 95  # their level [%]
CI = {"errorbar": ("ci", CI_LEVEL), "seed": 0}


# what the paper reports for each hypothesis (Sec. VI), as the figures label their reference
PAPER_H = {
    "h1": "paper: F(1,18) = 29.9, p < .001 (H1: the SA conditions lower Goal Error, R+SA < R and LA+SA < LA)",
    "h2": "paper (H2): in the scoop phase LA+SA's alignment is above R+SA's",
    "h3": "paper (H3): LA+SA fastest, Total and Idle Time (p < .05)",
}


def _caption(assistance: str, decoder: str | None, model: str | None) -> str:
    said = {"SA": assistance, "decoder": decoder, "participant model": model}
    return "; ".join(f"{what} = {name}" for what, name in said.items() if name)


def _layout(
    data: pd.DataFrame, stats: Stats, size: tuple[float, float], draw: Callable[..., None], n_axes: int = 1
) -> tuple[Figure, list[Axes], int]:
    """A figure of a subfigure per panel (the first PAPER_N participants, and the whole table if it holds
    more), titled with its N and our result (``stats``), each of ``n_axes`` axes drawn by
    ``draw(rows, *axes)``; its axes and number of panels."""
    unknown = sorted(set(stats or {}) - set(PANELS))
    if unknown:
        raise ConfigError(f"stats keys must be among {PANELS}, got {unknown}")
    head = data[data.participant < PAPER_N]
    n = data.participant.nunique()
    panels = [(HEADLINE, head, f"first {head.participant.nunique()} simulated participants (the headline)")]
    if n > head.participant.nunique():
        panels.append((COHORT, data, f"cohort of {n} (a reading)"))
    sns.set_theme(style="whitegrid")
    width, height = size
    fig = plt.figure(figsize=(width * len(panels), height), layout="constrained")
    subs: Iterable[SubFigure] = fig.subfigures(1, len(panels), squeeze=False)[0]
    # the titles fit the panel beside a legend on the right (of the conditions, ~1.6 in), padded to one height
    titles = [
        "\n".join(wrap_to(t, width - 1.6, 10) for t in (what, (stats or {}).get(p)) if t)
        for p, _, what in panels
    ]
    lines = max(t.count("\n") for t in titles)
    grid = []
    for sub, title in zip(subs, titles, strict=True):
        sub.suptitle(title + "\n " * (lines - title.count("\n")), fontsize=10)
        grid.append(list(np.atleast_1d(sub.subplots(1, n_axes, sharey=True))))
    for (_, part, _), axes in zip(panels, grid, strict=True):
        draw(part, *axes)
    return fig, [ax for axes in grid for ax in axes], len(panels)


def _finish(
    fig: Figure,
    axes: Sequence[Axes],
    title: str,
    notes: Sequence[tuple[Artist, str]],
    keys: Sequence[Artist] | None = (),
) -> Figure:
    """Share the y range, title the figure, add the legends: ``notes`` below, colours and ``keys`` right."""
    top = max(ax.get_ylim()[1] for ax in axes)
    bottom = min(0.0, *(ax.get_ylim()[0] for ax in axes))
    for ax in axes:
        ax.set_ylim(bottom, 1.08 * top)  # room for the labels above the tallest bar
    if keys is not None:
        handles = [mpatches.Patch(facecolor=PALETTE[c], label=c) for c in CONDITIONS]
        fig.legend(handles=[*handles, *keys], loc="outside right center", frameon=False, fontsize=9)
    fig.legend(
        [h for h, _ in notes], [t for _, t in notes], loc="outside lower center", frameon=False, fontsize=8
    )
    fig.suptitle(title, fontsize=10)
    return fig


def _hatch_note(data: pd.DataFrame, horizon: float | None = None, also: str = "") -> tuple[Artist, str]:
    """The legend's entry for the hatch (:data:`CENSORED`, ``also`` another reason), or that it is unknown."""
    patch = mpatches.Patch(facecolor="white", edgecolor="0.3", hatch=HATCH)
    if "completed" not in data.columns:
        if also:
            return patch, f"hatched: {also} (completion not given)"
        return mpatches.Patch(visible=False), "completion not given: censored bars not marked"
    if also:
        return patch, f"{CUT}, or {also}"
    when = "" if horizon is None or math.isnan(horizon) else f"; censored at the {horizon:g} s horizon"
    return patch, f"{CUT} (a lower bound{when})"


def _with_completion(data: pd.DataFrame, completed: pd.DataFrame | None) -> pd.DataFrame:
    """``data`` with its episodes' ``completed`` (bool): its own, else joined from ``completed`` on the
    :data:`ROW_KEYS` both hold (a ConfigError if one has no row); without either, ``data`` as it is."""
    if "completed" in data.columns:
        return data.assign(completed=data.completed.astype(bool))
    if completed is None:
        return data
    keys = [k for k in ROW_KEYS if k in data.columns and k in completed.columns]
    joined = data.merge(completed[[*keys, "completed"]], on=keys, how="left", validate="many_to_one")
    missing = joined.completed.isna()
    if missing.any():
        raise ConfigError(
            f"completed has no row for {int(missing.sum())} of the figure's rows (joined on {keys})"
        )
    return joined.assign(completed=joined.completed.astype(bool))


def _censored(part: pd.DataFrame, by: Sequence[str]) -> dict[Hashable, bool]:
    """Per group of ``by``: whether an episode is unfinished."""
    if "completed" not in part.columns:
        return {}
    done = part.groupby(list(by)).completed.all()
    return {key: not bool(ok) for key, ok in done.items()}


def _bars_at(patches: Iterable[Artist], levels: Sequence[str], hues: Sequence[str] = ()) -> Bars:
    """The drawn bars (rectangles of a finite height) by their group: seaborn centres a level's bar at 0, 1,
    ...; with hues, a (level, hue)'s bar dodged over 0.8 of a level."""
    slots: dict[Hashable, float] = {level: float(i) for i, level in enumerate(levels)}
    if hues:
        w = 0.8 / len(hues)
        slots = {(lv, h): i - 0.4 + w * (j + 0.5) for i, lv in enumerate(levels) for j, h in enumerate(hues)}
    bars: Bars = {}
    for bar in patches:
        if not isinstance(bar, mpatches.Rectangle) or math.isnan(bar.get_height()):
            continue
        centre = bar.get_x() + bar.get_width() / 2
        for key, x in slots.items():
            if abs(centre - x) < 0.02:
                bars[key] = bar
    return bars


def _hatch(bars: Bars, censored: Mapping[Hashable, bool]) -> None:
    """Hatch the bars of the censored groups (the others are left as they are)."""
    for key, bar in bars.items():
        if censored.get(key, False):
            bar.set_hatch(HATCH)
            bar.set_edgecolor("0.3")


def plot_goal_error(
    frame: pd.DataFrame,
    assistance: str = "hindsight",
    decoder: str | None = None,
    model: str | None = None,
    stats: Stats = None,
    completed: pd.DataFrame | None = None,
) -> Figure:
    """Fig. error: Goal Error per condition and task (bars: mean, 95% CI; dots: participants) of the SA
    member ``assistance``, ``decoder`` and ``model`` (None: every row); ``stats``: our result per panel;
    ``completed``, the Time table, marks the censored bars."""
    data = _with_completion(for_member(frame, assistance, decoder=decoder, model=model), completed)
    fig, axes, n = _layout(data, stats, (5.6, 4.4), _goal_error_axes)
    paper = wrap_to(PAPER_H["h1"], 5.6 * n, 10)
    title = f"Goal Error ({_caption(assistance, decoder, model)})\n{paper}"
    return _finish(fig, axes, title, [_hatch_note(data)])


def _goal_error_axes(part: pd.DataFrame, ax: Axes) -> None:
    """One panel of Goal Error: bars per task x condition (censored ones hatched), a dot per participant."""
    before = len(ax.patches)
    kwargs = {"x": "task", "y": "goal_error", "order": TASKS, "hue": "condition", "hue_order": CONDITIONS}
    sns.barplot(data=part, **kwargs, palette=PALETTE, **CI, ax=ax, alpha=0.85, legend=False)
    _hatch(_bars_at(ax.patches[before:], TASKS, CONDITIONS), _censored(part, ("task", "condition")))
    # no jitter: seaborn jitters with an unseeded generator, and the PNG would change run to run
    dots = {"dodge": True, "size": 2.5, "jitter": False, "legend": False, "alpha": 0.5}
    sns.stripplot(data=part, **kwargs, palette=PALETTE, **dots, ax=ax)
    ax.set_xlabel("task")
    ax.set_ylabel("Goal Error [m s]")


def plot_time(
    frame: pd.DataFrame,
    assistance: str = "hindsight",
    decoder: str | None = None,
    model: str | None = None,
    horizon: float | None = None,
    stats: Stats = None,
) -> Figure:
    """Fig. time: Total (solid) and Idle Time (light) per condition and task, means with 95% CI, each
    bar's share finished; ``horizon`` [s] defaults to the longest unfinished episode's time."""
    data = _with_completion(for_member(frame, assistance, decoder=decoder, model=model), None)
    if horizon is None:
        cut = data.total_time[~data.completed]
        horizon = float(cut.max()) if len(cut) else math.nan
    fig, axes, n = _layout(data, stats, (7.6, 4.8), _time_axes, n_axes=len(TASKS))
    idle = mpatches.Patch(facecolor="0.85", edgecolor="white")
    notes: list[tuple[Artist, str]] = [(idle, "light: Idle Time; text: share of episodes finished")]
    for m, (dx, colour) in WHISKERS.items():  # "Total Time's 95% CI: whisker left of the bar's centre"
        what = f"{m.replace('_', ' ').title()}'s {CI_LEVEL:g}% CI: whisker {'left' if dx < 0 else 'right'}"
        notes.append((Line2D([], [], color=colour, lw=2), f"{what} of the bar's centre"))
    notes.insert(0, _hatch_note(data, horizon))
    title = wrap_to(f"Total and Idle Time ({_caption(assistance, decoder, model)})", 7.6 * n, 10)
    title += f"\n{wrap_to(PAPER_H['h3'], 7.6 * n, 10)}"
    return _finish(fig, axes, title, notes, keys=None)


def _time_axes(part: pd.DataFrame, *axes: Axes) -> None:
    """One panel of Fig. time, an axes per task: Total Time per condition (hatched if censored; its share
    finished), Idle over it."""
    for ax, task in zip(axes, TASKS, strict=True):
        rows = part[part.task == task]
        before, lines = len(ax.patches), len(ax.lines)
        common = {"data": rows, "x": "condition", "order": CONDITIONS, **CI, "ax": ax}
        sns.barplot(**common, y="total_time", palette=PALETTE, hue="condition", legend=False)
        bars = _bars_at(ax.patches[before:], CONDITIONS)
        _hatch(bars, _censored(rows, ("condition",)))
        done = rows.groupby("condition").completed.mean()
        for condition, bar in bars.items():
            if condition in done:
                _label(ax, bar, f"{100 * float(done[condition]):.0f}% done")
        _whiskers(ax.lines[lines:], "total_time")
        lines = len(ax.lines)
        sns.barplot(**common, y="idle_time", color="white", alpha=0.6)
        _whiskers(ax.lines[lines:], "idle_time")
        ax.set_title(f"{task}: total (solid) and idle (light)", fontsize=10)
        ax.set_ylabel("time [s]")


def _whiskers(lines: Iterable[Line2D], measure: str) -> None:
    """Move a measure's whiskers (seaborn's error bars) by its :data:`WHISKERS` offset, in its colour."""
    dx, colour = WHISKERS[measure]
    for line in lines:
        line.set_xdata(np.asarray(line.get_xdata(), dtype=float) + dx)
        line.set_color(colour)
        line.set_gid(measure)


def _label(ax: Axes, bar: mpatches.Rectangle, text: str, foot: bool = False) -> None:
    """A small label at a bar's centre: just above its top, or (``foot``) upright, boxed, at its foot."""
    at = (bar.get_x() + bar.get_width() / 2, 0.0 if foot else bar.get_height())
    box = {"boxstyle": "round,pad=0.15", "facecolor": "white", "edgecolor": "none", "alpha": 0.8}
    style: dict[str, Any] = {"textcoords": "offset points", "ha": "center", "va": "bottom", "fontsize": 7}
    style |= {"rotation": 90 if foot else 0, "bbox": box if foot else None}
    ax.annotate(text, at, xytext=(0, 3 if foot else 2), **style)


def plot_alignment(
    frame: pd.DataFrame,
    assistance: str = "hindsight",
    decoder: str | None = None,
    model: str | None = None,
    stats: Stats = None,
    completed: pd.DataFrame | None = None,
) -> Figure:
    """Fig. dessert (left): Preference Alignment per Dessert phase and condition, scoop shaded; each bar
    says its n and is hatched where someone did not reach the phase or finish."""
    data = for_member(frame, assistance, decoder=decoder, model=model)
    data = data[(data.task == "Dessert") & data.phase.isin(PHASES)]
    data = _with_completion(data, completed)
    fig, axes, n = _layout(data, stats, (6.6, 4.4), _alignment_axes)
    scoop = mpatches.Patch(facecolor="0.92", label="shaded: the scoop phase (H2)")
    count = (mpatches.Patch(visible=False), "n (at a bar's foot): participants who reached the phase")
    notes = [_hatch_note(data, also="some participant did not reach the phase"), count]
    title = f"Dessert: alignment with each phase's preference ({_caption(assistance, decoder, model)})"
    title = f"{wrap_to(title, 6.6 * n, 10)}\n{PAPER_H['h2']}"
    return _finish(fig, axes, title, notes, keys=[scoop])


def _alignment_axes(part: pd.DataFrame, ax: Axes) -> None:
    """One panel of alignment: bars per phase x condition, hatched where censored, each with its n."""
    ax.axvspan(0.5, 1.5, color="0.92", zorder=0)  # the scoop phase
    before = len(ax.patches)
    hues = {"hue": "condition", "hue_order": CONDITIONS, "palette": PALETTE, **CI}
    sns.barplot(data=part, x="phase", y="alignment", order=PHASES, **hues, ax=ax, legend=False)
    # per (phase, condition): n who reached the phase (steps > 0), censored where not all or unfinished
    reached = part.steps > 0 if "steps" in part.columns else part.alignment.notna()
    groups = part.groupby(["phase", "condition"])
    of = groups.participant.nunique()
    n = part[reached].groupby(["phase", "condition"]).participant.nunique().reindex(of.index, fill_value=0)
    censored = n < of
    if "completed" in part.columns:
        censored |= ~groups.completed.all()
    bars = _bars_at(ax.patches[before:], PHASES, CONDITIONS)
    _hatch(bars, {key: bool(c) for key, c in censored.items()})
    for key, bar in bars.items():
        _label(ax, bar, f"n={int(n[key]) if key in n.index else 0}", foot=True)
    ax.set_ylabel("Preference Alignment (d · d*)")


def video_clips(
    episodes: Episodes, participant: int, assistance: str, stride: int, dt: float, task: str = "Dessert"
) -> list[tuple[np.ndarray, list[str]]]:
    """One participant's episode of ``task`` under each condition, every ``stride``-th state captioned with
    condition and time: :func:`lasa.evidence.video.write_clips`' clips."""
    clips = []
    for cond in CONDITIONS:
        asst = assistance if cond.endswith("+SA") else NO_ASSISTANCE
        hits = np.flatnonzero(
            (episodes.participant == participant)
            & (episodes.task == task)
            & (episodes.condition == cond)
            & (episodes.assistance == asst)
        )
        if not len(hits):
            raise ConfigError(f"no {task} episode of participant {participant} under {cond} ({asst})")
        e = int(hits[0])
        steps = np.arange(0, episodes.end[e] + 1, stride)
        clips.append((episodes.states[steps, e], [f"{cond}  t = {s * dt:.1f} s" for s in steps]))
    return clips


# every table's keys: who, under which condition, SA member, decoder variant and participant model, which task
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
