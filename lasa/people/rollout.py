"""Algorithm 1 (LA and LA+SA) for a batch of simulated users: at each step one decoder call evaluates
phi(z, s, b) for every user and joystick candidate z, each user picks one by Eq. S1 (a pilot maybe
another), and the episode runner takes Algorithm 1's step."""

from __future__ import annotations

import dataclasses

import numpy as np

from lasa.base.config import ControlConfig
from lasa.base.errors import ConfigError
from lasa.method.belief import uniform_log_belief
from lasa.method.decoder import ActionDecoder
from lasa.method.runner import Now, Runner, check_horizon
from lasa.method.step import Assist, check_decoder, decode_candidates, latent_grid
from lasa.people.users import UserPopulation, choose_latent, gumbel_noise, pilot_choice, user_costs
from lasa.world.goals import GoalTask


@dataclasses.dataclass(frozen=True)
class Trajectories:
    """The record of a batched rollout: s^t and b^t for t = 0..T, (T+1, U, .), and at each step the
    joystick input z (T, U, d), a_h^t and the blended command a^t before the safety clip, (T, U, n)."""

    states: np.ndarray
    beliefs: np.ndarray
    z: np.ndarray
    human_actions: np.ndarray
    actions: np.ndarray


class BoltzmannUsers:
    """The chooser of simulated users (Eq. S1) and pilots; ``z`` records their inputs (T, U, d)."""

    def __init__(
        self,
        decoder: ActionDecoder,
        users: UserPopulation,
        control: ControlConfig,
        horizon: int,
        noise: np.ndarray,
        pilot_noise: np.ndarray | None,
    ) -> None:
        self.decoder, self.users, self.dt = decoder, users, control.dt
        self.grid = latent_grid(control.n_z, decoder.z_dim)
        self.noise, self.pilot_noise = noise, pilot_noise
        self.z = np.empty((horizon, len(users), self.grid.shape[1]))
        self._k_prev: np.ndarray | None = None

    def __call__(self, now: Now) -> np.ndarray:
        """Every user's a_h at step ``now.t``: phi of the candidate each one picks."""
        t, users = now.t, self.users
        phi = decode_candidates(self.decoder, self.grid, now.state, now.belief)  # (U, K, n): one call
        costs = user_costs(users.target_at(t), now.state, phi, self.dt)
        k = choose_latent(costs, users.beta(t), gumbel_noise(self.noise[users.user, t]))
        if self.pilot_noise is not None:
            k = pilot_choice(users, k, self._k_prev, self.pilot_noise[users.user, t], len(self.grid))
            self._k_prev = k
        self.z[t] = self.grid[k]
        return phi[np.arange(len(k)), k]


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
    """Run Algorithm 1 for ``horizon`` steps of a batch of simulated users, blended by ``alpha`` (per
    user (U,) or one), each user u drawing from uniforms ``noise[users.user[u]]`` in (0, 1), (N, T, K)
    for K joystick candidates, and as pilots from ``pilot_noise`` (N, T, 2)
    (:func:`lasa.people.users.pilot_choice`); ``assistance``: each user's member (default the control's)."""
    check_decoder(decoder, task)
    check_horizon(horizon)
    n_users, k = len(users), control.n_z**decoder.z_dim
    if noise.ndim != 3 or noise.shape[1] < horizon or noise.shape[2] != k:
        raise ConfigError(f"noise must have shape (streams, >= {horizon}, {k}), got {noise.shape}")
    piloted = bool(users.pilot != "boltzmann" and users.pilot_prob > 0)
    got = None if pilot_noise is None else pilot_noise.shape
    if piloted and (got is None or len(got) != 3 or got[1] < horizon or got[2] != 2):
        raise ConfigError(
            f"a {users.pilot} pilot needs pilot_noise of shape (streams, >= {horizon}, 2), got {got}"
        )
    chooser = BoltzmannUsers(decoder, users, control, horizon, noise, pilot_noise if piloted else None)
    alphas = np.broadcast_to(np.asarray(alpha, dtype=float), (n_users,))
    start = np.broadcast_to(task.start, (n_users, task.robot.n_joints))
    assist = Assist(task, control, alphas, assistance)
    runner = Runner(assist, start, uniform_log_belief(n_users, task.n_goals))
    record = runner.run(chooser, horizon, progress=progress, desc=f"rollout {n_users} users")
    return Trajectories(record.states, record.beliefs, chooser.z, record.human_actions, record.actions)
