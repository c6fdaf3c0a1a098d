"""The single-user step (lasa.method.controller) against the batched reference step, over every option.

There is one implementation of Algorithm 1's step (:func:`lasa.method.step.shared_autonomy_step`);
the Controller runs it for one user and keeps that user's state and belief. These
property tests draw the whole option space (both likelihoods, every assistance member
of lasa.method.assistance, belief floor 0 and > 0,
alpha at 0, 1 and between, decoder depths, 1- and 2-axis joysticks, a task grown by a
new goal through the context map) with random states, beliefs and inputs, NaN and huge
ones included, and check that the Controller follows the user's row of a batched run
step for step, and that the safety invariants hold.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest
import torch
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lasa.base.errors import ConfigError
from lasa.method.assistance import ASSISTANCE
from lasa.method.belief import belief
from lasa.method.controller import Controller
from lasa.method.decoder import DecoderConfig, LatentActionModel
from lasa.method.newgoals import ContextMap, MappedDecoder, extend_task
from lasa.method.step import shared_autonomy_step
from lasa.world.robot import load_robot
from lasa.world.task import make_cup_task

REF = 1


@functools.cache
def _task(grown: bool):
    task = make_cup_task(load_robot("planar5"))
    return extend_task(task, task.robot.goal_positions()[REF] + [0.12, 0.0, 0.0], REF) if grown else task


@functools.cache
def _decoder(depth: int, z_dim: int, grown: bool):
    """An untrained decoder of the given shape (its weights are random, its arithmetic is real)."""
    task = _task(False)
    torch.manual_seed(depth * 10 + z_dim)
    cfg = DecoderConfig(
        robot="planar5", n_joints=5, n_goals=2, z_dim=z_dim, hidden=16, depth=depth, action_scale=0.375
    )
    model = LatentActionModel(cfg).eval()
    if not grown:
        return model
    return MappedDecoder(model, ContextMap.for_task(_task(True), task.n_goals, REF))


joystick = st.one_of(
    st.floats(-1.5, 1.5),
    st.sampled_from([np.nan, np.inf, -np.inf, 1e12, -1e12]),
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    likelihood=st.sampled_from(["preferences", "goal"]),
    assistance=st.sampled_from(ASSISTANCE),
    floor=st.sampled_from([0.0, 1e-6, 0.05]),
    alpha=st.one_of(st.sampled_from([0.0, 1.0]), st.floats(0.0, 1.0)),
    depth=st.sampled_from([1, 3]),
    z_dim=st.sampled_from([1, 2]),
    grown=st.booleans(),
    seed=st.integers(0, 2**16),
    inputs=st.lists(st.lists(joystick, min_size=2, max_size=2), min_size=1, max_size=6),
)
def test_controller_follows_its_row_of_the_batched_step(
    likelihood, assistance, floor, alpha, depth, z_dim, grown, seed, inputs
):
    task = _task(grown)
    decoder = _decoder(depth, z_dim, grown)
    control = dataclasses.replace(
        task.robot.control, likelihood=likelihood, belief_floor=floor, assistance=assistance
    )
    rng = np.random.default_rng(seed)
    robot, n_users, row = task.robot, 4, 2
    s = rng.uniform(robot.lower, robot.upper, (n_users, robot.n_joints))
    log_b = np.log(rng.dirichlet(np.ones(task.n_goals), n_users))
    ctl = Controller(decoder, task, control, alpha)
    ctl.reset(s[row], log_b[row])
    for z_user in inputs:
        z = rng.uniform(-1, 1, (n_users, z_dim))
        z[row] = z_user[:z_dim]
        ref = shared_autonomy_step(decoder, task, control, s, log_b, z, alpha)
        out = ctl.step(z[row])
        # the same arithmetic; a batch of 4 and a batch of 1 may round float32 products differently
        np.testing.assert_allclose(out, ref.state[row], atol=1e-6)
        np.testing.assert_allclose(ctl.log_belief, ref.log_belief[row], atol=1e-5)
        # safety: limits, step bound, a distribution, no command from a non-finite input
        assert np.all(out >= robot.lower) and np.all(out <= robot.upper)
        assert np.all(np.abs(out - s[row]) <= control.dt * control.max_joint_speed + 1e-12)
        np.testing.assert_allclose(ctl.belief.sum(), 1.0)
        assert ctl.belief.min() >= floor * (1 - 1e-9)
        assert ctl.last is not None
        if not np.all(np.isfinite(z[row])):
            np.testing.assert_array_equal(ctl.last.human_action[0], 0.0)
        s, log_b = ref.state, ref.log_belief


@pytest.mark.parametrize("alpha", [0.0, 1.0])
def test_alpha_endpoints_by_hand(alpha):
    """alpha = 0 moves by dt * phi alone (LA); alpha = 1 by dt * a_r alone, a_r = sum_g b(g)(g - s)."""
    task = _task(False)
    decoder = _decoder(3, 1, False)
    control = task.robot.control
    ctl = Controller(decoder, task, control, alpha)
    s0, b0 = ctl.state.copy(), ctl.belief.copy()
    out = ctl.step(0.4)
    phi = decoder.decode_numpy(np.array([0.4]), s0, b0)
    a_r = b0 @ task.goals - s0
    a = phi if alpha == 0.0 else a_r
    expected = np.clip(
        s0 + control.dt * np.clip(a, -control.max_joint_speed, control.max_joint_speed),
        task.robot.lower,
        task.robot.upper,
    )
    np.testing.assert_allclose(out, expected, atol=1e-6)


def test_scalar_and_array_inputs_agree_and_bad_shapes_are_refused():
    task = _task(False)
    a = Controller(_decoder(3, 1, False), task, task.robot.control, 0.2)
    b = Controller(_decoder(3, 1, False), task, task.robot.control, 0.2)
    for z in (0.3, -1.0, 0.9):
        np.testing.assert_array_equal(a.step(z), b.step(np.array([z])))
    with pytest.raises(ConfigError, match="z must have 1"):
        a.step(np.zeros(2))
    with pytest.raises(ConfigError, match="state"):
        a.reset(np.full(5, np.nan))
    with pytest.raises(ConfigError, match="alpha"):
        Controller(_decoder(3, 1, False), task, task.robot.control, 1.5)
    a.reset()
    np.testing.assert_array_equal(a.state, task.start)
    np.testing.assert_allclose(a.belief, np.full(task.n_goals, 1 / task.n_goals))


def test_a_decoder_for_another_task_is_refused(panda_task):
    with pytest.raises(ConfigError, match="trained for 'planar5'"):
        Controller(_decoder(3, 1, False), panda_task, panda_task.robot.control, 0.2)
    with pytest.raises(ConfigError, match="MappedDecoder"):
        Controller(_decoder(3, 1, False), _task(True), _task(True).robot.control, 0.2)


def test_belief_property_matches_log_belief():
    task = _task(False)
    ctl = Controller(_decoder(1, 2, False), task, task.robot.control, 0.2)
    for z in ([0.5, -0.5], [np.nan, 0.0], [1.0, 1.0]):
        ctl.step(np.array(z))
        np.testing.assert_allclose(ctl.belief, belief(ctl.log_belief))
