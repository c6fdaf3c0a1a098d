"""Metrics against hand-computed cases."""

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from lasa.base.errors import ConfigError
from lasa.evidence.metrics import confidence, normalized_error, time_to_reach


def test_normalized_error_by_hand():
    assert_allclose(normalized_error(np.array([3.0, 4.0]), np.zeros(2), 10.0), 0.5)


def test_time_to_reach_by_hand():
    errors = np.array([[1.0, 1.0, 1.0], [0.5, 0.04, 1.0], [0.03, 0.2, 1.0], [0.01, 0.01, 0.9]])
    steps, done = time_to_reach(errors, 0.05)
    assert_array_equal(steps, [2, 1, 3])
    assert_array_equal(done, [True, True, False])


def test_confidence_by_hand():
    assert_allclose(confidence(np.array([[0.9, 0.1], [0.3, 0.7]]), np.array([0, 0])), [0.9, 0.3])


def test_bad_tolerance():
    with pytest.raises(ConfigError, match="tolerance"):
        time_to_reach(np.zeros((2, 2)), -1.0)
