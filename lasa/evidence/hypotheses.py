"""The eating study's hypotheses H1-H3: :func:`analyse` runs their tests (:mod:`lasa.evidence.stats`),
:func:`judge` hands each claim's numbers to its rule (:mod:`lasa.evidence.rules`). H1 and H3 are not
testable when a condition finishes fewer than :data:`~lasa.evidence.rules.COMPLETION_BAR` of its episodes."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats as sps

from lasa.base.conditions import CONDITIONS
from lasa.base.config import NO_ASSISTANCE
from lasa.base.errors import ConfigError
from lasa.evidence import stats
from lasa.evidence.decision import CENSORED, NOT_TESTABLE
from lasa.evidence.findings import below_bar, completion_text
from lasa.evidence.rules import COMPLETION_BAR, rule
from lasa.evidence.sessions import complete_participants

_TIMES = ("total_time", "idle_time")  # H3's measures
TABLES = ("goal_error", "time", "alignment")  # the study's tables (lasa.experiments.study.run.run)
# a claim's judgement: (the tests' verdict, value, 95% ci_low, ci_high, measured)
Judged = tuple[str, float, float, float, str]
Result = Mapping[str, Any]  # analyse's numbers by name


def for_member(
    frame: pd.DataFrame,
    assistance: str,
    n: int | None = None,
    decoder: str | None = None,
    model: str | None = None,
) -> pd.DataFrame:
    """The rows of one SA member (and the unassisted ones), decoder, participant model and first ``n``."""
    rows = frame[(frame.assistance == assistance) | (frame.assistance == NO_ASSISTANCE)]
    if decoder is not None and "decoder" in rows.columns:
        rows = rows[(rows.decoder == decoder) | (rows.decoder == NO_ASSISTANCE)]
    if model is not None and "model" in rows.columns:
        rows = rows[rows.model == model]
    if n is not None:
        rows = rows[rows.participant < n]
    return rows.reset_index(drop=True)


def headline_model(time: pd.DataFrame, models: tuple[str, ...]) -> str:
    """The first of ``models`` whose R and R+SA episodes (every member) each finish at least
    :data:`~lasa.evidence.rules.COMPLETION_BAR` of the time, else the first (fixed before any verdict)."""
    if not models:
        raise ConfigError("headline_model needs at least one participant model")
    retarget = time[time.condition.isin(["R", "R+SA"])]
    for model in models:
        done = retarget[retarget.model == model].groupby(["condition", "assistance"]).completed.mean()
        if len(done) and (done >= COMPLETION_BAR).all():
            return model
    return models[0]


def analyse(
    frames: dict[str, pd.DataFrame],
    assistance: str,
    n: int | None = None,
    decoder: str | None = None,
    model: str | None = None,
    horizon: float = math.inf,
    n_resamples: int = 10_000,
) -> dict[str, Any]:
    """Every test the claims rest on, for one SA member, decoder variant, participant model and first ``n``;
    ``horizon`` [s] cuts H3's restricted times, ``n_resamples`` is its paired bootstrap's."""
    err, time, align = (for_member(frames[k], assistance, n, decoder, model) for k in TABLES)
    out: dict[str, Any] = {
        "n": int(err.participant.nunique()),
        "h1_within": stats.sa_effect_within(err, "goal_error"),
        "h1_between": stats.sa_effect_between(err, "goal_error"),
        "h1_rm": stats.rm_anova(err, "goal_error"),
        "h1_pairs": stats.pairwise(err, "goal_error", pairs=[("LA+SA", "LA"), ("R+SA", "R")]),
        "h1_mean_within": stats.sa_effect_within(err, "mean_distance"),
        "h1_mean_pairs": stats.pairwise(err, "mean_distance", pairs=[("LA+SA", "LA"), ("R+SA", "R")]),
    }
    scoop = align[(align.task == "Dessert")]
    wide = scoop.pivot_table(index="participant", columns=["phase", "condition"], values="alignment")
    missing = pd.Series(np.nan, index=wide.index)
    out["h2_phases"] = {
        phase: _paired(wide.get((phase, "LA+SA"), missing), wide.get((phase, "R+SA"), missing))
        for phase in ("stab", "scoop", "dip")
    }
    out.update(_h3(time, horizon, n_resamples))
    return out


def _h3(time: pd.DataFrame, horizon: float, n_resamples: int) -> dict[str, Any]:
    """H3's numbers: completion (``h3_short``: below the bar), restricted means, LA+SA's contrasts."""
    done = time.groupby("condition").completed.mean().reindex(list(CONDITIONS))
    contrasts = {m: stats.rmst_contrasts(time, m, horizon, n_resamples=n_resamples) for m in _TIMES}
    means = pd.DataFrame({m: stats.restricted_times(time, m, horizon).mean() for m in _TIMES})
    best = str(means.total_time.drop("LA+SA").idxmin())
    gap = contrasts["total_time"].set_index("b").loc[best]
    return {
        "h3_completion": done,
        "h3_short": _short_text(done, _censored(done)),
        "h3_total": contrasts["total_time"],
        "h3_idle": contrasts["idle_time"],
        "means": means,
        "h3_gap": (best, float(gap["diff"]), float(gap.ci_low), float(gap.ci_high)),
        "horizon": horizon,
        "n_resamples": n_resamples,
    }


def _paired(a: pd.Series, b: pd.Series) -> tuple[float, float, float, float, int]:
    """Mean of a - b, its 95% t interval, the paired t-test's p, the pairs (< 2 pairs: NaN but the count)."""
    keep = a.notna() & b.notna()
    a, b = a[keep], b[keep]
    if len(a) < 2:
        return np.nan, np.nan, np.nan, np.nan, int(len(a))
    res = sps.ttest_rel(a, b)
    ci = res.confidence_interval()
    return float((a - b).mean()), float(ci.low), float(ci.high), float(res.pvalue), int(len(a))


