r"""The eating study's claims H1-H3 (notebook 11): one row per reading, each with its verdict.

The claims follow the paper's own tests and significance level (p < .05), in the direction the
paper reports (:data:`CLAIM_TEXT`; rules in :mod:`lasa.evidence.rules`, on the numbers of
:mod:`lasa.experiments.study_tests`):

- **H1** (``study.h1``), SA lowers Goal Error: the within-subjects SA main effect of a 2x2
  repeated-measures ANOVA, with both pairwise comparisons; also as mean distance
  (``study.h1_mean_distance``) and as the paper's between-subjects F (``study.h1_paper_test``);
- **H2** (``study.h2``), LA lets users execute their preferences: Dessert scoop alignment,
  LA+SA against R+SA (paired t-test);
- **H3** (``study.h3``), LA+SA is the most efficient: restricted times, paired bootstrap;
  *not testable* when a condition finishes fewer than 95% of its episodes.

:func:`claims` writes one row per reading, ``study.<claim>`` the paper's and
``study.<claim>@<reading>`` each other (:func:`claim_id`); a verdict is settled when the 95%
interval of its effect excludes zero, else ``undecided``. Each rule in full, and when it was
written: ``docs/method-notes.md``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import pandas as pd

from lasa.base.conditions import CONDITIONS
from lasa.base.config import NO_ASSISTANCE
from lasa.evidence import latent_property
from lasa.evidence.claims import Claim, numbers_of
from lasa.evidence.decision import CENSORED, NOT_TESTABLE, UNDECIDED, effect_word, word
from lasa.evidence.findings import study_effect
from lasa.evidence.rules import COMPLETION_BAR, rule
from lasa.evidence.verdicts import shortfall
from lasa.experiments import study_tests
from lasa.experiments.study import PAPER_N
from lasa.experiments.study_tests import Judged, analyse, judge
from lasa.people.design import interface_of

__all__ = [
    "CLAIM_TEXT",
    "DECODER_KEYS",
    "claims",
    "claim_id",
    "figure_stats",
    "h1_table",
    "h2_table",
    "h3_tables",
    "members_table",
    "reading_of",
    "readings_table",
    "untestable_reason",
    "with_flips",
    "likert_row",
    "facts",
]

Analyses = Mapping[tuple, Mapping[str, Any]]  # claims()'s analyses, keyed by reading


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


# readings of each claim key: the claim it belongs to, and the reading's name (None: the paper's)
_KEYS = {
    "h1": ("h1", None),
    "h1_mean_distance": ("h1", "mean_distance"),
    "h1_paper_test": ("h1", "paper_test"),
    "h2": ("h2", None),
    "h3": ("h3", None),
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
    """``study.<claim>`` for the paper's reading, ``study.<claim>@<reading>`` for the others.

    The paper's reading is its measure, the study's belief (Javdani et al.'s cap), the headline
    decoder, the headline participant model, the headline member (hindsight, index 0) and its 10
    participants; every other reading names what differs, joined by ``+`` in that order:
    ``study.h1@mean_distance+grasp_set+cohort``, ``study.h1@uncapped+cohort``,
    ``study.h3@home_entropy``, ``study.h3@one_step``, ``study.h2@transfers_entropy+one_step+cohort``
    (``belief``: another belief than the study's, e.g. ``uncapped``; ``decoder``: a decoder reading
    other than the headline; ``model``: a participant model other than the headline).
    """
    base, measure = _KEYS[key]
    named = None if assistance_index == 0 else assistance  # the headline member goes unnamed
    reading = (measure, belief, decoder, model, named, "cohort" if cohort else None)
    parts = [p for p in reading if p]
    return f"study.{base}" + (f"@{'+'.join(parts)}" if parts else "")


DECODER_KEYS = ("h1", "h2", "h3")  # the claims judged for every other decoder reading (the paper's measures)


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
) -> tuple[list[Claim], dict[tuple, dict[str, object]]]:
    """The claims rows under every reading (measure, member, decoder, participant model, 10 or the cohort).

    Args:
        frames: :func:`lasa.experiments.study.run`'s tables.
        assistance: The SA members, the headline first.
        n_total: The cohort's size (its first :data:`lasa.experiments.study.PAPER_N` are the paper's study).
        decoders: The decoder readings in the frames' ``decoder`` column, the headline first
            (empty: the frames hold one reading). The headline decoder is judged under every
            measure and member; each other one under the paper's measures
            (:data:`DECODER_KEYS`) and the headline member.
        models: The participant models in the frames' ``model`` column, the headline first
            (default: that column's, in order of appearance; none: one model). Each is judged
            as the headline is, its ids naming it (:func:`claim_id`).
        horizon: Where an unfinished episode's time was cut [s] (H3's restricted times).
        untestable: If given, why the study cannot test its hypotheses at all (e.g. no
            decoder has both halves of the property): every row reads ``not testable`` with
            this reason in its note; ``measured`` keeps the numbers.
        untestable_decoders: Decoder reading -> why its rows are not testable, the same way.
        n_resamples: The paired bootstrap's resamples (H3).
        belief: If given, the frames ran with another belief than the study's (``uncapped``):
            every id names it (:func:`claim_id`).
        flips: Lead each headline row's note with the readings whose words differ
            (:func:`with_flips`); off to join these rows with another call's first.

    Returns:
        The rows, and the analyses keyed ``(member, n)`` for the headline decoder and model,
        ``(member, n, decoder)`` for another decoder under the headline model, and
        ``(member, n, decoder, model)`` under every other model (``decoder`` None when the
        frames hold one reading).

    A verdict is settled when its effect's 95% interval lies on one side of zero: then it is the
    tests' verdict (the rules: the module docstring, in full ``docs/method-notes.md``), else ``undecided``
    (never ``not testable``).
    """
    if not models and "model" in frames["time"].columns:
        models = tuple(dict.fromkeys(frames["time"].model))
    head = decoders[0] if decoders else None
    analyses: dict[tuple, dict[str, object]] = {}
    rows: list[Claim] = []
    for k, model in enumerate(models or (None,)):
        for m_i, sa, decoder, n, cohort in _readings(assistance, decoders, n_total):
            if not _ran(frames["time"], model, decoder):
                continue
            other = decoder if decoder != head else None
            reason = untestable or (untestable_decoders or {}).get(str(decoder))
            key = (sa, n, decoder, model) if k else (sa, n, other) if other else (sa, n)
            analyses[key] = result = analyse(frames, sa, n, decoder, model, horizon, n_resamples)
            for name, judged in judge(result).items():
                if other is None or name in DECODER_KEYS:
                    cid = claim_id(name, m_i, sa, cohort, other, model if k else None, belief)
                    rows.append(_claim_row(cid, name, judged, result, sa, decoder, model, reason))
    if belief is None and rows:  # a claim of its own, without readings
        rows.append(likert_row(min(n_total, PAPER_N), assistance[0]))
    return (with_flips(rows) if flips else rows), analyses


def likert_row(n: int, assistance: str) -> Claim:
    """Fig. dessert's subjective claim (the Likert t-tests): not testable with simulated participants,
    who answer no questionnaire; notebook 11 judges it from people's sessions when it reads them."""
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
    """(member, decoder reading, participant model) of an analyses key of :func:`claims`.

    The headline's keys do not name its decoder or model: ``decoder`` and ``model`` are the
    headline's, filled in where the key leaves them out.
    """
    return key[0], key[2] if len(key) > 2 and key[2] else decoder, key[3] if len(key) > 3 else model


