"""The one step of Algorithm 1, batched (:func:`advance`): a_h = phi(z, s, b), a member's a_r blended
in by Eq. M1 with each row's alpha (0: ``LA``), the belief updated (Alg. 1, line 8), and the safe step
s' = s + Delta a of Sec. V (:func:`safe_step`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from lasa.base import conditions
from lasa.base.conditions import METHODS
from lasa.base.config import ControlConfig, check_choice
from lasa.base.errors import ConfigError
from lasa.method.assistance import Member, assist
from lasa.method.belief import belief, belief_targets, log_likelihood, update_log_belief
from lasa.method.decoder import ActionDecoder
from lasa.world.goals import GoalTask

# Each method's decoder: "base" (reconstruction alone, Sec. III-A) or "entropy" (Eq. T6)
METHOD_DECODER: dict[str, str] = {m: str(conditions.parse(m, METHODS).decoder) for m in METHODS}


def method_alpha(method: str, control: ControlConfig) -> float:
    """The blend weight alpha of a method: 0 for LA, ``control.alpha`` for the assisted ones."""
    return conditions.alpha_of(method, control.alpha, METHODS, "method")


@dataclasses.dataclass(frozen=True)
class StepResult:
    """One step of Algorithm 1 for a batch: s^{t+1} [rad], log b^{t+1}, a_h^t, the command a^t before
    the safety clip, and a_r^t times its blend weight (zero where ``only_blended`` skips it)."""

    state: np.ndarray
    log_belief: np.ndarray
    human_action: np.ndarray
    action: np.ndarray
    robot_action: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class Assist:
    """What the step's assistance, blend and belief update read for a batch, and never change."""

    task: GoalTask
    control: ControlConfig
    alpha: np.ndarray  # each row's blend weight, (U,) (0: latent actions alone)
    assistance: np.ndarray | None = None  # each row's member or built-in name (None: control's)
    goal_sets: np.ndarray | None = None  # the belief's targets (None: control.likelihood's)
    # a_r only in rows with alpha > 0 (else every row, as the live log records): bitwise the same
    # for a member whose rows are independent (all built-in ones but ``point``)
    only_blended: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "alpha", np.asarray(self.alpha, dtype=float).reshape(-1))
        if self.goal_sets is None:
            object.__setattr__(self, "goal_sets", belief_targets(self.task, self.control.likelihood))
        if self.assistance is not None:
            members = np.asarray(self.assistance)  # names (compared fast), or objects among them
            members = members if members.dtype.kind == "U" else members.astype(object)
            if members.shape != self.alpha.shape:
                raise ConfigError(
                    f"assistance must name one member per row, shape {self.alpha.shape}, got {members.shape}"
                )
            object.__setattr__(self, "assistance", members)  # each is checked where it runs (assist)

    def rows(self, idx: np.ndarray) -> Assist:
        """The same for rows ``idx`` of the batch."""
        assistance = None if self.assistance is None else self.assistance[idx]
        return dataclasses.replace(self, alpha=self.alpha[idx], assistance=assistance)


def blend(a_h: np.ndarray, a_r: np.ndarray, alpha: float | np.ndarray) -> np.ndarray:
    """Eq. M1: a = (1 - alpha) a_h + alpha a_r; ``alpha`` in [0, 1], a scalar or one per row (...)."""
    alpha_arr = np.asarray(alpha, dtype=float)
    if not np.all((alpha_arr >= 0.0) & (alpha_arr <= 1.0)):
        raise ConfigError(f"alpha must be in [0, 1], got values in [{alpha_arr.min()}, {alpha_arr.max()}]")
    alpha_arr = alpha_arr[..., None]
    return (1.0 - alpha_arr) * a_h + alpha_arr * a_r


def sanitize(action: np.ndarray) -> np.ndarray:
    """Replace every row that holds a non-finite entry by a zero action."""
    return np.where(~np.all(np.isfinite(action), axis=-1, keepdims=True), 0.0, action)


