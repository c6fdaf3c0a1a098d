"""The eating study (notebook 11): its :class:`Config` and the simulated cohort's :func:`run` of both eating
tasks under R, R+SA, LA and LA+SA, each participant model, SA member and decoder variant."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from lasa.base.conditions import CONDITIONS, williams_square
from lasa.base.config import (
    NO_ASSISTANCE,
    AtLeastTwo,
    BeliefCap,
    ControlConfig,
    NonNegativeInt,
    PositiveInt,
    Seed,
    check_choice,
    check_list,
    check_range,
    validate_caps,
)
from lasa.base.errors import CheckpointError, ConfigError
from lasa.base.io import require_file
from lasa.base.paths import Paths
from lasa.evidence import latent_property
from lasa.experiments.sweep import check_names
from lasa.method.decoder import ActionDecoder, load_checkpoint
from lasa.people import participants, planning
from lasa.people.cohort import Cohort, ParticipantConfig, draw_cohort
from lasa.people.design import StudyConfig, interface_of
from lasa.pipeline.scaleout import run_jobs
from lasa.world.eating import STUDY_BELIEF_CAP, EatingTask
from lasa.world.measures import measures
from lasa.world.record import Episodes

PAPER_N = 10  # the paper's participants
DECODER_SELECTIONS = ("property", "all")  # Config.decoders: which decoder variants the study runs
Simulate = Callable[..., Episodes]  # lasa.people.participants.simulate's signature and return type

# participant model name -> its simulate, the headline first. A model of your own: add it here
# before building the Config that names it.
PARTICIPANT_MODELS: dict[str, Simulate] = {"planning": planning.simulate, "one_step": participants.simulate}


@dataclasses.dataclass(frozen=True)
class Config:
    """The simulated study (notebook 11); the participants' parameters are ``session.participant``."""

    participants: AtLeastTwo = 40  # the larger cohort; its first 10 are the paper-sized study [-]
    # how a session runs, the participants' parameters and the SA members, the headline first: hindsight
    # optimisation with goals as sets (the paper's study), its one-target member, grasp_set [-]
    session: StudyConfig = StudyConfig(assistance=("hindsight", "hindsight_point", "grasp_set"))
    seed: Seed = 0  # seed of the cohort and of the participants' choices [-]
    video_participant: NonNegativeInt = 0  # whose Dessert the video shows [-]
    participant_models: tuple[str, ...] = ("planning", "one_step")  # PARTICIPANT_MODELS, headline first [-]
    # decoder variants a model runs, the headline and the next in notebook 10's ranking (a model not
    # named runs every variant): a planning study costs ~5x a one-step one per variant
    variants_per_model: dict[str, PositiveInt] = dataclasses.field(default_factory=lambda: {"planning": 4})
    # which of notebook 10's decoder variants run (variants_to_run): "property" or "all" (LARGE=1) [-]
    decoders: str = "property"
    scheduler: str = ""  # a Dask scheduler address for the variants' runs ("" local; $LASA_SCHEDULER) [-]
    # local worker processes of the variants' runs and of the power (the same results with any number);
    # one by default: a participant model registered in this process only is unknown to a worker [-]
    jobs: PositiveInt = 1
    # who a replication needs (lasa.experiments.study.power): cohort sizes drawn [participants], and
    # cohorts drawn per size (100 draws give a power of 80% to within 4 points) [-]
    power_sizes: tuple[AtLeastTwo, ...] = (6, 10, 16, 24, 40, 60)
    power_draws: PositiveInt = 100
    # The study's belief: Javdani et al.'s cap, as notebook 10's decoders were trained; None
    # ("none"): Algorithm 1's uncapped belief [-]
    belief_cap: BeliefCap = STUDY_BELIEF_CAP
    # The cap sweep (lasa.experiments.study.caps): the headline's recipe at these caps; without a
    # cap the whole cohort runs (@uncapped), every other cap its first sweep_participants [-]
    cap_sweep: tuple[BeliefCap, ...] = (0.9, 0.95, 0.999, None)
    sweep_participants: AtLeastTwo = 10  # at most the cohort: sweep_n [-]

    def __post_init__(self) -> None:
        validate_caps(self)
        object.__setattr__(self, "participant_models", tuple(self.participant_models))
        check_names("participant model", self.participant_models, tuple(PARTICIPANT_MODELS))
        check_choice("decoders", self.decoders, DECODER_SELECTIONS)
        for name in self.variants_per_model:
            check_choice("variants_per_model's participant model", name, tuple(PARTICIPANT_MODELS))
        check_range("video_participant", self.video_participant, 0, self.participants, high_open=True)
        check_list("power_sizes", self.power_sizes, ascending=True)
        # warn of a cohort the Williams square does not balance, and of power sizes beyond it
        rows = len(williams_square(len(CONDITIONS)))
        beyond = [n for n in self.power_sizes if n > self.participants]
        for warn, text in (
            (
                self.participants % rows,
                f"participants = {self.participants} is not a multiple of {rows}: the balanced Latin "
                f"square's {rows} orders are filled unevenly, so order and carry-over are not balanced",
            ),
            (
                beyond,
                f"power_sizes {beyond} exceed participants ({self.participants}): those cohorts are "
                f"drawn with replacement from the {self.participants} simulated participants, so their "
                f"power rests on the spread of {self.participants} people",
            ),
        ):
            if warn:  # stacklevel 1, its own line: a config built twice (a replace) warns once
                warnings.warn(text, UserWarning, stacklevel=1)

    @property
    def sweep_n(self) -> int:
        """The participants each other cap of the sweep runs: ``sweep_participants``, at most the cohort."""
        return min(self.sweep_participants, self.participants)

    @property
    def other_caps(self) -> tuple[float | None, ...]:
        """The caps of ``cap_sweep`` other than the study's own (``belief_cap``), which run apart."""
        return tuple(c for c in self.cap_sweep if c != self.belief_cap)