def people_claims(
    frames: dict[str, pd.DataFrame], horizon: float | None = None, n_resamples: int = 10_000
) -> pd.DataFrame:
    """H1-H3 (and with ``likert`` tests, :func:`likert_verdict`) on people's sessions by the cohort's own
    tests and rules: a row per SA member and claim; ``horizon`` [s] defaults to the sessions' trial limit
    (``frames["limit"]``, from their sidecars: :func:`lasa.evidence.sessions.analyse_sessions`), else to
    the longest Total Time."""
    time = frames["time"]
    if horizon is None:
        limit = frames.get("limit")
        horizon = float(limit.limit_s.min()) if limit is not None else float(time.total_time.max())
    # within-subject tests: those who did every condition in every task (sessions.DROPPED; two or more)
    full = set(complete_participants(time, "claims")[0].participant)
    likert = frames.get("likert")  # people's answers' tests (lasa.evidence.sessions.likert_tests), if any
    frames = {k: frames[k][frames[k].participant.isin(full)] for k in TABLES}
    rows = []
    for assistance in sorted(set(time.assistance) - {NO_ASSISTANCE}) if len(full) >= 2 else []:
        result = analyse(frames, assistance, horizon=horizon, n_resamples=n_resamples)
        rows += [(assistance, claim, *judged, result["n"]) for claim, judged in judge(result).items()]
    if likert is not None and len(likert) and len(full) >= 2:
        verdict, share, n = likert_verdict(likert)
        said = f"LA+SA rated higher with p < .05 in {round(share * n)} of {n} comparisons (scale x condition)"
        rows.append(("all", "likert", verdict, share, math.nan, math.nan, said, len(full)))
    columns = ["member", "claim", "verdict", "value", "ci_low", "ci_high", "measured", "participants"]
    return pd.DataFrame(rows, columns=columns)


def likert_verdict(likert: pd.DataFrame) -> tuple[str, float, int]:
    """``study.likert``'s verdict on people's answers, the share rating LA+SA higher at p < .05, the count."""
    support = (likert["diff"] > 0.0) & (likert["p_corr"] < 0.05)
    share = float(support.mean())
    return rule("study.likert").verdict({"share": share}), share, int(len(likert))


