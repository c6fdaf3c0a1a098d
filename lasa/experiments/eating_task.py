r"""The eating task's 2-D latent actions (notebook 10): demonstrations, training, what z does.

Each segmentation of the demonstrations trains a base decoder, fine-tuned with lambda = 0 and with
notebook 03's rule's lambda; the study's headline is chosen by the latent property alone
(:func:`train_variants`), before any participant runs.
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
    cap_setting,
    check_choice,
    check_list,
    to_dict,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.base.paths import Paths
from lasa.evidence import latent_measure, latent_property
from lasa.experiments import entropy_ablation
from lasa.method.belief import belief_targets, confident_belief
from lasa.method.dataset import Demonstrations, save_demonstrations
from lasa.method.decoder import ActionDecoder, LatentActionModel, save_checkpoint
from lasa.method.train import TrainConfig
from lasa.people.demos import EATING_DEMOS, SEGMENTATIONS, DemoConfig, collect_eating_demonstrations
from lasa.pipeline.scaleout import run_jobs
from lasa.world.eating import GOALS, STUDY_BELIEF_CAP, EatingTask
from lasa.world.fork import tip_frames

__all__ = [
    "NAME",
    "COLUMNS",
    "Config",
    "BELIEFS",
    "Variants",
    "variant_names",
    "train_variants",
    "CAP_SOURCE",
    "CapDecoders",
    "cap_label",
    "cap_decoder_name",
    "train_caps",
    "directions",
    "plot",
    "property_sentence",
    "caps_sentence",
]

NAME = "eating_latent"
# latent_property.csv's source and task of the cap sweep's decoders (train_caps): apart from the
# decoder variants the rule chooses among (source and task "eating")
CAP_SOURCE = "eating_caps"
COLUMNS = ("robot", "goal", "belief", "z1", "z2", "vx", "vy", "vz", "tilt_rate", "toward")
BELIEFS = ("uncertain", "confident")


@dataclasses.dataclass(frozen=True)
class Config:
    """The eating decoder's data and training (notebook 10)."""

    demos: DemoConfig = EATING_DEMOS  # the demonstrations (lasa.people.demos.DemoConfig, its own seed)
    # training (lasa.method.train.TrainConfig, its seed every fine-tune's): z_dim stays 2, two stick axes
    train: TrainConfig = TrainConfig(z_dim=2)
    goal: str = "middle"  # the bowl the figure looks at [-]
    # segmentations trained: at paper scale the two with the property under the study's cap;
    # all of SEGMENTATIONS under LARGE=1 (configs/large.yaml) [-]
    segmentations: tuple[str, ...] = ("continuous", "transfers")
    # notebook 03's sweep, on the continuous base [-]
    lambdas: tuple[NonNegative, ...] = (0.0, 0.1, 0.3, 1.0, 3.0)
    sweep_steps: PositiveInt = 800  # fine-tuning steps of every lambda run (notebook 03's) [-]
    # small entropy weights searched for both halves of the property, one fine-tune each [-]
    search_lambdas: tuple[Positive, ...] = (0.003, 0.01, 0.03)
    search_segmentations: tuple[str, ...] = ()  # bases the search fine-tunes (LARGE=1: transfers, leaves) [-]
    # bases trained with the sector loss too (lasa.method.sectors; <segmentation>_sectors, lambda = 0); the
    # weight had the lower held-out reconstruction error of two probes (0.2: 0.0085, 1.0: 0.0118)
    sector_segmentations: tuple[str, ...] = ()  # segmentations trained with sectors (LARGE=1: leaves) [-]
    sector_weight: NonNegative = 0.2  # weight of the sector loss of those segmentations [-]
    # bases trained again with each search seed, fine-tuned with lambda = 0 (<segmentation>_seed<seed>) [-]
    seed_segmentations: tuple[str, ...] = ("transfers",)
    search_seeds: tuple[Seed, ...] = (1, 2)  # their training seeds (the variants' own: train.seed) [-]
    # the study's belief cap (lasa.world.eating.STUDY_BELIEF_CAP); None ("none"): Algorithm 1's uncapped
    belief_cap: BeliefCap = STUDY_BELIEF_CAP
    # the headline's recipe trained again at each of these caps (train_caps); notebook 11 runs them [-]
    cap_sweep: tuple[BeliefCap, ...] = (0.9, 0.95, 0.999, None)
    # local worker processes for the trainings (entropy_ablation.train_all): the same decoders with any [-]
    jobs: PositiveInt = 1

    def __post_init__(self) -> None:
        object.__setattr__(self, "belief_cap", cap_setting(self.belief_cap))
        object.__setattr__(self, "cap_sweep", tuple(cap_setting(c) for c in self.cap_sweep))
        validate(self)
        if len(set(self.cap_sweep)) != len(self.cap_sweep):
            raise ConfigError(f"cap_sweep must not repeat a cap, got {self.cap_sweep}")
        check_choice("goal", self.goal, GOALS)
        if self.train.z_dim != 2:
            raise ConfigError(
                f"train.z_dim must be 2 (the study's stick has two axes), got {self.train.z_dim}"
            )
        object.__setattr__(self, "segmentations", tuple(self.segmentations))
        object.__setattr__(self, "lambdas", tuple(float(x) for x in self.lambdas))
        if not self.segmentations:
            raise ConfigError("segmentations must name at least one of " + ", ".join(SEGMENTATIONS))
        for name in self.segmentations:
            check_choice("segmentation", name, SEGMENTATIONS)
        if "continuous" not in self.segmentations:
            raise ConfigError("segmentations must include 'continuous': the lambda sweep runs on its base")
        entropy_ablation.Config(lambdas=self.lambdas, sweep_steps=self.sweep_steps)  # its checks
        object.__setattr__(self, "search_lambdas", tuple(float(x) for x in self.search_lambdas))
        object.__setattr__(self, "search_segmentations", tuple(self.search_segmentations))
        object.__setattr__(self, "sector_segmentations", tuple(self.sector_segmentations))
        object.__setattr__(self, "seed_segmentations", tuple(self.seed_segmentations))
        object.__setattr__(self, "search_seeds", tuple(self.search_seeds))
        check_list("search_lambdas", self.search_lambdas, at_least=0, ascending=True)
        for field in (
            "segmentations",
            "search_segmentations",
            "sector_segmentations",
            "seed_segmentations",
            "search_seeds",
        ):
            check_list(field, getattr(self, field), at_least=0)
        if self.train.seed in self.search_seeds:
            raise ConfigError(
                f"search_seeds must differ from train.seed ({self.train.seed}), got {self.search_seeds}"
            )
        for field in ("search_segmentations", "sector_segmentations", "seed_segmentations"):
            for name in getattr(self, field):
                if name not in self.segmentations:
                    raise ConfigError(
                        f"{field} must be among segmentations {self.segmentations}, got {name!r}"
                    )
        if self.sector_segmentations and not self.sector_weight > 0:
            raise ConfigError(
                f"sector_weight must be > 0 when sector_segmentations are trained, got {self.sector_weight}"
            )


