"""Plot functions: data and ``ax=None`` in, axes out.

Each function draws one panel from data it is given (a frame, a dataset, paths), so a
notebook composes panels freely and the data behind each figure is saved beside it.
A planar arm is drawn in its x-z plane; the Panda from above (:func:`project`).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.patches import Circle, Rectangle

from lasa.demos import Demonstrations
from lasa.experiments import sim4_fits
from lasa.task import CupTask, grasp_frame

__all__ = [
    "METHOD_COLORS",
    "draw_scene",
    "plot_demonstrations",
    "plot_training_curves",
    "plot_held_paths",
    "plot_grasp_sweep",
    "project",
    "cup_axis",
    "is_planar",
    "plot_latent_meaning",
    "plot_sim1",
    "plot_sim2",
    "plot_sim3",
    "plot_sim4",
    "plot_entropy_grid",
    "plot_entropy_tradeoff",
    "grasp_preference",
]

METHOD_COLORS = {"LA": "#d95f02", "LA+SA": "#1b9e77", "LA+SA+Entropy": "#7570b3"}
CUP_COLORS = ("#e6553f", "#3f9959")


def _ax(ax: Axes | None) -> Axes:
    return plt.gca() if ax is None else ax


def is_planar(task: CupTask) -> bool:
    """Whether the robot moves in the world's x-z plane (every cup at y = 0)."""
    return bool(np.allclose(task.robot.cup_positions()[:, 1], 0.0))


def project(task: CupTask, points: np.ndarray) -> np.ndarray:
    """World points (..., 3) onto the plane a figure draws the task in, (..., 2).

    A planar arm is drawn in its own x-z plane. Any other robot is drawn from above,
    with the robot's left on the left: (-y, x).
    """
    points = np.asarray(points)
    if is_planar(task):
        return points[..., [0, 2]]
    return np.stack([-points[..., 1], points[..., 0]], axis=-1)


def cup_axis(task: CupTask, points: np.ndarray) -> np.ndarray:
    """Signed position along the axis from the left cup to the right cup [m], (...).

    Zero midway between the cups; the sign says which cup a point is closer to.
    """
    cups = task.robot.cup_positions()
    axis = cups[-1] - cups[0]
    axis[2] = 0.0
    axis /= np.linalg.norm(axis)
    return (np.asarray(points) - cups.mean(axis=0)) @ axis


def draw_scene(task: CupTask, ax: Axes | None = None) -> Axes:
    """The cups and the robot's base in the task's drawing plane (:func:`project`)."""
    ax = _ax(ax)
    cups = task.robot.cup_positions()
    if is_planar(task):
        ax.axhline(0.0, color="#8b6d4b", lw=2, zorder=0)
        for (x, _, _), color in zip(cups, CUP_COLORS, strict=True):
            ax.add_patch(Rectangle((x - 0.035, 0.0), 0.07, 0.12, color=color, alpha=0.8, zorder=1))
        ax.add_patch(Rectangle((-0.06, 0.0), 0.12, 0.12, color="#40444c", zorder=1))
        ax.set_xlabel("x [m]")
        ax.set_ylabel("z [m]")
    else:
        for cup, color in zip(project(task, cups), CUP_COLORS, strict=True):
            ax.add_patch(Circle(tuple(cup), 0.035, color=color, alpha=0.8, zorder=1))
        ax.add_patch(Circle(tuple(project(task, task.robot.base_position())), 0.06, color="#40444c"))
        ax.set_xlabel("left <- -y [m] -> right")
        ax.set_ylabel("x (forward) [m]")
    ax.set_aspect("equal")
    return ax


def grasp_preference(task: CupTask, states: np.ndarray) -> np.ndarray:
    """The grasp preference theta that the gripper's direction shows, shape (...).

    0 when the fingers point straight down, 1 when they point horizontally (the angle
    of the approach axis from vertical, divided by pi/2).
    """
    axes = task.robot.grasp_axes(states)
    horizontal = np.linalg.norm(axes[..., :2], axis=-1)
    return np.arctan2(horizontal, -axes[..., 2]) / (np.pi / 2)


