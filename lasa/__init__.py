"""lasa: Shared Autonomy with Learned Latent Actions (Jeon, Losey & Sadigh, RSS 2020).

A reproducibility package (extending it: ``docs/extending.md``). ``import lasa`` only re-exports,
lazily (PEP 562), and sets nothing: call :func:`lasa.runtime.pin` first, before numpy, torch or mujoco.
"""

import importlib
from typing import TYPE_CHECKING, Any

_HOMES = {  # module -> the public names it defines, imported on first use (`__getattr__`)
    "lasa.base.config": "ControlConfig",
    "lasa.base.errors": "ArtifactError CheckpointError ConfigError DamagedLogError EmptySelectionError"
    " IKError LasaError",
    "lasa.base.paths": "Paths",
    "lasa.evidence.claims": "Claim update_claims",
    "lasa.evidence.publish": "publish",
    "lasa.method.assistance": "Member",
    "lasa.method.dataset": "Demonstrations load_demonstrations save_demonstrations",
    "lasa.method.decoder": "ActionDecoder DecoderConfig LatentActionModel load_checkpoint save_checkpoint",
    "lasa.method.runner": "Runner",
    "lasa.method.context_map": "ContextMap MappedDecoder extend_task",
    "lasa.method.step": "Assist METHODS shared_autonomy_step",
    "lasa.method.train": "TrainConfig train_decoder",
    "lasa.people.demos": "DemoConfig collect_demonstrations",
    "lasa.people.rollout": "Trajectories rollout",
    "lasa.people.users": "UserPopulation",
    "lasa.world.goals": "GoalTask",
    "lasa.world.robot": "ROBOTS Robot RobotSpec load_robot",
    "lasa.world.task": "CupTask make_cup_task",
}
_EXPORTS = {name: module for module, names in _HOMES.items() for name in names.split()}

if TYPE_CHECKING:  # the lazy names, for type checkers
    from lasa.base.config import ControlConfig  # noqa: F401
    from lasa.base.errors import (  # noqa: F401
        ArtifactError,
        CheckpointError,
        ConfigError,
        DamagedLogError,
        EmptySelectionError,
        IKError,
        LasaError,
    )
    from lasa.base.paths import Paths  # noqa: F401
    from lasa.evidence.claims import Claim, update_claims  # noqa: F401
    from lasa.evidence.publish import publish  # noqa: F401
    from lasa.method.assistance import Member  # noqa: F401
    from lasa.method.context_map import ContextMap, MappedDecoder, extend_task  # noqa: F401
    from lasa.method.dataset import Demonstrations, load_demonstrations, save_demonstrations  # noqa: F401
    from lasa.method.decoder import (  # noqa: F401
        ActionDecoder,
        DecoderConfig,
        LatentActionModel,
        load_checkpoint,
        save_checkpoint,
    )
    from lasa.method.runner import Runner  # noqa: F401
    from lasa.method.step import METHODS, Assist, shared_autonomy_step  # noqa: F401
    from lasa.method.train import TrainConfig, train_decoder  # noqa: F401
    from lasa.people.demos import DemoConfig, collect_demonstrations  # noqa: F401
    from lasa.people.rollout import Trajectories, rollout  # noqa: F401
    from lasa.people.users import UserPopulation  # noqa: F401
    from lasa.world.goals import GoalTask  # noqa: F401
    from lasa.world.robot import ROBOTS, Robot, RobotSpec, load_robot  # noqa: F401
    from lasa.world.task import CupTask, make_cup_task  # noqa: F401


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

__all__ = [*_EXPORTS]