def safe_step(
    state: np.ndarray, action: np.ndarray, dt: float, lower: np.ndarray, upper: np.ndarray, max_speed: float
) -> np.ndarray:
    """s' = s + dt a, safe: a non-finite action row zero, velocities clipped to +-max_speed, s' to
    [lower, upper]; ConfigError if ``state`` is not finite (a sensor fault is not a command)."""
    if not np.all(np.isfinite(state)):
        raise ConfigError("state holds NaN or infinite joint positions; refusing to command")
    return np.clip(state + dt * np.clip(sanitize(action), -max_speed, max_speed), lower, upper)


def advance(
    assist: Assist, state: np.ndarray, log_b: np.ndarray, a_h: np.ndarray, b: np.ndarray | None = None
) -> StepResult:
    """Lines 6-9 of Algorithm 1 for a batch: assistance, blend (Eq. M1), belief update, safe step;
    ``b`` is ``belief(log_b)`` if the caller has it."""
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
    return StepResult(new_state, new_log_b, a_h, a, a_r * weight[:, None])


def _assistance(
    task: GoalTask, control: ControlConfig, state: np.ndarray, b: np.ndarray, assistance: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """a_r and the blend weight per row: ``control.assistance``, or each row's member."""
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
    assistance: str | Member | None = None,
) -> StepResult:
    """One step of Algorithm 1 from joystick input z (U, d) to commanded state, batched: the runner's
    step for a held input; ``alpha`` scalar or (U,), ``assistance`` every row's member (default
    ``control.assistance``), ``rest`` as :func:`human_action`."""
    check_decoder(decoder, task)
    z = np.asarray(z, dtype=float)
    finite = np.all(np.isfinite(z), axis=-1, keepdims=True)
    a_h = human_action(decoder.decode_numpy(np.where(finite, z, 0.0), state, belief(log_belief)), z, rest)
    alpha_arr = np.broadcast_to(np.asarray(alpha, dtype=float), state.shape[:1])
    members = None if assistance is None else np.full(len(state), assistance, dtype=object)
    return advance(Assist(task, control, alpha_arr, members), state, log_belief, a_h)


def human_action(decoded: np.ndarray, z: np.ndarray, rest: str) -> np.ndarray:
    """a_h from the decoded phi(z, s, b): nothing for a non-finite z; at rest (z = 0), phi(0, s, b)
    under ``rest="decode"`` (sims 1-4, Eq. S1), nothing under ``"zero"`` (teleop, the study)."""
    check_choice("rest", rest, REST)
    z = np.asarray(z, dtype=float)
    ok = np.all(np.isfinite(z), axis=-1, keepdims=True)
    if rest == "zero":
        ok = ok & np.any(z != 0.0, axis=-1, keepdims=True)
    return np.where(ok, decoded, 0.0)


def check_decoder(decoder: ActionDecoder, task: GoalTask) -> None:
    """The decoder must act in the task's robot and read a belief over its goals, else ConfigError."""
    if decoder.robot != task.robot.name:
        raise ConfigError(f"decoder was trained for {decoder.robot!r}, the task is for {task.robot.name!r}")
    if decoder.n_goals != task.n_goals:
        raise ConfigError(
            f"decoder reads a belief over {decoder.n_goals} goals, the task has {task.n_goals}; "
            "for a task grown by a new goal, wrap the decoder in lasa.method.context_map.MappedDecoder"
        )


def decode_candidates(
    decoder: ActionDecoder, z_grid: np.ndarray, state: np.ndarray, b: np.ndarray
) -> np.ndarray:
    """phi(z, s, b) for every user (s (U, n), b (U, G)) and candidate z (K, d) in one call, (U, K, n)."""
    return decoder.decode_numpy(z_grid[None], state[:, None], b[:, None])


def latent_grid(n_z: int, z_dim: int = 1) -> np.ndarray:
    """The joystick candidates a user weighs: an even grid on [-1, 1]^d, (n_z^d, d)."""
    axis = np.linspace(-1.0, 1.0, n_z)
    return np.stack([m.ravel() for m in np.meshgrid(*([axis] * z_dim), indexing="ij")], axis=-1)
