"""The goals' names where the page shows them: each goal's fork-tip position at its goal pose, projected
through the scene's fixed camera (MuJoCo's: along -z, y up, ``cam_fovy``) into [0, 1] from the top left.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from lasa.world.fork import tip_frames
from lasa.world.goals import GoalTask

__all__ = ["ASPECT", "project", "goal_labels"]

ASPECT = 4.0 / 3.0  # width / height of the page's picture (320 x 240 frames, a 480 x 360 canvas)


def project(model: mujoco.MjModel, data: mujoco.MjData, camera: int, points: np.ndarray) -> np.ndarray:
    """Image coordinates (x right, y down, in [0, 1] inside the picture) of world ``points`` (N, 3)."""
    pos, rot = data.cam_xpos[camera], data.cam_xmat[camera].reshape(3, 3)
    local = (np.asarray(points, dtype=float) - pos) @ rot  # camera frame: x right, y up, -z ahead
    tan = math.tan(math.radians(float(model.cam_fovy[camera])) / 2.0)
    depth = -local[:, 2]
    x = local[:, 0] / (depth * tan * ASPECT)
    y = local[:, 1] / (depth * tan)
    return np.stack([(x + 1.0) / 2.0, (1.0 - y) / 2.0], axis=1)


def goal_labels(task: GoalTask, camera: int) -> list[dict[str, Any]]:
    """``{"name", "x", "y"}`` per goal: where its name goes on the picture of camera ``camera``."""
    robot = task.robot
    data = mujoco.MjData(robot.model)  # its own: the station's robot and data are left as they are
    tips = tip_frames(robot, data, np.asarray(task.goals))[0]
    mujoco.mj_forward(robot.model, data)  # the (fixed) camera's pose (cam_xpos: mj_camlight)
    where = project(robot.model, data, camera, tips)
    return [
        {"name": str(name), "x": round(float(x), 4), "y": round(float(y), 4)}
        for name, (x, y) in zip(task.goal_names, where, strict=True)
    ]
