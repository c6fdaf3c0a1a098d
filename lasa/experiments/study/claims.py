"""The eating study's claims H1-H3 (notebook 11): a row per reading (:func:`claim_id`), judged by the paper's
tests and direction (:mod:`lasa.evidence.hypotheses`, :mod:`lasa.evidence.rules`), settled when the 95%
interval of its effect excludes zero, else ``undecided``. Each rule in full: ``docs/method-notes.md``."""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import pandas as pd

from lasa.base.conditions import CONDITIONS
from lasa.base.config import NO_ASSISTANCE
from lasa.evidence import latent_property
from lasa.evidence.claims import Claim, numbers_of
from lasa.evidence.decision import CENSORED, NOT_TESTABLE, UNDECIDED, effect_word, word
from lasa.evidence.findings import study_effect
from lasa.evidence.hypotheses import Judged, Result, analyse, h3_comparator, judge
from lasa.evidence.rules import COMPLETION_BAR, rule
from lasa.evidence.verdicts import shortfall
from lasa.experiments.study.run import PAPER_N
from lasa.people.design import interface_of

Analyses = Mapping[tuple, Result]  # claims()'s analyses, keyed by reading

CLAIM_TEXT = {
    "h1": (
        "H1: users with SA maintain their goals more accurately (Goal Error)",
        "F(1,18) = 29.9, p < .001; LA+SA < LA p < .001; R+SA < R p < .05",
    ),
    "h1_mean_distance": (
        "H1 with Goal Error read as the mean distance to the closest goal (the sum over the task / its time)",
        "F(1,18) = 29.9, p < .001 (for the summed distance)",
    ),
    "h1_paper_test": (
        "H1 under the paper's F(1,18) reading (participant means as independent groups)",
        "F(1,18) = 29.9, p < .001",
    ),
    "h2": (
        "H2: LA lets users execute their preferences (Dessert scoop alignment, LA+SA vs R+SA)",
        "R+SA stays in a stabbing orientation; LA+SA adjusts to scoop",
    ),
    "h3": (
        "H3: LA+SA completes the tasks most efficiently (Total and Idle Time)",
        "LA+SA fastest, Total and Idle Time, p < .05 vs each",
    ),
}


def claim_id(
    key: str,
    assistance_index: int,
    assistance: str,
    cohort: bool,
    decoder: str | None = None,
    model: str | None = None,
    belief: str | None = None,
) -> str:
    """``study.<claim>`` for the paper's reading (its measure, the study's belief, the headline decoder,
    model and member, 10 participants), else ``study.<claim>@<reading>``, what differs joined by ``+`` in
    that order: ``study.h1@mean_distance+grasp_set+cohort``, ``study.h2@transfers_entropy+cohort``."""
    base, _, measure = key.partition("_")  # h1_mean_distance: claim h1, reading mean_distance
    named = None if assistance_index == 0 else assistance  # the headline member goes unnamed
    reading = (measure, belief, decoder, model, named, "cohort" if cohort else None)
    parts = [p for p in reading if p]
    return f"study.{base}" + (f"@{'+'.join(parts)}" if parts else "")


PAPER_KEYS = ("h1", "h2", "h3")  # the paper's measures' claims: judged for every decoder variant and cap


