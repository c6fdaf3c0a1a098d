r"""Shared autonomy as a family: the readings of the robot's assistance a_r that the paper allows.

The paper instantiates shared autonomy with Eq. M2, :math:`a_r = \sum_g b(g)(g - s)`, blended
with the human's action by Eq. M1; its footnote 1 allows other instances, and Eq. M2 leaves
open what the goal g *is*. Each member is one reading; ``ControlConfig.assistance`` picks one
for every method with alpha > 0. A member returns a_r and a weight w in [0, 1] on the blend,

.. math::  a = (1 - \alpha w)\, a_h + \alpha w\, a_r ;

w = 1 for every member but ``arbitrated``, which is Eq. M1 exactly. The members:

- :func:`point`: Eq. M2 towards one pose per goal, g = s*(g, 0.5) (the default);
- :func:`grasp_set`: Eq. M2 towards the nearest grasp of each goal;
- :func:`arbitrated`: confidence-based arbitration (Dragan & Srinivasa 2013);
- :func:`hindsight`: hindsight optimisation, goals as sets of targets (Javdani et al. 2018);
- :func:`hindsight_point`: the same with one target per goal.

Every function is vectorised over users: beliefs (U, G), states (U, n), any number of goals G.
:func:`register_member` adds a member of one's own (``docs/extending.md``). What each reading
means and the derivation of ``hindsight``: ``docs/method-notes.md``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from lasa.base.config import ASSISTANCE, BUILT_IN_ASSISTANCE, NO_ASSISTANCE, REGISTERED_ASSISTANCE
from lasa.base.errors import ConfigError
from lasa.method.blend import assistance as eq_m2

__all__ = [
    "ASSISTANCE",
    "BUILT_IN_ASSISTANCE",
    "Member",
    "point",
    "grasp_set",
    "arbitrated",
    "hindsight",
    "hindsight_point",
    "hindsight_value",
    "nearest_grasps",
    "assist",
    "members",
    "register_member",
    "unregister_member",
]

# A member: (belief (U, G), state (U, n), goals (G, n), goal_sets (G, K, n), dt [s],
#   action_scale: sigma_h [rad/s])
# -> (a_r (U, n) [rad/s], blend weight w (U,) in [0, 1]).
Member = Callable[
    [np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float], tuple[np.ndarray, np.ndarray]
]


def point(
    belief: np.ndarray,
    state: np.ndarray,
    goals: np.ndarray,
    goal_sets: np.ndarray,
    dt: float,
    action_scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``point``: Eq. M2, a_r = sum_g b(g) (g - s), towards one pose per goal (the paper, Sec. III).

    Args:
        belief: b, shape (U, G).
        state: s, shape (U, n).
        goals: One pose per goal, shape (G, n).
        goal_sets: Unused here: each goal's grasps, shape (G, K, n).
        dt: Unused here: the control period Delta [s].
        action_scale: Unused here: sigma_h, the human's speed bound [rad/s].

    Returns:
        a_r, shape (U, n), and the blend weight w = 1, shape (U,).
    """
    return eq_m2(belief, goals, state), np.ones(len(state))


def nearest_grasps(state: np.ndarray, goal_sets: np.ndarray) -> np.ndarray:
    r"""The point of each goal's grasp polyline nearest to each state, shape (U, G, n).

    The segments that can be nearest come first from the squared distances in expanded form,
    :math:`\|s - a\|^2 - 2 t u + t^2 \|ab\|^2` with :math:`u = (s - a) \cdot ab` and
    :math:`t = \mathrm{clip}(u / \|ab\|^2, 0, 1)`, whose dot products are two (U, n) x (n, G (K-1))
    matrix products instead of (U, G, K-1, n) temporaries: every segment within a margin far above
    that form's rounding of the least. Those few get the direct arithmetic, :math:`a + t\,ab` and
    its distance, and the first nearest is taken, as an argmin over every segment takes it.

    Args:
        state: s, shape (U, n).
        goal_sets: Each goal's grasps s*(g, theta) on a grid of theta, a polyline, shape (G, K, n).
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


def _candidates(state: np.ndarray, a: np.ndarray, ab: np.ndarray, den: np.ndarray) -> np.ndarray:
    """Segments (U, G, K-1) whose squared distance, in expanded form, is within a margin of the
    least; the margin, 1e-12 of the squares' scale, is thousands of times that form's rounding."""
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
    belief: np.ndarray,
    state: np.ndarray,
    goals: np.ndarray,
    goal_sets: np.ndarray,
    dt: float,
    action_scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``grasp_set``: Eq. M2 towards the nearest grasp of each goal, a_r = sum_g b(g) (c_g(s) - s).

    c_g(s) is the point of goal g's grasp curve nearest to s (:func:`nearest_grasps`). The
    goal is read as the set of its grasps: near a cup the assistance pulls onto the curve,
    not along it, so any grasp the user holds on the curve is a fixed point of the pull.

    Returns:
        a_r, shape (U, n), and w = 1, shape (U,).
    """
    nearest = nearest_grasps(state, goal_sets)
    return np.einsum("ug,ugn->un", belief, nearest - state[:, None, :]), np.ones(len(state))


