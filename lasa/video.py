"""Off-screen MuJoCo video: render joint trajectories and write MP4s with mediapy.

Rendering is software-only (OSMesa; ``lasa`` sets ``MUJOCO_GL`` on import) and slow, so
keep frames small (even sizes such as 320x240) and render only the frames a video
shows. The scenes turn shadows and reflections off. mediapy needs an ``ffmpeg``
binary; when none is on the PATH we use the one the ``imageio-ffmpeg`` wheel ships.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import mediapy
import mujoco
import numpy as np
from PIL import Image, ImageDraw

from lasa.errors import ConfigError
from lasa.io import atomic_path
from lasa.robot import Robot

__all__ = ["render_states", "label_frames", "side_by_side", "write_video", "read_video"]


def _ensure_ffmpeg() -> None:
    if shutil.which("ffmpeg") is None:
        import imageio_ffmpeg

        mediapy.set_ffmpeg(imageio_ffmpeg.get_ffmpeg_exe())


def render_states(
    robot: Robot, states: np.ndarray, height: int = 240, width: int = 320, camera: str | None = None
) -> np.ndarray:
    """Render one frame per joint configuration from the robot's fixed camera.

    Args:
        robot: The robot (its scene and camera).
        states: Joint positions, shape (T, n).
        height: Frame height in pixels (even).
        width: Frame width in pixels (even).
        camera: Camera name (default: the robot's video camera).

    Returns:
        Frames, shape (T, height, width, 3), uint8.
    """
    if height % 2 or width % 2:
        raise ConfigError(f"frame size must be even for H.264, got {width}x{height}")
    states = np.atleast_2d(states)
    model = robot.model
    data = mujoco.MjData(model)
    adr = robot.qpos_adr
    frames = np.empty((len(states), height, width, 3), dtype=np.uint8)
    with mujoco.Renderer(model, height, width) as renderer:
        for i, q in enumerate(states):
            data.qpos[adr] = q
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera=camera or robot.spec.camera)
            frames[i] = renderer.render()
    return frames


def label_frames(frames: np.ndarray, text: str | list[str]) -> np.ndarray:
    """Write a caption in the top-left corner of every frame (one per frame, or shared)."""
    out = frames.copy()
    texts = [text] * len(frames) if isinstance(text, str) else text
    for i, t in enumerate(texts):
        img = Image.fromarray(out[i])
        ImageDraw.Draw(img).text((6, 4), t, fill=(20, 20, 20))
        out[i] = np.asarray(img)
    return out


def side_by_side(*videos: np.ndarray) -> np.ndarray:
    """Concatenate videos of equal frame size horizontally, padding the shorter ones."""
    length = max(len(v) for v in videos)
    padded = [np.concatenate([v, np.repeat(v[-1:], length - len(v), 0)]) for v in videos]
    return np.concatenate(padded, axis=2)


def write_video(path: str | os.PathLike[str], frames: np.ndarray, fps: float = 10.0) -> Path:
    """Atomically write frames (T, H, W, 3) to an H.264 MP4."""
    _ensure_ffmpeg()
    with atomic_path(path) as tmp:
        mediapy.write_video(tmp, frames, fps=fps)
    return Path(path)


def read_video(path: str | os.PathLike[str]) -> np.ndarray:
    """Decode an MP4 into frames (T, H, W, 3), uint8.

    Uses the ``imageio-ffmpeg`` reader, which works with that wheel's own ffmpeg
    (mediapy's reader passes an option newer ffmpeg builds reject).
    """
    import imageio_ffmpeg

    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    width, height = meta["size"]
    frames = [np.frombuffer(buf, dtype=np.uint8).reshape(height, width, 3) for buf in reader]
    return np.stack(frames)
