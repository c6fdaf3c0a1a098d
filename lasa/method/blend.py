r"""Shared autonomy's assistance (Eq. M2, :math:`a_r = \sum_g b(g)(g - s)`), blend (Eq. M1,
:math:`a = (1 - \alpha) a_h + \alpha a_r`) and the safe transition :math:`s' = s + \Delta a` of
Sec. V, vectorised over any leading batch dimensions.
"""

from __future__ import annotations

import numpy as np

from lasa.base.config import check_range
from lasa.base.errors import ConfigError

__all__ = ["assistance", "blend", "sanitize", "safe_step"]


def assistance(belief: np.ndarray, goals: np.ndarray, state: np.ndarray) -> np.ndarray:
    """Eq. M2: a_r = sum_g b(g) (g - s), shape (..., n), from b (..., G), goals (G, n), s (..., n)."""
    return belief @ goals - state * belief.sum(axis=-1, keepdims=True)


def blend(a_h: np.ndarray, a_r: np.ndarray, alpha: float | np.ndarray) -> np.ndarray:
    """Eq. M1: a = (1 - alpha) a_h + alpha a_r; ``alpha`` in [0, 1], a scalar or one per row (...)."""
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
    state: np.ndarray, action: np.ndarray, dt: float, lower: np.ndarray, upper: np.ndarray, max_speed: float
) -> np.ndarray:
    """The transition s' = s + dt a, safe: a non-finite action row is zero, each joint velocity
    clipped to [-max_speed, max_speed] [rad/s], the next state to the joint limits [lower, upper].

    Raises:
        ConfigError: if ``state`` is not finite (a sensor fault is not a command).
    """
    if not np.all(np.isfinite(state)):
        raise ConfigError("state holds NaN or infinite joint positions; refusing to command")
    velocity = np.clip(sanitize(action), -max_speed, max_speed)
    return np.clip(state + dt * velocity, lower, upper)
