"""The context map h(s, b) for goals added after training (Sec. IV-C), and Fig. sim4."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError, IKError
from lasa.experiments import sim4
from lasa.experiments.sim4 import analysis, episodes
from lasa.method.assistance import point
from lasa.method.belief import belief, belief_targets, log_likelihood, uniform_log_belief, update_log_belief
from lasa.method.context_map import (
    JOINT_KINDS,
    ContextMap,
    MappedDecoder,
    TaskSpaceMap,
    context_map,
    extend_task,
)
from lasa.method.step import shared_autonomy_step
from lasa.people.rollout import rollout
from lasa.people.users import UserPopulation

REF = 1  # the right-hand cup is the reference in these tests


@pytest.fixture(scope="module")
def grown(task):
    """planar5's task with a new cup 0.12 m beyond the right-hand one."""
    return extend_task(task, task.robot.goal_positions()[REF] + [0.12, 0.0, 0.0], REF)


@pytest.fixture(scope="module")
def panda_rotated(panda_task):
    """The Panda's task with a new cup on the reference cup's circle about the base, 0.3 rad on."""
    arm = panda_task.robot
    base, cup = arm.base_position(), arm.goal_positions()[REF]
    rel = cup - base
    radius, bearing = np.hypot(rel[0], rel[1]), np.arctan2(rel[1], rel[0])
    pos = base + [radius * np.cos(bearing - 0.3), radius * np.sin(bearing - 0.3), 0.0]
    pos[2] = cup[2]
    return extend_task(panda_task, pos, REF)


def _duplicate(task, kind="grasp"):
    """A 'new' goal standing exactly on the reference cup: a context at a training goal."""
    dup = dataclasses.replace(
        task,
        goal_names=(*task.goal_names, "copy"),
        curves=np.concatenate([task.curves, task.curves[REF][None]]),
        goals=np.concatenate([task.goals, task.goals[REF][None]]),
    )
    return ContextMap.for_task(dup, task.n_goals, REF, kind)


@pytest.mark.parametrize("kind", JOINT_KINDS)
def test_h_is_the_identity_at_a_training_goal(task, kind):
    cmap = _duplicate(task, kind)
    rng = np.random.default_rng(0)
    states = task.start + rng.normal(0, 0.6, (50, task.robot.n_joints))
    states = np.concatenate([states, task.curves[REF]])
    np.testing.assert_allclose(cmap.state(states), states, atol=1e-12)
    np.testing.assert_allclose(
        cmap.jacobian(states), np.broadcast_to(np.eye(5), (len(states), 5, 5)), atol=1e-12
    )
    actions = rng.normal(size=states.shape)
    np.testing.assert_allclose(cmap.action_from_training(actions, states), actions, atol=1e-12)
    # The belief of the duplicate joins the reference's: the training belief comes back.
    b = np.array([[0.2, 0.3, 0.5], [0.6, 0.1, 0.3]])
    np.testing.assert_allclose(cmap.belief(b), [[0.2, 0.8], [0.6, 0.4]])


def test_h_is_the_identity_at_the_start(grown):
    cmap = ContextMap.for_task(grown, 2, REF)
    assert cmap.weight(grown.start) == 0.0
    np.testing.assert_allclose(cmap.state(grown.start), grown.start)


def test_grasp_map_sends_each_new_grasp_to_the_same_training_grasp(task, grown):
    cmap = ContextMap.for_task(grown, 2, REF, "grasp")
    # w = 1 on the whole new curve: its least progress is lambda_1 itself, up to rounding (the
    # last bit differs between CPUs: 1 - 1e-16 on an Intel Xeon)
    np.testing.assert_allclose(cmap.weight(grown.curves[-1]), 1.0, rtol=0.0, atol=1e-12)
    mapped = cmap.state(grown.curves[-1])
    # exact up to the soft assignment's smoothing over neighbouring grasps
    assert np.abs(mapped - task.curves[REF]).max() < 0.01
    # The straight-line map moves the reference curve rigidly: only the mid grasp is exact.
    line = ContextMap.for_task(grown, 2, REF, "straight_line")
    np.testing.assert_allclose(line.state(grown.goals[-1]), task.goals[REF], atol=1e-12)
    assert np.abs(line.state(grown.curves[-1]) - task.curves[REF]).max() > 0.05