def variant_names(config: Config) -> list[str]:
    """The decoder variants, in training order (:func:`fine_tunes`)."""
    return [name for name, _, _ in fine_tunes(config, 0.0)]


def fine_tunes(config: Config, chosen: float) -> list[tuple[str, str, float | None]]:
    """(name, base, lambda) of every decoder variant; lambda None: notebook 03's rule's."""
    out: list[tuple[str, str, float | None]] = []
    for r in config.segmentations:
        out += [(r, r, 0.0), (f"{r}_entropy", r, None)]
        if r in config.search_segmentations:
            out += [(f"{r}_lambda{w:g}", r, w) for w in config.search_lambdas]
        if r in config.sector_segmentations:
            out.append((f"{r}_sectors", f"{r}_sectors", 0.0))
        if r in config.seed_segmentations:
            out += [(f"{r}_seed{s}", f"{r}_seed{s}", 0.0) for s in config.search_seeds]
    return out


def _bases(config: Config, train: TrainConfig) -> dict[str, tuple[str, TrainConfig]]:
    """Per base: its segmentation and training settings (the sector bases add the loss,
    the seed bases another seed).
    """
    out = {r: (r, train) for r in config.segmentations}
    for r in config.sector_segmentations:
        out[f"{r}_sectors"] = (r, dataclasses.replace(train, sector_weight=config.sector_weight))
    for r in config.seed_segmentations:
        out.update({f"{r}_seed{s}": (r, dataclasses.replace(train, seed=s)) for s in config.search_seeds})
    return out


