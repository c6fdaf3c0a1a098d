"""User-study statistics against known answers: hand-computed tables, t-test identities, Holm."""

from __future__ import annotations

import gc
import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd
import pytest
import scipy.stats
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from lasa.base.errors import ConfigError
from lasa.evidence import stats
from lasa.evidence.stats import (
    CONDITIONS,
    format_f,
    pairwise,
    rm_anova,
    sa_effect_between,
    sa_effect_within,
)
from lasa.evidence.study_design import factors, participant_means

TASKS = ("Entree", "Dessert")


def make_frame(
    values: np.ndarray, measure: str = "y", participants: Sequence[object] | None = None
) -> pd.DataFrame:
    """Tidy frame from values of shape (N, 4 conditions in CONDITIONS order, len(TASKS))."""
    values = np.asarray(values, dtype=float)
    ids = list(range(1, len(values) + 1)) if participants is None else list(participants)
    rows = [
        {"participant": ids[i], "condition": c, "task": t, measure: values[i, j, k], "extra": "ignored"}
        for i in range(values.shape[0])
        for j, c in enumerate(CONDITIONS)
        for k, t in enumerate(TASKS)
    ]
    return pd.DataFrame(rows)


def from_cells(cells: np.ndarray) -> pd.DataFrame:
    """Frame whose task mean is ``cells`` (N, 4): Entree = cell + 1, Dessert = cell - 1."""
    cells = np.asarray(cells, dtype=float)
    return make_frame(np.stack([cells + 1.0, cells - 1.0], axis=-1))


def random_frame(n: int, seed: int) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    # participant offsets, an SA benefit, an interface effect and noise
    values = (
        rng.normal(0.0, 2.0, (n, 1, 1))
        + np.array([0.0, -1.0, 0.5, -1.5])[None, :, None]
        + rng.normal(0.0, 1.0, (n, 4, 2))
    )
    return make_frame(values)


def holm(p: np.ndarray) -> np.ndarray:
    """Holm step-down adjusted p values: running max of (m - i) p_(i), capped at 1."""
    p = np.asarray(p, dtype=float)
    m = len(p)
    order = np.argsort(p)
    adjusted = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out = np.empty(m)
    out[order] = adjusted
    return out


# --- conditions and aggregation -------------------------------------------------------------------


def test_factors():
    assert [factors(c) for c in CONDITIONS] == [("R", "none"), ("R", "SA"), ("LA", "none"), ("LA", "SA")]
    with pytest.raises(ConfigError, match="allowed: R, R\\+SA, LA, LA\\+SA"):
        factors("SA")


def test_participant_means_mean_and_sum_over_tasks():
    cells = np.arange(8.0).reshape(2, 4)
    frame = from_cells(cells).sample(frac=1.0, random_state=0)  # row order must not matter
    means = participant_means(frame, "y")
    assert list(means.columns) == ["participant", "condition", "y"]
    assert list(means["condition"]) == list(CONDITIONS) * 2
    assert_allclose(means["y"], cells.ravel())
    sums = participant_means(frame, "y", agg="sum")
    assert_allclose(sums["y"], 2 * cells.ravel())
    overall = participant_means(frame, "y", by=())
    assert_allclose(overall["y"], cells.mean(axis=1))
    sa = participant_means(frame, "y", by=("assistance",))
    assert list(sa["assistance"]) == ["none", "SA"] * 2
    assert_allclose(sa["y"], [(0 + 2) / 2, (1 + 3) / 2, (4 + 6) / 2, (5 + 7) / 2])


# --- the 2x2 repeated-measures ANOVA by hand --------------------------------------------------------

