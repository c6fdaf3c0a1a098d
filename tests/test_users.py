"""Simulated users (Eq. S1): choice distribution, extremes, validation."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from lasa.base.errors import ConfigError
from lasa.method.step import latent_grid
from lasa.people.users import UserPopulation, choose_latent, gumbel_noise, user_costs


def test_costs_by_hand():
    target = np.array([[1.0, 0.0]])
    state = np.zeros((1, 2))
    phi = np.array([[[10.0, 0.0], [0.0, 10.0]]])  # dt = 0.1: next states (1, 0) and (0, 1)
    assert_allclose(user_costs(target, state, phi, 0.1), [[0.0, 2.0]])


def test_choice_frequencies_match_boltzmann():
    rng = np.random.default_rng(0)
    costs = np.array([[0.0, 0.5, 1.0]])
    beta = 2.0
    n = 200_000
    picks = choose_latent(np.repeat(costs, n, 0), np.full(n, beta), gumbel_noise(rng.random((n, 3))))
    freq = np.bincount(picks, minlength=3) / n
    expected = np.exp(-beta * costs[0]) / np.exp(-beta * costs[0]).sum()
    assert_allclose(freq, expected, atol=0.005)


def test_beta_zero_is_uniform_and_infinite_beta_is_optimal():
    rng = np.random.default_rng(1)
    n = 60_000
    costs = np.tile([3.0, 0.0, 1.0, 2.0], (n, 1))
    random = choose_latent(costs, np.zeros(n), gumbel_noise(rng.random((n, 4))))
    assert_allclose(np.bincount(random, minlength=4) / n, 0.25, atol=0.01)
    best = choose_latent(costs, np.full(n, np.inf), gumbel_noise(rng.random((n, 4))))
    assert np.all(best == 1)


def test_non_finite_costs_are_never_chosen():
    costs = np.array([[np.nan, 1.0, np.inf]])
    for beta in (0.0, 1.0, np.inf):
        for seed in range(20):
            u = np.random.default_rng(seed).random((1, 3))
            assert choose_latent(costs, np.array([beta]), gumbel_noise(u))[0] == 1


def test_latent_grid():
    assert_allclose(latent_grid(3)[:, 0], [-1, 0, 1])
    assert latent_grid(5, z_dim=2).shape == (25, 2)


def _population(**kw):
    base = dict(
        goal=np.zeros(2, int),
        theta=np.zeros(2),
        target=np.zeros((2, 3)),
        beta0=np.ones(2),
        slope=np.zeros(2),
        user=np.arange(2),
    )
    base.update(kw)
    return UserPopulation(**base)


def test_beta_schedule():
    users = _population(beta0=np.array([0.0, 5.0]), slope=np.array([2.0, 0.0]))
    assert_allclose(users.beta(0), [0.0, 5.0])
    assert_allclose(users.beta(10), [20.0, 5.0])


@pytest.mark.parametrize(
    "field,value,match",
    [
        ("beta0", np.array([1.0, -1.0]), "beta"),
        ("beta0", np.array([1.0, np.nan]), "beta"),
        ("slope", np.array([-1.0, 0.0]), "slope"),
        ("user", np.arange(3), "user"),
    ],
)
def test_bad_users_are_a_clear_error(field, value, match):
    with pytest.raises(ConfigError, match=match):
        _population(**{field: value})


def test_change_of_mind_switches_exactly_at_n():
    first = np.array([[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]])
    users = _population(target=np.zeros((2, 3)), first_target=first, change_step=np.array([3, 0]))
    assert_allclose(users.target_at(0), [[1, 1, 1], [0, 0, 0]])
    assert_allclose(users.target_at(2), [[1, 1, 1], [0, 0, 0]])  # t < N: still the first target
    assert_allclose(users.target_at(3), [[0, 0, 0], [0, 0, 0]])  # t = N: the true target
    plain = _population()
    assert plain.target_at(5) is plain.target


@pytest.mark.parametrize(
    "steps,match", [(np.array([-1, 2]), "change_step"), (np.array([1.5, 2.0]), "change_step")]
)
def test_bad_change_step_is_a_clear_error(steps, match):
    with pytest.raises(ConfigError, match=match):
        _population(first_target=np.zeros((2, 3)), change_step=steps)
    with pytest.raises(ConfigError, match="go together"):
        _population(first_target=np.zeros((2, 3)))


def test_subset_keeps_every_field():
    users = _population(first_target=np.ones((2, 3)), change_step=np.array([1, 2]))
    one = users.subset(np.array([1]))
    assert len(one) == 1 and one.change_step.tolist() == [2] and one.user.tolist() == [1]


def test_pilot_choice_hand_computed():
    from lasa.people.users import UserPopulation, pilot_choice

    def users(pilot, p):
        n = 3
        return UserPopulation(
            goal=np.zeros(n, int),
            theta=np.zeros(n),
            target=np.zeros((n, 2)),
            beta0=np.ones(n),
            slope=np.zeros(n),
            user=np.arange(n),
            pilot=pilot,
            pilot_prob=p,
        )

    choice, prev = np.array([4, 5, 6]), np.array([0, 1, 2])
    u = np.array([[0.1, 0.0], [0.5, 0.55], [0.9, 0.99]])  # event below p = 0.6 for the first two
    np.testing.assert_array_equal(pilot_choice(users("boltzmann", 0.6), choice, prev, u, 10), choice)
    np.testing.assert_array_equal(pilot_choice(users("laggy", 0.6), choice, prev, u, 10), [0, 1, 6])
    np.testing.assert_array_equal(pilot_choice(users("laggy", 0.6), choice, None, u, 10), choice)
    # noisy: the random input is floor(u2 * K): 0 and 5 for the users whose event fired
    np.testing.assert_array_equal(pilot_choice(users("noisy", 0.6), choice, prev, u, 10), [0, 5, 6])
    assert pilot_choice(users("noisy", 1.0), choice, prev, np.array([[0.0, 1.0]] * 3), 10).max() == 9