@dataclasses.dataclass(frozen=True)
class Variants:
    """The trained variants of the study's decoder and the choice among them.

    Attributes:
        models: Decoder per variant name (:func:`variant_names`).
        sweep: Notebook 03's sweep on the continuous base (one row per lambda).
        chosen_lambda: The lambda its rule picked.
        demos: Demonstration tuples (clean, noisy copies) and minutes of motion per segmentation.
        property: :func:`lasa.evidence.latent_measure.measure` rows of every variant.
        headline: The variant the property's rule picks.
    """

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
    train = config.train
    datasets, demo_rows = _demonstrations(task, control, config, paths)
    plan = _bases(config, train)
    runs = [
        entropy_ablation.Run(datasets[segmentation], control, settings)
        for segmentation, settings in plan.values()
    ]
    fitted = entropy_ablation.train_all(runs, config.jobs, progress, desc="base decoders")
    bases = {base: model for base, (model, _) in zip(plan, fitted, strict=True)}
    trained = {base: settings for base, (_, settings) in plan.items()}
    datasets.update({base: datasets[segmentation] for base, (segmentation, _) in plan.items()})
    sweep_config = entropy_ablation.Config(
        lambdas=config.lambdas, sweep_steps=config.sweep_steps, seed=train.seed, jobs=config.jobs
    )
    sweep = entropy_ablation.run_sweep(
        bases["continuous"], train, datasets["continuous"], task, control, sweep_config, progress=progress
    )
    models, fines = _fine_tune(task, control, config, paths, sweep, bases, trained, datasets, progress)
    jobs = [(m, control, n) for n, m in models.items()]
    frame = pd.concat(
        run_jobs(_measure, jobs, n_jobs=config.jobs, shared=(task, prop, "eating")), ignore_index=True
    )
    headline = latent_property.choose(latent_property.summary(frame))
    path = paths.artifact("eating_decoder", task.robot.name)
    _save(models[headline], path, fines[headline], control, config, variant=headline)
    return Variants(models, sweep.table, float(sweep.chosen), pd.DataFrame(demo_rows), frame, headline)


def _demonstrations(
    task: EatingTask, control: ControlConfig, config: Config, paths: Paths
) -> tuple[dict[str, Demonstrations], list[dict[str, object]]]:
    """Each segmentation's tuples (saved), and a row of its sizes."""
    datasets, rows = {}, []
    for segmentation in config.segmentations:
        demos = collect_eating_demonstrations(task, control, config.demos, segmentation=segmentation)
        save_demonstrations(
            demos, paths.artifact("eating_segmentation_demos", task.robot.name, segmentation=segmentation)
        )
        clean = demos.clean()
        rows.append(
            {
                "reading": segmentation,
                "demonstrations": int(clean.demo.max() + 1),
                "steps": len(clean),
                "minutes": len(clean) * control.dt / 60,
                "tuples": len(demos),
            }
        )
        datasets[segmentation] = demos
    return datasets, rows


