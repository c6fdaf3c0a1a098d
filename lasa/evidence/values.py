"""The claims' numbers as data, ``figures/claim_values.csv``: per claims row each quantity its rule
reads (value and interval) and each fact a sentence states (without an interval). The columns
(:data:`VALUE_COLUMNS`) are the README's data contract."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import pandas as pd

VALUES_NAME = "claim_values.csv"  # beside claims.csv
VALUE_COLUMNS = ("id", "robot", "figure", "reading", "quantity", "value", "low", "high", "level", "n")
HEADLINE = "headline"  # the reading column of a headline row


@dataclasses.dataclass(frozen=True)
class Number:
    """One number of a claims row: its value, its interval at ``level`` (NaN for a fact) and N."""

    value: float
    low: float = math.nan
    high: float = math.nan
    level: float = math.nan
    n: int = 0

    @property
    def interval(self) -> tuple[float, float] | None:
        """``(low, high)`` if both ends are known, else None."""
        return (self.low, self.high) if math.isfinite(self.low) and math.isfinite(self.high) else None


Numbers = Mapping[str, Number]  # quantity -> its number, for one claims row
Values = Mapping[tuple[str, str], Numbers]  # (id, robot) -> that row's numbers


def reading_of(claim_id: str) -> str:
    """The reading a claims id names after ``@``; :data:`HEADLINE` for a headline row."""
    return claim_id.split("@", 1)[1] if "@" in claim_id else HEADLINE


def _float(text: object) -> float:
    return float(str(text)) if str(text).strip() else math.nan


def read_values(frame: pd.DataFrame) -> dict[tuple[str, str], dict[str, Number]]:
    """``claim_values.csv`` (read as strings) as (id, robot) -> quantity -> :class:`Number`."""
    out: dict[tuple[str, str], dict[str, Number]] = {}
    for r in frame.itertuples(index=False):
        number = Number(_float(r.value), _float(r.low), _float(r.high), _float(r.level), int(float(r.n or 0)))
        out.setdefault((str(r.id), str(r.robot)), {})[str(r.quantity)] = number
    return out
