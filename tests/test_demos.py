"""Demonstrations: shapes, online beliefs, speed bounds, determinism, persistence."""

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from lasa.base.errors import ArtifactError, ConfigError
from lasa.method.dataset import load_demonstrations, save_demonstrations
from lasa.people.demos import DemoConfig, collect_demonstrations
from tests.conftest import SMALL_DEMOS


def test_shapes_and_normalised_beliefs(demos, task):
    n = task.robot.n_joints
    assert demos.states.shape[1] == n and demos.actions.shape == demos.states.shape
    assert demos.beliefs.shape == (len(demos), task.n_goals)
    assert_allclose(demos.beliefs.sum(1), 1.0, atol=1e-9)
    assert len(demos) == 2 * len(demos.clean())  # one noisy copy per tuple


def test_actions_respect_the_decoder_bound(demos, task):
    assert np.linalg.norm(demos.actions, axis=1).max() <= task.robot.control.action_scale + 1e-9


def test_reaches_end_at_the_desired_pose(demos, task):
    clean = demos.clean()
    dt = task.robot.control.dt
    for d in np.unique(clean.demo):
        m = (clean.demo == d) & (clean.phase == 0)
        s, a = clean.states[m], clean.actions[m]
        end = s[-1] + dt * a[-1]
        target = task.target(clean.goal[m][0], clean.theta[m][0])
        assert np.linalg.norm(end - target) < 2 * DemoConfig().tolerance


def test_belief_starts_uniform_and_commits_to_the_demonstrated_cup(demos):
    clean = demos.clean()
    first = np.r_[0, np.flatnonzero(np.diff(clean.demo)) + 1]
    assert_allclose(clean.beliefs[first], 0.5)
    true = clean.beliefs[np.arange(len(clean)), clean.goal]
    assert np.all(true[clean.phase > 0] > 0.99)  # confident during grasp adjustments


def test_beliefs_are_the_online_update_step_by_step(demos, task):
    """The collector's batched likelihoods give, bit for bit, the beliefs of Algorithm 1's update run one
    tuple at a time from uniform along each demonstration."""
    from lasa.method.belief import (
        belief,
        belief_targets,
        log_likelihood,
        uniform_log_belief,
        update_log_belief,
    )

    control, clean = task.robot.control, demos.clean()
    sets = belief_targets(task, control.likelihood)
    expected = np.empty_like(clean.beliefs)
    for k in range(len(clean)):
        if k == 0 or clean.demo[k] != clean.demo[k - 1]:
            log_b = uniform_log_belief(1, task.n_goals)[0]
        expected[k] = belief(log_b)
        lik = log_likelihood(
            clean.states[k], clean.actions[k], sets, control.dt, control.belief_beta, control.likelihood_step
        )
        log_b = update_log_belief(log_b, lik, control.belief_floor, control.belief_cap)
    assert_array_equal(clean.beliefs, expected)


def test_same_seed_same_data(task):
    a = collect_demonstrations(task, task.robot.control, SMALL_DEMOS)
    b = collect_demonstrations(task, task.robot.control, SMALL_DEMOS)
    c = collect_demonstrations(task, task.robot.control, dataclasses.replace(SMALL_DEMOS, seed=1))
    assert_array_equal(a.states, b.states)
    assert not np.array_equal(a.states, c.states)


def test_save_load_round_trip(demos, tmp_path):
    path = save_demonstrations(demos, tmp_path / "d.npz")
    loaded = load_demonstrations(path, robot="planar5")
    assert loaded.robot == "planar5"
    assert_array_equal(loaded.actions, demos.actions)
    with pytest.raises(ArtifactError, match="not 'panda'"):
        load_demonstrations(path, robot="panda")


def test_missing_and_corrupt_datasets_name_the_fix(tmp_path):
    with pytest.raises(ArtifactError, match="01_demonstrations"):
        load_demonstrations(tmp_path / "none.npz")
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"\x00garbage")
    with pytest.raises(ArtifactError, match="corrupt"):
        load_demonstrations(bad)


@pytest.mark.parametrize("field,value", [("n_theta", 0), ("speed", 1.5), ("perturb_std", -0.1)])
def test_bad_config_is_a_clear_error(field, value):
    with pytest.raises(ConfigError, match=field):
        DemoConfig(**{field: value})


@pytest.fixture(scope="module")
def eating_segmentations():
    from lasa.people.demos import SEGMENTATIONS, collect_eating_demonstrations
    from lasa.world.eating import make_eating_task

    task = make_eating_task()
    config = DemoConfig(n_theta=2, n_starts=1, n_adjust=1, n_perturb=0)
    control = task.robot.control
    return task, {r: collect_eating_demonstrations(task, control, config, r) for r in SEGMENTATIONS}


def _firsts(demos):
    return np.r_[0, np.flatnonzero(np.diff(demos.demo)) + 1]


def test_eating_segmentations_cut_the_demonstrations_as_their_names_say(eating_segmentations):
    from lasa.method.dataset import ADJUST, REACH, STROKE

    task, segmentations = eating_segmentations
    g = task.n_goals
    uniform = np.full(g, 1.0 / g)
    counts = {r: int(d.demo.max() + 1) for r, d in segmentations.items()}
    # 4 goals x 2 tilts x (home + 3 other goals) demonstrations, in every segmentation
    assert counts == {"continuous": 32, "home": 32, "transfers": 32, "leaves": 32}
    for segmentation, demos in segmentations.items():
        first = _firsts(demos)
        starts, beliefs = demos.states[first], demos.beliefs[first]
        from_home = np.all(np.isclose(starts, task.start), axis=1)
        if segmentation == "home":  # home or a perturbed home (never another goal's pose), uniform belief
            assert np.allclose(beliefs, uniform)
            entries = [task.target(o, t) for o in range(g) for t in (0.0, 1.0)]
            assert not any(np.allclose(s, e) for s in starts for e in entries)
        elif segmentation == "continuous":  # a move from another goal starts confident in it
            assert np.allclose(beliefs[from_home], uniform) and beliefs[~from_home].max(axis=1).min() > 0.9
        else:  # transfers, leaves: those from another goal only reach
            for d in np.unique(demos.demo[~np.isin(demos.demo, demos.demo[first][from_home])]):
                phases = set(demos.phase[demos.demo == d])
                assert REACH in phases and not phases & {ADJUST, STROKE}
            if segmentation == "transfers":  # every demonstration starts uniform, a transfer at an entry
                assert np.allclose(beliefs, uniform)
            else:  # leaves: a transfer starts confident in the goal it leaves, at a stroke's end
                assert np.allclose(beliefs[from_home], uniform)
                confident = beliefs[~from_home]
                assert confident.max(axis=1).min() > 0.9
                ends = {o: task.pose(o, np.linspace(0, 1, 201), np.ones(201)) for o in range(g)}
                for s, b in zip(starts[~from_home], confident, strict=True):
                    # on the stroke's end curve of the goal the belief is confident in
                    assert np.linalg.norm(ends[int(b.argmax())] - s, axis=1).min() < 0.02
    with pytest.raises(ConfigError, match="segmentation"):
        from lasa.people.demos import collect_eating_demonstrations

        collect_eating_demonstrations(task, task.robot.control, DemoConfig(n_theta=2), "sideways")