def test_panda_new_cup_on_the_circle_is_a_joint1_rotation(panda_task, panda_rotated):
    offset = panda_rotated.curves[-1] - panda_task.curves[REF]
    expected = np.zeros(7)
    expected[0] = -0.3
    assert np.abs(offset - expected).max() < 2e-3  # IK tolerance
    for kind in JOINT_KINDS:
        cmap = ContextMap.for_task(panda_rotated, 2, REF, kind)
        assert np.abs(cmap.state(panda_rotated.curves[-1]) - panda_task.curves[REF]).max() < 2e-3


@pytest.mark.parametrize("kind", JOINT_KINDS)
def test_jacobian_matches_finite_differences(grown, kind):
    cmap = ContextMap.for_task(grown, 2, REF, kind)
    rng = np.random.default_rng(1)
    # points along the way (0 < w < 1) and near the new cup's grasps (w = 1)
    lam = rng.uniform(0.2, 0.7, 6)[:, None]
    states = np.concatenate(
        [
            grown.start + lam * (grown.goals[-1] - grown.start) + rng.normal(0, 0.05, (6, 5)),
            grown.curves[-1][::8] + rng.normal(0, 0.03, (6, 5)),
        ]
    )
    eps = 1e-6
    for s in states:
        numeric = np.stack(
            [(cmap.state(s + eps * e) - cmap.state(s - eps * e)) / (2 * eps) for e in np.eye(5)], axis=1
        )
        np.testing.assert_allclose(cmap.jacobian(s), numeric, atol=1e-5)


@pytest.mark.parametrize("kind", JOINT_KINDS)
def test_action_round_trip(grown, kind):
    cmap = ContextMap.for_task(grown, 2, REF, kind)
    rng = np.random.default_rng(2)
    states = grown.start + rng.uniform(0, 1.2, (20, 1)) * (grown.goals[-1] - grown.start)
    actions = rng.normal(size=(20, 4, 5))  # 4 candidates per state share its Jacobian
    there = cmap.action_to_training(actions, states[:, None])
    back = cmap.action_from_training(there, states[:, None])
    np.testing.assert_allclose(back, actions, atol=1e-10)
    assert not np.allclose(there, actions)  # the map is not trivially the identity here


def test_belief_map_is_a_distribution(grown):
    cmap = ContextMap.for_task(grown, 2, REF)
    b = np.random.default_rng(3).dirichlet(np.ones(3), 100)
    hat = cmap.belief(b)
    np.testing.assert_allclose(hat.sum(-1), 1.0)
    np.testing.assert_allclose(hat[:, REF], b[:, REF] + b[:, 2])
    with pytest.raises(ConfigError, match="over 3 goals"):
        cmap.belief(b[:, :2])


def test_new_goal_belief_update_and_assistance(grown):
    control = grown.robot.control
    s = grown.start[None]
    toward_new = (grown.goals[-1] - grown.start)[None]
    toward_new *= control.action_scale / np.linalg.norm(toward_new)
    goal_sets = belief_targets(grown, control.likelihood)
    assert goal_sets.shape[0] == 3
    log_b = uniform_log_belief(1, 3)
    for _ in range(5):
        lik = log_likelihood(
            s, toward_new, goal_sets, control.dt, control.belief_beta, control.likelihood_step
        )
        log_b = update_log_belief(log_b, lik, control.belief_floor)
        s = s + control.dt * toward_new
    b = belief(log_b)[0]
    np.testing.assert_allclose(b.sum(), 1.0)
    assert b[2] > b[0] and b[2] > 1 / 3  # moving at the new cup makes it the likeliest
    # Eq. M2 with three goals, by hand: sum_g b(g) (g - s)
    b3 = np.array([[0.1, 0.2, 0.7]])
    expected = sum(b3[0, g] * (grown.goals[g] - s[0]) for g in range(3))
    np.testing.assert_allclose(point(b3, s, grown.goals, None, 0.0, 0.0)[0][0], expected)
    np.testing.assert_allclose(
        point(np.array([[0.0, 0.0, 1.0]]), s, grown.goals, None, 0.0, 0.0)[0][0], grown.goals[-1] - s[0]
    )


