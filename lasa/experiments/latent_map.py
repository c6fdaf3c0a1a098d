"""What a joystick input means, per context: the latent map (Sec. III-A, Fig. 1).

A constant z under latent actions alone (alpha = 0): from home with the belief updated online
(Algorithm 1), and at the right cup's grasp with a confident belief. Notebook ``02_decoder_training``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from lasa.base.config import AtLeastTwo, ControlConfig, PositiveInt, validate
from lasa.base.errors import ConfigError
from lasa.base.io import load_npz
from lasa.base.paths import Paths
from lasa.evidence import latent_property
from lasa.evidence.latent_measure import held_input_paths
from lasa.evidence.plots import draw_scene, frame_around, goal_colors, project, robots_present
from lasa.method.decoder import ActionDecoder
from lasa.world.robot import load_robot
from lasa.world.task import CupTask, cup_axis, grasp_frame, grasp_preference, make_cup_task

NAME = "latent_map"
COLUMNS = ("robot", "context", "z", "cup_axis", "grasp_theta", "steps")
DPI = 130


@dataclasses.dataclass(frozen=True)
class Config:
    """The held inputs and how long each is held, per context."""

    n_z: AtLeastTwo = 11  # held joystick inputs, evenly spaced on [-1, 1] [-]
    uniform_steps: PositiveInt = 100  # steps each input is held from home: long enough to reach a cup
    confident_steps: PositiveInt = 40  # steps each input is held at the cup: long enough to sweep the grasp

    def __post_init__(self) -> None:
        validate(self)


def run(
    decoder: ActionDecoder, task: CupTask, control: ControlConfig, config: Config = Config()
) -> tuple[pd.DataFrame, dict[str, np.ndarray]]:
    """Hold each input in both contexts: one row per (context, z) (:data:`COLUMNS`: where the grasp
    site ends up along the left-to-right cup axis [m], the grasp preference the gripper shows), and the
    arrays to save for the figure: ``z`` (K,) and the states of each context, (K, steps + 1, n)."""
    z = np.linspace(-1.0, 1.0, config.n_z)
    steps = {"uniform": config.uniform_steps, "confident": config.confident_steps}
    contexts = {  # start state, initial belief, whether the belief updates online
        "uniform": (task.start, np.full(task.n_goals, 1.0 / task.n_goals), True),
        "confident": (task.goals[1], np.eye(task.n_goals)[1], False),
    }
    paths = {
        name: held_input_paths(decoder, task, control, s0, b0, z, steps[name], update_belief=online)
        for name, (s0, b0, online) in contexts.items()
    }
    parts = []
    for name, p in paths.items():
        ends = (cup_axis(task, task.robot.grasp_positions(p[:, -1])), grasp_preference(task, p[:, -1]))
        values = (task.robot.name, name, z, *ends, steps[name])
        parts.append(pd.DataFrame(dict(zip(COLUMNS, values, strict=True))))
    return pd.concat(parts, ignore_index=True), {"z": z, **paths}


def plot_grasp_sweep(
    task: CupTask, paths: np.ndarray, z_values: np.ndarray, goal: int, ax: Axes, title: str
) -> Axes:
    """Gripper directions at the end of each held input, in the cup's grasp plane."""
    robot = task.robot
    cup = robot.goal_positions()[goal]
    _, r_side = grasp_frame(robot, goal, 1.0)
    side = r_side[:, 2].copy()
    side[2] = 0.0
    side /= np.linalg.norm(side)

    def plane(p: np.ndarray) -> np.ndarray:
        rel = np.asarray(p) - cup
        return np.stack([rel @ side, rel[..., 2]], axis=-1)

    norm = Normalize(-1.0, 1.0)
    cmap = plt.get_cmap("coolwarm")
    color = goal_colors(task.n_goals)[goal]
    ax.add_patch(Rectangle((-0.035, -cup[2]), 0.07, cup[2] + 0.02, color=color, alpha=0.6))
    for path, z in zip(paths, z_values, strict=True):
        xy = plane(robot.grasp_positions(path))
        ax.plot(xy[:, 0], xy[:, 1], color=cmap(norm(z)), lw=0.8)
        tip = xy[-1]
        back = tip - 0.06 * plane(cup + robot.grasp_axes(path[-1]))
        ax.plot([back[0], tip[0]], [back[1], tip[1]], color=cmap(norm(z)), lw=3, solid_capstyle="round")
    start = plane(robot.grasp_positions(paths[0, 0]))
    ax.plot(start[0], start[1], "ko", ms=4)
    ax.set(aspect="equal", xlabel="along the side-grasp direction [m]")
    ax.set_ylabel("height above the cup's grasp point [m]")
    ax.set_title(title)
    return ax