# Task means per participant in condition order (R, R+SA, LA, LA+SA), i.e. cells
# (interface, assistance) = (R,none) (R,SA) (LA,none) (LA,SA):
#   P1: 4 2 6 1     P2: 5 4 8 3     P3: 6 3 7 2          n = 3, grand mean 51/12 = 4.25
# Each 1-df effect is a +-1 contrast L_s per participant; with coefficients whose squares sum to 4,
#   SS_effect = (sum_s L_s)^2 / (4 n),  SS_error = sum_s (L_s - mean L)^2 / 4,  df = (1, n - 1 = 2).
# interface   L = (LA,none)+(LA,SA)-(R,none)-(R,SA)     = 1, 2, 0     SS = 9/12 = 0.75, SS_err = 2/4 = 0.5
#             F = 0.75 / (0.5 / 2) = 3
# assistance  L = (R,SA)+(LA,SA)-(R,none)-(LA,none)     = -7, -6, -8  SS = 441/12 = 36.75, SS_err = 0.5
#             F = 36.75 / 0.25 = 147.  Check by marginal means: none 36/6 = 6, SA 15/6 = 2.5,
#             SS = 6 * ((6 - 4.25)^2 + (2.5 - 4.25)^2) = 6 * 6.125 = 36.75.
# interaction L = (R,none)-(R,SA)-(LA,none)+(LA,SA)     = -3, -4, -2  SS = 81/12 = 6.75, SS_err = 0.5
#             F = 6.75 / 0.25 = 27
# With df (1, 2), F = t^2 for t on 2 df, whose two-sided p = 1 - sqrt(F / (F + 2)).
HAND_CELLS = np.array([[4, 2, 6, 1], [5, 4, 8, 3], [6, 3, 7, 2]])
HAND_F = {"interface": 3.0, "assistance": 147.0, "interface:assistance": 27.0}


@pytest.mark.parametrize("agg", ["mean", "sum"])
def test_rm_anova_hand_computed_table(agg):
    table = rm_anova(from_cells(HAND_CELLS), "y", agg=agg)  # summing two tasks scales by 2: same F
    assert list(table.columns) == ["effect", "F", "df1", "df2", "p"]
    assert list(table["effect"]) == list(HAND_F)
    f = np.array(list(HAND_F.values()))
    assert_allclose(table["F"], f, rtol=1e-10)
    assert list(table["df1"]) == [1, 1, 1]
    assert list(table["df2"]) == [2, 2, 2]
    assert_allclose(table["p"], 1.0 - np.sqrt(f / (f + 2.0)), rtol=1e-8)


def test_sa_effect_within_hand_table():
    result = sa_effect_within(from_cells(HAND_CELLS), "y")
    assert result["test"] == "within-subjects 2x2 repeated-measures ANOVA, SA main effect"
    assert_allclose(result["F"], 147.0, rtol=1e-10)
    assert (result["df1"], result["df2"], result["n"]) == (1, 2, 3)
    assert_allclose([result["mean_sa"], result["mean_no_sa"]], [2.5, 6.0])


# --- identities with t-tests ----------------------------------------------------------------------


