r"""The eating task's 2-D latent actions (notebook 10): demonstrations, training, what z does.

Each segmentation trains a base decoder, fine-tuned with lambda = 0 and with notebook 03's rule's lambda;
the headline is chosen by the latent property alone (:func:`train_variants`), before any participant runs.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import matplotlib.pyplot as plt
import mujoco
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.figure import Figure

from lasa.base.config import (
    BeliefCap,
    ControlConfig,
    NonNegative,
    Positive,
    PositiveInt,
    Seed,
    check_choice,
    check_list,
    to_dict,
    validate_caps,
)
from lasa.base.errors import ConfigError
from lasa.base.paths import Paths, resolve
from lasa.evidence import latent_measure, latent_property
from lasa.experiments import entropy_ablation
from lasa.experiments.sweep import check_names
from lasa.method.belief import belief_targets, confident_belief
from lasa.method.dataset import Demonstrations, save_demonstrations
from lasa.method.decoder import ActionDecoder, LatentActionModel, save_checkpoint
from lasa.method.kinesthetic import load_recorded, relabel_beliefs
from lasa.method.train import TrainConfig
from lasa.people.demos import EATING_DEMOS, SEGMENTATIONS, DemoConfig, collect_eating_demonstrations
from lasa.pipeline.scaleout import run_jobs
from lasa.world.eating import GOALS, STUDY_BELIEF_CAP, EatingTask
from lasa.world.fork import tip_frames

NAME = "eating_latent"
# latent_property.csv's source and task of the cap sweep's decoders (train_caps): apart from the
# decoder variants the rule chooses among (source and task "eating")
CAP_SOURCE = "eating_caps"
COLUMNS = ("robot", "goal", "belief", "z1", "z2", "vx", "vy", "vz", "tilt_rate", "toward")
BELIEFS = ("uncertain", "confident")
_Shared = tuple[EatingTask, latent_measure.PropertyConfig, str]  # run_jobs' shared: task, measure, source
_Variant = tuple[str, LatentActionModel, TrainConfig, ControlConfig]  # name, decoder, fine-tune, control
_SUBSETS = ("search_segmentations", "sector_segmentations", "seed_segmentations")  # of segmentations


@dataclasses.dataclass(frozen=True)
class Config:
    """The eating decoder's data and training (notebook 10)."""

    demos: DemoConfig = EATING_DEMOS  # the demonstrations (lasa.people.demos.DemoConfig, its own seed)
    train: TrainConfig = TrainConfig(z_dim=2)  # its seed every fine-tune's; z_dim 2: two stick axes
    goal: str = "middle"  # the bowl the figure looks at [-]
    # segmentations trained: at paper scale the two with the property under the study's cap;
    # all of SEGMENTATIONS under LARGE=1 (configs/large.yaml) [-]
    segmentations: tuple[str, ...] = ("continuous", "transfers")
    lambdas: tuple[NonNegative, ...] = (0.0, 0.1, 0.3, 1.0, 3.0)  # notebook 03's sweep, continuous base
    sweep_steps: PositiveInt = 800  # fine-tuning steps of every lambda run (notebook 03's) [-]
    search_lambdas: tuple[Positive, ...] = (0.003, 0.01, 0.03)  # small weights searched for both halves [-]
    search_segmentations: tuple[str, ...] = ()  # bases the search fine-tunes (LARGE=1: transfers, leaves) [-]
    # bases trained with the sector loss too (lasa.method.train; <segmentation>_sectors, lambda = 0); the
    # weight had the lower held-out reconstruction error of two probes (0.2: 0.0085, 1.0: 0.0118)
    sector_segmentations: tuple[str, ...] = ()  # segmentations trained with sectors (LARGE=1: leaves) [-]
    sector_weight: NonNegative = 0.2  # weight of the sector loss of those segmentations [-]
    # bases trained again with each search seed, fine-tuned with lambda = 0 (<segmentation>_seed<seed>) [-]
    seed_segmentations: tuple[str, ...] = ("transfers",)
    search_seeds: tuple[Seed, ...] = (1, 2)  # their training seeds (the variants' own: train.seed) [-]
    belief_cap: BeliefCap = STUDY_BELIEF_CAP  # the study's; None ("none"): Algorithm 1's uncapped
    cap_sweep: tuple[BeliefCap, ...] = (0.9, 0.95, 0.999, None)  # the headline's recipe again (train_caps)
    jobs: PositiveInt = 1  # local worker processes for the trainings: the same decoders with any number [-]
    # kinesthetic demonstrations recorded on the arm (`python -m lasa.live.teleop demos`), a .npz relative
    # to the repository: every reading trains from them instead of the synthetic ones; None: synthetic [-]
    recorded_demos: str | None = None

    def __post_init__(self) -> None:
        validate_caps(self)
        check_choice("goal", self.goal, GOALS)
        if self.train.z_dim != 2:
            raise ConfigError(
                f"train.z_dim must be 2 (the study's stick has two axes), got {self.train.z_dim}"
            )
        check_names("segmentations", self.segmentations, SEGMENTATIONS)
        if "continuous" not in self.segmentations:
            raise ConfigError("segmentations must include 'continuous': the lambda sweep runs on its base")
        for field in ("lambdas", "search_lambdas"):
            object.__setattr__(self, field, tuple(float(x) for x in getattr(self, field)))
        entropy_ablation.Config(lambdas=self.lambdas, sweep_steps=self.sweep_steps)  # its checks
        check_list("search_lambdas", self.search_lambdas, at_least=0, ascending=True)
        for field in ("segmentations", *_SUBSETS, "search_seeds"):
            object.__setattr__(self, field, check_list(field, getattr(self, field), at_least=0))
        if self.train.seed in self.search_seeds:
            raise ConfigError(
                f"search_seeds must differ from train.seed ({self.train.seed}), got {self.search_seeds}"
            )
        for field, name in ((f, n) for f in _SUBSETS for n in getattr(self, f)):
            if name not in self.segmentations:
                raise ConfigError(f"{field} must be among segmentations {self.segmentations}, got {name!r}")
        if self.sector_segmentations and not self.sector_weight > 0:
            raise ConfigError(
                f"sector_weight must be > 0 when sector_segmentations are trained, got {self.sector_weight}"
            )


