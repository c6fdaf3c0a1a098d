"""Rotations about the world's vertical axis, as matrices.

One helper, shared by the Panda's Denavit-Hartenberg reference (:mod:`lasa.world.franka`) and
the grasps of a new cup, turned about the robot's base (:mod:`lasa.method.context_map`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["rot_z"]


def rot_z(angle: float | np.ndarray) -> np.ndarray:
    """The rotation by ``angle`` [rad] about the z axis, shape (3, 3); for angles of shape (...,),
    one per angle, shape (..., 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    zero, one = np.zeros_like(c), np.ones_like(c)
    rows = [np.stack([c, -s, zero], -1), np.stack([s, c, zero], -1), np.stack([zero, zero, one], -1)]
    return np.stack(rows, -2)
