"""Any number of users and resamples gives an honest verdict (issue 48), on the figures' own rows.

A researcher's settings change how many users a verdict rests on and how many resamples its
intervals have. Drawn over both, on the committed paper-scale rows of sims 1-4 (a subset of their
users, the headline member), every claim's verdict must be honest: a settled verdict rests on at
least ``MIN_USERS`` users and ``min_resamples(level)`` resamples, its interval is ordered and
decides its rule at every corner, and an unsettled one reads "undecided" and says why.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from lasa.base.config import from_dict
from lasa.base.errors import ConfigError
from lasa.evidence.decision import NOT_TESTABLE, UNDECIDED
from lasa.evidence.rules import rule
from lasa.evidence.verdicts import MIN_USERS, USER, Looks, assess, member_frame, min_resamples
from lasa.experiments import sim1, sim2, sim3, sim4

FIGURES = Path(__file__).resolve().parents[1] / "figures"
SIMS = {m.NAME: m for m in (sim1, sim2, sim3, sim4)}


@functools.cache
def _rows(name: str, robot: str) -> pd.DataFrame:
    """The headline member's committed rows of one sim and robot."""
    frame = pd.read_csv(FIGURES / f"{name}.csv")
    return member_frame(frame[frame.robot == robot], "point")


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(sorted(SIMS)),
    robot=st.sampled_from(["planar5", "panda"]),
    users=st.integers(1, 90),
    n_boot=st.integers(1, 1000),
    level=st.sampled_from([0.95, 0.9875]),
    seed=st.integers(0, 3),
)
def test_any_users_and_resamples_give_an_honest_verdict(name, robot, users, n_boot, level, seed):
    module, frame = SIMS[name], _rows(name, robot)
    ids = np.sort(frame[USER].unique())[:users]
    sub = frame[frame[USER].isin(ids)]
    claims = assess(module.claims, sub, n_boot, seed, level=level, fast=getattr(module, "boot_values", None))
    enough = len(ids) >= MIN_USERS and n_boot >= min_resamples(level)
    for c in claims:
        assert c.n_users == len(ids)
        if c.reproduced == NOT_TESTABLE:
            assert not c.settled
            continue
        assert np.isfinite(c.value), c.id
        if c.settled:
            assert enough, c.id  # never settled on less than the least evidence
            assert c.ci_low <= c.ci_high and rule(c.id).settled(c.intervals), c.id
        else:
            assert c.reproduced == UNDECIDED and "Undecided: " in c.note, c.id
            if not enough:
                assert "Undecided: it rests on " in c.note, c.id


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(sorted(SIMS)),
    users=st.integers(-2, 90),
    block=st.integers(-1, 40),
    cap=st.integers(-1, 120),
    n_boot=st.integers(-1, 1000),
    seed=st.integers(0, 3),
)
def test_a_sims_looks_settings_are_refused_in_one_line_or_judged_honestly(
    name, users, block, cap, n_boot, seed
):
    """The settings of a sim's looks (users, block, cap, n_boot), drawn across and beyond their
    validated ranges: the config refuses them in one line naming the setting, or the verdicts of its
    first look on the figure's committed rows, at its design's level, are honest as above."""
    module = SIMS[name]
    drawn = {"users": users, "block": block, "cap": cap, "n_boot": n_boot, "seed": seed}
    try:
        config = from_dict(module.Config, drawn, where=f"a drawn {name} setting")
    except ConfigError as err:
        assert "\n" not in str(err) and any(k in str(err) for k in drawn), str(err)
        return
    frame = _rows(name, "panda")
    ids = np.sort(frame[USER].unique())[: config.users]
    level = Looks(config.users, config.block, config.cap).level
    fast = getattr(module, "boot_values", None)
    claims = assess(module.claims, frame[frame[USER].isin(ids)], config.n_boot, seed, level=level, fast=fast)
    enough = len(ids) >= MIN_USERS and config.n_boot >= min_resamples(level)
    assert all(enough for c in claims if c.settled)
    assert all(c.reproduced == UNDECIDED for c in claims if not c.settled and c.reproduced != NOT_TESTABLE)
