"""Demonstrations: shapes, online beliefs, speed bounds, determinism, persistence."""

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from lasa.demos import DemoConfig, collect_demonstrations, load_demonstrations, save_demonstrations
from lasa.errors import ArtifactError, ConfigError
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
