"""Stopping a live session cleanly when the process is told to stop (SIGINT, SIGTERM, SIGHUP).

A session that is killed must read ``interrupted``, never ``complete``, and keep the rows it
logged. Python turns SIGINT into ``KeyboardInterrupt`` but leaves SIGTERM and SIGHUP to
their default (the process dies where it stands, its sidecar at ``running``); and SDL, once
pygame starts it for a gamepad, installs handlers of its own that turn SIGINT and SIGTERM
into a quit event that nobody reads, so the signal is swallowed and the session runs on.

:class:`StopOnSignals` installs the session's own handlers for the time of the control loop
(after the device is opened, so they replace SDL's): a signal only records that a stop was
asked for; the loop sees it at its next step, ends, and the log is closed ``interrupted``.
A second signal while the first is pending raises ``KeyboardInterrupt`` (the loop's error
path closes the log ``interrupted`` too), for a step that would not end.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType, TracebackType
from typing import Any

__all__ = ["SIGNALS", "StopOnSignals"]

SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")  # the ways a terminal or a supervisor stops a process


class StopOnSignals:
    """A context in which SIGINT, SIGTERM and SIGHUP ask the control loop to stop.

    Outside the main thread (where Python allows no signal handler) it installs nothing.
    On exit the handlers in force before are restored (the default one where the previous
    handler was not Python's, such as SDL's).

    Attributes:
        received: The name of the first signal received (``"SIGTERM"``), or None.
    """

    def __init__(self) -> None:
        self.received: str | None = None
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> StopOnSignals:
        if threading.current_thread() is not threading.main_thread():
            return self
        for name in SIGNALS:
            number = getattr(signal, name, None)  # no SIGHUP on Windows
            if number is not None:
                self._previous[number] = signal.signal(number, self._handle)
        return self

    def _handle(self, number: int, frame: FrameType | None) -> None:
        if self.received is not None:
            raise KeyboardInterrupt(f"{signal.Signals(number).name} while stopping")
        self.received = signal.Signals(number).name

    def __exit__(
        self, kind: type[BaseException] | None, value: BaseException | None, tb: TracebackType | None
    ) -> None:
        for number, previous in self._previous.items():
            signal.signal(number, signal.SIG_DFL if previous is None else previous)
        self._previous.clear()