def plot(table: pd.DataFrame, run_paths: Paths, tasks: Mapping[str, CupTask] | None = None) -> Figure:
    """The latent map: one row per robot present whose held-input paths are saved (artifact
    ``latent_paths`` of ``run_paths``); ``tasks``: those already built, by robot name. Its panels: the
    grasp-site paths from home, coloured by the held z; the grasps at the cup (:func:`plot_grasp_sweep`);
    what z controls in each context (:func:`run`'s rows), the cup reached or the grasp."""
    norm = Normalize(-1.0, 1.0)
    cmap = plt.get_cmap("coolwarm")
    rows = [name for name in robots_present(table) if run_paths.artifact("latent_paths", name).is_file()]
    size, widths = (15, 4.3 * len(rows)), {"width_ratios": [1.1, 1.1, 1]}
    fig, axes = plt.subplots(len(rows), 3, figsize=size, squeeze=False, gridspec_kw=widths)
    for name, row in zip(rows, axes, strict=True):
        task = (tasks or {}).get(name) or make_cup_task(load_robot(name))
        saved = load_npz(run_paths.artifact("latent_paths", name), Paths.make_hint("latent_paths", name))
        drawn = [project(task, task.robot.grasp_positions(path)) for path in saved["uniform"]]
        ax = draw_scene(task, row[0])
        for xy, z in zip(drawn, saved["z"], strict=True):
            ax.plot(xy[:, 0], xy[:, 1], color=cmap(norm(z)), lw=1.3)
        ax.plot(drawn[0][0][0], drawn[0][0][1], "ko", ms=4)
        frame_around(task, ax, np.concatenate(drawn))
        ax.set_title(f"{name}: from home (belief uniform at first):\nz picks the cup")
        cup = f"{name}: confident in the right cup:\nz picks the grasp"
        plot_grasp_sweep(task, saved["confident"], saved["z"], 1, row[1], cup)
        for ax in row[:2]:
            plt.colorbar(
                plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="held joystick input z", shrink=0.8
            )
        mine = table[table.robot == name]
        ax = row[2]
        uni = mine[mine.context == "uniform"]
        conf = mine[mine.context == "confident"]
        ax.plot(uni.z, uni.cup_axis, "o-", color="#444", label="from uniform belief: cup reached")
        ax.set(xlabel="held joystick input z", ylabel="grasp site: left cup (-) ... right cup (+) [m]")
        ax.axhline(0, color="0.8", lw=0.8)
        twin = ax.twinx()
        twin.plot(conf.z, conf.grasp_theta, "s-", color="#7570b3", label="confident belief: grasp $\\theta$")
        twin.set_ylabel("grasp preference $\\theta$ (0 top, 1 side)")
        twin.set_ylim(min(-0.05, conf.grasp_theta.min() - 0.05), max(1.05, conf.grasp_theta.max() + 0.05))
        lines = ax.get_lines()[:1] + twin.get_lines()
        ax.legend(lines, [str(ln.get_label()) for ln in lines], frameon=False, loc="upper left", fontsize=8)
        ax.set_title(f"{name}: what z controls, per context")
    fig.tight_layout()
    return fig


def property_findings(summary: pd.DataFrame) -> str:
    """One decoder's latent property at each cup and from home, as Markdown bullets, from its
    :func:`lasa.evidence.latent_property.summary` (one row per cup)."""
    if summary.empty or summary.decoder.nunique() != 1:
        raise ConfigError(f"expected one decoder's rows, got {sorted(set(summary.decoder))}")
    holds = {True: "holds", False: "does not hold"}
    need = latent_property.LEAVE_COUNT
    lines = []
    for row in summary.itertuples():
        n, stay = int(row.n_inputs), round(row.stay_share * row.n_inputs)
        reach = f"θ from {row.theta_min:.2f} to {row.theta_max:.2f}"
        leave = (
            "the leave half is not measured"
            if np.isnan(row.leave_min)
            else f"from its mid-preference grasp {row.leave_min:.0f} reach another cup under LA+SA "
            f"(the leave half asks for {need * n / 64:g} of {n}), so it {holds[bool(row.leave_holds)]}"
        )
        lines.append(
            f"- **At the {row.goal} cup** (confident belief): {stay} of {n} stick deflections stay, reaching "
            f"{reach}, so the stay half {holds[bool(row.stay_holds)]}; {leave}."
        )
    home = {r.goal: round(r.from_home * r.n_inputs) for r in summary.itertuples()}
    each = ", ".join(f"{k} at the {g} cup" for g, k in home.items())
    reached = "every cup is reached" if bool(summary.all_reached.all()) else "not every cup is reached"
    lines.append(
        f"- **From home** (uniform belief, updated online): {sum(home.values())} of "
        f"{int(summary.n_inputs.max())} inputs reach a cup ({each}); {reached}."
    )
    meets = bool(latent_property.holds(summary).iloc[0])
    at = int(summary.has_property.sum())
    lines.append(
        f"- **The rule.** The decoder has the property at {at} of {len(summary)} cups, so it "
        f"{'meets' if meets else 'does not meet'} the rule."
    )
    return "\n".join(lines)
