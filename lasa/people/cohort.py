"""The eating study's simulated participants: their free parameters and their cohort, each doing the
four conditions in a counterbalanced order (Williams 1949); how they choose: :mod:`lasa.people.policy`."""

from __future__ import annotations

import dataclasses

import numpy as np

from lasa.base.conditions import CONDITIONS, williams_square
from lasa.base.config import NonNegative, Positive, UnitInterval, check_range, validate
from lasa.base.errors import ConfigError


@dataclasses.dataclass(frozen=True)
class ParticipantConfig:
    """The free parameters of a simulated participant, each set from what it means before any study
    was simulated (notebook 11)."""

    # beta = 20: an input 0.1 of a step worse than the best is chosen e^2 ~ 7x less often; spread
    # lognormal (a factor ~1.6 either way), as the paper's users differed in skill.
    beta_median: Positive = 20.0  # median beta_inf across participants [-]
    beta_spread: NonNegative = 0.5  # sigma of log beta_inf [-]
    novice_fraction: UnitInterval = 0.25  # rho: beta / beta_inf with no experience at all [-]
    learning_median: Positive = 60.0  # median time constant tau: joystick skills settle in minutes [s]
    learning_spread: NonNegative = 0.5  # sigma of log tau [-]
    practice_min: NonNegative = 120.0  # practice before a condition, uniform in [min, max] [s]
    practice_max: NonNegative = 300.0  # ... "up to 5 minutes" (the paper) [s]
    transfer: UnitInterval = 0.5  # share of earlier conditions' practice that carries over [-]
    idle_threshold: NonNegative = 0.1  # least progress worth an input (~1.5 mm a step), in best steps [-]
    patience: Positive = 1.0  # idle time (a choice reaction time) after which they try an input anyway [s]
    # a turn of the fork by 1 rad about its tip moves its grip by the fork's length (0.125 m)
    rotation_weight: NonNegative = 0.125  # l: metres of cost per radian of direction error [m/rad]

    def __post_init__(self) -> None:
        validate(self)
        check_range("practice_max", self.practice_max, self.practice_min)


@dataclasses.dataclass(frozen=True)
class Cohort:
    """Simulated participants drawn with ``config``: each one's beta_inf and learning time tau [s], (N,),
    practice before each condition (:data:`CONDITIONS` order) [s] and conditions in order, (N, 4)."""

    beta: np.ndarray
    learning_time: np.ndarray
    practice: np.ndarray
    order: np.ndarray
    config: ParticipantConfig

    def __len__(self) -> int:
        return len(self.beta)

    def experience(self) -> np.ndarray:
        """E_0: practice with each condition plus ``transfer`` x the practice before it, (N, 4) [s]."""
        ordered = np.take_along_axis(self.practice, self.order, axis=1)  # in session order
        carried = np.cumsum(np.pad(ordered[:, :-1], ((0, 0), (1, 0))), axis=1)  # the practice before each
        out = np.empty_like(self.practice)
        np.put_along_axis(out, self.order, ordered + self.config.transfer * carried, axis=1)
        return out


def draw_cohort(n: int, config: ParticipantConfig = ParticipantConfig(), seed: int = 0) -> Cohort:
    """Draw ``n`` participants, participant i the same whatever n (its own random stream), running
    row ``i mod 4`` of the Williams square: any 4 consecutive ones balance order and carry-over."""
    if int(n) != n or n < 1:
        raise ConfigError(f"the number of participants must be a positive integer, got {n!r}")
    beta, tau, practice = np.empty(n), np.empty(n), np.empty((n, len(CONDITIONS)))
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        beta[i] = config.beta_median * np.exp(config.beta_spread * rng.standard_normal())
        tau[i] = config.learning_median * np.exp(config.learning_spread * rng.standard_normal())
        practice[i] = rng.uniform(config.practice_min, config.practice_max, len(CONDITIONS))
    order = williams_square(len(CONDITIONS))[np.arange(n) % len(CONDITIONS)]
    return Cohort(beta=beta, learning_time=tau, practice=practice, order=order, config=config)
