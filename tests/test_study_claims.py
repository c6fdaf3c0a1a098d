"""The study's claims rules (lasa.experiments.study) on tables whose answers are known."""

import re
import warnings

import numpy as np
import pandas as pd
import pytest

from lasa.base.conditions import CONDITIONS
from lasa.base.config import NO_ASSISTANCE
from lasa.base.errors import ConfigError
from lasa.evidence import hypotheses
from lasa.experiments.study import analysis, claims
from lasa.experiments.study import run as study

STUDY_ASSISTANCE = ("hindsight", "grasp_set")


def frames(
    n: int, sa_error: float, la_sa_time: float, scoop_gain: float, seed: int = 0
) -> dict[str, pd.DataFrame]:
    """Tidy tables with chosen effects: SA's change of Goal Error, LA+SA's change of time, and
    LA+SA's gain of scoop alignment over R+SA; small participant-level noise."""
    rng = np.random.default_rng(seed)
    err, time, align = [], [], []
    for p in range(n):
        skill = rng.normal(0, 0.5)
        for cond in CONDITIONS:
            for assistance in STUDY_ASSISTANCE if cond.endswith("+SA") else (NO_ASSISTANCE,):
                for task in ("Entree", "Dessert"):
                    key = {
                        "robot": "panda",
                        "participant": p,
                        "condition": cond,
                        "assistance": assistance,
                        "task": task,
                        "order": 0,
                    }
                    e = 5 + skill + (sa_error if cond.endswith("+SA") else 0) + rng.normal(0, 0.1)
                    err.append({**key, "goal_error": e, "goal_error_bowls": e + 0.1, "mean_distance": e / 60})
                    t = 60 + 5 * skill + (la_sa_time if cond == "LA+SA" else 0) + rng.normal(0, 1)
                    time.append(
                        {**key, "total_time": t, "idle_time": t / 3, "mode_switches": 0, "completed": True}
                    )
                    for phase in ("stab", "scoop", "dip", "plate"):
                        a = (
                            0.8
                            + (scoop_gain if (cond == "LA+SA" and phase == "scoop") else 0)
                            + rng.normal(0, 0.02)
                        )
                        align.append(
                            {**key, "phase": phase, "preference": phase, "alignment": a, "steps": 10}
                        )
    return {"goal_error": pd.DataFrame(err), "time": pd.DataFrame(time), "alignment": pd.DataFrame(align)}


def verdicts(rows):
    return {c.id: c.reproduced for c in rows}


def test_clear_effects_reproduce_every_hypothesis():
    rows, analyses = claims.claims(
        frames(20, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15), STUDY_ASSISTANCE, 20
    )
    v = verdicts(rows)
    heads = ("study.h1", "study.h1@mean_distance", "study.h1@paper_test", "study.h2", "study.h3")
    for head in heads:
        for extra in ("", "grasp_set", "cohort", "grasp_set+cohort"):
            cid = head + (("+" if "@" in head else "@") + extra if extra else "")
            assert v[cid] == "yes", cid
    # one row per reading, no copy of a headline; and Fig. dessert's Likert claim, which simulated
    # participants cannot test (they answer no questionnaire)
    assert len(rows) == len(v) == 5 * 4 + 1
    by_id = {c.id: c for c in rows}
    assert by_id["study.likert"].reproduced == "not testable" and not by_id["study.likert"].settled
    assert "answer no questionnaire" in by_id["study.likert"].measured
    first = by_id["study.h1"]
    assert first.assistance == "hindsight" and first.n_users == 10 and first.settled
    assert first.ci_high < 0 and by_id["study.h1@cohort"].n_users == 20
    # the note states the effect in words with its sign, then the readings that flip it
    assert first.note.startswith("Measured effect: SA lowers Goal Error by -2.01 m s, F(1,9) = ")
    assert ". Every reading gives the same words. " in first.note
    h3 = by_id["study.h3"].note
    assert h3.startswith("Measured effect: LA+SA is faster than ") and " by -" in h3.split(". ")[0]
    # the paper's F(1,18) is the between-subjects reading; the within-subjects test has F(1,9)
    res = analyses[("hindsight", 10)]
    assert (res["h1_between"]["df1"], res["h1_between"]["df2"]) == (1, 18)
    assert (res["h1_within"]["df1"], res["h1_within"]["df2"]) == (1, 9)


def test_effects_in_the_wrong_direction_do_not_reproduce():
    rows, _ = claims.claims(
        frames(10, sa_error=+2.0, la_sa_time=+20.0, scoop_gain=-0.15), STUDY_ASSISTANCE[:1], 10
    )
    v = verdicts(rows)
    for cid in ("study.h1", "study.h1@mean_distance", "study.h1@paper_test", "study.h2", "study.h3"):
        assert v[cid] == "no", cid  # settled: the effect is clearly the wrong way


def test_a_small_effect_of_the_right_sign_is_partly():
    # LA+SA scoops slightly better than R+SA, far within the noise: higher, not significant
    data = frames(10, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.0, seed=4)
    a = data["alignment"]
    rng = np.random.default_rng(0)
    noisy = (a.phase == "scoop") & (a.condition == "LA+SA")
    a.loc[noisy, "alignment"] = 0.8 + 0.002 + rng.normal(0, 0.05, noisy.sum())
    rows, analyses = claims.claims(data, STUDY_ASSISTANCE[:1], 10)
    mean, low, high, p, pairs = analyses[("hindsight", 10)]["h2_phases"]["scoop"]
    assert pairs == 10 and low < 0 < high and p >= 0.05  # the interval straddles zero: cannot tell
    h2 = {c.id: c for c in rows}["study.h2"]
    assert h2.reproduced == "undecided" and not h2.settled
    assert f"the tests read {'partly' if mean > 0 else 'no'!r}" in h2.note


