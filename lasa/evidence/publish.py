"""Publish one robot's run of a figure: merge its rows, redraw the figure, update the claims.

Both robots' notebooks run side by side and write the same figures, so :func:`publish` does the
read-modify-write as one step under the figures folder's lock (:func:`lasa.base.io.locked`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol

import matplotlib.pyplot as plt
import pandas as pd
from matplotlib.figure import Figure

from lasa.base.errors import ConfigError
from lasa.base.io import atomic_path, locked, update_csv
from lasa.base.paths import Paths
from lasa.evidence.claims import Claim, update_claims

__all__ = ["FigureModule", "publish", "save_figure"]


class FigureModule(Protocol):
    """What :func:`publish` needs of a figure's module (see :mod:`lasa.experiments`); an optional
    ``DPI`` sets the PNG's resolution (150 if absent), an optional ``KEY`` the column whose
    values one run's rows replace (``robot`` if absent)."""

    NAME: str
    COLUMNS: tuple[str, ...]
    plot: Callable[..., Figure]


def save_figure(fig: Figure, path: str | Path, dpi: int = 150) -> Path:
    """Atomically save ``fig`` as PNG and close it."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    plt.close(fig)
    return Path(path)


def publish(
    module: FigureModule,
    frame: pd.DataFrame,
    paths: Paths,
    claims: Sequence[Claim] = (),
    **plot_args: Any,
) -> pd.DataFrame:
    """Merge ``frame`` into the figure's CSV, redraw its PNG, and write ``claims``.

    This robot's rows replace its old ones (the CSV ordered by robot, the same whichever finishes
    first); the figure is drawn from the file, every robot's rows as saved; ``plot_args`` go to
    ``module.plot`` after the table; ``claims`` replace the robot's old rows of ``claims.csv``.

    Returns:
        The merged table of every robot present.

    Raises:
        ConfigError: if ``frame`` lacks a column of ``module.COLUMNS``.
    """
    missing = [c for c in module.COLUMNS if c not in frame.columns]
    if missing:
        raise ConfigError(f"{module.NAME} rows lack column(s) {missing}")
    with locked(paths.figures):
        key = str(getattr(module, "KEY", "robot"))  # the column whose values a run replaces
        csv = update_csv(paths.figure(f"{module.NAME}.csv"), frame[list(module.COLUMNS)], key=key)
        # draw from the file: in memory, the last robot's rows would be in full precision
        table = pd.read_csv(csv)
        dpi = int(getattr(module, "DPI", 150))
        save_figure(module.plot(table, **plot_args), paths.figure(f"{module.NAME}.png"), dpi)
        if claims:
            update_claims(paths.claims, list(claims))
    return table
