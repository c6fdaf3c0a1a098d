"""Panels that several figures share: data and ``ax=None`` in, axes out (a planar arm in its x-z
plane, the Panda from above)."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.colors import LinearSegmentedColormap, Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Rectangle

from lasa.method.dataset import Demonstrations
from lasa.world.goals import GoalTask
from lasa.world.robot import ROBOTS
from lasa.world.task import CupTask

METHOD_COLORS = {"LA": "#d95f02", "LA+SA": "#1b9e77", "LA+SA+Entropy": "#7570b3"}
# Every goal's colour, in goal order: the two cups', the blue of a new cup's render, then more.
GOAL_COLORS = ("#e6553f", "#3f9959", "#4073d9", "#d9a02b", "#8c5bbf", "#3fb3b3", "#bf4f8f", "#7a7a7a")


def goal_colors(n_goals: int) -> tuple[str, ...]:
    """A colour for each of ``n_goals`` goals: :data:`GOAL_COLORS` in turn, repeated past its end."""
    return tuple(GOAL_COLORS[g % len(GOAL_COLORS)] for g in range(n_goals))


def belief_cmap(n_goals: int, goal_index: int) -> LinearSegmentedColormap:
    """The colour map of the belief in goal ``goal_index``: the goal's colour at 1, the other cup's
    (grey with more than two goals) at 0; a ValueError if ``goal_index`` is not a goal."""
    if not 0 <= goal_index < n_goals:
        raise ValueError(f"goal_index must be one of the {n_goals} goals, got {goal_index}")
    colors, name = goal_colors(n_goals), f"belief_in_goal_{goal_index}"
    low = colors[1 - goal_index] if n_goals == 2 else "#7a7a7a"
    return LinearSegmentedColormap.from_list(name, [low, "#dddddd", colors[goal_index]])


def is_planar(task: GoalTask) -> bool:
    """Whether the robot moves in the world's x-z plane (every cup at y = 0)."""
    return bool(np.allclose(task.robot.goal_positions()[:, 1], 0.0))


def project(task: GoalTask, points: np.ndarray) -> np.ndarray:
    """World points (..., 3) onto the task's drawing plane, (..., 2): a planar arm's x-z plane, any
    other robot from above with its left on the left, (-y, x)."""
    points = np.asarray(points)
    return points[..., [0, 2]] if is_planar(task) else np.stack([-points[..., 1], points[..., 0]], axis=-1)


def draw_scene(task: GoalTask, ax: Axes | None = None) -> Axes:
    """The goals (cups), each in its colour, and the robot's base in the task's drawing plane."""
    ax = plt.gca() if ax is None else ax
    cups = task.robot.goal_positions()
    colors = goal_colors(len(cups))
    if is_planar(task):
        ax.axhline(0.0, color="#8b6d4b", lw=2, zorder=0)
        for (x, _, _), color in zip(cups, colors, strict=True):
            ax.add_patch(Rectangle((x - 0.035, 0.0), 0.07, 0.12, color=color, alpha=0.8, zorder=1))
        ax.add_patch(Rectangle((-0.06, 0.0), 0.12, 0.12, color="#40444c", zorder=1))
        ax.set_xlabel("x [m]")
        ax.set_ylabel("z [m]")
    else:
        for cup, color in zip(project(task, cups), colors, strict=True):
            ax.add_patch(Circle(tuple(cup), 0.035, color=color, alpha=0.8, zorder=1))
        ax.add_patch(Circle(tuple(project(task, task.robot.base_position())), 0.06, color="#40444c"))
        ax.set_xlabel("left <- -y [m] -> right")
        ax.set_ylabel("x (forward) [m]")
    ax.set_aspect("equal")
    return ax