def test_a_phase_nobody_reached_is_not_evidence():
    data = frames(10, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15)
    a = data["alignment"]
    a.loc[a.phase == "scoop", "alignment"] = np.nan
    rows, analyses = claims.claims(data, STUDY_ASSISTANCE[:1], 10)
    assert np.isnan(analyses[("hindsight", 10)]["h2_phases"]["scoop"][0])
    assert verdicts(rows)["study.h2"] == "not testable"  # no interval: the test cannot run
    h2 = by_id(rows)["study.h2"]
    assert "scoop: no test (0 pairs)" in h2.measured and "too few pairs for an interval" in h2.note
    assert "nan" not in h2.measured + h2.note


def test_config_errors():
    from lasa.base.config import from_dict
    from lasa.base.errors import ConfigError

    with pytest.raises(ConfigError, match="assistance"):
        from_dict(study.Config, {"session": {"assistance": ["magic"]}})
    with pytest.raises(ConfigError, match=r"^study settings: session\.participant\.beta_median must be "):
        from_dict(study.Config, {"session": {"participant": {"beta_median": "20"}}}, where="study")
    nested = from_dict(study.Config, {"session": {"horizon": 30, "participant": {"beta_median": 30}}})
    assert (nested.session.horizon, nested.session.participant.beta_median) == (30, 30)
    assert (
        nested.session.assistance
        == study.Config().session.assistance
        == ("hindsight", "hindsight_point", "grasp_set")
    )
    with pytest.raises(ConfigError, match="video_participant"):
        study.Config(participants=4, video_participant=4)


def test_a_slower_condition_with_the_same_distance_is_told_apart():
    # SA doubles the time and leaves the distance alone: the summed Goal Error rises, the mean does not
    data = frames(10, sa_error=0.0, la_sa_time=0.0, scoop_gain=0.15)
    err = data["goal_error"]
    sa = err.condition.str.endswith("+SA")
    err.loc[sa, "goal_error"] *= 2
    rows, _ = claims.claims(data, STUDY_ASSISTANCE[:1], 10)
    v = verdicts(rows)
    assert v["study.h1"] == "no" and v["study.h1@mean_distance"] == "undecided"
    res = {c.id: c for c in rows}
    assert res["study.h1"].value > 0 and abs(res["study.h1@mean_distance"].value) < 0.01


def with_decoders(base: dict[str, pd.DataFrame], other: dict[str, pd.DataFrame]) -> dict[str, pd.DataFrame]:
    """The headline's tables (decoder ``head``) plus another reading's LA rows (decoder ``other``)."""
    out = {}
    for key in base:
        head = base[key].assign(
            decoder=np.where(base[key].condition.str.startswith("LA"), "head", NO_ASSISTANCE)
        )
        o = other[key]
        o = o[o.condition.str.startswith("LA") & o.assistance.isin([NO_ASSISTANCE, STUDY_ASSISTANCE[0]])]
        out[key] = pd.concat([head, o.assign(decoder="other")], ignore_index=True)
    return out


def test_another_decoder_reading_is_judged_on_its_own_la_rows():
    good = frames(20, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15)
    bad = frames(20, sa_error=-2.0, la_sa_time=+20.0, scoop_gain=-0.15, seed=1)
    data = with_decoders(good, bad)
    rows, analyses = claims.claims(data, STUDY_ASSISTANCE, 20, decoders=("head", "other"))
    v = verdicts(rows)
    # the headline decoder keeps every reading; the other reading gets the paper's measures only
    assert v["study.h3"] == "yes" and v["study.h2"] == "yes"
    assert v["study.h3@other"] == "no" and v["study.h2@other"] == "no"
    assert v["study.h3@other+cohort"] == "no"
    assert "study.h1@mean_distance+other" not in v and "study.h1@other+grasp_set" not in v
    assert {"study.h1@other", "study.h1@other+cohort"} <= set(v)
    assert ("hindsight", 10, "other") in analyses and ("hindsight", 10) in analyses
    # the other reading's LA+SA mean is its own, the Retargeting rows are shared
    assert (
        analyses[("hindsight", 10, "other")]["means"].total_time["LA+SA"]
        > analyses[("hindsight", 10)]["means"].total_time["LA+SA"]
    )
    assert (
        analyses[("hindsight", 10, "other")]["means"].total_time["R"]
        == analyses[("hindsight", 10)]["means"].total_time["R"]
    )
    assert (
        len(hypotheses.for_member(data["time"], "hindsight", 10, "other")) == 10 * 4 * 2
    )  # 4 conditions x 2 tasks


def test_switch_share_and_completion_by_hand():
    time = pd.DataFrame(
        [
            {
                "participant": p,
                "condition": c,
                "assistance": a,
                "task": t,
                "mode_switches": m,
                "total_time": tt,
                "completed": done,
            }
            for p, c, a, t, m, tt, done in (
                (0, "R", NO_ASSISTANCE, "Entree", 10, 10.0, True),
                (0, "R", NO_ASSISTANCE, "Dessert", 30, 30.0, True),
                (1, "R", NO_ASSISTANCE, "Entree", 20, 10.0, True),
                (1, "R", NO_ASSISTANCE, "Dessert", 0, 10.0, False),
                (0, "LA", NO_ASSISTANCE, "Entree", 0, 10.0, False),
                (1, "LA", NO_ASSISTANCE, "Entree", 0, 10.0, True),
            )
        ]
    )
    share = analysis.switch_share(time, dt=0.1).set_index("condition")
    # participant 0: 40 switches x 0.1 s / 40 s = 0.1; participant 1: 2 s / 20 s = 0.1
    assert list(share.index) == ["R"] and share.loc["R", "switch_share"] == pytest.approx(0.1)
    assert share.loc["R", "herlant_2016"] == 0.174
    done = analysis.completion(time).set_index("condition")
    assert done.loc["R", "finished"] == 0.75 and done.loc["LA", "finished"] == 0.5
    assert done.loc["R", "episodes"] == 4


