r"""The eating study (notebook 11): the simulated cohort's run and its :class:`Config`.

A cohort of simulated participants (:mod:`lasa.people.cohort`) does both eating tasks under R,
R+SA, LA and LA+SA. The first ten are the paper's study size; the whole cohort is the
larger one. Three tidy tables come out, one row per participant x condition x task (x
phase), each with its figure (:mod:`lasa.figures.study_plots`):

- ``study_goal_error``: Goal Error (Fig. error);
- ``study_time``: Total and Idle Time (Fig. time), with mode switches and completion;
- ``study_alignment``: Preference Alignment per phase (Fig. dessert, left panel).

Each participant model of ``Config.participant_models`` (:data:`PARTICIPANT_MODELS`: ``planning``,
who plans over held inputs, the headline once :mod:`lasa.people.planning` exists, and ``one_step``,
:func:`lasa.people.participants.simulate`) runs the whole study; the tables' ``model`` column says
which. The assisted conditions run under each member of ``Config.members`` (hindsight
optimisation, the paper's study, first: the headline), the unassisted ones once
(``assistance`` is ``none`` for them). The LA conditions run under every decoder reading of
notebook 10 (:func:`run`; the headline, chosen there by the property alone, first), and the
tables' ``decoder`` column says which; :func:`for_member` selects one reading's rows.

The claims H1-H3 and their rules are :mod:`lasa.figures.study_claims` (on the tests of
:mod:`lasa.figures.study_tests`); beside them, :mod:`lasa.figures.study_analysis` gives completion,
the headline participant model, where the unfinished LA episodes stopped and Retargeting's
mode-switch share.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping

import numpy as np
import pandas as pd

from lasa.base.conditions import CONDITIONS
from lasa.base.config import (
    NO_ASSISTANCE,
    AtLeastTwo,
    ControlConfig,
    NonNegativeInt,
    PositiveInt,
    Seed,
    check_choice,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.method.decoder import ActionDecoder
from lasa.people import participants, planning
from lasa.people.cohort import draw_cohort
from lasa.people.design import Episodes, StudyConfig, interface_of
from lasa.people.measures import measures
from lasa.world.eating import EatingTask

__all__ = [
    "Config",
    "PAPER_N",
    "PARTICIPANT_MODELS",
    "Simulate",
    "run",
    "for_member",
]

PAPER_N = 10  # the paper's participants
Simulate = Callable[..., Episodes]  # lasa.people.participants.simulate's signature and return type

# participant model name -> its simulate (the signature of lasa.people.participants.simulate);
# the headline first. A model of your own: add it here before building the Config that names it.
PARTICIPANT_MODELS: dict[str, Simulate] = {"planning": planning.simulate, "one_step": participants.simulate}


@dataclasses.dataclass(frozen=True)
class Config:
    """The simulated study (notebook 11); the participants' parameters are ``participant``."""

    participants: AtLeastTwo = 40  # the larger cohort; its first 10 are the paper-sized study [-]
    # how a session runs (horizon, waypoint tolerances, stick grid) and the participants' parameters
    # (session.participant); the SA readings, the first the headline: hindsight, as in the paper's
    # study, and grasp_set [-]
    session: StudyConfig = StudyConfig(members=("hindsight", "grasp_set"))
    seed: Seed = 0  # seed of the cohort and of the participants' choices [-]
    video_participant: NonNegativeInt = 0  # whose Dessert the video shows [-]
    # participant models (PARTICIPANT_MODELS); the first is the headline [-]
    participant_models: tuple[str, ...] = ("planning", "one_step")
    # decoder readings a model runs, the headline and the next ones in notebook 10's ranking (a
    # model not named runs every reading): a planning study costs ~5x a one-step one per reading
    readings_per_model: dict[str, PositiveInt] = dataclasses.field(default_factory=lambda: {"planning": 4})

    def __post_init__(self) -> None:
        validate(self)
        object.__setattr__(self, "participant_models", tuple(self.participant_models))
        models = self.participant_models
        if not models or len(set(models)) != len(models):
            raise ConfigError(f"participant_models must be non-empty and without repeats, got {models}")
        for name in models:
            check_choice("participant model", name, tuple(PARTICIPANT_MODELS))
        for name in self.readings_per_model:
            check_choice("readings_per_model's participant model", name, tuple(PARTICIPANT_MODELS))
        if not 0 <= self.video_participant < self.participants:
            raise ConfigError(
                f"video_participant must be in [0, {self.participants}), got {self.video_participant}"
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
    named in ``config.readings_per_model`` runs only the first that many of ``decoders``.

    Returns:
        The episodes per participant model and decoder reading (``episodes[model][decoder]``),
        and the three tidy tables. Their ``decoder`` column names the reading of each LA row
        (``none`` for Retargeting), their ``model`` column the participant model.
    """
    if not decoders:
        raise ConfigError("run needs at least one decoder (the headline first)")
    cohort = draw_cohort(config.participants, config.session.participant, config.seed)
    episodes: dict[str, dict[str, Episodes]] = {}
    parts: dict[str, list[pd.DataFrame]] = {"goal_error": [], "time": [], "alignment": []}
    for model in config.participant_models:
        simulate = PARTICIPANT_MODELS[model]
        episodes[model] = {}
        limit = config.readings_per_model.get(model, len(decoders))
        for i, (name, decoder) in enumerate(list(decoders.items())[:limit]):
            headline_only = dataclasses.replace(config.session, members=config.session.members[:1])
            settings = config.session if i == 0 else headline_only
            episodes[model][name] = simulate(
                task,
                decoder,
                cohort,
                control,
                settings,
                seed=config.seed,
                progress=progress,
                interfaces=("R", "LA") if i == 0 else ("LA",),
            )
            for key, frame in measures(task, episodes[model][name]).items():
                la = frame.condition.map({c: interface_of(c) == "LA" for c in CONDITIONS}).astype(bool)
                parts[key].append(frame.assign(decoder=np.where(la, name, NO_ASSISTANCE), model=model))
    return episodes, {key: pd.concat(frames, ignore_index=True) for key, frames in parts.items()}


def for_member(
    frame: pd.DataFrame,
    member: str,
    n: int | None = None,
    decoder: str | None = None,
    model: str | None = None,
) -> pd.DataFrame:
    """The rows of one SA reading (the unassisted conditions included), for the first ``n`` participants.

    With ``decoder``, the LA rows are that decoder reading's (a frame without a ``decoder``
    column holds one reading); with ``model``, the rows are that participant model's (a frame
    without a ``model`` column holds one model).
    """
    rows = frame[(frame.assistance == member) | (frame.assistance == NO_ASSISTANCE)]
    if decoder is not None and "decoder" in rows.columns:
        rows = rows[(rows.decoder == decoder) | (rows.decoder == NO_ASSISTANCE)]
    if model is not None and "model" in rows.columns:
        rows = rows[rows.model == model]
    if n is not None:
        rows = rows[rows.participant < n]
    return rows.reset_index(drop=True)
