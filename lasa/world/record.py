"""The study's record of eating-task episodes, simulated (:mod:`lasa.people`) or real
(:mod:`lasa.evidence.sessions`)."""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Episodes:
    """The record of a study: one episode per participant x condition x task.

    Attributes:
        participant, condition, task, assistance: Who, under which condition, which task, which SA
            member (``"none"`` for R and LA), (E,); ``order``: the condition's place in the session (0-3).
        states, tip, direction: Joint positions, fork-tip positions [m] and fork directions (unit),
            (T+1, E, .) (held after an episode ends); ``phase``: each step's phase index, (T+1, E).
        idle, switch: Whether the participant gave no stick input, or switched mode (R), (T, E).
        end: The step each episode ended (the horizon if unfinished), (E,); ``completed`` within it.
        belief: The robot's belief over the goals, (T+1, E, G); waypoint: the one worked towards at
            the end, (E,) (None: not logged)."""

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
        return np.arange(self.idle.shape[0])[:, None] < self.end[None, :]
