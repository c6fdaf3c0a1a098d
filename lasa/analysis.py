"""What the latent space does: decoded actions and held-input sweeps.

The heart of the paper is that the meaning of a joystick input changes with the
robot's confidence: when the belief is uniform, z chooses *which cup*; once it is
confident, the same z chooses *how to grasp*. These functions make that visible by
holding a joystick input constant and letting the robot move under it (latent actions
alone, alpha = 0), with the belief either held at the context's value or updated
online as in Algorithm 1.
"""

from __future__ import annotations

import numpy as np

from lasa.belief import belief as to_belief
from lasa.config import ControlConfig
from lasa.control import safe_step
from lasa.decoder import LatentActionModel
from lasa.errors import ConfigError
from lasa.rollout import shared_autonomy_step
from lasa.task import CupTask

__all__ = ["held_input_paths"]


def held_input_paths(
    model: LatentActionModel,
    task: CupTask,
    control: ControlConfig,
    start: np.ndarray,
    belief: np.ndarray,
    z_values: np.ndarray,
    steps: int,
    update_belief: bool = False,
) -> np.ndarray:
    """States reached by holding each joystick input for ``steps`` steps (LA, alpha = 0).

    All inputs advance together in one batch: each step makes one decoder call.

    Args:
        model: The decoder.
        task: The cup task (for the joint limits).
        control: Control-loop units.
        start: Start state, shape (n,).
        belief: The initial belief, shape (G,).
        z_values: Joystick inputs, shape (K,) or (K, d).
        steps: Number of steps each input is held.
        update_belief: Update the belief online with each decoded action (Algorithm 1);
            otherwise hold it fixed.

    Returns:
        States, shape (K, steps + 1, n).
    """
    if steps < 1:
        raise ConfigError(f"steps must be >= 1, got {steps}")
    belief = np.asarray(belief, dtype=float)
    if belief.shape != (task.n_goals,) or not np.isclose(belief.sum(), 1.0) or belief.min() < 0:
        raise ConfigError(f"belief must be a distribution over {task.n_goals} goals, got {belief}")
    z = np.asarray(z_values, dtype=float).reshape(len(z_values), -1)
    robot = task.robot
    s = np.broadcast_to(start, (len(z), robot.n_joints)).copy()
    log_b = np.log(np.broadcast_to(np.maximum(belief, 1e-300), (len(z), task.n_goals)))
    out = [s]
    for _ in range(steps):
        if update_belief:  # Algorithm 1 with alpha = 0: the method LA
            step = shared_autonomy_step(model, task, control, s, log_b, z, 0.0)
            s, log_b = step.state, step.log_belief
        else:
            a = model.decode_numpy(z, s, to_belief(log_b))
            s = safe_step(s, a, control.dt, robot.lower, robot.upper, control.max_joint_speed)
        out.append(s)
    return np.stack(out, axis=1)