def h1_table(analyses: Analyses, decoder: str, model: str) -> pd.DataFrame:
    """H1's tests under every reading: three rows per analysis, unrounded.

    Goal Error by the paper's between-subjects ANOVA and the within-subjects SA effect, and the
    mean distance within subjects; each with its test, F, degrees of freedom, p and the means
    with and without SA.

    Args:
        analyses: :func:`claims`'s analyses.
        decoder: The headline decoder reading.
        model: The headline participant model.
    """
    out = []
    for key, res in analyses.items():
        member, reading, m = reading_of(key, decoder, model)
        for name in ("h1_between", "h1_within", "h1_mean_within"):
            r = res[name]
            measure = "mean distance [m]" if name == "h1_mean_within" else "Goal Error [m s]"
            out.append(
                {
                    "model": m,
                    "decoder": reading,
                    "SA": member,
                    "participants": res["n"],
                    "measure": measure,
                    "test": r["test"],
                    "F": r["F"],
                    "df": f"({r['df1']},{r['df2']})",
                    "p": r["p"],
                    "mean with SA": r["mean_sa"],
                    "mean without": r["mean_no_sa"],
                }
            )
    return pd.DataFrame(out)


def h2_table(analyses: Analyses, decoder: str, model: str) -> pd.DataFrame:
    """H2's paired comparison per reading and Dessert phase, unrounded: LA+SA - R+SA's alignment,
    its interval, p and the participants paired (the arguments are :func:`h1_table`'s)."""
    return pd.DataFrame(
        [
            {
                "model": m,
                "decoder": reading,
                "SA": member,
                "participants": res["n"],
                "phase": ph,
                "LA+SA - R+SA": v[0],
                "ci_low": v[1],
                "ci_high": v[2],
                "p": v[3],
                "pairs": v[4],
            }
            for key, res in analyses.items()
            for member, reading, m in [reading_of(key, decoder, model)]
            for ph, v in res["h2_phases"].items()
        ]
    )


