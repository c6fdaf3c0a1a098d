"""Publish one robot's run of a figure: merge its rows, redraw the figure, update the claims.

``make figures`` runs the two robots' notebooks side by side, and both write the same
shared figures. :func:`publish` does the read-modify-write of a figure as one step
under the figures folder's lock (:func:`lasa.base.io.locked`): this robot's rows replace its
old ones in ``<NAME>.csv`` (rows ordered by robot, so the file is the same whichever
robot finishes first), the figure is redrawn from every robot present, and the robot's
claims replace its old rows of that figure in ``claims.csv``.
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

    Args:
        module: The figure's module (``NAME``, ``COLUMNS``, ``plot``).
        frame: One robot's rows; the CSV keeps the columns of ``module.COLUMNS``.
        paths: The run's folders.
        claims: This robot's claims of the figure (none for figures without claims).
        **plot_args: Passed to ``module.plot`` after the merged table.

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
        # Draw from the file, not from the merged frame: the robot that publishes last has
        # its rows in full precision in memory and the other's as rounded in the CSV, so
        # the figure would depend on which robot finished first. From the file, it is a
        # function of the data saved beside it.
        table = pd.read_csv(csv)
        dpi = int(getattr(module, "DPI", 150))
        save_figure(module.plot(table, **plot_args), paths.figure(f"{module.NAME}.png"), dpi)
        if claims:
            update_claims(paths.claims, list(claims))
    return table