def _sa_means(frame: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Each participant's mean with SA and without SA, by hand from the frame."""
    with_sa = frame["condition"].str.endswith("+SA")
    sa = frame[with_sa].groupby("participant")["y"].mean()
    none = frame[~with_sa].groupby("participant")["y"].mean()
    return sa.to_numpy(), none.loc[sa.index].to_numpy()


def test_within_sa_effect_is_paired_t_squared():
    frame = random_frame(10, seed=1)
    sa, none = _sa_means(frame)
    test = scipy.stats.ttest_rel(sa, none)
    result = sa_effect_within(frame, "y")
    assert (result["df1"], result["df2"], result["n"]) == (1, 9, 10)
    assert_allclose(result["F"], test.statistic**2, rtol=1e-9)
    assert_allclose(result["p"], test.pvalue, rtol=1e-7)
    assert_allclose([result["mean_sa"], result["mean_no_sa"]], [sa.mean(), none.mean()])
    assert format_f(result).startswith("F(1,9) = ")


def test_between_sa_effect_is_independent_t_squared_with_df_1_18():
    frame = random_frame(10, seed=2)
    sa, none = _sa_means(frame)
    test = scipy.stats.ttest_ind(sa, none)  # pooled variance, df 2N - 2
    result = sa_effect_between(frame, "y")
    assert result["test"].startswith("between-subjects one-way ANOVA on 2N participant means")
    assert "F(1,18)" in result["test"]
    assert (result["df1"], result["df2"], result["n"]) == (1, 18, 10)
    assert_allclose(result["F"], test.statistic**2, rtol=1e-9)
    assert_allclose(result["p"], test.pvalue, rtol=1e-7)
    assert_allclose([result["mean_sa"], result["mean_no_sa"]], [sa.mean(), none.mean()])
    # the two readings agree on the means but not on the test
    within = sa_effect_within(frame, "y")
    assert_allclose(within["mean_sa"], result["mean_sa"])
    assert within["df2"] == 9


# --- pairwise comparisons and Holm ------------------------------------------------------------------

# Constructed so that the paired differences, and hence t on 2 df, are known:
#   LA - LA+SA = 1, 2, 3   (mean 2, var 1)   -> t^2 = 2^2 / (1/3) = 12
#   R - R+SA   = 2, 4, 9   (mean 5, var 13)  -> t^2 = 5^2 / (13/3) = 75/13
#   R - LA     = -1, 0, 4  (mean 1, var 7)   -> t^2 = 1 / (7/3) = 3/7
# p = 1 - sqrt(t^2 / (t^2 + 2)).
PAIR_CELLS = np.array(
    [
        # R, R+SA, LA, LA+SA
        [0.0, -2.0, 1.0, 0.0],
        [2.0, -2.0, 2.0, 0.0],
        [7.0, -2.0, 3.0, 0.0],
    ]
)
PAIRS = [("LA", "LA+SA"), ("R", "R+SA"), ("R", "LA")]
PAIR_T2 = np.array([12.0, 75.0 / 13.0, 3.0 / 7.0])


def test_holm_leaves_the_garbage_collector_as_it_found_it(monkeypatch):
    """statsmodels' Holm calls gc.collect(); pairwise freezes the live objects for it, then thaws them."""
    cells, frozen_during = from_cells(PAIR_CELLS), []
    original = stats.multipletests
    monkeypatch.setattr(
        stats,
        "multipletests",
        lambda *a, **k: frozen_during.append(gc.get_freeze_count()) or original(*a, **k),
    )
    assert gc.get_freeze_count() == 0
    thawed = pairwise(cells, "y", pairs=PAIRS)
    assert gc.get_freeze_count() == 0 and frozen_during and frozen_during[0] > 0
    gc.freeze()  # a caller's own frozen objects stay frozen
    try:
        pd.testing.assert_frame_equal(pairwise(cells, "y", pairs=PAIRS), thawed)
        assert gc.get_freeze_count() > 0
    finally:
        gc.unfreeze()


def test_pairwise_known_p_values_and_holm():
    table = pairwise(from_cells(PAIR_CELLS), "y", pairs=PAIRS)
    assert list(table.columns) == [
        "a",
        "b",
        "mean_a",
        "mean_b",
        "diff",
        "t",
        "df",
        "p_unc",
        "p_corr",
        "correction",
    ]
    p = 1.0 - np.sqrt(PAIR_T2 / (PAIR_T2 + 2.0))
    assert_allclose(table["t"] ** 2, PAIR_T2, rtol=1e-10)
    assert_allclose(table["p_unc"], p, rtol=1e-8)
    # Holm by hand: p1 < p2 < p3, so 3 p1, max(3 p1, 2 p2), max(that, p3)
    expected = [3 * p[0], max(3 * p[0], 2 * p[1]), max(3 * p[0], 2 * p[1], p[2])]
    assert_allclose(table["p_corr"], expected, rtol=1e-8)
    assert_allclose(table["p_corr"], holm(table["p_unc"].to_numpy()), rtol=1e-12)
    assert list(table["df"]) == [2, 2, 2]
    assert set(table["correction"]) == {"holm"}
    # signs: LA is above LA+SA and R above R+SA, R is above LA on average
    assert_allclose(table["diff"], [2.0, 5.0, 1.0])
    assert (table["t"] > 0).all()
    assert_allclose(table["diff"], table["mean_a"] - table["mean_b"])


def test_pairwise_signs_flip_with_order_and_sum_keeps_t():
    frame = from_cells(PAIR_CELLS)
    forward = pairwise(frame, "y", pairs=[("LA", "LA+SA")])
    backward = pairwise(frame, "y", pairs=[("LA+SA", "LA")], agg="sum")
    assert forward["diff"].iloc[0] > 0 and forward["t"].iloc[0] > 0
    assert_allclose(backward["diff"], -2 * forward["diff"])  # sum of two tasks doubles the difference
    assert_allclose(backward["t"], -forward["t"])
    assert_allclose(backward["p_unc"], forward["p_unc"])
    assert_allclose(forward["p_corr"], forward["p_unc"])  # one test: nothing to correct


def test_pairwise_default_is_all_six_pairs_holm_corrected():
    frame = random_frame(10, seed=3)
    table = pairwise(frame, "y")
    expected_pairs = [
        ("R", "R+SA"),
        ("R", "LA"),
        ("R", "LA+SA"),
        ("R+SA", "LA"),
        ("R+SA", "LA+SA"),
        ("LA", "LA+SA"),
    ]
    assert list(zip(table["a"], table["b"], strict=True)) == expected_pairs
    assert_allclose(table["p_corr"], holm(table["p_unc"].to_numpy()), rtol=1e-12)
    cells = participant_means(frame, "y").pivot(index="participant", columns="condition", values="y")
    for row in table.itertuples():
        test = scipy.stats.ttest_rel(cells[row.a], cells[row.b])
        assert_allclose([row.t, row.p_unc], [test.statistic, test.pvalue], rtol=1e-10)
    bonferroni = pairwise(frame, "y", correction="bonferroni")
    assert_allclose(bonferroni["p_corr"], np.minimum(1.0, 6 * table["p_unc"]))
    uncorrected = pairwise(frame, "y", correction="none")
    assert_allclose(uncorrected["p_corr"], uncorrected["p_unc"])


# --- formatting ---------------------------------------------------------------------------------------


def test_format_f():
    assert format_f({"F": 12.345, "df1": 1, "df2": 9, "p": 0.0042}) == "F(1,9) = 12.3, p = .004"
    assert format_f({"F": 29.9, "df1": 1.0, "df2": 18.0, "p": 2e-5}) == "F(1,18) = 29.9, p < .001"
    assert format_f({"F": 0.456, "df1": 1, "df2": 9, "p": 0.52}) == "F(1,9) = 0.46, p = .520"
    row = rm_anova(from_cells(HAND_CELLS), "y").iloc[2].to_dict()
    assert format_f(row) == "F(1,2) = 27.0, p = .035"
    with pytest.raises(ConfigError, match="'p'"):
        format_f({"F": 1.0, "df1": 1, "df2": 2})


# --- errors --------------------------------------------------------------------------------------------


def test_missing_condition_for_a_participant_is_named():
    frame = from_cells(PAIR_CELLS)
    frame = frame[~((frame["participant"] == 2) & (frame["condition"] == "R+SA"))]
    for call in (
        lambda: rm_anova(frame, "y"),
        lambda: sa_effect_within(frame, "y"),
        lambda: pairwise(frame, "y"),
    ):
        with pytest.raises(ConfigError, match="participant 2 has no data for condition\\(s\\) R\\+SA"):
            call()
    # pairs that do not involve R+SA are still testable
    assert len(pairwise(frame, "y", pairs=[("LA", "LA+SA")])) == 1


def test_missing_task_in_a_cell_is_named():
    frame = from_cells(HAND_CELLS)
    frame = frame[
        ~((frame["participant"] == 3) & (frame["condition"] == "LA") & (frame["task"] == "Dessert"))
    ]
    with pytest.raises(
        ConfigError, match="participant 3 has no data for task\\(s\\) Dessert in condition 'LA'"
    ):
        rm_anova(frame, "y", agg="sum")


def test_between_needs_both_assistance_levels():
    frame = from_cells(HAND_CELLS)
    frame = frame[~((frame["participant"] == 1) & frame["condition"].isin(["R+SA", "LA+SA"]))]
    with pytest.raises(ConfigError, match="participant 1 has no rows with assistance 'SA'"):
        sa_effect_between(frame, "y")


def test_unknown_condition_lists_allowed():
    frame = from_cells(HAND_CELLS)
    frame.loc[0, "condition"] = "LA+Assist"
    for call in (lambda: rm_anova(frame, "y"), lambda: sa_effect_between(frame, "y")):
        with pytest.raises(ConfigError, match="'LA\\+Assist'.*allowed: R, R\\+SA, LA, LA\\+SA"):
            call()
    with pytest.raises(ConfigError, match="unknown condition 'SA'"):
        pairwise(from_cells(HAND_CELLS), "y", pairs=[("R", "SA")])


def test_missing_columns_are_named():
    frame = from_cells(HAND_CELLS).drop(columns=["task"])
    with pytest.raises(ConfigError, match="missing column\\(s\\) 'task'"):
        participant_means(frame, "y")
    with pytest.raises(ConfigError, match="missing column\\(s\\) 'goal_error'"):
        sa_effect_within(from_cells(HAND_CELLS), "goal_error")


def test_other_validation():
    frame = from_cells(HAND_CELLS)
    with pytest.raises(ConfigError, match="at least 2 participants, got 1"):
        rm_anova(frame[frame["participant"] == 1], "y")
    with pytest.raises(ConfigError, match="at least 2 participants"):
        sa_effect_between(frame[frame["participant"] == 1], "y")
    bad = frame.copy()
    bad.loc[3, "y"] = np.nan
    with pytest.raises(ConfigError, match="non-finite"):
        sa_effect_between(bad, "y")
    bad.loc[3, "y"] = np.inf
    with pytest.raises(ConfigError, match="non-finite"):
        pairwise(bad, "y")
    for call in (
        lambda: rm_anova(frame, "y", agg="median"),
        lambda: participant_means(frame, "y", agg="max"),
    ):
        with pytest.raises(ConfigError, match="unknown agg '(median|max)'; choose one of 'mean', 'sum'"):
            call()
    with pytest.raises(ConfigError, match="more than one row"):
        rm_anova(pd.concat([frame, frame.iloc[:1]]), "y")
    with pytest.raises(ConfigError, match="numeric"):
        rm_anova(frame, "extra")
    with pytest.raises(ConfigError, match="unknown correction"):
        pairwise(from_cells(PAIR_CELLS), "y", pairs=PAIRS, correction="nope")
    with pytest.raises(ConfigError, match="itself"):
        pairwise(frame, "y", pairs=[("LA", "LA")])
    with pytest.raises(ConfigError, match="cannot group by 'session'"):
        participant_means(frame, "y", by=("session",))


def test_string_participant_ids():
    frame = make_frame(np.stack([HAND_CELLS, HAND_CELLS], axis=-1), participants=["p01", "p02", "p03"])
    assert_allclose(rm_anova(frame, "y")["F"], list(HAND_F.values()), rtol=1e-10)


# --- property: participant offsets cancel ---------------------------------------------------------------


def _within_statistics(frame: pd.DataFrame) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        table = rm_anova(frame, "y")
        pairs = pairwise(frame, "y", correction="none")  # correction plays no part in t
    return np.concatenate([table["F"].to_numpy(), pairs["t"].to_numpy()])


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(min_value=3, max_value=5),
    seed=st.integers(min_value=0, max_value=2**32 - 1),
    who=st.integers(min_value=0, max_value=4),
    shift=st.integers(min_value=-100, max_value=100).filter(lambda c: c != 0),
)
def test_participant_offset_leaves_within_statistics_unchanged(n, seed, who, shift):
    values = np.random.default_rng(seed).integers(0, 20, size=(n, 4, 2)).astype(float)
    before = _within_statistics(make_frame(values))
    # degenerate data (no error variance) give F = inf or nan: nothing to compare
    assume(np.all(np.isfinite(before)) and np.all(np.abs(before) < 1e6))
    shifted = values.copy()
    shifted[who % n] += shift
    after = _within_statistics(make_frame(shifted))
    assert_allclose(after, before, rtol=1e-7, atol=1e-9)
    # the SA effect of the RM-ANOVA, not the between-subjects reading, is the invariant one
    assert_allclose(sa_effect_within(make_frame(shifted), "y")["F"], before[1], rtol=1e-7, atol=1e-9)