def test_the_readings_table_joins_property_completion_and_verdicts():
    good = frames(20, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15)
    bad = frames(20, sa_error=-2.0, la_sa_time=+20.0, scoop_gain=-0.15, seed=1)
    data = with_decoders(good, bad)
    data["time"].loc[(data["time"].decoder == "other") & (data["time"].participant < 5), "completed"] = False
    rows, _ = claims.claims(data, STUDY_ASSISTANCE, 20, decoders=("head", "other"))
    prop = pd.DataFrame(
        {
            "decoder": ["head", "head", "other", "other"],
            "has_property": [True, True, False, True],
            "stay_share": [0.6, 0.5, 0.1, 0.7],
        }
    )
    table = claims.variants_table(
        prop, analysis.completion(data["time"]), rows, ["head", "other"], "hindsight"
    )
    head, other = table.set_index("decoder").loc["head"], table.set_index("decoder").loc["other"]
    assert bool(head.headline) and not bool(other.headline)
    assert head["goals with the property"] == 2 and other["goals with the property"] == 1
    assert other["least share staying"] == 0.1
    assert head["LA finished"] == 1.0 and other["LA finished"] == 0.75  # 5 of 20 participants stuck
    # the other reading's LA finishes 5 of 10 (first 10) and 15 of 20 episodes (cohort): below 95%;
    # its LA+SA is slower than R even as a lower bound, so H3 reads no (censored)
    assert head["H3 (10 / all)"] == "reproduced / reproduced"
    assert (
        other["H3 (10 / all)"]
        == "not reproduced (censored: lower bound) / not reproduced (censored: lower bound)"
    )
    assert other["H3 effect (10)"].startswith("LA+SA is slower than R by at least +")
    assert head["H1 effect (10)"].startswith("SA lowers Goal Error by -")
    # Goal Error is summed over the task's time: H1 takes the guard too, and so does H2, whose
    # LA+SA participants may not have reached the phases it compares
    assert (
        head["H1 (10 / all)"] == "reproduced / reproduced"
        and other["H1 (10 / all)"] == "not testable / not testable"
    )
    assert other["H2 (10 / all)"] == "not testable / not testable"
    assert head["R finished"] == head["R+SA finished"] == other["R finished"] == 1.0


# --- H3 on censored times, not testable, participant models -------------------------------------


def by_id(rows):
    return {c.id: c for c in rows}


def test_h3_is_not_testable_when_an_arm_misses_95_percent_completion():
    data = frames(10, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15)
    time = data["time"]
    cut = time.condition.isin(["LA", "LA+SA"])
    time.loc[cut, "completed"] = False
    time.loc[cut, ["total_time", "idle_time"]] = 150.0  # every LA episode cut at the horizon
    rows, _ = claims.claims(data, STUDY_ASSISTANCE, 10, horizon=150.0)
    h3 = by_id(rows)["study.h3"]
    # LA+SA's times, cut at 150 s, are a lower bound already above R's: no, censored
    assert h3.reproduced == "no" and h3.settled
    assert h3.measured.startswith("censored: lower bound (completion: LA 0%, LA+SA 0%): ")
    assert "nan" not in h3.measured.lower() and "nan" not in h3.note.lower()
    assert "R 100%" in h3.measured and "150 s horizon" in h3.measured
    assert by_id(rows)["study.h3@grasp_set"].reproduced == "no"
    # H1 sums Goal Error over the task's time: censored too, so not testable with the same reason
    for cid in ("study.h1", "study.h1@mean_distance", "study.h1@paper_test"):
        h1 = by_id(rows)[cid]
        assert h1.reproduced == "not testable" and not h1.settled
        assert h1.measured.startswith("not testable (completion: LA 0%, LA+SA 0%); SA - no SA = ")
    # H2 compares LA+SA with R+SA only on the phases reached: LA+SA's censored episodes gate it too
    h2 = by_id(rows)["study.h2"]
    assert h2.reproduced == "not testable" and not h2.settled
    assert h2.measured.startswith("not testable (completion: LA+SA 0%, alignment only on the phases reached)")


def censored(data, conditions, share=0.5):
    """The first ``share`` of the participants' episodes of ``conditions`` cut at the horizon."""
    time = data["time"]
    cut = time.condition.isin(conditions) & (time.participant < share * time.participant.nunique())
    time.loc[cut, "completed"] = False
    return data


@pytest.mark.parametrize(
    ("sa_error", "cut", "word"),
    [
        (+2.0, ["LA+SA"], "no"),  # SA's lower bound is already higher: contradicted
        (-2.0, ["LA+SA"], "not testable"),  # a lower bound below the comparator: consistent with H1
        (+2.0, ["LA", "LA+SA"], "not testable"),  # a comparator censored too: nothing is bounded
    ],
)
def test_h1_reads_not_reproduced_when_its_censored_lower_bound_contradicts_it(sa_error, cut, word):
    data = censored(frames(10, sa_error=sa_error, la_sa_time=0.0, scoop_gain=0.15), cut)
    rows = by_id(claims.claims(data, STUDY_ASSISTANCE, 10, horizon=150.0)[0])
    for cid in ("study.h1", "study.h1@paper_test"):
        assert rows[cid].reproduced == word and rows[cid].settled == (word == "no")
        assert rows[cid].measured.startswith("censored: lower bound" if word == "no" else word)
    assert rows["study.h1@mean_distance"].reproduced == "not testable"  # a sum over a cut time: no bound
    if word == "no":
        assert rows["study.h1"].ci_low > 0 and "SA - no SA = +1.99" in rows["study.h1"].measured


