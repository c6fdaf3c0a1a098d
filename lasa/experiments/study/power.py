"""Who a human replication of the eating study needs: the power of H1-H3's own tests at each cohort size,
the share of cohorts drawn from the simulated participants whose effect's 95% interval excludes 0 on the
whole cohort's side (:func:`power`); :func:`needed`, :func:`sentence`. See ``docs/method-notes.md``."""

from __future__ import annotations

import gc
import math
import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd

from lasa.base.config import NO_ASSISTANCE, check_choice, check_range
from lasa.base.errors import ConfigError
from lasa.evidence.decision import NOT_TESTABLE
from lasa.evidence.hypotheses import TABLES, analyse, for_member, judge
from lasa.evidence.rules import rule
from lasa.pipeline.scaleout import run_jobs

POWER_CLAIMS: tuple[str, ...] = ("h1", "h2", "h3")  # the claim keys of judge whose power is simulated
SIZES: tuple[int, ...] = (6, 10, 16, 24, 40, 60)  # cohort sizes simulated by default [participants]
_CHUNK = 10  # drawn cohorts per job (the progress bar steps by a job) [-]

# what each claim's effect says, by its sign: (above 0, below 0)
_SAYS: dict[str, tuple[str, str]] = {
    "h1": ("SA raises Goal Error", "SA lowers Goal Error"),
    "h2": (
        "LA+SA aligns better than R+SA in the Dessert scoop phase",
        "LA+SA aligns worse than R+SA in the Dessert scoop phase",
    ),
    "h3": ("LA+SA slower than the fastest other condition", "LA+SA faster than the fastest other condition"),
}
_COLUMNS = "claim n power opposite_share untestable_share yes_share direction paper_direction draws".split()


def power(
    frames: dict[str, pd.DataFrame],
    assistance: str,
    decoder: str | None = None,
    model: str | None = None,
    sizes: Sequence[int] = SIZES,
    draws: int = 100,
    seed: int = 0,
    horizon: float = math.inf,
    progress: bool = False,
    n_resamples: int = 500,
    n_jobs: int = 1,
) -> pd.DataFrame:
    """The power of H1-H3's tests per claim and cohort size (:data:`_COLUMNS`) on
    :func:`lasa.experiments.study.run.run`'s ``frames`` of one member, decoder and model (None: the only
    one): ``draws`` cohorts of each of ``sizes`` drawn with replacement from ``seed`` (whatever ``n_jobs``);
    ``horizon`` [s] and ``n_resamples`` are H3's."""
    sizes = list(sizes)
    if not sizes or any(int(n) != n or n < 2 for n in sizes) or len(set(sizes)) != len(sizes):
        raise ConfigError(f"sizes must be distinct whole numbers >= 2 (participants), got {sizes}")
    for name, v, unit in (
        ("draws", draws, ""),
        ("n_resamples", n_resamples, ""),
        ("n_jobs", n_jobs, " (worker processes)"),
    ):
        if int(v) != v or v < 1:
            raise ConfigError(f"{name} must be a whole number >= 1{unit}, got {v!r}")
    sizes = [int(n) for n in sizes]
    tables = _rows_of(frames, assistance, decoder, model)
    setting = (assistance, decoder, model, float(horizon), int(n_resamples))
    full = _outcome(tables, setting, strict=True)
    ids = np.sort(tables["time"].participant.unique())  # the participants drawn from
    rng = np.random.default_rng(seed)
    drawn = [rng.integers(0, len(ids), size=(draws, n)) for n in sizes]
    # the largest cohorts first: the costliest jobs start early and the workers finish together
    by_cost = sorted(range(len(sizes)), key=lambda k: -sizes[k])
    jobs = [(k, drawn[k][i : i + _CHUNK]) for k in by_cost for i in range(0, draws, _CHUNK)]
    results = run_jobs(
        _evaluate, jobs, n_jobs=n_jobs, progress=progress, desc="power", shared=(tables, ids, setting)
    )
    per_size: list[list[dict[str, tuple[int, bool, bool]]]] = [[] for _ in sizes]
    for (k, _), outcomes in zip(jobs, results, strict=True):
        per_size[k].extend(outcomes)
    rows = [
        _row(claim, n, [o[claim] for o in per_size[k]], full[claim])
        for claim in POWER_CLAIMS
        for k, n in enumerate(sizes)
    ]
    return pd.DataFrame(rows, columns=_COLUMNS).astype({"paper_direction": "boolean"})