def test_grown_robot_has_the_new_cup(grown, task):
    cups = grown.robot.goal_positions()
    assert cups.shape == (3, 3)
    np.testing.assert_allclose(cups[:2], task.robot.goal_positions())
    np.testing.assert_allclose(cups[2], task.robot.goal_positions()[REF] + [0.12, 0, 0], atol=1e-12)
    assert grown.goal_names[-1] == "new"


@pytest.mark.parametrize(
    "where, error, match",
    [
        ([0.6, 0.1], ConfigError, "outside planar5's workspace: the arm moves in a vertical plane"),
        ([2.0, 0.0], ConfigError, "outside planar5's workspace: the table"),
        ([0.48, 0.0], ConfigError, "overlaps goal 'cup_right'"),
        ([0.55, 0.0, 0.5], ConfigError, "stands on the table"),
        ([float("nan"), 0.0], ConfigError, "finite"),
    ],
)
def test_bad_new_cup_is_a_clear_error(task, where, error, match):
    with pytest.raises(error, match=match):
        extend_task(task, np.array(where), REF)


def test_unreachable_new_cup_is_a_clear_error(panda_task):
    # on the table, but beyond the Panda's reach for a side grasp
    with pytest.raises(IKError, match="out of panda's reach"):
        extend_task(panda_task, np.array([0.85, -0.55]), REF)


def test_bad_ref_goal(task):
    with pytest.raises(ConfigError, match="ref_goal"):
        extend_task(task, np.array([0.6, 0.0]), 2)


def test_rollout_needs_the_map_for_a_grown_task(model, grown):
    users = UserPopulation(
        goal=np.array([2]),
        theta=np.array([0.5]),
        target=grown.goals[-1:],
        beta0=np.array([1000.0]),
        slope=np.zeros(1),
        user=np.zeros(1, dtype=int),
    )
    noise = np.random.default_rng(0).random((1, 5, grown.robot.control.n_z))
    with pytest.raises(ConfigError, match="MappedDecoder"):
        rollout(model, grown, users, 0.2, grown.robot.control, 5, noise)
    mapped = MappedDecoder(model, ContextMap.for_task(grown, 2, REF))
    assert (mapped.robot, mapped.n_goals, mapped.z_dim) == ("planar5", 3, 1)
    traj = rollout(mapped, grown, users, 0.2, grown.robot.control, 5, noise)
    assert traj.beliefs.shape == (6, 1, 3)
    np.testing.assert_allclose(traj.beliefs.sum(-1), 1.0)


def test_single_step_with_the_map_is_safe(model, grown):
    control = grown.robot.control
    mapped = MappedDecoder(model, ContextMap.for_task(grown, 2, REF))
    state = np.stack([grown.start, grown.curves[-1][10]])
    log_b = uniform_log_belief(2, 3)
    out = shared_autonomy_step(mapped, grown, control, state, log_b, np.array([[np.nan], [0.5]]), 0.2)
    assert np.all(np.isfinite(out.state))
    np.testing.assert_array_equal(out.human_action[0], 0.0)
    assert np.all(np.abs(out.state - state) <= control.dt * control.max_joint_speed + 1e-12)


def test_sim4_frame_and_determinism(model, task):
    config = sim4.Config(offsets=(0.08, 0.11, 0.14), users=2, horizon=6, assistance=("point",))
    frame, runs = sim4.run(model, task, task.robot.control, config)
    again, _ = sim4.run(model, task, task.robot.control, config)
    pd.testing.assert_frame_equal(frame, again)
    assert list(frame.columns) == list(episodes.EPISODE_COLUMNS)
    # the CSV's columns: the episodes', then each cup's mean, median and share on the other cup
    assert list(analysis.with_cup_columns(frame).columns) == list(sim4.COLUMNS)
    assert set(frame.mapping) == {"with", "without"}
    assert set(frame.h) == {"grasp", "straight_line", "straight_line_ee", "none"}
    assert len(frame) == 2 * 3 * 4
    assert frame.distance.max() == 1.0 and (frame.error >= 0).all()
    assert len(runs) == 3 and runs[0].task.n_goals == 3


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"offsets": ()}, "offsets"),
        ({"offsets": (-0.1,)}, "offset"),
        ({"direction": (0.0, 0.0)}, "direction"),
        ({"maps": ("nearest",)}, "map"),
        ({"users": 0}, "users"),
        ({"method": "LA+XX"}, "method"),
    ],
)
def test_bad_sim4_config(kw, match):
    with pytest.raises(ConfigError, match=match):
        sim4.Config(**kw)


