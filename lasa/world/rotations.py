"""Rotations about the world's vertical axis, as matrices.

One helper, shared by the Panda's Denavit-Hartenberg reference (:mod:`lasa.world.franka`) and
the grasps of a new cup, turned about the robot's base (:mod:`lasa.method.newgoals`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["rot_z"]


def rot_z(angle: float) -> np.ndarray:
    """The rotation by ``angle`` [rad] about the z axis, shape (3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