def _colored_path(ax: Axes, xy: np.ndarray, values: np.ndarray, cmap: str, norm: Normalize, lw: float = 1.2):
    segs = np.stack([xy[:-1], xy[1:]], axis=1)
    lc = LineCollection(list(segs), cmap=cmap, norm=norm, lw=lw)
    lc.set_array(values[:-1])
    ax.add_collection(lc)
    return lc


def _frame_around(task: CupTask, ax: Axes, points: np.ndarray, pad: float = 0.08) -> None:
    """Limit the axes to the drawn points, the cups and the base, with some padding."""
    cups = project(task, task.robot.cup_positions())
    base = project(task, task.robot.base_position())[None]
    pts = np.concatenate([points.reshape(-1, 2), cups, base])
    lo, hi = pts.min(axis=0) - pad, pts.max(axis=0) + pad
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(min(lo[1], -0.05) if is_planar(task) else lo[1], hi[1])


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
    norm = Normalize(0.0, 1.0)
    lc = None
    drawn = []
    for d in np.unique(clean.demo):
        m = clean.demo == d
        xy = project(task, task.robot.grasp_positions(clean.states[m]))
        drawn.append(xy)
        lc = _colored_path(ax, xy, clean.beliefs[m, goal_index], "coolwarm", norm, 0.9)
    if lc is not None:
        plt.colorbar(lc, ax=ax, label=f"belief in the {task.goal_names[goal_index]} cup", shrink=0.8)
        _frame_around(task, ax, np.concatenate(drawn))
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
    task: CupTask, paths: np.ndarray, z_values: np.ndarray, ax: Axes | None = None, title: str | None = None
) -> Axes:
    """Grasp-site paths when each joystick input is held, coloured by z.

    Args:
        task: The cup task.
        paths: States of each held input, shape (K, steps + 1, n).
        z_values: The held inputs, shape (K,).
        ax: Axes to draw on.
        title: Panel title.
    """
    ax = draw_scene(task, ax)
    norm = Normalize(-1.0, 1.0)
    cmap = plt.get_cmap("coolwarm")
    drawn = []
    for path, z in zip(paths, z_values, strict=True):
        xy = project(task, task.robot.grasp_positions(path))
        drawn.append(xy)
        ax.plot(xy[:, 0], xy[:, 1], color=cmap(norm(z)), lw=1.3)
    start = drawn[0][0]
    ax.plot(start[0], start[1], "ko", ms=4)
    _frame_around(task, ax, np.concatenate(drawn))
    plt.colorbar(
        plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="held joystick input z", shrink=0.8
    )
    if title:
        ax.set_title(title)
    return ax


def plot_grasp_sweep(
    task: CupTask,
    paths: np.ndarray,
    z_values: np.ndarray,
    goal: int,
    ax: Axes | None = None,
    title: str | None = None,
) -> Axes:
    """Gripper directions at the end of each held input, in the cup's grasp plane.

    The plane is vertical and contains the cup's side-grasp direction, so a top grasp
    points down and a side grasp points sideways. Each input draws the gripper's last
    6 cm as a thick segment, and the grasp site's path as a thin line.
    """
    ax = _ax(ax)
    robot = task.robot
    cup = robot.cup_positions()[goal]
    _, r_side = grasp_frame(robot, goal, 1.0)
    side = r_side[:, 2].copy()
    side[2] = 0.0
    side /= np.linalg.norm(side)

    def plane(p: np.ndarray) -> np.ndarray:
        rel = np.asarray(p) - cup
        return np.stack([rel @ side, rel[..., 2]], axis=-1)

    norm = Normalize(-1.0, 1.0)
    cmap = plt.get_cmap("coolwarm")
    ax.add_patch(Rectangle((-0.035, -cup[2]), 0.07, cup[2] + 0.02, color=CUP_COLORS[goal], alpha=0.6))
    for path, z in zip(paths, z_values, strict=True):
        xy = plane(robot.grasp_positions(path))
        ax.plot(xy[:, 0], xy[:, 1], color=cmap(norm(z)), lw=0.8)
        tip = xy[-1]
        back = tip - 0.06 * plane(cup + robot.grasp_axes(path[-1]))
        ax.plot([back[0], tip[0]], [back[1], tip[1]], color=cmap(norm(z)), lw=3, solid_capstyle="round")
    start = plane(robot.grasp_positions(paths[0, 0]))
    ax.plot(start[0], start[1], "ko", ms=4)
    ax.set_aspect("equal")
    ax.set_xlabel("along the side-grasp direction [m]")
    ax.set_ylabel("height above the cup's grasp point [m]")
    plt.colorbar(
        plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="held joystick input z", shrink=0.8
    )
    if title:
        ax.set_title(title)
    return ax