def claims(
    frames: dict[str, pd.DataFrame],
    assistance: tuple[str, ...],
    n_total: int,
    decoders: tuple[str, ...] = (),
    *,
    models: tuple[str, ...] = (),
    horizon: float = math.inf,
    untestable: str | None = None,
    untestable_decoders: Mapping[str, str] | None = None,
    n_resamples: int = 10_000,
    belief: str | None = None,
    flips: bool = True,
) -> tuple[list[Claim], dict[tuple, dict[str, Any]]]:
    """The claims rows under every reading (measure, member, decoder, model, n; the headlines first) and
    the analyses keyed ``(member, n)``, ``(member, n, decoder)``, ``(member, n, decoder, model)``;
    ``untestable`` (every row's) and ``untestable_decoders`` say why rows are not testable."""
    if not models and "model" in frames["time"].columns:
        models = tuple(dict.fromkeys(frames["time"].model))
    head = decoders[0] if decoders else None
    runs = [(m_i, sa, head) for m_i, sa in enumerate(assistance)]
    runs += [(0, assistance[0], d) for d in decoders[1:]]
    sizes = [(PAPER_N, False)] + ([(n_total, True)] if n_total > PAPER_N else [])
    analyses: dict[tuple, dict[str, Any]] = {}
    rows: list[Claim] = []
    for k, model in enumerate(models or (None,)):
        for (m_i, sa, decoder), (n, cohort) in itertools.product(runs, sizes):
            if not _ran(frames["time"], model, decoder):
                continue
            other = decoder if decoder != head else None
            reason = untestable or (untestable_decoders or {}).get(str(decoder))
            key = (sa, n, decoder, model) if k else (sa, n, other) if other else (sa, n)
            analyses[key] = result = analyse(frames, sa, n, decoder, model, horizon, n_resamples)
            for name, judged in judge(result).items():
                if other is None or name in PAPER_KEYS:
                    cid = claim_id(name, m_i, sa, cohort, other, model if k else None, belief)
                    rows.append(_claim_row(cid, name, judged, result, sa, decoder, model, reason))
    if belief is None and rows:  # a claim of its own, without readings
        rows.append(likert_row(min(n_total, PAPER_N), assistance[0]))
    return (with_flips(rows) if flips else rows), analyses


def likert_row(n: int, assistance: str) -> Claim:
    """Fig. dessert's subjective claim (the Likert t-tests): not testable with simulated participants."""
    why = "simulated participants answer no questionnaire"
    return Claim(
        id="study.likert",
        claim="H3, subjective: users rate LA+SA above the other conditions (Fig. dessert, Likert)",
        figure="study",
        paper="LA+SA higher, t-tests p < .05",
        measured=f"{NOT_TESTABLE} ({why})",
        reproduced=NOT_TESTABLE,
        note=f"{n} simulated participants; {NOT_TESTABLE} ({why}). Rule: {rule('study.likert').text}.",
        robot="panda",
        assistance=assistance,
        n_users=n,
    )


def reading_of(key: tuple, decoder: str, model: str) -> tuple[str, str, str]:
    """(member, decoder variant, participant model) of a :func:`claims` analyses key, ``decoder`` and
    ``model`` (the headline's) where it leaves them out."""
    return key[0], key[2] if len(key) > 2 and key[2] else decoder, key[3] if len(key) > 3 else model


def _each(analyses: Analyses, decoder: str, model: str) -> Iterator[tuple[dict[str, Any], Mapping[str, Any]]]:
    """Each analysis with its reading's leading columns (``model``, ``decoder``, ``SA``, ``participants``)."""
    for key, res in analyses.items():
        member, variant, m = reading_of(key, decoder, model)
        yield {"model": m, "decoder": variant, "SA": member, "participants": res["n"]}, res


def h1_table(analyses: Analyses, decoder: str, model: str) -> pd.DataFrame:
    """H1's tests (test, F, df, p, means with and without SA) per reading of :func:`claims`'s ``analyses``."""
    out = []
    for who, res in _each(analyses, decoder, model):
        for name in ("h1_between", "h1_within", "h1_mean_within"):
            r = res[name]
            measure = "mean distance [m]" if name == "h1_mean_within" else "Goal Error [m s]"
            test = {"measure": measure, "test": r["test"], "F": r["F"], "df": f"({r['df1']},{r['df2']})"}
            means = {"p": r["p"], "mean with SA": r["mean_sa"], "mean without": r["mean_no_sa"]}
            out.append(who | test | means)
    return pd.DataFrame(out)