@pytest.mark.parametrize(
    ("la_sa_time", "cut", "word"),
    [
        (+30.0, ["LA+SA"], "no"),
        (-20.0, ["LA+SA"], "not testable"),
        (+30.0, ["R", "LA+SA"], "no"),  # R censored: the contrast is with a measured arm
        (+30.0, ["R", "R+SA", "LA", "LA+SA"], "not testable"),
        (+30.0, ["LA"], "no"),  # LA+SA measured and slower than R: LA's censoring does not matter
        (-20.0, ["LA"], "not testable"),  # faster than R and R+SA, LA only bounded: not settled here
    ],
)
def test_h3_reads_not_reproduced_when_la_sa_lower_bound_is_already_slower(la_sa_time, cut, word):
    data = censored(frames(10, sa_error=-2.0, la_sa_time=la_sa_time, scoop_gain=0.15), cut)
    h3 = by_id(claims.claims(data, STUDY_ASSISTANCE, 10, horizon=150.0)[0])["study.h3"]
    assert h3.reproduced == word
    if word == "no":
        bound = "LA+SA" in cut  # its time a lower bound only when LA+SA itself is censored
        assert h3.settled and h3.ci_low > 0 and h3.measured.startswith("censored: lower bound") == bound
        assert ("a lower bound, against" in h3.measured) == bound
        assert ("against R's" in h3.measured) == ("R" not in cut)  # never compared with a censored arm


@pytest.mark.parametrize(("unfinished", "testable"), [(2, True), (3, False)])
def test_the_completion_guard_is_95_percent_of_the_episodes_analysed(unfinished, testable):
    # 20 participants x 2 tasks = 40 R+SA episodes in the cohort: 2 unfinished is 95%, 3 is 92.5%
    data = frames(20, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15)
    time = data["time"]
    late = time.index[
        (time.condition == "R+SA") & (time.assistance == "hindsight") & (time.participant >= 10)
    ]
    time.loc[late[:unfinished], "completed"] = False
    rows = by_id(claims.claims(data, STUDY_ASSISTANCE[:1], 20)[0])  # judged once, read twice
    cohort = rows["study.h3@cohort"]
    assert (cohort.reproduced == "yes") is testable
    if not testable:
        assert cohort.measured.startswith("not testable (completion: R+SA 92.5%)")
    assert rows["study.h3"].reproduced == "yes"  # first 10: all


def h3_frames(total: dict[str, float], idle: dict[str, float], n: int = 6) -> dict[str, pd.DataFrame]:
    """Tables whose per-task times are ``total`` / ``idle`` per condition, + participant i x 2 s."""
    data = frames(n, sa_error=-2.0, la_sa_time=0.0, scoop_gain=0.15)
    time = data["time"]
    time["total_time"] = time.condition.map(total) + 2.0 * time.participant
    time["idle_time"] = time.condition.map(idle) + 1.0 * time.participant
    return data


def test_h3_by_hand_yes_partly_no_on_restricted_means():
    slow = {"R": 40.0, "R+SA": 45.0, "LA": 50.0}
    yes = h3_frames({**slow, "LA+SA": 30.0}, {"R": 10.0, "R+SA": 10.0, "LA": 12.0, "LA+SA": 5.0}, n=10)
    rows, analyses = claims.claims(yes, STUDY_ASSISTANCE[:1], 10)
    h3 = by_id(rows)["study.h3"]
    # every participant's gap is the same: LA+SA - R = 2 x (30 - 40) = -20 s exactly, interval degenerate
    assert (h3.reproduced, h3.value, h3.ci_low, h3.ci_high, h3.settled) == ("yes", -20.0, -20.0, -20.0, True)
    assert analyses[("hindsight", 10)]["h3_gap"][0] == "R"
    # fastest on Total Time, but idle as long as R's: partly, settled (the Total gap excludes 0)
    partly = h3_frames({**slow, "LA+SA": 30.0}, {"R": 10.0, "R+SA": 10.0, "LA": 12.0, "LA+SA": 10.0}, n=10)
    h3 = by_id(claims.claims(partly, STUDY_ASSISTANCE[:1], 10)[0])["study.h3"]
    assert (h3.reproduced, h3.settled) == ("partly", True)
    # slower than R: no, settled; the gap is to R, LA+SA - R = +10 s
    no = h3_frames({**slow, "LA+SA": 45.0}, {"R": 10.0, "R+SA": 10.0, "LA": 12.0, "LA+SA": 5.0}, n=10)
    h3 = by_id(claims.claims(no, STUDY_ASSISTANCE[:1], 10)[0])["study.h3"]
    assert (h3.reproduced, h3.value, h3.settled) == ("no", 10.0, True)


