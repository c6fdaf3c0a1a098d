"""The rollout's fast paths give the reference arithmetic's results to the bit."""

import numpy as np
import pytest
import torch

from lasa.method.belief import _distance_no_grad, distance_to_sets_torch, log_likelihood, log_likelihood_torch
from lasa.people.users import choose_latent, gumbel_noise, user_costs


def same_bits(x, y):
    x, y = np.asarray(x), np.asarray(y)
    return x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()


@pytest.mark.parametrize("rows", [1, 5, 63, 64, 500, 2000])
def test_distance_matches_the_differentiable_one(task, rows):
    rng = np.random.default_rng(rows)
    goal_sets = torch.as_tensor(task.curves)
    on_curve = task.curves[:, :-1] + rng.uniform(0, 1, (*task.curves[:, :-1].shape[:2], 1)) * np.diff(
        task.curves, axis=1
    )
    for points in (
        np.tile(task.start, (rows, 1)) + rng.normal(scale=0.3, size=(rows, task.robot.n_joints)),
        on_curve.reshape(-1, task.robot.n_joints)[:rows],
        rng.normal(size=(rows, task.robot.n_joints)),
    ):
        pts = torch.as_tensor(points)
        assert torch.equal(_distance_no_grad(pts, goal_sets), distance_to_sets_torch(pts, goal_sets))


def test_distance_of_non_finite_points(task):
    rng = np.random.default_rng(0)
    goal_sets = torch.as_tensor(task.curves)
    pts = torch.as_tensor(rng.normal(size=(300, task.robot.n_joints)))
    pts[3, 1] = torch.nan
    pts[7, 0] = torch.inf
    assert torch.equal(
        _distance_no_grad(pts, goal_sets).isnan(), distance_to_sets_torch(pts, goal_sets).isnan()
    )
    assert same_bits(
        np.nan_to_num(_distance_no_grad(pts, goal_sets).numpy()),
        np.nan_to_num(distance_to_sets_torch(pts, goal_sets).numpy()),
    )


@pytest.mark.parametrize("max_step", [None, 0.0375])
def test_log_likelihood_matches_torch(task, max_step):
    rng = np.random.default_rng(1)
    n = task.robot.n_joints
    s = task.start + rng.normal(scale=0.3, size=(256, n))
    a = rng.normal(scale=0.3, size=(256, n))
    ref = log_likelihood_torch(
        torch.as_tensor(s), torch.as_tensor(a), torch.as_tensor(task.curves), 0.1, 20.0, max_step
    )
    assert same_bits(log_likelihood(s, a, task.curves, 0.1, 20.0, max_step), ref.numpy())


def test_choice_fast_path_matches_masked_path():
    rng = np.random.default_rng(3)
    costs = rng.random((500, 21))
    gumbel = gumbel_noise(rng.random((500, 21)))
    beta = rng.choice([0.0, 75.0, 1000.0], 500)
    fast = choose_latent(costs, beta, gumbel)
    slow = choose_latent(
        np.where(np.arange(21) == 20, np.inf, np.pad(costs[:, :20], ((0, 0), (0, 1)))), beta, gumbel
    )
    slow_ref = np.argmax(np.where(beta[:, None] > 0, -(beta[:, None] * costs), 0.0) + gumbel, axis=1)
    assert np.array_equal(fast, slow_ref)
    assert np.all(slow < 20)


def test_user_costs_by_hand_and_fallback():
    target, state = np.array([[1.0, 0.0]]), np.zeros((1, 2))
    phi = np.array([[[10.0, 0.0], [0.0, 10.0]]])
    assert same_bits(
        user_costs(target, state, phi, 0.1), np.einsum("ukn,ukn->uk", *(2 * [target[:, None] - 0.1 * phi]))
    )
    assert user_costs(target, state, phi.astype(np.float32), 0.1).dtype == np.float64
