"""Held-input sweeps used by the latent map."""

import numpy as np
import pytest

from lasa.analysis import held_input_paths
from lasa.errors import ConfigError


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
