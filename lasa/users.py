r"""Simulated users: Boltzmann-rational joystick choices (Eq. S1).

A simulated user wants the robot at :math:`s^*`, the pose of their goal cup and
preferred grasp, and weighs each joystick input z by where it would move the robot:

.. math::

    p(z) \propto \exp\big\{-\beta(t)\, \|s^* - (s + \Delta\,\phi(z, s, b))\|^2\big\}.

We read :math:`s + \Delta\phi` as the next state the user's own input would produce,
with the control period Delta of the transition :math:`s' = s + \Delta a` (the paper
writes :math:`s + \phi`, with Delta absorbed into its action units). The user does not
model the robot's assistance. beta = 0 gives uniformly random inputs, beta -> inf the
best input on the grid of candidates. The rationality may change over time,
:math:`\beta(t) = \beta_0 + m t` (learning users, Fig. sim3, start at beta_0 = 0), and so
may the goal: a user who changes their mind (Fig. sim2) aims at ``first_target`` for
the steps t < N and at ``target`` from step N on.

Sampling uses the Gumbel-max trick on pre-drawn uniforms, so that a user's choices
depend only on its own random stream: the same user with the same seed makes the same
draws under every method, a paired comparison.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from lasa.errors import ConfigError

__all__ = ["UserPopulation", "user_costs", "choose_latent", "gumbel_noise", "latent_grid"]


@dataclasses.dataclass(frozen=True)
class UserPopulation:
    """A batch of U simulated users, as arrays.

    Attributes:
        goal: Index of each user's cup, shape (U,).
        theta: Each user's preferred grasp in [0, 1], shape (U,).
        target: Each user's desired final pose s*, shape (U, n) [rad].
        beta0: Rationality at t = 0, shape (U,) [1/rad^2].
        slope: Growth of the rationality per step, m in beta(t) = beta0 + m t, (U,).
        seed: The random stream each user draws from (an index into the noise), (U,).
        first_target: The pose each user aims at before changing their mind, (U, n);
            ``None`` for users who never do.
        change_step: N, the first step at which each user aims at ``target``, (U,).
    """

    goal: np.ndarray
    theta: np.ndarray
    target: np.ndarray
    beta0: np.ndarray
    slope: np.ndarray
    seed: np.ndarray
    first_target: np.ndarray | None = None
    change_step: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.goal)
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is not None and len(value) != n:
                raise ConfigError(f"UserPopulation.{f.name} has {len(value)} rows, expected {n}")
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

    def subset(self, index: np.ndarray) -> UserPopulation:
        """The users at ``index`` (an integer or boolean index array), as a new population."""
        picked = {
            f.name: None if getattr(self, f.name) is None else np.asarray(getattr(self, f.name))[index]
            for f in dataclasses.fields(self)
        }
        return UserPopulation(**picked)  # type: ignore[arg-type]

    def target_at(self, t: int) -> np.ndarray:
        """The pose each user aims at during step t, shape (U, n)."""
        if self.first_target is None or self.change_step is None:
            return self.target
        return np.where((t < np.asarray(self.change_step))[:, None], self.first_target, self.target)

    def beta(self, t: int) -> np.ndarray:
        """Rationality beta(t) = beta0 + m t of every user at step t, shape (U,)."""
        return self.beta0 + self.slope * t


def latent_grid(n_z: int, z_dim: int = 1) -> np.ndarray:
    """The joystick candidates the user weighs: an even grid on [-1, 1]^d, (n_z^d, d)."""
    axis = np.linspace(-1.0, 1.0, n_z)
    mesh = np.meshgrid(*([axis] * z_dim), indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=-1)


def user_costs(target: np.ndarray, state: np.ndarray, phi: np.ndarray, dt: float) -> np.ndarray:
    """||s* - (s + dt phi(z))||^2 for every user and candidate, shape (U, K).

    Args:
        target: s* per user, shape (U, n).
        state: s per user, shape (U, n).
        phi: Decoded action of every candidate, shape (U, K, n).
        dt: Control period.
    """
    diff = (target - state)[:, None, :] - dt * phi
    return np.einsum("ukn,ukn->uk", diff, diff)


def gumbel_noise(uniform: np.ndarray) -> np.ndarray:
    """Gumbel(0, 1) samples from uniforms in (0, 1)."""
    u = np.clip(uniform, 1e-12, 1.0 - 1e-12)
    return -np.log(-np.log(u))


def choose_latent(costs: np.ndarray, beta: np.ndarray, gumbel: np.ndarray) -> np.ndarray:
    """Sample a candidate index per user from p(z) ∝ exp(-beta cost) (Gumbel-max).

    An infinite beta picks the best candidate (ties broken by the noise). Non-finite
    costs (a decoder fault) are never chosen over a finite one.

    Args:
        costs: Cost of every candidate, shape (U, K).
        beta: Rationality per user, shape (U,).
        gumbel: Gumbel noise, shape (U, K).

    Returns:
        Chosen candidate indices, shape (U,).
    """
    costs = np.where(np.isfinite(costs), costs, np.inf)
    beta = np.asarray(beta, dtype=float)[:, None]
    finite_beta = np.isfinite(beta)
    with np.errstate(invalid="ignore"):
        logits = np.where(finite_beta, -np.where(beta > 0, beta * costs, 0.0), 0.0)
        logits = np.where(np.isinf(costs), -np.inf, logits)
    # infinitely rational users: the best cost wins, noise only breaks exact ties
    best = costs <= costs.min(axis=1, keepdims=True)
    logits = np.where(finite_beta, logits, np.where(best, 0.0, -np.inf))
    return np.argmax(logits + gumbel, axis=1)
