"""Algorithm 1, batched: one decoder call per step, invariants, determinism."""

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from lasa.base.errors import ConfigError
from lasa.method.step import METHODS, latent_grid, method_alpha
from lasa.people.rollout import rollout
from lasa.people.users import UserPopulation

HORIZON = 25


def make_users(task, n=6, beta=50.0):
    goal = np.arange(n) % 2
    theta = np.linspace(0, 1, n)
    return UserPopulation(
        goal=goal,
        theta=theta,
        target=task.target(goal, theta),
        beta0=np.full(n, beta),
        slope=np.zeros(n),
        user=np.arange(n),
    )


def noise_for(task, n, horizon=HORIZON, seed=0):
    return np.random.default_rng(seed).random((n, horizon, task.robot.control.n_z))


def test_one_decoder_call_per_step_covers_every_user_and_candidate(model, task, monkeypatch):
    users = make_users(task, 7)
    shapes = []
    original = type(model).decode

    def counting(self, z, s, b):
        shapes.append(tuple(z.shape))
        return original(self, z, s, b)

    monkeypatch.setattr(type(model), "decode", counting)
    rollout(model, task, users, 0.2, task.robot.control, HORIZON, noise_for(task, 7))
    n_z = task.robot.control.n_z
    assert shapes == [(7, n_z, 1)] * HORIZON


def test_invariants(model, task):
    users = make_users(task, 8, beta=0.0)  # random users explore the most
    ctl = task.robot.control
    traj = rollout(model, task, users, np.linspace(0, 1, 8), ctl, HORIZON, noise_for(task, 8))
    robot = task.robot
    assert np.all(traj.states >= robot.lower) and np.all(traj.states <= robot.upper)
    assert np.all(np.abs(np.diff(traj.states, axis=0)) <= ctl.dt * ctl.max_joint_speed + 1e-12)
    assert_allclose(traj.beliefs.sum(-1), 1.0, atol=1e-9)
    # every input is a joystick candidate, and a_h is phi of it in the step's context
    assert set(np.unique(traj.z)) <= set(latent_grid(ctl.n_z, 1).ravel())
    assert_allclose(
        traj.human_actions, model.decode_numpy(traj.z, traj.states[:-1], traj.beliefs[:-1]), atol=1e-6
    )
    assert np.all(np.linalg.norm(traj.human_actions, axis=-1) <= ctl.action_scale + 1e-6)
    assert_allclose(traj.states[0], np.broadcast_to(task.start, traj.states[0].shape))


def test_alpha_zero_and_one(model, task):
    users = make_users(task, 2)
    ctl = task.robot.control
    traj = rollout(model, task, users, np.array([0.0, 1.0]), ctl, HORIZON, noise_for(task, 2))
    assert_allclose(traj.actions[:, 0], traj.human_actions[:, 0])  # LA: a = a_h
    b, s = traj.beliefs[:-1, 1], traj.states[:-1, 1]
    assert_allclose(traj.actions[:, 1], b @ task.goals - s)  # full autonomy: a = a_r


def test_same_seed_same_trajectories(model, task):
    users = make_users(task, 4)
    ctl = task.robot.control
    a = rollout(model, task, users, 0.2, ctl, HORIZON, noise_for(task, 4))
    b = rollout(model, task, users, 0.2, ctl, HORIZON, noise_for(task, 4))
    c = rollout(model, task, users, 0.2, ctl, HORIZON, noise_for(task, 4, seed=1))
    assert_array_equal(a.states, b.states)
    assert not np.array_equal(a.states, c.states)


def test_a_user_does_not_depend_on_its_batch(model, task):
    users = make_users(task, 4)
    ctl = task.robot.control
    noise = noise_for(task, 4)
    full = rollout(model, task, users, 0.2, ctl, HORIZON, noise)
    one = users.subset(np.array([2]))
    alone = rollout(model, task, one, 0.2, ctl, HORIZON, noise)
    assert_allclose(alone.states[:, 0], full.states[:, 2], atol=1e-5)


