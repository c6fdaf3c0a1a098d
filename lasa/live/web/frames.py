"""The robot drawn on the server (``--frames server``): MuJoCo's off-screen renderer, small JPEG frames, best
effort: one worker renders the newest state, a request while it is busy is dropped, the loop never waits."""

from __future__ import annotations

import asyncio
import io
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np


class FrameRenderer:
    """JPEG frames (320 x 240 px, quality 70) of the eating scene at given joint positions, from one rendering
    thread."""

    def __init__(self) -> None:
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="frames")
        self._busy = False
        self._scene: Any = None  # (robot, renderer, data, camera), made on the rendering thread

    def _render(self, q: Sequence[float] | None) -> bytes:
        import mujoco
        from PIL import Image

        if self._scene is None:
            from lasa.world.eating import make_eating_task

            robot = make_eating_task().robot
            renderer = mujoco.Renderer(robot.model, 240, 320)
            camera = robot.model.camera(robot.spec.camera).id
            self._scene = (robot, renderer, mujoco.MjData(robot.model), camera)
        robot, renderer, data, camera = self._scene
        if q is not None:
            data.qpos[robot.qpos_adr] = np.asarray(q, dtype=float)
        mujoco.mj_forward(robot.model, data)
        renderer.update_scene(data, camera=camera)
        buffer = io.BytesIO()
        Image.fromarray(renderer.render()).save(buffer, "JPEG", quality=70)
        return buffer.getvalue()

    async def warm_up(self) -> None:
        """Build the scene and the GL context, and render once: at the server's start, not in a
        participant's first ticks (building them holds the interpreter for a few hundred ms)."""
        await asyncio.get_running_loop().run_in_executor(self._pool, self._render, None)

    async def frame(self, q: Sequence[float]) -> bytes | None:
        """A frame at joint positions ``q``, or None if the renderer is busy with another."""
        if self._busy:
            return None
        self._busy = True
        try:
            return await asyncio.get_running_loop().run_in_executor(self._pool, self._render, list(q))
        finally:
            self._busy = False

    def _free(self) -> None:
        if self._scene is not None:
            self._scene[1].close()  # on the thread that made its GL context
            self._scene = None

    def close(self) -> None:
        """Free the renderer and stop the rendering thread."""
        self._pool.submit(self._free)
        self._pool.shutdown(wait=True, cancel_futures=False)
