"""lasa: Shared Autonomy with Learned Latent Actions (Jeon, Losey & Sadigh, RSS 2020), a reproducibility
package (extending it: ``docs/extending.md``). ``import lasa`` only re-exports, lazily (PEP 562), and sets
nothing: call :func:`lasa.runtime.pin` first, before numpy, torch or mujoco."""

import contextlib
import importlib
import importlib.metadata
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the lazy names for type checkers, and (_lazy_table) what __getattr__ imports
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


def _lazy_table() -> dict[str, str]:
    """Each public name -> its module, read from the ``if TYPE_CHECKING:`` imports above."""
    import ast

    with open(__file__, encoding="utf-8") as source:
        tree = ast.parse(source.read())
    (block,) = [n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "TYPE_CHECKING"]
    return {a.name: str(n.module) for n in block.body if isinstance(n, ast.ImportFrom) for a in n.names}


_EXPORTS = _lazy_table()


def __getattr__(name: str) -> Any:
    """Import a public name's module when the name is first used."""
    if name not in _EXPORTS:
        raise AttributeError(f"module 'lasa' has no attribute {name!r}")
    globals()[name] = value = getattr(importlib.import_module(_EXPORTS[name]), name)
    return value


__version__ = "0.0.0+unknown"  # a source tree that was never installed
with contextlib.suppress(Exception):  # the installed package's (pyproject.toml): it cannot drift
    __version__ = importlib.metadata.version("lasa")

__all__ = [*_EXPORTS]
