"""The latent map (lasa.experiments.latent_map): held-input sweeps and the rows of the figure."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from reference_step import latent_step

from lasa.base.errors import ConfigError
from lasa.evidence.latent_measure import held_input_paths
from lasa.experiments.latent_map import Config, run


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
    assert list(held["z"]) == [-1.0, 0.0, 1.0]
    robot, control = task.robot, task.robot.control
    cups = robot.goal_positions()
    # the confident context starts at the right cup with the mid-preference grasp, by the geometry:
    # the grasp site at the standoff from the cup's centre, the approach turned 45 degrees (theta =
    # 0.5 of a quarter turn) from pointing down, in the arm's plane towards the far side of the cup
    for start in held["confident"][:, 0]:
        site, approach = robot.grasp_positions(start), robot.grasp_axes(start)
        assert math.dist(site, cups[1]) == pytest.approx(robot.spec.grasp_standoff, abs=1e-3)
        assert math.degrees(math.acos(-approach[2])) == pytest.approx(45.0, abs=0.5)
        assert_allclose(cups[1] - site, robot.spec.grasp_standoff * approach, atol=1e-3)
    # every held path, step by step, is Algorithm 1 with alpha = 0 written out by hand: from home with
    # a uniform belief updated online, and at the cup with the belief held on the right cup
    for name, online in (("uniform", True), ("confident", False)):
        for path, z in zip(held[name], held["z"], strict=True):
            b = np.full(task.n_goals, 1.0 / task.n_goals) if online else np.eye(task.n_goals)[1]
            for s, s_next in zip(path[:-1], path[1:], strict=True):
                ref = latent_step(model, task, control, s, b, [z], alpha=0.0)
                assert_allclose(s_next, ref["s"], rtol=0, atol=1e-8)
                b = ref["b"] if online else b
    # the rows read the last state: along the left-to-right cup axis from the cups' midpoint [m],
    # and the approach's angle from pointing down, in quarter turns
    axis = (cups[-1] - cups[0]) * [1.0, 1.0, 0.0]
    axis /= np.linalg.norm(axis)
    for row in frame.itertuples():
        last = held[row.context][list(held["z"]).index(row.z), -1]
        approach = robot.grasp_axes(last)
        assert row.cup_axis == pytest.approx((robot.grasp_positions(last) - cups.mean(axis=0)) @ axis)
        assert row.grasp_theta == pytest.approx(math.acos(-approach[2]) / (math.pi / 2))
        assert row.steps == {"uniform": 4, "confident": 2}[row.context]
    # two steps of at most dt * sigma_h per joint cannot carry the grasp far from theta = 0.5
    assert (frame[frame.context == "confident"].grasp_theta - 0.5).abs().max() < 0.2


def test_leave_paths_are_the_reference_step_held_with_each_rows_alpha(model, task):
    """The leave half's held inputs: every row, with its own alpha, the stick at rest commanding
    nothing, is Algorithm 1 written out by hand (tests/reference_step.py), the belief updated."""
    from lasa.evidence.latent_measure import leave_paths

    control = task.robot.control
    starts = np.stack([task.target(0, 0.5), task.target(1, 0.3), task.start])
    beliefs = np.array([[0.9, 0.1], [0.2, 0.8], [0.5, 0.5]])
    z, alphas = np.array([[0.7], [0.0], [-1.0]]), np.array([0.0, 0.5, 0.3])
    paths = leave_paths(model, task, control, starts, beliefs, z, alphas, steps=6)
    assert paths.shape == (3, 7, task.robot.n_joints)
    for row in range(3):
        s, b = starts[row], beliefs[row]
        for t in range(6):
            ref = latent_step(model, task, control, s, b, z[row], alpha=alphas[row], rest="zero")
            s, b = ref["s"], ref["b"]
            assert_allclose(paths[row, t + 1], s, rtol=0, atol=1e-6)
