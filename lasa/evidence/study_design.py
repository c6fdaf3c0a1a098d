"""The user study's 2x2 within-subjects design, interface (R, LA) x assistance (none, SA): a tidy frame
(one row per participant x condition x task), validated and reduced per participant and cell."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from lasa.base.conditions import CONDITIONS
from lasa.base.config import check_choice
from lasa.base.errors import ConfigError

INTERFACES: tuple[str, ...] = ("R", "LA")  # levels of the interface factor
SA_LEVELS: tuple[str, ...] = ("none", "SA")  # levels of the assistance factor
AGGS: tuple[str, ...] = ("mean", "sum")  # how a participant's cell (its tasks) reduces to one value
# Columns every frame needs besides the measure; interface and assistance derive from condition
_KEYS: tuple[str, ...] = ("participant", "condition", "task")
_DERIVED: tuple[str, ...] = ("interface", "assistance")


def factors(condition: str) -> tuple[str, str]:
    """A condition's (interface, assistance) levels, ``"LA+SA"`` -> ``("LA", "SA")``; ConfigError: unknown."""
    if not isinstance(condition, str) or condition not in CONDITIONS:
        raise ConfigError(f"unknown condition {condition!r}; allowed: {', '.join(CONDITIONS)}")
    interface, _, assistance = condition.partition("+")
    return interface, assistance or "none"


def prepare(frame: pd.DataFrame, measure: str) -> pd.DataFrame:
    """Validate ``frame`` and return a copy with only the key columns, ``measure`` as float and
    ``interface`` / ``assistance`` columns derived from ``condition``."""
    if not isinstance(frame, pd.DataFrame):
        raise TypeError(f"frame must be a pandas DataFrame, got {type(frame).__name__}")
    if measure in _KEYS + _DERIVED:
        raise ConfigError(f"measure {measure!r} is a key column; name the column holding the measure")
    missing = [name for name in (*_KEYS, measure) if name not in frame.columns]
    if missing:
        have = [str(name) for name in frame.columns]
        raise ConfigError(f"frame is missing column(s) {', '.join(map(repr, missing))}; it has {have}")
    if frame.empty:
        raise ConfigError("frame has no rows")
    if frame["participant"].isna().any():
        raise ConfigError("column 'participant' has missing values")

    conditions = frame["condition"]
    unknown = sorted({repr(c) for c in conditions.unique() if c not in CONDITIONS})
    if unknown:
        raise ConfigError(f"unknown condition(s) {', '.join(unknown)}; allowed: {', '.join(CONDITIONS)}")

    values = frame[measure]
    if not pd.api.types.is_numeric_dtype(values) or pd.api.types.is_bool_dtype(values):
        raise ConfigError(f"measure {measure!r} must be numeric, got dtype {values.dtype}")
    values = values.astype(float)
    bad = ~np.isfinite(values.to_numpy())
    keys = list(_KEYS)
    if bad.any():
        rows = frame.loc[bad, keys].head(3).to_dict("records")
        raise ConfigError(f"measure {measure!r} has {int(bad.sum())} non-finite value(s), e.g. at {rows}")

    duplicated = frame.duplicated(subset=keys, keep=False)
    if duplicated.any():
        row = frame.loc[duplicated, keys].iloc[0].to_dict()
        raise ConfigError(
            f"more than one row for participant x condition x task {row}; expected exactly one per cell"
        )

    out = frame[keys].copy()
    out[measure] = values
    out["interface"] = conditions.map(lambda c: factors(c)[0])
    out["assistance"] = conditions.map(lambda c: factors(c)[1])
    return out


def check_participants(data: pd.DataFrame) -> int:
    """The number of participants in prepared ``data``; fewer than 2 is an error."""
    n = data["participant"].nunique()
    if n < 2:
        raise ConfigError(f"need at least 2 participants, got {n}")
    return int(n)


def _check_complete(data: pd.DataFrame, conditions: Sequence[str]) -> None:
    have = data.groupby("participant", sort=True)["condition"].agg(set)
    for participant, present in have.items():
        lacking = [c for c in conditions if c not in present]
        if lacking:
            raise ConfigError(
                f"participant {participant!r} has no data for condition(s) {', '.join(lacking)}; "
                "within-subject tests need every participant in every condition compared"
            )
    tasks = set(data["task"].unique())
    subset = data[data["condition"].isin(list(conditions))]
    cells = subset.groupby(["participant", "condition"], sort=True)["task"].agg(set)
    for (participant, condition), present in cells.items():
        lacking_tasks = sorted(map(str, tasks - present))
        if lacking_tasks:
            raise ConfigError(
                f"participant {participant!r} has no data for task(s) {', '.join(lacking_tasks)} "
                f"in condition {condition!r}; aggregating over tasks needs every task in every cell"
            )


def aggregate(data: pd.DataFrame, measure: str, by: Sequence[str], agg: str) -> pd.DataFrame:
    """One value of ``measure`` per participant x ``by`` levels (``data`` already prepared)."""
    order = {"condition": CONDITIONS, "interface": INTERFACES, "assistance": SA_LEVELS}
    ordered = {name: list(order[name]) for name in by if name in order}
    grouped = data.assign(
        **{k: pd.Categorical(data[k], categories=v, ordered=True) for k, v in ordered.items()}
    )
    out = grouped.groupby(["participant", *by], sort=True, observed=True)[measure].agg(agg).reset_index()
    return out.astype({name: str for name in ordered})


def participant_means(
    frame: pd.DataFrame, measure: str, by: Sequence[str] = ("condition",), agg: str = "mean"
) -> pd.DataFrame:
    """One value of ``measure`` per participant and ``by`` level (``()``: everything), the ``agg``
    (``"mean"``/``"sum"``) of the rest, in the study's order; a ConfigError for invalid data."""
    check_choice("agg", agg, AGGS)
    by = list(by)
    data = prepare(frame, measure)
    unknown = [name for name in by if name not in data.columns or name == "participant" or name == measure]
    if unknown:
        allowed = ["condition", "task", *_DERIVED]
        raise ConfigError(f"cannot group by {', '.join(map(repr, unknown))}; allowed: {allowed}")
    return aggregate(data, measure, by, agg)


def condition_cells(frame: pd.DataFrame, measure: str, agg: str, conditions: Sequence[str]) -> pd.DataFrame:
    """Validated per participant x condition values for ``conditions``, complete and balanced."""
    check_choice("agg", agg, AGGS)
    data = prepare(frame, measure)
    check_participants(data)
    _check_complete(data, conditions)
    data = data[data["condition"].isin(list(conditions))]
    return aggregate(data, measure, ["condition", "interface", "assistance"], agg)
