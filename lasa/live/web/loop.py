"""The web study's loop: one :meth:`lasa.live.station.Station.step` per tick, 10 Hz per participant.

:func:`run_trial` drives :class:`lasa.live.session.Session` (deadlines, misses, the log closed on
any exit) from the page's latest input. Every participant's step runs in one worker thread, in
turn (:data:`STEPPER`): steps of small NumPy and torch calls in several threads fight over the
GIL and each takes several times as long (``benchmarks/web_load.py``).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from lasa.live.devices import StickSample
from lasa.live.session import Session, open_log
from lasa.live.station import SessionConfig, Station
from lasa.live.web.protocol import Inputs

__all__ = ["STEPPER", "open_trial", "tick", "run_trial"]

STEPPER = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="lasa-step")
"""The one thread that runs every participant's :func:`tick`, one after another."""


def open_trial(
    config: SessionConfig, folder: Path, attempt: int, duration_s: float, order: int = 0
) -> Session:
    """A warmed-up station and its new log ``<participant>_<task>_<condition>_<time>_a<attempt>``.

    The attempt makes every session's name new (a participant back after a disconnect never
    overwrites one); ``order`` is the condition's position in the participant's schedule.
    """
    station = Station(config)
    station.warm_up()
    writer = open_log(
        station, folder, suffix=f"_a{attempt}", interface="web", attempt=attempt, order=int(order)
    )
    return Session(station, writer, max(1, int(round(duration_s / station.control.dt))))


def tick(trial: Session, sample: StickSample) -> dict[str, Any]:
    """The loop's one step on ``sample``, logged, and the page's state message."""
    rec = trial.step(sample)
    assert rec is not None
    station = trial.station
    return {
        "type": "tick",
        "step": trial.steps,
        "q": [float(v) for v in rec["s"]],
        "belief": [float(v) for v in rec["b"]],
        "goals": list(station.task.goal_names),
        "instruction": station.phase_text(),
        "late": trial.misses,
        "stop": bool(rec["stop"]),
        "connected": bool(rec["connected"]),
        "done": station.done,
        "remaining_s": (trial.max_steps - trial.steps) * station.control.dt,
    }


async def run_trial(
    trial: Session,
    inputs: Inputs,
    send: Callable[[dict[str, Any]], Awaitable[None]],
    connected: Callable[[], bool],
    finish: Callable[[], bool],
) -> str:
    """Tick until done, out of time, ``finish()`` or the page goes; returns the status the log closed with.

    ``interrupted`` if the page went away or anything raised (the server's shutdown included),
    else ``complete``. A step under way when the loop is cancelled logs its row first.
    """
    status = "complete"
    step: concurrent.futures.Future[dict[str, Any]] | None = None
    with trial.guard():
        try:
            while trial.steps < trial.max_steps:
                if not connected():
                    status = "interrupted"
                    break
                step = STEPPER.submit(tick, trial, inputs.take())
                await send(await asyncio.wrap_future(step))
                if trial.station.done or finish():
                    break
                pause = trial.pause()
                if pause > 0:
                    await asyncio.sleep(pause)
        except BaseException:
            if step is not None:
                concurrent.futures.wait([step])  # a few ms: the step's row goes in before the log closes
            raise
    trial.close(status)
    return status
