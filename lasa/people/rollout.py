"""Algorithm 1 (LA and LA+SA) for a batch of simulated users choosing among joystick candidates.

Every user of a sweep advances together, as rows of arrays. At each step one decoder call
evaluates phi(z, s, b) for every user and every joystick candidate z on the grid (U x K rows,
:func:`lasa.method.step.decode_candidates`); each user picks a candidate by Eq. S1
(:mod:`lasa.people.users`), which sets a_h; and :func:`lasa.method.step.advance`, the shared
step, blends, updates the belief and takes the safe step.

Users of different methods, rationalities and streams share a batch, and so share each
decoder call.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from tqdm.auto import tqdm

from lasa.base.config import ControlConfig, check_choice
from lasa.base.errors import ConfigError
from lasa.method.assistance import members as members_of_family
from lasa.method.belief import belief, belief_targets, uniform_log_belief
from lasa.method.decoder import ActionDecoder
from lasa.method.step import advance, check_decoder, decode_candidates, latent_grid
from lasa.people.users import UserPopulation, choose_latent, gumbel_noise, pilot_choice, user_costs
from lasa.world.goals import GoalTask

__all__ = ["Trajectories", "rollout"]


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


def rollout(
    decoder: ActionDecoder,
    task: GoalTask,
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
        task: The goal task (goals, start pose, joint limits via its robot).
        users: The simulated users (targets, rationality, random streams).
        alpha: Blend weight per user, shape (U,), or one for all.
        control: Control-loop units (dt, speed bound, belief model, n_z).
        horizon: Number of control steps T.
        noise: Uniforms in (0, 1) of shape (n_streams, T, K); user u draws from
            ``noise[users.stream[u]]``. K must equal the number of joystick candidates.
        progress: Show a tqdm progress bar over the steps.
        pilot_noise: Uniforms of shape (n_streams, T, 2) for laggy and noisy pilots
            (``users.pilot``, :func:`lasa.people.users.pilot_choice`); user u draws from
            ``pilot_noise[users.stream[u]]``. Needed only by those pilots.
        assistance: Each user's member of :mod:`lasa.method.assistance` (built in, or added by
            :func:`lasa.method.assistance.register_member`), shape (U,), so that
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
    assistance = _assistance_rows(assistance, n_users)
    piloted = _piloted(users, pilot_noise, horizon)
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
    goal_sets = belief_targets(task, control.likelihood)
    for t in tqdm(range(horizon), desc=f"rollout {n_users} users", disable=not progress):
        b = beliefs[t]  # belief(log_b), computed once per step
        phi = decode_candidates(decoder, grid, s, b)  # (U, K, n): the one decoder call
        costs = user_costs(users.target_at(t), s, phi, control.dt)
        k = choose_latent(costs, users.beta(t), gumbel_noise(noise[users.stream, t]))
        if piloted:
            assert pilot_noise is not None
            k = pilot_choice(users, k, k_prev, pilot_noise[users.stream, t], len(grid))
            k_prev = k
        step = advance(task, control, s, log_b, phi[rows, k], alpha, goal_sets, b, assistance)
        s, log_b = step.state, step.log_belief
        zs[t], a_hs[t], acts[t] = grid[k], step.human_action, step.action
        states[t + 1], beliefs[t + 1] = s, belief(log_b)
    return Trajectories(states=states, beliefs=beliefs, z=zs, human_actions=a_hs, actions=acts)


def _assistance_rows(assistance: np.ndarray | None, n_users: int) -> np.ndarray | None:
    """Each user's assistance member, checked: one known member per user (None: the control's)."""
    if assistance is None:
        return None
    assistance = np.asarray(assistance, dtype=str)
    if assistance.shape != (n_users,):
        raise ConfigError(
            f"assistance must name one member per user, shape ({n_users},), got {assistance.shape}"
        )
    for name in set(assistance.tolist()):
        check_choice("assistance", name, members_of_family())
    return assistance


def _piloted(users: UserPopulation, pilot_noise: np.ndarray | None, horizon: int) -> bool:
    """Whether the users are laggy or noisy pilots; if so, their uniforms must cover the horizon."""
    piloted = bool(users.pilot != "boltzmann" and users.pilot_prob > 0)
    got = None if pilot_noise is None else pilot_noise.shape
    if piloted and (got is None or len(got) != 3 or got[1] < horizon or got[2] != 2):
        raise ConfigError(
            f"a {users.pilot} pilot needs pilot_noise of shape (streams, >= {horizon}, 2), got {got}"
        )
    return piloted
