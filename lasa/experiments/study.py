r"""The eating study (notebook 11): the simulated cohort's run and its :class:`Config`.

A cohort of simulated participants (:mod:`lasa.people.cohort`) does both eating tasks under R,
R+SA, LA and LA+SA. The first ten are the paper's study size; the whole cohort is the
larger one. Three tidy tables come out, one row per participant x condition x task (x
phase), each with its figure (:mod:`lasa.experiments.study_plots`):

- ``study_goal_error``: Goal Error (Fig. error);
- ``study_time``: Total and Idle Time (Fig. time), with mode switches and completion;
- ``study_alignment``: Preference Alignment per phase (Fig. dessert, left panel).

Each participant model of ``Config.participant_models`` (:data:`PARTICIPANT_MODELS`: ``planning``,
who plans over held inputs, the headline once :mod:`lasa.people.planning` exists, and ``one_step``,
:func:`lasa.people.participants.simulate`) runs the whole study; the tables' ``model`` column says
which. The assisted conditions run under each member of ``Config.session.assistance`` (hindsight
optimisation, the paper's study, first: the headline), the unassisted ones once
(``assistance`` is ``none`` for them). The LA conditions run under every decoder reading of
notebook 10 (:func:`run`; the headline, chosen there by the property alone, first), and the
tables' ``decoder`` column says which; :func:`for_member` selects one reading's rows.

The claims H1-H3 and their rules are :mod:`lasa.experiments.study_claims` (on the tests of
:mod:`lasa.experiments.study_tests`); beside them, :mod:`lasa.experiments.study_analysis` gives completion,
the headline participant model, where the unfinished LA episodes stopped and Retargeting's
mode-switch share.
"""

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
    cap_setting,
    check_choice,
    check_list,
    validate,
)
from lasa.base.errors import CheckpointError, ConfigError
from lasa.base.io import require_file
from lasa.base.paths import Paths
from lasa.evidence import latent_property
from lasa.method.decoder import ActionDecoder, load_checkpoint
from lasa.people import participants, planning
from lasa.people.cohort import Cohort, ParticipantConfig, draw_cohort
from lasa.people.design import StudyConfig, interface_of
from lasa.pipeline.scaleout import run_jobs
from lasa.world.eating import STUDY_BELIEF_CAP, EatingTask
from lasa.world.measures import measures
from lasa.world.record import Episodes

__all__ = [
    "Config",
    "PAPER_N",
    "PARTICIPANT_MODELS",
    "DECODER_SELECTIONS",
    "Simulate",
    "load_decoders",
    "eating_property",
    "participant_table",
    "readings_to_run",
    "run",
    "for_member",
]

PAPER_N = 10  # the paper's participants
DECODER_SELECTIONS = ("property", "all")  # Config.decoders: which decoder readings the study runs
Simulate = Callable[..., Episodes]  # lasa.people.participants.simulate's signature and return type

# participant model name -> its simulate (the signature of lasa.people.participants.simulate);
# the headline first. A model of your own: add it here before building the Config that names it.
PARTICIPANT_MODELS: dict[str, Simulate] = {"planning": planning.simulate, "one_step": participants.simulate}


