"""Power by simulation (lasa.experiments.study.power): drawn cohorts through the claims' own tests.

The synthetic studies keep the committed tables' rows and columns (the headline reading) and
replace the measures the claims test: a large effect is found in every drawn cohort, in the
direction it has; no effect is found in about 5% of them; an arm finishing too few episodes
makes its claims untestable.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence.hypotheses import for_member
from lasa.experiments.study import power as study_power
from lasa.experiments.study.power import needed, power, sentence

FIGURES = Path(__file__).resolve().parents[1] / "figures"
READING = {"assistance": "hindsight", "decoder": "transfers", "model": "planning"}


@pytest.fixture(scope="module")
def committed() -> dict[str, pd.DataFrame]:
    """The committed study tables, the headline reading's rows of its first 20 participants.

    Twenty keep the whole cohort's tests cheap (the repeated-measures ANOVA's design grows as
    the participants squared) and leave the drawn cohorts of 10 mostly distinct people.
    """
    out = {}
    for key in ("goal_error", "time", "alignment"):
        frame = pd.read_csv(FIGURES / f"study_{key}.csv")
        out[key] = for_member(frame, READING["assistance"], 20, READING["decoder"], READING["model"])
    return out


def _centred(frame: pd.DataFrame, column: str, rows: pd.Series, other: pd.Series) -> pd.DataFrame:
    """``frame`` with ``column`` shifted on ``rows`` so that the cohort's mean of rows - other is 0."""
    shift = (
        frame[rows].groupby("participant")[column].mean() - frame[other].groupby("participant")[column].mean()
    )
    out = frame.copy()
    out.loc[rows, column] -= float(shift.mean())
    return out


def synthetic(committed: dict[str, pd.DataFrame], effect: float, seed: int = 1) -> dict[str, pd.DataFrame]:
    """A study where SA changes Goal Error by ``effect`` m s, LA+SA adds ``effect / 10`` scoop
    alignment over R+SA and is ``20 * effect`` s faster than R (R+SA and LA are 100 s slower).

    With ``effect`` 0 each difference is centred on the whole cohort (exactly no effect there).
    Every episode finishes.
    """
    rng = np.random.default_rng(seed)
    n = int(committed["time"].participant.max()) + 1
    person = rng.normal(0.0, 1.0, n)

    err = committed["goal_error"].copy()
    sa = err.condition.str.endswith("+SA")
    err["goal_error"] = 3.0 + 0.5 * person[err.participant] + rng.normal(0.0, 0.3, len(err)) + effect * sa

    align = committed["alignment"].copy()
    scoop = (align.task == "Dessert") & (align.phase == "scoop")
    la_sa = scoop & (align.condition == "LA+SA")
    noise = 0.7 + 0.05 * person[align.participant] + rng.normal(0.0, 0.03, len(align))
    align["alignment"] = np.where(scoop, noise + abs(effect) / 10 * la_sa, align.alignment)

    time = committed["time"].copy()
    slow = time.condition.isin(["R+SA", "LA"]) * 100.0
    fast = (time.condition == "LA+SA") * -20.0 * abs(effect)
    time["total_time"] = 60.0 + 5.0 * person[time.participant] + rng.normal(0.0, 4.0, len(time)) + slow + fast
    time["idle_time"] = 0.25 * time.total_time
    time["completed"] = True
    if effect == 0.0:
        err = _centred(err, "goal_error", sa, ~sa)
        align = _centred(align, "alignment", la_sa, scoop & (align.condition == "R+SA"))
        time = _centred(time, "total_time", time.condition == "LA+SA", time.condition == "R")
        time["idle_time"] = 0.25 * time.total_time
    return {"goal_error": err, "time": time, "alignment": align}