def _fine_tune(
    task: EatingTask,
    control: ControlConfig,
    config: Config,
    paths: Paths,
    sweep: entropy_ablation.Sweep,
    bases: dict[str, LatentActionModel],
    trained: dict[str, TrainConfig],
    datasets: dict[str, Demonstrations],
    progress: bool,
) -> tuple[dict[str, LatentActionModel], dict[str, TrainConfig]]:
    """Every variant's decoder (:func:`fine_tunes`; the sweep's own where it trained it), saved."""
    goal_sets = belief_targets(task, control.likelihood)
    lam = sweep.chosen
    models: dict[str, LatentActionModel] = {}
    fines: dict[str, TrainConfig] = {}
    runs: dict[str, entropy_ablation.Run] = {}
    for name, base, weight in fine_tunes(config, lam):
        weight = lam if weight is None else weight
        if base == "continuous" and weight in sweep.models:
            models[name], fines[name] = sweep.models[weight], sweep.configs[weight]
            continue
        fines[name] = dataclasses.replace(
            trained[base], steps=config.sweep_steps, entropy_lambda=weight, seed=trained[base].seed
        )
        runs[name] = entropy_ablation.Run(datasets[base], control, fines[name], goal_sets, bases[base])
    fitted = entropy_ablation.train_all(list(runs.values()), config.jobs, progress, desc="decoder readings")
    models.update({name: model for name, (model, _) in zip(runs, fitted, strict=True)})
    models = {name: models[name] for name, _, _ in fine_tunes(config, lam)}  # in training order
    for name, model in models.items():
        path = paths.artifact("eating_segmentation_decoder", task.robot.name, segmentation=name)
        _save(model, path, fines[name], control, config, variant=name)
    return models, fines


def _save(
    model: LatentActionModel,
    path: Path,
    fine: TrainConfig,
    control: ControlConfig,
    config: Config,
    variant: str,
) -> None:
    """A variant's decoder, saved with the settings that made it and the variant's name."""
    save_checkpoint(
        model,
        path,
        train=to_dict(fine),
        control=to_dict(control),
        demos=to_dict(config.demos),
        reading=variant,
    )


def cap_label(cap: float | None) -> str:
    """A belief cap's name in decoder variant names: ``uncapped``, or ``cap0.99``."""
    return "uncapped" if cap is None else f"cap{cap:g}"


def cap_decoder_name(headline: str, cap: float | None) -> str:
    """The cap sweep's decoder of ``headline``'s recipe trained at ``cap``: ``transfers_uncapped``."""
    return f"{headline}_{cap_label(cap)}"


@dataclasses.dataclass(frozen=True)
class CapDecoders:
    """The cap sweep's decoders (:func:`train_caps`).

    Attributes:
        models: Decoder per cap of the sweep (None: uncapped), the headline's recipe at that cap.
        names: Their variant names (:func:`cap_decoder_name`), per cap.
        property: Their :func:`lasa.evidence.latent_measure.measure` rows, each at its cap
            (source :data:`CAP_SOURCE`).
    """

    models: dict[float | None, LatentActionModel]
    names: dict[float | None, str]
    property: pd.DataFrame


def train_caps(
    task: EatingTask,
    control: ControlConfig,
    config: Config,
    paths: Paths,
    variants: Variants,
    prop: latent_measure.PropertyConfig = latent_measure.PropertyConfig(),
    progress: bool = True,
) -> CapDecoders:
    """The headline's recipe trained again at every cap of ``config.cap_sweep`` but the study's."""
    caps = [c for c in config.cap_sweep if c != control.belief_cap]
    lam = variants.chosen_lambda
    base, weight = {name: (b, w) for name, b, w in fine_tunes(config, lam)}[variants.headline]
    segmentation, base_train = _bases(config, config.train)[base]
    weight = lam if weight is None else weight
    fine = dataclasses.replace(
        base_train, steps=config.sweep_steps, entropy_lambda=weight, seed=base_train.seed
    )
    controls = {c: dataclasses.replace(control, belief_cap=c) for c in caps}
    demos = {
        c: collect_eating_demonstrations(task, controls[c], config.demos, segmentation=segmentation)
        for c in caps
    }
    runs = [entropy_ablation.Run(demos[c], controls[c], base_train) for c in caps]
    bases = entropy_ablation.train_all(runs, config.jobs, progress, desc="bases at each cap")
    goal_sets = belief_targets(task, control.likelihood)
    runs = [
        entropy_ablation.Run(demos[c], controls[c], fine, goal_sets, model)
        for c, (model, _) in zip(caps, bases, strict=True)
    ]
    fitted = entropy_ablation.train_all(runs, config.jobs, progress, desc="decoders at each cap")
    models = {c: model for c, (model, _) in zip(caps, fitted, strict=True)}
    names = {c: cap_decoder_name(variants.headline, c) for c in caps}
    for c, model in models.items():
        path = paths.artifact("eating_segmentation_decoder", task.robot.name, segmentation=names[c])
        _save(model, path, fine, controls[c], config, variant=names[c])
    jobs = [(models[c], controls[c], names[c]) for c in caps]
    frames = run_jobs(_measure, jobs, n_jobs=config.jobs, shared=(task, prop, CAP_SOURCE))
    frame = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=latent_property.COLUMNS)
    return CapDecoders(models, names, frame)


