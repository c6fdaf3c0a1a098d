"""The server's control loop: one :meth:`lasa.live.station.Station.step` per tick, 10 Hz per participant.

The robot's step runs here and only here (the page draws and reads input). :func:`tick` is the
loop's one step: it reads the page's latest input, runs the station's step, logs the row
exactly as ``teleop run`` does (:class:`lasa.evidence.sessionlog.SessionWriter`: the CSV rows,
the sidecar, the scene XML) and returns the state message for the page. :func:`run_trial`
calls it once per Delta of wall-clock time, counts the ticks that overran their deadline (the
page shows the count, the sidecar records it), and closes the log ``complete`` when the task
is done, the time is up or the participant ends a practice, ``interrupted`` when the page goes.

**Every participant's step runs in one worker thread, in turn** (:data:`STEPPER`). A step is a
few milliseconds of small NumPy and torch calls that hold Python's GIL; run in several threads
at once, they hand the GIL back and forth and each takes several times as long (the load test,
``benchmarks/web_load.py``, measured it). One thread runs them back to back instead, and the
event loop's thread keeps the WebSockets moving meanwhile.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import dataclasses
import datetime as dt_
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import numpy as np

from lasa.evidence.sessionlog import SessionWriter
from lasa.live.devices import StickSample
from lasa.live.station import SessionConfig, Station, log_row
from lasa.live.web.protocol import Inputs

__all__ = ["STEPPER", "Trial", "open_trial", "tick", "run_trial"]

STEPPER = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="lasa-step")
"""The one thread that runs every participant's :func:`tick`, one after another."""


@dataclasses.dataclass
class Trial:
    """One logged session in progress.

    Attributes:
        station: The robot side (:class:`lasa.live.station.Station`).
        writer: The session's log.
        max_steps: The longest session, in ticks.
        started: Wall-clock start of the first tick [s, ``time.perf_counter``].
        steps: Ticks run; misses: ticks that overran their deadline; compute: each tick's time [s].
    """

    station: Station
    writer: SessionWriter
    max_steps: int
    started: float = 0.0
    steps: int = 0
    misses: int = 0
    compute: list[float] = dataclasses.field(default_factory=list)


def open_trial(config: SessionConfig, folder: Path, attempt: int, duration_s: float, order: int = 0) -> Trial:
    """Build the station, warm it up and open its log ``<participant>_<task>_<condition>_<time>_a<n>``.

    The attempt number makes every session's name new: a participant who comes back after a
    disconnect starts a new session and never overwrites one. ``order`` is the condition's
    position in the participant's schedule (0 first), kept in the sidecar for the analysis.
    """
    station = Station(config)
    station.warm_up()
    stamp = dt_.datetime.now(dt_.UTC).strftime("%Y%m%dT%H%M%S")
    stem = f"{config.participant}_{config.task}_{config.condition}_{stamp}_a{attempt}"
    meta = {**station.meta(), "interface": "web", "attempt": attempt, "order": int(order)}
    writer = SessionWriter(folder, stem, meta, station.robot.xml(), station.columns())
    return Trial(station, writer, max(1, int(round(duration_s / station.control.dt))))


def tick(trial: Trial, sample: StickSample) -> dict[str, Any]:
    """The loop's one step: the station's step on ``sample``, its log row, and the page's state message."""
    station = trial.station
    k = trial.steps
    deadline = trial.started + (k + 1) * station.control.dt
    t0 = time.perf_counter()
    rec = station.step(sample)
    now = time.perf_counter()
    late = now > deadline
    trial.compute.append(now - t0)
    trial.misses += int(late)
    trial.writer.append(log_row(k, now - trial.started, late, rec))
    trial.steps = k + 1
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


def _close(trial: Trial, status: str) -> None:
    compute = trial.compute or [0.0]
    trial.writer.close(
        status,
        steps=trial.steps,
        step_time_median_s=float(np.median(compute)),
        step_time_p99_s=float(np.percentile(compute, 99)),
        deadline_misses=trial.misses,
        done=trial.station.done,
    )


async def run_trial(
    trial: Trial,
    inputs: Inputs,
    send: Callable[[dict[str, Any]], Awaitable[None]],
    connected: Callable[[], bool],
    finish: Callable[[], bool],
) -> str:
    """Tick at the station's rate until done, out of time, ``finish()`` or the page goes; returns the status.

    Each step runs in :data:`STEPPER`'s thread, so a step never holds up the page's messages.
    Whatever ends the loop, the log is closed: ``interrupted`` if the page went away (or anything
    raised, the server's shutdown included), its rows kept; else ``complete``. A step under way
    when the loop is cancelled finishes and logs its row first, so the log never closes under it.
    """
    dt = trial.station.control.dt
    status = "complete"
    trial.started = time.perf_counter()
    step: concurrent.futures.Future[dict[str, Any]] | None = None
    try:
        while trial.steps < trial.max_steps:
            if not connected():
                status = "interrupted"
                break
            step = STEPPER.submit(tick, trial, inputs.take())
            message = await asyncio.wrap_future(step)
            await send(message)
            if trial.station.done or finish():
                break
            pause = trial.started + trial.steps * dt - time.perf_counter()
            if pause > 0:
                await asyncio.sleep(pause)
    except BaseException:
        if step is not None:
            concurrent.futures.wait([step])  # a few ms: the step's row goes in before the log closes
        _close(trial, "interrupted")
        raise
    _close(trial, status)
    return status
