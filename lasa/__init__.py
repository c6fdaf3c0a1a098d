"""lasa: Shared Autonomy with Learned Latent Actions (Jeon, Losey & Sadigh, RSS 2020).

A reproducibility package: MuJoCo robots and the cup task, demonstrations, the
conditional-autoencoder decoder phi(z, s, b), shared autonomy (Algorithm 1),
Boltzmann-rational simulated users, and one module per figure (:mod:`lasa.sims`).

Rendering is software-only by default: ``MUJOCO_GL`` is set to ``osmesa`` here,
before anything imports mujoco (it is read once, at import). Set it yourself first
to override (``egl``, ``glfw``, or ``disable`` when nothing renders).

The public API is re-exported here, imported lazily; each concept lives in its own module.
"""

import importlib
import os
from typing import TYPE_CHECKING, Any

os.environ.setdefault("MUJOCO_GL", "osmesa")

from lasa.ffmpeg import pin_mediapy  # noqa: E402 (after MUJOCO_GL, which it does not touch)

pin_mediapy()  # mediapy reads and writes with the pinned wheel's ffmpeg, once it is imported

# The public API, imported on first use (PEP 562): `import lasa.runner` or `lasa.errors`
# stays light (no torch, no MuJoCo), which the notebook runner pays for on every run.
# name -> module that defines it; `__all__` lists the same names (tests/test_init.py checks).
_EXPORTS = {
    "ArtifactError": "lasa.errors",
    "Claim": "lasa.claims",
    "ConfigError": "lasa.errors",
    "ContextMap": "lasa.newgoals",
    "ControlConfig": "lasa.config",
    "Controller": "lasa.controller",
    "CupTask": "lasa.task",
    "DecoderConfig": "lasa.decoder",
    "DemoConfig": "lasa.demos",
    "Demonstrations": "lasa.demos",
    "IKError": "lasa.errors",
    "LasaError": "lasa.errors",
    "LatentActionModel": "lasa.decoder",
    "METHODS": "lasa.rollout",
    "MappedDecoder": "lasa.newgoals",
    "Paths": "lasa.paths",
    "ROBOTS": "lasa.robot",
    "Robot": "lasa.robot",
    "TrainConfig": "lasa.train",
    "Trajectories": "lasa.rollout",
    "UserPopulation": "lasa.users",
    "collect_demonstrations": "lasa.demos",
    "extend_task": "lasa.newgoals",
    "load_checkpoint": "lasa.decoder",
    "load_demonstrations": "lasa.demos",
    "load_robot": "lasa.robot",
    "make_cup_task": "lasa.task",
    "publish": "lasa.sims.publish",
    "rollout": "lasa.rollout",
    "save_checkpoint": "lasa.decoder",
    "save_demonstrations": "lasa.demos",
    "shared_autonomy_step": "lasa.rollout",
    "train_decoder": "lasa.train",
    "update_claims": "lasa.claims",
}

if TYPE_CHECKING:
    from lasa.claims import Claim, update_claims
    from lasa.config import ControlConfig
    from lasa.controller import Controller
    from lasa.decoder import DecoderConfig, LatentActionModel, load_checkpoint, save_checkpoint
    from lasa.demos import (
        DemoConfig,
        Demonstrations,
        collect_demonstrations,
        load_demonstrations,
        save_demonstrations,
    )
    from lasa.errors import ArtifactError, ConfigError, IKError, LasaError
    from lasa.newgoals import ContextMap, MappedDecoder, extend_task
    from lasa.paths import Paths
    from lasa.robot import ROBOTS, Robot, load_robot
    from lasa.rollout import METHODS, Trajectories, rollout, shared_autonomy_step
    from lasa.sims.publish import publish
    from lasa.task import CupTask, make_cup_task
    from lasa.train import TrainConfig, train_decoder
    from lasa.users import UserPopulation


def __getattr__(name: str) -> Any:
    """Import a public name's module when the name is first used."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'lasa' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


try:  # the installed package's version (pyproject.toml), so that it cannot drift from the release
    from importlib.metadata import version as _version

    __version__ = _version("lasa")
except Exception:  # running from a source tree that was never installed
    __version__ = "0.0.0+unknown"

__all__ = [
    "ArtifactError",
    "Claim",
    "ConfigError",
    "ContextMap",
    "ControlConfig",
    "Controller",
    "CupTask",
    "DecoderConfig",
    "DemoConfig",
    "Demonstrations",
    "IKError",
    "LasaError",
    "LatentActionModel",
    "METHODS",
    "MappedDecoder",
    "Paths",
    "ROBOTS",
    "Robot",
    "TrainConfig",
    "Trajectories",
    "UserPopulation",
    "collect_demonstrations",
    "extend_task",
    "load_checkpoint",
    "load_demonstrations",
    "load_robot",
    "make_cup_task",
    "publish",
    "rollout",
    "save_checkpoint",
    "save_demonstrations",
    "shared_autonomy_step",
    "train_decoder",
    "update_claims",
]
