"""A Franka (Panda or FR3) as a station's robot link, over ``franky-control`` (libfranka): each tick reads
the measured joints and sends the guarded joint velocity for the next tick (:mod:`lasa.live.guard`).

The same code drives a real arm at its FCI address and ``franky-sim`` (libfranka's protocol, MuJoCo inside)
on a loopback address. ``dry_run`` (shadow mode) reads and computes everything and sends nothing. A
libfranka error stops the arm and raises :class:`lasa.live.link.LinkError`; recovery is an explicit call
(:func:`recover`, ``python -m lasa.live.teleop recover``), never automatic."""

from __future__ import annotations

import contextlib
import ipaddress
import os
import re
import shutil
import subprocess
import sys
import threading
import time
import types
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from lasa.base.errors import ConfigError
from lasa.live.guard import Guard
from lasa.live.link import LinkError
from lasa.live.station import SessionConfig, Station
from lasa.world.eating import make_eating_task

START_TOLERANCE = 0.05  # [rad] each joint this close to the task's start pose, or the session refuses
HOME_SPEED = 0.1  # franky's relative dynamics factor of the confirmed move to the start pose


def realtime_default(address: str) -> str:
    """``"ignore"`` for a loopback address (franky-sim, no real-time kernel needed), else ``"enforce"``."""
    try:
        return "ignore" if ipaddress.ip_address(address).is_loopback else "enforce"
    except ValueError:
        return "enforce"  # a host name: a real robot's


def connect(address: str, realtime: str | None = None, timeout: float = 30.0) -> Any:
    """A ``franky.Robot`` at ``address``; ``realtime`` ``enforce`` (a real-time kernel, as on a real arm) or
    ``ignore`` (default by :func:`realtime_default`). LinkError if it cannot connect, or no answer comes
    within ``timeout`` seconds (the robot serves one client at a time)."""
    import franky

    realtime = realtime or realtime_default(address)
    if realtime not in ("enforce", "ignore"):
        raise ConfigError(f"realtime must be 'enforce' or 'ignore', got {realtime!r}")
    config = franky.RealtimeConfig.Enforce if realtime == "enforce" else franky.RealtimeConfig.Ignore
    result: list[Any] = []

    def attempt() -> None:
        try:
            result.append(franky.Robot(address, realtime_config=config))
        except (franky.Exception, RuntimeError) as exc:
            result.append(exc)

    worker = threading.Thread(target=attempt, daemon=True)
    worker.start()
    worker.join(timeout)
    if not result:
        raise LinkError(
            f"the Franka at {address} did not answer within {timeout:g} s: is another program connected?"
        )
    if isinstance(result[0], Exception):
        exc = result[0]
        hint = " (no real-time kernel: pass --realtime ignore)" if "realtime" in str(exc).lower() else ""
        raise LinkError(f"cannot connect to the Franka at {address}: {exc}{hint}") from exc
    return result[0]


def joints(robot: Any) -> np.ndarray:
    """A franky robot's measured joint positions, (7,) [rad]; LinkError if it cannot be read or reports
    something that is not 7 finite numbers."""
    import franky

    try:
        q = np.array(robot.current_joint_state.position, dtype=float)
    except (franky.Exception, RuntimeError) as exc:  # libfranka's network errors: RuntimeError
        raise LinkError(f"reading the Franka's state failed: {exc}") from exc
    if q.shape != (7,) or not np.all(np.isfinite(q)):
        raise LinkError(f"the Franka reported joint positions {q}")
    return q


class FrankaLink:
    """A Franka over franky; ``guard`` checks each command, ``dry_run`` sends none."""

    physical = True

    def __init__(self, robot: Any, guard: Guard, address: str, dry_run: bool = False) -> None:
        import franky

        self._franky = franky
        self.robot = robot
        self.guard = guard
        self.dry_run = dry_run
        self.name = f"franka {address}" + (" (dry run)" if dry_run else "")
        self.sent = 0

    def read(self) -> np.ndarray:
        """The measured joint positions, (7,) [rad] (:func:`joints`)."""
        return joints(self.robot)

    def columns(self) -> list[str]:
        """The guarded velocity sent ``v0``..``v6``, whether it was ``sent`` and the ``guard`` code."""
        return [f"v{i}" for i in range(7)] + ["sent", "guard"]

    def command(self, state: np.ndarray, target: np.ndarray, dt: float) -> dict[str, Any]:
        """Send the guarded velocity towards ``target`` for ``dt`` (franky holds it, then stops)."""
        v, code = self.guard.check(state, (np.asarray(target) - state) / dt)
        if not self.dry_run:
            motion = self._franky.JointVelocityMotion(
                v.tolist(), duration=self._franky.Duration(int(dt * 1000))
            )
            try:
                self.robot.move(motion, asynchronous=True)
            except (self._franky.Exception, RuntimeError) as exc:  # libfranka's network errors: RuntimeError
                self.hold()
                raise LinkError(f"the Franka refused a command: {exc}") from exc
            self.sent += 1
        return {"v": v, "sent": not self.dry_run, "guard": code}

    def hold(self) -> dict[str, Any]:
        """Stop the running motion (zero velocity); errors are swallowed: this is the way out."""
        self.guard.stopped()
        if not self.dry_run:
            try:
                self.robot.stop()
            except Exception:  # noqa: BLE001 - stopping must never raise; the arm's own reflexes hold it
                pass
        return {"v": np.zeros(7), "sent": not self.dry_run, "guard": 0}

    def reset(self, start: np.ndarray) -> None:
        """Nothing: a real arm starts where it is (:func:`check_start` says if that is the start pose)."""

    def close(self) -> None:
        """Stop the arm and wait for the motion to end."""
        self.hold()
        try:
            self.robot.join_motion(timeout=1.0)
        except Exception:  # noqa: BLE001 - a lost link has nothing to join
            pass


