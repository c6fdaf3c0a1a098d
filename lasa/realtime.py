r"""Algorithm 1 for one user at control rate: joystick input in, commanded state out.

:func:`lasa.rollout.shared_autonomy_step` is the reference step. It is batched, and
goes through torch and scipy for every call, which costs about 1 ms per step for a
single user: torch dispatches each of the decoder's seven operations in 5-15 us, and
``scipy.special.logsumexp`` takes about 100 us per call on a 2-vector. A robot's
control loop runs one user at 1 kHz, so :class:`Controller` runs the same step for one
user in plain numpy, float64, on arrays prepared once:

1. decode: phi(z, s, b), the decoder's MLP on weights copied out of the torch model
   (a tested copy: it must agree with :meth:`LatentActionModel.decode`);
2. assistance a_r = sum_g b(g) (g - s) (Eq. M2) and blend (Eq. M1);
3. the belief update with the likelihood of :mod:`lasa.belief` (same goal sets, same
   regret normaliser, same floor);
4. the safe transition: a non-finite input decodes to no human action, joint speeds
   are clipped, and the state stays within the joint limits.

``tests/test_realtime.py`` checks that the two steps agree on whole trajectories.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from lasa.config import ControlConfig, check_range
from lasa.decoder import LatentActionModel
from lasa.errors import ConfigError
from lasa.task import CupTask

__all__ = ["Controller"]


def _layers(model: LatentActionModel) -> list[tuple[np.ndarray, np.ndarray]]:
    """(W^T, b) of each Linear of the decoder MLP, float64; tanh between them."""
    layers = []
    modules = list(model.decoder)
    for i, module in enumerate(modules):
        if isinstance(module, torch.nn.Linear):
            w = module.weight.detach().double().numpy().T.copy()
            layers.append((w, module.bias.detach().double().numpy().copy()))
        elif not isinstance(module, torch.nn.Tanh) or i == len(modules) - 1:
            raise ConfigError(f"Controller supports Linear/Tanh decoders, found {type(module).__name__}")
    return layers


class Controller:
    """The shared-autonomy control step for one user, without torch in the loop.

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
        self._layers = _layers(model)
        self._mean = model.state_mean.double().numpy().copy()
        self._inv_std = 1.0 / model.state_std.double().numpy()
        self._scale = float(cfg.action_scale)
        self._d, self._n, self._g = cfg.z_dim, cfg.n_joints, cfg.n_goals
        self._x = np.empty(self._d + self._n + self._g)  # decoder input, filled in place
        sets = np.asarray(task.belief_targets(control.likelihood), dtype=float)
        if sets.shape[1] == 1:  # point goals: a degenerate polyline of one zero-length segment
            sets = np.concatenate([sets, sets], axis=1)
        # Segment k of goal g runs from a_gk along ab_gk. For a point p, with t the clipped
        # projection parameter, |p - a - t ab|^2 = |p|^2 - 2 p.a + |a|^2 - 2 t (p.ab - a.ab)
        # + t^2 |ab|^2: one matrix-vector product gives p.a and p.ab for every segment.
        a = sets[:, :-1].reshape(-1, sets.shape[2])
        ab = np.diff(sets, axis=1).reshape(-1, sets.shape[2])
        self._n_seg = sets.shape[1] - 1
        self._proj = np.ascontiguousarray(np.concatenate([a, ab]).T)  # (n, 2 S)
        self._aa = np.einsum("sn,sn->s", a, a)
        self._a_ab = np.einsum("sn,sn->s", a, ab)
        self._ab2 = np.maximum(np.einsum("sn,sn->s", ab, ab), 1e-12)
        self._pts = np.empty((2, sets.shape[2]))
        self._goals = np.asarray(task.goals, dtype=float)
        self._alpha = float(alpha)
        self._dt = float(control.dt)
        self._beta = float(control.belief_beta)
        self._max_step = control.likelihood_step
        self._floor = float(control.belief_floor)
        self._log_floor = math.log(self._floor) if self._floor > 0 else -math.inf
        self._log_keep = math.log1p(-self._g * self._floor)
        self._speed = float(control.max_joint_speed)
        self._lower, self._upper = task.robot.lower.copy(), task.robot.upper.copy()
        self._start = np.asarray(task.start, dtype=float).copy()
        self.state = self._start.copy()
        self.log_belief = np.full(self._g, -math.log(self._g))

    def reset(self, state: np.ndarray | None = None, log_belief: np.ndarray | None = None) -> None:
        """Back to the start pose and the uniform belief (or the given ones)."""
        self.state = self._start.copy() if state is None else np.array(state, dtype=float)
        if not np.all(np.isfinite(self.state)) or self.state.shape != (self._n,):
            raise ConfigError(f"state must be {self._n} finite joint positions")
        self.log_belief = (
            np.full(self._g, -math.log(self._g)) if log_belief is None else np.array(log_belief, dtype=float)
        )

    @property
    def belief(self) -> np.ndarray:
        """b over the goals, shape (G,)."""
        b = np.exp(self.log_belief - self.log_belief.max())
        return b / b.sum()

    def decode(self, z: np.ndarray, state: np.ndarray, belief: np.ndarray) -> np.ndarray:
        """phi(z, s, b) for one input, shape (n,): the decoder MLP in numpy."""
        x = self._x
        d, n = self._d, self._n
        np.clip(z, -1.0, 1.0, out=x[:d])
        np.multiply(state - self._mean, self._inv_std, out=x[d : d + n])
        x[d + n :] = belief
        h = x
        last = len(self._layers) - 1
        for i, (w, b) in enumerate(self._layers):
            h = h @ w + b
            if i < last:
                np.tanh(h, out=h)
        norm = max(math.sqrt(float(h @ h)), 1e-8)
        return h * (self._scale * math.tanh(norm) / norm)

    def _distances(self, points: np.ndarray) -> np.ndarray:
        """Distance from each of P points (P, n) to each goal's polyline, shape (P, G)."""
        n_seg = self._ab2.size
        dots = points @ self._proj  # (P, 2 S): p.a, then p.ab
        along = dots[:, n_seg:] - self._a_ab
        t = np.clip(along / self._ab2, 0.0, 1.0)
        sq = np.einsum("pn,pn->p", points, points)[:, None] - 2.0 * dots[:, :n_seg] + self._aa
        sq += t * (t * self._ab2 - 2.0 * along)
        best = sq.reshape(len(points), -1, self._n_seg).min(axis=2)
        return np.sqrt(np.maximum(best, 0.0))

    def step(self, z: float | np.ndarray) -> np.ndarray:
        """One step from joystick input z (shape (d,) or a scalar) to the commanded state.

        A non-finite input is no human action (the assistance still applies).

        Returns:
            The new state s', shape (n,) (also kept in :attr:`state`).
        """
        s, log_b = self.state, self.log_belief
        z_arr = np.asarray(z, dtype=float).reshape(self._d)
        b = np.exp(log_b - log_b.max())
        b /= b.sum()
        if np.isfinite(z_arr).all():
            a_h = self.decode(z_arr, s, b)
        else:
            a_h = np.zeros(self._n)
        a = (1.0 - self._alpha) * a_h + self._alpha * (b @ self._goals - s)
        pts = self._pts
        pts[0] = s
        np.multiply(a_h, self._dt, out=pts[1])
        pts[1] += s
        dist = self._distances(pts)
        before = dist[0]
        progress = dist[1] - before
        if self._max_step is not None:
            progress += np.minimum(before, self._max_step)
        post = log_b - self._beta * progress
        top = post.max()
        post -= top + math.log(float(np.exp(post - top).sum()))
        if self._floor > 0.0:
            post = np.logaddexp(self._log_keep + post, self._log_floor)
        np.clip(a, -self._speed, self._speed, out=a)
        new = s + self._dt * a
        np.clip(new, self._lower, self._upper, out=new)
        self.state, self.log_belief = new, post
        return new
