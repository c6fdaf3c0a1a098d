r"""Shared autonomy: the assistance, the blend and the safe control step.

Eq. M2, the robot's assistance towards each goal in proportion to its belief:

.. math::  a_r = \sum_{g \in G} b(g)\,(g - s)

Eq. M1, the blend of the human's decoded action with the assistance:

.. math::  a = (1 - \alpha)\, a_h + \alpha\, a_r, \qquad \alpha \in [0, 1]

and the transition of Sec. V, :math:`s' = s + \Delta a`, made safe: a non-finite action
becomes zero (the robot holds still), each joint's velocity is clipped to the robot's
speed bound, and the next state is clipped to the joint limits. Everything is
vectorised over any number of leading batch dimensions.
"""

from __future__ import annotations

import numpy as np

from lasa.base.config import check_range
from lasa.base.errors import ConfigError

__all__ = ["assistance", "blend", "sanitize", "safe_step"]


def assistance(belief: np.ndarray, goals: np.ndarray, state: np.ndarray) -> np.ndarray:
    """Eq. M2: a_r = sum_g b(g) (g - s), shape (..., n).

    Args:
        belief: Beliefs b, shape (..., G), each row summing to one.
        goals: Goals, shape (G, n).
        state: States s, shape (..., n).
    """
    return belief @ goals - state * belief.sum(axis=-1, keepdims=True)


def blend(a_h: np.ndarray, a_r: np.ndarray, alpha: float | np.ndarray) -> np.ndarray:
    """Eq. M1: a = (1 - alpha) a_h + alpha a_r.

    Args:
        a_h: Human (decoded) actions, shape (..., n).
        a_r: Assistive actions, shape (..., n).
        alpha: Blend weight(s) in [0, 1]: a scalar, or one per batch row, shape (...).
    """
    alpha_arr = np.asarray(alpha, dtype=float)
    if alpha_arr.ndim == 0:
        check_range("alpha", float(alpha_arr), 0.0, 1.0)
    elif not np.all((alpha_arr >= 0.0) & (alpha_arr <= 1.0)):
        raise ConfigError(f"alpha must be in [0, 1], got values in [{alpha_arr.min()}, {alpha_arr.max()}]")
    alpha_arr = alpha_arr[..., None]
    return (1.0 - alpha_arr) * a_h + alpha_arr * a_r


def sanitize(action: np.ndarray) -> np.ndarray:
    """Replace every row that holds a non-finite entry by a zero action."""
    bad = ~np.all(np.isfinite(action), axis=-1, keepdims=True)
    return np.where(bad, 0.0, action)


def safe_step(
    state: np.ndarray,
    action: np.ndarray,
    dt: float,
    lower: np.ndarray,
    upper: np.ndarray,
    max_speed: float,
) -> np.ndarray:
    """The transition s' = s + dt a, with the control loop's safety invariants.

    - a row of ``action`` with a NaN or infinite entry becomes a zero action;
    - each joint velocity is clipped to [-max_speed, max_speed], so no step moves a
      joint by more than ``dt * max_speed``;
    - the next state is clipped to the joint limits [lower, upper].

    Args:
        state: Current joint positions, shape (..., n). Must be finite.
        action: Commanded joint velocities, shape (..., n).
        dt: Control period [s].
        lower: Lower joint limits, shape (n,).
        upper: Upper joint limits, shape (n,).
        max_speed: Per-joint speed bound [rad/s].

    Raises:
        ConfigError: if ``state`` is not finite (a sensor fault is not a command).
    """
    if not np.all(np.isfinite(state)):
        raise ConfigError("state holds NaN or infinite joint positions; refusing to command")
    velocity = np.clip(sanitize(action), -max_speed, max_speed)
    return np.clip(state + dt * velocity, lower, upper)