def _rows_of(
    frames: dict[str, pd.DataFrame], assistance: str, decoder: str | None, model: str | None
) -> dict[str, pd.DataFrame]:
    """The three tables' rows of one member, decoder variant and model (``for_member``), checked."""
    missing = [k for k in TABLES if k not in frames]
    if missing:
        raise ConfigError(f"frames lacks {missing}; pass lasa.experiments.study.run.run's three tables")
    time = frames["time"]
    for name, value, column in (("assistance", assistance, "assistance"), ("decoder", decoder, "decoder")):
        if value is not None and column in time.columns:
            check_choice(name, value, sorted(set(time[column]) - {NO_ASSISTANCE}))
    if model is not None and "model" in time.columns:
        check_choice("participant model", model, sorted(set(time.model)))
    out = {k: for_member(frames[k], assistance, None, decoder, model) for k in TABLES}
    if out["time"].participant.nunique() < 2:
        raise ConfigError(f"the rows of ({assistance}, {decoder}, {model}) have fewer than 2 participants")
    return out


def _drawn(tables: dict[str, pd.DataFrame], ids: np.ndarray, chosen: np.ndarray) -> dict[str, pd.DataFrame]:
    """The tables of a drawn cohort: participant ``ids[chosen[j]]``'s rows as new participant ``j``."""
    out = {}
    for key, frame in tables.items():
        codes = np.searchsorted(ids, frame.participant.to_numpy())
        order = np.argsort(codes, kind="stable")
        starts = np.searchsorted(codes[order], np.arange(len(ids) + 1))
        lengths = np.diff(starts)[chosen]
        ends = np.cumsum(lengths)
        pos = np.repeat(starts[chosen] - ends + lengths, lengths) + np.arange(ends[-1])
        rows = frame.iloc[order[pos]].reset_index(drop=True)
        out[key] = rows.assign(participant=np.repeat(np.arange(len(chosen)), lengths))
    return out


def _outcome(
    tables: dict[str, pd.DataFrame],
    setting: tuple[str, str | None, str | None, float, int],
    strict: bool = False,
) -> dict[str, tuple[float, float, float, str]]:
    """Per claim: a cohort's (value, ci_low, ci_high, verdict); unless ``strict``, errors: not testable."""
    assistance, decoder, model, horizon, n_resamples = setting
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        # exempt the objects alive now from collection while the tests run: statsmodels' Holm
        # correction calls gc.collect() each time (~3x faster, the same results)
        gc.freeze()
        try:
            judged = judge(analyse(tables, assistance, None, decoder, model, horizon, n_resamples))
        except ConfigError:
            if strict:
                raise
            return {c: (math.nan, math.nan, math.nan, NOT_TESTABLE) for c in POWER_CLAIMS}
        finally:
            gc.unfreeze()
    return {c: (judged[c][1], judged[c][2], judged[c][3], judged[c][0]) for c in POWER_CLAIMS}


def _evaluate(
    shared: tuple[dict[str, pd.DataFrame], np.ndarray, tuple], job: tuple[int, np.ndarray]
) -> list[dict[str, tuple[int, bool, bool]]]:
    """Per drawn cohort of the job, per claim: :func:`_side`."""
    tables, ids, setting = shared
    judged = (_outcome(_drawn(tables, ids, chosen), setting) for chosen in job[1])
    return [{claim: _side(claim, *v) for claim, v in one.items()} for one in judged]


def _side(claim: str, value: float, low: float, high: float, verdict: str) -> tuple[int, bool, bool]:
    """(side of 0 the interval lies on, else 0; whether the test could not run; reads yes, settled)."""
    if verdict == NOT_TESTABLE or not (math.isfinite(low) and math.isfinite(high)):
        return 0, True, False
    side = 1 if low > 0.0 else -1 if high < 0.0 else 0
    settled = rule(f"study.{claim}").settled({"effect": (low, high)})
    return side, False, bool(settled and verdict == "yes")


def _row(
    claim: str, n: int, outcomes: list[tuple[int, bool, bool]], full: tuple[float, float, float, str]
) -> dict[str, object]:
    """One row of :func:`power`'s table: a claim at one size, from its drawn cohorts' outcomes."""
    paper = rule(f"study.{claim}").direction
    assert paper is not None
    value, _, _, verdict = full
    testable = verdict != NOT_TESTABLE and math.isfinite(value)
    signed = testable and value != 0.0
    sign = (1 if value > 0.0 else -1) if signed else paper.sign
    says = _SAYS[claim][0 if sign > 0 else 1]
    why = "the whole cohort is not testable" if not testable else "the whole cohort's effect is 0"
    sides = np.array([o[0] for o in outcomes])
    return {
        "claim": claim,
        "n": n,
        "power": float(np.mean(sides == sign)),
        "opposite_share": float(np.mean(sides == -sign)),
        "untestable_share": float(np.mean([o[1] for o in outcomes])),
        "yes_share": float(np.mean([o[2] for o in outcomes])),
        "direction": says if signed else f"{says} (the paper's; {why})",
        "paper_direction": (sign == paper.sign) if signed else pd.NA,
        "draws": len(outcomes),
    }