def test_a_large_effect_is_found_in_every_drawn_cohort_in_its_direction(committed):
    # SA *raises* Goal Error here (against the paper); H2 and H3 go the paper's way
    table = power(synthetic(committed, effect=+1.0), **READING, sizes=(6,), draws=8, seed=3)
    rows = table.set_index("claim")
    assert list(rows.index) == ["h1", "h2", "h3"]
    assert (rows.power == 1.0).all() and (rows.untestable_share == 0.0).all()
    assert (rows.opposite_share == 0.0).all() and (rows.draws == 8).all() and (rows.n == 6).all()
    assert rows.direction["h1"] == "SA raises Goal Error" and not rows.paper_direction["h1"]
    assert rows.direction["h2"].startswith("LA+SA aligns better") and rows.paper_direction["h2"]
    assert rows.direction["h3"] == "LA+SA faster than the fastest other condition"
    assert rows.paper_direction["h3"]
    # H1 reads "no" against the paper, so never yes; H2 and H3 read yes, settled
    assert rows.yes_share["h1"] == 0.0 and rows.yes_share["h2"] == 1.0 and rows.yes_share["h3"] == 1.0


def test_without_an_effect_few_drawn_cohorts_are_significant(committed):
    table = power(synthetic(committed, effect=0.0), **READING, sizes=(10,), draws=16, seed=5)
    rows = table.set_index("claim")
    assert (rows.untestable_share == 0.0).all()
    either = rows.power + rows.opposite_share
    # about 5% expected (2.5% each side; H3's percentile bootstrap runs a little above it at
    # n = 10): at most 3 of 16 per claim, 6 of the 48 in all
    assert (either <= 3 / 16).all() and either.sum() <= 6 / 16, rows[["power", "opposite_share"]]
    assert "effect is 0" in rows.direction["h1"] and pd.isna(rows.paper_direction["h1"])


def test_an_arm_finishing_too_few_episodes_makes_its_claims_untestable(committed):
    study = synthetic(committed, effect=-1.0)
    time = study["time"]
    study["time"] = time.assign(completed=time.condition != "LA")  # LA never finishes
    rows = power(study, **READING, sizes=(6,), draws=4).set_index("claim")
    for claim in ("h1", "h3"):  # Goal Error and time are censored in LA
        assert rows.untestable_share[claim] == 1.0 and rows.power[claim] == 0.0
        assert pd.isna(rows.paper_direction[claim]) and "not testable" in rows.direction[claim]
    assert rows.untestable_share["h2"] == 0.0 and rows.power["h2"] == 1.0  # H2 does not compare LA


def test_each_drawn_cohort_counts_on_the_side_its_interval_lies(committed, monkeypatch):
    # the tests scripted: the whole cohort's effect above 0, then one drawn cohort above, one
    # below, one straddling 0 and one not testable
    script = iter(
        [
            ("no", 1.0, 0.5, 1.5),
            ("no", 1.0, 0.5, 1.5),
            ("no", -1.0, -1.5, -0.5),
            ("no", 0.1, -0.5, 0.7),
            ("not testable", np.nan, np.nan, np.nan),
        ]
    )
    monkeypatch.setattr(study_power, "analyse", lambda *args: next(script))
    monkeypatch.setattr(study_power, "judge", lambda judged: dict.fromkeys(("h1", "h2", "h3"), (*judged, "")))
    table = power(committed, **READING, sizes=(6,), draws=4)
    assert table.power.tolist() == [0.25] * 3 and table.opposite_share.tolist() == [0.25] * 3
    assert table.untestable_share.tolist() == [0.25] * 3 and (table.yes_share == 0.0).all()
    assert table.direction.tolist()[0] == "SA raises Goal Error" and not table.paper_direction[0]
    assert table.paper_direction.tolist()[1:] == [True, False]  # H2 above 0 is the paper's; H3 is not


def test_the_same_seed_gives_the_same_table_in_any_number_of_processes(committed):
    study = synthetic(committed, effect=-0.1)
    first = power(study, **READING, sizes=(6, 8), draws=2, seed=11)
    again = power(study, **READING, sizes=(6, 8), draws=2, seed=11)
    pd.testing.assert_frame_equal(first, again)
    spread = power(study, **READING, sizes=(6, 8), draws=2, seed=11, n_jobs=2)  # notebook 11's two processes
    pd.testing.assert_frame_equal(first, spread)
    assert list(first.n) == [6, 8] * 3


