"""The one ffmpeg lasa's videos use: the pinned ``imageio-ffmpeg`` wheel's.

mediapy runs whatever ``ffmpeg`` it is told to, else the one on the PATH; :mod:`lasa.evidence.video`
points it here (``mediapy.set_ffmpeg``) wherever it writes or reads a video. The pinned pair,
mediapy 1.2.7 and imageio-ffmpeg 0.7.0 (ffmpeg 7.0.2), works together: mediapy's reader passes
``-vsync``, which ffmpeg 9 (imageio-ffmpeg 0.8) no longer has.
"""

from __future__ import annotations

import functools
import importlib.resources
import os
from pathlib import Path

__all__ = ["pinned_ffmpeg"]


@functools.cache
def pinned_ffmpeg() -> str:
    """Return the ffmpeg binary shipped inside the installed ``imageio-ffmpeg`` wheel.

    Unlike ``imageio_ffmpeg.get_ffmpeg_exe`` this never falls back to the
    ``IMAGEIO_FFMPEG_EXE`` variable, a conda ffmpeg or one on the PATH, so the encoder
    (ffmpeg and x264 versions) is the one that ``environment.lock`` pins.

    Returns:
        Absolute path of the executable.

    Raises:
        RuntimeError: The installed ``imageio-ffmpeg`` ships no binary for this platform.
    """
    folder = importlib.resources.files("imageio_ffmpeg.binaries")
    found = [
        Path(str(f))
        for f in folder.iterdir()
        if f.name.startswith("ffmpeg") and not f.name.endswith((".py", ".md", ".txt"))
    ]
    if len(found) != 1 or not os.access(found[0], os.X_OK):
        raise RuntimeError(
            f"expected one ffmpeg binary in the imageio-ffmpeg wheel, found {[f.name for f in found]} "
            f"in {folder}; reinstall the pinned environment with `make setup` (imageio-ffmpeg "
            "must be the platform wheel, which bundles ffmpeg)"
        )
    return str(found[0])
