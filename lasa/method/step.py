"""The one step of Algorithm 1, batched: joystick input in, commanded state out.

Every loop of the package advances with :func:`advance`, through the episode runner
(:class:`lasa.method.episodes.Runner`). At each step:

1. the joystick input z is decoded, a_h = phi(z, s, b) (:func:`shared_autonomy_step`; a
   chooser that weighs many candidates decodes them in one call, :func:`decode_candidates`);
2. the robot's assistance a_r (Eq. M2, or another member of :mod:`lasa.method.assistance`
   named by ``ControlConfig.assistance``) is blended with a_h (Eq. M1) using each
   user's alpha: alpha = 0 is the method ``LA``, alpha > 0 is ``LA+SA``;
3. the belief is updated with a_h (Alg. 1, line 8);
4. the robot takes the safe step s' = clip(s + dt a).

The decoder is anything that follows :class:`lasa.method.decoder.ActionDecoder`: the trained
model, or a wrapper of it such as the context map of new goals
(:class:`lasa.method.newgoals.MappedDecoder`), which this module does not need to know about.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from lasa.base import conditions
from lasa.base.conditions import METHODS
from lasa.base.config import ControlConfig, check_choice
from lasa.base.errors import ConfigError
from lasa.method.assistance import assist
from lasa.method.belief import belief, belief_targets, log_likelihood, update_log_belief
from lasa.method.blend import blend, safe_step, sanitize
from lasa.method.decoder import ActionDecoder
from lasa.world.goals import GoalTask

__all__ = [
    "Assist",
    "StepResult",
    "check_decoder",
    "decode_candidates",
    "latent_grid",
    "advance",
    "shared_autonomy_step",
    "human_action",
    "METHODS",
    "METHOD_DECODER",
    "method_alpha",
    "REST",
]

# Which decoder each method uses (:mod:`lasa.base.conditions`): "base" is trained on
# reconstruction alone (Sec. III-A), "entropy" with the entropy term of Eq. T6 (lasa.method.entropy).
METHOD_DECODER: dict[str, str] = {m: str(conditions.parse(m, METHODS).decoder) for m in METHODS}


def method_alpha(method: str, control: ControlConfig) -> float:
    """The blend weight alpha of a method: 0 for LA, ``control.alpha`` for the assisted ones."""
    return conditions.alpha_of(method, control.alpha, METHODS, "method")


@dataclasses.dataclass(frozen=True)
class StepResult:
    """One step of Algorithm 1 for a batch of users.

    Attributes:
        state: s^{t+1}, shape (U, n) [rad].
        log_belief: log b^{t+1}, shape (U, G).
        human_action: a_h^t, shape (U, n) [rad/s] (zero where the input was not finite).
        action: the blended command a^t before the safety clip, shape (U, n) [rad/s].
        robot_action: the robot's assistance a_r^t, times its blend weight, shape (U, n) [rad/s]; zero
            in a row whose alpha is 0 if its :class:`Assist` skips those (``only_blended``).
    """

    state: np.ndarray
    log_belief: np.ndarray
    human_action: np.ndarray
    action: np.ndarray
    robot_action: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class Assist:
    """What the step's assistance, blend and belief update read for a batch, and never change.

    Attributes:
        task: The goal task (goals, preference sets, joint limits).
        control: Control-loop units (dt, speed bound, belief model, the default member).
        alpha: The blend weight of each row, (U,) (0: latent actions alone).
        assistance: Each row's member of :mod:`lasa.method.assistance`, (U,); ``None``: every row
            runs ``control.assistance``.
        goal_sets: The belief's targets (:func:`lasa.method.belief.belief_targets`); ``None``:
            those of ``control.likelihood``.
        only_blended: Compute a_r only in the rows that blend it in (alpha > 0), and report a
            zero ``robot_action`` in the others; by default every row computes it (the live log
            records what the assistance would have done under LA too). The step is the same to the
            bit for a member that computes a row's a_r from that row alone, as every built-in one
            does but ``point``, whose Eq. M2 is one matrix product over the batch and rounds by its
            size. The study's simulated participants ask for it (:mod:`lasa.people.simulation`,
            :mod:`lasa.people.planning`): many of their rows run without assistance.
    """

    task: GoalTask
    control: ControlConfig
    alpha: np.ndarray
    assistance: np.ndarray | None = None
    goal_sets: np.ndarray | None = None
    only_blended: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "alpha", np.asarray(self.alpha, dtype=float).reshape(-1))
        if self.goal_sets is None:
            object.__setattr__(self, "goal_sets", belief_targets(self.task, self.control.likelihood))
        if self.assistance is not None:
            names = np.asarray(self.assistance, dtype=str)
            if names.shape != self.alpha.shape:
                raise ConfigError(
                    f"assistance must name one member per row, shape {self.alpha.shape}, got {names.shape}"
                )
            object.__setattr__(self, "assistance", names)  # each name is checked where it runs (assist)

    def rows(self, idx: np.ndarray) -> Assist:
        """The same for rows ``idx`` of the batch."""
        assistance = None if self.assistance is None else self.assistance[idx]
        return dataclasses.replace(self, alpha=self.alpha[idx], assistance=assistance)


def advance(
    assist: Assist, state: np.ndarray, log_b: np.ndarray, a_h: np.ndarray, b: np.ndarray | None = None
) -> StepResult:
    """Lines 6-9 of Algorithm 1 for a batch: assistance, blend (Eq. M1), belief update, safe step.

    Args:
        assist: The batch's fixed parts (one row per episode).
        state: s^t, (U, n). log_b: log b^t, (U, G).
        a_h: The decoded human actions, (U, n) (a row that is not finite commands nothing).
        b: ``belief(log_b)``, if the caller has it already.
    """
    task, control = assist.task, assist.control
    a_h = sanitize(a_h)
    if b is None:
        b = belief(log_b)
    a_r, weight = np.zeros_like(state), np.zeros(len(state))
    helped = (assist.alpha > 0.0) | (not assist.only_blended)  # alpha = 0 blends in no assistance
    if helped.all():
        a_r, weight = _assistance(task, control, state, b, assist.assistance)
    elif helped.any():
        members = None if assist.assistance is None else assist.assistance[helped]
        a_r[helped], weight[helped] = _assistance(task, control, state[helped], b[helped], members)
    a = blend(a_h, a_r, assist.alpha * weight)
    sets, beta, max_step = assist.goal_sets, control.belief_beta, control.likelihood_step
    assert sets is not None  # filled in by Assist.__post_init__
    lik = log_likelihood(state, a_h, sets, control.dt, beta, max_step)
    new_log_b = update_log_belief(log_b, lik, control.belief_floor, control.belief_cap)
    robot = task.robot
    new_state = safe_step(state, a, control.dt, robot.lower, robot.upper, control.max_joint_speed)
    return StepResult(
        state=new_state, log_belief=new_log_b, human_action=a_h, action=a, robot_action=a_r * weight[:, None]
    )


def _assistance(
    task: GoalTask, control: ControlConfig, state: np.ndarray, b: np.ndarray, assistance: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """a_r and the blend weight per row: ``control.assistance``, or each row's member.

    The members' goal sets are the task's preference sets (``task.preference_sets``):
    the cups' grasp curves, or the eating task's whole stroke surfaces.
    """
    goal_sets = task.preference_sets
    if assistance is None:
        return assist(control.assistance, b, state, task.goals, goal_sets, control.dt, control.action_scale)
    a_r, weight = np.empty_like(state), np.empty(len(state))
    for name in dict.fromkeys(assistance.tolist()):
        rows = assistance == name
        a_r[rows], weight[rows] = assist(
            name, b[rows], state[rows], task.goals, goal_sets, control.dt, control.action_scale
        )
    return a_r, weight


REST = ("decode", "zero")  # what a stick at rest commands (shared_autonomy_step's ``rest``)


def shared_autonomy_step(
    decoder: ActionDecoder,
    task: GoalTask,
    control: ControlConfig,
    state: np.ndarray,
    log_belief: np.ndarray,
    z: np.ndarray,
    alpha: float | np.ndarray,
    rest: str = "decode",
) -> StepResult:
    """One step of Algorithm 1 from joystick input to commanded state, batched over users.

    Decode z (a_h = phi(z, s, b)), blend with the assistance (Eqs. M1-M2), update the belief
    (Alg. 1, line 8), take the safe step: the episode runner's step for a held input
    (:func:`lasa.method.episodes.held_input`). A non-finite input decodes to no human action;
    the assistance still applies. ``rest`` is what the stick at rest (z = 0) commands:
    ``"decode"``, phi(0, s, b) (sims 1-4, Eq. S1); ``"zero"``, no human action (live
    teleoperation, the study's participants, through :func:`human_action`). Why: ``docs/method-notes.md``.

    Args:
        decoder: The decoder phi (a trained model or a wrapper, e.g. a ``MappedDecoder``).
        task: The goal task (cups or eating).
        control: Control-loop units.
        state: s^t, shape (U, n).
        log_belief: log b^t, shape (U, G).
        z: Joystick inputs, shape (U, d); clamped to [-1, 1] by the decoder.
        alpha: Blend weight, scalar or shape (U,).
        rest: ``"decode"`` or ``"zero"``.
    """
    check_decoder(decoder, task)
    check_choice("rest", rest, REST)
    z = np.asarray(z, dtype=float)
    finite = np.all(np.isfinite(z), axis=-1, keepdims=True)
    a_h = human_action(decoder.decode_numpy(np.where(finite, z, 0.0), state, belief(log_belief)), z, rest)
    alpha_arr = np.broadcast_to(np.asarray(alpha, dtype=float), state.shape[:1])
    return advance(Assist(task, control, alpha_arr), state, log_belief, a_h)


def human_action(decoded: np.ndarray, z: np.ndarray, rest: str) -> np.ndarray:
    """Latent actions' a_h from the decoded phi(z, s, b), under the stick-at-rest convention.

    A row whose input is not finite commands nothing; with ``rest="zero"`` neither does a
    stick at rest (z = 0); with ``rest="decode"`` the rest position means phi(0, s, b). The
    one place the convention is applied: :func:`shared_autonomy_step` (sims 1-4's reference
    step, teleop, the benchmark) and the study's participants, who decode their candidates
    themselves (:func:`lasa.people.participants.simulate`), both call it.

    Args:
        decoded: phi(z, s, b) for each row, shape (U, n) [rad/s].
        z: The inputs, shape (U, d).
        rest: ``"decode"`` or ``"zero"``.
    """
    check_choice("rest", rest, REST)
    z = np.asarray(z, dtype=float)
    ok = np.all(np.isfinite(z), axis=-1, keepdims=True)
    if rest == "zero":
        ok = ok & np.any(z != 0.0, axis=-1, keepdims=True)
    return np.where(ok, decoded, 0.0)


def check_decoder(decoder: ActionDecoder, task: GoalTask) -> None:
    """The decoder must act in the task's robot and read a belief over the task's goals.

    Raises:
        ConfigError: naming the mismatch.
    """
    if decoder.robot != task.robot.name:
        raise ConfigError(f"decoder was trained for {decoder.robot!r}, the task is for {task.robot.name!r}")
    if decoder.n_goals != task.n_goals:
        raise ConfigError(
            f"decoder reads a belief over {decoder.n_goals} goals, the task has {task.n_goals}; "
            "for a task grown by a new goal, wrap the decoder in lasa.method.newgoals.MappedDecoder"
        )


def decode_candidates(
    decoder: ActionDecoder, z_grid: np.ndarray, state: np.ndarray, b: np.ndarray
) -> np.ndarray:
    """phi(z, s, b) for every user and every candidate, in one decoder call.

    Args:
        decoder: The decoder.
        z_grid: Candidates, shape (K, d).
        state: States, shape (U, n).
        b: Beliefs, shape (U, G).

    Returns:
        Decoded actions, shape (U, K, n), float64.
    """
    return decoder.decode_numpy(z_grid[None], state[:, None], b[:, None])


def latent_grid(n_z: int, z_dim: int = 1) -> np.ndarray:
    """The joystick candidates a user weighs: an even grid on [-1, 1]^d, (n_z^d, d)."""
    axis = np.linspace(-1.0, 1.0, n_z)
    mesh = np.meshgrid(*([axis] * z_dim), indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=-1)
