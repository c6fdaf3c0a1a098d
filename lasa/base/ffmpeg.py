"""The one ffmpeg lasa's videos use: the pinned ``imageio-ffmpeg`` wheel's, for mediapy too.

mediapy runs whatever ``ffmpeg`` it is told to (``mediapy.set_ffmpeg``), else the one on the
PATH, which may be missing or another version. ``import lasa`` points mediapy at the binary
inside the pinned ``imageio-ffmpeg`` wheel (``environment.lock``): at once if mediapy is
already imported, otherwise the moment it is (:func:`pin_mediapy`, an import hook: ``import
lasa`` itself stays light, without mediapy's matplotlib). The pinned pair, mediapy 1.2.7 and
imageio-ffmpeg 0.7.0 (ffmpeg 7.0.2), works together: mediapy's reader passes ``-vsync``,
which ffmpeg 9 (imageio-ffmpeg 0.8) no longer has.
"""

from __future__ import annotations

import functools
import importlib.abc
import importlib.machinery
import importlib.resources
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType

__all__ = ["pinned_ffmpeg", "pin_mediapy"]


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


def _configure(mediapy: ModuleType) -> None:
    try:
        mediapy.set_ffmpeg(pinned_ffmpeg())
    except RuntimeError:  # no pinned wheel here: leave mediapy's own choice, write_video says why
        pass


class _MediapyHook(importlib.abc.MetaPathFinder):
    """Configures mediapy right after it is first imported, then steps aside."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname != "mediapy":
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        loader = None if spec is None else spec.loader
        if loader is None or not hasattr(loader, "exec_module"):
            return spec
        run = loader.exec_module

        def exec_module(module: ModuleType) -> None:
            run(module)
            _configure(module)

        loader.exec_module = exec_module  # type: ignore[method-assign]
        return spec


def pin_mediapy() -> None:
    """Point mediapy at :func:`pinned_ffmpeg`, now or when it is first imported."""
    if "mediapy" in sys.modules:
        _configure(sys.modules["mediapy"])
    elif not any(isinstance(f, _MediapyHook) for f in sys.meta_path):
        sys.meta_path.insert(0, _MediapyHook())
