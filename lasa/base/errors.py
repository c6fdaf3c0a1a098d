"""Exceptions raised by lasa: each names what was wrong and, where it can, what to do about it."""

from __future__ import annotations


class LasaError(Exception):
    """Base class of every error that lasa raises on purpose."""


class ConfigError(LasaError, ValueError):
    """A parameter is outside its allowed range, or a name is unknown."""


class EmptySelectionError(ConfigError):
    """A setting left a selection empty; the message names the setting and what to change."""


class ArtifactError(LasaError, FileNotFoundError):
    """A dataset, checkpoint or figure input is missing, corrupt or for another robot."""


class CheckpointError(ArtifactError):
    """A checkpoint that does not load, or holds another decoder, robot, number of goals or task."""


class DamagedLogError(ArtifactError):
    """A session log or its sidecar that does not parse, or disagrees with itself or its scene."""


class IKError(LasaError, RuntimeError):
    """Inverse kinematics did not reach a grasp pose within tolerance."""


class NotebookError(LasaError, RuntimeError):
    """A notebook stopped on ``ename: evalue``: its cause, the ``partial`` run, what was ``restored``."""

    def __init__(self, notebook: str, ename: str, evalue: str, partial: str, restored: str = "") -> None:
        self.ename, self.evalue, self.partial, self.restored = ename, evalue, partial, restored
        cause = evalue.strip().splitlines()[-1] if evalue.strip() else "(no message)"
        then = f"; {restored}" if restored else ""
        super().__init__(f"{notebook} failed: {ename}: {cause} (the partial run is in {partial}){then}")