def arbitrated(
    belief: np.ndarray,
    state: np.ndarray,
    goals: np.ndarray,
    goal_sets: np.ndarray,
    dt: float,
    action_scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``arbitrated``: policy blending with confidence-based arbitration (Dragan & Srinivasa 2013).

    The robot predicts the most likely goal g_hat = argmax_g b(g) and assists towards it
    alone, a_r = g_hat - s. Its say in the blend grows with the confidence of that
    prediction, the linear arbitration w = (max_g b(g) - 1/G) / (1 - 1/G): no assistance
    while the belief is uniform, alpha at full confidence.

    Returns:
        a_r, shape (U, n), and w in [0, 1], shape (U,).
    """
    n_goals = belief.shape[-1]
    best = belief.argmax(axis=-1)
    weight = np.clip((belief.max(axis=-1) - 1.0 / n_goals) / (1.0 - 1.0 / n_goals), 0.0, 1.0)
    return goals[best] - state, weight


def hindsight_value(state: np.ndarray, goal_sets: np.ndarray, delta: float) -> np.ndarray:
    """V_g(s): each goal's hindsight cost-to-go, the Huber distance to its nearest target, (U, G).

    V_g(s) = min_k H(||g_k - s||), where the targets g_k are the goal's set (a polyline of
    poses, :func:`nearest_grasps`; one pose is a set of one) and H is the Huber cost of radius
    ``delta``: H(d) = d for d >= delta, d^2 / (2 delta) + delta / 2 within it (continuous, with
    a continuous gradient). H is increasing, so the least over the targets is H of the distance
    to the nearest one.
    """
    nearest = nearest_grasps(state, goal_sets)
    dist = np.linalg.norm(nearest - state[:, None, :], axis=-1)
    return np.where(dist >= delta, dist, dist**2 / (2.0 * delta) + delta / 2.0)


def _hindsight_pull(
    belief: np.ndarray, state: np.ndarray, targets: np.ndarray, delta: float, action_scale: float
) -> np.ndarray:
    """sigma_h sum_g b(g) (t_g - s) / max(||t_g - s||, delta), with t_g each goal's target, (U, G, n)."""
    diff = targets - state[:, None, :]  # (U, G, n)
    dist = np.maximum(np.linalg.norm(diff, axis=-1, keepdims=True), delta)
    return action_scale * np.einsum("ug,ugn->un", belief, diff / dist)


