"""lasa.evidence.verdicts: intervals, settled or undecided, the sequential design, one row per reading."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lasa.base.errors import ConfigError
from lasa.evidence.claims import Claim
from lasa.evidence.rules import rule as rule_of
from lasa.evidence.verdicts import (
    MIN_USERS,
    Looks,
    assess,
    block_seed,
    block_users,
    bootstrap_frames,
    member_frame,
    min_resamples,
    sequential,
    shortfall,
)

TOY = "sim3.entropy_learners"  # a real rule: yes if both gains > 0, partly if one


def toy(frame: pd.DataFrame) -> list[Claim]:
    """The sim3 rule on a toy frame: gain_fast = mean x, gain_slow = mean y."""
    values = {"gain_fast": float(frame.x.mean()), "gain_slow": float(frame.y.mean())}
    return [
        Claim(
            id=TOY,
            claim="toy",
            figure="sim3",
            paper="both > 0",
            measured=f"x {values['gain_fast']:.3f}",
            reproduced=rule_of(TOY).verdict(values),
            note="",
            robot=str(frame.robot.iloc[0]),
            values=values,
        )
    ]


def users(
    xs: list[float], ys: list[float] | None = None, assistance: str = "point", start: int = 0
) -> pd.DataFrame:
    ys = [1.0] * len(xs) if ys is None else ys
    return pd.DataFrame(
        {
            "robot": "planar5",
            "seed": np.arange(start, start + len(xs)),
            "x": xs,
            "y": ys,
            "assistance": assistance,
        }
    )


def test_constant_users_give_a_degenerate_settled_interval():
    [c] = assess(toy, users([0.5] * 6), n_boot=200, min_users=6)
    assert c.reproduced == "yes" and c.settled and c.value == 0.5
    assert c.ci_low == c.ci_high == 0.5 and c.n_users == 6
    assert "6 users per point" in c.note and "Undecided" not in c.note


def test_an_interval_across_zero_reads_undecided_with_the_point_verdict():
    # mean x = 0.1 > 0 (point: yes), but users spread widely on both sides of zero
    [c] = assess(toy, users([-1.0, 1.2, -0.9, 1.1, -1.0, 1.2]), n_boot=200, min_users=6)
    assert c.reproduced == "undecided" and not c.settled
    assert c.ci_low < 0 < c.ci_high
    assert "gain_fast" in c.note and "reaches 0" in c.note and "read 'yes'" in c.note


def test_a_verdict_that_is_not_its_rules_is_an_error():
    def wrong(frame):
        return [Claim(**{**toy(frame)[0].__dict__, "reproduced": "no"})]

    with pytest.raises(ConfigError, match="is not its rule's"):
        assess(wrong, users([0.5] * 3), n_boot=5)


def test_bootstrap_keeps_a_users_rows_together_and_relabels_repeats():
    frame = pd.DataFrame({"seed": [0, 0, 1, 1, 2, 2], "k": [0, 1, 0, 1, 0, 1], "x": [1, 1, 2, 2, 3, 3]})
    for sample in bootstrap_frames(frame, 20, seed=3):
        assert len(sample) == 6 and sample.seed.nunique() == 3  # a repeated user counts twice
        assert (sample.groupby("seed").k.apply(sorted).map(tuple) == (0, 1)).all()
        assert (sample.groupby("seed").x.nunique() == 1).all()  # pairing survives


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-1, 1, allow_nan=False), min_size=4, max_size=30), st.integers(0, 10))
def test_interval_brackets_the_resampled_range_and_is_seeded(xs, seed):
    frame = users(xs)
    [c] = assess(toy, frame, n_boot=40, seed=seed)
    assert min(xs) - 1e-12 <= c.ci_low <= c.ci_high <= max(xs) + 1e-12
    again = assess(toy, frame, n_boot=40, seed=seed)[0]
    assert (again.ci_low, again.ci_high, again.reproduced) == (c.ci_low, c.ci_high, c.reproduced)
    if c.settled:  # a settled verdict is the rule's at every end of the interval
        assert rule_of(TOY).verdict({"gain_fast": c.ci_low, "gain_slow": 1.0}) == c.reproduced
        assert rule_of(TOY).verdict({"gain_fast": c.ci_high, "gain_slow": 1.0}) == c.reproduced


def test_the_design_fixes_its_looks_and_guard():
    d = Looks()
    assert d.sizes == (60, 90, 120, 150) and d.level == pytest.approx(1 - 0.05 / 4)
    assert block_users(d, 0) == (0, 60) and block_users(d, 1) == (60, 30) and block_users(d, 3) == (120, 30)
    assert Looks(10, 30, 25).sizes == (10, 25)  # the last block is cut at the cap
    assert block_seed(7, 0) == 7 and block_seed(7, 1) != block_seed(7, 2) != 7
    with pytest.raises(ConfigError, match="must not exceed cap"):
        Looks(200, 30, 150)
    with pytest.raises(ConfigError, match="block must be a positive integer"):
        Looks(60, 0, 150)


def _runner(xs_by_look: list[list[float]], log: list):
    """A run_block of toy users: look k's new users have the values xs_by_look[k]."""

    def run(look, assistance):
        log.append((look, assistance))
        start = sum(len(x) for x in xs_by_look[:look])
        return pd.concat(
            [users(xs_by_look[look], assistance=m, start=start) for m in assistance], ignore_index=True
        )

    return run


