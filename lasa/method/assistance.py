r"""Shared autonomy as a family of members, each a way of computing the robot's assistance a_r.

Eq. M2, :math:`a_r = \sum_g b(g)(g - s)`, is the paper's (its footnote 1 allows others). A member
returns a_r and a weight w in [0, 1] on the blend :math:`a = (1 - \alpha w) a_h + \alpha w a_r` (w = 1
but for ``arbitrated``), vectorised over users. Each member: ``docs/method-notes.md``.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Protocol, runtime_checkable

import numpy as np
from numpy import ndarray

from lasa.base.errors import ConfigError


@runtime_checkable
class Member(Protocol):
    """A member of the shared-autonomy family: any function of this signature is one
    (``docs/extending.md``); configs name the built-in ones, :data:`MEMBERS`."""

    def __call__(
        self,
        belief: ndarray,
        state: ndarray,
        goals: ndarray,
        goal_sets: ndarray,
        dt: float,
        action_scale: float,
    ) -> tuple[ndarray, ndarray]:
        """a_r (U, n) [rad/s] and w (U,) from b (U, G), s (U, n), one pose per goal (G, n), each
        goal's grasps (G, K, n), the period Delta [s] and the human's speed bound sigma_h [rad/s]."""


def point(
    belief: ndarray, state: ndarray, goals: ndarray, goal_sets: ndarray, dt: float, action_scale: float
) -> tuple[ndarray, ndarray]:
    """``point``: Eq. M2, a_r = sum_g b(g) (g - s), towards one pose per goal (Sec. III); w = 1."""
    return belief @ goals - state * belief.sum(axis=-1, keepdims=True), np.ones(len(state))


def nearest_grasps(state: ndarray, goal_sets: ndarray) -> ndarray:
    r"""The point of each goal's grasp polyline (G, K, n) nearest to each state s (U, n), (U, G, n).

    Segments within a margin of the least expanded-form distance get the direct arithmetic,
    :math:`a + t\,ab`; the first nearest is taken, as an argmin over every segment takes it.
    """
    if goal_sets.shape[1] == 1:
        return np.broadcast_to(goal_sets[None, :, 0], (len(state), *goal_sets[:, 0].shape)).copy()
    a, ab = goal_sets[:, :-1], np.diff(goal_sets, axis=1)  # segments a + t ab, (G, K-1, n)
    den = np.maximum(np.einsum("gkn,gkn->gk", ab, ab), 1e-12)
    user, goal, seg = np.nonzero(_candidates(state, a, ab, den))
    rel = state[user] - a[goal, seg]
    t = np.clip(np.einsum("cn,cn->c", rel, ab[goal, seg]) / den[goal, seg], 0.0, 1.0)
    closest = a[goal, seg] + t[:, None] * ab[goal, seg]
    dist = np.linalg.norm(state[user] - closest, axis=-1)
    pair = user * a.shape[0] + goal
    order = np.lexsort((seg, dist, pair))  # by (user, goal), then distance, then the first segment
    first = order[np.r_[True, pair[order][1:] != pair[order][:-1]]]
    return closest[first].reshape(len(state), a.shape[0], -1)


def _candidates(state: ndarray, a: ndarray, ab: ndarray, den: ndarray) -> ndarray:
    """Segments (U, G, K-1) whose expanded-form squared distance is within 1e-12 of the squares'
    scale (thousands of times that form's rounding) of the least."""
    n_goals, n_seg, n = ab.shape
    a2, ab2 = a.reshape(-1, n), ab.reshape(-1, n)
    u = state @ ab2.T - np.einsum("kn,kn->k", a2, ab2)  # (s - a) . ab, (U, G (K-1))
    t = np.clip(u / den.reshape(-1), 0.0, 1.0)
    ss = np.einsum("un,un->u", state, state)[:, None]
    sq = ss - 2.0 * (state @ a2.T) + np.einsum("kn,kn->k", a2, a2) + t * (t * den.reshape(-1) - 2.0 * u)
    sq = sq.reshape(len(state), n_goals, n_seg)
    scale = 1.0 + ss[:, :, None] + float(np.max(a2 * a2, initial=0.0) * n + np.max(ab2 * ab2) * n)
    return sq <= sq.min(axis=-1, keepdims=True) + 1e-12 * scale


def grasp_set(
    belief: ndarray, state: ndarray, goals: ndarray, goal_sets: ndarray, dt: float, action_scale: float
) -> tuple[ndarray, ndarray]:
    """``grasp_set``: Eq. M2 towards each goal's nearest grasp c_g(s), a_r = sum_g b(g) (c_g(s) - s);
    w = 1."""
    nearest = nearest_grasps(state, goal_sets)
    return np.einsum("ug,ugn->un", belief, nearest - state[:, None, :]), np.ones(len(state))


def arbitrated(
    belief: ndarray, state: ndarray, goals: ndarray, goal_sets: ndarray, dt: float, action_scale: float
) -> tuple[ndarray, ndarray]:
    """``arbitrated``: policy blending (Dragan & Srinivasa 2013), a_r = g_hat - s towards the
    likeliest goal, w = (max_g b(g) - 1/G) / (1 - 1/G)."""
    n_goals = belief.shape[-1]
    best = belief.argmax(axis=-1)
    weight = np.clip((belief.max(axis=-1) - 1.0 / n_goals) / (1.0 - 1.0 / n_goals), 0.0, 1.0)
    return goals[best] - state, weight


def hindsight_value(state: ndarray, goal_sets: ndarray, delta: float) -> ndarray:
    """V_g(s) = min_k H(||g_k - s||), each goal's hindsight cost-to-go, (U, G); H the Huber cost of
    radius ``delta``: d for d >= delta, d^2 / (2 delta) + delta / 2 within it."""
    dist = np.linalg.norm(nearest_grasps(state, goal_sets) - state[:, None, :], axis=-1)
    return np.where(dist >= delta, dist, dist**2 / (2.0 * delta) + delta / 2.0)


def _hindsight_pull(
    belief: ndarray, state: ndarray, targets: ndarray, delta: float, action_scale: float
) -> ndarray:
    """sigma_h sum_g b(g) (t_g - s) / max(||t_g - s||, delta), with t_g each goal's target, (U or 1, G, n)."""
    diff = targets - state[:, None, :]  # (U, G, n)
    dist = np.maximum(np.linalg.norm(diff, axis=-1, keepdims=True), delta)
    return action_scale * np.einsum("ug,ugn->un", belief, diff / dist)


def hindsight(
    belief: ndarray, state: ndarray, goals: ndarray, goal_sets: ndarray, dt: float, action_scale: float
) -> tuple[ndarray, ndarray]:
    """``hindsight``: hindsight optimisation, goals as sets of targets (Javdani et al. 2018); w = 1,
    delta = Delta sigma_h (:func:`hindsight_value`):

    .. math::  a_r = -\\sigma_h \\nabla_s \\sum_g b(g) V_g(s)
               = \\sigma_h \\sum_g b(g) \\frac{c_g(s) - s}{\\max(\\|c_g(s) - s\\|, \\delta)} .
    """
    pull = _hindsight_pull(belief, state, nearest_grasps(state, goal_sets), dt * action_scale, action_scale)
    return pull, np.ones(len(state))


def hindsight_point(
    belief: ndarray, state: ndarray, goals: ndarray, goal_sets: ndarray, dt: float, action_scale: float
) -> tuple[ndarray, ndarray]:
    """``hindsight_point``: :func:`hindsight` with one target per goal, its pose in ``goals``; w = 1."""
    return _hindsight_pull(belief, state, goals[None], dt * action_scale, action_scale), np.ones(len(state))


MEMBERS: Mapping[str, Member] = MappingProxyType(
    {m.__name__: m for m in (point, grasp_set, arbitrated, hindsight, hindsight_point)}
)  # the built-in members by the names configs use, :data:`lasa.base.config.BUILT_IN_ASSISTANCE`


def resolve(member: str | Member) -> Member:
    """The member a config gives: a built-in one by its name, or the member itself (else ConfigError)."""
    if isinstance(member, str):
        if member not in MEMBERS:
            raise ConfigError(f"unknown assistance {member!r}; choose one of {', '.join(map(repr, MEMBERS))}")
        return MEMBERS[member]
    if not isinstance(member, Member):
        raise ConfigError(f"an assistance member is a built-in's name or a function, got {member!r}")
    return member


def assist(
    assistance: str | Member,
    belief: ndarray,
    state: ndarray,
    goals: ndarray,
    goal_sets: ndarray,
    dt: float,
    action_scale: float,
) -> tuple[ndarray, ndarray]:
    """a_r and w of member ``assistance`` (:func:`resolve`), with the arguments of :class:`Member`."""
    return resolve(assistance)(belief, state, goals, goal_sets, dt, action_scale)
