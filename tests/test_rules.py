"""lasa.evidence.rules: every rule against hand-computed cases, and settledness on boxes of intervals."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lasa.base.errors import ConfigError
from lasa.evidence.rules import RULES, rule


@pytest.mark.parametrize(
    ("cid", "values", "verdict"),
    [
        ("sim1.final_error", {"share_lower": 1.0}, "yes"),
        ("sim1.final_error", {"share_lower": 0.6}, "partly"),
        ("sim1.final_error", {"share_lower": 0.5}, "no"),  # "more than half"
        # the effect only: LA slower at both betas, whatever the paper's sizes (those are the number)
        ("sim1.time_ratio", {"ratio_75": 1.45, "ratio_1000": 1.30}, "yes"),
        ("sim1.time_ratio", {"ratio_75": 2.5, "ratio_1000": 1.01}, "yes"),
        ("sim1.time_ratio", {"ratio_75": 0.98, "ratio_1000": 1.35}, "partly"),
        ("sim1.time_ratio", {"ratio_75": 0.98, "ratio_1000": 0.9}, "no"),
        # each gap must favour LA+SA at beta = 75 and be smaller in size at 1000
        (
            "sim1.gap_narrows",
            {"time_narrowing": 0.1, "time_gap_75": 0.45, "error_narrowing": 0.2, "error_gap_75": 0.3},
            "yes",
        ),
        (
            "sim1.gap_narrows",
            {"time_narrowing": -0.3, "time_gap_75": 0.05, "error_narrowing": 0.2, "error_gap_75": 0.3},
            "partly",
        ),
        # an error gap in which LA+SA is worse, shrinking: not the paper's gap, so that part fails
        (
            "sim1.gap_narrows",
            {"time_narrowing": -0.3, "time_gap_75": 0.05, "error_narrowing": 0.02, "error_gap_75": -0.1},
            "no",
        ),
        ("sim1.entropy_sa", {"share_weaker": 0.1}, "no"),
        # the paper's two parts: final error grows, confidence falls with N
        ("sim2.sa_trapped", {"error_growth": 0.5, "confidence_drop": 0.6}, "yes"),
        ("sim2.sa_trapped", {"error_growth": 0.5, "confidence_drop": -0.01}, "partly"),
        ("sim2.sa_trapped", {"error_growth": 0.0, "confidence_drop": 0.0}, "no"),
        ("sim2.entropy_escapes", {"success_entropy": 0.97, "margin": 0.9}, "yes"),
        ("sim2.entropy_escapes", {"success_entropy": 0.7, "margin": 0.1}, "partly"),
        ("sim3.entropy_learners", {"gain_fast": 0.2, "gain_slow": -0.01}, "partly"),
        ("sim4.grasp_linear", {"slope": 0.1, "r2": 0.95, "share_below": 1.0}, "yes"),
        ("sim4.grasp_linear", {"slope": 1.3, "r2": 0.95, "share_below": 1.0}, "yes"),  # size: the number
        ("sim4.grasp_linear", {"slope": -0.001, "r2": 0.05, "share_below": 1.0}, "partly"),
        ("sim4.straight_line_linear", {"slope": 0.1, "r2": 0.95, "share_below": 0.8}, "partly"),
        ("sim4.straight_line_linear", {"slope": 0.1, "r2": 0.5, "share_below": 0.8}, "no"),
        ("sim4.no_map_training_goal", {"slope": 1.1, "r2": 0.99}, "yes"),
        ("sim4.no_map_training_goal", {"slope": 1.55, "r2": 0.99}, "yes"),  # y = x's size: the number
        ("sim4.no_map_training_goal", {"slope": 1.0, "r2": 0.5}, "no"),
    ],
)
def test_rules_against_hand_computed_cases(cid, values, verdict):
    assert rule(cid).verdict(values) == verdict


def test_a_reading_finds_its_claims_rule_and_an_unknown_claim_is_an_error():
    assert rule("sim1.time_ratio@grasp_set") is RULES["sim1.time_ratio"]
    with pytest.raises(ConfigError, match="no rule for claim"):
        rule("sim9.nothing")
    with pytest.raises(ConfigError, match="needs"):
        rule("sim1.time_ratio").verdict({"ratio_75": 1.0})


def test_settled_needs_every_interval_clear_of_the_thresholds_that_matter():
    r = rule("sim1.time_ratio")
    assert r.settled({"ratio_75": (1.35, 1.55), "ratio_1000": (1.2, 1.4)})  # yes everywhere
    assert not r.settled({"ratio_75": (0.95, 1.55), "ratio_1000": (1.2, 1.4)})  # 1 inside: yes or partly
    # both below 1 decide "no"; a paper number's band (1.30 +- 0.15) is no threshold of the effect
    assert r.settled({"ratio_75": (0.8, 0.95), "ratio_1000": (0.5, 0.9)})
    assert r.settled({"ratio_75": (1.1, 1.7), "ratio_1000": (1.01, 1.5)})
    assert r.verdicts_in({"ratio_75": (0.9, 1.1), "ratio_1000": (1.2, 1.4)}) == {"yes", "partly"}
    assert not r.settled({"ratio_75": (math.nan, 1.0), "ratio_1000": (1.2, 1.4)})  # unknown decides nothing
    share = rule("sim1.final_error")
    assert share.settled({"share_lower": (1.0, 1.0)})  # an interval at a threshold's value, not across it
    assert not share.settled({"share_lower": (0.8, 1.0)})
    assert share.straddled({"share_lower": (0.8, 1.0)}) == ["share_lower [0.8, 1] reaches 1"]


@settings(max_examples=200, deadline=None)
@given(st.sampled_from(sorted(RULES)), st.data())
def test_every_rule_is_constant_between_its_thresholds(cid, data):
    """Moving a number without crossing one of its thresholds never changes a verdict:
    the thresholds named are all the rule reads, which is what makes `settled` sound."""
    r = RULES[cid]
    values, moved = {}, {}
    for q in r.quantities:
        cuts = sorted({-1e3, *q.thresholds, 1e3})
        k = data.draw(st.integers(0, len(cuts) - 2))
        lo, hi = cuts[k], cuts[k + 1]
        a, b = data.draw(st.floats(0.01, 0.99)), data.draw(st.floats(0.01, 0.99))
        values[q.name] = lo + a * (hi - lo)
        moved[q.name] = lo + b * (hi - lo)
    assert r.verdict(values) == r.verdict(moved)
    box = {n: (min(values[n], moved[n]), max(values[n], moved[n])) for n in values}
    assert r.settled(box)


def test_not_testable_is_exported_and_h3_states_its_guard_and_its_late_change():
    import lasa.evidence.decision as decision
    import lasa.evidence.rules as rules

    assert decision.NOT_TESTABLE == "not testable"
    assert (
        decision.NOT_TESTABLE not in decision.VERDICTS
    )  # never a rule's: the data's precondition decides it
    text = rule("study.h3").text
    assert "95%" in text and "restricted mean" in text and "bootstrap" in text and "t-test" not in text
    late = rules.AFTER_RESULTS["study.h3"]
    assert "censored" in late and "t-tests on times capped" in late and "95%" in late
    h3 = rule("study.h3@one_step")
    assert h3.verdict({"effect": -1.0}) == "yes" and h3.settled({"effect": (-9.0, -0.5)})
    assert not h3.settled({"effect": (-9.0, 0.5)})  # the fastest-other gap's interval straddles 0


@pytest.mark.parametrize(
    ("cid", "results", "verdict"),
    [
        # H1: the main effect and both pairwise comparisons, below 0 and significant
        ("study.h1", {"effect": -1.0, "p": 0.01, "effect a - b": -0.5, "p a - b": 0.04}, "yes"),
        ("study.h1", {"effect": -1.0, "p": 0.01, "effect a - b": -0.5, "p a - b": 0.05}, "partly"),
        ("study.h1", {"effect": -1.0, "p": 0.01, "effect a - b": 0.5, "p a - b": 0.01}, "partly"),
        ("study.h1", {"effect": -1.0, "p": 0.05, "effect a - b": -0.5, "p a - b": 0.01}, "no"),
        ("study.h1", {"effect": 1.0, "p": 0.01}, "no"),
        ("study.h1@paper_test", {"effect": -1.0, "p": 0.01}, "yes"),  # no comparisons: yes or no
        # H2: above 0, significant or not
        ("study.h2", {"effect": 0.02, "p": 0.01}, "yes"),
        ("study.h2", {"effect": 0.02, "p": 0.2}, "partly"),
        ("study.h2", {"effect": -0.02, "p": 0.01}, "no"),
        ("study.h2", {"effect": math.nan, "p": math.nan}, "no"),  # too few pairs
        # H3: every contrast's interval below 0; else LA+SA's restricted mean the lowest
        (
            "study.h3",
            {"high t LA+SA - R": -1.0, "high i LA+SA - R": -0.1, "mean R": 9.0, "mean LA+SA": 5.0},
            "yes",
        ),
        (
            "study.h3",
            {"high t LA+SA - R": -1.0, "high i LA+SA - R": 0.1, "mean R": 9.0, "mean LA+SA": 5.0},
            "partly",
        ),
        (
            "study.h3",
            {"high t LA+SA - R": 1.0, "mean R": 5.0, "mean LA+SA": 5.0},
            "no",
        ),  # a tie is not the lowest
    ],
)
def test_the_studys_tests_decide_yes_partly_no(cid, results, verdict):
    assert rule(cid).tested(results) == verdict


def test_a_rule_without_tests_has_no_tested_verdict():
    with pytest.raises(ConfigError, match="rests on no tests"):
        rule("sim1.final_error").tested({"share_lower": 1.0})


def test_an_interval_ending_within_a_fifth_of_its_width_of_a_threshold_is_fragile():
    r = rule("sim1.time_ratio")  # thresholds 1 on both ratios; paper 1.45 ± 0.15 and 1.3 ± 0.15
    far = {"ratio_75": (1.2, 1.25), "ratio_1000": (1.9, 2.0)}  # no end within 0.01 / 0.02 of an edge
    assert r.fragile(far) == []
    # width 0.1, margin 0.02: 1.01 is 0.01 from the threshold 1
    near = {"ratio_75": (1.01, 1.11), "ratio_1000": (1.9, 2.0)}
    assert r.fragile(near) == ["ratio_75 [1.01, 1.11] ends 0.01 from 1"]
    # the paper number's band edge counts too: 1.3 + 0.15 = 1.45, 0.015 from 1.465 (margin 0.02)
    band = {"ratio_75": (1.2, 1.25), "ratio_1000": (1.365, 1.465)}
    assert r.fragile(band) == ["ratio_1000 [1.36, 1.47] ends 0.015 from 1.45"]
    # just outside the margin (0.021 > 0.02), and a zero-width interval, are not fragile
    assert r.fragile({"ratio_75": (1.021, 1.121), "ratio_1000": (1.9, 2.0)}) == []
    assert r.fragile({"ratio_75": (1.0, 1.0), "ratio_1000": (1.9, 2.0)}) == []


def test_an_unknown_interval_is_not_fragile():
    r = rule("sim1.time_ratio")
    assert r.fragile({"ratio_75": (math.nan, 1.0), "ratio_1000": (1.9, 2.0)}) == []