# --- restricted mean times and the paired bootstrap (H3) ---------------------------------------


def test_paired_bootstrap_by_hand():
    # two participants with differences 1 and 3: every resample's mean is 1, 2 or 3, and with
    # 10,000 resamples both tails (each 1/4 of the resamples) reach the extremes
    mean, low, high = stats.paired_bootstrap(np.array([1.0, 3.0]))
    assert (float(mean), float(low), float(high)) == (2.0, 1.0, 3.0)
    # a constant difference has a degenerate interval; columns share their resamples, so a
    # column twice another has an interval exactly twice as wide
    mean, low, high = stats.paired_bootstrap(np.array([[-5.0, 1.0], [-5.0, 2.0], [-5.0, 4.0]]), seed=3)
    assert mean.tolist() == [-5.0, 7 / 3] and low[0] == high[0] == -5.0
    m2, l2, h2 = stats.paired_bootstrap(np.array([[1.0, 2.0], [2.0, 4.0], [4.0, 8.0]]), seed=3)
    assert l2[1] == pytest.approx(2 * l2[0]) and h2[1] == pytest.approx(2 * h2[0])


def test_paired_bootstrap_is_the_per_resample_loop_batched_and_seeded():
    x = np.array([0.3, -1.2, 2.5, 0.0, 4.1])
    mean, low, high = stats.paired_bootstrap(x, n_resamples=500, seed=7)
    rng = np.random.default_rng(7)
    idx = rng.integers(0, len(x), size=(500, len(x)))
    loop = [x[row].mean() for row in idx]
    assert (low, high) == pytest.approx(tuple(np.percentile(loop, [2.5, 97.5])), rel=1e-12)
    assert stats.paired_bootstrap(x, n_resamples=500, seed=7)[1] == low  # the same seed, the same interval
    assert stats.paired_bootstrap(x, n_resamples=500, seed=8)[1] != low
    with pytest.raises(ConfigError, match=">= 2 participants"):
        stats.paired_bootstrap(np.array([1.0]))
    with pytest.raises(ConfigError, match="non-finite"):
        stats.paired_bootstrap(np.array([1.0, np.nan]))