def test_fewer_participants_than_the_papers_never_settle():
    """The same clear-cut H3 as above on 6 participants, fewer than the paper's 10: undecided, with why;
    and on 10 participants but 100 bootstrap resamples, fewer than a 95% interval's 200 (issue 48)."""
    slow = {"R": 40.0, "R+SA": 45.0, "LA": 50.0, "LA+SA": 30.0}
    idle = {"R": 10.0, "R+SA": 10.0, "LA": 12.0, "LA+SA": 5.0}
    h3 = by_id(claims.claims(h3_frames(slow, idle, n=6), STUDY_ASSISTANCE[:1], 6)[0])["study.h3"]
    assert (h3.reproduced, h3.settled, h3.value) == ("undecided", False, -20.0)
    assert "it rests on 6 participants, fewer than the 10 a settled verdict needs" in h3.note
    assert "the tests read 'yes'" in h3.note
    few = claims.claims(h3_frames(slow, idle, n=10), STUDY_ASSISTANCE[:1], 10, n_resamples=100)[0]
    h3 = by_id(few)["study.h3"]
    assert (h3.reproduced, h3.settled) == ("undecided", False)
    assert "on 100 resamples, fewer than the 200 a 95% interval needs" in h3.note
    assert all(not c.settled for c in few if c.n_users < 10)


def test_h3_runs_no_t_test_on_times(monkeypatch):
    real = hypotheses.stats.pairwise

    def guarded(frame, measure, *args, **kwargs):
        assert measure not in ("total_time", "idle_time"), "H3 must not t-test (capped) times"
        return real(frame, measure, *args, **kwargs)

    monkeypatch.setattr(hypotheses.stats, "pairwise", guarded)
    rows, analyses = claims.claims(
        frames(10, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15), STUDY_ASSISTANCE, 10
    )
    assert by_id(rows)["study.h3"].reproduced == "yes"
    assert "p_corr" not in analyses[("hindsight", 10)]["h3_total"].columns


def test_untestable_marks_every_row_and_keeps_the_numbers():
    data = frames(20, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15)
    plain, _ = claims.claims(data, STUDY_ASSISTANCE, 20)
    reason = "no decoder with both halves of the property; best reading t: least share staying 0.10"
    marked, _ = claims.claims(data, STUDY_ASSISTANCE, 20, untestable=reason)
    assert [c.id for c in marked] == [c.id for c in plain] and len(marked) == 20 + 1  # + study.likert
    for before, after in zip(plain, marked, strict=True):
        assert after.reproduced == "not testable" and not after.settled, after.id
        if after.id == "study.likert":  # not testable for its own reason, marked or not
            assert after == before
            continue
        assert f"not testable ({reason})" in after.note and after.measured == before.measured
        assert after.value == before.value


def with_decoders_and_models(n: int = 20) -> dict[str, pd.DataFrame]:
    """Decoders ``head`` and ``other`` under models ``a`` (LA+SA fast) and ``b`` (LA+SA slow)."""
    good = frames(n, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15)
    bad = frames(n, sa_error=-2.0, la_sa_time=+20.0, scoop_gain=-0.15, seed=1)
    a, b = with_decoders(good, bad), with_decoders(bad, good)
    return {k: pd.concat([a[k].assign(model="a"), b[k].assign(model="b")], ignore_index=True) for k in a}


def test_untestable_decoders_marks_that_readings_rows_only():
    data = with_decoders(
        frames(10, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15),
        frames(10, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15, seed=1),
    )
    rows, _ = claims.claims(
        data, STUDY_ASSISTANCE, 10, decoders=("head", "other"), untestable_decoders={"other": "why"}
    )
    v = verdicts(rows)
    assert {v[f"study.{h}@other"] for h in ("h1", "h2", "h3")} == {"not testable"}
    assert "not testable (why)" in by_id(rows)["study.h2@other"].note
    assert v["study.h3"] == v["study.h2"] == "yes" and "not testable (" not in by_id(rows)["study.h3"].note


@pytest.fixture(scope="module")
def judged() -> tuple[dict[str, pd.DataFrame], list, dict]:
    """:func:`with_decoders_and_models` judged once for the tests that only read it (data, rows, analyses)."""
    data = with_decoders_and_models()
    rows, analyses = claims.claims(data, STUDY_ASSISTANCE, 20, decoders=("head", "other"))
    return data, rows, analyses


def test_each_participant_model_is_judged_and_named_in_the_ids(judged):
    data, rows, analyses = judged
    v = verdicts(rows)
    # model a (the first, the headline) keeps the paper's ids; model b names itself, after the decoder
    assert v["study.h3"] == "yes" and v["study.h3@b"] == "no" and v["study.h1@b+cohort"] == "yes"
    assert (
        v["study.h2@other"] == "no"
        and v["study.h2@other+b"] == "yes"
        and v["study.h3@other+b+cohort"] == "yes"
    )
    assert "study.h1@mean_distance+b+grasp_set+cohort" in v
    # per model: 5 keys x (2 members x 2 sizes) + 3 x 2 sizes; and Fig. dessert's Likert claim, once
    assert len(rows) == 2 * (5 * 4 + 3 * 2) + 1
    assert ("hindsight", 10, "head", "b") in analyses and ("hindsight", 10, "other", "b") in analyses
    assert ("hindsight", 10) in analyses and ("hindsight", 20, "other") in analyses
    assert "b (effect not reproduced)" in by_id(rows)["study.h3"].note  # a reading that flips it
    assert claims.claim_id("h3", 0, "hindsight", False, None, "one_step") == "study.h3@one_step"
    assert claims.claim_id("h1", 0, "hindsight", True, None, "one_step") == "study.h1@one_step+cohort"
    assert (
        claims.claim_id("h2", 0, "hindsight", False, "transfers_entropy", "one_step")
        == "study.h2@transfers_entropy+one_step"
    )
    done = analysis.completion(data["time"])
    assert list(done.columns[:4]) == ["model", "decoder", "assistance", "condition"]
    assert len(done) == 2 * (2 + 2 * 2 + 2)  # per model: R, R+SA x 2, LA, LA+SA x 2 (head), LA, LA+SA (other)


