"""The user study's statistical tests on its 2x2 design: the SA effect as the paper's F(1,18) (2N observations
as independent) and as the design's repeated-measures F(1, N-1), Holm-corrected paired t-tests, and restricted
mean times with a paired bootstrap. F and p come from statsmodels and scipy."""

from __future__ import annotations

import gc
from collections.abc import Sequence
from itertools import combinations
from typing import Any

import numpy as np
import pandas as pd
import scipy.stats
from statsmodels.formula.api import ols
from statsmodels.stats.anova import AnovaRM, anova_lm
from statsmodels.stats.multitest import multipletests

from lasa.base.conditions import CONDITIONS
from lasa.base.errors import ConfigError
from lasa.evidence.study_design import (
    SA_LEVELS,
    aggregate,
    check_participants,
    condition_cells,
    factors,
    prepare,
)

EFFECTS: tuple[str, ...] = ("interface", "assistance", "interface:assistance")  # rm_anova's rows, in order

# what sa_effect_between and sa_effect_within return, in order
RESULT_KEYS = ("test", "F", "df1", "df2", "p", "n", "mean_sa", "mean_no_sa", "ci_low", "ci_high")
BETWEEN_TEST = "between-subjects one-way ANOVA on 2N participant means (the paper's F(1,18) reading)"
WITHIN_TEST = "within-subjects 2x2 repeated-measures ANOVA, SA main effect"


def sa_effect_between(frame: pd.DataFrame, measure: str) -> dict[str, Any]:
    """The SA effect as the paper's F(1,18), a one-way ANOVA on 2N participant means, df (1, 2N-2), as
    :data:`RESULT_KEYS` (``ci_*``: SA - no SA, 95%, pooled t); a participant lacking either is an error."""
    data = prepare(frame, measure)
    n = check_participants(data)
    means = aggregate(data, measure, ["assistance"], "mean")
    counts = means.groupby("participant")["assistance"].agg(set)
    for participant, present in counts.items():
        if lacking := [level for level in SA_LEVELS if level not in present]:
            conditions = [c for c in CONDITIONS if factors(c)[1] in lacking]
            raise ConfigError(
                f"participant {participant!r} has no rows with assistance {lacking[0]!r} "
                f"(condition(s) {', '.join(conditions)}); each participant needs a mean with and without SA"
            )
    table = pd.DataFrame({"y": means[measure].to_numpy(), "sa": means["assistance"].to_numpy()})
    fit = anova_lm(ols("y ~ C(sa)", data=table).fit())
    row = fit.loc["C(sa)"]
    sa, no_sa = table.loc[table["sa"] == "SA", "y"], table.loc[table["sa"] == "none", "y"]
    ci = scipy.stats.ttest_ind(sa, no_sa).confidence_interval()
    df = (int(round(float(row["df"]))), int(round(float(fit.loc["Residual", "df"]))))
    return _sa_result(BETWEEN_TEST, float(row["F"]), df, float(row["PR(>F)"]), n, sa, no_sa, ci)


def _sa_result(
    test: str, f: float, df: tuple[int, int], p: float, n: int, sa: pd.Series, no_sa: pd.Series, ci: Any
) -> dict[str, Any]:
    cells = (test, f, *df, p, n, float(sa.mean()), float(no_sa.mean()), float(ci.low), float(ci.high))
    return dict(zip(RESULT_KEYS, cells, strict=True))


def rm_anova(frame: pd.DataFrame, measure: str, agg: str = "mean") -> pd.DataFrame:
    """Two-way (interface x assistance) repeated-measures ANOVA, participants as subjects, on tasks
    aggregated by ``agg``: per effect of :data:`EFFECTS` its ``F``, ``df1``, ``df2`` (1, N-1) and ``p``."""
    cells = condition_cells(frame, measure, agg, CONDITIONS)
    table = AnovaRM(cells, depvar=measure, subject="participant", within=["interface", "assistance"]).fit()
    rows = [table.anova_table.loc[effect] for effect in EFFECTS]
    column = {"F": "F Value", "df1": "Num DF", "df2": "Den DF", "p": "Pr > F"}
    out = {key: [float(r[name]) for r in rows] for key, name in column.items()}
    degrees = {key: [int(round(x)) for x in out[key]] for key in ("df1", "df2")}
    return pd.DataFrame({"effect": list(EFFECTS)} | out | degrees)


