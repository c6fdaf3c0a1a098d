"""Episode metrics: the error normalised as in the paper (the joint-space distance to s* over the
distance between the goals), the time to reach a tolerance, and the confidence b(g*)."""

from __future__ import annotations

import numpy as np

from lasa.base.config import check_range


def normalized_error(states: np.ndarray, target: np.ndarray, goal_distance: float) -> np.ndarray:
    """||s - s*|| / goal_distance, shape (...) for states (..., n) and targets broadcastable."""
    check_range("goal_distance", goal_distance, 0.0, low_open=True)
    return np.linalg.norm(states - target, axis=-1) / goal_distance


def time_to_reach(errors: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Per episode of ``errors`` (T+1, U), the first step within ``tolerance`` (T if never), and
    whether it completed, each (U,)."""
    check_range("tolerance", tolerance, 0.0, low_open=True)
    reached = errors <= tolerance
    completed = reached.any(axis=0)
    return np.where(completed, reached.argmax(axis=0), errors.shape[0] - 1), np.asarray(completed)


def confidence(beliefs: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """b(g*) for each episode: beliefs (U, G), true goal indices (U,) -> (U,)."""
    return beliefs[np.arange(len(goal)), goal]
