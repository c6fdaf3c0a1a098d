"""The eating study's design: its settings (:class:`StudyConfig`) and its episodes (:func:`layout`),
both tasks under the 2x2 conditions for every participant, each assisted one under every SA member."""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated

import annotated_types as at
import numpy as np

from lasa.base.conditions import CONDITIONS, alpha_of
from lasa.base.conditions import parse as parse_condition
from lasa.base.config import (
    BUILT_IN_ASSISTANCE,
    NO_ASSISTANCE,
    TRIAL_LIMIT_S,
    ControlConfig,
    Integer,
    Number,
    Positive,
    PositiveInt,
    check_choice,
    check_list,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.method.retarget import RetargetConfig
from lasa.people.cohort import Cohort, ParticipantConfig
from lasa.world.eating import TASK_NAMES
from lasa.world.fork import ANGLE_TOL, POSITION_TOL


def interface_of(condition: str) -> str:
    """``R`` or ``LA``: the control interface of one of the study's conditions."""
    return parse_condition(condition, CONDITIONS).interface


@dataclasses.dataclass(frozen=True)
class StudyConfig:
    """How a study session runs (the participants' parameters are in ``participant``)."""

    # steps allowed per task (TRIAL_LIMIT_S, 150 s, at dt = 0.1 s); unfinished tasks count the horizon [-]
    horizon: PositiveInt = round(TRIAL_LIMIT_S / ControlConfig.dt)
    # a waypoint is reached this close [m] with the fork's direction this close [rad] (WaypointTracker)
    position_tol: Positive = POSITION_TOL
    angle_tol: Annotated[Number, at.Gt(0.0), at.Le(math.pi)] = ANGLE_TOL
    # The SA members the assisted conditions run under (lasa.method.assistance); the first is the
    # headline. The paper's study used hindsight optimisation.
    assistance: tuple[str, ...] = ("hindsight",)
    n_z: Annotated[Integer, at.Ge(3)] = 5  # stick positions per axis the participant weighs (odd) [-]
    participant: ParticipantConfig = ParticipantConfig()
    retarget: RetargetConfig = RetargetConfig()

    def __post_init__(self) -> None:
        validate(self)
        for name in check_list("assistance", self.assistance):
            check_choice("assistance", name, BUILT_IN_ASSISTANCE)
        if self.n_z % 2 == 0:
            raise ConfigError(f"n_z must be odd (the rest position is the grid's middle), got {self.n_z!r}")


@dataclasses.dataclass(frozen=True)
class Layout:
    """The episodes of a study and each one's fixed settings, (E,) each (participants' order)."""

    part: np.ndarray  # participant index
    tsk: np.ndarray  # task index into TASK_NAMES
    cond: np.ndarray  # condition index into CONDITIONS
    assistance: np.ndarray  # SA member, NO_ASSISTANCE for R and LA
    assistance_run: np.ndarray  # the member advance() runs (alpha = 0 where there is none)
    is_la: np.ndarray  # latent actions (else Retargeting)
    alpha: np.ndarray  # blend weight
    order: np.ndarray  # position of the condition in the participant's session
    e0: np.ndarray  # experience before the condition [s]
    beta_inf: np.ndarray
    tau: np.ndarray  # learning time constant [s]


def layout(
    cohort: Cohort, control: ControlConfig, assistance: tuple[str, ...], interfaces: tuple[str, ...]
) -> Layout:
    """The study's episodes, participant-major, then pair (the unassisted conditions once, each
    assisted one under every member), then task; every participant model runs this order."""
    pairs: list[tuple[str, str]] = [(c, NO_ASSISTANCE) for c in ("R", "LA") if c in interfaces]
    pairs += [(c, m) for m in assistance for c in ("R+SA", "LA+SA") if interface_of(c) in interfaces]
    n_a, n_t = len(pairs), len(TASK_NAMES)
    part = np.repeat(np.arange(len(cohort)), n_a * n_t)
    pair = np.tile(np.repeat(np.arange(n_a), n_t), len(cohort))
    cond = np.array([CONDITIONS.index(pairs[a][0]) for a in pair])
    assistance_rows = np.array([pairs[a][1] for a in pair])
    return Layout(
        part=part,
        tsk=np.tile(np.arange(n_t), len(cohort) * n_a),
        cond=cond,
        assistance=assistance_rows,
        assistance_run=np.where(assistance_rows == NO_ASSISTANCE, assistance[0], assistance_rows),
        is_la=np.array([interface_of(c) == "LA" for c in CONDITIONS])[cond],
        alpha=np.array([alpha_of(c, control.alpha, CONDITIONS) for c in CONDITIONS])[cond],
        order=np.argsort(cohort.order, axis=1)[part, cond],
        e0=cohort.experience()[part, cond],
        beta_inf=cohort.beta[part],
        tau=cohort.learning_time[part],
    )
