r"""Algorithm 1 for one user at the control rate: joystick input in, commanded state out.

:class:`Controller` keeps one user's state and belief and advances them with the very
step the simulations run, :func:`lasa.method.step.shared_autonomy_step`, called with a
batch of one. There is one implementation of the step, so a live robot and a simulated
user are driven by the same arithmetic.

**Rate.** The step integrates :math:`s' = s + \Delta a` with the control period
:math:`\Delta` = ``control.dt`` (0.1 s for both robots), so a live loop runs one step
per :math:`\Delta` of wall-clock time: 10 Hz. One step costs about 1.5 ms on this
package's 2-core reference machine (p50 1.5 ms, p99 2.8 ms in ``benchmarks/results.json``;
``make bench`` measures it), under 3% of that 100 ms deadline, so the step needs no separate
fast path.
"""

from __future__ import annotations

import numpy as np

from lasa.base.config import ControlConfig, check_range
from lasa.base.errors import ConfigError
from lasa.method.belief import belief, uniform_log_belief
from lasa.method.decoder import ActionDecoder
from lasa.method.step import StepResult, check_decoder, shared_autonomy_step
from lasa.world.goals import GoalTask

__all__ = ["Controller"]


class Controller:
    """The shared-autonomy control step for one user, with its state and belief.

    Args:
        decoder: The decoder phi (a trained model, or a wrapper such as
            :class:`lasa.method.newgoals.MappedDecoder`); its robot and goals must be the task's.
        task: The goal task (goals, belief's goal sets, joint limits).
        control: Control-loop units.
        alpha: Blend weight in [0, 1] (0 is ``LA``).

    Attributes:
        state: The current joint positions s, shape (n,) [rad].
        log_belief: The current log-belief, shape (G,).
        last: The last step's full result (human action a_h, blended action a), or
            ``None`` before the first step.
    """

    def __init__(self, decoder: ActionDecoder, task: GoalTask, control: ControlConfig, alpha: float) -> None:
        check_decoder(decoder, task)
        self.alpha = check_range("alpha", alpha, 0.0, 1.0)
        self.decoder, self.task, self.control = decoder, task, control
        self.state = np.asarray(task.start, dtype=float).copy()
        self.log_belief = uniform_log_belief(1, task.n_goals)[0]
        self.last: StepResult | None = None

    def reset(self, state: np.ndarray | None = None, log_belief: np.ndarray | None = None) -> None:
        """Back to the start pose and the uniform belief (or the given ones).

        Raises:
            ConfigError: if the state is not n finite joint positions, or the log-belief
                not G finite values.
        """
        n, g = self.task.robot.n_joints, self.task.n_goals
        new = np.asarray(self.task.start if state is None else state, dtype=float).copy()
        if new.shape != (n,) or not np.all(np.isfinite(new)):
            raise ConfigError(f"state must be {n} finite joint positions, got {state!r}")
        log_b = uniform_log_belief(1, g)[0] if log_belief is None else np.array(log_belief, dtype=float)
        if log_b.shape != (g,) or not np.all(np.isfinite(log_b)):
            raise ConfigError(f"log_belief must be {g} finite values, got {log_belief!r}")
        self.state, self.log_belief, self.last = new, log_b, None

    @property
    def belief(self) -> np.ndarray:
        """b over the goals, shape (G,)."""
        return belief(self.log_belief)

    def step(self, z: float | np.ndarray) -> np.ndarray:
        """One step from joystick input z (shape (d,), or a scalar for d = 1) to the next state.

        A non-finite input is no human action (the assistance still applies); an input
        beyond [-1, 1] is clamped by the decoder.

        Returns:
            The new state s', shape (n,) (also kept in :attr:`state`).

        Raises:
            ConfigError: if z does not have the decoder's d entries.
        """
        z_arr = np.asarray(z, dtype=float).reshape(-1)
        if z_arr.shape != (self.decoder.z_dim,):
            raise ConfigError(f"z must have {self.decoder.z_dim} entries, got shape {np.shape(z)}")
        out = shared_autonomy_step(
            self.decoder,
            self.task,
            self.control,
            self.state[None],
            self.log_belief[None],
            z_arr[None],
            self.alpha,
        )
        self.state, self.log_belief = out.state[0], out.log_belief[0]
        self.last = out
        return self.state
