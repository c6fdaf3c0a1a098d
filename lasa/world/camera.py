"""Where world points appear in the picture of a scene's camera: MuJoCo's pinhole camera (the vertical
field of view ``fovy``, the picture's aspect ratio setting the horizontal one), in the picture's
coordinates [0, 1] x [0, 1], x to the right and y down, as a page lays labels over the picture."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from lasa.base.config import check_range
from lasa.base.errors import ConfigError
from lasa.world.robot import Robot


def camera_pose(robot: Robot, camera: str) -> tuple[np.ndarray, np.ndarray]:
    """The world position (3,) and rotation (3, 3) of ``robot``'s camera ``camera``, the arm at home.

    The rotation's columns are the camera's axes in the world, MuJoCo's: x to the picture's right, y up
    it, z backwards (the camera looks along -z). A camera fixed in the world, as the scenes' are, has
    this pose whatever the arm's pose.

    Raises:
        ConfigError: ``camera`` is not a camera of the robot's scene.
    """
    model = robot.model
    if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
        raise ConfigError(f"{robot.name}'s scene has no camera {camera!r}")
    data = mujoco.MjData(model)  # its own: the robot's data is left as it is
    mujoco.mj_resetDataKeyframe(model, data, model.key(robot.spec.home_key).id)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)  # the cameras' poses (cam_xpos, cam_xmat)
    cam = model.camera(camera).id
    return data.cam_xpos[cam].copy(), data.cam_xmat[cam].reshape(3, 3).copy()


def project(robot: Robot, points: np.ndarray, camera: str, aspect: float) -> np.ndarray:
    """Where world ``points`` (N, 3) [m] appear in camera ``camera``'s picture of width / height
    ``aspect``: (N, 2), x right and y down, (0, 0) the top-left corner and (1, 1) the bottom-right one
    (a point outside the picture falls outside [0, 1]).

    Args:
        robot: The robot whose scene holds the camera (posed as :func:`camera_pose`).
        points: World positions, shape (N, 3) [m], all in front of the camera.
        camera: The camera's name in the scene.
        aspect: The picture's width over its height (> 0).

    Raises:
        ConfigError: An unknown camera, an aspect that is not positive, or a point that is not in front
            of the camera (it has no place in the picture).
    """
    check_range("aspect", aspect, 0.0, low_open=True)
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ConfigError(f"points must have shape (N, 3), got {points.shape}")
    position, rotation = camera_pose(robot, camera)
    local = (points - position) @ rotation  # the points in the camera's frame
    behind = ~(local[:, 2] < 0.0)  # NaN too
    if behind.any():
        raise ConfigError(f"camera {camera!r} sees only points in front of it, not {points[behind].tolist()}")
    fovy = float(robot.model.cam_fovy[robot.model.camera(camera).id])
    tan = math.tan(math.radians(fovy) / 2.0)
    x = local[:, 0] / (-local[:, 2] * tan * aspect)  # -1 at the picture's left edge, 1 at its right
    y = local[:, 1] / (-local[:, 2] * tan)  # -1 at its bottom, 1 at its top
    return np.stack([(x + 1.0) / 2.0, (1.0 - y) / 2.0], axis=1)