def hindsight(
    belief: np.ndarray,
    state: np.ndarray,
    goals: np.ndarray,
    goal_sets: np.ndarray,
    dt: float,
    action_scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``hindsight``: hindsight optimisation with goals as sets of targets (Javdani et al. 2018).

    The first-order hindsight-optimal action, a_r = argmin_a sum_g b(g) Q_g(s, a), for a
    cost-to-go that is the distance to the nearest target of each goal's set ``goal_sets[g]``
    (Huber within one step, radius delta = Delta sigma_h: :func:`hindsight_value`), taken at the
    human's speed bound sigma_h, with c_g(s) the nearest target:

    .. math::  a_r = -\\sigma_h \\nabla_s \\sum_g b(g) V_g(s)
               = \\sigma_h \\sum_g b(g) \\frac{c_g(s) - s}{\\max(\\|c_g(s) - s\\|, \\delta)} .

    With a confident belief the pull vanishes anywhere on the goal's set: the assistance holds
    the goal and leaves the preference to the user (Sec. III). The derivation:
    ``docs/method-notes.md``; one target per goal: :func:`hindsight_point`.

    Returns:
        a_r, shape (U, n), and w = 1, shape (U,).
    """
    delta = dt * action_scale
    return _hindsight_pull(belief, state, nearest_grasps(state, goal_sets), delta, action_scale), np.ones(
        len(state)
    )


def hindsight_point(
    belief: np.ndarray,
    state: np.ndarray,
    goals: np.ndarray,
    goal_sets: np.ndarray,
    dt: float,
    action_scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``hindsight_point``: :func:`hindsight` with one target per goal, its pose in ``goals``.

    The reading in which each goal is the single pose g (the mid-preference pose, as Eq. M2's
    ``point``): a_r = sigma_h sum_g b(g) (g - s) / max(||g - s||, delta). Near a goal it pulls
    towards that one pose, so it resists every preference that lies elsewhere in the goal's set.

    Returns:
        a_r, shape (U, n), and w = 1, shape (U,).
    """
    targets = np.broadcast_to(goals[None], (len(state), *goals.shape))
    return _hindsight_pull(belief, state, targets, dt * action_scale, action_scale), np.ones(len(state))


_MEMBERS: dict[str, Member] = {
    "point": point,
    "grasp_set": grasp_set,
    "arbitrated": arbitrated,
    "hindsight": hindsight,
    "hindsight_point": hindsight_point,
}


def members() -> tuple[str, ...]:
    """Every member's name: :data:`BUILT_IN_ASSISTANCE`, then the registered ones in turn."""
    return tuple(_MEMBERS)


def register_member(name: str, member: Member, *, replace: bool = False) -> None:
    """Add a member to the family, from outside the package.

    After it, ``ControlConfig(assistance=name)`` is valid and every assisted step under it
    (:func:`lasa.method.step.shared_autonomy_step`, :func:`lasa.people.rollout.rollout`, the
    :class:`lasa.method.runner.Runner`) calls ``member``, as :func:`assist` calls the
    built-in ones: ``member(belief, state, goals, goal_sets, dt, action_scale)`` with the shapes of
    :func:`assist`, returning a_r (U, n) and the blend weight w (U,) in [0, 1]. The figures'
    default members stay the four of :data:`ASSISTANCE`.

    Args:
        name: The member's name (not a built-in's, nor ``"none"``).
        member: The function.
        replace: Replace a member registered under ``name`` before.

    Raises:
        ConfigError: for a built-in's name, ``"none"``, an empty name, or a name taken
            (unless ``replace``).
    """
    if not isinstance(name, str) or not name or name == NO_ASSISTANCE or name in BUILT_IN_ASSISTANCE:
        raise ConfigError(
            f"a registered member needs a new name (not {NO_ASSISTANCE!r} or a built-in's), got {name!r}"
        )
    if name in _MEMBERS and not replace:
        raise ConfigError(f"assistance member {name!r} is registered already; pass replace=True")
    if not callable(member):
        raise ConfigError(f"assistance member {name!r} must be a function, got {member!r}")
    _MEMBERS[name] = member
    if name not in REGISTERED_ASSISTANCE:
        REGISTERED_ASSISTANCE.append(name)


def unregister_member(name: str) -> None:
    """Remove a member added by :func:`register_member` (the built-in ones stay).

    Raises:
        ConfigError: if ``name`` is not a registered member.
    """
    if name not in REGISTERED_ASSISTANCE:
        raise ConfigError(
            f"{name!r} is not a registered assistance member; registered: {REGISTERED_ASSISTANCE}"
        )
    del _MEMBERS[name]
    REGISTERED_ASSISTANCE.remove(name)


def assist(
    assistance: str,
    belief: np.ndarray,
    state: np.ndarray,
    goals: np.ndarray,
    goal_sets: np.ndarray,
    dt: float,
    action_scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The assistance a_r and the blend weight w of member ``assistance``.

    Args:
        assistance: One of :func:`members`: :data:`ASSISTANCE`, or a registered member.
        belief: b, shape (U, G).
        state: s, shape (U, n).
        goals: One pose per goal, shape (G, n).
        goal_sets: Each goal's grasps, shape (G, K, n).
        dt: The control period Delta [s].
        action_scale: sigma_h, the human's speed bound [rad/s] (``hindsight`` moves at it).

    Raises:
        ConfigError: for an unknown member.
    """
    member = _MEMBERS.get(assistance)
    if member is None:
        raise ConfigError(
            f"unknown assistance {assistance!r}; choose one of {', '.join(map(repr, _MEMBERS))}"
        )
    return member(belief, state, goals, goal_sets, dt, action_scale)