def _measure(
    shared: tuple[EatingTask, latent_measure.PropertyConfig, str],
    job: tuple[LatentActionModel, ControlConfig, str],
) -> pd.DataFrame:
    """One decoder's property rows (a job of :func:`lasa.pipeline.scaleout.run_jobs`)."""
    task, prop, source = shared
    model, control, name = job
    return latent_measure.measure(
        task, model, control, prop, source=source, task_name=source, decoder_name=name
    )


def directions(
    task: EatingTask, decoder: ActionDecoder, control: ControlConfig, goal: str, n: int = 8
) -> pd.DataFrame:
    """What the ``n`` full stick deflections do at ``goal``'s mid-preference entry, per belief."""
    g = GOALS.index(check_choice("goal", goal, GOALS))
    state = task.target(g, 0.5)
    angles = 2 * np.pi * np.arange(n) / n
    z = np.round(np.stack([np.cos(angles), np.sin(angles)], axis=1), 12)  # at rest the stick commands nothing
    confident = confident_belief(task.n_goals, g, control.belief_floor, control.belief_cap)
    beliefs = {"uncertain": np.full(task.n_goals, 1.0 / task.n_goals), "confident": confident}
    data = mujoco.MjData(task.robot.model)
    pos, axis, jp, jr = tip_frames(task.robot, data, state[None])
    goals = task.robot.goal_positions()
    rows = []
    for name, b in beliefs.items():
        qdot = decoder.decode_numpy(
            z, np.broadcast_to(state, (len(z), len(state))), np.broadcast_to(b, (len(z), len(b)))
        )
        v = qdot @ jp[0].T  # (Z, 3)
        w = qdot @ jr[0].T
        d_axis = np.cross(w, axis[0])  # rate of change of the fork's direction
        # tilt from vertical: angle between the axis and (0, 0, -1); its rate
        tilt_rate = -d_axis[:, 2] / max(np.sqrt(1.0 - axis[0, 2] ** 2), 1e-6)
        to_goal = goals - pos[0]
        to_goal /= np.linalg.norm(to_goal, axis=1, keepdims=True)
        speed = np.linalg.norm(v, axis=1)
        cos = (v / np.maximum(speed, 1e-12)[:, None]) @ to_goal.T
        best = np.where(np.arange(len(GOALS)) == g, -np.inf, cos).argmax(axis=1)  # other goals
        toward = np.where(
            speed < 0.01, "-", np.where(cos[np.arange(len(z)), best] > 0.7, np.asarray(GOALS)[best], "here")
        )
        rows.append(
            pd.DataFrame(
                {
                    "robot": task.robot.name,
                    "goal": goal,
                    "belief": name,
                    "z1": z[:, 0],
                    "z2": z[:, 1],
                    "vx": v[:, 0],
                    "vy": v[:, 1],
                    "vz": v[:, 2],
                    "tilt_rate": tilt_rate,
                    "toward": toward,
                }
            )
        )
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
    for ax, name in zip(axes, BELIEFS, strict=True):
        part = frame[frame.belief == name]
        ax.add_patch(plt.Circle((0, 0), 1.0, fill=False, color="0.8", lw=1))
        for _, row in part.iterrows():
            x0, y0 = row.z1, row.z2
            ax.annotate(
                "",
                xy=(x0 - row.vy * scale, y0 + row.vx * scale),
                xytext=(x0, y0),
                arrowprops={"arrowstyle": "-|>", "color": "0.2", "lw": 1.6},
            )
            ax.scatter([x0], [y0], s=90, color=cmap(norm(np.degrees(row.tilt_rate))), edgecolor="k", zorder=3)
            label = f"{row.toward}\n{100 * row.vz:+.0f} cm/s up"
            ax.text(x0 * 1.3, y0 * 1.3 - 0.12, label, fontsize=7, ha="center", va="center")
        ax.set_xlim(-1.9, 1.9)
        ax.set_ylim(-1.9, 1.9)
        ax.set_aspect("equal")
        ax.set_xticks([-1, 0, 1])
        ax.set_yticks([-1, 0, 1])
        ax.set_xlabel("stick axis z1")
        ax.set_title(f"belief {name}")
    axes[0].set_ylabel("stick axis z2")
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=norm)
    fig.colorbar(sm, ax=axes, label="tilt rate of the fork [deg/s]", shrink=0.75)
    goal = frame.goal.iloc[0]
    fig.suptitle(
        f"What each stick deflection does at the {goal} bowl\n"
        "arrows: the fork tip's velocity seen from above, 0.1 m/s = half a radius"
    )
    return fig


