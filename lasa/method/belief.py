r"""The robot's belief over goals in log space (Algorithm 1, line 8): :math:`b'(g) \propto
P(a_h \mid s, g)\, b(g)`, a Boltzmann model of progress towards g (the points g, or each goal's
preference set with the regret form), bounded by a floor and an optional cap. Why:
``docs/method-notes.md``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from lasa.base.config import LIKELIHOODS, ControlConfig, check_choice, check_range
from lasa.world.goals import GoalTask

# a context is "confident" when its top belief lies within this of the cap (or of one) [-]
CONFIDENT_MARGIN = 0.01


def belief_targets(task: GoalTask, likelihood: str) -> np.ndarray:
    """What the belief measures progress towards, (G, K, n): the goals (K = 1) or preference sets."""
    check_choice("likelihood", likelihood, LIKELIHOODS)
    return task.goals[:, None, :] if likelihood == "goal" else task.preference_sets


def uniform_log_belief(batch: int, n_goals: int) -> np.ndarray:
    """Log of the uniform prior, shape (batch, n_goals)."""
    return np.full((batch, n_goals), -np.log(n_goals))


def distance_to_sets_torch(points: torch.Tensor, goal_sets: torch.Tensor) -> torch.Tensor:
    """Euclidean distance from points (..., n) to each goal's polyline (G, K, n), (..., G);
    differentiable."""
    p = points[..., None, None, :]  # (..., 1, 1, n)
    if goal_sets.shape[1] == 1:
        return torch.linalg.vector_norm(p[..., 0, :] - goal_sets[:, 0], dim=-1)
    a, ab = goal_sets[:, :-1], torch.diff(goal_sets, dim=1)  # (G, K-1, n)
    return _segment_distances(p, a, ab, (ab * ab).sum(-1).clamp_min(1e-12)).min(dim=-1).values


def log_likelihood_torch(
    state: torch.Tensor,
    action: torch.Tensor,
    goal_sets: torch.Tensor,
    dt: float,
    beta: float,
    max_step: float | None = None,
    distance: Callable[[torch.Tensor, torch.Tensor], torch.Tensor] | None = None,
) -> torch.Tensor:
    """Log P(a_h | s, g) up to a constant shared by all goals, (..., G); differentiable. ``beta`` is
    beta_b; ``max_step`` Delta sigma_h [rad] normalises by each goal's best action (``None``: not);
    ``distance(points, goal_sets)`` is :func:`distance_to_sets_torch` or one equal to it."""
    distance = distance_to_sets_torch if distance is None else distance
    check_range("belief_beta", beta, 0.0)
    moved = state + dt * action
    if distance is _distance_no_grad and moved.shape == state.shape:
        before, after = distance(torch.stack([state, moved]), goal_sets).unbind(0)  # one pass for both
    else:
        before, after = distance(state, goal_sets), distance(moved, goal_sets)
    progress = after - before
    if max_step is not None:
        check_range("max_step", max_step, 0.0)
        progress = progress + before.clamp(max=max_step)
    return -beta * progress


def _segment_distances(
    p: torch.Tensor, a: torch.Tensor, ab: torch.Tensor, denom: torch.Tensor
) -> torch.Tensor:
    """Distances from points p to segments a + t ab (``denom`` = ||ab||^2 >= 1e-12)."""
    t = ((p - a) * ab).sum(-1) / denom
    return torch.linalg.vector_norm(p - (a + t.clamp(0.0, 1.0)[..., None] * ab), dim=-1)


_CANDIDATE_ROWS = 1024  # rows per block of _candidates: its work arrays stay in a core's L2 cache


def _candidates(points: torch.Tensor, a: torch.Tensor, ab: torch.Tensor, denom: torch.Tensor) -> torch.Tensor:
    r"""The segments that can be a point's nearest, shape (rows, G, K-1), bool; no gradient.

    :math:`d^2 = \|p - a\|^2 + t (t \|ab\|^2 - 2 u)` in float64 from two small matrix products;
    a segment is kept when :math:`d^2 \le (d_{\min} + m)^2`, m about 170 float32 rounding units.
    """
    n_goals, n_seg, n = ab.shape
    a64, ab64 = a.double().reshape(-1, n), ab.double().reshape(-1, n)
    den = denom.double().reshape(-1)
    a_ab, a_a = (a64 * ab64).sum(-1), (a64 * a64).sum(-1)
    shift = 1.0 + float(a64.abs().max() + ab64.abs().max())
    out = torch.empty(points.shape[0], n_goals, n_seg, dtype=torch.bool)
    for start in range(0, points.shape[0], _CANDIDATE_ROWS):
        p = points[start : start + _CANDIDATE_ROWS].double()
        u = torch.addmm(a_ab, p, ab64.T, beta=-1.0)  # (p - a) . ab
        t = (u / den).clamp_(0.0, 1.0)
        sq = torch.addmm(a_a, p, a64.T, alpha=-2.0)  # ||p - a||^2 - ||p||^2
        sq.add_((p * p).sum(-1, keepdim=True)).addcmul_(t, u.mul_(-2.0).addcmul_(t, den))
        sq = sq.clamp_min_(0.0).view(-1, n_goals, n_seg)
        margin = 1e-5 * (shift + p.abs().amax(-1))  # (rows,)
        bound = sq.amin(-1).sqrt_().add_(margin[:, None]).square_()
        torch.le(sq, bound[..., None], out=out[start : start + _CANDIDATE_ROWS])
    return out


def _nearest_segment(
    points: torch.Tensor, a: torch.Tensor, ab: torch.Tensor, denom: torch.Tensor
) -> torch.Tensor:
    """The segment distance_to_sets_torch takes each goal's minimum at, (rows, G); no gradient. Ties
    among :func:`_candidates` are settled by the reference arithmetic, the first least as ``min``."""
    n_goals, n_seg, _ = ab.shape
    with torch.no_grad():
        points = points.detach()
        cand = _candidates(points, a, ab, denom)
        index = cand.to(torch.uint8).argmax(dim=-1)  # the first candidate
        row, goal, seg = (cand & (cand.sum(-1) > 1)[..., None]).nonzero(as_tuple=True)
        if row.numel():
            dist = _segment_distances(points[row], a[goal, seg], ab[goal, seg], denom[goal, seg])
            pair = row * n_goals + goal
            least = torch.full((index.numel(),), torch.inf, dtype=dist.dtype)
            least.scatter_reduce_(0, pair, dist, "amin")
            first = torch.full((index.numel(),), n_seg, dtype=seg.dtype)
            ties = dist == least[pair]
            first.scatter_reduce_(0, pair[ties], seg[ties], "amin")
            first = first.view_as(index)
            index = torch.where(first < n_seg, first, index)
    return index


def nearest_distance(points: torch.Tensor, goal_sets: torch.Tensor) -> torch.Tensor:
    """:func:`distance_to_sets_torch`, the same value and gradient, differentiated through the nearest
    segment only (found without autograd), (..., G)."""
    if goal_sets.shape[1] == 1 or not bool(torch.isfinite(points).all()):
        return distance_to_sets_torch(points, goal_sets)
    lead, n, n_goals = points.shape[:-1], points.shape[-1], goal_sets.shape[0]
    a, ab = goal_sets[:, :-1], torch.diff(goal_sets, dim=1)  # (G, K-1, n)
    denom = (ab * ab).sum(-1).clamp_min(1e-12)
    flat = points.reshape(-1, n)
    seg = _nearest_segment(flat, a, ab, denom)  # (rows, G)
    goal = torch.arange(n_goals)
    a_k, ab_k, denom_k = a[goal, seg], ab[goal, seg], denom[goal, seg]  # (rows, G, n), (rows, G)
    return _segment_distances(flat[:, None, :], a_k, ab_k, denom_k).reshape(*lead, n_goals)


def _distance_no_grad(points: torch.Tensor, goal_sets: torch.Tensor) -> torch.Tensor:
    """:func:`distance_to_sets_torch` without autograd, bitwise equal, faster (float64)."""
    dtype = torch.promote_types(points.dtype, goal_sets.dtype)
    if goal_sets.shape[1] == 1 or points.requires_grad or goal_sets.requires_grad or dtype != torch.float64:
        return distance_to_sets_torch(points, goal_sets)
    return nearest_distance(points.to(dtype), goal_sets.to(dtype))


def distance_to_sets(points: np.ndarray, goal_sets: np.ndarray) -> np.ndarray:
    """:func:`distance_to_sets_torch` on numpy arrays (float64), shape (..., G)."""
    with torch.no_grad():
        out = _distance_no_grad(torch.as_tensor(points, dtype=torch.float64), torch.as_tensor(goal_sets))
    return out.numpy()


def log_likelihood(
    state: np.ndarray,
    action: np.ndarray,
    goal_sets: np.ndarray,
    dt: float,
    beta: float,
    max_step: float | None = None,
) -> np.ndarray:
    """:func:`log_likelihood_torch` on numpy arrays (float64), (..., G); goal_sets may be points (G, n)."""
    sets = np.asarray(goal_sets, dtype=np.float64)
    s, a = torch.as_tensor(state, dtype=torch.float64), torch.as_tensor(action, dtype=torch.float64)
    g = torch.as_tensor(sets[:, None, :] if sets.ndim == 2 else sets)
    with torch.no_grad():
        return log_likelihood_torch(s, a, g, dt, beta, max_step, _distance_no_grad).numpy()


def logsumexp(x: np.ndarray) -> np.ndarray:
    """log sum exp along the last axis, kept as a length-1 axis (a row of only -inf gives -inf)."""
    return np.logaddexp.reduce(x, axis=-1, keepdims=True)


def cap_log_belief(log_b: np.ndarray, cap: float) -> np.ndarray:
    """No goal above ``cap`` in (1/2, 1) (Javdani et al.'s ``max_prob_any_goal``): the top goal's
    excess is spread evenly over the others, in log space; ``log_b`` normalised, (..., G)."""
    check_range("belief_cap", cap, 0.5, 1.0, low_open=True, high_open=True)
    n_goals = log_b.shape[-1]
    top = np.argmax(log_b, axis=-1)[..., None]
    over = np.take_along_axis(log_b, top, axis=-1) > np.log(cap)  # (..., 1)
    if not over.any():
        return log_b
    is_top = np.arange(n_goals) == top
    # the top's excess b_top - cap = (1 - cap) - sum of the others: exact when b_top is near one
    excess = np.where(over, (1.0 - cap) - np.exp(logsumexp(np.where(is_top, -np.inf, log_b))), 1.0)
    share = np.log(np.maximum(excess, 1e-300) / (n_goals - 1))
    return np.where(over, np.where(is_top, np.log(cap), np.logaddexp(log_b, share)), log_b)


def update_log_belief(
    log_b: np.ndarray, log_lik: np.ndarray, floor: float = 0.0, cap: float | None = None
) -> np.ndarray:
    """One Bayesian update b' ∝ P(a_h | s, g) b(g) in log space, (..., G); then each goal keeps at
    least ``floor`` in [0, 1/G), and at most ``cap`` (:func:`cap_log_belief`) if given."""
    n_goals = log_b.shape[-1]
    check_range("belief_floor", floor, 0.0, 1.0 / n_goals, high_open=True)
    post = log_b + log_lik
    post = post - logsumexp(post)
    if floor > 0.0:
        # b <- (1 - G f) b + f: at least f each, still summing to one, the order kept
        post = np.logaddexp(np.log1p(-n_goals * floor) + post, np.log(floor))
    if cap is not None:
        post = cap_log_belief(post, cap)
    return post


def confident_belief(n_goals: int, goal: int, floor: float = 0.0, cap: float | None = None) -> np.ndarray:
    """The most confident belief in ``goal`` the update keeps (the rest at the floor or cap), (G,)."""
    rest = floor if cap is None else max(floor, (1.0 - cap) / (n_goals - 1))
    b = np.full(n_goals, rest)
    b[goal] = 1.0 - (n_goals - 1) * rest
    return b


def confidence_threshold(cap: float | None) -> float:
    """The top belief above which a context is confident: the cap (or one) less :data:`CONFIDENT_MARGIN`."""
    return (1.0 if cap is None else cap) - CONFIDENT_MARGIN


def belief(log_b: np.ndarray) -> np.ndarray:
    """Beliefs from log-beliefs (they sum to one along the last axis)."""
    return np.exp(log_b - logsumexp(log_b))


def online_beliefs(
    goal_sets: np.ndarray,
    control: ControlConfig,
    states: np.ndarray,
    actions: np.ndarray,
    log_b0: np.ndarray | None = None,
) -> np.ndarray:
    r"""The belief before each (s, a) of a demonstration, (N, G): what the online update (Algorithm 1,
    line 8, with ``control``'s beta_b, Delta sigma_h, floor and cap) computes along it from ``log_b0`` (G,)
    (default uniform). The likelihoods are one batched call; the update, a recurrence through the floor
    and cap, runs step by step on G numbers."""
    lik = log_likelihood(states, actions, goal_sets, control.dt, control.belief_beta, control.likelihood_step)
    log_b = uniform_log_belief(1, len(goal_sets))[0] if log_b0 is None else np.asarray(log_b0, float)
    out = np.empty((len(states), len(goal_sets)))
    for k in range(len(states)):
        out[k] = belief(log_b)
        log_b = update_log_belief(log_b, lik[k], control.belief_floor, control.belief_cap)
    return out
