"""The one episode runner: recording, stopping, determinism, and a batch as its rows run alone.

The reference is tests/reference_step.py, Algorithm 1's step written again from the paper's
equations one user at a time; nothing there calls lasa's step.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from reference_step import softmax, step_with

from lasa.base.errors import ConfigError
from lasa.method.belief import uniform_log_belief
from lasa.method.decoder import DecoderConfig, LatentActionModel
from lasa.method.runner import Now, Runner
from lasa.method.step import Assist
from lasa.world.robot import load_robot
from lasa.world.task import make_cup_task

TASK = make_cup_task(load_robot("planar5"))


def _decoder(seed: int = 0) -> LatentActionModel:
    torch.manual_seed(seed)
    cfg = DecoderConfig(
        robot="planar5", n_joints=5, n_goals=2, z_dim=1, hidden=16, depth=2, action_scale=0.375
    )
    return LatentActionModel(cfg).eval()


def _held(decoder, z: np.ndarray):
    """A chooser that holds each episode's input z[row] and decodes it (the stick at rest decoded too)."""

    def choose(now: Now) -> np.ndarray:
        return decoder.decode_numpy(z[now.rows], now.state, now.belief)

    return choose


def _runner(n_users: int, alpha: float, **kw) -> Runner:
    assist = Assist(TASK, TASK.robot.control, np.full(n_users, alpha))
    start = np.broadcast_to(TASK.start, (n_users, TASK.robot.n_joints))
    return Runner(assist, start, uniform_log_belief(n_users, TASK.n_goals), **kw)


def test_the_record_follows_the_reference_step_by_step():
    """Every recorded state and belief is the reference step's, from the chooser's a_h."""
    decoder, z = _decoder(), np.array([[-0.7], [0.0], [0.9]])
    control = TASK.robot.control
    record = _runner(3, 0.4).run(_held(decoder, z), horizon=12)
    assert record.states.shape == (13, 3, 5) and record.human_actions.shape == (12, 3, 5)
    assert_array_equal(record.states[0], np.broadcast_to(TASK.start, (3, 5)))
    assert_array_equal(record.end, [12, 12, 12])
    for u in range(3):
        s, b = TASK.start.copy(), np.full(2, 0.5)
        for t in range(12):
            a_h = decoder.decode_numpy(z[u][None], s[None], b[None])[0]
            ref = step_with(TASK, control, s, b, a_h, 0.4)
            # float32 decoding in a batch of 3 and of 1 differ in the last bits: 1e-6 is float32's
            assert_allclose(record.human_actions[t, u], a_h, atol=1e-6)
            assert_allclose(record.actions[t, u], ref["a"], atol=1e-6)
            s, b = ref["s"], ref["b"]
            assert_allclose(record.states[t + 1, u], s, atol=1e-6)
            assert_allclose(record.beliefs[t + 1, u], b, atol=1e-6)


def test_an_observer_stops_episodes_and_the_record_holds_them():
    """An episode stops at the step its observer says; its state is held and its actions are zero."""
    decoder, z = _decoder(), np.array([[0.8], [0.8], [-0.8]])
    stop_at = np.array([3, 7, 99])

    def observe(t: int, runner: Runner) -> np.ndarray:
        assert runner.t == t  # observed after t steps
        return stop_at == t

    record = _runner(3, 0.0).run(_held(decoder, z), horizon=10, observe=observe)
    assert_array_equal(record.end, [3, 7, 10])
    for u, k in enumerate([3, 7, 10]):
        assert_array_equal(
            record.states[k:, u], np.broadcast_to(record.states[k, u], record.states[k:, u].shape)
        )
        assert not np.any(record.human_actions[k:, u])
        assert np.all(np.any(record.human_actions[:k, u] != 0.0, axis=-1))
    alone = _runner(1, 0.0).run(_held(decoder, z[:1]), horizon=3)  # the stopped row ran as it would alone
    assert_allclose(record.states[:4, 0], alone.states[:, 0], atol=1e-6)


def test_when_every_episode_stops_the_run_ends_early():
    calls = []

    def choose(now: Now) -> np.ndarray:
        calls.append(now.t)
        return np.zeros((len(now.rows), 5))

    record = _runner(2, 0.0).run(choose, horizon=50, observe=lambda t, r: np.full(2, t == 4))
    assert calls == [0, 1, 2, 3] and list(record.end) == [4, 4]
    assert_array_equal(record.states[4:], np.broadcast_to(record.states[4], record.states[4:].shape))


