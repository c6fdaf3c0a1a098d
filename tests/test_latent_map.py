"""The latent map (lasa.figures.latent_map): held-input sweeps and the rows of the figure."""

import numpy as np
import pytest

from lasa.base.errors import ConfigError
from lasa.figures.latent_map import Config, held_input_paths, run


def test_held_paths_shape_and_limits(model, task):
    z = np.linspace(-1, 1, 5)
    paths = held_input_paths(
        model, task, task.robot.control, task.start, np.array([0.5, 0.5]), z, 10, update_belief=True
    )
    assert paths.shape == (5, 11, task.robot.n_joints)
    assert np.all(paths >= task.robot.lower) and np.all(paths <= task.robot.upper)


def test_bad_belief_is_refused(model, task):
    with pytest.raises(ConfigError, match="belief"):
        held_input_paths(model, task, task.robot.control, task.start, np.array([0.7, 0.7]), np.zeros(1), 3)


def test_latent_map_rows(model, task):
    frame, held = run(model, task, task.robot.control, Config(n_z=3, uniform_steps=4, confident_steps=2))
    assert len(frame) == 6 and set(frame.context) == {"uniform", "confident"}
    assert held["uniform"].shape == (3, 5, task.robot.n_joints) and held["confident"].shape[1] == 3
    # the confident context starts at the right cup's goal and holds the belief there
    np.testing.assert_allclose(
        held["confident"][:, 0], np.broadcast_to(task.goals[1], (3, task.robot.n_joints))
    )
    # at the cup, the grasp shown starts from the mid-preference one (theta = 0.5), and two steps of
    # at most dt * sigma_h per joint cannot carry it far from there
    from lasa.world.task import grasp_preference

    np.testing.assert_allclose(grasp_preference(task, held["confident"][:, 0]), 0.5, atol=0.02)
    assert (frame[frame.context == "confident"].grasp_theta - 0.5).abs().max() < 0.2
