"""The eating study's measures (Sec. VI) from the record of a simulated or logged session: Total
Time, Idle Time, Goal Error (metre-seconds) and Preference Alignment (not the Likert questionnaire)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from lasa.world.eating import GOALS, PREFERENCES, TASK_NAMES, TASKS, EatingTask, fork_direction
from lasa.world.record import Episodes


def goal_error(tip: np.ndarray, goals: np.ndarray, active: np.ndarray, dt: float) -> np.ndarray:
    """Goal Error: the tip's distance to the closest goal, summed over the task's steps, times dt.

    Per episode [m s], (E,), from ``tip`` (T, E, 3), ``goals`` (G, 3) and the ``active`` steps (T, E).
    """
    dist = np.linalg.norm(tip[:, :, None, :] - goals[None, None], axis=-1).min(axis=-1)
    return (dist * active).sum(axis=0) * dt


def total_time(end: np.ndarray, dt: float) -> np.ndarray:
    """Total Time: the steps until the task was done (or to the limit, if never) times dt, per episode [s]."""
    return end * dt


def idle_time(idle: np.ndarray, active: np.ndarray, dt: float) -> np.ndarray:
    """Idle Time: time without stick input while the task ran, per episode [s], (E,)."""
    return (idle & active).sum(axis=0) * dt


def alignment(direction: np.ndarray, desired: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Preference Alignment: mean of d . d* over the masked steps, per episode (NaN if none), (E,).

    ``direction`` (T, E, 3) is the fork's, ``desired`` d(theta) (E, 3) or (T, E, 3), ``mask`` (T, E) the
    phase's steps.
    """
    dots = np.einsum("tei,tei->te", direction, np.broadcast_to(desired, direction.shape))
    count = mask.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, (dots * mask).sum(axis=0) / count, np.nan)


def measures(task: EatingTask, episodes: Episodes) -> dict[str, pd.DataFrame]:
    """The study's tidy tables ``goal_error``, ``time`` and ``alignment``: one row per participant x
    condition x task (x phase for alignment). Goal Error is to the closest of all four goals
    (``goal_error``) or of the three bowls (``goal_error_bowls``); ``mean_distance`` is it over the time."""
    robot = task.robot
    dt = episodes.dt
    active = episodes.active()
    tip = episodes.tip[:-1]
    goals = robot.goal_positions()
    bowls = [i for i, g in enumerate(GOALS) if g != "plate"]
    who = ("participant", "condition", "assistance", "task", "order")
    keys = pd.DataFrame({"robot": robot.name, **{k: getattr(episodes, k) for k in who}})
    error = keys.assign(
        goal_error=goal_error(tip, goals, active, dt),
        goal_error_bowls=goal_error(tip, goals[bowls], active, dt),
    )
    error["mean_distance"] = error.goal_error / np.maximum(episodes.end * dt, dt)
    time = keys.assign(
        total_time=total_time(episodes.end, dt),
        idle_time=idle_time(episodes.idle, active, dt),
        mode_switches=(episodes.switch & active).sum(axis=0),
        completed=episodes.completed,
    )
    direction = episodes.direction[:-1]
    rows = []
    for name in TASK_NAMES:
        cols = episodes.task == name
        for i, ph in enumerate(TASKS[name]):
            pref = ph.preference or "stab"
            desired = fork_direction(robot, GOALS.index(ph.goal), PREFERENCES[pref])
            mask = (episodes.phase[:-1, cols] == i) & active[:, cols]
            row = {
                "robot": robot.name,
                **{k: getattr(episodes, k)[cols] for k in ("participant", "condition", "assistance")},
                "task": name,
                "phase": ph.name,
                "preference": pref,
                "alignment": alignment(direction[:, cols], desired, mask),
                "steps": mask.sum(axis=0),
            }
            rows.append(pd.DataFrame(row))
    return {"goal_error": error, "time": time, "alignment": pd.concat(rows, ignore_index=True)}
