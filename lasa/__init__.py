"""lasa: Shared Autonomy with Learned Latent Actions (Jeon, Losey & Sadigh, RSS 2020).

A reproducibility package: MuJoCo robots and the cup task, demonstrations, the
conditional-autoencoder decoder phi(z, s, b), shared autonomy (Algorithm 1),
Boltzmann-rational simulated users, and the sweeps behind the paper's figures.

Rendering is software-only by default: ``MUJOCO_GL`` is set to ``osmesa`` here,
before anything imports mujoco (it is read once, at import). Set it yourself first
to override (``egl``, ``glfw``, or ``disable`` when nothing renders).

The public API is re-exported here; each concept lives in its own module.
"""

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")

from lasa.claims import Claim, update_claims  # noqa: E402
from lasa.config import ControlConfig  # noqa: E402
from lasa.decoder import DecoderConfig, LatentActionModel, load_checkpoint, save_checkpoint  # noqa: E402
from lasa.demos import (  # noqa: E402
    DemoConfig,
    Demonstrations,
    collect_demonstrations,
    load_demonstrations,
    save_demonstrations,
)
from lasa.errors import ArtifactError, ConfigError, IKError, LasaError  # noqa: E402
from lasa.experiments import Sim1Config, run_fixed_expertise, sim1_claims  # noqa: E402
from lasa.robot import ROBOTS, Robot, load_robot  # noqa: E402
from lasa.rollout import METHODS, Trajectories, rollout, shared_autonomy_step  # noqa: E402
from lasa.task import CupTask, make_cup_task  # noqa: E402
from lasa.train import TrainConfig, train_decoder  # noqa: E402
from lasa.users import UserPopulation  # noqa: E402

__version__ = "0.1.0"

__all__ = [
    "ArtifactError",
    "Claim",
    "ConfigError",
    "ControlConfig",
    "CupTask",
    "DecoderConfig",
    "DemoConfig",
    "Demonstrations",
    "IKError",
    "LasaError",
    "LatentActionModel",
    "METHODS",
    "ROBOTS",
    "Robot",
    "Sim1Config",
    "TrainConfig",
    "Trajectories",
    "UserPopulation",
    "collect_demonstrations",
    "load_checkpoint",
    "load_demonstrations",
    "load_robot",
    "make_cup_task",
    "rollout",
    "run_fixed_expertise",
    "save_checkpoint",
    "save_demonstrations",
    "shared_autonomy_step",
    "sim1_claims",
    "train_decoder",
    "update_claims",
]