def test_method_alpha_and_unknown_method(task):
    ctl = task.robot.control
    assert method_alpha("LA", ctl) == 0.0
    assert method_alpha("LA+SA", ctl) == ctl.alpha
    assert method_alpha("LA+SA+Entropy", ctl) == ctl.alpha
    assert set(METHODS) == {"LA", "LA+SA", "LA+SA+Entropy"}
    with pytest.raises(ConfigError, match="unknown method 'SA'"):
        method_alpha("SA", ctl)


def test_bad_arguments_are_clear(model, task):
    users = make_users(task, 2)
    ctl = task.robot.control
    with pytest.raises(ConfigError, match="noise"):
        rollout(model, task, users, 0.2, ctl, HORIZON, np.zeros((2, 3, 4)))
    with pytest.raises(ConfigError, match="horizon"):
        rollout(model, task, users, 0.2, ctl, 0, noise_for(task, 2))
    with pytest.raises(ConfigError, match="alpha"):
        rollout(model, task, users, 1.5, ctl, HORIZON, noise_for(task, 2))


def test_bad_members_and_pilot_noise_are_clear(model, task):
    users, ctl, noise = make_users(task, 2), task.robot.control, noise_for(task, 2)
    with pytest.raises(ConfigError, match=r"one member per row, shape \(2,\), got \(3,\)"):
        rollout(model, task, users, 0.2, ctl, HORIZON, noise, assistance=np.array(["point"] * 3))
    with pytest.raises(ConfigError, match="unknown assistance 'nearest'; choose one of"):
        rollout(model, task, users, 0.2, ctl, HORIZON, noise, assistance=np.array(["point", "nearest"]))
    laggy = dataclasses.replace(users, pilot="laggy", pilot_prob=0.3)
    for bad in (None, np.zeros((2, HORIZON - 1, 2)), np.zeros((2, HORIZON, 3))):
        with pytest.raises(
            ConfigError, match=r"a laggy pilot needs pilot_noise of shape \(streams, >= 25, 2\)"
        ):
            rollout(model, task, laggy, 0.2, ctl, HORIZON, noise, pilot_noise=bad)
    rollout(model, task, laggy, 0.2, ctl, HORIZON, noise, pilot_noise=np.full((2, HORIZON, 2), 0.5))


def test_step_never_commands_outside_limits_for_random_huge_or_nan_input(model, task):
    from lasa.method.belief import belief, uniform_log_belief
    from lasa.method.step import shared_autonomy_step

    rng = np.random.default_rng(0)
    robot, ctl = task.robot, task.robot.control
    n_users = 400
    s = rng.uniform(robot.lower, robot.upper, size=(n_users, robot.n_joints))
    log_b = uniform_log_belief(n_users, task.n_goals)
    z = np.concatenate(
        [
            rng.uniform(-1, 1, (100, 1)),
            rng.normal(scale=1e12, size=(100, 1)),
            np.full((100, 1), np.nan),
            np.where(rng.random((100, 1)) < 0.5, np.inf, -np.inf),
        ]
    )
    for alpha in (0.0, ctl.alpha, 1.0):
        for _ in range(20):
            out = shared_autonomy_step(model, task, ctl, s, log_b, z, alpha)
            assert np.all(np.isfinite(out.state))
            assert np.all(out.state >= robot.lower) and np.all(out.state <= robot.upper)
            assert np.all(np.abs(out.state - s) <= ctl.dt * ctl.max_joint_speed + 1e-12)
            assert_allclose(belief(out.log_belief).sum(-1), 1.0, atol=1e-9)
            assert np.all(out.human_action[200:] == 0.0)  # non-finite input: no human action
            s, log_b = out.state, out.log_belief


