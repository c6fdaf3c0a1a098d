r"""How a simulated participant of the eating study chooses an input, however they foresee it: by how
far it lowers the cost :math:`C = \|p - p^*\| + \ell\, \angle(d, d^*)` to the waypoint, Boltzmann with
:math:`\beta(t) = \beta_\infty (1 - (1 - \rho) e^{-(E_0 + t\Delta)/\tau})`, or rest."""

from __future__ import annotations

import numpy as np

from lasa.people.cohort import ParticipantConfig
from lasa.people.design import Layout
from lasa.people.users import choose_latent, gumbel_noise
from lasa.world.fork import angle_between


def progress_gain(
    pos: np.ndarray,
    axis: np.ndarray,
    dp: np.ndarray,
    new_dir: np.ndarray,
    p_star: np.ndarray,
    d_star: np.ndarray,
    rotation_weight: float,
) -> np.ndarray:
    """How much each candidate (tip motion ``dp``, new direction) lowers the cost C, (A, K) [m]."""
    c_now = np.linalg.norm(pos - p_star, axis=1) + rotation_weight * angle_between(axis, d_star)
    c_new = np.linalg.norm(pos[:, None, :] + dp - p_star[:, None, :], axis=2)
    c_new = c_new + rotation_weight * angle_between(new_dir, d_star[:, None, :])
    return c_now[:, None] - c_new


def choose(
    values: np.ndarray,
    layout: Layout,
    idx: np.ndarray,
    t: int,
    streams: list[np.random.Generator],
    waited: np.ndarray,
    dt: float,
    participant: ParticipantConfig,
) -> tuple[np.ndarray, np.ndarray]:
    """The Boltzmann choice (A,) of episodes ``idx`` at step t of their task, by their participants'
    beta(t), among candidates worth ``values`` (A, P), each drawing P uniforms from ``streams[e]``, and
    whether to give it rather than rest (A,): when the best is worth ``idle_threshold``, or after resting
    (``waited``, (E,) steps) for ``patience``."""
    experience = layout.e0[idx] + t * dt
    beta = layout.beta_inf[idx] * (
        1.0 - (1.0 - participant.novice_fraction) * np.exp(-experience / layout.tau[idx])
    )
    uniforms = np.stack([streams[e].random(values.shape[1]) for e in idx])
    choice = choose_latent(-values, beta, gumbel_noise(uniforms))
    patience_steps = max(1, round(participant.patience / dt))
    return choice, (values.max(axis=1) >= participant.idle_threshold) | (waited[idx] >= patience_steps)
