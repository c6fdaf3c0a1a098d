"""Stand-ins the study's tests share: a decoder with the study's mechanics and no trained model."""

from __future__ import annotations

import numpy as np


class LinearDecoder:
    """phi(z, s, b) = z W on the eating task's Panda (4 goals, a 2-axis stick), W seeded."""

    robot, n_goals, z_dim = "panda", 4, 2

    def __init__(self, seed: int = 0, scale: float = 0.3) -> None:
        self.weights = scale * np.random.default_rng(seed).normal(size=(2, 7))

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        shape = np.broadcast_shapes(z.shape[:-1], s.shape[:-1], b.shape[:-1])
        return np.broadcast_to(np.asarray(z) @ self.weights, (*shape, 7)).copy()