def _times(rows):
    return pd.DataFrame(rows, columns=["participant", "condition", "task", "total_time"])


def test_restricted_times_cut_each_episode_at_the_horizon_then_sum_the_tasks():
    rows = []
    for p in (0, 1):
        for c in CONDITIONS:
            rows += [(p, c, "Entree", 10.0 * (p + 1)), (p, c, "Dessert", 20.0)]
    rows[0] = (0, "R", "Entree", 200.0)  # ran past a 150 s horizon: counts 150
    wide = stats.restricted_times(_times(rows), "total_time", horizon=150.0)
    assert list(wide.columns) == list(CONDITIONS)
    assert wide.loc[0, "R"] == 170.0 and wide.loc[0, "LA"] == 30.0 and wide.loc[1, "LA+SA"] == 40.0
    assert stats.restricted_times(_times(rows), "total_time").loc[0, "R"] == 220.0  # no horizon: uncut


def test_rmst_contrasts_by_hand():
    # LA+SA is 5 s faster than LA for both participants, 10 s faster than R+SA for one, as fast as R
    base = {"R": 30.0, "R+SA": 30.0, "LA": 35.0, "LA+SA": 30.0}
    rows = [(p, c, t, v / 2) for p in (0, 1) for c, v in base.items() for t in ("Entree", "Dessert")]
    rows = [(p, c, t, v + (5.0 if (p, c) == (1, "R+SA") else 0.0)) for p, c, t, v in rows]
    out = stats.rmst_contrasts(_times(rows), "total_time", horizon=150.0).set_index("b")
    assert list(out.index) == ["R", "R+SA", "LA"] and (out.a == "LA+SA").all() and (out.n == 2).all()
    assert out.loc["LA", ["diff", "ci_low", "ci_high"]].tolist() == [-5.0, -5.0, -5.0]
    assert out.loc["R+SA", "diff"] == -5.0 and out.loc["R+SA", ["ci_low", "ci_high"]].tolist() == [-10.0, 0.0]
    assert out.loc["R", ["diff", "ci_low", "ci_high"]].tolist() == [0.0, 0.0, 0.0]
    assert out.loc["LA", "mean_b"] == 35.0 and out.loc["LA", "mean_a"] == 30.0