def _hand_made() -> pd.DataFrame:
    powers = {"h1": (0.5, 0.79, 0.9), "h2": (0.1, 0.2, 0.3), "h3": (0.85, 0.7, 1.0)}
    return pd.DataFrame(
        [
            {
                "claim": claim,
                "n": n,
                "power": p,
                "opposite_share": 0.0,
                "untestable_share": 0.7 if claim == "h2" else 0.0,
                "yes_share": 0.0,
                "direction": f"{claim} direction",
                "paper_direction": claim != "h3",
                "draws": 100,
            }
            for claim, ps in powers.items()
            for n, p in zip((6, 10, 16), ps, strict=True)
        ]
    )


def test_needed_is_the_smallest_size_from_which_power_reaches_the_target():
    rows = needed(_hand_made()).set_index("claim")
    assert rows.needed["h1"] == 16 and rows.power["h1"] == 0.9 and rows.needed_text["h1"] == "16"
    # h3 reaches 0.8 at 6 but not at 10: it needs 16
    assert rows.needed["h3"] == 16 and not rows.paper_direction["h3"]
    assert "reached 0.8 at n = 6 (0.85) but fell below it at n = 10 (0.70)" in rows.explanation["h3"]
    assert pd.isna(rows.needed["h2"]) and rows.needed_text["h2"] == "more than 16"
    assert "cannot run in 70%" in rows.explanation["h2"] and rows.power["h2"] == 0.3
    between = needed(_hand_made(), interpolate=True).set_index("claim")
    assert between.needed["h1"] == 11  # 10 + (0.8 - 0.79) / (0.9 - 0.79) * 6 = 10.5, rounded up
    assert between.needed["h3"] == 12  # 10 + (0.8 - 0.7) / (1.0 - 0.7) * 6 = 12
    low = needed(_hand_made(), target=0.5, interpolate=True).set_index("claim")
    assert low.needed["h1"] == 6 and low.needed["h3"] == 6 and pd.isna(low.needed["h2"])


def test_sentence_names_whom_to_recruit():
    table = needed(_hand_made())
    assert "recruit 16 participants" in sentence(table, "h1") and "H1" in sentence(table, "h1")
    assert "; the paper's direction)" in sentence(table, "h1")
    assert "against the paper's direction" in sentence(table, "h3")
    assert sentence(table, "h2").startswith("No simulated cohort of up to 16 gives H2")
    assert all("simulated participants" in sentence(table, c) for c in ("h1", "h2", "h3"))
    with pytest.raises(ConfigError, match="claim"):
        sentence(table, "h4")


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"sizes": (1, 10)}, "sizes"),
        ({"sizes": ()}, "sizes"),
        ({"sizes": (6, 6)}, "sizes"),
        ({"draws": 0}, "draws"),
        ({"n_resamples": 0}, "n_resamples"),
        ({"n_jobs": 0}, "n_jobs"),
        ({"assistance": "nobody"}, "assistance"),
        ({"decoder": "nothing"}, "decoder"),
        ({"model": "nobody"}, "participant model"),
    ],
)
def test_bad_power_arguments_are_refused(committed, kwargs, message):
    with pytest.raises(ConfigError, match=message):
        power(committed, **(READING | kwargs))


@pytest.mark.parametrize("target", [0.0, 1.0, 1.5, -0.2])
def test_a_target_outside_0_1_is_refused(target):
    with pytest.raises(ConfigError, match="target"):
        needed(_hand_made(), target=target)


def test_needed_refuses_a_table_not_of_power():
    with pytest.raises(ConfigError, match="lacks"):
        needed(_hand_made().drop(columns="untestable_share"))