def demonstrations(
    task: EatingTask, control: ControlConfig, config: Config, segmentation: str = "continuous"
) -> Demonstrations:
    """The demonstrations a reading trains from: ``config.recorded_demos`` (checked against ``task``, the
    beliefs recomputed under ``control``'s cap if it is not the study's), else the synthetic ones cut by
    ``segmentation``."""
    if config.recorded_demos is None:
        return collect_eating_demonstrations(task, control, config.demos, segmentation=segmentation)
    demos = load_recorded(resolve(config.recorded_demos), task)
    return demos if control == task.robot.control else relabel_beliefs(demos, task, control)


def demonstrations_used(config: Config) -> str:
    """Which demonstrations the decoders train from, for the notebook to say."""
    if config.recorded_demos is None:
        return "synthetic demonstrations (lasa.people.demos.collect_eating_demonstrations)"
    return f"recorded kinesthetic demonstrations {resolve(config.recorded_demos)}"


def variant_names(config: Config) -> list[str]:
    """The decoder variants, in training order (:func:`fine_tunes`)."""
    return [name for name, _, _ in fine_tunes(config, 0.0)]


def fine_tunes(config: Config, chosen: float) -> list[tuple[str, str, float]]:
    """(name, base, lambda) of every decoder variant, the sector and seed bases (:func:`_bases`) as they
    are; ``chosen``: notebook 03's rule's lambda."""
    out: list[tuple[str, str, float]] = []
    bases = _bases(config)
    for r in config.segmentations:
        out += [(r, r, 0.0), (f"{r}_entropy", r, chosen)]
        if r in config.search_segmentations:
            out += [(f"{r}_lambda{w:g}", r, w) for w in config.search_lambdas]
        out += [(b, b, 0.0) for b, (segmentation, _) in bases.items() if segmentation == r and b != r]
    return out


def _bases(config: Config) -> dict[str, tuple[str, TrainConfig]]:
    """Per base: its segmentation and training settings (the sector bases add the loss, the seed
    bases another seed)."""
    train = config.train
    out = {r: (r, train) for r in config.segmentations}
    for r in config.sector_segmentations:
        out[f"{r}_sectors"] = (r, dataclasses.replace(train, sector_weight=config.sector_weight))
    for r in config.seed_segmentations:
        out.update({f"{r}_seed{s}": (r, dataclasses.replace(train, seed=s)) for s in config.search_seeds})
    return out


@dataclasses.dataclass(frozen=True)
class Variants:
    """The trained variants of the study's decoder, notebook 03's sweep on the continuous base, the
    demonstrations' sizes per segmentation, every variant's property rows and the rule's ``headline``."""

    models: dict[str, LatentActionModel]
    sweep: pd.DataFrame
    chosen_lambda: float
    demos: pd.DataFrame
    property: pd.DataFrame
    headline: str


