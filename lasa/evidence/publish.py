"""Publish one robot's run of a figure: merge its rows, redraw the figure, update the claims, all
under the figures folder's lock (both robots' notebooks write the same figures side by side)."""

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


class FigureModule(Protocol):
    """What :func:`publish` needs of a figure's module; optional ``DPI`` (150) and ``KEY`` (``robot``)."""

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
    module: FigureModule, frame: pd.DataFrame, paths: Paths, claims: Sequence[Claim] = (), **plot_args: Any
) -> pd.DataFrame:
    """Merge ``frame`` into the figure's CSV (replacing this robot's rows), redraw its PNG from the file
    (``plot_args`` to ``module.plot``), write ``claims``, and return the merged table of every robot."""
    if missing := [c for c in module.COLUMNS if c not in frame.columns]:
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
