"""The entropy term's ablation: a sweep over lambda, its rule, and what it does (Sec. IV-B).

Every lambda, 0 included (the control, and the decoder of LA and LA+SA), fine-tunes notebook 02's
base decoder with the same schedule, batches and noise. Notebook ``03_entropy_ablation``.
"""

from __future__ import annotations

import dataclasses

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from lasa.base.config import ControlConfig, NonNegative, PositiveInt, Seed, check_list, validate
from lasa.base.errors import ConfigError, EmptySelectionError
from lasa.evidence.plots import robot_rows
from lasa.method.belief import CONFIDENT_MARGIN, belief_targets, confidence_threshold
from lasa.method.dataset import Demonstrations
from lasa.method.decoder import LatentActionModel
from lasa.method.entropy import LAMBDA_COST, choose_lambda, context_entropy, context_grid
from lasa.method.train import TrainConfig, reconstruction_error, train_decoder
from lasa.pipeline.scaleout import run_jobs
from lasa.world.goals import GoalTask

NAME = "entropy_ablation"
# kind "sweep": one row per lambda; kind "grid": one row per context of the grid, for
# lambda = 0 and the chosen lambda
COLUMNS = ("robot", "kind", "lambda", "progress", "confidence", "entropy", "recon_error", "val_error")
DPI = 130


@dataclasses.dataclass(frozen=True)
class Config:
    """The lambda sweep."""

    lambdas: tuple[NonNegative, ...] = (0.0, 0.1, 0.3, 1.0, 3.0)  # ascending, 0 (the control) and > 0 [-]
    sweep_steps: PositiveInt = 800  # fine-tuning steps of every lambda, 0 included, from the base decoder [-]
    seed: Seed = 0  # seed of every fine-tuning run (the same for all lambdas: paired batches) [-]
    jobs: PositiveInt = 1  # worker processes (train_all), runs seeded: the same decoders with any number [-]

    def __post_init__(self) -> None:
        validate(self)
        check_list("lambdas", self.lambdas, at_least=2, ascending=True, why="0 and at least one lambda > 0")
        if 0.0 not in {float(lam) for lam in self.lambdas}:
            raise ConfigError(f"lambdas must include 0 (the control), got {self.lambdas!r}")


@dataclasses.dataclass(frozen=True)
class Sweep:
    """The sweep's results: per lambda its decoder, training config and log, and ``table``, one row per
    lambda: ``entropy_confident`` (mean entropy of p_(s,b) at confident demonstrated contexts [nats]),
    ``recon_error`` (on the clean demonstrations) and ``val_error`` (held out) [(rad/s)^2]; ``chosen`` the
    rule's lambda (0 if no lambda > 0 is within its cost bound: :func:`lasa.method.entropy.choose_lambda`)."""

    table: pd.DataFrame
    models: dict[float, LatentActionModel]
    configs: dict[float, TrainConfig]
    histories: dict[float, pd.DataFrame]
    chosen: float


@dataclasses.dataclass(frozen=True)
class Run:
    """One training run: :func:`lasa.method.train.train_decoder`'s arguments."""

    demos: Demonstrations
    control: ControlConfig
    config: TrainConfig
    goal_sets: np.ndarray | None = None
    init: LatentActionModel | None = None


def _train(run: Run) -> tuple[LatentActionModel, pd.DataFrame]:
    return train_decoder(
        run.demos, run.control, run.config, goal_sets=run.goal_sets, init=run.init, progress=False
    )


def train_all(
    runs: list[Run], jobs: int = 1, progress: bool = False, desc: str = "training runs"
) -> list[tuple[LatentActionModel, pd.DataFrame]]:
    """Each run's decoder and loss history, in order, over ``jobs`` local worker processes."""
    return run_jobs(_train, runs, n_jobs=jobs, progress=progress, desc=desc)


