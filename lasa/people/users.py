r"""Simulated users: Boltzmann-rational joystick choices (Eq. S1), by Gumbel-max on their own draws,
:math:`p(z) \propto \exp\{-\beta(t) \|s^* - (s + \Delta\,\phi(z, s, b))\|^2\}`, :math:`\beta(t) =
\beta_0 + m t`, their goal maybe changing at step N; :data:`PILOTS` adds laggy and noisy pilots."""

from __future__ import annotations

import dataclasses

import numpy as np

from lasa.base.config import check_choice, check_range
from lasa.base.errors import ConfigError

PILOTS = ("boltzmann", "laggy", "noisy")
_SCALARS = ("pilot", "pilot_prob")  # UserPopulation fields shared by every user


@dataclasses.dataclass(frozen=True)
class UserPopulation:
    """A batch of U simulated users, as arrays.

    Attributes:
        goal, theta, target: Each user's cup and preferred grasp in [0, 1], (U,), and final pose s*, (U, n).
        beta0, slope: Rationality at t = 0 [1/rad^2] and its growth m per step (beta0 + m t), (U,).
        user: Each user's index, which picks their draws from the noise, (U,) (the CSVs' ``seed``).
        first_target, change_step: The pose each user aims at before step N, and N, (U, n) and (U,)
            (``None``: users who never change their mind).
        pilot, pilot_prob: The kind of all users (:data:`PILOTS`) and p of a laggy or noisy pilot [-]."""

    goal: np.ndarray
    theta: np.ndarray
    target: np.ndarray
    beta0: np.ndarray
    slope: np.ndarray
    user: np.ndarray
    first_target: np.ndarray | None = None
    change_step: np.ndarray | None = None
    pilot: str = "boltzmann"
    pilot_prob: float = 0.0

    def __post_init__(self) -> None:
        check_choice("pilot", self.pilot, PILOTS)
        check_range("pilot_prob", self.pilot_prob, 0.0, 1.0)
        for name, value in self._rows().items():
            if value is not None and len(value) != len(self.goal):
                raise ConfigError(f"UserPopulation.{name} has {len(value)} rows, expected {len(self.goal)}")
        if np.any(~np.isfinite(self.beta0) & ~np.isposinf(self.beta0)) or np.any(self.beta0 < 0):
            raise ConfigError(f"beta must be >= 0, got min {np.min(self.beta0)}")
        if np.any(~np.isfinite(self.slope)) or np.any(self.slope < 0):
            raise ConfigError(f"slope must be a finite number >= 0, got min {np.min(self.slope)}")
        if (self.first_target is None) != (self.change_step is None):
            raise ConfigError("first_target and change_step go together: give both or neither")
        if self.change_step is not None:
            steps = np.asarray(self.change_step)
            if steps.dtype.kind not in "iu" or np.any(steps < 0):
                raise ConfigError(f"change_step N must hold integers >= 0, got {steps}")

    def __len__(self) -> int:
        return len(self.goal)

    def _rows(self) -> dict[str, np.ndarray | None]:
        """The fields with one row per user."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in _SCALARS}

    def subset(self, index: np.ndarray) -> UserPopulation:
        """The users at ``index`` (an integer or boolean index array), as a new population."""
        picked = {name: None if v is None else np.asarray(v)[index] for name, v in self._rows().items()}
        return dataclasses.replace(self, **picked)  # type: ignore[arg-type]

    def target_at(self, t: int) -> np.ndarray:
        """The pose each user aims at during step t, shape (U, n)."""
        if self.first_target is None or self.change_step is None:
            return self.target
        return np.where((t < np.asarray(self.change_step))[:, None], self.first_target, self.target)

    def beta(self, t: int) -> np.ndarray:
        """Rationality beta(t) = beta0 + m t of every user at step t, shape (U,)."""
        return self.beta0 + self.slope * t


def user_costs(target: np.ndarray, state: np.ndarray, phi: np.ndarray, dt: float) -> np.ndarray:
    """||s* - (s + dt phi(z))||^2, (U, K), for targets and states (U, n) and candidates' phi (U, K, n)."""
    offset = (target - state)[:, None, :]
    diff = dt * phi
    same_shape = diff.shape == np.broadcast_shapes(offset.shape, diff.shape)
    if same_shape and diff.dtype == np.result_type(offset, diff):
        np.subtract(offset, diff, out=diff)  # the same difference, without a second buffer
    else:
        diff = offset - diff
    return np.einsum("ukn,ukn->uk", diff, diff)


def gumbel_noise(uniform: np.ndarray) -> np.ndarray:
    """Gumbel(0, 1) samples from uniforms in (0, 1)."""
    u = np.clip(uniform, 1e-12, 1.0 - 1e-12)  # a new array: the steps below reuse it
    np.log(u, out=u)
    np.negative(u, out=u)
    np.log(u, out=u)
    return np.negative(u, out=u)


def choose_latent(costs: np.ndarray, beta: np.ndarray, gumbel: np.ndarray) -> np.ndarray:
    """A candidate index per user (U,) from p(z) ∝ exp(-beta cost) by Gumbel-max, for ``costs`` and
    ``gumbel`` (U, K) and ``beta`` (U,); an infinite beta picks the best candidate (the noise breaks
    ties); a non-finite cost (a decoder fault) is never chosen over a finite one."""
    beta = np.asarray(beta, dtype=float)[:, None]
    if np.all(np.isfinite(costs)) and np.all(np.isfinite(beta)) and np.all(beta >= 0.0):
        # the common case in fewer passes (a zero beta gives -0.0 for 0.0: the same sums)
        logits = np.multiply(beta, costs)
        np.negative(logits, out=logits)
        return np.argmax(logits + gumbel, axis=1)
    costs = np.where(np.isfinite(costs), costs, np.inf)
    finite_beta = np.isfinite(beta)
    with np.errstate(invalid="ignore"):
        logits = np.where(finite_beta, -np.where(beta > 0, beta * costs, 0.0), 0.0)
        logits = np.where(np.isinf(costs), -np.inf, logits)
    # infinitely rational users: the best cost wins, noise only breaks exact ties
    best = costs <= costs.min(axis=1, keepdims=True)
    logits = np.where(finite_beta, logits, np.where(best, 0.0, -np.inf))
    return np.argmax(logits + gumbel, axis=1)


def pilot_choice(
    users: UserPopulation,
    choice: np.ndarray,
    previous: np.ndarray | None,
    uniforms: np.ndarray,
    n_candidates: int,
) -> np.ndarray:
    """The inputs (U,) pilots give instead of Eq. S1's ``choice`` (U,): with probability
    ``pilot_prob`` (``uniforms[:, 0]``), a laggy pilot repeats ``previous`` (None at the first step),
    a noisy one gives a random input of ``n_candidates`` (``uniforms[:, 1]``)."""
    if users.pilot == "boltzmann" or users.pilot_prob == 0.0:
        return choice
    event = uniforms[:, 0] < users.pilot_prob
    if users.pilot == "laggy":
        return choice if previous is None else np.where(event, previous, choice)
    random = np.minimum((uniforms[:, 1] * n_candidates).astype(int), n_candidates - 1)
    return np.where(event, random, choice)
