"""Where things live: the repository root (never the working directory) and each artifact's path."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from lasa.base.errors import ConfigError

_PACKAGE = Path(__file__).resolve().parents[1]  # lasa/ (this module is lasa/base/paths.py)


def repo_root() -> Path:
    """``LASA_ROOT`` if set (ConfigError unless a folder), else the folder above ``lasa/``."""
    if env := os.environ.get("LASA_ROOT"):
        if not (root := Path(env).expanduser().resolve()).is_dir():
            raise ConfigError(f"LASA_ROOT={env!r} is not a folder")
        return root
    return _PACKAGE.parent


def resolve(path: str | os.PathLike[str]) -> Path:
    """``path`` if absolute, else ``path`` under the repository root."""
    path = Path(path).expanduser()
    return path if path.is_absolute() else repo_root() / path


ARTIFACTS: dict[str, tuple[str, str]] = {  # name -> (path under the build folder, the notebook writing it)
    "demos": ("data/demos_{robot}.npz", "01_demonstrations"),
    "decoder": ("models/decoder_{robot}.pt", "02_decoder_training"),
    "latent_paths": ("analysis/latent_{robot}.npz", "02_decoder_training"),
    # the entropy ablation's pair: the base decoder fine-tuned without the term and with it
    "decoder_lambda0": ("models/decoder_{robot}_lambda0.pt", "03_entropy_ablation"),
    "decoder_entropy": ("models/decoder_{robot}_entropy.pt", "03_entropy_ablation"),
    # The eating study's data and 2-D decoder (Sec. VI; the Panda only).
    "eating_demos": ("data/eating_demos_{robot}.npz", "10_eating_task"),
    "eating_decoder": ("models/eating_decoder_{robot}.pt", "10_eating_task"),  # the headline segmentation
    "eating_segmentation_demos": ("data/eating_demos_{robot}_{segmentation}.npz", "10_eating_task"),
    "eating_segmentation_decoder": ("models/eating_decoder_{robot}_{segmentation}.pt", "10_eating_task"),
}


@dataclasses.dataclass(frozen=True)
class Paths:
    """The build folder (datasets, checkpoints, analysis) and figures folder of one run."""

    build: Path
    figures: Path

    @classmethod
    def of(cls, build_dir: str | os.PathLike[str], figures_dir: str | os.PathLike[str]) -> Paths:
        """The run's folders, relative ones under the repository root (not the working directory)."""
        return cls(resolve(build_dir), resolve(figures_dir))

    def artifact(self, name: str, robot: str, **fields: str) -> Path:
        """The path of artifact ``name`` (:data:`ARTIFACTS`) for ``robot``, ``fields`` filling its pattern."""
        if name not in ARTIFACTS:
            raise ConfigError(f"unknown artifact {name!r}; known: {sorted(ARTIFACTS)}")
        try:
            return self.build / ARTIFACTS[name][0].format(robot=robot, **fields)
        except KeyError as exc:
            raise ConfigError(f"artifact {name!r} needs the field {exc}") from exc

    @staticmethod
    def make_hint(name: str, robot: str) -> str:
        """The command that makes artifact ``name`` for ``robot``."""
        return f"make figures (it runs notebooks/{ARTIFACTS[name][1]}.ipynb for {robot})"

    def figure(self, name: str) -> Path:
        """A file in the figures folder, e.g. ``figure("sim1_fixed_expertise.csv")``."""
        return self.figures / name

    @property
    def claims(self) -> Path:
        """The claims table, ``<figures>/claims.csv`` (``claims.md`` beside it)."""
        return self.figures / "claims.csv"