def sa_effect_within(frame: pd.DataFrame, measure: str) -> dict[str, Any]:
    """The SA main effect of the 2x2 repeated-measures ANOVA (:func:`rm_anova`, task means), as
    :func:`sa_effect_between` returns it, with df (1, N-1) and ``ci_*`` a paired t over participants."""
    row = rm_anova(frame, measure, agg="mean").set_index("effect").loc["assistance"]
    cells = condition_cells(frame, measure, "mean", CONDITIONS)
    per_participant = cells.groupby(["participant", "assistance"])[measure].mean().unstack("assistance")
    # the 95% interval of SA - no SA: a paired t over participants (its t^2 is the main effect's F)
    sa, no_sa = per_participant["SA"], per_participant["none"]
    ci = scipy.stats.ttest_rel(sa, no_sa).confidence_interval()
    df, n = (int(row["df1"]), int(row["df2"])), int(len(per_participant))
    return _sa_result(WITHIN_TEST, float(row["F"]), df, float(row["p"]), n, sa, no_sa, ci)


def pairwise(
    frame: pd.DataFrame,
    measure: str,
    agg: str = "mean",
    pairs: Sequence[tuple[str, str]] | None = None,
    correction: str = "holm",
) -> pd.DataFrame:
    """Paired t-tests between conditions on per-participant values (``agg`` over tasks), corrected across
    the ``pairs`` (default all 6) by a ``multipletests`` method or ``"none"`` (non-finite p left out): per
    pair ``a``, ``b``, ``mean_a``, ``mean_b``, ``diff`` (``mean_a - mean_b``), ``t`` (positive when ``a``
    is larger), ``df`` (N-1), ``p_unc``, ``p_corr``, ``correction``."""
    chosen = [tuple(pair) for pair in (combinations(CONDITIONS, 2) if pairs is None else pairs)]
    if not chosen:
        raise ConfigError("pairs is empty; give at least one (a, b) pair of conditions")
    for pair in chosen:
        if len(pair) != 2:
            raise ConfigError(f"each pair must be (a, b), got {pair!r}")
        for condition in pair:
            factors(condition)
        if pair[0] == pair[1]:
            raise ConfigError(f"pair {pair!r} compares a condition with itself")
    used = [c for c in CONDITIONS if any(c in pair for pair in chosen)]
    cells = condition_cells(frame, measure, agg, used)
    wide = cells.pivot(index="participant", columns="condition", values=measure)
    rows = []
    for a, b in chosen:
        x, y = wide[a].to_numpy(dtype=float), wide[b].to_numpy(dtype=float)
        test = scipy.stats.ttest_rel(x, y)
        means = {"mean_a": float(x.mean()), "mean_b": float(y.mean()), "diff": float(x.mean() - y.mean())}
        tested = {"t": float(test.statistic), "df": len(x) - 1, "p_unc": float(test.pvalue)}
        rows.append({"a": a, "b": b, **means, **tested})
    out = pd.DataFrame(rows)
    out["p_corr"] = _corrected(out["p_unc"].to_numpy(dtype=float), correction)
    out["correction"] = correction
    return out


def _corrected(p_unc: np.ndarray, correction: str) -> np.ndarray:
    """The finite ``p_unc`` corrected by ``correction``, the live objects frozen meanwhile (and thawed
    after): statsmodels' Holm branch calls ``gc.collect()``, which scans every object of a large process."""
    p_corr = p_unc.copy()
    finite = np.isfinite(p_unc)
    if correction == "none" or not finite.any():
        return p_corr
    already = gc.get_freeze_count() > 0
    if not already:
        gc.freeze()
    try:
        p_corr[finite] = np.asarray(multipletests(p_unc[finite], method=correction)[1])
    except ValueError as error:
        raise ConfigError(
            f"unknown correction {correction!r}: {error}; use a multipletests method or 'none'"
        ) from error
    finally:
        if not already:
            gc.unfreeze()
    return p_corr


