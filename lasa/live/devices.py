r"""Input devices for live teleoperation: a gamepad, the keyboard, or a script, each polled for one
:class:`StickSample` per step (two axes, a mode press, stop held), made safe once (:func:`safe_axes`)."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import threading
from collections.abc import Sequence
from typing import Protocol

import numpy as np
import pandas as pd

from lasa.base.errors import ConfigError

NOTCH = 0.25  # keyboard: one arrow press moves an axis by this much [-]
DEADZONE = 0.05  # gamepad: |axis| below this reads as zero (stick drift) [-]


@dataclasses.dataclass(frozen=True)
class StickSample:
    """One control step's input."""

    raw: np.ndarray  # the axes as read, (2,) (NaN if absent)
    mode: bool = False  # the mode button pressed since the last poll
    stop: bool = False  # the stop input held
    connected: bool = True  # the device answered

    @property
    def z(self) -> np.ndarray:
        """The joystick input the controller may use: :func:`safe_axes` of ``raw``."""
        return safe_axes(self.raw, self.connected)


def safe_axes(raw: np.ndarray, connected: bool = True) -> np.ndarray:
    """z, (2,): ``raw`` made safe: zero if disconnected, non-finite axes zero, clipped to [-1, 1]."""
    axes = np.asarray(raw, dtype=float).reshape(-1)
    if axes.shape != (2,):
        raise ConfigError(f"a stick sample has 2 axes, got shape {np.shape(raw)}")
    if not connected:
        return np.zeros(2)
    return np.clip(np.where(np.isfinite(axes), axes, 0.0), -1.0, 1.0)


class Device(Protocol):
    """What the teleoperation loop reads from: a device of your own needs only these two methods."""

    def poll(self) -> StickSample:
        """This step's input."""

    def close(self) -> None:
        """Release the device (by default: nothing to release)."""
        return None


class ScriptedDevice(Device):
    """Samples from a script, one per step (``axes`` (T, 2), NaN reads zero; ``mode``, ``stop`` and
    ``connected`` (T,), default none, never, always), then rest (zero axes)."""

    def __init__(
        self,
        axes: np.ndarray,
        mode: Sequence[bool] | np.ndarray | None = None,
        stop: Sequence[bool] | np.ndarray | None = None,
        connected: Sequence[bool] | np.ndarray | None = None,
    ) -> None:
        self.axes = np.asarray(axes, dtype=float).reshape(-1, 2)
        n = len(self.axes)
        self.mode, self.stop, self.connected = (
            np.full(n, default) if flags is None else np.asarray(flags, bool)
            for flags, default in ((mode, False), (stop, False), (connected, True))
        )
        for name in ("mode", "stop", "connected"):
            if (shape := getattr(self, name).shape) != (n,):
                raise ConfigError(f"{name} must have one entry per step ({n}), got {shape}")
        self.step = 0

    @classmethod
    def from_table(cls, table: pd.DataFrame, mode: str = "mode") -> ScriptedDevice:
        """A script from a table of ``raw0``, ``raw1`` and optional ``stop``, ``connected`` and ``mode`` (or
        the column named by ``mode``: a session log's ``mode_press``), nonzero = true."""
        flags = {
            name: table[col].to_numpy() > 0 if col in table else None
            for name, col in (("mode", mode), ("stop", "stop"), ("connected", "connected"))
        }
        return cls(table[["raw0", "raw1"]].to_numpy(), **flags)

    @classmethod
    def from_file(cls, path: str) -> ScriptedDevice:
        """A script from a CSV file (columns as :meth:`from_table`); else a ConfigError in one line."""
        try:
            table = pd.read_csv(path)
        except FileNotFoundError:
            raise ConfigError(f"no script file {path} for --device scripted:<file.csv>") from None
        except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as exc:
            raise ConfigError(
                f"script {path} is not a CSV table: {str(exc).strip().splitlines()[-1]}"
            ) from None
        if not {"raw0", "raw1"} <= set(table.columns):
            raise ConfigError(f"script {path} needs columns raw0 and raw1, has {list(table.columns)}")
        return cls.from_table(table)

    def poll(self) -> StickSample:
        """The next scripted sample (zero axes after the script's end)."""
        i = self.step
        self.step += 1
        if i >= len(self.axes):
            return StickSample(raw=np.zeros(2))
        return StickSample(
            self.axes[i].copy(), *(bool(flags[i]) for flags in (self.mode, self.stop, self.connected))
        )

    @property
    def finished(self) -> bool:
        """Whether every scripted sample has been read."""
        return self.step >= len(self.axes)


