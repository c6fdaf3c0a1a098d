"""The claims table: for each claim of the paper, did it reproduce?

Each figure notebook evaluates its claims from the data behind its figure and writes
its rows into ``figures/claims.csv`` (and the same table as ``figures/claims.md`` for
the README). Rows are keyed by (figure, robot, claim): re-running a notebook replaces
its own rows and leaves the others. ``reproduced`` is ``yes``, ``partly`` or ``no``;
a claim that does not reproduce is a result, reported with its measured value and the
most likely reason in ``note``.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import pandas as pd

from lasa.errors import ConfigError
from lasa.io import locked, write_csv, write_text

__all__ = ["Claim", "update_claims", "render_markdown", "CLAIM_COLUMNS"]

CLAIM_COLUMNS = ("claim", "figure", "paper", "measured", "reproduced", "note", "robot")
VERDICTS = ("yes", "partly", "no")


@dataclasses.dataclass(frozen=True)
class Claim:
    """One row of the claims table."""

    claim: str  # the paper's claim, in a sentence
    figure: str  # the figure it belongs to, e.g. "sim1"
    paper: str  # what the paper reports
    measured: str  # what we measured
    reproduced: str  # "yes", "partly" or "no"
    note: str  # how the verdict was decided, and the likely reason if not "yes"
    robot: str  # the robot it was measured on

    def __post_init__(self) -> None:
        if self.reproduced not in VERDICTS:
            raise ConfigError(f"reproduced must be one of {VERDICTS}, got {self.reproduced!r}")


def render_markdown(frame: pd.DataFrame) -> str:
    """The claims table as a GitHub-flavoured Markdown table."""
    cols = list(CLAIM_COLUMNS)
    lines = ["| " + " | ".join(cols) + " |", "| " + " | ".join("---" for _ in cols) + " |"]
    for _, row in frame.iterrows():
        cells = [str(row[c]).replace("|", "\\|").replace("\n", " ") for c in cols]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def update_claims(path: str | os.PathLike[str], claims: list[Claim]) -> pd.DataFrame:
    """Replace these claims' rows in the CSV at ``path`` (and its ``.md`` twin).

    Args:
        path: The claims CSV, e.g. ``figures/claims.csv``; created if missing.
        claims: The rows to write; existing rows with the same (figure, robot, claim)
            are replaced, all other rows are kept.

    Returns:
        The whole table after the update.
    """
    path = Path(path)
    with locked(path.parent):
        new = pd.DataFrame([dataclasses.asdict(c) for c in claims], columns=list(CLAIM_COLUMNS))
        if path.exists():
            old = pd.read_csv(path, dtype=str, keep_default_na=False)
            missing = set(CLAIM_COLUMNS) - set(old.columns)
            if missing:
                raise ConfigError(f"{path} lacks columns {sorted(missing)}; delete it to start afresh")
            key = ["figure", "robot", "claim"]
            keep = ~old.set_index(key).index.isin(new.set_index(key).index)
            table = pd.concat([old.loc[keep, list(CLAIM_COLUMNS)], new], ignore_index=True)
        else:
            table = new
        table = table.sort_values(["figure", "robot"], kind="stable").reset_index(drop=True)
        write_csv(path, table)
        write_text(path.with_suffix(".md"), render_markdown(table))
    return table