def train_variants(
    task: EatingTask,
    control: ControlConfig,
    config: Config,
    paths: Paths,
    prop: latent_measure.PropertyConfig = latent_measure.PropertyConfig(),
    progress: bool = True,
) -> Variants:
    """Train every decoder variant, measure its property, choose the headline by the property alone."""
    datasets: dict[str, Demonstrations] = {}
    sizes: list[tuple[object, ...]] = []
    robot = task.robot.name
    for r in config.segmentations:  # each segmentation's tuples, saved, and a row of their sizes
        datasets[r] = demos = demonstrations(task, control, config, segmentation=r)
        save_demonstrations(demos, paths.artifact("eating_segmentation_demos", robot, segmentation=r))
        clean = demos.clean()
        sizes.append((r, int(clean.demo.max() + 1), len(clean), len(clean) * control.dt / 60, len(demos)))
    demo_rows = pd.DataFrame(sizes, columns=["reading", "demonstrations", "steps", "minutes", "tuples"])
    plan = _bases(config)
    runs = [entropy_ablation.Run(datasets[r], control, settings) for r, settings in plan.values()]
    fitted = entropy_ablation.train_all(runs, config.jobs, progress, desc="base decoders")
    bases = {base: model for base, (model, _) in zip(plan, fitted, strict=True)}
    datasets.update({base: datasets[segmentation] for base, (segmentation, _) in plan.items()})
    sweep_config = entropy_ablation.Config(
        lambdas=config.lambdas, sweep_steps=config.sweep_steps, seed=config.train.seed, jobs=config.jobs
    )
    continuous = (bases["continuous"], config.train, datasets["continuous"])
    sweep = entropy_ablation.run_sweep(*continuous, task, control, sweep_config, progress)
    goal_sets = belief_targets(task, control.likelihood)
    models, fines, runs_of = {}, {}, {}
    for name, base, weight in fine_tunes(config, sweep.chosen):
        if base == "continuous" and weight in sweep.models:  # the sweep's own
            models[name], fines[name] = sweep.models[weight], sweep.configs[weight]
        else:
            fines[name] = dataclasses.replace(plan[base][1], steps=config.sweep_steps, entropy_lambda=weight)
            runs_of[name] = entropy_ablation.Run(datasets[base], control, fines[name], goal_sets, bases[base])
    fitted = entropy_ablation.train_all(list(runs_of.values()), config.jobs, progress, "decoder readings")
    models.update({name: model for name, (model, _) in zip(runs_of, fitted, strict=True)})
    variants = [(name, models[name], fines[name], control) for name, _, _ in fine_tunes(config, sweep.chosen)]
    frame = _keep(config, paths, (task, prop, "eating"), variants)
    headline = latent_property.choose(latent_property.summary(frame))
    path = paths.artifact("eating_decoder", robot)
    _save(path, (headline, models[headline], fines[headline], control), config)
    kept = {name: model for name, model, _, _ in variants}
    return Variants(kept, sweep.table, float(sweep.chosen), demo_rows, frame, headline)


def _save(path: Path, variant: _Variant, config: Config) -> None:
    """A variant's decoder, saved with the settings that made it and the variant's name."""
    name, model, fine, control = variant
    extra: dict[str, object] = {
        "train": to_dict(fine),
        "control": to_dict(control),
        "demos": to_dict(config.demos),
    }
    if config.recorded_demos is not None:  # only then: the synthetic path's checkpoints stay as they were
        extra["recorded_demos"] = config.recorded_demos
    save_checkpoint(model, path, **extra, reading=name)


def _keep(config: Config, paths: Paths, shared: _Shared, variants: list[_Variant]) -> pd.DataFrame:
    """Save each (name, decoder, fine-tune, control) as its variant's decoder; their property rows."""
    for variant in variants:
        path = paths.artifact("eating_segmentation_decoder", shared[0].robot.name, segmentation=variant[0])
        _save(path, variant, config)
    frames = run_jobs(_measure, variants, n_jobs=config.jobs, shared=shared)
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=latent_property.COLUMNS)


def cap_label(cap: float | None) -> str:
    """A belief cap's name in decoder variant names: ``uncapped``, or ``cap0.99``."""
    return "uncapped" if cap is None else f"cap{cap:g}"


def cap_decoder_name(headline: str, cap: float | None) -> str:
    """The cap sweep's decoder of ``headline``'s recipe trained at ``cap``: ``transfers_uncapped``."""
    return f"{headline}_{cap_label(cap)}"