def _names(items: list[str]) -> str:
    """```a```, ```a`` and ``b```, ```a``, ``b`` and ``c```."""
    quoted = [f"`{i}`" for i in items]
    return quoted[0] if len(quoted) == 1 else f"{', '.join(quoted[:-1])} and {quoted[-1]}"


def _misses(rows: pd.DataFrame) -> str:
    """Where one decoder's property fails: the half and the goals, e.g. ``the stay half at the plate``."""
    parts = []
    for half, column in (("stay", "stay_holds"), ("leave", "leave_holds")):
        goals = list(rows.goal[~rows[column].astype(bool)])
        if len(goals) == len(rows):
            parts.append(f"the {half} half at every goal")
        elif goals:
            parts.append(f"the {half} half at {' and '.join(f'the {g}' for g in goals)}")
    if not rows.all_reached.astype(bool).all():
        parts.append("a goal from home")
    return " and ".join(parts) or "the rule"


def property_sentence(prop: pd.DataFrame) -> str:
    """Which decoder variants meet the two-half rule, which the rule ranks first, how the others fall short.

    Args:
        prop: One task's :func:`lasa.evidence.latent_property.summary` (the variants the rule chooses among).
    """
    meets = latent_property.holds(prop)
    first = latent_property.choose(prop)
    good, bad = list(meets[meets].index), list(meets[~meets].index)
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
    tails = [
        f"`{d}` misses {_misses(part)} "
        f"(at most {100 * part.stay_share.max():.0f}% of the inputs stay at a goal)"
        for d, part in prop[prop.decoder.isin(bad)].groupby("decoder", sort=False)
    ]
    return head + (f" {'; '.join(tails)}." if tails else "")


def caps_sentence(cap_prop: pd.DataFrame) -> str:
    """At which caps the headline's recipe meets the rule (:func:`train_caps`' property), in one sentence."""
    if cap_prop.empty:
        return "No other cap was trained."
    meets = latent_property.holds(cap_prop)
    good = list(meets[meets].index)
    said = f"the rule is met by {_names(good)}" if good else "no cap's decoder meets the rule"
    missing = cap_prop[cap_prop.decoder.isin(list(meets[~meets].index))]
    tails = [f"`{d}` misses {_misses(part)}" for d, part in missing.groupby("decoder", sort=False)]
    return f"Of the recipe's decoders at other caps, {said}" + (f"; {'; '.join(tails)}." if tails else ".")
