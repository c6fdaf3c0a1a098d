r"""How a simulated participant of the eating study chooses an input, whichever way they foresee it.

A participant values each candidate input (a stick position, in Retargeting also a mode; for a
planning participant also a hold) by the progress it makes towards the current waypoint
(:func:`lasa.world.eating.waypoints`) under the cost

.. math::  C = \|p - p^*\| + \ell\, \angle(d, d^*)

(:func:`progress_gain`), in units of the best translation one step of Retargeting makes
(``dt * linear_speed``). How the candidates' effects are foreseen is the participant model's:
one step ahead (:mod:`lasa.people.participants`) or over held inputs
(:mod:`lasa.people.planning`). They pick an input by a Boltzmann choice with their own
rationality beta (Gumbel-max, on their episode's own random stream), and give no input at all
(idle) when no candidate would make at least ``idle_threshold`` of that unit of progress,
until their ``patience`` runs out: then they try their Boltzmann choice anyway
(:func:`choose`). Rationality improves with experience,

.. math::  \beta(t) = \beta_\infty \big(1 - (1 - \rho)\, e^{-(E_0 + t\,\Delta)/\tau}\big),

where E_0 is the practice before the condition (:meth:`lasa.people.cohort.Cohort.experience`).
"""

from __future__ import annotations

import numpy as np

from lasa.people.cohort import ParticipantConfig
from lasa.people.design import Layout
from lasa.people.users import choose_latent, gumbel_noise
from lasa.world.fork import angle_between

__all__ = ["progress_gain", "rationality", "choose"]


def progress_gain(
    pos: np.ndarray,
    axis: np.ndarray,
    dp: np.ndarray,
    new_dir: np.ndarray,
    p_star: np.ndarray,
    d_star: np.ndarray,
    rotation_weight: float,
) -> np.ndarray:
    """How much each candidate lowers a participant's cost to the waypoint, (A, K) [m].

    The cost of a tip pose is its distance to the waypoint plus ``rotation_weight`` times
    the angle between its direction and the waypoint's
    (:class:`lasa.people.cohort.ParticipantConfig`).
    """
    c_now = np.linalg.norm(pos - p_star, axis=1) + rotation_weight * angle_between(axis, d_star)
    c_new = np.linalg.norm(pos[:, None, :] + dp - p_star[:, None, :], axis=2)
    c_new = c_new + rotation_weight * angle_between(new_dir, d_star[:, None, :])
    return c_now[:, None] - c_new


def rationality(
    layout: Layout, idx: np.ndarray, t: int, dt: float, participant: ParticipantConfig
) -> np.ndarray:
    """beta(t) of the participants of episodes ``idx`` at step t of their task, (A,)."""
    experience = layout.e0[idx] + t * dt
    return layout.beta_inf[idx] * (
        1.0 - (1.0 - participant.novice_fraction) * np.exp(-experience / layout.tau[idx])
    )


def choose(
    values: np.ndarray,
    beta: np.ndarray,
    streams: list[np.random.Generator],
    idx: np.ndarray,
    waited: np.ndarray,
    dt: float,
    participant: ParticipantConfig,
) -> tuple[np.ndarray, np.ndarray]:
    """The Boltzmann choice of episodes ``idx`` among candidates worth ``values`` (A, P), and
    whether they want to give it.

    Each episode draws P uniforms from its own stream (``streams[e]``) for the Gumbel-max
    choice. An episode wants to give an input when its best candidate makes at least
    ``idle_threshold`` of progress, or when it has rested (``waited``, (E,) steps) for its
    ``patience``.

    Returns:
        The chosen candidate (A,) and whether to give it rather than rest (A,).
    """
    uniforms = np.stack([streams[e].random(values.shape[1]) for e in idx])
    choice = choose_latent(-values, beta, gumbel_noise(uniforms))
    patience_steps = max(1, round(participant.patience / dt))
    wants = (values.max(axis=1) >= participant.idle_threshold) | (waited[idx] >= patience_steps)
    return choice, wants