def train_caps(
    task: EatingTask,
    control: ControlConfig,
    config: Config,
    paths: Paths,
    variants: Variants,
    prop: latent_measure.PropertyConfig = latent_measure.PropertyConfig(),
    progress: bool = True,
) -> pd.DataFrame:
    """The headline's recipe trained again at every cap of ``config.cap_sweep`` but the study's (each
    saved as :func:`cap_decoder_name`): their property rows (source :data:`CAP_SOURCE`)."""
    caps = [c for c in config.cap_sweep if c != control.belief_cap]
    base, weight = {n: (b, w) for n, b, w in fine_tunes(config, variants.chosen_lambda)}[variants.headline]
    seg, base_train = _bases(config)[base]
    fine = dataclasses.replace(base_train, steps=config.sweep_steps, entropy_lambda=weight)
    controls = [dataclasses.replace(control, belief_cap=c) for c in caps]
    demos = [demonstrations(task, c, config, segmentation=seg) for c in controls]
    runs = [entropy_ablation.Run(d, c, base_train) for d, c in zip(demos, controls, strict=True)]
    bases = entropy_ablation.train_all(runs, config.jobs, progress, desc="bases at each cap")
    goal_sets = belief_targets(task, control.likelihood)
    runs = [
        entropy_ablation.Run(d, c, fine, goal_sets, m)
        for d, c, (m, _) in zip(demos, controls, bases, strict=True)
    ]
    fitted = entropy_ablation.train_all(runs, config.jobs, progress, desc="decoders at each cap")
    names = [cap_decoder_name(variants.headline, c) for c in caps]
    kept = [(n, m, fine, c) for n, (m, _), c in zip(names, fitted, controls, strict=True)]
    return _keep(config, paths, (task, prop, CAP_SOURCE), kept)


def _measure(shared: _Shared, job: _Variant) -> pd.DataFrame:
    """One variant's property rows (a job of :func:`lasa.pipeline.scaleout.run_jobs`)."""
    (task, prop, source), (name, model, _, ctl) = shared, job
    return latent_measure.measure(task, model, ctl, prop, source=source, task_name=source, decoder_name=name)


def directions(
    task: EatingTask, decoder: ActionDecoder, control: ControlConfig, goal: str, n: int = 8
) -> pd.DataFrame:
    """What the ``n`` full stick deflections do at ``goal``'s mid-preference entry, per belief."""
    g = GOALS.index(check_choice("goal", goal, GOALS))
    state = task.target(g, 0.5)
    z = latent_measure.ring(n, 2)  # at rest the stick commands nothing
    states = np.broadcast_to(state, (len(z), len(state)))
    confident = confident_belief(task.n_goals, g, control.belief_floor, control.belief_cap)
    beliefs = {"uncertain": np.full(task.n_goals, 1.0 / task.n_goals), "confident": confident}
    pos, axis, jp, jr = tip_frames(task.robot, mujoco.MjData(task.robot.model), state[None])
    to_goal = task.robot.goal_positions() - pos[0]
    to_goal /= np.linalg.norm(to_goal, axis=1, keepdims=True)
    rows = []
    for name, b in beliefs.items():
        qdot = decoder.decode_numpy(z, states, np.broadcast_to(b, (len(z), len(b))))
        v = qdot @ jp[0].T
        w = qdot @ jr[0].T
        d_axis = np.cross(w, axis[0])  # rate of change of the fork's direction
        # tilt from vertical: angle between the axis and (0, 0, -1); its rate
        tilt_rate = -d_axis[:, 2] / max(np.sqrt(1.0 - axis[0, 2] ** 2), 1e-6)
        speed = np.linalg.norm(v, axis=1)
        cos = (v / np.maximum(speed, 1e-12)[:, None]) @ to_goal.T
        best = np.where(np.arange(len(GOALS)) == g, -np.inf, cos).argmax(axis=1)  # other goals
        toward = np.where(
            speed < 0.01, "-", np.where(cos[np.arange(len(z)), best] > 0.7, np.asarray(GOALS)[best], "here")
        )
        values = [task.robot.name, goal, name, *z.T, *v.T, tilt_rate, toward]
        rows.append(pd.DataFrame(dict(zip(COLUMNS, values, strict=True))))
    return pd.concat(rows, ignore_index=True)