def h2_table(analyses: Analyses, decoder: str, model: str) -> pd.DataFrame:
    """H2's LA+SA - R+SA alignment per reading and Dessert phase: interval, p, pairs (``h1_table``'s args)."""
    names = ("LA+SA - R+SA", "ci_low", "ci_high", "p", "pairs")
    return pd.DataFrame(
        [
            who | {"phase": ph} | dict(zip(names, v, strict=True))
            for who, res in _each(analyses, decoder, model)
            for ph, v in res["h2_phases"].items()
        ]
    )


def h3_tables(analyses: Analyses, decoder: str, model: str) -> list[tuple[str, pd.DataFrame, pd.DataFrame]]:
    """H3's ``(title, means, times)`` per reading (``h1_table``'s args): the restricted mean time per
    condition [s] with its completion (``finished``); LA+SA's bootstrap comparisons, total then idle."""
    out = []
    for who, res in _each(analyses, decoder, model):
        short = f"; H3 not testable (completion: {res['h3_short']})" if res["h3_short"] else ""
        title = (
            f"model = {who['model']}, decoder = {who['decoder']}, SA = {who['SA']}, {res['n']} participants: "
            f"restricted mean time per participant over both tasks [s], completion{short}"
        )
        means = res["means"].assign(finished=res["h3_completion"])
        out.append((title, means, pd.concat({"total": res["h3_total"], "idle": res["h3_idle"]})))
    return out


def _ran(time: pd.DataFrame, model: str | None, decoder: str | None) -> bool:
    """Whether the time table holds LA episodes of this participant model and decoder variant."""
    for column, value in (("model", model), ("decoder", decoder)):
        if value is not None and column in time.columns:
            time = time[time[column] == value]
    return len(time) > 0


def facts(key: str, result: Result, judged: Judged) -> dict[str, float]:
    """The numbers a row's sentences read beside its effect (``claim_values.csv``'s facts): ``testable``,
    ``censored``, ``completion.<condition>``, ``difference``, ``F``, ``p`` and so on, H3's ``versus.<c>``."""
    verdict, _, _, _, measured = judged
    out = {"testable": float(verdict != NOT_TESTABLE), "censored": float(measured.startswith(CENSORED))}
    out |= {f"completion.{c}": float(v) for c, v in result["h3_completion"].fillna(0.0).items()}
    if key.startswith("h1"):
        tests = {"h1_paper_test": "h1_between", "h1_mean_distance": "h1_mean_within"}
        test = result[tests.get(key, "h1_within")]
        scale = 100.0 if key == "h1_mean_distance" else 1.0
        out["difference"] = scale * float(test["mean_sa"] - test["mean_no_sa"])
        out |= {k: float(test[k]) for k in ("F", "df1", "df2", "p")}
    elif key == "h2":
        mean, _, _, p, pairs = result["h2_phases"]["scoop"]
        out |= {"difference": float(mean), "p": float(p), "pairs": float(pairs)}
    else:
        other = h3_comparator(result)
        if other is not None:
            out[f"versus.{other}"] = float(result["means"].total_time[other])
    return out