@dataclasses.dataclass(frozen=True)
class Config:
    """The simulated study (notebook 11); the participants' parameters are ``participant``."""

    participants: AtLeastTwo = 40  # the larger cohort; its first 10 are the paper-sized study [-]
    # how a session runs (horizon, waypoint tolerances, stick grid) and the participants' parameters
    # (session.participant), and the SA readings (session.assistance):
    # the SA readings, the first the headline: hindsight optimisation with goals as sets, as in
    # the paper's study; its one-target reading; grasp_set [-]
    session: StudyConfig = StudyConfig(assistance=("hindsight", "hindsight_point", "grasp_set"))
    seed: Seed = 0  # seed of the cohort and of the participants' choices [-]
    video_participant: NonNegativeInt = 0  # whose Dessert the video shows [-]
    # participant models (PARTICIPANT_MODELS); the first is the headline [-]
    participant_models: tuple[str, ...] = ("planning", "one_step")
    # decoder readings a model runs, the headline and the next ones in notebook 10's ranking (a
    # model not named runs every reading): a planning study costs ~5x a one-step one per reading
    readings_per_model: dict[str, PositiveInt] = dataclasses.field(default_factory=lambda: {"planning": 4})
    # which of notebook 10's decoder readings the participants run (:func:`readings_to_run`):
    # "property", those that meet the property rule and the headline's entropy version (the paper's
    # remedy, as a contrast); "all", every reading (LARGE=1) [-]
    decoders: str = "property"
    scheduler: str = ""  # a Dask scheduler address for the readings' runs ("" local; $LASA_SCHEDULER) [-]
    # local worker processes of the readings' runs and of the power's drawn cohorts: the same
    # episodes and table with any number (each run is seeded and single-threaded, the draws are
    # made up front); configs/paper.yaml asks for two (both cores: this notebook runs last).
    # One by default: a participant model registered in this process only
    # (tests, a notebook cell) is unknown to a worker [-]
    jobs: PositiveInt = 1
    # who a replication needs (lasa.experiments.study_power): cohort sizes drawn from the simulated
    # participants [participants], and cohorts drawn per size (each one analysis, ~0.3 s; 100 draws
    # give a power of 80% to within 4 points) [-]
    power_sizes: tuple[AtLeastTwo, ...] = (6, 10, 16, 24, 40, 60)
    power_draws: PositiveInt = 100
    # The study's belief: Javdani et al.'s cap (lasa.world.eating.STUDY_BELIEF_CAP); notebook 10's
    # decoders must have been trained with it. None ("none"): Algorithm 1's uncapped belief [-]
    belief_cap: BeliefCap = STUDY_BELIEF_CAP
    # The cap sweep (lasa.experiments.study_caps): notebook 10's decoders of the headline's recipe at these
    # caps (its cap_sweep, or a part of it), each run with the belief at its cap; without a cap the
    # whole cohort runs (the reading @uncapped), every other cap its first sweep_participants [-]
    cap_sweep: tuple[BeliefCap, ...] = (0.9, 0.95, 0.999, None)
    # the paper's 10 (at most the cohort: sweep_n); configs/large.yaml runs the cohort [-]
    sweep_participants: AtLeastTwo = 10

    def __post_init__(self) -> None:
        object.__setattr__(self, "belief_cap", cap_setting(self.belief_cap))
        object.__setattr__(self, "cap_sweep", tuple(cap_setting(c) for c in self.cap_sweep))
        validate(self)
        if len(set(self.cap_sweep)) != len(self.cap_sweep):
            raise ConfigError(f"cap_sweep must not repeat a cap, got {self.cap_sweep}")
        object.__setattr__(self, "participant_models", tuple(self.participant_models))
        models = self.participant_models
        if not models or len(set(models)) != len(models):
            raise ConfigError(f"participant_models must be non-empty and without repeats, got {models}")
        for name in models:
            check_choice("participant model", name, tuple(PARTICIPANT_MODELS))
        check_choice("decoders", self.decoders, DECODER_SELECTIONS)
        for name in self.readings_per_model:
            check_choice("readings_per_model's participant model", name, tuple(PARTICIPANT_MODELS))
        if not 0 <= self.video_participant < self.participants:
            raise ConfigError(
                f"video_participant must be in [0, {self.participants}), got {self.video_participant}"
            )
        check_list("power_sizes", self.power_sizes, ascending=True)
        self._warn_about_the_cohort()

    def _warn_about_the_cohort(self) -> None:
        """Warn (one line each) of a cohort the Latin square does not balance, and of power sizes
        beyond it.

        Participant i runs row i mod 4 of the Williams square (:func:`lasa.people.cohort.draw_cohort`):
        only a multiple of 4 balances the conditions' order and carry-over. A power size above
        ``participants`` is not refused: :mod:`lasa.experiments.study_power` draws its cohorts with
        replacement (each drawn participant a new person), which is defined at any size, and the
        paper scale asks for it (60 drawn from 40) to find where the power reaches 80%. But such a
        cohort repeats simulated participants, and its power rests on the spread of ``participants``
        simulated people, not of as many as it draws: the warning says so.
        """
        rows = len(williams_square(len(CONDITIONS)))
        if self.participants % rows:
            warnings.warn(
                f"participants = {self.participants} is not a multiple of {rows}: the balanced Latin "
                f"square's {rows} orders are filled unevenly, so order and carry-over are not balanced",
                UserWarning,
                stacklevel=1,  # its own line: a config built twice (a replace) warns once
            )
        beyond = [n for n in self.power_sizes if n > self.participants]
        if beyond:
            warnings.warn(
                f"power_sizes {beyond} exceed participants ({self.participants}): those cohorts are "
                f"drawn with replacement from the {self.participants} simulated participants, so their "
                f"power rests on the spread of {self.participants} people",
                UserWarning,
                stacklevel=1,  # its own line: a config built twice (a replace) warns once
            )

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
    """Notebook 10's decoder readings ``names``, each checked to have been trained with the belief
    capped at ``cap``: a decoder reads b, and one trained with another belief is lost with this one.

    Raises:
        ArtifactError: A decoder is missing (notebook 10 trains it).
        CheckpointError: A decoder was trained with another ``belief_cap``.
    """
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


def eating_property(figures: Path) -> pd.DataFrame:
    """Notebook 10's property of the eating decoders: :func:`lasa.evidence.latent_property.summary`
    of the eating rows of ``latent_property.csv`` in the ``figures`` folder.

    Raises:
        ArtifactError: The file is missing (notebook 10 makes it).
    """
    frame = pd.read_csv(require_file(figures / "latent_property.csv", "make figures (notebook 10)"))
    return latent_property.summary(frame.query("task == 'eating'"))


def participant_table(participant: ParticipantConfig) -> pd.DataFrame:
    """The participants' parameters, one row each (``parameter``, ``value``), in their field order."""
    fields = dataclasses.fields(participant)
    return pd.DataFrame([{"parameter": f.name, "value": getattr(participant, f.name)} for f in fields])