def plot_latent_meaning(frame: pd.DataFrame, ax: Axes | None = None) -> Axes:
    """What z controls in each context: the cup reached, or the grasp.

    Args:
        frame: Rows with columns ``context``, ``z``, ``cup_axis`` (grasp-site position
            along the left-to-right cup axis after holding z, metres) and
            ``grasp_theta`` (the grasp preference shown).
    """
    ax = _ax(ax)
    uni = frame[frame.context == "uniform"]
    conf = frame[frame.context == "confident"]
    ax.plot(uni.z, uni.cup_axis, "o-", color="#444", label="from uniform belief: cup reached")
    ax.set_xlabel("held joystick input z")
    ax.set_ylabel("grasp site: left cup (-) ... right cup (+) [m]")
    ax.axhline(0, color="0.8", lw=0.8)
    twin = ax.twinx()
    twin.plot(conf.z, conf.grasp_theta, "s-", color="#7570b3", label="confident belief: grasp $\\theta$")
    twin.set_ylabel("grasp preference $\\theta$ (0 top, 1 side)")
    twin.set_ylim(min(-0.05, conf.grasp_theta.min() - 0.05), max(1.05, conf.grasp_theta.max() + 0.05))
    lines = ax.get_lines()[:1] + twin.get_lines()
    ax.legend(lines, [str(ln.get_label()) for ln in lines], frameon=False, loc="upper left", fontsize=8)
    return ax


def _method_lineplot(frame: pd.DataFrame, x: str, y: str, ax: Axes) -> Axes:
    methods = [m for m in METHOD_COLORS if m in set(frame.method)]
    sns.lineplot(
        data=frame,
        x=x,
        y=y,
        hue="method",
        hue_order=methods,
        palette=METHOD_COLORS,
        errorbar=("ci", 95),
        n_boot=500,
        seed=0,
        ax=ax,
        marker="o" if frame[x].nunique() < 30 else None,
    )
    ax.legend(frameon=False, title=None)
    return ax


def plot_sim1(frame: pd.DataFrame, metric: str, ax: Axes | None = None) -> Axes:
    """Fig. sim1: a metric against beta per method, with 95% bootstrap bands.

    Args:
        frame: The sim1 frame (columns ``beta``, ``method`` and ``metric``).
        metric: ``final_error`` or ``time``.
        ax: Axes to draw on.
    """
    ax = _method_lineplot(frame, "beta", metric, _ax(ax))
    ax.set_xscale("log")
    ax.set_xlabel(r"user rationality $\beta$")
    ax.set_ylabel(
        {"final_error": "final state error (normalised)", "time": "time to reach s* [steps]"}.get(
            metric, metric
        )
    )
    for beta in (75, 1000):
        ax.axvline(beta, color="0.85", lw=0.8, zorder=0)
    return ax


def plot_sim2(frame: pd.DataFrame, metric: str, ax: Axes | None = None) -> Axes:
    """Fig. sim2: final error or confidence in the true cup against the change step N."""
    ax = _method_lineplot(frame, "change_step", metric, _ax(ax))
    ax.set_xlabel("change of mind at step N")
    ax.set_ylabel(
        {"final_error": "final state error (normalised)", "confidence": "confidence b(g*) at the end"}.get(
            metric, metric
        )
    )
    return ax