def frame_around(task: GoalTask, ax: Axes, points: np.ndarray, pad: float = 0.08) -> None:
    """Limit the axes to the drawn points, the goals and the base, with some padding."""
    cups = project(task, task.robot.goal_positions())
    base = project(task, task.robot.base_position())[None]
    pts = np.concatenate([points.reshape(-1, 2), cups, base])
    lo, hi = pts.min(axis=0) - pad, pts.max(axis=0) + pad
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(min(lo[1], -0.05) if is_planar(task) else lo[1], hi[1])


def plot_demonstrations(
    task: CupTask, demos: Demonstrations, ax: Axes | None = None, goal_index: int = 1
) -> Axes:
    """Grasp-site paths of the clean demonstrations, coloured by the belief in cup ``goal_index``."""
    ax = draw_scene(task, ax)
    clean = demos.clean()
    norm = Normalize(0.0, 1.0)
    cmap = belief_cmap(len(task.goal_names), goal_index)
    lc = None
    drawn = []
    for d in np.unique(clean.demo):
        m = clean.demo == d
        xy = project(task, task.robot.grasp_positions(clean.states[m]))
        drawn.append(xy)
        lc = LineCollection(list(np.stack([xy[:-1], xy[1:]], axis=1)), cmap=cmap, norm=norm, lw=0.9)
        lc.set_array(clean.beliefs[m, goal_index][:-1])
        ax.add_collection(lc)
    if lc is not None:
        plt.colorbar(lc, ax=ax, label=f"belief in the {task.goal_names[goal_index]} cup", shrink=0.8)
        frame_around(task, ax, np.concatenate(drawn))
    return ax


TRAIN_COLOR, VAL_COLOR = "#1f77b4", "#d95f02"  # the training curves: loss (left axis), error (right)


def plot_training_curves(history: pd.DataFrame, ax: Axes | None = None) -> tuple[Axes, Axes]:
    """Training loss (left, in sigma_h^2 plus the sector term) and held-out error ||e_a||^2 (right,
    (rad/s)^2) against optimiser step, each on a log axis of its own; returns both axes."""
    ax = plt.gca() if ax is None else ax
    twin = ax.twinx()
    ax.plot(history["step"], history["train_loss"], color=TRAIN_COLOR, label="training loss")
    twin.plot(history["step"], history["val_error"], color=VAL_COLOR, ls="--", label="held-out error")
    labels = (
        (ax, TRAIN_COLOR, "training loss [-] ($\\|e_a\\|^2 / \\sigma_h^2$ + sector)"),
        (twin, VAL_COLOR, "held-out $\\|e_a\\|^2$ [(rad/s)$^2$]"),
    )
    for axes, color, text in labels:
        axes.set_yscale("log")
        axes.set_ylabel(text, color=color)
        axes.tick_params(axis="y", which="both", colors=color)
    ax.set_xlabel("optimiser step")
    lines = [*ax.get_lines(), *twin.get_lines()]
    ax.legend(lines, [str(line.get_label()) for line in lines], frameon=False)
    return ax, twin


def robots_present(table: pd.DataFrame) -> list[str]:
    """The robots with rows in ``table``, in the built-in robots' order (``lasa.world.robot.ROBOTS``)."""
    have = set(table.robot)
    return [name for name in ROBOTS if name in have]


def robot_rows(
    table: pd.DataFrame, n_cols: int, figsize_per_row: tuple[float, float]
) -> tuple[Figure, list[tuple[str, pd.DataFrame, np.ndarray]]]:
    """A figure with a row of ``n_cols`` panels per robot in ``table``; each robot's name, rows and axes."""
    present = robots_present(table)
    width, height = figsize_per_row
    fig, axes = plt.subplots(len(present), n_cols, figsize=(width, height * len(present)), squeeze=False)
    return fig, [(name, table[table.robot == name], row) for name, row in zip(present, axes, strict=True)]