def judge(result: Result) -> dict[str, Judged]:
    """(the claim's rule on its tests' numbers, the effect, its 95% interval, measured) per claim key."""
    out = {
        "h1": _h1(result, "h1_within"),
        "h1_mean_distance": _h1(result, "h1_mean_within", "cm", 100.0),
        "h1_paper_test": _h1(result, "h1_between"),
        "h2": _h2(result),
        "h3": _h3_verdict(result),
    }
    return _censored_goal_error(out, result["h3_completion"])


def _h1(result: Result, name: str, unit: str = "m s", scale: float = 1.0) -> Judged:
    """H1 on the test ``name``: within subjects with its pairwise comparisons (values in ``unit`` by
    ``scale``), or ``h1_between``, the paper's F(1,18) reading (no pairwise comparisons)."""
    between = name == "h1_between"
    test = result[name]
    pairs = [] if between else list(result[name.replace("within", "pairs")].itertuples())
    diff = test["mean_sa"] - test["mean_no_sa"]
    tests = {"effect": diff, "p": test["p"]}
    for r in pairs:
        tests |= {f"effect {r.a} - {r.b}": r.diff, f"p {r.a} - {r.b}": r.p_corr}
    lost = [name for name, v in (tests | {"F": test["F"]}).items() if not math.isfinite(v)]  # e.g. F = -inf
    if lost:
        said = f"{NOT_TESTABLE} (its test could not be computed: {', '.join(lost)} not finite)"
        return NOT_TESTABLE, math.nan, math.nan, math.nan, said
    how = "between, the paper's df" if between else "within"
    said = f"SA - no SA = {scale * diff:+.2f} {unit}; {stats.format_f(test)} ({how})"
    if not between:
        said += "; " + "; ".join(
            f"{r.a} - {r.b} = {scale * r.diff:+.2f} {unit} (p_holm = {r.p_corr:.3g})" for r in pairs
        )
    verdict = rule("study.h1@paper_test" if between else "study.h1").tested(tests)
    return verdict, diff, test["ci_low"], test["ci_high"], said


def _h2(result: Result) -> Judged:
    """H2: scoop-phase alignment LA+SA - R+SA; ``measured`` lists every Dessert phase."""
    phases = result["h2_phases"]
    mean, low, high, p, _ = phases["scoop"]
    text = "; ".join(
        f"{ph}: {m:+.3f} (p = {pp:.3g}, {k} pairs)" if np.isfinite(pp) else f"{ph}: no test ({k} pairs)"
        for ph, (m, _, _, pp, k) in phases.items()
    )
    verdict = rule("study.h2").tested({"effect": mean, "p": p})
    return verdict, mean, low, high, f"alignment LA+SA - R+SA, Dessert phases: {text}"


def _censored(done: pd.Series) -> list[str]:
    """The conditions below the completion bar (NaN too): their measures are lower bounds."""
    return [c for c, _ in below_bar(done.items())]


def _short_text(done: pd.Series, conditions: list[str]) -> str:
    """``"LA 0%, LA+SA 45%"``: the completion of ``conditions``."""
    return completion_text(list(done.reindex(conditions).fillna(0.0).items()))


def _censored_goal_error(out: dict[str, Judged], done: pd.Series) -> dict[str, Judged]:
    """H1 and H2 when some condition finishes too few episodes: H1 ``no`` if only SA conditions are
    censored and SA's Goal Error, a lower bound, is already higher (its interval clear of 0), else (and the
    mean distance always) not testable; H2 not testable when LA+SA or R+SA is censored."""
    censored = _censored(done)
    if not censored:
        return out
    short = _short_text(done, censored)
    sa = {c for c in done.index if str(c).endswith("+SA")}
    for key in ("h1", "h1_mean_distance", "h1_paper_test"):
        verdict, value, low, high, measured = out[key]
        if key != "h1_mean_distance" and set(censored) <= sa and math.isfinite(low) and low > 0.0:
            lead = f"{CENSORED} (completion: {short}): SA's Goal Error, a lower bound, is already higher"
            out[key] = ("no", value, low, high, f"{lead}; {measured}")
        else:
            text = f"{NOT_TESTABLE} (completion: {short}); {measured}"
            out[key] = (NOT_TESTABLE, math.nan, math.nan, math.nan, text)
    compared = [c for c in censored if c in ("LA+SA", "R+SA")]
    if compared:
        gate = f"completion: {_short_text(done, compared)}, alignment only on the phases reached"
        out["h2"] = (NOT_TESTABLE, math.nan, math.nan, math.nan, f"{NOT_TESTABLE} ({gate}); {out['h2'][4]}")
    return out


