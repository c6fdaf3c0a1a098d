"""Fig. sim4's figure: the grasp error at new cups against their distance, per kind of map, per robot."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from mpl_toolkits.axes_grid1 import make_axes_locatable

from lasa.evidence import verdicts
from lasa.evidence.plots import paper_slope, robots_present, users_text, wrap_to
from lasa.experiments import sweep
from lasa.experiments.sim4.analysis import end_shares, equation, fits

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
    side = make_axes_locatable(ax).append_axes("right", size="38%", pad=0.6)  # every episode's error
    for kind, (color, name, marker, dashes, dx) in H_STYLES.items():
        if kind not in table.index:
            continue
        part = frame[frame.h == kind]
        side.scatter(part.distance, part.error, s=5, color=color, alpha=0.35, lw=0, label=name)
        cups = _cup_means(part)
        bars = [cups["mean"] - cups.low, cups.high - cups["mean"]]
        ax.errorbar(
            cups.distance + dx, cups["mean"], yerr=bars, fmt=marker, color=color, zorder=3, **MEAN_STYLE
        )
        ax.scatter(
            cups.distance + dx, cups["median"], marker=marker, edgecolors=color, zorder=4, **MEDIAN_STYLE
        )
        f = table.loc[kind]
        label = f"{name}: {equation(f, 2)}, R² = {f.r2:.2f}"
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
    if share := other_share_text(frame):
        ax.text(0.02, 0.98, share, transform=ax.transAxes, va="top", fontsize=7, wrap=True)
    for slope, (label, ls) in PAPER_LINES.items():
        paper_slope(ax, slope, label, x_max=1.05, ls=ls, lw=1.8, zorder=6)
    ax.set_xlim(0, 1.05)
    ax.set_ylim(min(bottoms) - 0.02 * max(tops), max(1.1, max(tops) * 1.08))
    ax.set_xlabel(f"distance of the new cup from the training cup (normalised)\n{PAPER_UNITS}", fontsize=8)
    ax.set_ylabel("grasp error at the gripper (normalised)")
    ax.legend(frameon=False, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.2))
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
    return ax


def other_share_text(frame: pd.DataFrame) -> str:
    """The share of no-map users whose belief ends on the other training cup, at the nearest and the
    farthest cup (:func:`end_shares`); empty without ``end_goal`` or no-map rows."""
    if "end_goal" not in frame or not (frame.h == "none").any():
        return ""
    other = end_shares(frame).loc["none", "other"]
    return (
        f"without the map, belief ends on the other training cup:\n{100 * other.iloc[0]:.0f}% of users at "
        f"the nearest cup, {100 * other.iloc[-1]:.0f}% at the farthest"
    )


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
