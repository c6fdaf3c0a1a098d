"""The claims table: for each claim of the paper, did it reproduce?

Each figure notebook evaluates its claims from the data behind its figure and writes
its rows into ``figures/claims.csv`` (and the same table as ``figures/claims.md``, which
the README's table is generated from). Each row has a stable ``id`` (``sim1.final_error``),
so a claim can be reworded without leaving its old row behind: a figure's run replaces
every row of that (figure, robot) and leaves the others. Rows are unique by (id, robot).
``assistance`` names the reading of shared autonomy the row was measured under
(``point``: Eq. M2 towards one pose per goal). Each claim has a headline row, ``<figure>.<name>``,
measured under the default reading, and one row per member of the family,
``<figure>.<name>@<member>`` (:mod:`lasa.verdicts`). ``ci_low`` and ``ci_high`` bound the
number the verdict rests on (a bootstrap 95% interval over users), and ``seeds_agree``
says on how many independent draws of users the verdict comes out the same.
``reproduced`` is ``yes``, ``partly`` or ``no``;
a claim that does not reproduce is a result, reported with its measured value and the
most likely reason in ``note``.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from pathlib import Path

import pandas as pd

from lasa.errors import ConfigError
from lasa.io import locked, write_csv, write_text
from lasa.rules import UNDECIDED

__all__ = ["Claim", "update_claims", "render_markdown", "sync_readme", "CLAIM_COLUMNS", "README_MARKERS"]

README_MARKERS = (
    "<!-- claims:begin (generated from figures/claims.md by make figures) -->",
    "<!-- claims:end -->",
)

CLAIM_COLUMNS = (
    "id",
    "claim",
    "figure",
    "robot",
    "assistance",
    "paper",
    "measured",
    "ci_low",
    "ci_high",
    "reproduced",
    "settled",
    "n_users",
    "note",
)
VERDICTS = ("yes", "partly", "no", UNDECIDED)


@dataclasses.dataclass(frozen=True)
class Claim:
    """One row of the claims table."""

    id: str  # stable key, "<figure>.<name>": survives a rewording of ``claim``
    claim: str  # the paper's claim, in a sentence
    figure: str  # the figure it belongs to, e.g. "sim1"
    paper: str  # what the paper reports
    measured: str  # what we measured
    reproduced: str  # "yes", "partly", "no", or "undecided" when an interval straddles a threshold
    note: str  # how the verdict was decided, and the likely reason if not "yes"
    robot: str  # the robot it was measured on
    assistance: str = "point"  # the shared-autonomy reading: Eq. M2 towards one pose per goal
    value: float = math.nan  # the number the verdict rests on (``measured`` names it first)
    ci_low: float = math.nan  # bootstrap 95% interval of ``value`` (lasa.verdicts)
    ci_high: float = math.nan
    settled: bool = False  # every interval clear of its rule's thresholds (lasa.verdicts)
    n_users: int = 0  # simulated users (or participants) per point the verdict rests on
    values: Mapping[str, float] = dataclasses.field(default_factory=dict)  # the rule's numbers

    def __post_init__(self) -> None:
        if not self.id.startswith(f"{self.figure}.") or " " in self.id:
            raise ConfigError(f"claim id must be '<figure>.<name>' without spaces, got {self.id!r}")
        if self.reproduced not in VERDICTS:
            raise ConfigError(f"reproduced must be one of {VERDICTS}, got {self.reproduced!r}")


def _row(claim: Claim) -> dict[str, object]:
    """A claim as a table row: the interval to 4 significant digits, empty where unknown."""
    row: dict[str, object] = {f.name: getattr(claim, f.name) for f in dataclasses.fields(claim)}
    del row["values"], row["value"]
    row["settled"] = "yes" if claim.settled else "no"
    for key in ("ci_low", "ci_high"):
        row[key] = "" if math.isnan(getattr(claim, key)) else f"{getattr(claim, key):.4g}"
    return row


def render_markdown(frame: pd.DataFrame) -> str:
    """The claims table as a GitHub-flavoured Markdown table."""
    cols = list(CLAIM_COLUMNS)
    lines = ["| " + " | ".join(cols) + " |", "| " + " | ".join("---" for _ in cols) + " |"]
    for _, row in frame.iterrows():
        cells = [str(row[c]).replace("|", "\\|").replace("\n", " ") for c in cols]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def update_claims(path: str | os.PathLike[str], claims: list[Claim]) -> pd.DataFrame:
    """Replace the rows of these claims' (figure, robot) pairs in the CSV at ``path``.

    Every row of a (figure, robot) that ``claims`` covers is dropped first, so a claim
    that a figure no longer makes leaves the table; rows of other figures and robots are
    kept. The ``.md`` twin is rewritten from the result. Runs under the folder lock
    (robots run in parallel).

    Args:
        path: The claims CSV, e.g. ``figures/claims.csv``; created if missing.
        claims: The rows to write; (id, robot) must be unique among them.

    Returns:
        The whole table after the update, ordered by figure, robot and id.

    Raises:
        ConfigError: if two claims share an (id, robot), or the file has other columns.
    """
    path = Path(path)
    new = pd.DataFrame([_row(c) for c in claims], columns=list(CLAIM_COLUMNS))
    if new.duplicated(["id", "robot"]).any():
        dup = new.loc[new.duplicated(["id", "robot"]), "id"].tolist()
        raise ConfigError(f"claim ids must be unique per robot, repeated: {dup}")
    with locked(path.parent):
        if path.exists():
            old = pd.read_csv(path, dtype=str, keep_default_na=False)
            if list(old.columns) != list(CLAIM_COLUMNS):
                raise ConfigError(
                    f"{path} has columns {list(old.columns)}, expected {list(CLAIM_COLUMNS)}; "
                    "delete it and re-run the figure notebooks"
                )
            covered = pd.MultiIndex.from_frame(new[["figure", "robot"]].drop_duplicates())
            keep = ~pd.MultiIndex.from_frame(old[["figure", "robot"]]).isin(covered)
            table = pd.concat([old.loc[keep], new], ignore_index=True)
        else:
            table = new
        table = table.sort_values(["figure", "robot", "id"], kind="stable").reset_index(drop=True)
        write_csv(path, table)
        write_text(path.with_suffix(".md"), render_markdown(table))
    return table


def sync_readme(readme: str | os.PathLike[str], table_md: str | os.PathLike[str]) -> bool:
    """Put the claims table ``table_md`` between the README's claims markers.

    ``make figures`` runs this after the notebooks, so the README's table is always the
    last full run's ``figures/claims.md``, never a hand-edited copy.

    Returns:
        Whether the README changed.

    Raises:
        ConfigError: if the README lacks either marker (:data:`README_MARKERS`).
    """
    readme, table_md = Path(readme), Path(table_md)
    text = readme.read_text()
    begin, end = README_MARKERS
    if begin not in text or end not in text or text.index(begin) > text.index(end):
        raise ConfigError(f"{readme} must hold the lines {begin!r} and {end!r}, in that order")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    new = f"{head}{begin}\n{table_md.read_text().rstrip()}\n{end}{tail}"
    if new == text:
        return False
    write_text(readme, new)
    return True


if __name__ == "__main__":
    import sys

    if len(sys.argv) != 3:
        raise SystemExit("usage: python -m lasa.claims README.md figures/claims.md")
    changed = sync_readme(sys.argv[1], sys.argv[2])
    print(f"{sys.argv[1]}: claims table {'updated' if changed else 'already current'}")
