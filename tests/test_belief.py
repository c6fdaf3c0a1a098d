"""Belief update (Alg. 1, line 8) against hand-computed two-goal cases, and invariants."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from lasa.base.config import ControlConfig
from lasa.base.errors import ConfigError
from lasa.method.belief import (
    belief,
    cap_log_belief,
    confidence_threshold,
    confident_belief,
    distance_to_sets,
    log_likelihood,
    logsumexp,
    uniform_log_belief,
    update_log_belief,
)

GOALS = np.array([[1.0, 0.0], [-1.0, 0.0]])


def test_progress_likelihood_two_goals_by_hand():
    # s = 0, a = (1, 0), dt = 0.5: the next state (0.5, 0) is 0.5 closer to g1 and
    # 0.5 farther from g2. With beta = 1: log-likelihoods +0.5 and -0.5.
    lik = log_likelihood(np.zeros(2), np.array([1.0, 0.0]), GOALS, dt=0.5, beta=1.0)
    assert_allclose(lik, [0.5, -0.5])
    post = belief(update_log_belief(uniform_log_belief(1, 2)[0], lik))
    assert_allclose(post, [1 / (1 + np.exp(-1.0)), 1 / (1 + np.exp(1.0))])  # 0.7311, 0.2689


def test_update_multiplies_prior():
    prior = np.log(np.array([0.2, 0.8]))
    lik = np.array([np.log(3.0), 0.0])  # the action is 3x as likely under g1
    post = belief(update_log_belief(prior, lik))
    assert_allclose(post, [0.6 / 1.4, 0.8 / 1.4])


def test_regret_likelihood_by_hand():
    # Standing still at g1 (s = g1): progress is 0 for both goals, but the best step
    # could have brought g2 0.1 closer, so staying is evidence for g1: +0.1 * beta.
    lik = log_likelihood(GOALS[0], np.zeros(2), GOALS, dt=0.1, beta=2.0, max_step=0.1)
    assert_allclose(lik, [0.0, -0.2])
    # Far from both goals the normaliser is the same for both and cancels.
    s = np.array([0.0, 5.0])
    a = np.array([1.0, 0.0])
    plain = log_likelihood(s, a, GOALS, 0.1, 2.0)
    regret = log_likelihood(s, a, GOALS, 0.1, 2.0, max_step=0.1)
    assert_allclose(regret - regret[0], plain - plain[0])


def test_distance_to_polyline_by_hand():
    goal_sets = np.array([[[0.0, 0.0], [2.0, 0.0]], [[0.0, 3.0], [0.0, 3.0 + 1e-9]]])
    d = distance_to_sets(np.array([[1.0, 1.0], [3.0, 0.0]]), goal_sets)
    assert_allclose(d, [[1.0, np.hypot(1.0, 2.0)], [1.0, np.hypot(3.0, 3.0)]], rtol=1e-6)


@pytest.mark.parametrize("floor", [0.0, 1e-6, 0.1])
def test_beliefs_stay_normalised(floor):
    rng = np.random.default_rng(0)
    log_b = uniform_log_belief(64, 3)
    goals = rng.normal(size=(3, 4))
    for _ in range(200):
        s, a = rng.normal(size=(64, 4)), rng.normal(scale=10, size=(64, 4))
        log_b = update_log_belief(log_b, log_likelihood(s, a, goals, 0.1, 50.0), floor)
        b = belief(log_b)
        assert_allclose(b.sum(-1), 1.0, atol=1e-12)
        assert np.all(b >= floor * (1 - 1e-9))
        assert np.all(np.isfinite(log_b))


def test_floor_mixes_with_uniform():
    post = belief(update_log_belief(np.log([0.5, 0.5]), np.array([0.0, -1e6]), floor=0.01))
    assert_allclose(post, [0.99, 0.01])


def test_bad_parameters_are_clear():
    with pytest.raises(ConfigError, match="belief_beta"):
        log_likelihood(np.zeros(2), np.zeros(2), GOALS, 0.1, -1.0)
    with pytest.raises(ConfigError, match="belief_floor"):
        update_log_belief(np.zeros(2), np.zeros(2), floor=0.5)


@settings(max_examples=50, deadline=None)
@given(
    rows=st.lists(
        st.lists(st.floats(-1e3, 1e3) | st.just(-np.inf), min_size=1, max_size=6), min_size=1, max_size=5
    ).filter(lambda r: len({len(x) for x in r}) == 1)
)
def test_logsumexp_is_scipys(rows):
    from scipy.special import logsumexp as scipy_logsumexp  # noqa: PLC0415

    x = np.array(rows)
    with np.errstate(divide="ignore"):
        expected = scipy_logsumexp(x, axis=-1, keepdims=True)
    np.testing.assert_allclose(logsumexp(x), expected, rtol=1e-13, atol=1e-12)


# --- the cap (Javdani et al.'s max_prob_any_goal) ---------------------------------------------


def test_the_cap_by_hand_four_goals():
    # b = (0.995, 0.003, 0.001, 0.001), cap 0.99: the top gives up 0.005, a third of it to each other goal
    b = np.array([0.995, 0.003, 0.001, 0.001])
    out = belief(cap_log_belief(np.log(b), 0.99))
    assert_allclose(out, [0.99, 0.003 + 0.005 / 3, 0.001 + 0.005 / 3, 0.001 + 0.005 / 3], rtol=0, atol=1e-15)
    # the same through the update: a likelihood that pushes goal 2 above the cap, then the cap
    lik = np.log(np.array([1.0, 1.0, 1000.0, 1.0]))
    post = belief(update_log_belief(np.log(np.full(4, 0.25)), lik, 0.0, 0.99))
    raw = np.array([1.0, 1.0, 1000.0, 1.0]) / 1003.0
    excess = raw[2] - 0.99
    assert_allclose(post, [raw[0] + excess / 3, raw[1] + excess / 3, 0.99, raw[3] + excess / 3], atol=1e-15)


def test_a_capped_belief_near_one_keeps_its_excess_exactly():
    # b_top = 1 - 3e-12: its excess over the cap is (1 - cap) - rest, not 1 - 3e-12 - cap rounded
    log_b = np.log(np.array([1.0 - 3e-12, 1e-12, 1e-12, 1e-12]))
    out = belief(cap_log_belief(log_b, 0.99))
    assert_allclose(out, [0.99, 0.01 / 3, 0.01 / 3, 0.01 / 3], rtol=1e-12)


@settings(max_examples=200, deadline=None)
@given(
    raw=st.lists(st.floats(1e-9, 1.0), min_size=2, max_size=6),
    power=st.floats(0.0, 30.0),
    cap=st.floats(0.501, 0.9999),
)
def test_the_cap_invariants(raw, power, cap):
    """Sums to one, none above the cap, the order kept, and a no-op (bit for bit) when none is above."""
    b = np.asarray(raw) ** power
    log_b = np.log(b / b.sum())
    out = cap_log_belief(log_b, cap)
    p = belief(out)
    assert abs(np.exp(out).sum() - 1.0) < 1e-12
    assert p.max() <= cap + 1e-12
    before = belief(log_b)
    for i in range(len(p)):
        for j in range(len(p)):
            if before[i] > before[j]:
                assert p[i] >= p[j] - 1e-15
    if before.max() <= cap:
        assert np.array_equal(out, log_b)
    else:
        assert p.max() == pytest.approx(cap, abs=1e-12)


def test_the_cap_is_validated_and_none_is_no_cap():
    with pytest.raises(ConfigError, match="belief_cap"):
        cap_log_belief(np.log(np.full(4, 0.25)), 0.5)
    with pytest.raises(ConfigError, match="belief_cap"):
        ControlConfig(belief_cap=1.0)
    assert (
        ControlConfig(belief_cap="none").belief_cap is None
        and ControlConfig(belief_cap="None").belief_cap is None
    )
    log_b = np.log(np.array([0.9999, 1e-4 / 3, 1e-4 / 3, 1e-4 / 3]))
    assert np.array_equal(
        update_log_belief(log_b, np.zeros(4), 0.0, None), update_log_belief(log_b, np.zeros(4))
    )


def test_the_confident_belief_and_its_threshold_follow_the_cap():
    assert_allclose(confident_belief(4, 2, 1e-6, 0.99), [0.01 / 3, 0.01 / 3, 0.99, 0.01 / 3])
    assert_allclose(confident_belief(4, 0, 1e-6), [1 - 3e-6, 1e-6, 1e-6, 1e-6])
    assert confidence_threshold(None) == pytest.approx(0.99) and confidence_threshold(0.99) == pytest.approx(
        0.98
    )
    # the confident belief counts as confident under its own cap, always
    for cap in (None, 0.6, 0.9, 0.99, 0.999):
        assert confident_belief(4, 1, 1e-6, cap).max() > confidence_threshold(cap)


def test_a_long_run_of_evidence_never_takes_a_goal_above_the_cap():
    log_b = uniform_log_belief(3, 4)
    lik = np.log(np.array([[50.0, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 1e6], [1.0, 1.0, 1.0, 1.0]]))
    for _ in range(200):
        log_b = update_log_belief(log_b, lik, 1e-6, 0.99)
        assert belief(log_b).max() <= 0.99 + 1e-12
    assert_allclose(belief(log_b)[:2].max(axis=1), 0.99, atol=1e-12)  # the evidence holds them at the cap
