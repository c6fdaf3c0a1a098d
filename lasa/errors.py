"""Exceptions raised by lasa.

Every error names what was wrong and, where it can, what to do about it: the allowed
range of a parameter, or the command that makes a missing artifact.
"""

from __future__ import annotations


class LasaError(Exception):
    """Base class of every error that lasa raises on purpose."""


class ConfigError(LasaError, ValueError):
    """A parameter is outside its allowed range, or a name is unknown."""


class ArtifactError(LasaError, FileNotFoundError):
    """A dataset, checkpoint or figure input is missing, corrupt or for another robot."""


class IKError(LasaError, RuntimeError):
    """Inverse kinematics did not reach a grasp pose within tolerance."""
