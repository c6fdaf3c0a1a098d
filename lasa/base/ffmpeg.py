"""The one ffmpeg lasa's videos use (:mod:`lasa.evidence.video` points mediapy at it): the pinned
``imageio-ffmpeg`` 0.7.0 wheel's (ffmpeg 7.0.2; mediapy 1.2.7 passes ``-vsync``, gone from ffmpeg 9)."""

from __future__ import annotations

import functools
import importlib.resources
import os
from pathlib import Path


@functools.cache
def pinned_ffmpeg() -> str:
    """The path of the ffmpeg inside the installed ``imageio-ffmpeg`` wheel, never another (the PATH's)."""
    folder = importlib.resources.files("imageio_ffmpeg.binaries")
    found = [Path(str(f)) for f in folder.iterdir() if f.name.startswith("ffmpeg")]
    found = [f for f in found if not f.name.endswith((".py", ".md", ".txt"))]
    if len(found) != 1 or not os.access(found[0], os.X_OK):
        raise RuntimeError(
            f"expected one ffmpeg binary in the imageio-ffmpeg wheel, found {[f.name for f in found]} "
            f"in {folder}; reinstall the pinned environment with `make setup` (imageio-ffmpeg "
            "must be the platform wheel, which bundles ffmpeg)"
        )
    return str(found[0])
