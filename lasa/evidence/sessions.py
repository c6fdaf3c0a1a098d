"""People's sessions of the eating study, read back for analysis: the logs and the questionnaire.

- :func:`load_sessions`: logged sessions (:mod:`lasa.evidence.sessionlog`, written live by
  :mod:`lasa.live.teleop`) as the :class:`lasa.people.participants.Episodes` that the simulated
  cohort produces, so people's sessions go through the same measures
  (:func:`lasa.people.participants.measures`) and statistics.
- :func:`read_likert`: the answers :func:`lasa.live.studykit.survey` saved (``likert.csv``).
- :func:`likert_tests`: the paired t-tests of Fig. dessert's right panel, LA+SA against each
  other condition on each scale (Holm's correction over the three comparisons of a scale).
- :func:`analyse_sessions`: all of it for one folder, as notebook 11 calls it.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from lasa.base.conditions import CONDITIONS
from lasa.base.conditions import parse as parse_condition
from lasa.base.config import NO_ASSISTANCE
from lasa.base.errors import ArtifactError, ConfigError
from lasa.evidence.sessionlog import read_session
from lasa.people.participants import Episodes, tip_frames

__all__ = ["SCALES", "read_likert", "load_sessions", "likert_tests", "analyse_sessions"]

SCALES = ("Easy", "Helpful", "Precise", "Intuitive", "Prefer")


def read_likert(folder: str | os.PathLike[str]) -> pd.DataFrame | None:
    """The questionnaire answers saved in ``folder``, or None if there are none."""
    path = Path(folder) / "likert.csv"
    return pd.read_csv(path, dtype={"participant": str}) if path.is_file() else None


def load_sessions(
    folder: str | os.PathLike[str],
    task: object,
    include_interrupted: bool = False,
    include_damaged: bool = False,
) -> Episodes:
    """The eating-task sessions in ``folder`` as :class:`lasa.people.participants.Episodes`.

    Args:
        folder: The sessions folder.
        task: The eating task (:func:`lasa.world.eating.make_eating_task`): its robot gives the
            fork's pose from the logged states.
        include_interrupted: Keep sessions that did not end normally (they count as not
            completed); by default they are left out.
        include_damaged: Analyse a damaged log's rows anyway (a cell that does not parse,
            or fewer or more rows than its sidecar records); by default a damaged log is an
            error and nothing is analysed.

    Raises:
        ArtifactError: if the folder holds no eating-task session, or a damaged one.
    """
    import mujoco

    from lasa.world.eating import EatingTask

    if not isinstance(task, EatingTask):
        raise ConfigError(
            "load_sessions reads eating-task sessions; pass lasa.world.eating.make_eating_task()"
        )
    sidecars = sorted(Path(folder).glob("*.json"))
    logs = []
    for sidecar in sidecars:
        frame, meta = read_session(sidecar, allow_damaged=include_damaged)
        if meta.get("task") not in ("Entree", "Dessert") or meta.get("condition") not in CONDITIONS:
            continue
        if meta["status"] != "complete" and not include_interrupted:
            continue
        logs.append((frame, meta))
    if not logs:
        raise ArtifactError(f"no eating-task session in {folder}")
    robot = task.robot
    n = robot.n_joints
    horizon = max(len(f) for f, _ in logs)
    states = np.empty((horizon + 1, len(logs), n))
    phase = np.zeros((horizon + 1, len(logs)), dtype=int)
    idle = np.zeros((horizon, len(logs)), dtype=bool)
    switch = np.zeros((horizon, len(logs)), dtype=bool)
    end = np.empty(len(logs), dtype=int)
    for e, (frame, _) in enumerate(logs):
        s = frame[[f"s{i}" for i in range(n)]].to_numpy()
        states[0, e] = task.start
        states[1 : len(s) + 1, e] = s
        states[len(s) + 1 :, e] = s[-1] if len(s) else task.start
        phase[1 : len(s) + 1, e] = frame.phase.to_numpy()
        phase[len(s) + 1 :, e] = phase[len(s), e]
        moved = (frame[["z0", "z1"]].to_numpy() != 0).any(axis=1)
        # a mode press is input in Retargeting (it switches modes) and nothing in latent actions
        retargeting = parse_condition(str(logs[e][1]["condition"])).interface == "R"
        pressed = (frame.mode_press.to_numpy() > 0) & retargeting
        held = frame.stop.to_numpy() > 0
        idle[: len(s), e] = ~moved & ~pressed & ~held
        switch[: len(s), e] = pressed & ~held
        end[e] = len(s)
    data = mujoco.MjData(robot.model)
    flat = states.reshape(-1, n)
    tip, direction, _, _ = tip_frames(robot, data, flat)
    meta_list = [m for _, m in logs]
    conditions = np.array([m["condition"] for m in meta_list])
    return Episodes(
        participant=np.array([m["participant"] for m in meta_list]),
        condition=conditions,
        assistance=np.where(
            np.array([parse_condition(str(c)).assisted for c in conditions], dtype=bool),
            np.array([m.get("control", {}).get("assistance", "hindsight") for m in meta_list]),
            NO_ASSISTANCE,
        ),
        task=np.array([m["task"] for m in meta_list]),
        order=np.zeros(len(logs), dtype=int),
        states=states,
        tip=tip.reshape(horizon + 1, len(logs), 3),
        direction=direction.reshape(horizon + 1, len(logs), 3),
        phase=phase,
        idle=idle,
        switch=switch,
        end=end,
        completed=np.array([bool(m.get("done", False)) for m in meta_list]),
        dt=float(meta_list[0]["dt"]),
    )


def likert_tests(answers: pd.DataFrame) -> pd.DataFrame:
    """Fig. dessert (right): on each scale, LA+SA against each other condition (paired t, Holm)."""
    from lasa.evidence import stats

    out = []
    for scale, part in answers.groupby("scale", sort=False):
        frame = part.assign(task="survey").rename(columns={"answer": "value"})
        pairs = [("LA+SA", c) for c in CONDITIONS if c != "LA+SA" and c in set(frame.condition)]
        table = stats.pairwise(frame, "value", pairs=pairs)
        out.append(table.assign(scale=scale))
    return pd.concat(out, ignore_index=True)


def analyse_sessions(folder: str | os.PathLike[str], task: object) -> dict[str, pd.DataFrame]:
    """People's sessions through the simulated cohort's measures and statistics.

    Returns:
        The tidy ``goal_error``, ``time`` and ``alignment`` tables of the sessions
        (:func:`lasa.people.participants.measures`), ``means`` per condition, and, when every participant
        did every condition, ``sa_effect`` (the within-subjects SA test on Goal Error and on
        the mean distance) and ``time_tests`` (LA+SA against each condition, times summed over
        tasks, Holm); with questionnaire answers, ``likert`` (:func:`likert_tests`).
    """
    from lasa.evidence import stats
    from lasa.people.participants import measures

    episodes = load_sessions(folder, task)
    frames = measures(task, episodes)  # type: ignore[arg-type]
    out = dict(frames)
    out["means"] = (
        frames["time"]
        .merge(frames["goal_error"], on=["robot", "participant", "condition", "assistance", "task", "order"])
        .groupby("condition")[["total_time", "idle_time", "mode_switches", "goal_error", "mean_distance"]]
        .mean()
    )
    counts = frames["time"].groupby("participant").condition.nunique()
    if len(counts) >= 2 and (counts == len(CONDITIONS)).all():
        err = frames["goal_error"]
        rows = [stats.sa_effect_within(err, m) | {"measure": m} for m in ("goal_error", "mean_distance")]
        out["sa_effect"] = pd.DataFrame(rows)
        others = [("LA+SA", c) for c in CONDITIONS if c != "LA+SA"]
        out["time_tests"] = pd.concat(
            {
                m: stats.pairwise(frames["time"], m, agg="sum", pairs=others)
                for m in ("total_time", "idle_time")
            }
        )
    answers = read_likert(folder)
    if answers is not None and answers.participant.nunique() >= 2:
        out["likert"] = likert_tests(answers)
    return out