def test_the_readings_table_has_a_row_per_model_and_decoder():
    data = with_decoders_and_models()
    data["time"].loc[
        (data["time"].model == "b") & (data["time"].condition == "R") & (data["time"].participant == 0),
        "completed",
    ] = False
    rows, _ = claims.claims(data, STUDY_ASSISTANCE, 20, decoders=("head", "other"))
    prop = pd.DataFrame(
        {"decoder": ["head", "other"], "has_property": [True, False], "stay_share": [0.6, 0.1]}
    )
    table = claims.variants_table(
        prop, analysis.completion(data["time"]), rows, ["head", "other"], "hindsight"
    )
    assert list(zip(table.model, table.decoder, strict=True)) == [
        ("a", "head"),
        ("a", "other"),
        ("b", "head"),
        ("b", "other"),
    ]
    t = table.set_index(["model", "decoder"])
    assert t.loc[("a", "head"), "R finished"] == 1.0 and t.loc[("b", "other"), "R finished"] == 0.95  # 38/40
    assert t.loc[("a", "head"), "H3 (10 / all)"] == "reproduced / reproduced"
    # model b's R: participant 0 unfinished in both tasks, 18 of 20 episodes (first 10: censored, not
    # compared, but LA+SA is already slower than a measured condition) and 38 of 40 (the cohort: 95%)
    assert t.loc[("b", "head"), "H3 (10 / all)"] == "not reproduced / not reproduced"
    assert (
        t.loc[("b", "head"), "H2 (10 / all)"] == "not reproduced / not reproduced"
    )  # the guard is H1's and H3's
    assert t.loc[("b", "head"), "H1 (10 / all)"].startswith("not testable / ")


def test_untestable_reason_needs_a_decoder_that_meets_the_rule():
    def table(stay, leave, reached):
        rows = []
        for d, ss, ls, r in zip(("stays", "leaves"), stay, leave, reached, strict=True):
            for g, st, lv in zip(range(4), ss, ls, strict=True):
                rows.append(
                    {
                        "task": "eating",
                        "decoder": d,
                        "goal": g,
                        "n_inputs": 64,
                        "stay_share": st,
                        "theta_range": 1.0,
                        "leave_min": lv,
                        "all_reached": r,
                        "stay_holds": st >= 0.5,
                    }
                )
        frame = pd.DataFrame(rows)
        frame["has_property"] = frame.stay_holds & (frame.leave_min >= 7) & frame.all_reached
        return frame

    # "leaves" has both halves at every goal and reaches every goal: testable
    assert claims.untestable_reason(table([[0.6] * 4, [0.5] * 4], [[0] * 4, [7] * 4], [True, True])) is None
    # "stays" stays everywhere but never leaves; "leaves" leaves everywhere but stays at one goal only
    why = claims.untestable_reason(
        table([[0.6] * 4, [0.5, 0.2, 0.1, 0.3]], [[0, 2, 0, 1], [30] * 4], [True, True])
    )
    assert why == (
        "no decoder with both halves of the property; best reading leaves: both halves at 1 of 4 goals, "
        "the stay half at 1, every goal reached from home, least share staying 0.10, fewest inputs leaving "
        "a goal for another 30 of 64"
    )  # latent_property.choose ranks goals with both halves before goals with the stay half
    assert "(" not in why  # the verdict table's cell quotes it inside parentheses


def test_a_reading_without_an_interval_is_not_testable_never_undecided():
    # H2 with one pair in the scoop phase: no t interval, so no verdict and no `nan` in the table
    judged = (
        "partly",
        0.02,
        float("nan"),
        float("nan"),
        "alignment LA+SA - R+SA, Dessert phases: scoop: +0.020",
    )
    done = pd.Series({"R": 1.0, "R+SA": 1.0, "LA": 1.0, "LA+SA": 1.0})
    nan = float("nan")
    result = {"n": 10, "h3_completion": done, "h2_phases": {"scoop": (0.02, nan, nan, nan, 1)}}
    row = claims._claim_row("study.h2@leaves", "h2", judged, result, "hindsight", "leaves", None, None)
    assert (row.reproduced, row.settled) == ("not testable", False)
    assert row.note.startswith("Measured effect: no scoop-phase comparison (1 pairs). ")
    assert row.facts["pairs"] == 1 and row.facts["testable"] == 0 and row.facts["completion.LA"] == 1
    assert row.measured.startswith("not testable (too few pairs for an interval)")
    assert "fewer than two participants" in row.note and "nan" not in row.note


def test_the_members_table_sets_the_sa_readings_side_by_side():
    data = with_decoders(
        frames(20, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15), frames(20, -2.0, -20.0, 0.15)
    )
    data = {k: v.assign(model="planning") for k, v in data.items()}
    time = data["time"]
    time.loc[
        (time.assistance == STUDY_ASSISTANCE[1]) & (time.condition == "LA+SA") & (time.participant < 4),
        "completed",
    ] = False
    rows, _ = claims.claims(data, STUDY_ASSISTANCE, 20, decoders=("head", "other"))
    table = claims.members_table(analysis.completion(time), rows, STUDY_ASSISTANCE, "head", "planning")
    assert list(table.SA) == list(STUDY_ASSISTANCE) and list(table.headline) == [True, False]
    head, other = table.iloc[0], table.iloc[1]
    assert head["LA+SA finished"] == 1.0 and other["LA+SA finished"] == 0.8  # 8 of 40 episodes cut
    assert head["R+SA finished"] == other["R+SA finished"] == 1.0
    assert (
        head["H1 (10 / all)"] == "reproduced / reproduced"
        and other["H1 (10 / all)"] == "not testable / not testable"
    )
    assert head["H1 effect (10)"].startswith("SA lowers Goal Error by -")
    assert other["H3 effect (10)"] == "no contrast (a compared condition finishes too few episodes)"


