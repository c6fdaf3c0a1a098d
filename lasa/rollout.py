"""Algorithm 1 (LA and LA+SA), batched over simulated users and joystick candidates.

Every user of a sweep advances together, as rows of arrays. At each step:

1. one decoder call evaluates phi(z, s, b) for every user and every joystick
   candidate z on the grid (U x K rows);
2. each user picks a candidate by Eq. S1 (:mod:`lasa.users`), which sets a_h;
3. the robot's assistance a_r (Eq. M2, or another member of :mod:`lasa.assistance`
   named by ``ControlConfig.assistance``) is blended with a_h (Eq. M1) using each
   user's alpha: alpha = 0 is the method ``LA``, alpha > 0 is ``LA+SA``;
4. the belief is updated with a_h (Alg. 1, line 8);
5. the robot takes the safe step s' = clip(s + dt a).

Users of different methods, rationalities and seeds share a batch, and so share each
decoder call. The decoder is anything that follows :class:`lasa.decoder.ActionDecoder`:
the trained model, or a wrapper of it such as the context map of new goals
(:class:`lasa.newgoals.MappedDecoder`), which this module does not need to know about.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from tqdm.auto import tqdm

from lasa.assistance import assist
from lasa.belief import belief, log_likelihood, uniform_log_belief, update_log_belief
from lasa.config import ASSISTANCE, ControlConfig, check_choice
from lasa.control import blend, safe_step, sanitize
from lasa.decoder import ActionDecoder
from lasa.errors import ConfigError
from lasa.task import CupTask
from lasa.users import (
    UserPopulation,
    choose_latent,
    gumbel_noise,
    latent_grid,
    pilot_choice,
    user_costs,
)

__all__ = [
    "Trajectories",
    "StepResult",
    "check_decoder",
    "decode_candidates",
    "advance",
    "shared_autonomy_step",
    "rollout",
    "METHODS",
    "METHOD_DECODER",
    "method_alpha",
]

METHODS = ("LA", "LA+SA", "LA+SA+Entropy")
# Which decoder each method uses: "base" is trained on reconstruction alone (Sec. III-A),
# "entropy" with the entropy term of Eq. T6 (lasa.entropy).
METHOD_DECODER = {"LA": "base", "LA+SA": "base", "LA+SA+Entropy": "entropy"}


def method_alpha(method: str, control: ControlConfig) -> float:
    """The blend weight alpha of a method: 0 for LA, ``control.alpha`` for the others."""
    if method not in METHODS:
        raise ConfigError(f"unknown method {method!r}; choose one of {', '.join(map(repr, METHODS))}")
    return 0.0 if method == "LA" else control.alpha


@dataclasses.dataclass(frozen=True)
class Trajectories:
    """The record of a batched rollout.

    Attributes:
        states: s^t for t = 0..T, shape (T+1, U, n) [rad].
        beliefs: b^t for t = 0..T, shape (T+1, U, G).
        z: The joystick input chosen at each step, shape (T, U, d).
        human_actions: a_h^t, shape (T, U, n) [rad/s].
        actions: The blended command a^t before the safety clip, shape (T, U, n).
    """

    states: np.ndarray
    beliefs: np.ndarray
    z: np.ndarray
    human_actions: np.ndarray
    actions: np.ndarray


@dataclasses.dataclass(frozen=True)
class StepResult:
    """One step of Algorithm 1 for a batch of users.

    Attributes:
        state: s^{t+1}, shape (U, n) [rad].
        log_belief: log b^{t+1}, shape (U, G).
        human_action: a_h^t, shape (U, n) [rad/s] (zero where the input was not finite).
        action: the blended command a^t before the safety clip, shape (U, n) [rad/s].
        assistance: the robot's assistance a_r^t, times its blend weight, shape (U, n) [rad/s].
    """

    state: np.ndarray
    log_belief: np.ndarray
    human_action: np.ndarray
    action: np.ndarray
    assistance: np.ndarray | None = None


def advance(
    task: CupTask,
    control: ControlConfig,
    state: np.ndarray,
    log_b: np.ndarray,
    a_h: np.ndarray,
    alpha: np.ndarray,
    sets: np.ndarray,
    b: np.ndarray | None = None,
    members: np.ndarray | None = None,
) -> StepResult:
    """Lines 6-9 of Algorithm 1 for a batch: assistance, blend, belief update, safe transition.

    ``a_h`` is the decoded human action (U, n), ``alpha`` the blend weight per user (U,),
    ``sets`` the belief likelihood's goal sets (``task.belief_targets``), ``b`` the
    belief ``belief(log_b)`` if the caller has it already.
    """
    a_h = sanitize(a_h)
    if b is None:
        b = belief(log_b)
    a_r, weight = _assistance(task, control, state, b, members)
    a = blend(a_h, a_r, alpha * weight)
    lik = log_likelihood(state, a_h, sets, control.dt, control.belief_beta, control.likelihood_step)
    new_log_b = update_log_belief(log_b, lik, control.belief_floor)
    robot = task.robot
    new_state = safe_step(state, a, control.dt, robot.lower, robot.upper, control.max_joint_speed)
    return StepResult(
        state=new_state, log_belief=new_log_b, human_action=a_h, action=a, assistance=a_r * weight[:, None]
    )


def _assistance(
    task: CupTask, control: ControlConfig, state: np.ndarray, b: np.ndarray, members: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """a_r and the blend weight per user: ``control.assistance``, or each user's member.

    The goal sets of ``grasp_set`` are the task's (``task.belief_targets("grasp_set")``):
    the cups' grasp curves, or the eating task's whole stroke surfaces.
    """
    sets = task.belief_targets("grasp_set")
    if members is None:
        return assist(control.assistance, b, state, task.goals, sets, control.dt, control.action_scale)
    a_r, weight = np.empty_like(state), np.empty(len(state))
    for name in dict.fromkeys(members.tolist()):
        rows = members == name
        a_r[rows], weight[rows] = assist(
            name, b[rows], state[rows], task.goals, sets, control.dt, control.action_scale
        )
    return a_r, weight


REST = ("decode", "zero")  # what a stick at rest commands (shared_autonomy_step's ``rest``)


def shared_autonomy_step(
    decoder: ActionDecoder,
    task: CupTask,
    control: ControlConfig,
    state: np.ndarray,
    log_belief: np.ndarray,
    z: np.ndarray,
    alpha: float | np.ndarray,
    rest: str = "decode",
) -> StepResult:
    """One step of Algorithm 1 from joystick input to commanded state, batched over users.

    This is the step a teleoperated robot runs (:class:`lasa.controller.Controller` is
    this step for one user, and :class:`lasa.teleop.Station` runs it for latent actions):
    decode the joystick input, blend with the assistance, update the belief, take the safe
    step. A joystick input that is not finite (a disconnected or faulty device) decodes to
    no human action at all, so it can never become a command; the robot's own assistance
    still applies.

    **The stick at rest** (z = 0) is a named choice, ``rest``, because the loops differ:

    - ``"decode"``: phi(0, s, b), the decoder's own meaning of the rest position. The
      simulated users of sims 1-4 (Eq. S1 weighs z = 0 among its grid's inputs, and the
      paper's phi is defined there), :class:`lasa.controller.Controller` and the
      benchmark's reference step use it.
    - ``"zero"``: no human action. Live teleoperation uses it (:class:`lasa.teleop.Station`:
      a person who lets go of the stick expects the arm to stop, the assistance apart), and
      it is the convention of the study's simulated participants (:func:`lasa.study.simulate`,
      which decodes its candidates itself: resting the stick is their idle input).

    Args:
        decoder: The decoder phi (a trained model, or a wrapper such as
            :class:`lasa.newgoals.MappedDecoder` for a task grown by a new goal).
        task: The cup task.
        control: Control-loop units.
        state: s^t, shape (U, n).
        log_belief: log b^t, shape (U, G).
        z: Joystick inputs, shape (U, d); clamped to [-1, 1] by the decoder.
        alpha: Blend weight, scalar or shape (U,).
        rest: What a stick at rest commands: ``"decode"`` or ``"zero"`` (see above).
    """
    check_decoder(decoder, task)
    check_choice("rest", rest, REST)
    z = np.asarray(z, dtype=float)
    ok = np.all(np.isfinite(z), axis=-1, keepdims=True)
    a_h = decoder.decode_numpy(np.where(ok, z, 0.0), state, belief(log_belief))
    if rest == "zero":
        ok = ok & np.any(z != 0.0, axis=-1, keepdims=True)
    a_h = np.where(ok, a_h, 0.0)
    alpha_arr = np.broadcast_to(np.asarray(alpha, dtype=float), state.shape[:1])
    sets = task.belief_targets(control.likelihood)
    return advance(task, control, state, log_belief, a_h, alpha_arr, sets)


def check_decoder(decoder: ActionDecoder, task: CupTask) -> None:
    """The decoder must act in the task's robot and read a belief over the task's goals.

    Raises:
        ConfigError: naming the mismatch.
    """
    if decoder.robot != task.robot.name:
        raise ConfigError(f"decoder was trained for {decoder.robot!r}, the task is for {task.robot.name!r}")
    if decoder.n_goals != task.n_goals:
        raise ConfigError(
            f"decoder reads a belief over {decoder.n_goals} goals, the task has {task.n_goals}; "
            "for a task grown by a new goal, wrap the decoder in lasa.newgoals.MappedDecoder"
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


def rollout(
    decoder: ActionDecoder,
    task: CupTask,
    users: UserPopulation,
    alpha: float | np.ndarray,
    control: ControlConfig,
    horizon: int,
    noise: np.ndarray,
    progress: bool = False,
    pilot_noise: np.ndarray | None = None,
    assistance: np.ndarray | None = None,
) -> Trajectories:
    """Run Algorithm 1 for a batch of simulated users.

    Args:
        decoder: The decoder phi(z, s, b); its robot and goals must be the task's.
        task: The cup task (goals, start pose, joint limits via its robot).
        users: The simulated users (targets, rationality, random streams).
        alpha: Blend weight per user, shape (U,), or one for all.
        control: Control-loop units (dt, speed bound, belief model, n_z).
        horizon: Number of control steps T.
        noise: Uniforms in (0, 1) of shape (n_streams, T, K); user u draws from
            ``noise[users.seed[u]]``. K must equal the number of joystick candidates.
        progress: Show a tqdm progress bar over the steps.
        pilot_noise: Uniforms of shape (n_streams, T, 2) for laggy and noisy pilots
            (``users.pilot``, :func:`lasa.users.pilot_choice`); user u draws from
            ``pilot_noise[users.seed[u]]``. Needed only by those pilots.
        assistance: Each user's member of :mod:`lasa.assistance`, shape (U,), so that
            users of several readings share one batch (and each decoder call); default
            ``control.assistance`` for everyone.

    Returns:
        The trajectories of every user.
    """
    check_decoder(decoder, task)
    if int(horizon) != horizon or horizon < 1:
        raise ConfigError(f"horizon must be a positive integer, got {horizon!r}")
    n_users = len(users)
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), (n_users,))
    grid = latent_grid(control.n_z, decoder.z_dim)
    if noise.ndim != 3 or noise.shape[1] < horizon or noise.shape[2] != len(grid):
        raise ConfigError(f"noise must have shape (streams, >= {horizon}, {len(grid)}), got {noise.shape}")
    n = task.robot.n_joints
    members = None
    if assistance is not None:
        members = np.asarray(assistance, dtype=str)
        if members.shape != (n_users,):
            raise ConfigError(
                f"assistance must name one member per user, shape ({n_users},), got {members.shape}"
            )
        for name in set(members.tolist()):
            check_choice("assistance", name, ASSISTANCE)
    piloted = users.pilot != "boltzmann" and users.pilot_prob > 0
    if piloted and (
        pilot_noise is None
        or pilot_noise.ndim != 3
        or pilot_noise.shape[1] < horizon
        or pilot_noise.shape[2] != 2
    ):
        got = None if pilot_noise is None else pilot_noise.shape
        raise ConfigError(
            f"a {users.pilot} pilot needs pilot_noise of shape (streams, >= {horizon}, 2), got {got}"
        )
    k_prev: np.ndarray | None = None

    states = np.empty((horizon + 1, n_users, n))
    beliefs = np.empty((horizon + 1, n_users, task.n_goals))
    zs = np.empty((horizon, n_users, grid.shape[1]))
    a_hs = np.empty((horizon, n_users, n))
    acts = np.empty((horizon, n_users, n))
    s = np.broadcast_to(task.start, (n_users, n)).copy()
    log_b = uniform_log_belief(n_users, task.n_goals)
    states[0], beliefs[0] = s, belief(log_b)
    rows = np.arange(n_users)
    sets = task.belief_targets(control.likelihood)
    for t in tqdm(range(horizon), desc=f"rollout {n_users} users", disable=not progress):
        b = beliefs[t]  # belief(log_b), computed once per step
        phi = decode_candidates(decoder, grid, s, b)  # (U, K, n): the one decoder call
        costs = user_costs(users.target_at(t), s, phi, control.dt)
        k = choose_latent(costs, users.beta(t), gumbel_noise(noise[users.seed, t]))
        if piloted:
            assert pilot_noise is not None
            k = pilot_choice(users, k, k_prev, pilot_noise[users.seed, t], len(grid))
            k_prev = k
        step = advance(task, control, s, log_b, phi[rows, k], alpha, sets, b, members)
        s, log_b = step.state, step.log_belief
        zs[t], a_hs[t], acts[t] = grid[k], step.human_action, step.action
        states[t + 1], beliefs[t + 1] = s, belief(log_b)
    return Trajectories(states=states, beliefs=beliefs, z=zs, human_actions=a_hs, actions=acts)