def test_sequential_stops_at_the_first_settled_look():
    log: list = []
    out = sequential(
        _runner([[0.5] * 4, [0.5] * 2], log),
        toy,
        ("point", "grasp_set"),
        "point",
        Looks(4, 2, 6),
        800,
        min_users=4,
    )
    assert log == [(0, ("point", "grasp_set"))]  # settled at once: no more users
    assert [c.id for c in out.claims] == [TOY, f"{TOY}@grasp_set"]  # no copy of the headline
    assert out.claims[0].n_users == 4 and out.claims[0].settled and out.claims[0].assistance == "point"
    assert out.claims[0].note.startswith("The effect is settled at look 1 of 2.")
    assert list(out.looks.users) == [4]


def test_sequential_adds_headline_users_until_the_cap_and_says_undecided():
    log: list = []
    looks = [[-1.0, 1.2, -0.9, 1.1], [-1.0, 1.2], [-0.9, 1.0]]
    out = sequential(_runner(looks, log), toy, ("point", "hindsight"), "point", Looks(4, 2, 8), 50)
    assert log == [
        (0, ("point", "hindsight")),
        (1, ("point",)),
        (2, ("point",)),
    ]  # later looks: headline only
    head, other = out.claims
    assert head.n_users == 8 and head.reproduced == "undecided"
    assert "The effect is undecided at look 3 of 3, the cap (8 users)." in head.note
    assert other.id == f"{TOY}@hindsight" and other.n_users == 4  # the other readings: the first look
    assert list(out.looks.users) == [4, 6, 8] and out.frame.look.max() == 2


def test_a_headline_member_outside_the_members_is_an_error():
    with pytest.raises(ConfigError, match="is not among the members"):
        sequential(_runner([[0.5]], []), toy, ("hindsight",), "point", Looks(1, 1, 1))


def test_member_frames_share_the_unassisted_rows_of_their_own_users():
    la = users([0.0] * 6, assistance="none")
    frame = pd.concat([la, users([0.5] * 6, assistance="point"), users([-0.5] * 3, assistance="grasp_set")])
    assert len(member_frame(frame, "point")) == 12
    assert len(member_frame(frame, "grasp_set")) == 6  # LA rows of users 0-2 only (paired)
    assert set(member_frame(frame, "point").assistance) == {"none", "point"}


def test_no_finite_values_leave_the_interval_unknown_and_undecided():
    def nan_rule(frame):
        c = toy(frame)[0]
        return [
            Claim(
                **{
                    **c.__dict__,
                    "values": {"gain_fast": float("nan"), "gain_slow": 1.0},
                    "reproduced": "partly",
                }
            )
        ]

    [c] = assess(nan_rule, users([0.5, 0.2]), n_boot=5)
    assert np.isnan(c.ci_low) and np.isnan(c.ci_high) and c.reproduced == "undecided"


def test_a_reading_joins_the_readings_an_id_names_already():
    from lasa.evidence.verdicts import with_reading

    assert with_reading("sim1.time_ratio", "grasp_set") == "sim1.time_ratio@grasp_set"
    assert with_reading("sim4.x@joint_space", "grasp_set") == "sim4.x@joint_space+grasp_set"  # one "@"


def test_the_least_evidence_a_settled_verdict_rests_on():
    """Issue 48, findings 1-2: 5 resamples beyond each bound (800 at 98.75%, 200 at 95%) and 60 users."""
    assert (min_resamples(0.9875), min_resamples(0.95), MIN_USERS) == (800, 200, 60)
    assert shortfall(60, 1000, 0.9875) == ""
    assert shortfall(4, 50, 0.9875) == (
        "it rests on 4 users, fewer than the 60 a settled verdict needs, "
        "and on 50 resamples, fewer than the 800 a 98.75% interval needs"
    )


def test_one_resample_or_one_user_never_settles():
    """n_boot = 1 made an interval of the single resample, which left out its own point estimate (issue 48:
    share_lower = 0.667 [1, 1], settled); one user made a zero-width interval, settled. Both read undecided,
    with the reason, and the point estimates' word beside it."""
    frame = users([1.0, 1.0, 0.0] * 20)  # 60 users, mean 0.667
    [c] = assess(toy, frame, n_boot=1, seed=3)
    assert (c.reproduced, c.settled) == ("undecided", False)
    assert "on 1 resamples, fewer than the 200 a 95% interval needs" in c.note and "read 'yes'" in c.note
    [one] = assess(toy, users([0.5]), n_boot=200)
    assert (one.reproduced, one.settled, one.ci_low, one.ci_high) == ("undecided", False, 0.5, 0.5)
    assert "it rests on 1 users, fewer than the 60" in one.note


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(1, 80),
    n_boot=st.integers(1, 300),
    level=st.sampled_from([0.95, 0.9875]),
    seed=st.integers(0, 5),
)
def test_a_settled_verdict_rests_on_enough_users_and_resamples(n, n_boot, level, seed):
    """Whatever the users' values, a verdict is settled only on MIN_USERS users and min_resamples(level)."""
    xs = np.random.default_rng(seed).uniform(0.2, 1.0, n)  # clearly > 0: settled whenever allowed
    [c] = assess(toy, users(list(xs)), n_boot=n_boot, seed=seed, level=level)
    enough = n >= MIN_USERS and n_boot >= min_resamples(level)
    assert c.settled == enough
    assert c.reproduced == ("yes" if enough else "undecided")