def confident_contexts(
    demos: Demonstrations, cap: float | None = None, every: int = 10
) -> tuple[np.ndarray, np.ndarray]:
    """Every ``every``-th clean demonstrated context with a confident belief: (states, beliefs);
    EmptySelectionError if no demonstrated context is that confident."""
    clean = demos.clean()
    threshold = confidence_threshold(cap)
    confident = clean.beliefs.max(axis=1) > threshold
    if not confident.any():
        top = float(clean.beliefs.max()) if len(clean) else float("nan")
        raise EmptySelectionError(
            f"no demonstrated context is confident (top belief > {threshold:g}, belief_cap {cap} less "
            f"{CONFIDENT_MARGIN:g}); the demonstrations' highest belief is {top:.6g}. Demonstrations that "
            "dwell at a goal (more steps at each goal) reach it; the cap sets the threshold (belief_cap)"
        )
    return clean.states[confident][::every], clean.beliefs[confident][::every]


def run_sweep(
    base: LatentActionModel,
    base_train: TrainConfig,
    demos: Demonstrations,
    task: GoalTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = True,
) -> Sweep:
    """Fine-tune ``base`` (notebook 02's decoder) once per lambda (0 included) and pick lambda by the
    fixed rule; each run keeps ``base_train``'s settings but ``steps``, ``entropy_lambda`` and ``seed``."""
    goal_sets = belief_targets(task, control.likelihood)
    probe = confident_contexts(demos, control.belief_cap)
    clean = demos.clean()
    lambdas = [float(x) for x in config.lambdas]
    configs = {
        lam: dataclasses.replace(base_train, steps=config.sweep_steps, entropy_lambda=lam, seed=config.seed)
        for lam in lambdas
    }
    runs = [Run(demos, control, configs[lam], goal_sets, base) for lam in lambdas]
    trained = train_all(runs, config.jobs, progress, desc="lambda sweep")
    models, histories = (dict(zip(lambdas, part, strict=True)) for part in zip(*trained, strict=True))
    rows = [
        {
            "lambda": lam,
            "entropy_confident": float(context_entropy(models[lam], *probe, goal_sets, control).mean()),
            "recon_error": reconstruction_error(models[lam], clean.states, clean.actions, clean.beliefs),
            "val_error": float(histories[lam].val_error.iloc[-1]),
        }
        for lam in lambdas
    ]
    table = pd.DataFrame(rows)
    return Sweep(table, models, configs, histories, choose_lambda(table, task.n_goals))


def grid_rows(sweep: Sweep, task: GoalTask, control: ControlConfig) -> pd.DataFrame:
    """This robot's rows of the figure (:data:`COLUMNS`): the sweep, and the entropy over a grid."""
    goal_sets = belief_targets(task, control.likelihood)
    progress, conf, states, beliefs = context_grid(task.start, task.goals[1], 1, task.n_goals)
    robot = task.robot.name
    lams = dict.fromkeys((0.0, sweep.chosen))  # the control alone if the rule kept it
    grid = {lam: context_entropy(sweep.models[lam], states, beliefs, goal_sets, control) for lam in lams}
    grids = [(robot, "grid", lam, progress, conf, e, np.nan, np.nan) for lam, e in grid.items()]
    t = sweep.table
    swept = (robot, "sweep", t["lambda"], np.nan, np.nan, t.entropy_confident, t.recon_error, t.val_error)
    frames = [pd.DataFrame(dict(zip(COLUMNS, part, strict=True))) for part in [*grids, swept]]
    return pd.concat(frames, ignore_index=True)


