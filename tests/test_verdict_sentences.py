"""The verdict table's result sentences: written from the claims' numbers, never from a note's prose."""

import math

from lasa.evidence.findings import completion_text, finding, short_conditions, study_effect
from lasa.evidence.values import Number

ROBOTS = ("planar5", "panda")
NAN = math.nan


def numbers(**intervals):
    """A row's numbers: each quantity at the middle of its (low, high)."""
    return {k: Number((lo + hi) / 2, lo, hi, 0.9875, 150) for k, (lo, hi) in intervals.items()}


def test_the_gap_sentence_follows_each_robots_intervals():
    # the time gap favours LA+SA at beta = 75 and grows on both robots; the error gap narrows on
    # planar5, and on the Panda LA+SA is worse at beta = 75: that narrowing is not the paper's gap
    values = {
        ("sim1.gap_narrows", "planar5"): numbers(
            time_narrowing=(-0.4, -0.2),
            time_gap_75=(0.1, 0.2),
            error_narrowing=(0.01, 0.02),
            error_gap_75=(0.02, 0.05),
        ),
        ("sim1.gap_narrows", "panda"): numbers(
            time_narrowing=(-0.4, -0.3),
            time_gap_75=(0.1, 0.3),
            error_narrowing=(0.01, 0.02),
            error_gap_75=(-0.05, -0.02),
        ),
    }
    assert finding("sim1.gap_narrows", values, ROBOTS) == (
        "the time gap grows (both robots); the error gap narrows (planar5); "
        "LA+SA is worse in error at beta = 75 (the Panda)"
    )
    both = numbers(
        time_narrowing=(0.1, 0.2), time_gap_75=(0.3, 0.4), error_narrowing=(0.1, 0.2), error_gap_75=(0.2, 0.3)
    )
    values = {("sim1.gap_narrows", r): both for r in ROBOTS}
    assert (
        finding("sim1.gap_narrows", values, ROBOTS)
        == "the time gap narrows (both robots); the error gap narrows (both robots)"
    )
    assert finding("sim1.gap_narrows", {}, ROBOTS) == ""  # no numbers: no result stated


def test_the_time_ratio_and_sim4_sentences_read_each_interval_against_its_reference():
    values = {
        ("sim1.time_ratio", "planar5"): numbers(ratio_75=(0.8, 1.1), ratio_1000=(1.3, 1.4)),
        ("sim1.time_ratio", "panda"): numbers(ratio_75=(0.7, 0.9), ratio_1000=(1.2, 1.5)),
    }
    assert finding("sim1.time_ratio", values, ROBOTS) == (
        "at beta = 1000 LA+SA is faster (both robots); at beta = 75 no clear gain (planar5); "
        "at beta = 75 LA+SA is slower (the Panda)"
    )
    sim4 = {("sim4.straight_line_linear", "panda"): numbers(slope=(-0.1, 0.2))}
    assert (
        finding("sim4.straight_line_linear", sim4, ROBOTS)
        == "no measurable growth with the distance (the Panda)"
    )


def study(value, low, high, n, **facts):
    out = {"effect": Number(value, low, high, 0.95, n)}
    return out | {k: Number(v, n=n) for k, v in ({"testable": 1.0, "censored": 0.0} | facts).items()}