def method_lineplot(frame: pd.DataFrame, x: str, y: str, ax: Axes | None = None, level: float = 0.95) -> Axes:
    """``y`` against ``x`` per method, in the methods' colours, with bootstrap bands at ``level`` of
    the mean over the rows (users) at that ``x``, 1000 resamples from a fixed seed."""
    ax = plt.gca() if ax is None else ax
    methods = [m for m in METHOD_COLORS if m in set(frame.method)]
    hue: dict[str, Any] = {"hue": "method", "hue_order": methods, "palette": METHOD_COLORS}
    marker = "o" if frame[x].nunique() < 30 else None
    sns.lineplot(
        data=frame, x=x, y=y, errorbar=("ci", 100.0 * level), n_boot=1000, seed=0, ax=ax, marker=marker, **hue
    )
    ax.legend(frameon=False, title=None)
    return ax


def band_handle(level: float) -> Patch:
    """A legend entry that says what the bands are: bootstrap intervals over users at ``level``."""
    return Patch(color="0.5", alpha=0.3, lw=0, label=f"bands: {100 * level:.4g}% bootstrap CI over users")


def legend_below(ax: Axes, extra: Sequence[Artist] = ()) -> None:
    """The axes' legend, plus ``extra`` entries, below the axes, where it covers no data."""
    handles, labels = ax.get_legend_handles_labels()
    handles, labels = [*handles, *extra], [*labels, *(h.get_label() for h in extra)]
    ax.legend(handles, labels, frameon=False, fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.17))


def users_text(table: pd.DataFrame, keys: Sequence[str], per: str = "point") -> str:
    """A title's N, distinct users over the groups of ``keys``: ``"150 users per point"``, or per
    robot ``"users per point: planar5 60, panda 150"``; a range ``60–150`` where groups differ."""
    counts = table.groupby(["robot", *keys])["seed"].nunique()
    spans = {r: (int(counts[r].min()), int(counts[r].max())) for r in robots_present(table)}
    text = {r: f"{lo}" if lo == hi else f"{lo}–{hi}" for r, (lo, hi) in spans.items()}
    if len(set(text.values())) == 1:
        return f"{next(iter(text.values()))} users per {per}"
    return f"users per {per}: " + ", ".join(f"{r} {n}" for r, n in text.items())


# the paper's numbers and orderings, drawn the same way in every figure: black, dotted, labelled
PAPER_STYLE: dict[str, Any] = {"color": "0.1", "ls": ":", "lw": 1.3, "zorder": 4}


def paper_handle(text: str) -> Line2D:
    """A legend entry in the paper's style (:data:`PAPER_STYLE`) for an ordering the paper states."""
    return Line2D([], [], label=text, **PAPER_STYLE)


def paper_slope(ax: Axes, slope: float, label: str, x_max: float = 1.0, **style: Any) -> Line2D:
    """The paper's line ``y = slope * x`` through the origin, drawn on [0, x_max], labelled."""
    xs = np.array([0.0, x_max])
    (line,) = ax.plot(xs, slope * xs, label=label, **{**PAPER_STYLE, **style})
    return line


def paper_point(ax: Axes, x: float, y: float, label: str, tolerance: float, tol_label: str | None) -> Line2D:
    """The paper's value ``y`` at ``x``: a star, labelled (``label``) in the legend and beside it, and
    y +- ``tolerance`` faintly, labelled ``tol_label``."""
    band: dict[str, Any] = {"fmt": "none", "ecolor": "0.1", "alpha": 0.3, "elinewidth": 6, "capsize": 0}
    ax.errorbar([x], [y], yerr=tolerance, label=tol_label, zorder=3, **band)
    (point,) = ax.plot([x], [y], marker="*", ms=11, ls="none", color="0.1", label=label, zorder=5)
    ax.annotate(f"paper {y:g}", (x, y), xytext=(7, 0), textcoords="offset points", fontsize=7, va="center")
    return point


def wrap_to(text: str, inches: float, fontsize: float = 12.0) -> str:
    """``text`` wrapped into lines that fit ``inches`` at ``fontsize`` [pt], a character taken as
    0.55 of the font size wide (a little more than most are)."""
    return textwrap.fill(text, max(20, int(inches * 72 / (0.55 * fontsize))))
