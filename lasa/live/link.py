"""The robot a live station steps against: a *robot link* reads the measured joint positions and takes the
next 0.1 s's command. :class:`SimLink` is MuJoCo's transition s' = s + Delta a (the safe step's state, as
sims and replays integrate it); :class:`lasa.live.franka.FrankaLink` drives a Franka over libfranka."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from lasa.base.errors import LasaError


class LinkError(LasaError, RuntimeError):
    """The robot link failed (a lost connection, a libfranka reflex or error): the arm is stopped, the session
    ends ``interrupted``, and nothing recovers by itself."""


class RobotLink(Protocol):
    """What a station needs of a robot: a link of your own needs these members.

    Attributes:
        name: ``"sim"`` or the robot's kind and address, recorded in the session's sidecar.
        physical: Whether a real (or simulated-over-the-network) arm moves: the session then runs the
            watchdog (:class:`lasa.live.session.Watchdog`) and logs the command columns."""

    name: str
    physical: bool

    def read(self) -> np.ndarray:
        """The measured joint positions s, (n,) [rad]; LinkError if the robot cannot be read."""

    def command(self, state: np.ndarray, target: np.ndarray, dt: float) -> dict[str, Any]:
        """Move from the measured ``state`` towards ``target`` (the safe step's s') over ``dt``; returns what
        the log records of the command (:meth:`columns`)."""

    def columns(self) -> list[str]:
        """The log columns :meth:`command` and :meth:`hold` fill (none for MuJoCo's transition)."""

    def hold(self) -> dict[str, Any]:
        """Stop now, zero velocity (never raises); returns the log's record of it, as :meth:`command`."""

    def reset(self, start: np.ndarray) -> None:
        """A new session from ``start``: MuJoCo's transition starts there, a real arm is where it is."""

    def close(self) -> None:
        """Stop and release the robot."""


class SimLink:
    """MuJoCo's transition: the measured state is the last target, exactly (s' = s + Delta a, safe)."""

    name = "sim"
    physical = False

    def __init__(self, start: np.ndarray) -> None:
        self.state = np.array(start, dtype=float)

    def read(self) -> np.ndarray:
        """The state the last command reached."""
        return self.state

    def command(self, state: np.ndarray, target: np.ndarray, dt: float) -> dict[str, Any]:
        """Reach ``target`` in one step."""
        self.state = np.array(target, dtype=float)
        return {}

    def columns(self) -> list[str]:
        """None: the state columns are the command."""
        return []

    def hold(self) -> dict[str, Any]:
        """Nothing moves between steps."""
        return {}

    def reset(self, start: np.ndarray) -> None:
        """Start at ``start``."""
        self.state = np.array(start, dtype=float)

    def close(self) -> None:
        """Nothing to release."""