def _synthetic(slopes: dict[str, float], noise: float = 0.0) -> pd.DataFrame:
    rng = np.random.default_rng(0)
    x = np.repeat(np.linspace(0.2, 1.0, 5), 10)
    rows = [
        pd.DataFrame(
            {
                "robot": "planar5",
                "mapping": "without" if h == "none" else "with",
                "h": h,
                "distance": x,
                "seed": np.tile(np.arange(10), 5),
                "error": slope * x + noise * rng.normal(size=x.size),
            }
        )
        for h, slope in slopes.items()
    ]
    return pd.concat(rows, ignore_index=True)


def test_sim4_claim_rules():
    def headline(frame: pd.DataFrame) -> list:
        return [c for c in sim4.claims(frame) if "@" not in c.id]  # not the @intercept readings

    claims = headline(_synthetic({"straight_line": 0.11, "grasp": 0.0, "none": 1.0}))
    verdicts = [c.reproduced for c in claims]
    assert verdicts == ["yes", "partly", "yes"]  # straight line, grasp (flat), without
    assert "0.110x" in claims[0].measured
    claims = headline(_synthetic({"straight_line": 0.8, "none": 1.6}))
    # the effect only: both grow linearly and the map helps; 0.8 against 0.11, and 1.6 against
    # y = x, are the rows' number words (lasa.evidence.claims.criteria)
    assert [c.reproduced for c in claims] == ["yes", "yes"]
    # a map that is worse than none at the near cups is "no", whatever its slope
    flat_high = _synthetic({"grasp": 0.0, "none": 1.0})
    flat_high.loc[flat_high.h == "grasp", "error"] = 0.5
    assert headline(flat_high)[0].reproduced == "no"
    fits = analysis.fits(_synthetic({"straight_line": 0.3, "none": 1.3}))
    assert fits.loc["straight_line", "slope"] == pytest.approx(0.3)
    assert fits.loc["none", "r2"] == pytest.approx(1.0)


def test_mapped_decoder_is_the_map_around_the_model(model, grown):
    """a_h = J_h(s)^-1 phi(z, h(s, b)): the wrapper against the map and the model directly."""
    cmap = ContextMap.for_task(grown, 2, REF)
    mapped = MappedDecoder(model, cmap)
    rng = np.random.default_rng(3)
    s = grown.curves[-1][rng.integers(0, 41, 6)] + rng.normal(0, 0.05, (6, 5))
    b = rng.dirichlet(np.ones(3), 6)
    z = rng.uniform(-1, 1, (6, 1))
    s_hat, b_hat = cmap(s, b)
    expected = np.linalg.solve(cmap.jacobian(s), model.decode_numpy(z, s_hat, b_hat)[..., None])[..., 0]
    np.testing.assert_allclose(mapped.decode_numpy(z, s, b), expected, atol=1e-12)
    with pytest.raises(ConfigError, match="training goals"):
        MappedDecoder(MappedDecoder(model, cmap), cmap)


def test_sim4_refuses_a_method_whose_decoder_is_missing(model, task):
    with pytest.raises(ConfigError, match="needs the 'entropy' decoder"):
        sim4.run(
            model,
            task,
            task.robot.control,
            sim4.Config(offsets=(0.08, 0.11, 0.14), users=1, horizon=2, method="LA+SA+Entropy"),
        )


def test_sim4_members_share_batches_without_changing_the_headline(model, task):
    """Members run together, paired by seed; the headline member's rows equal a run of it alone."""
    config = sim4.Config(offsets=(0.08, 0.11, 0.14), users=2, horizon=6, assistance=("point", "grasp_set"))
    frame, runs = sim4.run(model, task, task.robot.control, config)
    alone, alone_runs = sim4.run(
        model, task, task.robot.control, dataclasses.replace(config, assistance=("point",))
    )
    assert list(dict.fromkeys(frame.assistance)) == ["point", "grasp_set"]
    head = frame[frame.assistance == "point"].reset_index(drop=True)
    pd.testing.assert_frame_equal(head, alone)
    np.testing.assert_array_equal(runs[1].without_map.states, alone_runs[1].without_map.states)
    other = frame[frame.assistance == "grasp_set"]
    assert (other.seed.to_numpy() == head.seed.to_numpy()).all()  # paired users


