"""The single-user control step (lasa.realtime) against the batched reference step."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from lasa.belief import uniform_log_belief
from lasa.errors import ConfigError
from lasa.realtime import Controller
from lasa.rollout import shared_autonomy_step


def _inputs(n: int = 120) -> np.ndarray:
    rng = np.random.default_rng(0)
    z = np.clip(np.cumsum(rng.normal(0, 0.3, n)), -1.5, 1.5)  # also beyond the joystick's range
    z[[17, 40]] = np.nan  # a faulty device
    z[60] = np.inf
    z[80] = 1e9
    return z


@pytest.mark.parametrize("which", ["planar5", "panda"])
def test_controller_matches_the_reference_step(which, model, task, panda_model, panda_task):
    model, task = (model, task) if which == "planar5" else (panda_model, panda_task)
    control = task.robot.control
    ctl = Controller(model, task, control, control.alpha)
    s, log_b = task.start[None].copy(), uniform_log_belief(1, task.n_goals)
    for z in _inputs():
        ref = shared_autonomy_step(model, task, control, s, log_b, np.array([[z]]), control.alpha)
        s, log_b = ref.state, ref.log_belief
        out = ctl.step(z)
        # float64 here, float32 in torch: agreement to float32 rounding, accumulated over the episode
        np.testing.assert_allclose(out, s[0], atol=1e-5)
        np.testing.assert_allclose(ctl.log_belief, log_b[0], atol=1e-4)
        np.testing.assert_allclose(ctl.belief.sum(), 1.0)


def test_decode_matches_torch(model, task):
    ctl = Controller(model, task, task.robot.control, 0.2)
    rng = np.random.default_rng(1)
    for _ in range(20):
        z = rng.uniform(-1.2, 1.2, 1)
        s = task.start + rng.normal(0, 0.5, task.robot.n_joints)
        b = rng.dirichlet(np.ones(task.n_goals))
        with torch.no_grad():
            ref = model.decode(*(torch.as_tensor(x, dtype=torch.float32) for x in (z, s, b))).numpy()
        np.testing.assert_allclose(ctl.decode(z, s, b), ref, atol=1e-5)


def test_commands_stay_within_limits_and_the_step_bound(model, task):
    control = task.robot.control
    ctl = Controller(model, task, control, 0.5)
    prev = ctl.state.copy()
    for z in np.tile([1.0, -1.0, np.nan, 1e12], 50):
        out = ctl.step(z)
        assert np.all(np.isfinite(out))
        assert np.all(out >= task.robot.lower) and np.all(out <= task.robot.upper)
        assert np.abs(out - prev).max() <= control.dt * control.max_joint_speed + 1e-12
        prev = out.copy()


def test_nan_input_is_no_human_action(model, task):
    control = task.robot.control
    ctl = Controller(model, task, control, 0.0)  # LA: without assistance, no input means no motion
    out = ctl.step(np.nan)
    np.testing.assert_array_equal(out, task.start)


def test_same_inputs_same_trajectory(model, task):
    control = task.robot.control
    runs = []
    for _ in range(2):
        ctl = Controller(model, task, control, control.alpha)
        runs.append(np.array([ctl.step(z).copy() for z in _inputs()]))
    np.testing.assert_array_equal(runs[0], runs[1])


def test_bad_controller_input(model, task, panda_task):
    with pytest.raises(ConfigError, match="trained for 'planar5'"):
        Controller(model, panda_task, panda_task.robot.control, 0.2)
    with pytest.raises(ConfigError, match="alpha"):
        Controller(model, task, task.robot.control, 1.5)
    ctl = Controller(model, task, task.robot.control, 0.2)
    with pytest.raises(ConfigError, match="finite"):
        ctl.reset(state=np.full(task.robot.n_joints, np.nan))