def plot(frame: pd.DataFrame) -> Figure:
    """Two panels (uncertain, confident belief), each the stick seen from above."""
    sns.set_theme(style="white")
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.2))
    tilt = np.degrees(frame.tilt_rate.to_numpy())
    vmax = max(float(np.abs(tilt).max()), 1.0)
    cmap = plt.get_cmap("coolwarm")
    norm = plt.Normalize(-vmax, vmax)
    scale = 0.5 / 0.1  # 0.1 m/s -> half the unit circle
    arrow = {"arrowstyle": "-|>", "color": "0.2", "lw": 1.6}
    for ax, name in zip(axes, BELIEFS, strict=True):
        part = frame[frame.belief == name]
        ax.add_patch(plt.Circle((0, 0), 1.0, fill=False, color="0.8", lw=1))
        for _, row in part.iterrows():
            x0, y0 = row.z1, row.z2
            xy = (x0 - row.vy * scale, y0 + row.vx * scale)
            ax.annotate("", xy=xy, xytext=(x0, y0), arrowprops=arrow)
            ax.scatter([x0], [y0], s=90, color=cmap(norm(np.degrees(row.tilt_rate))), edgecolor="k", zorder=3)
            label = f"{row.toward}\n{100 * row.vz:+.0f} cm/s up"
            ax.text(x0 * 1.3, y0 * 1.3 - 0.12, label, fontsize=7, ha="center", va="center")
        ticks, lim = [-1, 0, 1], (-1.9, 1.9)
        ax.set(xlim=lim, ylim=lim, aspect="equal", xticks=ticks, yticks=ticks, xlabel="stick axis z1")
        ax.set_title(f"belief {name}")
    axes[0].set_ylabel("stick axis z2")
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=norm)
    fig.colorbar(sm, ax=axes, label="tilt rate of the fork [deg/s]", shrink=0.75)
    fig.suptitle(
        f"What each stick deflection does at the {frame.goal.iloc[0]} bowl\n"
        "arrows: the fork tip's velocity seen from above, 0.1 m/s = half a radius"
    )
    return fig


def _names(items: list[str]) -> str:
    """```a```, ```a`` and ``b```, ```a``, ``b`` and ``c```."""
    quoted = [f"`{i}`" for i in items]
    return quoted[0] if len(quoted) == 1 else f"{', '.join(quoted[:-1])} and {quoted[-1]}"


def property_sentence(prop: pd.DataFrame) -> str:
    """Which decoder variants meet the two-half rule, which the rule ranks first, how the others fall
    short; ``prop``: one task's :func:`lasa.evidence.latent_property.summary`."""
    meets = latent_property.holds(prop)
    first = latent_property.choose(prop)
    good = list(meets[meets].index)
    if good:
        rows = prop[prop.decoder.isin(good)]
        stay, n, leave = 100 * rows.stay_share.min(), int(rows.n_inputs.max()), rows.leave_min.min()
        head = (
            f"{len(good)} of {len(meets)} readings meet the rule: {_names(good)}; "
            f"the rule ranks `{first}` first. At each, at least {stay:.0f}% of the {n} inputs stay "
            f"at every goal, and at least {leave:.0f} reach every other goal from each stroke end."
        )
    else:
        head = f"None of the {len(meets)} readings meets the rule; the best reading is `{first}`."
    tails = _shortfalls(prop, meets, " (at most {:.0f}% of the inputs stay at a goal)")
    return head + (f" {tails}." if tails else "")


def caps_sentence(cap_prop: pd.DataFrame) -> str:
    """At which caps the headline's recipe meets the rule (:func:`train_caps`' property), in one sentence."""
    if cap_prop.empty:
        return "No other cap was trained."
    meets = latent_property.holds(cap_prop)
    good = list(meets[meets].index)
    said = f"the rule is met by {_names(good)}" if good else "no cap's decoder meets the rule"
    tails = _shortfalls(cap_prop, meets, "")
    return f"Of the recipe's decoders at other caps, {said}" + (f"; {tails}." if tails else ".")


def _shortfalls(prop: pd.DataFrame, meets: pd.Series, share: str) -> str:
    """```d`` misses ...`` of each decoder that misses the rule: the halves and goals (``the stay half at
    the plate``), or ``a goal from home``; ``share`` formats its top stay share."""
    tails = []
    for d, rows in prop[prop.decoder.isin(list(meets[~meets].index))].groupby("decoder", sort=False):
        parts = []
        for half, column in (("stay", "stay_holds"), ("leave", "leave_holds")):
            goals = list(rows.goal[~rows[column].astype(bool)])
            if len(goals) == len(rows):
                parts.append(f"the {half} half at every goal")
            elif goals:
                parts.append(f"the {half} half at {' and '.join(f'the {g}' for g in goals)}")
        if not rows.all_reached.astype(bool).all():
            parts.append("a goal from home")
        misses = " and ".join(parts) or "the rule"
        tails.append(f"`{d}` misses {misses}" + share.format(100 * rows.stay_share.max()))
    return "; ".join(tails)
