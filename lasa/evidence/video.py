"""Off-screen MuJoCo video: render joint trajectories (software, slow: keep frames small and even)
and write MP4s that are a function of their frames alone, with mediapy and the pinned ffmpeg."""

from __future__ import annotations

import os
import platform
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

import mediapy
import mujoco
import numpy as np
from PIL import Image, ImageDraw

from lasa.base.errors import ConfigError
from lasa.base.ffmpeg import pinned_ffmpeg
from lasa.base.io import atomic_path
from lasa.world.robot import Robot

LAYOUTS = ("side_by_side", "in_turn")  # write_clips: the clips beside each other, or one after another


# x264's SSSE3/AVX kernels differ in bits from plain C: pin the x86-64 baseline, elsewhere plain C.
_X264_ASM = "MMX2,SSE2" if platform.machine().lower() in {"x86_64", "amd64"} else "0"

# Output options that make the MP4 a function of the frames alone (see write_video).
_BITEXACT_ARGS = (
    "-threads", "1",  # one x264 thread: the thread count changes the bitstream and its SEI
    "-x264-params", f"asm={_X264_ASM}",  # the same x264 kernels on every CPU
    "-filter_threads", "1",  # one thread for the RGB -> YUV conversion as well
    "-sws_flags", "bicubic+accurate_rnd+bitexact",  # RGB -> YUV as the C code, not the SIMD
    "-flags:v", "+bitexact",  # no "Lavc..." version string in the stream
    "-fflags", "+bitexact",  # no "Lavf..." encoder tag or other muxer extras
    "-map_metadata", "-1",  # copy no metadata (e.g. creation time) into the container
)  # fmt: skip


def render_states(
    robot: Robot, states: np.ndarray, height: int = 240, width: int = 320, n_jobs: int = 1
) -> np.ndarray:
    """Frames (T, height, width, 3), uint8, of ``states`` (T, n) from the robot's video camera, height and
    width even; ``n_jobs`` > 1 worker processes (joblib) render contiguous parts: the same frames."""
    if height % 2 or width % 2:
        raise ConfigError(f"frame size must be even for H.264, got {width}x{height}")
    if int(n_jobs) != n_jobs or n_jobs < 1:
        raise ConfigError(f"n_jobs must be a positive integer, got {n_jobs!r}")
    states = np.atleast_2d(states)
    if n_jobs > 1 and len(states) > 1:
        from joblib import Parallel, delayed  # noqa: PLC0415 (only when asked for workers)

        parts = np.array_split(states, min(n_jobs, len(states)))
        rendered = Parallel(n_jobs=len(parts))(delayed(render_states)(robot, p, height, width) for p in parts)
        return np.concatenate(rendered)
    data = mujoco.MjData(robot.model)
    frames = np.empty((len(states), height, width, 3), dtype=np.uint8)
    with mujoco.Renderer(robot.model, height, width) as renderer:
        for i, q in enumerate(states):
            data.qpos[robot.qpos_adr] = q
            mujoco.mj_forward(robot.model, data)
            renderer.update_scene(data, camera=robot.spec.camera)
            frames[i] = renderer.render()
    return frames


def label_frames(frames: np.ndarray, text: str | Sequence[str]) -> np.ndarray:
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
    """Atomically write frames (T, H, W, 3), uint8, H and W even, to an H.264 (yuv420p) MP4, the same bytes
    on every machine; quantiser 20 up to 640x480 pixels, 28 above (why: ``docs/method-notes.md``)."""
    frames = np.asarray(frames)
    if frames.ndim != 4 or frames.shape[-1] != 3:
        raise ConfigError(f"frames must have shape (T, H, W, 3), got {frames.shape}")
    height, width = frames.shape[1:3]
    if height % 2 or width % 2:
        raise ConfigError(f"frame size must be even for H.264 (yuv420p), got {width}x{height}")
    mediapy.set_ffmpeg(pinned_ffmpeg())
    qp = 20 if height * width <= 640 * 480 else 28
    h264 = {"codec": "h264", "encoded_format": "yuv420p", "ffmpeg_args": list(_BITEXACT_ARGS)}
    with atomic_path(path) as tmp:
        mediapy.write_video(tmp, frames, fps=fps, qp=qp, **h264)
    return Path(path)


def write_clips(
    robot: Robot,
    clips: Sequence[tuple[np.ndarray, str | Sequence[str]]],
    path: str | os.PathLike[str],
    fps: float,
    layout: Literal["side_by_side", "in_turn"] = "side_by_side",
    height: int = 240,
    width: int = 320,
    n_jobs: int = 1,
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Render and caption ``clips``, ``(states (T, n), caption or one per frame)``, lay them out
    (:data:`LAYOUTS`; shorter clips side by side hold their last frame), write the MP4: the video, clips."""
    if layout not in LAYOUTS:
        raise ConfigError(f"layout must be one of {LAYOUTS}, got {layout!r}")
    if not clips:
        raise ConfigError("write_clips needs at least one clip")
    states = [np.atleast_2d(s) for s, _ in clips]
    for i, (s, (_, caption)) in enumerate(zip(states, clips, strict=True)):
        if not len(s):
            raise ConfigError(f"clip {i} has no states to render")
        if not isinstance(caption, str) and len(caption) != len(s):
            raise ConfigError(f"clip {i}: {len(caption)} captions for {len(s)} frames")
    frames = render_states(robot, np.concatenate(states), height, width, n_jobs)
    parts = np.split(frames, np.cumsum([len(s) for s in states])[:-1])
    shown = [label_frames(part, caption) for part, (_, caption) in zip(parts, clips, strict=True)]
    video = side_by_side(*shown) if layout == "side_by_side" else np.concatenate(shown)
    write_video(path, video, fps=fps)
    return video, shown


def read_video(path: str | os.PathLike[str]) -> np.ndarray:
    """Decode an MP4 into frames (T, H, W, 3), uint8, with mediapy and the pinned ffmpeg."""
    mediapy.set_ffmpeg(pinned_ffmpeg())
    return np.asarray(mediapy.read_video(str(path)))