def h3_tables(analyses: Analyses, decoder: str, model: str) -> list[tuple[str, pd.DataFrame, pd.DataFrame]]:
    """H3's times per reading, unrounded: ``(title, means, times)`` per analysis.

    ``title`` names the reading, its participants and, where a condition finishes too few
    episodes, why H3 is not testable; ``means`` is the restricted mean time per participant
    over both tasks [s] with its completion (``finished``), one row per condition; ``times``
    stacks the bootstrap comparisons of LA+SA with each other condition, ``total`` then
    ``idle`` (the arguments are :func:`h1_table`'s).
    """
    out = []
    for key, res in analyses.items():
        member, reading, m = reading_of(key, decoder, model)
        short = f"; H3 not testable (completion: {res['h3_short']})" if res["h3_short"] else ""
        title = (
            f"model = {m}, decoder = {reading}, SA = {member}, {res['n']} participants: restricted mean "
            f"time per participant over both tasks [s], completion{short}"
        )
        means = res["means"].assign(finished=res["h3_completion"])
        out.append((title, means, pd.concat({"total": res["h3_total"], "idle": res["h3_idle"]})))
    return out


def _readings(
    assistance: tuple[str, ...], decoders: tuple[str, ...], n_total: int
) -> list[tuple[int, str, str | None, int, bool]]:
    """(member index, member, decoder, participants, cohort) of each reading a participant model is judged in.

    Every member under the headline decoder, then every other decoder under the headline member;
    each for the first :data:`lasa.experiments.study.PAPER_N` participants and, if larger, the cohort.
    """
    head = decoders[0] if decoders else None
    runs = [(m_i, sa, head) for m_i, sa in enumerate(assistance)]
    runs += [(0, assistance[0], d) for d in decoders[1:]]
    sizes = [(PAPER_N, False)] + ([(n_total, True)] if n_total > PAPER_N else [])
    return [(m_i, sa, decoder, n, cohort) for m_i, sa, decoder in runs for n, cohort in sizes]


def _ran(time: pd.DataFrame, model: str | None, decoder: str | None) -> bool:
    """Whether the time table holds LA episodes of this participant model and decoder reading."""
    rows = time
    if model is not None and "model" in time.columns:
        rows = rows[rows.model == model]
    if decoder is not None and "decoder" in time.columns:
        rows = rows[rows.decoder == decoder]
    return len(rows) > 0


