r"""Algorithm 1 for one user at control rate: joystick input in, commanded state out.

:func:`lasa.rollout.shared_autonomy_step` is the reference step. It is batched, and
goes through torch and scipy on every call, which costs about 1 ms per step for a
single user: torch dispatches each of the decoder's seven operations in 5-15 us, and
``scipy.special.logsumexp`` takes about 100 us per call on a 2-vector. The same step in
plain numpy still took 105 us (median) here, two dozen array calls of 1-3 us each. A
robot's control loop runs one user at 1 kHz, so :class:`Controller` compiles the step
with numba, float64, on arrays prepared once:

1. decode: phi(z, s, b), the decoder's MLP on weights copied out of the torch model
   (a tested copy: it must agree with :meth:`LatentActionModel.decode`);
2. assistance a_r = sum_g b(g) (g - s) (Eq. M2) and blend (Eq. M1);
3. the belief update with the likelihood of :mod:`lasa.belief` (same goal sets, same
   regret normaliser, same floor);
4. the safe transition: a non-finite input decodes to no human action, joint speeds
   are clipped, and the state stays within the joint limits.

``tests/test_realtime.py`` checks that the two steps agree on whole trajectories. The
kernel is compiled on first use (a few seconds, then cached beside the module).
"""

from __future__ import annotations

import math

import numba
import numpy as np
import torch
from numba.typed import List as TypedList

from lasa.belief import belief
from lasa.config import ControlConfig, check_range
from lasa.decoder import LatentActionModel
from lasa.errors import ConfigError
from lasa.task import CupTask

__all__ = ["Controller"]


@numba.njit(cache=True)
def _mlp(x: np.ndarray, weights: TypedList, biases: TypedList) -> np.ndarray:  # pragma: no cover (jit)
    """Linear layers (x @ W^T + b) with tanh between them."""
    h = x
    last = len(weights) - 1
    for i in range(last + 1):
        h = h @ weights[i] + biases[i]
        if i < last:
            h = np.tanh(h)
    return h


@numba.njit(cache=True)
def _decode(
    z: np.ndarray,
    s: np.ndarray,
    b: np.ndarray,
    weights: TypedList,
    biases: TypedList,
    mean: np.ndarray,
    inv_std: np.ndarray,
    scale: float,
) -> np.ndarray:  # pragma: no cover (jit)
    """phi(z, s, b): the MLP, then the radial squash to norm below sigma_h."""
    d, n, g = z.shape[0], s.shape[0], b.shape[0]
    x = np.empty(d + n + g)
    for i in range(d):
        x[i] = min(1.0, max(-1.0, z[i]))
    for i in range(n):
        x[d + i] = (s[i] - mean[i]) * inv_std[i]
    for i in range(g):
        x[d + n + i] = b[i]
    v = _mlp(x, weights, biases)
    norm = max(math.sqrt(np.sum(v * v)), 1e-8)
    return v * (scale * math.tanh(norm) / norm)


@numba.njit(cache=True)
def _distances(
    p: np.ndarray, proj: np.ndarray, aa: np.ndarray, a_ab: np.ndarray, ab2: np.ndarray, n_goals: int
) -> np.ndarray:  # pragma: no cover (jit)
    """Distance from p to each goal's polyline (segments a + t ab, t in [0, 1]), shape (G,)."""
    dots = p @ proj  # p.a for every segment, then p.ab
    n_all = aa.shape[0]
    per_goal = n_all // n_goals
    pp = np.sum(p * p)
    out = np.empty(n_goals)
    for g in range(n_goals):
        best = np.inf
        for k in range(g * per_goal, (g + 1) * per_goal):
            along = dots[n_all + k] - a_ab[k]
            t = min(1.0, max(0.0, along / ab2[k]))
            sq = pp - 2.0 * dots[k] + aa[k] + t * (t * ab2[k] - 2.0 * along)
            best = min(best, sq)
        out[g] = math.sqrt(max(best, 0.0))
    return out