def plot_sim3(frame: pd.DataFrame, learner: str, ax: Axes | None = None) -> Axes:
    """Fig. sim3: error over time of one kind of learner, per method, with 95% bands."""
    part = frame[frame.learner == learner]
    ax = _method_lineplot(part, "t", "error", _ax(ax))
    slope = part.slope.iloc[0]
    ax.set_title(f"{learner} learner: beta(t) = {slope:g} t")
    ax.set_xlabel("time step t")
    ax.set_ylabel("state error (normalised)")
    return ax


def plot_entropy_grid(
    progress: np.ndarray,
    conf: np.ndarray,
    values: np.ndarray,
    ax: Axes | None = None,
    title: str | None = None,
) -> Axes:
    """Entropy of p_(s,b) over a grid of contexts: progress to the goal x confidence in it."""
    ax = _ax(ax)
    ps, cs = np.unique(progress), np.unique(conf)
    grid = values.reshape(len(ps), len(cs)).T
    mesh = ax.pcolormesh(ps, cs, grid, vmin=0.0, vmax=np.log(2), cmap="viridis", shading="nearest")
    plt.colorbar(mesh, ax=ax, label="entropy of p(s,b) [nats] (max log 2)")
    ax.set_xlabel("state: from home (0) to the right cup's goal (1)")
    ax.set_ylabel("belief in the right cup")
    if title:
        ax.set_title(title)
    return ax


def plot_entropy_tradeoff(sweep: pd.DataFrame, chosen: float, ax: Axes | None = None) -> Axes:
    """Held-out reconstruction error against entropy at confident contexts, per lambda."""
    ax = _ax(ax)
    ax.plot(sweep.entropy_confident, sweep.recon_error, "o-", color="#444")
    for _, row in sweep.iterrows():
        mark = " (chosen)" if np.isclose(row["lambda"], chosen) else ""
        ax.annotate(
            f"λ={row['lambda']:g}{mark}",
            (row.entropy_confident, row.recon_error),
            textcoords="offset points",
            xytext=(5, 5),
            fontsize=8,
        )
    ax.set_xlabel("mean entropy of p(s,b) at confident contexts [nats]")
    ax.set_ylabel("reconstruction error on the demonstrations [(rad/s)$^2$]")
    return ax


H_STYLES = {
    "none": ("#d95f02", "without the map"),
    "straight_line": ("#7570b3", "straight-line h (paper)"),
    "grasp": ("#1b9e77", "grasp-to-grasp h (ours)"),
}


def plot_sim4(frame: pd.DataFrame, ax: Axes | None = None) -> Axes:
    """Fig. sim4: grasp error at new cups against their distance, per kind of map.

    Each cup's episodes are drawn as faint points and their mean with a 95% bootstrap
    interval; the line is the least-squares fit through the means (its equation and R^2
    in the legend, from :func:`lasa.experiments.sim4_fits`). The dashed line is y = x.
    """
    ax = _ax(ax)
    fits = sim4_fits(frame)
    xs = np.linspace(0.0, 1.0, 2)
    ax.plot(xs, xs, ls="--", color="0.6", lw=1, label="y = x")
    for kind, (color, name) in H_STYLES.items():
        if kind not in fits.index:
            continue
        part = frame[frame.h == kind]
        ax.scatter(part.distance, part.error, s=6, color=color, alpha=0.15, lw=0)
        sns.pointplot(
            data=part,
            x="distance",
            y="error",
            native_scale=True,
            color=color,
            errorbar=("ci", 95),
            n_boot=500,
            seed=0,
            linestyle="none",
            markersize=4,
            ax=ax,
        )
        f = fits.loc[kind]
        ax.plot(
            xs,
            f.slope * xs + f.intercept,
            color=color,
            lw=1.5,
            label=f"{name}: y = {f.slope:.2f}x {f.intercept:+.2f}, R² = {f.r2:.2f}",
        )
    ax.set_xlim(0, 1.05)
    ax.set_ylim(0, max(1.1, float(frame.groupby(["h", "distance"]).error.mean().max()) * 1.1))
    ax.set_xlabel("distance of the new goal from the training goal (normalised)")
    ax.set_ylabel("grasp error (normalised)")
    ax.legend(frameon=False, fontsize=8, loc="upper left")
    return ax