def readings_to_run(prop: pd.DataFrame, selection: str = "property") -> list[str]:
    """The decoder readings the participants run, the headline first (notebook 10's ranking).

    ``"property"`` (paper scale): only decoders that meet the property rule
    (:func:`lasa.evidence.latent_property.holds`), and the headline's entropy version
    ``<headline>_entropy`` (Eq. T6, the paper's remedy for a trapped user) as a contrast, if
    notebook 10 trained it. A reading that fails the rule is reported by its property row and
    not run through the participants. If no decoder meets the rule, the best-ranked one runs as
    the headline (its rows read "not testable", :func:`lasa.experiments.study_claims.untestable_reason`).
    ``"all"``: every reading, in the ranking's order (``LARGE=1``).

    Args:
        prop: :func:`lasa.evidence.latent_property.summary` of the eating decoders.
        selection: One of :data:`DECODER_SELECTIONS`.
    """
    check_choice("decoders", selection, DECODER_SELECTIONS)
    ranked = list(latent_property.ranking(prop).index)
    if selection == "all":
        return ranked
    meets = latent_property.holds(prop)
    keep = [d for d in ranked if meets.get(d, False)] or ranked[:1]
    contrast = f"{keep[0]}_entropy"
    return keep + ([contrast] if contrast in ranked and contrast not in keep else [])


@dataclasses.dataclass(frozen=True)
class _Shared:
    """What every (participant model, decoder reading) run reads: sent to each worker once."""

    task: EatingTask
    decoders: dict[str, ActionDecoder]
    cohort: Cohort
    control: ControlConfig
    config: Config


def _run_reading(shared: _Shared, job: tuple[str, int, str]) -> Episodes:
    """One participant model's study with one decoder reading (the headline, index 0, runs R too)."""
    model, i, name = job
    config = shared.config
    headline_only = dataclasses.replace(config.session, assistance=config.session.assistance[:1])
    return PARTICIPANT_MODELS[model](
        shared.task,
        shared.decoders[name],
        shared.cohort,
        shared.control,
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
    """Simulate the cohort under each participant model and measure it.

    Each of ``config.participant_models`` (the headline first) runs the same cohort. The first
    of ``decoders`` is the headline: every condition under every member. Each other reading
    runs LA and LA+SA only, under the headline member (Retargeting does not use the decoder:
    its episodes are the headline run's, the same participants and random streams). A model
    named in ``config.readings_per_model`` runs only the first that many of ``decoders``. The
    runs are independent jobs (:func:`lasa.pipeline.scaleout.run_jobs`): in this process, or on
    the Dask cluster that ``config.scheduler`` or ``$LASA_SCHEDULER`` names, with the same result.

    Returns:
        The episodes per participant model and decoder reading (``episodes[model][decoder]``),
        and the three tidy tables. Their ``decoder`` column names the reading of each LA row
        (``none`` for Retargeting), their ``model`` column the participant model.
    """
    if not decoders:
        raise ConfigError("run needs at least one decoder (the headline first)")
    cohort = draw_cohort(config.participants, config.session.participant, config.seed)
    names = list(decoders)
    jobs = [
        (model, i, name)
        for model in config.participant_models
        for i, name in enumerate(names[: config.readings_per_model.get(model, len(names))])
    ]
    shared = _Shared(task, dict(decoders), cohort, control, config)
    ran = run_jobs(
        _run_reading,
        jobs,
        scheduler=config.scheduler or None,
        n_jobs=config.jobs,
        progress=progress,
        desc="study runs",
        shared=shared,
    )
    episodes: dict[str, dict[str, Episodes]] = {}
    parts: dict[str, list[pd.DataFrame]] = {"goal_error": [], "time": [], "alignment": []}
    for (model, _, name), record in zip(jobs, ran, strict=True):
        episodes.setdefault(model, {})[name] = record
        for key, frame in measures(task, record).items():
            la = frame.condition.map({c: interface_of(c) == "LA" for c in CONDITIONS}).astype(bool)
            parts[key].append(frame.assign(decoder=np.where(la, name, NO_ASSISTANCE), model=model))
    return episodes, {key: pd.concat(frames, ignore_index=True) for key, frames in parts.items()}


def for_member(
    frame: pd.DataFrame,
    assistance: str,
    n: int | None = None,
    decoder: str | None = None,
    model: str | None = None,
) -> pd.DataFrame:
    """The rows of one SA reading (the unassisted conditions included), for the first ``n`` participants.

    With ``decoder``, the LA rows are that decoder reading's (a frame without a ``decoder``
    column holds one reading); with ``model``, the rows are that participant model's (a frame
    without a ``model`` column holds one model).
    """
    rows = frame[(frame.assistance == assistance) | (frame.assistance == NO_ASSISTANCE)]
    if decoder is not None and "decoder" in rows.columns:
        rows = rows[(rows.decoder == decoder) | (rows.decoder == NO_ASSISTANCE)]
    if model is not None and "model" in rows.columns:
        rows = rows[rows.model == model]
    if n is not None:
        rows = rows[rows.participant < n]
    return rows.reset_index(drop=True)
