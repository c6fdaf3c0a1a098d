"""lasa.verdicts: the bootstrap interval, agreement across draws, and one row per reading."""

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lasa.claims import Claim
from lasa.errors import ConfigError
from lasa.verdicts import assess, bootstrap_frames, by_member, member_frame, member_of


def rule(frame: pd.DataFrame) -> list[Claim]:
    """A toy claim: 'x is positive on average'; yes if mean > 0.1, partly if > 0, else no."""
    m = float(frame.x.mean())
    return [
        Claim(
            id="sim1.toy",
            claim="x is positive",
            figure="sim1",
            paper="x > 0",
            measured=f"mean x {m:.3f}",
            reproduced="yes" if m > 0.1 else "partly" if m > 0 else "no",
            note="rule: toy",
            robot=str(frame.robot.iloc[0]),
            value=m,
        )
    ]


def users(x_per_draw: list[list[float]], member: str = "point") -> pd.DataFrame:
    rows = []
    seed = 0
    for d, xs in enumerate(x_per_draw):
        for x in xs:
            rows.append(dict(robot="planar5", seed=seed, draw=d, x=x, assistance=member))
            seed += 1
    return pd.DataFrame(rows)


def test_constant_users_give_a_degenerate_interval_and_full_agreement():
    [c] = assess(rule, users([[0.5, 0.5]] * 5), n_boot=50)
    assert c.reproduced == "yes" and c.value == 0.5
    assert c.ci_low == c.ci_high == 0.5 and c.seeds_agree == "5/5"


def test_agreement_counts_the_draws_whose_verdict_is_the_pooled_one():
    # pooled mean 0.26 -> yes; draws: 1.0 yes, 0.3 yes, 0.05 partly, -0.05 no, 0.0 no
    frame = users([[1.0, 1.0], [0.3, 0.3], [0.05, 0.05], [-0.05, -0.05], [0.0, 0.0]])
    [c] = assess(rule, frame, n_boot=200)
    assert c.reproduced == "yes" and c.seeds_agree == "2/5"
    assert c.ci_low <= c.value <= c.ci_high
    assert c.ci_low >= -0.05 and c.ci_high <= 1.0  # a mean of resampled users stays in their range


def test_bootstrap_keeps_a_users_rows_together_and_relabels_repeats():
    frame = pd.DataFrame({"seed": [0, 0, 1, 1, 2, 2], "k": [0, 1, 0, 1, 0, 1], "x": [1, 1, 2, 2, 3, 3]})
    for sample in bootstrap_frames(frame, 20, seed=3):
        assert len(sample) == 6 and sample.seed.nunique() == 3  # a repeated user counts twice
        assert (sample.groupby("seed").k.apply(sorted).map(tuple) == (0, 1)).all()
        assert (sample.groupby("seed").x.nunique() == 1).all()  # pairing survives


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-1, 1, allow_nan=False), min_size=4, max_size=30), st.integers(0, 10))
def test_interval_brackets_the_resampled_range(xs, seed):
    frame = users([xs])
    [c] = assess(rule, frame, n_boot=40, seed=seed)
    assert min(xs) - 1e-12 <= c.ci_low <= c.ci_high <= max(xs) + 1e-12
    again = assess(rule, frame, n_boot=40, seed=seed)[0]
    assert (again.ci_low, again.ci_high) == (c.ci_low, c.ci_high)  # seeded: deterministic


def test_by_member_gives_a_headline_and_a_row_per_member():
    la = users([[0.0]] * 2, member="none")
    frame = pd.concat([la, users([[0.5]] * 2, "point"), users([[-0.5]] * 2, "grasp_set")])
    rows = by_member(rule, frame, "point", n_boot=20)
    assert [(c.id, c.assistance, c.reproduced) for c in rows] == [
        ("sim1.toy", "point", "yes"),
        ("sim1.toy@point", "point", "yes"),
        ("sim1.toy@grasp_set", "grasp_set", "no"),
    ]
    assert rows[0].note.startswith("Headline under the default reading (point). The verdict depends")
    # each member's rows include the shared unassisted ones
    assert len(member_frame(frame, "grasp_set")) == 4 and member_of(member_frame(frame, "point")) == "point"


def test_same_verdict_everywhere_is_said_so():
    frame = pd.concat([users([[0.5]] * 2, "point"), users([[0.7]] * 2, "hindsight")])
    head = by_member(rule, frame, "point", n_boot=10)[0]
    assert "Same verdict under every reading: point yes (2/2), hindsight yes (2/2)" in head.note


def test_a_missing_headline_member_or_mixed_frame_is_an_error():
    frame = users([[0.5]], "hindsight")
    with pytest.raises(ConfigError, match="headline member 'point' has no rows"):
        by_member(rule, frame, "point")
    mixed = pd.concat([users([[0.5]], "point"), users([[0.5]], "hindsight")])
    with pytest.raises(ConfigError, match="mixes assistance members"):
        member_of(mixed)


def test_no_finite_values_leave_the_interval_empty():
    def nan_rule(frame):
        return [c.__class__(**{**c.__dict__, "value": math.nan}) for c in rule(frame)]

    [c] = assess(nan_rule, users([[0.5, 0.2]]), n_boot=5)
    assert np.isnan(c.ci_low) and np.isnan(c.ci_high)