def test_step_matches_the_rollout(model, task):
    """The rollout's step is the teleoperation step, for the inputs the users chose."""
    from lasa.method.belief import uniform_log_belief
    from lasa.method.step import shared_autonomy_step

    users = make_users(task, 3)
    ctl = task.robot.control
    traj = rollout(model, task, users, 0.2, ctl, 5, noise_for(task, 3, horizon=5))
    s, log_b = traj.states[0], uniform_log_belief(3, task.n_goals)
    for t in range(5):
        out = shared_autonomy_step(model, task, ctl, s, log_b, traj.z[t], 0.2)
        assert_allclose(out.state, traj.states[t + 1], atol=1e-6)
        s, log_b = out.state, out.log_belief


def test_the_stick_at_rest_is_a_named_choice(model, task):
    """rest="decode" commands phi(0, s, b); rest="zero" commands nothing there, and the same elsewhere."""
    from lasa.method.belief import belief, uniform_log_belief
    from lasa.method.step import shared_autonomy_step

    control = task.robot.control
    state = np.stack([task.start, task.goals[0], task.goals[1]])
    log_b = uniform_log_belief(3, task.n_goals)
    z = np.array([[0.0], [0.5], [0.0]])
    decoded = shared_autonomy_step(model, task, control, state, log_b, z, 0.0, rest="decode")
    zero = shared_autonomy_step(model, task, control, state, log_b, z, 0.0, rest="zero")
    phi = model.decode_numpy(z, state, belief(log_b))
    assert np.abs(phi[[0, 2]]).max() > 0  # the decoder moves the arm at z = 0 ...
    assert_array_equal(decoded.human_action, phi)  # ... and "decode" commands it
    assert_array_equal(zero.human_action[[0, 2]], 0.0)  # "zero" commands nothing at rest
    assert_array_equal(zero.human_action[1], decoded.human_action[1])
    assert_array_equal(zero.state[0], state[0])  # alpha = 0: the arm holds
    with pytest.raises(ConfigError, match="rest"):
        shared_autonomy_step(model, task, control, state, log_b, z, 0.0, rest="hold")


def test_the_users_chooser_is_eq_s1_written_out_per_user(model, task):
    """BoltzmannUsers against Eq. S1 by hand, one user and one candidate at a time: each user's
    cost ||s* - (s + dt phi(z))||^2, Gumbel-max over -beta cost, and a laggy pilot's repeat."""
    import math

    from lasa.method.belief import belief, uniform_log_belief
    from lasa.method.runner import Now
    from lasa.people.rollout import BoltzmannUsers

    control = task.robot.control
    users = dataclasses.replace(make_users(task, n=4, beta=30.0), pilot="laggy", pilot_prob=0.5)
    noise, pilot = noise_for(task, 4, horizon=2, seed=3), np.random.default_rng(4).random((4, 2, 2))
    chooser = BoltzmannUsers(model, users, control, 2, noise, pilot)
    rng = np.random.default_rng(5)
    state = task.start + 0.05 * rng.standard_normal((4, task.robot.n_joints))
    log_b = uniform_log_belief(4, task.n_goals)
    grid = np.linspace(-1.0, 1.0, control.n_z)
    previous = [None] * 4
    for t in range(2):
        a_h = chooser(Now(t, np.arange(4), state, belief(log_b), log_b))
        for u in range(4):
            s, target, beta = state[u], users.target_at(t)[u], users.beta(t)[u]
            phis = [model.decode_numpy(np.array([[z]]), s[None], belief(log_b[u : u + 1]))[0] for z in grid]
            costs = [float(np.sum((target - (s + control.dt * phi)) ** 2)) for phi in phis]
            gumbel = [-math.log(-math.log(x)) for x in noise[users.user[u], t]]
            k = int(np.argmax([-beta * c + g for c, g in zip(costs, gumbel, strict=True)]))
            event = pilot[users.user[u], t, 0] < 0.5
            k = previous[u] if (event and previous[u] is not None) else k
            previous[u] = k
            assert chooser.z[t, u, 0] == grid[k], (t, u)
            assert_allclose(a_h[u], phis[k], atol=1e-6)
