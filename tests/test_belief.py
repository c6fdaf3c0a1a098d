"""Belief update (Alg. 1, line 8) against hand-computed two-goal cases, and invariants."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from lasa.base.errors import ConfigError
from lasa.method.belief import (
    belief,
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