# GLFW key codes, as MuJoCo's viewer reports them to its key callback: the arrows' axis and direction
_ARROWS = {262: (0, 1.0), 263: (0, -1.0), 264: (1, -1.0), 265: (1, 1.0)}
_KEY_SPACE, _KEY_M, _KEY_S = 32, 77, 83


class KeyboardDevice(Device):
    """The keyboard, press-to-set through :meth:`key_callback` (MuJoCo's viewer reports presses, never
    releases): an arrow moves its axis a notch and it stays there; space recentres, ``M`` mode, ``S`` stop."""

    def __init__(self) -> None:
        self._axes = np.zeros(2)
        self._mode = False
        self._stop = False
        self._lock = threading.Lock()

    def key_callback(self, key: int) -> None:
        """Update the held axes, the mode press or the stop toggle from one key press."""
        with self._lock:
            if key in _ARROWS:
                axis, sign = _ARROWS[key]
                self._axes[axis] = min(1.0, max(-1.0, self._axes[axis] + sign * NOTCH))
            elif key == _KEY_SPACE:
                self._axes[:] = 0.0
            elif key == _KEY_M:
                self._mode = True
            elif key == _KEY_S:
                self._stop = not self._stop

    def poll(self) -> StickSample:
        """The axes in force, and the mode press since the last poll."""
        with self._lock:
            sample = StickSample(raw=self._axes.copy(), mode=self._mode, stop=self._stop)
            self._mode = False
        return sample


class GamepadDevice(Device):
    """A gamepad through pygame's SDL joystick API: axes 0 and 1 (y flipped: forward is +z2), button 0
    mode, button 1 stop; one gone away reads disconnected. ConfigError if none is connected."""

    def __init__(self) -> None:
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        # SDL's event queue (which the joystick needs) comes with its video subsystem; the
        # dummy driver gives it without opening a window (MuJoCo's viewer is the window)
        os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        # SDL would turn SIGINT and SIGTERM into a quit event nobody reads: the session's own
        # handlers stop it instead (lasa.live.session.StopOnSignals)
        os.environ["SDL_NO_SIGNAL_HANDLERS"] = "1"
        import pygame

        self._pg = pygame
        try:
            pygame.display.init()
            pygame.joystick.init()
            pygame.event.pump()
        except pygame.error as exc:
            raise ConfigError(f"SDL could not start its joystick subsystem: {exc}") from exc
        if pygame.joystick.get_count() == 0:
            raise ConfigError("no gamepad at index 0 (0 connected)")
        self._stick = pygame.joystick.Joystick(0)
        self._was_pressed = False

    def poll(self) -> StickSample:
        """Read the stick; a gamepad that went away reads as disconnected (zero input)."""
        pg = self._pg
        with contextlib.suppress(pg.error):
            pg.event.pump()
            if self._stick.get_init() and pg.joystick.get_count() > 0:
                raw = np.array([self._stick.get_axis(0), -self._stick.get_axis(1)], dtype=float)
                pressed = bool(self._stick.get_button(0))
                mode = pressed and not self._was_pressed  # one press, however long held
                self._was_pressed = pressed
                stop = bool(self._stick.get_button(1))
                return StickSample(raw=np.where(np.abs(raw) < DEADZONE, 0.0, raw), mode=mode, stop=stop)
        return StickSample(raw=np.full(2, np.nan), connected=False)

    def close(self) -> None:
        """Release SDL's joystick subsystem."""
        self._pg.joystick.quit()


def open_device(kind: str = "auto") -> tuple[Device, str]:
    """The device ``gamepad``, ``keyboard``, ``auto`` (a gamepad if connected) or ``scripted:<file.csv>``,
    and a sentence naming it."""
    if kind.startswith("scripted:"):
        return ScriptedDevice.from_file(kind.split(":", 1)[1]), "input: scripted"
    if kind not in ("auto", "gamepad", "keyboard"):
        raise ConfigError(f"unknown device {kind!r}; choose 'auto', 'gamepad' or 'keyboard'")
    if kind in ("auto", "gamepad"):
        try:
            return GamepadDevice(), "input: gamepad (stick = z, button 0 = mode, button 1 = stop)"
        except (ConfigError, ImportError) as exc:
            if kind == "gamepad":
                raise ConfigError(f"no gamepad: {exc}") from exc
    return KeyboardDevice(), (
        "input: keyboard, no gamepad found (arrows set z by quarter steps and hold it, space recentres, "
        "M = mode, S = stop)"
    )