def facts(key: str, result: Mapping[str, object], judged: Judged) -> dict[str, float]:
    """The numbers a row's sentences read beside its effect (``claim_values.csv``'s facts).

    ``testable`` (1 or 0) and ``censored`` (1 when the effect rests on a censored arm's lower
    bound); each condition's completion (``completion.LA``); for H1 the SA - no SA difference in
    the measure's unit (``difference``: m s, or cm for the mean distance) and its test's ``F``,
    ``df1``, ``df2``, ``p``; for H2 the scoop-phase difference, ``p`` and ``pairs``; for H3 the
    compared condition's restricted mean Total Time (``versus.<condition>``, s).
    """
    verdict, _, _, _, measured = judged
    done = result["h3_completion"]
    assert isinstance(done, pd.Series)
    out = {"testable": float(verdict != NOT_TESTABLE), "censored": float(measured.startswith(CENSORED))}
    out |= {f"completion.{c}": float(v) for c, v in done.fillna(0.0).items()}
    if key.startswith("h1"):
        tests = {"h1_paper_test": "h1_between", "h1_mean_distance": "h1_mean_within"}
        test = result[tests.get(key, "h1_within")]
        assert isinstance(test, dict)
        scale = 100.0 if key == "h1_mean_distance" else 1.0
        out["difference"] = scale * float(test["mean_sa"] - test["mean_no_sa"])
        out |= {k: float(test[k]) for k in ("F", "df1", "df2", "p")}
    elif key == "h2":
        phases = result["h2_phases"]
        assert isinstance(phases, dict)
        mean, _, _, p, pairs = phases["scoop"]
        out |= {"difference": float(mean), "p": float(p), "pairs": float(pairs)}
    else:
        other, means = study_tests.h3_comparator(result), result["means"]
        assert isinstance(means, pd.DataFrame)
        if other is not None:
            out[f"versus.{other}"] = float(means.total_time[other])
    return out


def _shortfall(key: str, n: int, result: Mapping[str, object]) -> str:
    """Why the row cannot be settled on its participants (fewer than the paper's :data:`PAPER_N`) or,
    for H3, its bootstrap's resamples (:func:`lasa.evidence.verdicts.shortfall`); "" if it can."""
    resamples = result.get("n_resamples") if key == "h3" else None
    return shortfall(n, resamples, 0.95, min_users=PAPER_N, unit="participants")  # type: ignore[arg-type]


def _claim_row(
    cid: str,
    key: str,
    judged: Judged,
    result: Mapping[str, object],
    assistance: str,
    decoder: str | None,
    model: str | None,
    reason: str | None,
) -> Claim:
    """One claims row: the tests' verdict, settled or undecided, or not testable with its reason.

    Its numbers are its effect with its interval and :func:`facts`; its note starts with
    ``Measured effect: <effect>.``, written from them (:func:`lasa.evidence.findings.study_effect`);
    the claims table puts the row's two words before it (:func:`lasa.evidence.claims.note_lead`).
    """
    verdict, value, low, high, measured = judged
    r = rule(cid)
    numbers = facts(key, result, judged)
    if verdict != NOT_TESTABLE and not (math.isfinite(low) and math.isfinite(high)):
        verdict, measured = NOT_TESTABLE, f"{NOT_TESTABLE} (too few pairs for an interval); {measured}"
    numbers = {k: v for k, v in numbers.items() if math.isfinite(v)}  # F of an uncomputed test
    testable = verdict != NOT_TESTABLE and reason is None
    n = int(result["n"])  # type: ignore[call-overload]
    short = _shortfall(key, n, result)
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
        # an unsettled row says so as every claims row does ("Undecided: ", lasa.evidence.verdicts)
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
    """Each headline row's note led by the readings whose effect differs from it (once per row list).

    The paper states no number the study's rules compare, so the effect is the only word that
    can differ (its number is ``n/a``). A headline without readings (``study.likert``) is left as it is.
    """
    read = {c.id.split("@", 1)[0] for c in rows if "@" in c.id}
    heads = {c.id for c in rows if "@" not in c.id and c.id in read}
    out = []
    for c in rows:
        if c.id in heads:
            flips = [
                f"{o.id.split('@')[1]} (effect {effect_word(o.reproduced)})"
                for o in rows
                if o.id.startswith(c.id + "@") and o.reproduced != c.reproduced
            ]
            lead = (
                f"Readings with other words: {'; '.join(flips)}. "
                if flips
                else "Every reading gives the same words. "
            )
            measured = "Measured effect: "
            effect, rest = c.note.split(". ", 1) if c.note.startswith(measured) else ("", c.note)
            c = dataclasses.replace(c, note=(f"{effect}. " if effect else "") + lead + rest)
        out.append(c)
    return out


