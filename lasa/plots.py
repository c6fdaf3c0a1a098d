"""Plot functions: data and ``ax=None`` in, axes out.

Each function draws one panel from data it is given (a frame, a dataset, paths), so a
notebook composes panels freely and the data behind each figure is saved beside it.
Planar-arm geometry is drawn in the arm's x-z plane, in metres.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.patches import Rectangle

from lasa.demos import Demonstrations
from lasa.task import CupTask

__all__ = [
    "METHOD_COLORS",
    "draw_scene",
    "plot_demonstrations",
    "plot_training_curves",
    "plot_held_paths",
    "plot_latent_meaning",
    "plot_sim1",
    "grasp_preference",
]

METHOD_COLORS = {"LA": "#d95f02", "LA+SA": "#1b9e77", "LA+SA+Entropy": "#7570b3"}
CUP_COLORS = ("#e6553f", "#3f9959")


def _ax(ax: Axes | None) -> Axes:
    return plt.gca() if ax is None else ax


def draw_scene(task: CupTask, ax: Axes | None = None) -> Axes:
    """The table, the cups and the arm's base, in the x-z plane."""
    ax = _ax(ax)
    ax.axhline(0.0, color="#8b6d4b", lw=2, zorder=0)
    for (x, _, _), color in zip(task.robot.cup_positions(), CUP_COLORS, strict=True):
        ax.add_patch(Rectangle((x - 0.035, 0.0), 0.07, 0.12, color=color, alpha=0.8, zorder=1))
    ax.add_patch(Rectangle((-0.06, 0.0), 0.12, 0.12, color="#40444c", zorder=1))
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    return ax


def grasp_preference(task: CupTask, states: np.ndarray) -> np.ndarray:
    """The grasp preference theta that the gripper's direction shows, shape (...).

    0 when the fingers point straight down, 1 when they point horizontally away from
    the base (the angle of the approach axis from vertical, divided by pi/2).
    """
    axes = task.robot.grasp_axes(states)
    horizontal = np.abs(axes[..., 0])
    return np.arctan2(horizontal, -axes[..., 2]) / (np.pi / 2)


def _colored_path(
    ax: Axes, xz: np.ndarray, values: np.ndarray, cmap: str, norm: plt.Normalize, lw: float = 1.2
):
    segs = np.stack([xz[:-1], xz[1:]], axis=1)
    lc = LineCollection(list(segs), cmap=cmap, norm=norm, lw=lw)
    lc.set_array(values[:-1])
    ax.add_collection(lc)
    return lc


def plot_demonstrations(
    task: CupTask, demos: Demonstrations, ax: Axes | None = None, goal_index: int = 1
) -> Axes:
    """Grasp-site paths of the demonstrations, coloured by the belief in one cup.

    Args:
        task: The cup task.
        demos: The dataset; only the clean tuples are drawn.
        ax: Axes to draw on.
        goal_index: Whose belief colours the paths (default: the right cup).
    """
    ax = draw_scene(task, ax)
    clean = demos.clean()
    norm = plt.Normalize(0.0, 1.0)
    lc = None
    for d in np.unique(clean.demo):
        m = clean.demo == d
        xyz = task.robot.grasp_positions(clean.states[m])
        lc = _colored_path(ax, xyz[:, [0, 2]], clean.beliefs[m, goal_index], "coolwarm", norm, 0.9)
    if lc is not None:
        plt.colorbar(lc, ax=ax, label=f"belief in the {task.goal_names[goal_index]} cup", shrink=0.8)
    ax.set_xlim(-0.75, 0.75)
    ax.set_ylim(-0.05, 1.05)
    return ax


def plot_training_curves(history: pd.DataFrame, ax: Axes | None = None) -> Axes:
    """Training loss and held-out reconstruction error against optimiser step."""
    ax = _ax(ax)
    ax.plot(history["step"], history["train_loss"], label="train loss (units of $\\sigma_h^2$)")
    ax.plot(history["step"], history["val_error"], label="held-out $\\|e_a\\|^2$ [(rad/s)$^2$]")
    ax.set_yscale("log")
    ax.set_xlabel("optimiser step")
    ax.legend(frameon=False)
    return ax