def _claim_row(
    cid: str,
    key: str,
    judged: Judged,
    result: Result,
    assistance: str,
    decoder: str | None,
    model: str | None,
    reason: str | None,
) -> Claim:
    """One claims row: the tests' verdict, settled or undecided, or not testable with its reason."""
    verdict, value, low, high, measured = judged
    r = rule(cid)
    numbers = facts(key, result, judged)
    if verdict != NOT_TESTABLE and not (math.isfinite(low) and math.isfinite(high)):
        verdict, measured = NOT_TESTABLE, f"{NOT_TESTABLE} (too few pairs for an interval); {measured}"
    numbers = {k: v for k, v in numbers.items() if math.isfinite(v)}  # F of an uncomputed test
    testable = verdict != NOT_TESTABLE and reason is None
    n = int(result["n"])
    resamples = result.get("n_resamples") if key == "h3" else None
    short = shortfall(n, resamples, 0.95, min_users=PAPER_N, unit="participants")
    settled = testable and r.settled({"effect": (low, high)}) and not short
    if verdict == NOT_TESTABLE and "too few pairs" in measured:
        why = f"{NOT_TESTABLE} (too few pairs for an interval): fewer than two participants "
        why += "reached the compared phase under both conditions"
    elif verdict == NOT_TESTABLE and "could not be computed" in measured:
        why = measured
    elif verdict == NOT_TESTABLE:
        why = measured.split(";", 1)[0] + ": every compared condition must finish "
        why += f"{100 * COMPLETION_BAR:.0f}% of its episodes before its measure is compared"
    else:
        why = ("" if settled else "Undecided: ") + f"95% interval of the effect [{low:.3g}, {high:.3g}]"
        if short:
            why += f": {short}; the tests read {verdict!r}"
        elif not settled:
            why += f", which straddles 0; the tests read {verdict!r}"
    claim, paper = CLAIM_TEXT[key]
    row = Claim(
        id=cid,
        claim=claim,
        figure="study",
        paper=paper,
        measured=measured,
        reproduced=verdict if settled else NOT_TESTABLE if not testable else UNDECIDED,
        note="",
        robot="panda",
        assistance=assistance,
        value=float(value),
        ci_low=float(low),
        ci_high=float(high),
        settled=settled,
        n_users=n,
        values={"effect": float(value)},
        intervals={"effect": (float(low), float(high))},
        level=0.95,
        facts=numbers | {"testable": float(testable)},
    )
    effect = study_effect(cid, numbers_of(row)) or "none measured"
    note = (
        f"Measured effect: {effect}. "
        + (f"{NOT_TESTABLE} ({reason}). " if reason else "")
        + f"{n} simulated participants; SA = {assistance}; "
        + (f"decoder = {decoder}; " if decoder else "")
        + (f"participant model = {model}; " if model else "")
        + f"{why}. Rule: {r.text}."
    )
    return dataclasses.replace(row, note=note)


def with_flips(rows: list[Claim]) -> list[Claim]:
    """Each headline row's note led by the readings whose effect word differs from it (once per row list)."""
    read = {c.id.split("@", 1)[0] for c in rows if "@" in c.id}  # the headlines with other readings
    out = []
    for c in rows:
        if c.id in read:
            flips = [
                f"{o.id.split('@')[1]} (effect {effect_word(o.reproduced)})"
                for o in rows
                if o.id.startswith(c.id + "@") and o.reproduced != c.reproduced
            ]
            same = "Every reading gives the same words. "
            lead = f"Readings with other words: {'; '.join(flips)}. " if flips else same
            effect, rest = c.note.split(". ", 1) if c.note.startswith("Measured effect: ") else ("", c.note)
            c = dataclasses.replace(c, note=(f"{effect}. " if effect else "") + lead + rest)
        out.append(c)
    return out


def untestable_reason(prop: pd.DataFrame) -> str | None:
    """Why the study cannot test H1-H3 (the best variant's numbers), None if a decoder meets the rule."""
    if latent_property.holds(prop).any():
        return None
    best = latent_property.choose(prop)
    mine = prop[prop.decoder == best]
    both, stay = int(mine.has_property.sum()), int(mine.stay_holds.sum())
    reached = "every" if mine.all_reached.all() else "not every"
    return (
        f"no decoder with both halves of the property; best reading {best}: both halves at {both} of "
        f"{len(mine)} goals, the stay half at {stay}, {reached} goal reached from home, least share staying "
        f"{mine.stay_share.min():.2f}, fewest inputs leaving a goal for another {mine.leave_min.min():.0f} "
        f"of {int(mine.n_inputs.max())}"
    )


