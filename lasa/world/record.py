"""The study's record of eating-task episodes, simulated (:mod:`lasa.people`) or real
(:mod:`lasa.evidence.sessions`)."""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["Episodes"]


@dataclasses.dataclass(frozen=True)
class Episodes:
    """The record of a study: one episode per participant x condition x task.

    Attributes:
        participant, condition, task: Who, under which condition (name), which task (name), (E,).
        assistance: The SA member of each episode (``"none"`` for R and LA), (E,).
        order: The position of the condition in the participant's session (0-3), (E,).
        states: Joint positions, (T+1, E, n) [rad] (held after an episode ends).
        tip: Fork-tip positions, (T+1, E, 3) [m].
        direction: Fork directions (unit), (T+1, E, 3).
        phase: Index of the phase each step belongs to, (T+1, E).
        idle: Whether the participant gave no stick input at each step, (T, E).
        switch: Whether the step was a mode switch (Retargeting), (T, E).
        end: The step each episode ended (its Total Time in steps; the horizon if unfinished), (E,).
        completed: Whether it finished within the horizon, (E,).
        dt: The control period [s].
        belief: The robot's belief over the goals at each step, (T+1, E, G) (None: not logged).
        waypoint: The waypoint each episode was working towards when it ended, (E,) (None: not logged).
    """

    participant: np.ndarray
    condition: np.ndarray
    assistance: np.ndarray
    task: np.ndarray
    order: np.ndarray
    states: np.ndarray
    tip: np.ndarray
    direction: np.ndarray
    phase: np.ndarray
    idle: np.ndarray
    switch: np.ndarray
    end: np.ndarray
    completed: np.ndarray
    dt: float
    belief: np.ndarray | None = None
    waypoint: np.ndarray | None = None

    def active(self) -> np.ndarray:
        """(T, E): whether each episode was still running at each step."""
        steps = np.arange(self.idle.shape[0])[:, None]
        return steps < self.end[None, :]