def untestable_reason(prop: pd.DataFrame) -> str | None:
    """Why the study cannot test H1-H3, or None: does a decoder meet the property's rule?

    Args:
        prop: :func:`lasa.evidence.latent_property.summary` of the eating decoders.

    Returns:
        None if some decoder has both halves of the property at every goal and reaches every
        goal from home (:func:`lasa.evidence.latent_property.holds`); else a reason naming the
        best reading (:func:`lasa.evidence.latent_property.choose`) and its numbers: the goals
        with both halves and with the stay half, whether every goal is reached from home, its
        least share staying and the fewest inputs that leave a goal for another (LA+SA).
    """
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


def readings_table(
    prop: pd.DataFrame,
    done: pd.DataFrame,
    rows: list[Claim],
    decoders: list[str],
    assistance: str,
    models: tuple[str, ...] = (),
) -> pd.DataFrame:
    """One row per participant model and decoder reading, the headlines first: property, completion, verdicts.

    Args:
        prop: :func:`lasa.evidence.latent_property.summary` of the eating decoders.
        done: :func:`lasa.experiments.study_analysis.completion` of the study's time table.
        rows: The study's claims rows (:func:`claims`).
        decoders: The decoder readings, the headline first.
        assistance: The headline SA member (the assisted conditions' completion is under it).
        models: The participant models, the headline first; default: ``done``'s ``model``
            column in order of appearance (none: one model, and no ``model`` column).

    Columns: ``model`` (with models), ``decoder``, ``headline`` (the headline decoder),
    ``goals with the property``, ``least share staying``, ``R finished``, ``R+SA finished``,
    ``LA finished``, ``LA+SA finished`` (that model's; Retargeting's do not depend on the
    decoder), H1-H3's verdicts for 10 participants / the cohort (``-`` where the study
    had no cohort), and each one's effect for the first 10 in words (``H1 effect (10)``, ...).
    """
    if not models and "model" in done.columns:
        models = tuple(dict.fromkeys(done.model))
    by_id = {c.id: c for c in rows}
    keys = [k for k in ("model", "decoder", "assistance", "condition") if k in done.columns]
    finished = done.set_index(keys).finished
    out = []
    for k, model in enumerate(models or (None,)):
        lead = () if model is None else (model,)
        for d in decoders:
            if not _ran(done, model, d):
                continue
            other = None if d == decoders[0] else d
            mine = prop[prop.decoder == d]
            arms = {
                c: (NO_ASSISTANCE if interface_of(c) == "R" else d, assistance if "+" in c else NO_ASSISTANCE)
                for c in CONDITIONS
            }
            out.append(
                {
                    **({} if model is None else {"model": model}),
                    "decoder": d,
                    "headline": other is None,
                    "goals with the property": int(mine.has_property.sum()),
                    "least share staying": mine.stay_share.min(),
                    **{f"{c} finished": finished.get((*lead, *arms[c], c)) for c in CONDITIONS},
                    **_verdict_cells(by_id, assistance, other, model if k else None),
                }
            )
    return pd.DataFrame(out)