def test_the_study_effect_is_written_from_its_numbers():
    h1 = study(-2.04, -2.8, -1.3, 10, difference=-2.04, F=36.4, df1=1, df2=9, p=2e-4)
    assert study_effect("study.h1", h1) == "SA lowers Goal Error by -2.04 m s, F(1,9) = 36.4, p < .001"
    mean = study(0.5, 0.1, 0.9, 10, difference=1.5, F=8.0, df1=1, df2=9, p=0.0196, censored=1.0)
    said = study_effect("study.h1@mean_distance+cohort", mean)
    assert said == "SA raises the mean distance by at least +1.50 cm, F(1,9) = 8.00, p = .020"
    h2 = study(-0.062, -0.11, -0.01, 10, difference=-0.062, p=0.0336, pairs=10)
    assert study_effect("study.h2", h2) == (
        "LA+SA's scoop alignment is below R+SA's by -0.062, paired t, 10 pairs, p = 0.0336"
    )
    assert study_effect("study.h2", study(NAN, NAN, NAN, 10, difference=NAN, p=NAN, pairs=1)) == (
        "no scoop-phase comparison (1 pairs)"
    )
    h3 = study(36.6, 29.8, 44.9, 10, **{"versus.R": 80.0})
    assert (
        study_effect("study.h3", h3) == "LA+SA is slower than R by +36.6 s [+29.8, +44.9] (restricted means)"
    )
    assert study_effect("study.h3", study(NAN, NAN, NAN, 10)).startswith("no contrast")


def test_the_study_sentences_say_what_each_n_tells_and_what_was_cut():
    def rows(head, cohort=None, cid="study.h2"):
        out = {(cid, "panda"): head}
        return out | ({(f"{cid}@cohort", "panda"): cohort} if cohort is not None else {})

    undecided, told = study(0.02, -0.01, 0.05, 10), study(0.045, 0.03, 0.06, 40)
    assert finding("study.h2", rows(undecided, told), ROBOTS) == (
        "LA+SA tilts the fork further into the scoop than R+SA; "
        "10 simulated participants cannot tell, 40 tell it"
    )
    assert finding("study.h2", rows(study(0.03, 0.01, 0.05, 10), told), ROBOTS).endswith(
        "; 10 and 40 simulated participants alike tell it"
    )
    other = study(-0.045, -0.06, -0.03, 40)
    assert finding("study.h2", rows(undecided, other), ROBOTS).startswith(
        "R+SA tilts the fork further into the scoop than LA+SA; 10 simulated participants cannot tell"
    )
    done = {"completion.R": 1.0, "completion.R+SA": 1.0, "completion.LA": 0.9, "completion.LA+SA": 0.45}
    cut = study(NAN, NAN, NAN, 10, testable=0.0, **done)
    assert finding("study.h1", rows(cut, cid="study.h1"), ROBOTS) == (
        "simulated participants finish 90% of their LA episodes and 45% of their LA+SA episodes: "
        "the rest are cut, Goal Error censored"
    )
    assert finding("study.h3", rows(cut, cid="study.h3"), ROBOTS) == (
        "LA finishes 90% of its episodes, LA+SA finishes 45% of its episodes: the assistance holds "
        "simulated participants at a bowl"
    )
    # a censored lower bound that already decides H3: judged, so what each N tells
    bound = study(36.0, 25.0, 88.0, 10, censored=1.0, **done)
    assert finding("study.h3", rows(bound, cid="study.h3"), ROBOTS).startswith(
        "another condition is faster than LA+SA; 10 simulated participants tell it"
    )


def test_short_arms_are_those_below_the_completion_bar():
    facts = {"completion.R": Number(1.0), "completion.LA": Number(0.2), "completion.LA+SA": Number(0.95)}
    assert short_conditions(facts) == [("LA", 0.2)]
    assert completion_text([("LA", 0.2), ("LA+SA", 0.455)]) == "LA 20%, LA+SA 45.5%"


def test_a_censored_effect_says_so_from_its_fact_not_its_text():
    import pandas as pd

    from lasa.evidence.claims import effect_text

    row = pd.Series({"effect": "not reproduced", "figure": "study", "measured": "anything"})
    assert effect_text(row, study(36.0, 25.0, 88.0, 10, censored=1.0)) == (
        "not reproduced (censored: lower bound) by simulated participants"
    )
    assert effect_text(row, study(36.0, 25.0, 88.0, 10)) == "not reproduced by simulated participants"
    sim = pd.Series({"effect": "undecided", "figure": "sim1", "measured": "censored: lower bound"})
    assert effect_text(sim, {}) == "undecided"