def recover(robot: Any) -> None:
    """Clear libfranka's error state: the operator's explicit command after checking the arm (a session never
    calls it)."""
    import franky

    try:
        robot.recover_from_errors()
    except franky.Exception as exc:
        raise LinkError(f"recovery failed: {exc}") from exc


def check_start(
    state: np.ndarray, start: np.ndarray, guard: Guard, tolerance: float = START_TOLERANCE
) -> None:
    """Refuse (ConfigError) a measured ``state`` outside the shared limits, or farther than ``tolerance``
    from the task's ``start`` in any joint; the message says how to move the arm there."""
    if not guard.within_limits(state):
        raise ConfigError(
            f"the arm is at {np.round(state, 3).tolist()}, outside the joint limits the Panda and the FR3 "
            f"share (with a {guard.margin} rad margin): move it inside by hand (guiding mode) first"
        )
    far = np.abs(state - start)
    if far.max() > tolerance:
        joint = int(far.argmax()) + 1
        raise ConfigError(
            f"the arm is {far.max():.3f} rad from the task's start pose at joint {joint} (allowed: "
            f"{tolerance}): move it there with `python -m lasa.live.teleop home --franka ADDRESS` "
            "(a joint motion you confirm)"
        )


def move_home(robot: Any, start: np.ndarray, guard: Guard, speed: float = HOME_SPEED) -> float:
    """Move the arm to ``start`` by a joint motion at ``speed`` (franky's relative dynamics factor), which the
    operator has confirmed; returns its seconds."""
    import franky

    if not guard.within_limits(np.asarray(start)):
        raise ConfigError("the start pose is outside the shared joint limits")
    t0 = time.perf_counter()
    try:
        target = franky.JointState(np.asarray(start, float).tolist())
        motion = franky.JointMotion(target, relative_dynamics_factor=speed)
        robot.move(motion)
        deadline = time.perf_counter() + 3.0  # the motion's end: the arm's own tracking still settles
        while np.abs(np.array(robot.current_joint_state.position) - start).max() > 0.01:
            if time.perf_counter() > deadline:
                break
            time.sleep(0.05)
    except franky.Exception as exc:
        raise LinkError(f"the move to the start pose failed: {exc}") from exc
    return time.perf_counter() - t0


class SimulatorAddress(str):
    """franky-sim's loopback address, with its server ``process`` (a test stops it to cut the link)."""

    process: subprocess.Popen[str]


@contextlib.contextmanager
def simulator(timeout: float = 60.0) -> Iterator[SimulatorAddress]:
    """Run ``franky-sim`` (libfranka's protocol, MuJoCo inside, headless) on a free loopback address for
    the ``with`` block; yields the address to connect to. Tests and benchmarks use it; so can you."""
    exe = shutil.which("franky-sim", path=str(Path(sys.executable).parent)) or shutil.which("franky-sim")
    if exe is None:
        raise ConfigError("franky-sim is not installed (make setup installs it from environment.lock)")
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "MUJOCO_GL": "disable"}
    proc = subprocess.Popen(
        [exe, "--simulator", "mujoco"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env
    )
    try:
        address = SimulatorAddress(_address(proc, time.monotonic() + timeout))
        address.process = proc
        assert proc.stdout is not None  # drained, so that the server never blocks on a full pipe
        threading.Thread(target=proc.stdout.read, daemon=True).start()
        yield address
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _address(proc: subprocess.Popen[str], deadline: float) -> str:
    """The loopback address franky-sim prints once it listens; LinkError if it exits or stays silent."""
    assert proc.stdout is not None
    seen = []
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        seen.append(line.strip())
        found = re.search(r"'(127(?:\.\d{1,3}){3})'", line)
        if found:
            return found.group(1)
    raise LinkError(f"franky-sim did not start: {' | '.join(seen[-5:]) or 'no output'}")


def franka_station(
    config: SessionConfig, address: str, *, dry_run: bool = False, realtime: str | None = None
) -> Station:
    """A station of an eating task on the Franka at ``address``, guarded, after the start check."""
    if config.task == "cups" or config.robot != "panda":
        raise ConfigError(
            "a Franka runs the eating tasks (Entree, Dessert) with the Panda model; the cups' scene has no "
            "table for the workspace guard"
        )
    task = make_eating_task()
    guard = Guard.around(task.robot, task.start)
    link = FrankaLink(connect(address, realtime), guard, address, dry_run=dry_run)
    check_start(link.read(), task.start, guard)
    return Station(config, link)


class LoggedArm:
    """A physical session's measured joints, read back in order (its first row twice: the station reads
    once at its start): a dry-run :class:`FrankaLink` on it recomputes every logged command."""

    def __init__(self, states: np.ndarray) -> None:
        self._states = np.concatenate([states[:1], states])
        self._next = 0

    @property
    def current_joint_state(self) -> Any:
        """The next logged state, as franky's ``JointState`` shows it (``.position``)."""
        row = self._states[min(self._next, len(self._states) - 1)]
        self._next += 1
        return types.SimpleNamespace(position=row)


def replay_link(states: np.ndarray) -> FrankaLink:
    """A dry-run link that reads a Franka session's logged ``states`` (T, 7) back, guarded as live."""
    task = make_eating_task()
    guard = Guard.around(task.robot, task.start)
    return FrankaLink(LoggedArm(states), guard, "a session log", dry_run=True)
