"""The live session loop that ``teleop run`` and the web study share: one logged step per Delta
(:class:`Session`), and :class:`StopOnSignals`, so that a killed session reads ``interrupted``."""

from __future__ import annotations

import contextlib
import dataclasses
import datetime as dt_
import signal
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np

from lasa.evidence.sessionlog import SessionWriter
from lasa.live.devices import StickSample
from lasa.live.station import Station


class StopOnSignals:
    """A context in which SIGINT, SIGTERM and SIGHUP ask the loop to stop (``received``: the first; Python
    leaves SIGTERM and SIGHUP to their default, SDL swallows SIGINT and SIGTERM). Outside the main thread it
    installs nothing; a second signal raises ``KeyboardInterrupt``; on exit the previous handlers (SIG_DFL
    where they were not Python's) are restored."""

    def __init__(self) -> None:
        self.received: str | None = None
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> StopOnSignals:
        if threading.current_thread() is threading.main_thread():
            # how a terminal or supervisor stops a process (Windows: no SIGHUP)
            for number in (getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n)):
                self._previous[number] = signal.signal(number, self._handle)
        return self

    def _handle(self, number: int, frame: FrameType | None) -> None:
        if self.received is not None:
            raise KeyboardInterrupt(f"{signal.Signals(number).name} while stopping")
        self.received = signal.Signals(number).name

    def __exit__(self, *exc: object) -> None:
        for number, previous in self._previous.items():
            signal.signal(number, signal.SIG_DFL if previous is None else previous)
        self._previous.clear()


class Watchdog:
    """Why a session on a physical link must stop now, or None: no connected input for ``no_input_s``
    (default 0.3 s), a late tick (its step ended past its deadline)."""

    def __init__(self, dt: float, no_input_s: float = 0.3) -> None:
        self.dt, self.no_input_s = dt, no_input_s
        self.silent = 0  # consecutive steps without a connected input

    def check(self, sample: StickSample, late: bool) -> str | None:
        """The reason to stop after a step on ``sample`` that was ``late`` or not."""
        self.silent = 0 if sample.connected else self.silent + 1
        if self.silent * self.dt >= self.no_input_s - 1e-9:
            return f"watchdog: no input for {self.silent * self.dt:.1f} s"
        if late:
            return "watchdog: a late tick"
        return None


def open_log(
    station: Station, folder: str | Path, stem: str | None = None, suffix: str = "", **meta: Any
) -> SessionWriter:
    """A new log of ``station`` in ``folder``: ``stem`` or ``<participant>_<task>_<condition>_<time>``
    and ``suffix``; its sidecar holds :meth:`lasa.live.station.Station.meta` and ``meta``."""
    c = station.config
    stamp = dt_.datetime.now(dt_.UTC).strftime("%Y%m%dT%H%M%S")
    stem = stem or f"{c.participant}_{c.task}_{c.condition}_{stamp}{suffix}"
    return SessionWriter(folder, stem, {**station.meta(), **meta}, station.robot.xml(), station.columns())


@dataclasses.dataclass
class Session:
    """A running session: its station, log (None: none), ``realtime`` (steps have deadlines and log wall-clock
    times, else ``step * dt``), ``started`` (``time.perf_counter``), ``steps`` logged, deadline ``misses`` and
    each step's ``compute`` time [s]. It closes the log with the timing, ``complete`` or ``interrupted``."""

    station: Station
    writer: SessionWriter | None
    max_steps: int
    realtime: bool = True
    started: float = 0.0
    steps: int = 0
    misses: int = 0
    late: bool = False  # whether the last step ended past its deadline
    compute: list[float] = dataclasses.field(default_factory=list)

    def step(self, sample: StickSample, show: Callable[[dict[str, Any]], bool] | None = None) -> dict | None:
        """The station's step on ``sample``, logged; None (nothing logged) if ``show(record)`` is False."""
        k, dt = self.steps, self.station.control.dt
        deadline = self.started + (k + 1) * dt
        t0 = time.perf_counter()
        rec = self.station.step(sample)
        if show is not None and not show(rec):
            return None
        now = time.perf_counter()
        late = self.realtime and now > deadline
        self.compute.append(now - t0)
        self.misses += int(late)
        self.late = late
        if self.writer is not None:  # the row in Station.columns' order: step, time, late, then the record
            row = [k, now - self.started if self.realtime else k * dt, float(late)]
            self.writer.append(row + [float(v) for value in rec.values() for v in np.ravel(value)])
        self.steps = k + 1
        return rec

    def pause(self) -> float:
        """Seconds until the next step's deadline (<= 0: due)."""
        return self.started + self.steps * self.station.control.dt - time.perf_counter()

    def timing(self) -> dict[str, Any]:
        """Steps, the step time's median and 99th percentile [s], deadline misses, whether done."""
        compute = self.compute or [0.0]
        return {
            "steps": self.steps,
            "step_time_median_s": float(np.median(compute)),
            "step_time_p99_s": float(np.percentile(compute, 99)),
            "deadline_misses": self.misses,
            "done": self.station.done,
        }

    def close(self, status: str, **extra: Any) -> None:
        """Close the log as ``status`` with the timing (and ``extra``)."""
        if self.writer is not None:
            self.writer.close(status, **self.timing(), **extra)

    @contextlib.contextmanager
    def guard(self) -> Iterator[Session]:
        """Start the clock; on any exception close the log ``interrupted`` (its rows kept) and re-raise."""
        self.started = time.perf_counter()
        try:
            yield self
        except BaseException:
            self.close("interrupted")
            raise
