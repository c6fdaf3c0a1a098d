r"""The robot's belief over goals, updated in log space (Algorithm 1, line 8).

After the human's decoded action :math:`a_h` at state s, each goal's belief is
multiplied by the likelihood of that action and renormalised:

.. math::

    b'(g) \propto P(a_h \mid s, g)\, b(g), \qquad
    P(a_h \mid s, g) \propto \exp\!\big(-\beta_b \,(\|g - (s + \Delta a_h)\| - \|g - s\|)\big),

a Boltzmann model of progress towards g: an action that brings the robot closer to g
makes g more likely.

That default has a flaw once the user's desired grasp is not g itself. Two refinements
make the likelihood robust, and ``ControlConfig.likelihood`` selects them:

- ``"goal"``, the plain progress model exactly as above: distances to the points g.
- ``"grasp_set"``: distances to each goal's *set of grasps* (the polyline
  s*(g, theta) over theta, ``goal_sets`` of shape (G, K, n)), and each goal's
  Boltzmann normaliser approximated by its best action, so that the likelihood is
  exp(-beta_b * regret) with regret = d_g(s') - d_g(s) + min(Delta sigma_h, d_g(s)) >= 0,
  the progress lost against the best one step could make. Far from every goal the
  extra term is the same for all goals and cancels (this *is* the default, on sets).
  Near a goal it stops counting "not moving further into a goal one already stands
  at" as evidence against it.

Why both matter, measured on planar5 (notebook 04 states them): with point goals the
belief in the true cup fell to a median of 0.07 during demonstrated grasp
adjustments; with sets but no normaliser, a user holding a top grasp against the
assistance kept pushing along the preference curve, every push counted as evidence
for the *other* cup, and 17% of near-optimal LA+SA users ended at the wrong cup.
A floor keeps every goal's belief at least ``belief_floor`` (a goal-switch prior):
without it a saturated belief could take arbitrarily long to recover when the user
changes their mind.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from lasa.base.config import check_range

__all__ = [
    "uniform_log_belief",
    "distance_to_sets",
    "distance_to_sets_torch",
    "log_likelihood",
    "log_likelihood_torch",
    "logsumexp",
    "update_log_belief",
    "belief",
]


def uniform_log_belief(batch: int, n_goals: int) -> np.ndarray:
    """Log of the uniform prior, shape (batch, n_goals)."""
    return np.full((batch, n_goals), -np.log(n_goals))


def distance_to_sets_torch(points: torch.Tensor, goal_sets: torch.Tensor) -> torch.Tensor:
    """Euclidean distance from each point to each goal's polyline, shape (..., G).

    Differentiable in ``points`` (the entropy regulariser backpropagates through it).

    Args:
        points: Points, shape (..., n).
        goal_sets: One polyline of K vertices per goal, shape (G, K, n); K = 1 is a point.
    """
    p = points[..., None, None, :]  # (..., 1, 1, n)
    if goal_sets.shape[1] == 1:
        return torch.linalg.vector_norm(p[..., 0, :] - goal_sets[:, 0], dim=-1)
    a, ab = goal_sets[:, :-1], torch.diff(goal_sets, dim=1)  # (G, K-1, n)
    t = ((p - a) * ab).sum(-1) / (ab * ab).sum(-1).clamp_min(1e-12)
    closest = a + t.clamp(0.0, 1.0)[..., None] * ab
    return torch.linalg.vector_norm(p - closest, dim=-1).min(dim=-1).values


def log_likelihood_torch(
    state: torch.Tensor,
    action: torch.Tensor,
    goal_sets: torch.Tensor,
    dt: float,
    beta: float,
    max_step: float | None = None,
) -> torch.Tensor:
    """Log P(a_h | s, g) up to a constant shared by all goals, shape (..., G); differentiable.

    Args:
        state: States s, shape (..., n).
        action: Human actions a_h, shape (..., n).
        goal_sets: Goal sets (polylines), shape (G, K, n); K = 1 for point goals.
        dt: Control period Delta [s].
        beta: Belief temperature beta_b >= 0.
        max_step: If given, the longest step the user can make, Delta sigma_h [rad]:
            each goal's likelihood is then normalised by its best action (the regret
            form, see the module docstring). ``None`` is the plain progress model.
    """
    return _log_likelihood(state, action, goal_sets, dt, beta, max_step, distance_to_sets_torch)


def _log_likelihood(
    state: torch.Tensor,
    action: torch.Tensor,
    goal_sets: torch.Tensor,
    dt: float,
    beta: float,
    max_step: float | None,
    distance: Callable[[torch.Tensor, torch.Tensor], torch.Tensor],
) -> torch.Tensor:
    """:func:`log_likelihood_torch` with the distance function ``distance(points, goal_sets)``."""
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


def _as_sets(goals: np.ndarray) -> np.ndarray:
    return goals[:, None, :] if goals.ndim == 2 else goals


# Elements of the (rows, G, K-1, n) work buffer of _distance_blocked: a chunk of rows that
# stays in cache, and few enough chunks that the Python loop costs nothing.
_CHUNK_ELEMENTS = 1 << 18
# Below this many points, _distance_no_grad skips the pruning (its fixed cost dominates).
_PRUNE_MIN_POINTS = 64


def _segment_rows(
    p: torch.Tensor, a: torch.Tensor, ab: torch.Tensor, denom: torch.Tensor, out: torch.Tensor
) -> torch.Tensor:
    """distance_to_sets_torch's per-segment arithmetic on rows (..., n) into ``out`` (..., n).

    ``p``, ``a``, ``ab`` broadcast to ``out``'s shape and ``denom`` to its leading shape. The
    same operations in the same order on each row as there; only addition and multiplication
    swap operands (``t * ab + a`` for ``a + t * ab``), which IEEE arithmetic leaves exact.
    Every reduction runs over a contiguous last axis of n, as there. Returns the distances.
    """
    t = torch.sub(p, a, out=out).mul_(ab).sum(-1)
    t.div_(denom).clamp_(0.0, 1.0)
    torch.mul(t[..., None], ab, out=out)
    out.add_(a)  # closest = a + t ab
    torch.sub(p, out, out=out)
    return torch.linalg.vector_norm(out, dim=-1)


def _distance_blocked(
    flat: torch.Tensor, a: torch.Tensor, ab: torch.Tensor, denom: torch.Tensor
) -> torch.Tensor:
    """Distances (rows, G) of points (rows, n) to every segment, in cache-sized chunks of rows."""
    rows = flat.shape[0]
    out = torch.empty(rows, ab.shape[0], dtype=ab.dtype)
    chunk = max(1, min(rows, _CHUNK_ELEMENTS // max(1, ab.numel())))
    work = torch.empty(chunk, *ab.shape, dtype=ab.dtype)
    for start in range(0, rows, chunk):
        p = flat[start : start + chunk, None, None, :]
        dist = _segment_rows(p, a, ab, denom, work[: p.shape[0]])
        out[start : start + p.shape[0]] = dist.min(dim=-1).values
    return out


def _distance_pruned(
    flat: torch.Tensor, a: torch.Tensor, ab: torch.Tensor, denom: torch.Tensor
) -> torch.Tensor | None:
    """Distances (rows, G) like :func:`_distance_blocked`, on the segments that can be nearest.

    A cheap bound drops every segment that cannot hold a point's minimum: with m the
    segment's midpoint, h the longest half-segment and D the least ||p - m|| over a goal's
    segments, the computed distance to a segment is within h (plus rounding) of ||p - m||,
    so a segment with ||p - m|| > D + 2h (plus generous rounding margins) is farther than
    the nearest midpoint's segment. The kept segments get the exact per-row arithmetic of
    :func:`_segment_rows`, and the minimum over them is the minimum over all, bit for bit.
    Returns None (use :func:`_distance_blocked`) where the bound would keep most segments.
    """
    rows, n = flat.shape
    n_goals, n_seg = ab.shape[:2]
    mid = (a + 0.5 * ab).reshape(-1, n)  # (G (K-1), n)
    half = 0.5 * torch.linalg.vector_norm(ab, dim=-1).max()
    pp = (flat * flat).sum(-1, keepdim=True)  # (rows, 1)
    mm = (mid * mid).sum(-1)
    sq = torch.addmm(pp + mm, flat, mid.T, alpha=-2.0).view(rows, n_goals, n_seg)  # ||p - m||^2
    scale = pp + mm.max() + 1.0  # (rows, 1)
    err_sq = 1e-12 * scale  # >> the rounding of sq, about 1e-15 (||p||^2 + ||m||^2)
    slack = 1e-9 * scale.sqrt()  # >> the rounding of a computed distance
    reach = (sq.amin(-1) + err_sq).clamp_min(0.0).sqrt_() + 2.0 * half + 2.0 * slack  # (rows, G)
    keep = sq <= (reach * reach + err_sq)[..., None]
    idx = keep.view(-1).nonzero().squeeze(1)
    if 2 * idx.numel() > keep.numel():
        return None
    point = torch.div(idx, n_goals * n_seg, rounding_mode="floor")
    seg = idx - point * (n_goals * n_seg)
    p = flat.index_select(0, point)
    dist = _segment_rows(
        p,
        a.reshape(-1, n).index_select(0, seg),
        ab.reshape(-1, n).index_select(0, seg),
        denom.reshape(-1).index_select(0, seg),
        torch.empty_like(p),
    )
    out = torch.full((rows * n_goals,), torch.inf, dtype=dist.dtype)
    out.scatter_reduce_(0, torch.div(idx, n_seg, rounding_mode="floor"), dist, "amin")
    return out.view(rows, n_goals)


def _distance_no_grad(points: torch.Tensor, goal_sets: torch.Tensor) -> torch.Tensor:
    """:func:`distance_to_sets_torch` without autograd, bitwise equal to it, in less time.

    Each distance to a segment is computed by the same operations on the same values as
    there (:func:`_segment_rows`), and the minimum over segments is exact, so the result
    is the same to the bit; the speed comes from skipping the segments that cannot be
    nearest (:func:`_distance_pruned`), and from working in cache-sized chunks into reused
    buffers instead of six fresh (U, G, K-1, n) temporaries.
    """
    if goal_sets.shape[1] == 1 or points.requires_grad or goal_sets.requires_grad:
        return distance_to_sets_torch(points, goal_sets)
    dtype = torch.promote_types(points.dtype, goal_sets.dtype)
    if dtype != torch.float64:
        return distance_to_sets_torch(points, goal_sets)
    a, ab = goal_sets[:, :-1], torch.diff(goal_sets, dim=1)  # (G, K-1, n)
    denom = (ab * ab).sum(-1).clamp_min(1e-12)
    a, ab, denom = a.to(dtype), ab.to(dtype), denom.to(dtype)  # exact: promotion to float64
    lead, n = points.shape[:-1], points.shape[-1]
    flat = points.reshape(-1, n)
    out = None
    finite = bool(torch.isfinite(flat).all()) and bool(torch.isfinite(goal_sets).all())
    if flat.shape[0] >= _PRUNE_MIN_POINTS and finite:
        out = _distance_pruned(flat, a, ab, denom)
    if out is None:
        out = _distance_blocked(flat, a, ab, denom)
    return out.reshape(*lead, goal_sets.shape[0])


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
    """:func:`log_likelihood_torch` on numpy arrays (float64), shape (..., G).

    ``goal_sets`` may also be goal points, shape (G, n), read as sets of one pose (K = 1).
    """
    with torch.no_grad():
        out = _log_likelihood(
            torch.as_tensor(state, dtype=torch.float64),
            torch.as_tensor(action, dtype=torch.float64),
            torch.as_tensor(_as_sets(np.asarray(goal_sets, dtype=np.float64))),
            dt,
            beta,
            max_step,
            _distance_no_grad,
        )
    return out.numpy()


def logsumexp(x: np.ndarray) -> np.ndarray:
    """log sum exp along the last axis, kept as a length-1 axis: numpy's ``logaddexp`` reduced.

    scipy's ``logsumexp`` gives the same to the last bits or two, with array-API dispatch around
    it that cost a third of a planning participant's belief update at the study's batches; the
    ufunc's reduction skips it. A row of only -inf gives -inf, as scipy's does.
    """
    return np.logaddexp.reduce(x, axis=-1, keepdims=True)


def update_log_belief(log_b: np.ndarray, log_lik: np.ndarray, floor: float = 0.0) -> np.ndarray:
    """One Bayesian update b' ∝ P(a_h | s, g) b(g), in log space.

    Args:
        log_b: Current log-beliefs, shape (..., G).
        log_lik: Log-likelihoods of the observed action under each goal, (..., G).
        floor: Each goal keeps at least this belief after the update, in [0, 1/G).

    Returns:
        Normalised log-beliefs, shape (..., G).
    """
    n_goals = log_b.shape[-1]
    check_range("belief_floor", floor, 0.0, 1.0 / n_goals, high_open=True)
    post = log_b + log_lik
    post = post - logsumexp(post)
    if floor > 0.0:
        # Mix with the uniform distribution: b <- (1 - G f) b + f. Every goal keeps at
        # least f, the result still sums to one, and the order of beliefs is unchanged.
        post = np.logaddexp(np.log1p(-n_goals * floor) + post, np.log(floor))
    return post


def belief(log_b: np.ndarray) -> np.ndarray:
    """Beliefs from log-beliefs (they sum to one along the last axis)."""
    return np.exp(log_b - logsumexp(log_b))