def test_a_held_belief_stays_and_the_run_is_deterministic():
    decoder, z = _decoder(3), np.array([[0.5], [-0.2]])
    held = _runner(2, 0.0, update_belief=False).run(_held(decoder, z), horizon=8)
    assert_array_equal(held.beliefs, np.full((9, 2, 2), 0.5))
    again = [_runner(2, 0.3).run(_held(decoder, z), horizon=8) for _ in range(2)]
    for field in ("states", "beliefs", "human_actions", "actions", "end"):
        assert_array_equal(getattr(again[0], field), getattr(again[1], field))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    z=st.lists(st.floats(-1.0, 1.0), min_size=1, max_size=5),
    alpha=st.lists(st.floats(0.0, 1.0), min_size=5, max_size=5),
    stops=st.lists(st.integers(1, 9), min_size=5, max_size=5),
)
def test_a_batch_is_its_rows_run_alone(z, alpha, stops):
    """Each row of a batch, with its own alpha and stopping step, is that row run alone.

    The chooser is row-wise NumPy (a pull of strength z towards goal 0), so any difference beyond BLAS
    rounding (the assistance's b @ goals is a matrix product of the batch) is the runner's.
    """
    n = len(z)
    zs, alphas, stop = np.array(z)[:, None], np.array(alpha[:n]), np.array(stops[:n])

    def pull(z_rows: np.ndarray):
        return lambda now: z_rows[now.rows] * (TASK.goals[0] - now.state)

    start = np.broadcast_to(TASK.start, (n, 5))
    batch = Runner(Assist(TASK, TASK.robot.control, alphas), start, uniform_log_belief(n, 2))
    record = batch.run(pull(zs), horizon=10, observe=lambda t, r: stop == t)
    for u in range(n):
        one = Runner(Assist(TASK, TASK.robot.control, alphas[u : u + 1]), start[:1], uniform_log_belief(1, 2))
        alone = one.run(pull(zs[u : u + 1]), horizon=int(stop[u]))
        assert_allclose(record.states[: stop[u] + 1, u], alone.states[:, 0], rtol=0, atol=1e-12)
        assert_allclose(record.beliefs[: stop[u] + 1, u], alone.beliefs[:, 0], rtol=0, atol=1e-12)


def test_bad_batches_are_refused():
    assist = Assist(TASK, TASK.robot.control, np.zeros(2))
    with pytest.raises(ConfigError, match="log_belief"):
        Runner(assist, np.zeros((2, 5)), np.zeros((2, 3)))
    with pytest.raises(ConfigError, match="2 rows, the batch 3"):
        Runner(assist, np.zeros((3, 5)), uniform_log_belief(3, 2))
    with pytest.raises(ConfigError, match="horizon"):
        _runner(1, 0.0).run(lambda now: np.zeros((1, 5)), horizon=0)


def test_the_belief_property_is_the_softmax_of_the_log_belief():
    runner = _runner(1, 0.0)
    runner.log_belief[:] = [[0.3, -1.2]]
    assert_allclose(runner.belief[0], softmax(np.array([0.3, -1.2])), atol=1e-15)


@settings(max_examples=25, deadline=None)
@given(
    alphas=st.lists(st.sampled_from([0.0, 0.0, 0.3, 1.0]), min_size=1, max_size=6),
    member=st.sampled_from(["hindsight", "hindsight_point", "grasp_set", "arbitrated"]),
    seed=st.integers(0, 2**16),
)
def test_rows_without_assistance_skip_it_and_step_the_same(alphas, member, seed):
    """With Assist.only_blended, advance computes a_r only in the rows whose alpha is above 0: the
    step (state, belief, blended action) is the one that computes a_r everywhere, to the bit, for
    every member that computes a row from that row alone (all built-in ones but point, whose matrix
    product rounds by batch size); the skipped rows' robot_action is zero, and by default it is the
    would-be assistance a_r w."""
    from lasa.method.assistance import assist
    from lasa.method.belief import belief
    from lasa.method.step import advance

    rng = np.random.default_rng(seed)
    n, alpha = len(alphas), np.array(alphas)
    state = TASK.start + rng.normal(0.0, 0.3, (n, 5))
    log_b = np.log(rng.dirichlet(np.ones(2), n))
    a_h = rng.normal(0.0, 0.3, (n, 5))
    members = np.full(n, member)
    skip = advance(Assist(TASK, TASK.robot.control, alpha, members, only_blended=True), state, log_b, a_h)
    full = advance(Assist(TASK, TASK.robot.control, alpha, members), state, log_b, a_h)
    for name in ("state", "log_belief", "human_action", "action"):
        assert getattr(skip, name).tobytes() == getattr(full, name).tobytes(), name
    helped = alpha > 0
    assert (skip.robot_action[~helped] == 0).all()
    assert skip.robot_action[helped].tobytes() == full.robot_action[helped].tobytes()
    control = TASK.robot.control
    a_r, w = assist(
        member, belief(log_b), state, TASK.goals, TASK.preference_sets, control.dt, control.action_scale
    )
    assert_allclose(
        full.robot_action[~helped], (a_r * w[:, None])[~helped], rtol=0, atol=1e-15
    )  # would-be a_r
    assert_allclose(belief(skip.log_belief).sum(-1), 1.0)
