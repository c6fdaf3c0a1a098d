"""Episode metrics: final state error, time to reach, and confidence.

Errors are normalised as in the paper: the joint-space distance to the user's desired
pose s*, divided by the distance between the goals. Time counts control steps until
the normalised error first drops to a stated tolerance (the horizon if it never does).
"""

from __future__ import annotations

import numpy as np

from lasa.base.config import check_range

__all__ = ["normalized_error", "time_to_reach", "confidence"]


def normalized_error(states: np.ndarray, target: np.ndarray, goal_distance: float) -> np.ndarray:
    """||s - s*|| / goal_distance, shape (...) for states (..., n) and targets broadcastable."""
    check_range("goal_distance", goal_distance, 0.0, low_open=True)
    return np.linalg.norm(states - target, axis=-1) / goal_distance


def time_to_reach(errors: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """First step at which each episode's error is within ``tolerance``.

    Args:
        errors: Normalised errors over time, shape (T+1, U) (row 0 is the start).
        tolerance: Completion threshold on the normalised error.

    Returns:
        (time, completed): steps to completion, or T where never completed, shape (U,);
        and whether each episode completed, shape (U,).
    """
    check_range("tolerance", tolerance, 0.0, low_open=True)
    reached = errors <= tolerance
    completed = reached.any(axis=0)
    horizon = errors.shape[0] - 1
    return np.where(completed, reached.argmax(axis=0), horizon), np.asarray(completed)


def confidence(beliefs: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """b(g*) for each episode: beliefs (U, G), true goal indices (U,) -> (U,)."""
    return beliefs[np.arange(len(goal)), goal]