@numba.njit(cache=True)
def _step(
    z: np.ndarray,
    s: np.ndarray,
    log_b: np.ndarray,
    weights: TypedList,
    biases: TypedList,
    mean: np.ndarray,
    inv_std: np.ndarray,
    scale: float,
    goals: np.ndarray,
    proj: np.ndarray,
    aa: np.ndarray,
    a_ab: np.ndarray,
    ab2: np.ndarray,
    alpha: float,
    dt: float,
    beta: float,
    max_step: float,
    floor: float,
    lower: np.ndarray,
    upper: np.ndarray,
    speed: float,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover (jit)
    """One step of Algorithm 1 for one user; returns (s', log b')."""
    n_goals = log_b.shape[0]
    b = np.exp(log_b - np.max(log_b))
    b /= np.sum(b)
    a_h = np.zeros(s.shape[0])
    if np.all(np.isfinite(z)):
        a_h = _decode(z, s, b, weights, biases, mean, inv_std, scale)
    a = (1.0 - alpha) * a_h + alpha * (b @ goals - s)
    before = _distances(s, proj, aa, a_ab, ab2, n_goals)
    after = _distances(s + dt * a_h, proj, aa, a_ab, ab2, n_goals)
    post = np.empty(n_goals)
    for g in range(n_goals):
        progress = after[g] - before[g]
        if max_step >= 0.0:
            progress += min(before[g], max_step)
        post[g] = log_b[g] - beta * progress
    top = np.max(post)
    post -= top + math.log(np.sum(np.exp(post - top)))
    if floor > 0.0:
        keep, log_floor = math.log1p(-n_goals * floor), math.log(floor)
        for g in range(n_goals):
            x = keep + post[g]
            hi = max(x, log_floor)
            post[g] = hi + math.log(math.exp(x - hi) + math.exp(log_floor - hi))
    new = np.empty(s.shape[0])
    for i in range(s.shape[0]):
        v = min(speed, max(-speed, a[i]))
        new[i] = min(upper[i], max(lower[i], s[i] + dt * v))
    return new, post


def _layers(model: LatentActionModel) -> tuple[TypedList, TypedList]:
    """(W^T, b) of each Linear of the decoder MLP, float64; tanh between them."""
    weights, biases = TypedList(), TypedList()
    modules = list(model.decoder)
    for i, module in enumerate(modules):
        if isinstance(module, torch.nn.Linear):
            weights.append(np.ascontiguousarray(module.weight.detach().double().numpy().T))
            biases.append(module.bias.detach().double().numpy().copy())
        elif not isinstance(module, torch.nn.Tanh) or i == len(modules) - 1:
            raise ConfigError(f"Controller supports Linear/Tanh decoders, found {type(module).__name__}")
    return weights, biases


class Controller:
    """The shared-autonomy control step for one user, compiled, without torch in the loop.

    Args:
        model: The decoder phi(z, s, b); its robot and goal count must match the task.
        task: The cup task (goals, belief sets, joint limits).
        control: Control-loop units.
        alpha: Blend weight in [0, 1] (0 is ``LA``).

    Attributes:
        state: The current joint positions s, shape (n,) [rad].
        log_belief: The current log-belief, shape (G,).
    """

    def __init__(self, model: LatentActionModel, task: CupTask, control: ControlConfig, alpha: float) -> None:
        if model.config.robot != task.robot.name:
            raise ConfigError(
                f"decoder was trained for {model.config.robot!r}, the task is for {task.robot.name!r}"
            )
        if model.config.n_goals != task.n_goals:
            raise ConfigError(f"decoder reads {model.config.n_goals} goals, the task has {task.n_goals}")
        check_range("alpha", alpha, 0.0, 1.0)
        cfg = model.config
        self._d, self._n, self._g = cfg.z_dim, cfg.n_joints, cfg.n_goals
        self._weights, self._biases = _layers(model)
        self._mean = model.state_mean.double().numpy().copy()
        self._inv_std = 1.0 / model.state_std.double().numpy()
        self._scale = float(cfg.action_scale)
        sets = np.asarray(task.belief_targets(control.likelihood), dtype=float)
        if sets.shape[1] == 1:  # point goals: a degenerate polyline of one zero-length segment
            sets = np.concatenate([sets, sets], axis=1)
        # Segment k runs from a_k along ab_k. For a point p and the clipped projection t,
        # |p - a - t ab|^2 = |p|^2 - 2 p.a + |a|^2 - 2 t (p.ab - a.ab) + t^2 |ab|^2: one
        # matrix-vector product gives p.a and p.ab for every segment of every goal.
        a = sets[:, :-1].reshape(-1, sets.shape[2])
        ab = np.diff(sets, axis=1).reshape(-1, sets.shape[2])
        self._proj = np.ascontiguousarray(np.concatenate([a, ab]).T)  # (n, 2 S)
        self._aa = np.einsum("sn,sn->s", a, a)
        self._a_ab = np.einsum("sn,sn->s", a, ab)
        self._ab2 = np.maximum(np.einsum("sn,sn->s", ab, ab), 1e-12)
        self._goals = np.ascontiguousarray(task.goals, dtype=float)
        self._alpha = float(alpha)
        self._dt = float(control.dt)
        self._beta = float(control.belief_beta)
        self._max_step = -1.0 if control.likelihood_step is None else float(control.likelihood_step)
        self._floor = float(control.belief_floor)
        self._speed = float(control.max_joint_speed)
        self._lower, self._upper = task.robot.lower.copy(), task.robot.upper.copy()
        self._start = np.asarray(task.start, dtype=float).copy()
        self._z = np.zeros(self._d)
        self.state = self._start.copy()
        self.log_belief = np.full(self._g, -math.log(self._g))

    def reset(self, state: np.ndarray | None = None, log_belief: np.ndarray | None = None) -> None:
        """Back to the start pose and the uniform belief (or the given ones)."""
        new = self._start.copy() if state is None else np.array(state, dtype=float)
        if new.shape != (self._n,) or not np.all(np.isfinite(new)):
            raise ConfigError(f"state must be {self._n} finite joint positions")
        self.state = new
        self.log_belief = (
            np.full(self._g, -math.log(self._g)) if log_belief is None else np.array(log_belief, dtype=float)
        )

    @property
    def belief(self) -> np.ndarray:
        """b over the goals, shape (G,)."""
        return belief(self.log_belief)

    def decode(self, z: np.ndarray, state: np.ndarray, belief: np.ndarray) -> np.ndarray:
        """phi(z, s, b) for one input, shape (n,)."""
        return _decode(
            np.asarray(z, dtype=float).reshape(self._d),
            np.asarray(state, dtype=float),
            np.asarray(belief, dtype=float),
            self._weights,
            self._biases,
            self._mean,
            self._inv_std,
            self._scale,
        )

    def step(self, z: float | np.ndarray) -> np.ndarray:
        """One step from joystick input z (shape (d,) or a scalar) to the commanded state.

        A non-finite input is no human action (the assistance still applies).

        Returns:
            The new state s', shape (n,) (also kept in :attr:`state`).
        """
        if self._d == 1 and isinstance(z, float | int):
            self._z[0] = z
            z_arr = self._z
        else:
            z_arr = np.asarray(z, dtype=float).reshape(self._d)
        self.state, self.log_belief = _step(
            z_arr,
            self.state,
            self.log_belief,
            self._weights,
            self._biases,
            self._mean,
            self._inv_std,
            self._scale,
            self._goals,
            self._proj,
            self._aa,
            self._a_ab,
            self._ab2,
            self._alpha,
            self._dt,
            self._beta,
            self._max_step,
            self._floor,
            self._lower,
            self._upper,
            self._speed,
        )
        return self.state
