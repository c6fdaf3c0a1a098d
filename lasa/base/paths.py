"""Where things live: the repository root, and every artifact's path with its make hint.

A notebook runs from Make and papermill (working directory: the repository root), and
from Jupyter (working directory: ``notebooks/``). Relative folders such as ``build`` and
``figures`` therefore resolve against the repository root, never the working directory,
so the three behave the same.

Each artifact that one notebook writes and another reads is named once here, with the
notebook that makes it, so that a missing file's error says how to make it.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from lasa.base.errors import ConfigError

__all__ = ["repo_root", "resolve", "ARTIFACTS", "Paths"]

_PACKAGE = Path(__file__).resolve().parents[1]  # lasa/ (this module is lasa/base/paths.py)


def repo_root() -> Path:
    """The repository root: ``LASA_ROOT`` if set, else the folder holding this package.

    The package is installed in editable mode (``make setup``), so the folder above
    ``lasa/`` is the clone. For a non-editable install, set ``LASA_ROOT``.

    Raises:
        ConfigError: if ``LASA_ROOT`` names a folder that does not exist.
    """
    env = os.environ.get("LASA_ROOT")
    if env:
        root = Path(env).expanduser().resolve()
        if not root.is_dir():
            raise ConfigError(f"LASA_ROOT={env!r} is not a folder")
        return root
    return _PACKAGE.parent


def resolve(path: str | os.PathLike[str]) -> Path:
    """``path`` if absolute, else ``path`` under the repository root."""
    path = Path(path).expanduser()
    return path if path.is_absolute() else repo_root() / path


# name -> (path under the build folder, the notebook that writes it)
ARTIFACTS: dict[str, tuple[str, str]] = {
    "demos": ("data/demos_{robot}.npz", "01_demonstrations"),
    "decoder": ("models/decoder_{robot}.pt", "02_decoder_training"),
    "latent_paths": ("analysis/latent_{robot}.npz", "02_decoder_training"),
    # The entropy ablation's pair (notebook 03): the base decoder fine-tuned for the same
    # steps and schedule, without the term (lambda = 0) and with it (the chosen lambda).
    "decoder_lambda0": ("models/decoder_{robot}_lambda0.pt", "03_entropy_ablation"),
    "decoder_entropy": ("models/decoder_{robot}_entropy.pt", "03_entropy_ablation"),
    # The eating study's data and 2-D decoder (Sec. VI; the Panda only).
    "eating_demos": ("data/eating_demos_{robot}.npz", "10_eating_task"),
    "eating_decoder": ("models/eating_decoder_{robot}.pt", "10_eating_task"),  # the headline reading
    "eating_reading_demos": ("data/eating_demos_{robot}_{reading}.npz", "10_eating_task"),
    "eating_reading_decoder": ("models/eating_decoder_{robot}_{reading}.pt", "10_eating_task"),
}


@dataclasses.dataclass(frozen=True)
class Paths:
    """The build and figures folders of one run, resolved against the repository root.

    Attributes:
        build: Datasets, checkpoints and analysis files (``build`` by default).
        figures: Figures, the CSV behind each, videos and the claims table.
    """

    build: Path
    figures: Path

    @classmethod
    def of(cls, build_dir: str | os.PathLike[str], figures_dir: str | os.PathLike[str]) -> Paths:
        """The run's folders; relative ones are under the repository root, not the working directory.

        That is what the notebooks need (the same files from Jupyter, papermill and Make). Code of
        your own that should write where it runs passes absolute folders, or builds
        ``Paths(build, figures)`` itself (``docs/extending.md``).
        """
        return cls(resolve(build_dir), resolve(figures_dir))

    def artifact(self, name: str, robot: str, **fields: str) -> Path:
        """The path of artifact ``name`` (a key of :data:`ARTIFACTS`) for ``robot``.

        ``fields`` fill the rest of its pattern (``reading`` for the eating readings).
        """
        if name not in ARTIFACTS:
            raise ConfigError(f"unknown artifact {name!r}; known: {sorted(ARTIFACTS)}")
        try:
            return self.build / ARTIFACTS[name][0].format(robot=robot, **fields)
        except KeyError as exc:
            raise ConfigError(f"artifact {name!r} needs the field {exc}") from exc

    @staticmethod
    def make_hint(name: str, robot: str) -> str:
        """The command that makes artifact ``name`` for ``robot``."""
        notebook = ARTIFACTS[name][1]
        return f"make figures (it runs notebooks/{notebook}.ipynb for {robot})"

    def figure(self, name: str) -> Path:
        """A file in the figures folder, e.g. ``figure("sim1_fixed_expertise.csv")``."""
        return self.figures / name

    @property
    def claims(self) -> Path:
        """The claims table, ``<figures>/claims.csv`` (``claims.md`` beside it)."""
        return self.figures / "claims.csv"