def plot_held_paths(
    task: CupTask,
    paths: np.ndarray,
    z_values: np.ndarray,
    ax: Axes | None = None,
    gripper: bool = False,
    title: str | None = None,
) -> Axes:
    """Grasp-site paths when each joystick input is held, coloured by z.

    Args:
        task: The cup task.
        paths: States of each held input, shape (K, steps + 1, n).
        z_values: The held inputs, shape (K,).
        ax: Axes to draw on.
        gripper: Also draw the final gripper direction of each path.
        title: Panel title.
    """
    ax = draw_scene(task, ax)
    norm = plt.Normalize(-1.0, 1.0)
    cmap = plt.get_cmap("coolwarm")
    for path, z in zip(paths, z_values, strict=True):
        xyz = task.robot.grasp_positions(path)
        ax.plot(xyz[:, 0], xyz[:, 2], color=cmap(norm(z)), lw=1.3)
        if gripper:
            axis = task.robot.grasp_axes(path[-1])
            tip = xyz[-1, [0, 2]]
            back = tip - 0.06 * axis[[0, 2]]
            ax.plot([back[0], tip[0]], [back[1], tip[1]], color=cmap(norm(z)), lw=3, solid_capstyle="round")
    start = task.robot.grasp_positions(paths[0, 0])
    ax.plot(start[0], start[2], "ko", ms=4)
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    plt.colorbar(sm, ax=ax, label="held joystick input z", shrink=0.8)
    if title:
        ax.set_title(title)
    return ax


def plot_latent_meaning(frame: pd.DataFrame, ax: Axes | None = None) -> Axes:
    """What z controls in each context: the cup reached, or the grasp.

    Args:
        frame: Rows with columns ``context``, ``z``, ``final_x`` (grasp-site x after
            holding z, metres) and ``grasp_theta`` (the grasp preference shown).
    """
    ax = _ax(ax)
    uni = frame[frame.context == "uniform"]
    conf = frame[frame.context == "confident"]
    ax.plot(uni.z, uni.final_x, "o-", color="#444", label="from uniform belief: grasp-site x [m]")
    ax.set_xlabel("held joystick input z")
    ax.set_ylabel("grasp-site x after holding z [m]")
    ax.axhline(0, color="0.8", lw=0.8)
    twin = ax.twinx()
    twin.plot(conf.z, conf.grasp_theta, "s-", color="#7570b3", label="confident belief: grasp $\\theta$")
    twin.set_ylabel("grasp preference $\\theta$ (0 top, 1 side)")
    twin.set_ylim(min(-0.05, conf.grasp_theta.min() - 0.05), max(1.05, conf.grasp_theta.max() + 0.05))
    lines = ax.get_lines()[:1] + twin.get_lines()
    ax.legend(lines, [str(ln.get_label()) for ln in lines], frameon=False, loc="upper left", fontsize=8)
    return ax


def plot_sim1(frame: pd.DataFrame, metric: str, ax: Axes | None = None) -> Axes:
    """Fig. sim1: a metric against beta per method, with 95% bootstrap bands.

    Args:
        frame: The sim1 frame (columns ``beta``, ``method`` and ``metric``).
        metric: ``final_error`` or ``time``.
        ax: Axes to draw on.
    """
    ax = _ax(ax)
    methods = [m for m in METHOD_COLORS if m in set(frame.method)]
    sns.lineplot(
        data=frame,
        x="beta",
        y=metric,
        hue="method",
        hue_order=methods,
        palette=METHOD_COLORS,
        errorbar=("ci", 95),
        n_boot=500,
        seed=0,
        marker="o",
        ax=ax,
    )
    ax.set_xscale("log")
    ax.set_xlabel(r"user rationality $\beta$")
    ax.set_ylabel(
        {"final_error": "final state error (normalised)", "time": "time to reach s* [steps]"}.get(
            metric, metric
        )
    )
    for beta in (75, 1000):
        ax.axvline(beta, color="0.85", lw=0.8, zorder=0)
    ax.legend(frameon=False, title=None)
    return ax