def _property(meets: dict[str, bool]) -> pd.DataFrame:
    """A property summary of two goals per decoder: ``meets[d]`` says whether d has both halves at both."""
    rows = []
    for d, ok in meets.items():
        for goal in ("a", "b"):
            rows.append(
                {
                    "task": "eating",
                    "decoder": d,
                    "goal": goal,
                    "has_property": ok,
                    "all_reached": True,
                    "stay_holds": ok,
                    "leave_min": 10.0 if ok else 3.0,
                    "stay_share": 0.6 if ok else 0.2,
                    "theta_range": 1.0,
                }
            )
    return pd.DataFrame(rows)


def test_only_decoders_with_the_property_and_the_headlines_entropy_version_run():
    prop = _property({"leaves": False, "transfers": True, "transfers_entropy": False, "home": False})
    assert study.variants_to_run(prop) == ["transfers", "transfers_entropy"]
    assert set(study.variants_to_run(prop, "all")) == {"leaves", "transfers", "transfers_entropy", "home"}
    assert study.variants_to_run(prop, "all")[0] == "transfers"  # the ranking's order, the headline first
    both = _property({"home": True, "transfers": True, "home_entropy": False})
    assert study.variants_to_run(both) == ["home", "transfers", "home_entropy"]  # every one that meets it
    none = _property({"leaves": False, "home": False})
    assert len(study.variants_to_run(none)) == 1  # no decoder meets the rule: the best-ranked one alone
    with pytest.raises(ConfigError, match="decoders"):
        study.variants_to_run(prop, "some")
    with pytest.raises(ConfigError, match="decoders"):
        study.Config(decoders="some")


def test_reading_of_fills_in_what_the_headlines_keys_leave_out():
    assert claims.reading_of(("hindsight", 10), "head", "a") == ("hindsight", "head", "a")
    assert claims.reading_of(("hindsight", 10, "other"), "head", "a") == ("hindsight", "other", "a")
    assert claims.reading_of(("hindsight", 40, None, "b"), "head", "a") == ("hindsight", "head", "b")
    assert claims.reading_of(("grasp_set", 10, "other", "b"), "head", "a") == (
        "grasp_set",
        "other",
        "b",
    )


def test_the_h1_h2_h3_tables_have_a_block_per_analysis_named_by_its_reading(judged):
    _, _, analyses = judged
    h1 = claims.h1_table(analyses, "head", "a")
    assert len(h1) == 3 * len(analyses)
    assert set(h1.measure) == {"Goal Error [m s]", "mean distance [m]"} and set(h1.model) == {"a", "b"}
    assert set(h1.decoder) == {"head", "other"} and set(h1.SA) == set(STUDY_ASSISTANCE)
    first = analyses[("hindsight", 10)]["h1_within"]
    row = h1[(h1.model == "a") & (h1.decoder == "head") & (h1.SA == "hindsight") & (h1.participants == 10)]
    assert row.iloc[1].F == first["F"] and row.iloc[1].df == f"({first['df1']},{first['df2']})"
    h2 = claims.h2_table(analyses, "head", "a")
    assert len(h2) == 3 * len(analyses) and list(h2.phase[:3]) == ["stab", "scoop", "dip"]
    scoop = analyses[("hindsight", 10)]["h2_phases"]["scoop"]
    assert h2.iloc[1]["LA+SA - R+SA"] == scoop[0] and h2.iloc[1].pairs == scoop[4]
    h3 = claims.h3_tables(analyses, "head", "a")
    assert len(h3) == len(analyses)
    title, means, times = h3[0]
    assert title.startswith("model = a, decoder = head, SA = hindsight, 10 participants:")
    assert "not testable" not in title  # every episode finished
    assert list(means.index) == list(CONDITIONS) and (means.finished == 1.0).all()
    assert list(times.index.get_level_values(0).unique()) == ["total", "idle"]
    assert any("decoder = other" in t for t, _, _ in h3) and any(t.startswith("model = b") for t, _, _ in h3)


def test_switch_shares_split_each_model_into_the_first_10_and_the_cohort():
    rows = [
        {"participant": p, "condition": "R", "assistance": NO_ASSISTANCE, "task": t, "model": m,
         "mode_switches": 10 + p, "total_time": 20.0, "completed": True}
        for m in ("a", "b") for p in range(12) for t in ("Entree", "Dessert")
    ]  # fmt: skip
    time = pd.DataFrame(rows)
    out = analysis.switch_shares(time, 0.1, ("b", "a"))
    assert list(zip(out.model, out.participants_of, strict=True)) == [
        ("b", "first 10"), ("b", "cohort"), ("a", "first 10"), ("a", "cohort")
    ]  # fmt: skip
    assert list(out.participants) == [10, 12, 10, 12]
    first = analysis.switch_share(time[time.model == "a"], 0.1, n=study.PAPER_N)
    assert out.switch_share.iloc[2] == pytest.approx(first.switch_share.iloc[0])


