"""The kit for running the eating study with people: schedule, questionnaire, and reading sessions.

- :func:`write_schedule`: the order of the four conditions for N participants, a balanced
  Latin square (Williams design, :func:`lasa.study.williams_square`), participant i on row
  i mod 4, as the simulated cohort.
- :func:`survey`: the paper's 7-point Likert questionnaire after each condition, on five
  scales (Easy, Helpful, Precise, Intuitive, Prefer), saved beside the sessions in
  ``likert.csv`` (one row per participant x condition x scale).
- :func:`load_sessions`: logged sessions (:mod:`lasa.sessionlog`) as the
  :class:`lasa.study.Episodes` that the simulated cohort produces, so people's sessions go
  through the same measures (:func:`lasa.study.measures`) and statistics.
- :func:`likert_tests`: the paired t-tests of Fig. dessert's right panel, LA+SA against each
  other condition on each scale (Holm's correction over the three comparisons of a scale).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from lasa.errors import ArtifactError, ConfigError
from lasa.io import locked, write_csv
from lasa.sessionlog import read_session
from lasa.study import CONDITIONS, NO_ASSISTANCE, Episodes, tip_frames, williams_square

__all__ = [
    "SCALES",
    "write_schedule",
    "survey",
    "read_likert",
    "load_sessions",
    "likert_tests",
    "analyse_sessions",
]

SCALES = ("Easy", "Helpful", "Precise", "Intuitive", "Prefer")
QUESTIONS = {
    "Easy": "It was easy to complete the tasks with this robot.",
    "Helpful": "The robot was helpful.",
    "Precise": "I could make precise motions.",
    "Intuitive": "The robot was intuitive to control.",
    "Prefer": "I would use this condition again.",
}


def write_schedule(n: int, out: str | os.PathLike[str]) -> Path:
    """Write the order of conditions for ``n`` participants (CSV: participant, position, condition)."""
    if int(n) != n or n < 1:
        raise ConfigError(f"the number of participants must be a positive integer, got {n!r}")
    square = williams_square(len(CONDITIONS))
    rows = [
        {"participant": f"p{i:02d}", "position": k + 1, "condition": CONDITIONS[c]}
        for i in range(n)
        for k, c in enumerate(square[i % len(CONDITIONS)])
    ]
    return write_csv(out, pd.DataFrame(rows))


def survey(
    folder: str | os.PathLike[str], participant: str, condition: str, answers: list[int] | None = None
) -> Path:
    """Record one participant's questionnaire after one condition in ``<folder>/likert.csv``.

    Args:
        folder: The sessions folder.
        participant: The participant's id.
        condition: The condition just done.
        answers: One answer in 1..7 per scale of :data:`SCALES`; asked on the terminal if None.

    Raises:
        ConfigError: for an answer outside 1..7, or the wrong number of answers.
    """
    if condition not in CONDITIONS:
        raise ConfigError(f"unknown condition {condition!r}; choose one of {CONDITIONS}")
    if answers is None:
        answers = []
        print(f"{participant}, {condition}: 1 = strongly disagree ... 7 = strongly agree")
        for scale in SCALES:
            answers.append(int(input(f"{QUESTIONS[scale]} [1-7]: ")))
    if len(answers) != len(SCALES) or any(not 1 <= int(a) <= 7 for a in answers):
        raise ConfigError(f"give {len(SCALES)} answers in 1..7 ({', '.join(SCALES)}), got {answers}")
    path = Path(folder) / "likert.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    new = pd.DataFrame(
        {
            "participant": participant,
            "condition": condition,
            "scale": SCALES,
            "answer": [int(a) for a in answers],
        }
    )
    with locked(path.parent):
        if path.exists():
            old = pd.read_csv(path, dtype={"participant": str})
            keep = ~((old.participant == participant) & (old.condition == condition))
            new = pd.concat([old[keep], new], ignore_index=True)
        write_csv(path, new)
    return path


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
    """The eating-task sessions in ``folder`` as :class:`lasa.study.Episodes`.

    Args:
        folder: The sessions folder.
        task: The eating task (:func:`lasa.eating.make_eating_task`): its robot gives the
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

    from lasa.eating import EatingTask

    if not isinstance(task, EatingTask):
        raise ConfigError("load_sessions reads eating-task sessions; pass lasa.eating.make_eating_task()")
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
        pressed = (frame.mode_press.to_numpy() > 0) & str(logs[e][1]["condition"]).startswith("R")
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
            np.char.endswith(conditions.astype(str), "+SA"),
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
    from lasa import stats

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
        (:func:`lasa.study.measures`), ``means`` per condition, and, when every participant
        did every condition, ``sa_effect`` (the within-subjects SA test on Goal Error and on
        the mean distance) and ``time_tests`` (LA+SA against each condition, times summed over
        tasks, Holm); with questionnaire answers, ``likert`` (:func:`likert_tests`).
    """
    from lasa import stats
    from lasa.study import measures

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