def paired_bootstrap(
    diffs: np.ndarray, n_resamples: int = 10_000, seed: int = 0, level: float = 0.95
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(mean, low, high)`` of paired differences ``(participants[, contrasts])``, a percentile bootstrap
    interval at ``level``, every contrast resampled with the same participants."""
    x = np.asarray(diffs, dtype=float)
    if x.ndim not in (1, 2) or len(x) < 2:
        raise ConfigError(f"diffs must be (participants[, contrasts]) with >= 2 participants, got {x.shape}")
    if not np.isfinite(x).all():
        raise ConfigError("diffs has non-finite values; drop the participants without a pair first")
    if n_resamples < 1 or not 0 < level < 1:
        raise ConfigError(f"need n_resamples >= 1 and level in (0, 1), got {n_resamples} and {level}")
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, len(x), size=(n_resamples, len(x)))
    means = x[idx].mean(axis=1)  # (n_resamples[, contrasts])
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(means, [tail, 100 - tail], axis=0)
    return x.mean(axis=0), low, high


def restricted_times(frame: pd.DataFrame, measure: str, horizon: float = np.inf) -> pd.DataFrame:
    """Each participant's restricted time ``measure`` per condition, ``min(T, horizon)`` [s] summed
    over tasks: participants x :data:`CONDITIONS` (a ConfigError if one lacks a condition or task)."""
    clipped = frame.assign(**{measure: np.minimum(frame[measure].astype(float), horizon)})
    cells = condition_cells(clipped, measure, "sum", CONDITIONS)
    return cells.pivot(index="participant", columns="condition", values=measure)[list(CONDITIONS)]


def rmst_contrasts(
    frame: pd.DataFrame,
    measure: str,
    horizon: float = np.inf,
    reference: str = "LA+SA",
    n_resamples: int = 10_000,
    seed: int = 0,
) -> pd.DataFrame:
    """Restricted mean time of ``reference`` minus each other condition: ``a``, ``b``, ``mean_a``, ``mean_b``,
    ``diff`` (``mean_a - mean_b``), its paired-bootstrap 95% interval ``ci_low``, ``ci_high``, and ``n``."""
    factors(reference)
    wide = restricted_times(frame, measure, horizon)
    others = [c for c in CONDITIONS if c != reference]
    diffs = wide[reference].to_numpy()[:, None] - wide[others].to_numpy()
    mean, low, high = paired_bootstrap(diffs, n_resamples, seed)
    means = {"mean_a": float(wide[reference].mean()), "mean_b": wide[others].mean().to_numpy()}
    bounds = {"diff": mean, "ci_low": low, "ci_high": high, "n": len(wide)}
    return pd.DataFrame({"a": reference, "b": others} | means | bounds)


def format_f(result: dict[str, Any]) -> str:
    """APA-style F report of a dict with ``F``, ``df1``, ``df2`` and ``p``: ``"F(1,9) = 12.3, p = .004"``."""
    if missing := [key for key in ("F", "df1", "df2", "p") if key not in result]:
        raise ConfigError(f"result is missing {', '.join(map(repr, missing))}; got keys {sorted(result)}")
    f_value, p_value = float(result["F"]), float(result["p"])
    f_text = f"{f_value:.1f}" if abs(f_value) >= 10 else f"{f_value:.2f}"
    p_text = "p < .001" if p_value < 0.001 else f"p = {f'{p_value:.3f}'.removeprefix('0')}"
    df = [str(int(x)) if (x := float(result[k])).is_integer() else f"{x:g}" for k in ("df1", "df2")]
    return f"F({df[0]},{df[1]}) = {f_text}, {p_text}"
