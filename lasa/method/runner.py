"""The one episode runner: a batch of episodes advanced by Algorithm 1's step until they stop; every
loop differs only by its *chooser*, the running episodes' human actions a_h at step t.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from tqdm.auto import tqdm

from lasa.base.errors import ConfigError
from lasa.method.belief import belief
from lasa.method.decoder import ActionDecoder
from lasa.method.step import Assist, StepResult, advance, human_action


@dataclasses.dataclass(frozen=True)
class Now:
    """What a chooser sees of the running episodes at step t (from 0): their indices in the batch
    (A,), s^t (A, n) [rad], b^t and log b^t (A, G)."""

    t: int
    rows: np.ndarray
    state: np.ndarray
    belief: np.ndarray
    log_belief: np.ndarray


Chooser = Callable[[Now], np.ndarray]  # the running episodes' human actions a_h, (A, n) [rad/s]
Observer = Callable[[int, "Runner"], np.ndarray]  # after step t's state: the episodes that finished, (U,)


def check_horizon(horizon: int) -> None:
    """A run's horizon is a positive whole number of steps, else ConfigError."""
    if int(horizon) != horizon or horizon < 1:
        raise ConfigError(f"horizon must be a positive integer, got {horizon!r}")


def held_input(decoder: ActionDecoder, z: np.ndarray, rest: str = "decode") -> Chooser:
    """The chooser that holds input ``z[row]`` (U, d) for each episode: a_h = phi(z, s, b), under
    the stick-at-rest convention ``rest`` (:func:`lasa.method.step.human_action`)."""
    z = np.asarray(z, dtype=float)

    def choose(now: Now) -> np.ndarray:
        rows = z[now.rows]
        return human_action(decoder.decode_numpy(rows, now.state, now.belief), rows, rest)

    return choose


@dataclasses.dataclass(frozen=True)
class Record:
    """A batch of finished episodes: s^t, b^t (T+1, U, .) held after an episode stops; a_h^t and the
    command a^t (T, U, n), zero after it stops; the step each stopped at (T at the horizon), (U,)."""

    states: np.ndarray
    beliefs: np.ndarray
    human_actions: np.ndarray
    actions: np.ndarray
    end: np.ndarray


class Runner:
    """Episodes advanced together through Algorithm 1's step, from s^0 (U, n) and log b^0 (U, G);
    ``update_belief=False`` holds b at b^0 (the property's confident hold). ``running`` (U,) and
    ``t``, the steps taken, follow the run."""

    def __init__(
        self, assist: Assist, start: np.ndarray, log_belief: np.ndarray, update_belief: bool = True
    ) -> None:
        self.assist, self.update_belief = assist, update_belief
        self.state = np.array(start, dtype=float)
        self.log_belief = np.array(log_belief, dtype=float)
        n_users = len(self.state)
        if self.state.ndim != 2 or self.log_belief.shape != (n_users, assist.task.n_goals):
            raise ConfigError(
                f"start must be (U, n) and log_belief (U, {assist.task.n_goals}); "
                f"got {self.state.shape} and {self.log_belief.shape}"
            )
        if len(assist.alpha) != n_users:
            raise ConfigError(f"the assist has {len(assist.alpha)} rows, the batch {n_users} episodes")
        self.running = np.ones(n_users, dtype=bool)
        self.t = 0

    @property
    def belief(self) -> np.ndarray:
        """b of every episode, (U, G)."""
        return belief(self.log_belief)

    def step(self, choose: Chooser, b: np.ndarray | None = None) -> StepResult:
        """One step of the running episodes (in ``np.flatnonzero(running)`` order): their
        chooser's a_h, then Algorithm 1's step; ``b`` is every episode's belief if the caller has it."""
        rows = np.flatnonzero(self.running)
        b = belief(self.log_belief[rows]) if b is None else b[rows]
        state, log_b = self.state[rows], self.log_belief[rows]
        a_h = choose(Now(self.t, rows, state, b, log_b))
        result = advance(self.assist.rows(rows), state, log_b, a_h, b)
        self.state[rows] = result.state
        if self.update_belief:
            self.log_belief[rows] = result.log_belief
        self.t += 1
        return result

    def run(
        self,
        choose: Chooser,
        horizon: int,
        observe: Observer | None = None,
        progress: bool = False,
        desc: str = "episodes",
    ) -> Record:
        """Run every episode until it stops or the horizon T: record s and b, step, observe
        (``observe(t, runner)`` returns the episodes that finished at step t)."""
        check_horizon(horizon)
        n_users, (n, g) = len(self.state), (self.state.shape[1], self.log_belief.shape[1])
        states, beliefs = np.empty((horizon + 1, n_users, n)), np.empty((horizon + 1, n_users, g))
        a_hs, acts = np.zeros((horizon, n_users, n)), np.zeros((horizon, n_users, n))
        end = np.full(n_users, horizon)
        with tqdm(total=horizon, desc=desc, disable=not progress) as bar:
            for t in range(horizon + 1):
                b = self.belief  # recorded, and the running rows' b at this step
                states[t], beliefs[t] = self.state, b
                if observe is not None:
                    finished = observe(t, self) & self.running
                    end[finished], self.running = t, self.running & ~finished
                if t == horizon or not self.running.any():
                    break
                rows = np.flatnonzero(self.running)
                result = self.step(choose, b)
                a_hs[t, rows], acts[t, rows] = result.human_action, result.action
                bar.update(1)
        states[t + 1 :], beliefs[t + 1 :] = states[t], beliefs[t]
        return Record(states=states, beliefs=beliefs, human_actions=a_hs, actions=acts, end=end)