def plot(table: pd.DataFrame) -> Figure:
    """One row per robot present: the entropy of p_(s,b) over a grid of contexts (progress to the goal x
    confidence in it) at lambda = 0 and at the chosen lambda, and the sweep's trade-off: reconstruction
    error on the clean demonstrations against entropy at confident contexts, per lambda."""
    fig, rows = robot_rows(table, 3, (16, 4.2))
    for name, part, row in rows:
        lams = sorted(set(part[part.kind == "grid"]["lambda"]))
        for ax, lam in zip(row, lams, strict=False):
            g = part[(part.kind == "grid") & (part["lambda"] == lam)]
            ps = np.unique(g.progress.to_numpy())
            cs = np.unique(g.confidence.to_numpy())
            grid = g.entropy.to_numpy().reshape(len(ps), len(cs)).T
            mesh = ax.pcolormesh(ps, cs, grid, vmin=0.0, vmax=np.log(2), cmap="viridis", shading="nearest")
            plt.colorbar(mesh, ax=ax, label="entropy of p(s,b) [nats] (max log 2)")
            ax.set(
                xlabel="state: from home (0) to the right cup's goal (1)", ylabel="belief in the right cup"
            )
            ax.set_title(f"{name}: lambda = {lam:g}" + (" (control)" if lam == 0 else " (chosen)"))
        if len(lams) == 1:  # the rule kept the control: no other decoder to draw
            row[1].set_axis_off()
            row[1].set_title(f"{name}: no lambda > 0 within the rule's cost bound")
        sweep = part[part.kind == "sweep"]
        row[2].plot(sweep.entropy, sweep.recon_error, "o-", color="#444")
        for _, r in sweep.iterrows():
            mark = " (chosen)" if np.isclose(r["lambda"], max(lams)) else ""
            where = {"textcoords": "offset points", "xytext": (5, 5), "fontsize": 8}
            row[2].annotate(f"λ={r['lambda']:g}{mark}", (r.entropy, r.recon_error), **where)
        row[2].set(
            xlabel="mean entropy of p(s,b) at confident contexts [nats]",
            ylabel="reconstruction error on the demonstrations [(rad/s)$^2$]",
        )
        row[2].set_title(f"{name}: reconstruction vs entropy over lambda")
    fig.tight_layout()
    return fig


def findings(table: pd.DataFrame, chosen: float, n_goals: int) -> str:
    """The rule's choice and its cost against the lambda = 0 control, as Markdown bullets from the sweep
    (:class:`Sweep`'s ``table``, lambda = 0 included); ``n_goals`` G: the entropy's maximum is log G."""
    rows = table.set_index("lambda")
    if 0.0 not in rows.index or chosen not in rows.index:
        raise ConfigError(f"the sweep must hold lambda = 0 and {chosen:g}; it has {list(rows.index)}")
    run, control, top = rows.loc[chosen], rows.loc[0.0], float(np.log(n_goals))
    if chosen == 0.0:  # no lambda > 0 was within the rule's cost bound
        others = rows[rows.index > 0]
        cheapest = others.recon_error.idxmin()
        return (
            f"- **The rule keeps the control, λ = 0.** No λ > 0 of the sweep keeps the reconstruction error "
            f"within {LAMBDA_COST:g}× the control's {control.recon_error:.3g} (rad/s)²: the least costly, "
            f"λ = {cheapest:g}, has {others.recon_error[cheapest] / control.recon_error:.2f}× it. The "
            f"LA+SA+Entropy decoder is then the control's, without the entropy term; a sweep of smaller λ "
            f"may find one."
        )
    spread = f"{run.entropy_confident:.3f} nats, {run.entropy_confident / top:.0%} of the most, log {n_goals}"
    cost = run.recon_error / control.recon_error
    side = "below" if cost < 1 else "above" if cost > 1 else "equal to"
    return (
        f"- **The rule chooses λ = {chosen:g}.** At confident contexts its mean entropy of p is {spread}; "
        f"the control's is {control.entropy_confident:.3f} ({control.entropy_confident / top:.0%}).\n"
        f"- **Its cost.** Its reconstruction error is {run.recon_error:.3g} (rad/s)², {cost:.2f}× the "
        f"control's {control.recon_error:.3g} ({side} it); held out, {run.val_error:.3g} against "
        f"{control.val_error:.3g}."
    )