def variants_table(
    prop: pd.DataFrame,
    done: pd.DataFrame,
    rows: list[Claim],
    decoders: list[str],
    assistance: str,
    models: tuple[str, ...] = (),
) -> pd.DataFrame:
    """Per participant model and decoder variant, the headlines first: the property (``prop``), completion
    (``done``: :func:`.analysis.completion`) under the headline member, the claims ``rows``' verdicts."""
    if not models and "model" in done.columns:
        models = tuple(dict.fromkeys(done.model))
    by_id = {c.id: c for c in rows}
    out = []
    for k, model in enumerate(models or (None,)):
        for d in decoders:
            if not _ran(done, model, d):
                continue
            other = None if d == decoders[0] else d
            mine = prop[prop.decoder == d]
            out.append(
                {
                    **({} if model is None else {"model": model}),
                    "decoder": d,
                    "headline": other is None,
                    "goals with the property": int(mine.has_property.sum()),
                    "least share staying": mine.stay_share.min(),
                    **_finished(done, model, d, assistance, CONDITIONS),
                    **_verdict_cells(by_id, 0, assistance, other, model if k else None),
                }
            )
    return pd.DataFrame(out)


def _verdict_cells(
    by_id: Mapping[str, Claim], assistance_index: int, assistance: str, decoder: str | None, model: str | None
) -> dict[str, str]:
    """H1-H3's verdicts of one reading (:func:`claim_id`'s args), ``10 / all``, and the first 10's effect."""
    out = {}
    for h in PAPER_KEYS:
        ids = [claim_id(h, assistance_index, assistance, cohort, decoder, model) for cohort in (False, True)]
        out[f"{h.upper()} (10 / all)"] = " / ".join(_word(by_id[i]) if i in by_id else "-" for i in ids)
        out[f"{h.upper()} effect (10)"] = _effect(by_id[ids[0]]) if ids[0] in by_id else "-"
    return out


def _effect(row: Claim) -> str:
    """A row's measured effect in words, ``-`` if none."""
    return study_effect(row.id, numbers_of(row)) or "-"


def _word(row: Claim) -> str:
    """A row's word in the claims table's vocabulary, ``(censored: lower bound)`` added where censored."""
    said = word(row.reproduced, {})
    return f"{said} ({CENSORED})" if row.facts.get("censored") == 1.0 else said


def members_table(
    done: pd.DataFrame, rows: list[Claim], assistance: tuple[str, ...], decoder: str, model: str
) -> pd.DataFrame:
    """The SA members side by side under the headline ``decoder`` and ``model``: R+SA's and LA+SA's
    completion (``done``: :func:`.analysis.completion`) and H1-H3's verdicts (:func:`_verdict_cells`)."""
    by_id = {c.id: c for c in rows}
    return pd.DataFrame(
        [
            {"SA": sa, "headline": m_i == 0}
            | _finished(done, model, decoder, sa, ("R+SA", "LA+SA"))
            | _verdict_cells(by_id, m_i, sa, None, None)
            for m_i, sa in enumerate(assistance)
        ]
    )


def _finished(
    done: pd.DataFrame, model: str | None, decoder: str, assistance: str, conditions: Sequence[str]
) -> dict[str, object]:
    """``<condition> finished``: :func:`.analysis.completion`'s share of each of ``conditions`` under the
    reading (R's rows run no decoder, the unassisted ones no SA member)."""
    keys = [k for k in ("model", "decoder", "assistance", "condition") if k in done.columns]
    finished = done.set_index(keys).finished
    out = {}
    for c in conditions:
        arm = {"model": model, "decoder": NO_ASSISTANCE if interface_of(c) == "R" else decoder}
        arm |= {"assistance": assistance if "+" in c else NO_ASSISTANCE, "condition": c}
        out[f"{c} finished"] = finished.get(tuple(arm[k] for k in keys))
    return out


def figure_stats(rows: list[Claim], n_total: int) -> dict[str, dict[str, str]]:
    """Our result per claim and figure panel (the plots' ``stats``): ``"ours (10): <word>; <effect>"``."""
    by_id = {c.id: c for c in rows}
    panels = (("headline", False), ("cohort", True))[: 2 if n_total > PAPER_N else 1]
    found = {h: {p: by_id.get(claim_id(h, 0, "", cohort)) for p, cohort in panels} for h in PAPER_KEYS}
    return {
        h: {p: f"ours ({r.n_users}): {_word(r)}; {_effect(r)}" for p, r in mine.items() if r is not None}
        for h, mine in found.items()
    }
