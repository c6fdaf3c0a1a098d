"""Recording kinesthetic demonstrations: a person guides the arm (a real Franka in its guiding mode) while the
recorder reads its joints every Delta, for a duration or until stopped (Ctrl-C, SIGTERM, SIGHUP: a clean stop
that keeps what was recorded); then the recording is cut into reaches and strokes and saved as the dataset D
(:mod:`lasa.method.kinesthetic`), the raw joint stream beside it. Every write is atomic."""

from __future__ import annotations

import dataclasses
import signal
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import pandas as pd

from lasa.base.config import check_range
from lasa.base.errors import ConfigError
from lasa.base.io import save_npz
from lasa.live.franka import connect, joints
from lasa.live.link import LinkError
from lasa.live.session import StopOnSignals
from lasa.method.dataset import PHASE_NAMES, save_demonstrations
from lasa.method.kinesthetic import Segmentation, SegmentConfig, recorded_demonstrations
from lasa.world.eating import GOALS, make_eating_task


class Reader(Protocol):
    """What the recorder needs of a robot link: :meth:`lasa.live.link.RobotLink.read`."""

    def read(self) -> np.ndarray:
        """The measured joint positions, (n,) [rad]."""


@dataclasses.dataclass(frozen=True)
class Recording:
    """A recorded joint stream: ``states`` (T, n) [rad] read at ``times`` (T,) [s from the first], every
    ``dt`` [s]; ``stopped`` says why it ended (``duration``, ``stopped``, or a signal's name)."""

    states: np.ndarray
    times: np.ndarray
    dt: float
    stopped: str


class JointReader:
    """A franky robot's measured joints as a :class:`Reader` (a real Franka switched to guiding mode)."""

    def __init__(self, robot: Any) -> None:
        self.robot = robot

    def read(self) -> np.ndarray:
        """The measured joint positions, (7,) [rad] (:func:`lasa.live.franka.joints`)."""
        return joints(self.robot)


def record(
    link: Reader,
    dt: float,
    duration: float | None = None,
    stop: Callable[[], bool] | None = None,
    on_sample: Callable[[int, np.ndarray], None] | None = None,
) -> Recording:
    """Read ``link`` every ``dt`` [s] on a fixed schedule for ``duration`` [s] (None: until stopped), until
    ``stop()`` is true, or until a signal (SIGINT, SIGTERM, SIGHUP) arrives; ``on_sample(k, s)`` after
    each read. A LinkError ends the recording too (``stopped`` says so): what was read is kept."""
    check_range("dt", dt, 0.0, low_open=True)
    limit = None if duration is None else int(round(check_range("duration", duration, 0.0) / dt)) + 1
    states: list[np.ndarray] = []
    times: list[float] = []
    why = "duration"
    t0 = time.perf_counter()
    with StopOnSignals() as signals:
        while limit is None or len(states) < limit:
            if signals.received is not None or (stop is not None and stop()):
                why = signals.received or "stopped"
                break
            try:
                states.append(np.asarray(link.read(), dtype=float))
            except LinkError as exc:
                why = f"link: {exc}"
                break
            times.append(time.perf_counter() - t0)
            if on_sample is not None:
                on_sample(len(states) - 1, states[-1])
            time.sleep(max(0.0, t0 + len(states) * dt - time.perf_counter()))
    n = len(states[0]) if states else 7
    return Recording(np.reshape(states, (-1, n)), np.asarray(times), dt, why)


def save_recording(recording: Recording, path: str | Path) -> Path:
    """Save a recording's raw joint stream (``states``, ``times``, ``dt``, ``stopped``) atomically."""
    fields = {f.name: np.asarray(getattr(recording, f.name)) for f in dataclasses.fields(recording)}
    return save_npz(path, **fields)


def summary(segmentation: Segmentation, dt: float, goals: tuple[str, ...] = GOALS) -> pd.DataFrame:
    """Per goal and phase: the demonstrations and samples kept, and their seconds (``dt`` each)."""
    keep = segmentation.keep
    frame = pd.DataFrame(
        {
            "goal": np.asarray(goals)[segmentation.goal[keep]],
            "phase": np.asarray(PHASE_NAMES)[segmentation.phase[keep]],
            "demo": segmentation.demo[keep],
        }
    )
    table = frame.groupby(["goal", "phase"]).agg(demos=("demo", "nunique"), samples=("demo", "size"))
    return table.assign(seconds=table.samples * dt)


def save_demonstrations_of(
    recording: Recording, out: str | Path, config: SegmentConfig = SegmentConfig()
) -> tuple[Path, Segmentation]:
    """Cut ``recording`` (the eating task's Panda, the study's belief) and save the dataset to ``out`` and
    the raw stream beside it (``<out>.raw.npz``, saved first); ConfigError if nothing was kept."""
    out = Path(out)
    save_recording(recording, out.with_suffix(".raw.npz"))
    task = make_eating_task()
    control = task.robot.control
    if abs(recording.dt - control.dt) > 1e-9:
        raise ConfigError(f"the recording's dt {recording.dt} s is not the control's {control.dt} s")
    if len(recording.states) < 2:
        raise ConfigError(f"{len(recording.states)} samples recorded: nothing to cut (raw stream kept)")
    demos, seg = recorded_demonstrations(task, control, recording.states, config)
    if not seg.keep.any():
        raise ConfigError(
            "no demonstration in the recording: the fork never moved to a bowl or the plate "
            f"(within {config.radius} m of a stroke); the raw stream is at {out.with_suffix('.raw.npz')}"
        )
    return save_demonstrations(demos, out), seg


def guide(robot: Any) -> None:
    """Switch a franky robot to guiding mode (all six Cartesian directions, the elbow free); franky-sim
    may ignore it. LinkError if the arm refuses."""
    try:
        robot.set_guiding_mode([True] * 6, True)
    except Exception as exc:  # franky.Exception
        raise LinkError(f"the Franka refused guiding mode: {exc}") from exc


def run_demos(address: str, out: str, duration: float | None, realtime: str | None) -> int:
    """``demos``: connect, switch on guiding mode, record with progress every second, cut, save, print a
    summary; 128 + the signal's number if a signal stopped the recording (what was recorded is saved)."""
    if not out.endswith(".npz"):
        raise ConfigError(f"--out must name a .npz file, got {out!r}")
    robot = connect(address, realtime)
    guide(robot)
    dt = make_eating_task().robot.control.dt
    print(f"recording every {dt} s: guide the arm; Ctrl-C stops and saves", flush=True)
    every = int(round(1.0 / dt))

    def progress(k: int, s: np.ndarray) -> None:
        if k % every == 0:
            print(f"  {k * dt:6.1f} s  joints {np.round(s, 2).tolist()}", flush=True)

    recording = record(JointReader(robot), dt, duration, on_sample=progress)
    print(f"stopped ({recording.stopped}) after {len(recording.states)} samples", flush=True)
    path, seg = save_demonstrations_of(recording, out)
    table = summary(seg, dt)
    kept = int(seg.keep.sum())
    print(table.to_string())
    print(
        f"{path}: {int(seg.demo.max()) + 1} demonstrations, {kept} samples = {kept * dt:.1f} s kept, "
        f"{len(recording.states) - kept} dropped (at rest, arriving nowhere, or the last)"
    )
    stopped_by = getattr(signal, recording.stopped, None) if recording.stopped.startswith("SIG") else None
    return 0 if stopped_by is None else 128 + int(stopped_by)
