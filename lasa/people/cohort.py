r"""Who takes part in the eating study: the simulated participants' parameters and their cohort.

Ten people did the paper's study; here a cohort of simulated participants stands in for
them (:func:`draw_cohort`). Each one has their own rationality and learning time, and does
the four conditions of the 2x2 design in a counterbalanced order (a balanced Latin square,
Williams 1949: :func:`lasa.base.conditions.williams_square`). Their experience before a condition,

.. math::  E_0 = \text{practice with this condition} + \text{transfer} \times
    \text{practice with the conditions done before it},

makes the order of conditions matter (:meth:`Cohort.experience`), and gives the
counterbalancing something to balance. How a participant uses these parameters to choose an
input is :mod:`lasa.people.policy`.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from lasa.base.conditions import CONDITIONS, williams_square
from lasa.base.config import NonNegative, Positive, UnitInterval, interval, validate
from lasa.base.errors import ConfigError

__all__ = ["ParticipantConfig", "Cohort", "draw_cohort"]


@dataclasses.dataclass(frozen=True)
class ParticipantConfig:
    """The free parameters of a simulated participant, each with its reason.

    All were set before any study was simulated, from what they mean; none was changed
    after seeing which value makes a hypothesis hold (notebook 11 says so).
    """

    # Rationality in units of the best step's progress: at beta = 20 an input 0.1 of a
    # step worse than the best is chosen e^2 ~ 7x less often: people pick near-best stick
    # directions but not the exact best one. Spread across people: lognormal, sigma 0.5
    # (a factor ~1.6 either way), as the paper's users differed in skill.
    beta_median: Positive = 20.0  # median beta_inf across participants [-]
    beta_spread: NonNegative = 0.5  # sigma of log beta_inf [-]
    novice_fraction: UnitInterval = 0.25  # rho: beta / beta_inf with no experience at all [-]
    # Joystick skills settle within minutes of practice; the paper gave up to 5 minutes.
    learning_median: Positive = 60.0  # median time constant tau of the improvement [s]
    learning_spread: NonNegative = 0.5  # sigma of log tau [-]
    practice_min: NonNegative = 120.0  # practice before a condition, uniform in [min, max] [s]
    practice_max: NonNegative = 300.0  # ... "up to 5 minutes" (the paper) [s]
    transfer: UnitInterval = 0.5  # share of earlier conditions' practice that carries over [-]
    # A motion of under ~1.5 mm per step (10% of the best step) is not worth a push: the
    # participant rests the stick.
    idle_threshold: NonNegative = 0.1  # least progress, in best-step units, worth an input [-]
    # Resting is not forever: after about a second with nothing worth a push (a choice
    # reaction time with an unfamiliar mapping), a person tries an input anyway.
    patience: Positive = 1.0  # idle time after which the participant tries their Boltzmann choice [s]
    # A turn of the fork by 1 rad about its tip moves its grip by the fork's length (0.125 m):
    # orientation errors weigh like the displacement they cause at the hand.
    rotation_weight: NonNegative = 0.125  # l: metres of cost per radian of direction error [m/rad]

    def __post_init__(self) -> None:
        validate(self)
        if self.practice_max < self.practice_min:
            raise ConfigError(
                f"practice_max must be in {interval(self.practice_min, math.inf)} (at least practice_min), "
                f"got {self.practice_max!r}"
            )


@dataclasses.dataclass(frozen=True)
class Cohort:
    """Simulated participants: each one's rationality, learning and order of conditions.

    Attributes:
        beta: beta_inf per participant, shape (N,).
        learning_time: tau per participant, shape (N,) [s].
        practice: Practice before each condition (in :data:`CONDITIONS` order), (N, 4) [s].
        order: The conditions each participant does, in order (indices), (N, 4).
        config: The parameters they were drawn with.
    """

    beta: np.ndarray
    learning_time: np.ndarray
    practice: np.ndarray
    order: np.ndarray
    config: ParticipantConfig

    def __len__(self) -> int:
        return len(self.beta)

    def experience(self) -> np.ndarray:
        """E_0: practice with each condition plus the carried-over practice of earlier ones, (N, 4) [s]."""
        out = self.practice.copy()
        for i, order in enumerate(self.order):
            carried = 0.0
            for c in order:
                out[i, c] += self.config.transfer * carried
                carried += self.practice[i, c]
        return out


def draw_cohort(n: int, config: ParticipantConfig = ParticipantConfig(), seed: int = 0) -> Cohort:
    """Draw ``n`` participants; participant i is the same whatever n is (its own random stream).

    Participant i runs row ``i mod 4`` of :func:`lasa.base.conditions.williams_square`, so any 4
    consecutive participants balance order and carry-over.
    """
    if int(n) != n or n < 1:
        raise ConfigError(f"the number of participants must be a positive integer, got {n!r}")
    square = williams_square(len(CONDITIONS))
    beta, tau, practice = np.empty(n), np.empty(n), np.empty((n, len(CONDITIONS)))
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        beta[i] = config.beta_median * np.exp(config.beta_spread * rng.standard_normal())
        tau[i] = config.learning_median * np.exp(config.learning_spread * rng.standard_normal())
        practice[i] = rng.uniform(config.practice_min, config.practice_max, len(CONDITIONS))
    order = square[np.arange(n) % len(CONDITIONS)]
    return Cohort(beta=beta, learning_time=tau, practice=practice, order=order, config=config)