def test_sim4_vectorized_bootstrap_gives_the_resampled_frames_numbers(model, task):
    from lasa.evidence.verdicts import assess

    config = sim4.Config(offsets=(0.08, 0.11, 0.14), users=6, horizon=15, assistance=("point",))
    frame, _ = sim4.run(model, task, task.robot.control, config)
    slow = assess(sim4.claims, frame, n_boot=40, seed=1)
    fast = assess(sim4.claims, frame, n_boot=40, seed=1, fast=sim4.boot_values)
    for a, b in zip(slow, fast, strict=True):
        assert (a.id, a.reproduced, a.settled) == (b.id, b.reproduced, b.settled)
        np.testing.assert_allclose([a.ci_low, a.ci_high], [b.ci_low, b.ci_high], rtol=1e-9, atol=1e-12)


def _dup_site_task(task):
    """A 'new' cup standing on the reference cup, in the scene too: the gripper's map is the identity."""
    robot = task.robot.with_cup(task.robot.goal_positions()[REF])
    return dataclasses.replace(
        task,
        robot=robot,
        goal_names=(*task.goal_names, "copy"),
        curves=np.concatenate([task.curves, task.curves[REF][None]]),
        goals=np.concatenate([task.goals, task.goals[REF][None]]),
    )


@pytest.mark.parametrize("which", ["task", "panda_task"])
def test_gripper_line_map_is_the_identity_at_a_training_goal(which, request):
    task = request.getfixturevalue(which)
    cmap = context_map(_dup_site_task(task), task.n_goals, REF, "straight_line_ee")
    assert isinstance(cmap, TaskSpaceMap) and cmap.delta == 0.0
    rng = np.random.default_rng(0)
    states = task.curves[REF][::8] + rng.normal(0, 0.02, (6, task.robot.n_joints))
    np.testing.assert_allclose(cmap.state(states), states, atol=2e-3)
    actions = rng.normal(size=(6, 3, task.robot.n_joints))
    np.testing.assert_allclose(cmap.action_from_training(actions, states[:, None]), actions, atol=2e-2)


def test_gripper_line_map_sends_each_new_grasp_to_the_same_training_grasp(panda_task, panda_rotated):
    cmap = context_map(panda_rotated, 2, REF, "straight_line_ee")
    assert cmap.delta == pytest.approx(-0.3, abs=1e-6)
    mapped = cmap.state(panda_rotated.curves[-1])
    metres, degrees = episodes.grasp_error(panda_task.robot, mapped, panda_task.curves[REF])
    assert metres.max() < 1e-3 and degrees.max() < 0.2 and cmap.fallbacks == 0


def test_gripper_line_map_differential_and_actions(task, grown):
    """M(s) against finite differences of the mapped site, and J(s_hat) a_hat = M(s) a."""
    cmap = context_map(grown, 2, REF, "straight_line_ee")
    rng = np.random.default_rng(2)
    lam = rng.uniform(0.2, 0.7, 4)[:, None]
    states = grown.start + lam * (grown.goals[-1] - grown.start) + rng.normal(0, 0.03, (4, 5))
    m, eps = cmap.differential(states), 1e-4
    for i, s in enumerate(states):
        for k, e in enumerate(np.eye(5)):
            hi, lo = task.robot.grasp_positions(np.stack([cmap.state(s + eps * e), cmap.state(s - eps * e)]))
            np.testing.assert_allclose((hi - lo) / (2 * eps), m[i, :3, k], atol=2e-3)
    a_hat = rng.normal(size=(4, 2, 5))
    a = cmap.action_from_training(a_hat, states[:, None])
    _, _, j_hat = task.robot.grasp_jacobians(cmap.state(states))
    np.testing.assert_allclose(
        np.einsum("uin,ukn->uki", m, a), np.einsum("uin,ukn->uki", j_hat, a_hat), atol=1e-8
    )