def test_break_even_is_the_time_gap_per_mode_switch_by_hand():
    # mean total time per task and mode switches of each arm: (condition, member) -> (time, switches)
    arms = {
        ("R", NO_ASSISTANCE): (40.0, 10), ("LA", NO_ASSISTANCE): (80.0, 0),
        ("R+SA", "hindsight"): (50.0, 5), ("LA+SA", "hindsight"): (60.0, 0),
        ("R+SA", "grasp_set"): (45.0, 5), ("LA+SA", "grasp_set"): (70.0, 0),
    }  # fmt: skip
    rows = []
    for (cond, member), (t, switches) in arms.items():
        decoder = "head" if cond.startswith("LA") else NO_ASSISTANCE
        for p in range(2):
            key = {"participant": p, "condition": cond, "assistance": member, "task": "Dessert"}
            rows.append({**key, "decoder": decoder, "model": "a", "total_time": t, "mode_switches": switches})
            # another participant model and another decoder reading, both ignored
            rows.append({**key, "decoder": decoder, "model": "b", "total_time": 999.0, "mode_switches": 1})
            if cond.startswith("LA"):
                rows.append(
                    {**key, "decoder": "other", "model": "a", "total_time": 999.0, "mode_switches": 0}
                )
    gap = analysis.break_even(pd.DataFrame(rows), STUDY_ASSISTANCE, "head", "a")
    cost = gap["break-even cost per switch [s]"]
    assert list(gap.index) == [(m, c) for m in STUDY_ASSISTANCE for c in ("R", "R+SA")]
    assert cost.to_dict() == pytest.approx(
        {
            ("hindsight", "R"): 2.0,
            ("hindsight", "R+SA"): 2.0,
            ("grasp_set", "R"): 3.0,
            ("grasp_set", "R+SA"): 5.0,
        }
    )
    assert gap.loc[("grasp_set", "R+SA"), "LA+SA time [s]"] == 70.0
    assert gap.loc[("hindsight", "R"), "switches per task"] == 10


def test_stuck_episodes_runs_stuck_over_every_model_and_reading(monkeypatch):
    seen = []

    def fake(task, episodes, decoder, config):
        seen.append((episodes, decoder))
        return pd.DataFrame({"participant": [episodes]})

    monkeypatch.setattr(analysis, "stuck", fake)
    episodes = {"a": {"head": "a-head", "other": "a-other"}, "b": {"head": "b-head"}}
    decoders = {"head": "phi-head", "other": "phi-other"}
    out = analysis.stuck_episodes(None, episodes, decoders, None, ("b", "a"))
    assert seen == [("b-head", "phi-head"), ("a-head", "phi-head"), ("a-other", "phi-other")]
    assert list(out.participant) == ["b-head", "a-head", "a-other"]
    assert list(out.model) == ["b", "a", "a"] and list(out.decoder) == ["head", "head", "other"]


def test_the_participants_table_lists_every_parameter(tmp_path):
    import dataclasses

    from lasa.base.errors import ArtifactError
    from lasa.people.cohort import ParticipantConfig

    participant = ParticipantConfig()
    table = study.participant_table(participant)
    assert list(table.parameter) == [f.name for f in dataclasses.fields(ParticipantConfig)]
    assert len(table) == len(dataclasses.fields(participant)) and list(table.columns) == [
        "parameter",
        "value",
    ]
    with pytest.raises(ArtifactError, match="notebook 10"):
        study.eating_property(tmp_path / "figures")


def test_the_likert_claim_reads_the_share_of_significant_comparisons_in_favour():
    from lasa.evidence.hypotheses import likert_verdict

    # three comparisons per scale (LA+SA against R, R+SA, LA), two scales: diff = LA+SA - other
    likert = pd.DataFrame(
        {
            "scale": ["Easy"] * 3 + ["Prefer"] * 3,
            "a": ["LA+SA"] * 6,
            "b": ["R", "R+SA", "LA"] * 2,
            "diff": [1.2, 0.8, 2.0, 1.0, -0.5, 1.5],
            "p_corr": [0.01, 0.2, 0.001, 0.03, 0.01, 0.04],
        }
    )
    # in favour and significant: Easy-R, Easy-LA, Prefer-R, Prefer-LA (Prefer-R+SA is significant against)
    assert likert_verdict(likert) == ("partly", 4 / 6, 6)
    assert likert_verdict(likert.assign(diff=1.0, p_corr=0.01))[:2] == ("yes", 1.0)
    assert likert_verdict(likert.assign(p_corr=0.5))[:2] == ("no", 0.0)


def test_a_headline_without_readings_keeps_its_note():
    rows, _ = claims.claims(
        frames(10, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15), STUDY_ASSISTANCE[:1], 10
    )
    likert = {c.id: c for c in rows}["study.likert"]
    assert likert.note == claims.likert_row(10, STUDY_ASSISTANCE[0]).note  # no "Every reading ..."


def test_a_test_that_cannot_be_computed_reads_not_testable_with_no_non_finite_number():
    """Issue 48, finding 9: a 1-step horizon gave every episode the same Goal Error, and claims.csv got
    ``F(1,1) = -inf, p = 1.000`` and ``p_holm = nan``. Equal errors everywhere: the H1 row reads not testable,
    says which statistic is not finite, and carries no non-finite number in its text or facts."""
    data = frames(10, sa_error=-2.0, la_sa_time=-20.0, scoop_gain=0.15)
    data["goal_error"]["goal_error"] = 5.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        rows, _ = claims.claims(data, STUDY_ASSISTANCE[:1], 10)
    h1 = by_id(rows)["study.h1"]
    assert (h1.reproduced, h1.settled) == ("not testable", False)
    assert h1.measured == (
        "not testable (its test could not be computed: p LA+SA - LA, p R+SA - R not finite)"
    )  # the Holm-corrected p of each pair: zero variance
    assert np.isnan(h1.value) and np.isnan(h1.ci_low) and np.isnan(h1.ci_high)
    assert all(np.isfinite(v) for v in h1.facts.values())
    for row in rows:
        assert not re.search(r"(?<![A-Za-z])(nan|-?inf)(?![A-Za-z])", row.measured), row.id