def load_decoders(
    paths: Paths, robot: str, names: Sequence[str], cap: float | None
) -> dict[str, ActionDecoder]:
    """Notebook 10's decoder variants ``names``; a CheckpointError if one was trained with another cap."""
    out: dict[str, ActionDecoder] = {}
    for name in names:
        path = paths.artifact("eating_segmentation_decoder", robot, segmentation=name)
        model, meta = load_checkpoint(
            path, robot=robot, make_hint=Paths.make_hint("eating_segmentation_decoder", robot)
        )
        trained = (meta.get("control") or {}).get("belief_cap", "not recorded")
        if trained != cap:
            raise CheckpointError(
                f"{path} was trained with belief_cap {trained}, the study runs it at {cap}: run notebook 10 "
                "with the same belief_cap, or set this notebook's belief_cap to the decoder's"
            )
        out[name] = model
    return out


def eating_property(figures: Path, source: str | None = None) -> pd.DataFrame:
    """Notebook 10's property (:func:`lasa.evidence.latent_property.summary`) of the eating decoders,
    or with ``source`` of that source's rows (the cap sweep's)."""
    frame = pd.read_csv(require_file(figures / "latent_property.csv", "make figures (notebook 10)"))
    return latent_property.summary(
        frame.query("task == 'eating'") if source is None else frame[frame.source == source]
    )


def participant_table(participant: ParticipantConfig) -> pd.DataFrame:
    """The participants' parameters, one row each (``parameter``, ``value``), in their field order."""
    fields = dataclasses.fields(participant)
    return pd.DataFrame([{"parameter": f.name, "value": getattr(participant, f.name)} for f in fields])


def variants_to_run(prop: pd.DataFrame, selection: str = "property") -> list[str]:
    """The decoder variants the participants run in notebook 10's ranking: ``"all"``, or ``"property"``:
    those that meet the property rule (none: the best), and ``<headline>_entropy`` if trained."""
    check_choice("decoders", selection, DECODER_SELECTIONS)
    ranked = list(latent_property.ranking(prop).index)
    if selection == "all":
        return ranked
    meets = latent_property.holds(prop)
    keep = [d for d in ranked if meets.get(d, False)] or ranked[:1]
    contrast = f"{keep[0]}_entropy"
    return keep + ([contrast] if contrast in ranked and contrast not in keep else [])


_Shared = tuple[EatingTask, dict[str, ActionDecoder], Cohort, ControlConfig, Config]


def _run_variant(shared: _Shared, job: tuple[str, int, str]) -> Episodes:
    """One participant model's study with one decoder variant (the headline, index 0, runs R too)."""
    (task, decoders, cohort, control, config), (model, i, name) = shared, job
    headline_only = dataclasses.replace(config.session, assistance=config.session.assistance[:1])
    return PARTICIPANT_MODELS[model](
        task,
        decoders[name],
        cohort,
        control,
        config.session if i == 0 else headline_only,
        seed=config.seed,
        progress=False,
        interfaces=("R", "LA") if i == 0 else ("LA",),
    )


def run(
    task: EatingTask,
    decoders: Mapping[str, ActionDecoder],
    control: ControlConfig,
    config: Config,
    progress: bool = True,
) -> tuple[dict[str, dict[str, Episodes]], dict[str, pd.DataFrame]]:
    """Simulate the cohort under each participant model: ``episodes[model][decoder]`` and the tidy tables
    ``goal_error``, ``time``, ``alignment`` (``decoder`` ``none`` on R's rows). The headline decoder (the
    first) runs every condition and member, the others LA and LA+SA under the headline member."""
    if not decoders:
        raise ConfigError("run needs at least one decoder (the headline first)")
    cohort = draw_cohort(config.participants, config.session.participant, config.seed)
    names = list(decoders)
    jobs = [
        (model, i, name)
        for model in config.participant_models
        for i, name in enumerate(names[: config.variants_per_model.get(model, len(names))])
    ]
    ran = run_jobs(
        _run_variant,
        jobs,
        scheduler=config.scheduler or None,
        n_jobs=config.jobs,
        progress=progress,
        desc="study runs",
        shared=(task, dict(decoders), cohort, control, config),
    )
    episodes: dict[str, dict[str, Episodes]] = {}
    parts: dict[str, list[pd.DataFrame]] = {"goal_error": [], "time": [], "alignment": []}
    for (model, _, name), record in zip(jobs, ran, strict=True):
        episodes.setdefault(model, {})[name] = record
        for key, frame in measures(task, record).items():
            la = frame.condition.map({c: interface_of(c) == "LA" for c in CONDITIONS}).astype(bool)
            parts[key].append(frame.assign(decoder=np.where(la, name, NO_ASSISTANCE), model=model))
    return episodes, {key: pd.concat(frames, ignore_index=True) for key, frames in parts.items()}