def needed(table: pd.DataFrame, target: float = 0.8, interpolate: bool = False) -> pd.DataFrame:
    """Per claim of :func:`power`'s ``table``, the smallest cohort from which every size reaches ``target``
    power (``interpolate``: linearly where it crosses, rounded up): ``needed`` (NA if none) and why."""
    check_range("target (a power)", target, 0.0, 1.0, low_open=True, high_open=True)
    lacking = [c for c in _COLUMNS if c not in table.columns]
    if lacking:
        raise ConfigError(f"table lacks {lacking}; pass lasa.experiments.study.power.power's table")
    rows = [
        _needed_row(claim, part.sort_values("n"), target, interpolate)
        for claim, part in table.groupby("claim", sort=False)
    ]
    return pd.DataFrame(rows).astype({"needed": "Int64", "paper_direction": "boolean"})


def _needed_row(claim: str, part: pd.DataFrame, target: float, interpolate: bool) -> dict[str, object]:
    """One claim's row of :func:`needed`, from its rows of :func:`power`'s table sorted by n."""
    n, p = part.n.to_numpy(), part.power.to_numpy(dtype=float)
    short = np.flatnonzero(p < target)
    i = int(short[-1]) + 1 if len(short) else 0  # from here on, every size reaches the target
    head = {"claim": claim, "target": target}
    tail = {"direction": part.direction.iloc[0], "paper_direction": part.paper_direction.iloc[0]}
    early = np.flatnonzero(p[:i] >= target)
    dip = (
        f"; it reached {target:g} at n = {int(n[early[0]])} ({p[early[0]]:.2f}) but fell below it "
        if len(early)
        else ""
    )
    if i == len(n):
        last = part.iloc[-1]
        why = f"power {p[-1]:.2f} at n = {int(n[-1])}, the largest size simulated"
        why += f"{dip}after" if dip else ""
        if last.untestable_share > 0.0:  # a share power cannot reach past
            why += (
                f"; the test cannot run in {100 * last.untestable_share:.0f}% of the drawn cohorts of "
                f"{int(n[-1])} (not testable, e.g. a condition finishing too few episodes)"
            )
        more = {"needed": pd.NA, "needed_text": f"more than {int(n[-1])}", "power": float(p[-1])}
        return head | more | tail | {"explanation": why}
    size, how = float(n[i]), "the smallest simulated size from which every size reaches it"
    if interpolate and i > 0:
        size = n[i - 1] + (target - p[i - 1]) / (p[i] - p[i - 1]) * (n[i] - n[i - 1])
        how = f"interpolated linearly between n = {int(n[i - 1])} ({p[i - 1]:.2f}) and n = {int(n[i])}"
    whole = math.ceil(size - 1e-9)  # rounded up; 1e-9: a float error (12.000000000000002) adds none
    found = {"needed": whole, "needed_text": str(whole), "power": float(p[i])}
    why = f"power {p[i]:.2f} at n = {int(n[i])} and at least {target:g} at every larger size simulated"
    why += f" ({int(part.draws.min())} drawn cohorts each); {how}"
    if dip:
        why += f"{dip}at n = {int(n[short[-1]])} ({p[short[-1]]:.2f})"
    untestable = float(part.untestable_share.iloc[i])
    if untestable > 0.0:
        why += f"; {100 * untestable:.0f}% of the drawn cohorts of {int(n[i])} could not run the test"
    return head | found | tail | {"explanation": why}


def sentence(table: pd.DataFrame, claim: str) -> str:
    """Whom a replication of ``claim`` (``h1``-``h3``) should recruit, from :func:`needed`'s ``table``."""
    check_choice("claim", claim, list(table.claim))
    row = table.set_index("claim").loc[claim]
    pct = f"{100 * row.target:.0f}%"
    if pd.isna(row.paper_direction):
        said = row.direction  # it says why it is the paper's direction
    else:
        said = f"{row.direction}; {'the' if row.paper_direction else 'against the'} paper's direction"
    basis = "this rests on simulated participants' effects and spread, not on people"
    if pd.isna(row.needed):
        largest = row.needed_text.removeprefix("more than ")
        return (
            f"No simulated cohort of up to {largest} gives {claim.upper()} ({said}) {pct} power at "
            f"α = .05: {row.explanation}; {basis}."
        )
    return (
        f"To test {claim.upper()} ({said}) with {pct} power at α = .05, recruit {row.needed} "
        f"participants; {basis}."
    )