def _h3_verdict(result: Result) -> Judged:
    """H3: the rule on LA+SA's restricted-mean contrasts, its gap to the fastest other condition."""
    total, idle, means, gap = result["h3_total"], result["h3_idle"], result["means"], result["h3_gap"]
    short, done, horizon = result["h3_short"], result["h3_completion"], result["horizon"]
    to = "uncut" if math.isinf(horizon) else f"restricted to the {horizon:g} s horizon"
    times = ", ".join(
        f"{c} {means.total_time[c]:.0f} s (idle {means.idle_time[c]:.0f} s)" for c in CONDITIONS
    )
    finished = ", ".join(f"{c} {100 * v:.3g}%" for c, v in done.fillna(0.0).items())
    tail = f"mean total (idle) time over both tasks, {to}: {times}; completion: {finished}"
    if short:
        return _h3_censored(result, tail)
    tests = {
        f"high {m} {r.a} - {r.b}": r.ci_high
        for m, contrasts in (("total_time", total), ("idle_time", idle))
        for r in contrasts.itertuples()
    }
    tests |= {f"mean {c}": means.total_time[c] for c in means.index}
    best, g_mean, g_low, g_high = gap
    said = f"LA+SA - {best} (the fastest other) = {g_mean:+.1f} s [{g_low:+.1f}, {g_high:+.1f}] (restricted "
    said += f"means, paired bootstrap); {tail}"
    return rule("study.h3").tested(tests), float(g_mean), float(g_low), float(g_high), said


def _censored_comparator(total: pd.DataFrame, censored: list[str]) -> pd.Series | None:
    """The contrast of LA+SA with the fastest measured comparator clear of 0, None if there is none."""
    clear = total[(total.ci_low > 0.0) & ~total.b.isin(censored)]
    return None if clear.empty else clear.loc[clear.mean_b.idxmin()]


def h3_comparator(result: Result) -> str | None:
    """The condition H3 compares LA+SA with (:func:`_h3_verdict`), None if none."""
    if not result["h3_short"]:
        return str(result["h3_gap"][0])
    r = _censored_comparator(result["h3_total"], _censored(result["h3_completion"]))
    return None if r is None else str(r.b)


def _h3_censored(result: Result, tail: str) -> Judged:
    """H3 with a censored condition: ``no`` if LA+SA's restricted mean Total Time is above a measured
    comparator's (the fastest, interval clear of 0; LA+SA's a lower bound if censored), else not testable."""
    censored = _censored(result["h3_completion"])
    short = result["h3_short"]
    r = _censored_comparator(result["h3_total"], censored)
    if r is None:
        return NOT_TESTABLE, math.nan, math.nan, math.nan, f"{NOT_TESTABLE} (completion: {short}); {tail}"
    bound = "LA+SA" in censored
    lead = CENSORED if bound else "LA+SA measured, the censored conditions not compared"
    said = (
        f"{lead} (completion: {short}): LA+SA's restricted mean Total Time {r.mean_a:.0f} s"
        + (", a lower bound," if bound else "")
        + f" against {r.b}'s {r.mean_b:.0f} s: LA+SA - {r.b} = {r['diff']:+.1f} s "
        f"[{r.ci_low:+.1f}, {r.ci_high:+.1f}] (paired bootstrap); {tail}"
    )
    return "no", float(r["diff"]), float(r.ci_low), float(r.ci_high), said