def _verdict_cells(
    by_id: Mapping[str, Claim],
    assistance: str,
    decoder: str | None,
    model: str | None,
    assistance_index: int = 0,
) -> dict[str, str]:
    """H1-H3's verdicts of one reading (:func:`claim_id`'s arguments), ``10 / all``.

    Beside each, ``H<k> effect (10)``: the first 10's effect in words with its sign
    (:func:`lasa.evidence.findings.study_effect`). ``-`` where the study had no such row (no
    cohort beyond the first 10).
    """
    out = {}
    for h in DECODER_KEYS:
        ids = [claim_id(h, assistance_index, assistance, cohort, decoder, model) for cohort in (False, True)]
        out[f"{h.upper()} (10 / all)"] = " / ".join(_word(by_id[i]) if i in by_id else "-" for i in ids)
        out[f"{h.upper()} effect (10)"] = (_effect(by_id[ids[0]]) or "-") if ids[0] in by_id else "-"
    return out


def _effect(row: Claim) -> str:
    """A row's effect in words with its sign and test, from its numbers."""
    return study_effect(row.id, numbers_of(row))


def _word(row: Claim) -> str:
    """A row's word in the claims table's vocabulary, ``(censored: lower bound)`` added where it rests
    on a censored arm."""
    said = word(row.reproduced, {})
    return f"{said} ({CENSORED})" if row.facts.get("censored") == 1.0 else said


def members_table(
    done: pd.DataFrame, rows: list[Claim], assistance: tuple[str, ...], decoder: str, model: str
) -> pd.DataFrame:
    """The SA readings side by side, under the headline decoder and participant model.

    One row per member (the headline first): the assisted conditions' completion (R+SA and
    LA+SA; R and LA do not depend on the member), and H1-H3's verdicts for 10 participants /
    the cohort, each with its effect for the first 10 in words (:func:`lasa.evidence.findings.study_effect`).

    Args:
        done: :func:`lasa.experiments.study_analysis.completion` of the study's time table.
        rows: The study's claims rows (:func:`claims`).
        assistance: The SA members, the headline first.
        decoder: The headline decoder reading.
        model: The headline participant model.
    """
    keys = [k for k in ("model", "decoder", "assistance", "condition") if k in done.columns]
    finished = done.set_index(keys).finished
    by_id = {c.id: c for c in rows}
    out = []
    for m_i, sa in enumerate(assistance):
        cells: dict[str, object] = {"SA": sa, "headline": m_i == 0}
        for c in ("R+SA", "LA+SA"):
            arm = {"model": model, "decoder": NO_ASSISTANCE if c == "R+SA" else decoder}
            arm |= {"assistance": sa, "condition": c}
            cells[f"{c} finished"] = finished.get(tuple(arm[k] for k in keys))
        cells |= _verdict_cells(by_id, sa, None, None, m_i)
        out.append(cells)
    return pd.DataFrame(out)


def figure_stats(rows: list[Claim], n_total: int) -> dict[str, dict[str, str]]:
    """Our result beside the paper's in each study figure: H1, H2, H3's headline rows, 10 and the cohort.

    ``{"h1": {"headline": "ours (10): <word>; <effect>", "cohort": ...}, "h2": ..., "h3": ...}``
    (:func:`lasa.experiments.study_plots.plot_goal_error`'s ``stats``); ``cohort`` only when the
    study has one.
    """
    by_id = {c.id: c for c in rows}
    out: dict[str, dict[str, str]] = {}
    for h in DECODER_KEYS:
        out[h] = {}
        for panel, cohort in (("headline", False), ("cohort", True)):
            row = by_id.get(claim_id(h, 0, "", cohort))
            if row is None or (cohort and n_total <= PAPER_N):
                continue
            out[h][panel] = f"ours ({row.n_users}): {_word(row)}; {_effect(row) or '-'}"
    return out
