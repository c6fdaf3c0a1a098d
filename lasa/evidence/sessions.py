"""People's sessions of the eating study, read back as the simulated cohort's record
(:class:`lasa.world.record.Episodes`) so they go through the same measures and statistics."""

from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from lasa.base.conditions import CONDITIONS
from lasa.base.conditions import parse as parse_condition
from lasa.base.config import NO_ASSISTANCE, TRIAL_LIMIT_S
from lasa.base.errors import ArtifactError, ConfigError
from lasa.base.io import locked
from lasa.evidence.questionnaire import DEMOGRAPHICS, LIKERT, TLX_SUBSCALES
from lasa.evidence.sessionlog import read_session
from lasa.world.fork import tip_frames
from lasa.world.record import Episodes

QUESTIONS = LIKERT  # the 7-point Likert questionnaire after each condition: scale -> statement
SCALES = tuple(QUESTIONS)
PRACTICE_TASK = "Dessert"  # practice on the harder task; its logs go to <sessions>/practice/, never analysed


def read_likert(folder: str | os.PathLike[str]) -> pd.DataFrame | None:
    """The questionnaire answers saved in ``folder``, or None if there are none."""
    path = Path(folder) / "likert.csv"
    return pd.read_csv(path, dtype={"participant": str}) if path.is_file() else None


def read_tlx(folder: str | os.PathLike[str]) -> pd.DataFrame | None:
    """The NASA-TLX ratings saved in ``folder`` (participant, condition, subscale, value), with each
    participant's and condition's raw TLX (the mean of the six subscales) as subscale ``raw``; None if
    there are none."""
    path = Path(folder) / "tlx.csv"
    if not path.is_file():
        return None
    tlx = pd.read_csv(path, dtype={"participant": str})
    tlx = tlx[tlx.subscale.isin(TLX_SUBSCALES)]
    raw = tlx.groupby(["participant", "condition"], sort=False).value.mean().reset_index()
    return pd.concat([tlx, raw.assign(subscale="raw")[tlx.columns]], ignore_index=True)


def read_demographics(folder: str | os.PathLike[str]) -> pd.DataFrame | None:
    """The optional demographics saved in ``folder`` (participant, item, answer), or None."""
    path = Path(folder) / "demographics.csv"
    return pd.read_csv(path, dtype=str, keep_default_na=False) if path.is_file() else None


def demographics_counts(answers: pd.DataFrame) -> pd.DataFrame:
    """How many participants gave each answer to each item (item, answer, count), in the form's order."""
    rows = [
        (item, answer, int(((answers.item == item) & (answers.answer == answer)).sum()))
        for item, choices in DEMOGRAPHICS.items()
        for answer in choices
    ]
    return pd.DataFrame(rows, columns=["item", "answer", "count"])


# The largest share of a trial's ticks without the participant's input (a frozen tab, a lost network)
# that still counts as the participant's own trial; more, and the trial is left out. The principle,
# fixed before any session was read: a page that runs sends input 20 times a second and the server
# reads input as missing only after half a second of silence, so a working page loses no tick; we
# allow the same 5% that the tests allow a false positive, and no more, so that at least 19 of 20
# logged ticks were driven by the person. Not tuned on any result.
DISCONNECTED_SHARE = 0.05
# Why a session is left out of the analysis (scan_sessions), as a pre-registration states it.
LEFT_OUT = {
    "damaged": "a damaged log: an unreadable sidecar, a torn or non-finite row, rows out of time order",
    "task": "not an eating-study session (another task, or a condition outside the four)",
    "status": "a session that did not end normally (interrupted, or stopped by a failure)",
    "disconnected": f"a trial in which more than {DISCONNECTED_SHARE:.0%} of the ticks had no input from "
    "the participant (a frozen page, a lost network)",
}


def session_limit(meta: dict[str, Any]) -> float:
    """A session's trial limit [s]: its sidecar's ``limit_s``, else :data:`TRIAL_LIMIT_S`."""
    return float(meta.get("limit_s", TRIAL_LIMIT_S))


def disconnected(frame: pd.DataFrame, meta: dict[str, Any]) -> tuple[int, int]:
    """A session's ticks without the participant's input and its ticks: the sidecar's
    ``disconnected_ticks`` if it records them, else its rows' ``connected`` column (none: 0)."""
    if "disconnected_ticks" in meta:
        return int(meta["disconnected_ticks"]), len(frame)
    if "connected" in frame:
        return int((frame.connected.to_numpy() == 0).sum()), len(frame)
    return 0, len(frame)


def disconnected_flag(ticks: int, steps: int) -> str | None:
    """Why a trial of ``steps`` ticks, ``ticks`` of them without input, breaks :data:`DISCONNECTED_SHARE`
    (None: it does not)."""
    if steps <= 0 or ticks <= DISCONNECTED_SHARE * steps:
        return None
    return f"{ticks} of {steps} ticks without input (more than {DISCONNECTED_SHARE:.0%})"


# Who a within-subject test leaves out (complete_participants).
DROPPED = "a participant who did not do every condition (in every task the test reads) is named and left out."


def scan_sessions(
    folder: str | os.PathLike[str], include_interrupted: bool = False, include_damaged: bool = False
) -> tuple[list[tuple[pd.DataFrame, dict[str, Any]]], pd.DataFrame]:
    """The analysable eating-task sessions in ``folder`` (``(rows, sidecar)`` pairs, by name) and the table
    ``session``, ``reason`` (:data:`LEFT_OUT`) of those left out; ``include_damaged`` keeps a damaged log's
    rows that parse. ArtifactError if two kept sessions log one participant, condition and task."""
    logs, left_out = [], []
    seen: dict[tuple[str, str, str], str] = {}
    for sidecar in sorted(Path(folder).glob("*.json")):
        try:
            frame, meta = read_session(sidecar, allow_damaged=include_damaged)
        except ArtifactError as exc:
            left_out.append((sidecar.stem, f"{LEFT_OUT['damaged']} ({exc})"))
            continue
        key = (str(meta.get("participant")), str(meta.get("condition")), str(meta.get("task")))
        if meta.get("task") not in ("Entree", "Dessert") or meta.get("condition") not in CONDITIONS:
            left_out.append((sidecar.stem, f"{LEFT_OUT['task']} (task {meta.get('task')!r})"))
        elif meta["status"] != "complete" and not include_interrupted:
            left_out.append((sidecar.stem, f"{LEFT_OUT['status']} ({meta['status']})"))
        elif (flag := disconnected_flag(*disconnected(frame, meta))) is not None:
            left_out.append((sidecar.stem, f"{LEFT_OUT['disconnected']} ({flag})"))
        elif key in seen:
            raise ArtifactError(
                f"sessions {seen[key]} and {sidecar.name} in {folder} both log participant {key[0]}, "
                f"condition {key[1]}, task {key[2]}: move one of them out of the folder"
            )
        else:
            seen[key] = sidecar.name
            logs.append((frame, {**meta, "session": sidecar.name}))
    return logs, pd.DataFrame(left_out, columns=["session", "reason"])


def load_sessions(
    folder: str | os.PathLike[str],
    task: object,
    include_interrupted: bool = False,
    include_damaged: bool = False,
) -> Episodes:
    """The eating-task sessions in ``folder`` (:func:`scan_sessions`, each left out named in a
    warning) as :class:`lasa.world.record.Episodes`; an ArtifactError if none is sound."""
    return _episodes(folder, task, "load_sessions", include_interrupted, include_damaged)[0]


def _episodes(
    folder: str | os.PathLike[str], task: Any, caller: str, *flags: bool
) -> tuple[Episodes, pd.DataFrame, float]:
    """The sessions :func:`scan_sessions` keeps (``flags``: its own), those left out (each in a warning)
    and the shortest trial limit among those kept [s] (:func:`session_limit`)."""
    import mujoco

    from lasa.world.eating import EatingTask

    if not isinstance(task, EatingTask):
        raise ConfigError(f"{caller} reads eating-task sessions; pass lasa.world.eating.make_eating_task()")
    logs, left_out = scan_sessions(folder, *flags)
    for row in left_out.itertuples():
        warnings.warn(f"left out session {row.session}: {row.reason}", stacklevel=3)
    if not logs:
        why = "; ".join(f"{r.session}: {r.reason}" for r in left_out.itertuples())
        raise ArtifactError(
            f"no sound eating-task session in {folder}" + (f" (left out: {why})" if why else "")
        )
    robot, metas = task.robot, [m for _, m in logs]
    n, horizon = robot.n_joints, max(len(f) for f, _ in logs)
    states = np.empty((horizon + 1, len(logs), n))
    phase = np.zeros((horizon + 1, len(logs)), dtype=int)
    idle = np.zeros((horizon, len(logs)), dtype=bool)
    switch = np.zeros((horizon, len(logs)), dtype=bool)
    end = np.array([len(f) for f, _ in logs], dtype=int)
    for e, (frame, meta) in enumerate(logs):
        held = np.minimum(np.arange(horizon + 1), len(frame))  # each step's row, the last held after the end
        states[:, e] = np.concatenate([task.start[None], frame[[f"s{i}" for i in range(n)]].to_numpy()])[held]
        phase[:, e] = np.concatenate([[0], frame.phase.to_numpy()])[held]
        moved = (frame[["z0", "z1"]].to_numpy() != 0).any(axis=1)
        # a mode press is input in Retargeting (it switches modes) and nothing in latent actions
        pressed = (frame.mode_press.to_numpy() > 0) & (
            parse_condition(str(meta["condition"])).interface == "R"
        )
        stopped = frame.stop.to_numpy() > 0
        idle[: len(frame), e] = ~moved & ~pressed & ~stopped
        switch[: len(frame), e] = pressed & ~stopped
    tip, direction, _, _ = tip_frames(robot, mujoco.MjData(robot.model), states.reshape(-1, n))
    conditions = np.array([m["condition"] for m in metas])
    assisted = np.array([parse_condition(str(c)).assisted for c in conditions], dtype=bool)
    members = np.array([m.get("control", {}).get("assistance", "hindsight") for m in metas])
    episodes = Episodes(
        participant=np.array([m["participant"] for m in metas]),
        condition=conditions,
        assistance=np.where(assisted, members, NO_ASSISTANCE),
        task=np.array([m["task"] for m in metas]),
        # the condition's position in the participant's schedule, as the web study records it (0
        # where a session does not say: the terminal's `teleop run`)
        order=np.array([int(m.get("order", 0)) for m in metas], dtype=int),
        states=states,
        tip=tip.reshape(horizon + 1, len(logs), 3),
        direction=direction.reshape(horizon + 1, len(logs), 3),
        phase=phase,
        idle=idle,
        switch=switch,
        end=end,
        completed=np.array([bool(m.get("done", False)) for m in metas]),
        dt=float(metas[0]["dt"]),
    )
    return episodes, left_out, min(session_limit(m) for m in metas)


def likert_tests(answers: pd.DataFrame) -> pd.DataFrame:
    """Fig. dessert (right): on each scale, LA+SA against each other condition (paired t, Holm)."""
    from lasa.evidence import stats

    out = []
    for scale, part in answers.groupby("scale", sort=False):
        frame = part.assign(task="survey").rename(columns={"answer": "value"})
        pairs = [("LA+SA", c) for c in CONDITIONS if c != "LA+SA" and c in set(frame.condition)]
        out.append(stats.pairwise(frame, "value", pairs=pairs).assign(scale=scale))
    return pd.concat(out, ignore_index=True)


def tlx_tests(ratings: pd.DataFrame) -> pd.DataFrame:
    """The raw TLX and each subscale: LA+SA against each other condition, as :func:`likert_tests` (paired t,
    Holm); ``scale`` names the subscale (``raw``: the mean of the six)."""
    return likert_tests(ratings.rename(columns={"subscale": "scale", "value": "answer"}))


def complete_participants(
    frame: pd.DataFrame, test: str, by_task: bool = True
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rows of the participants who did every condition (in every task, if ``by_task``), and the
    table ``participant``, ``test``, ``reason`` of those dropped: named, never silently lost."""
    tasks = sorted(set(frame.task)) if by_task else [None]
    dropped = []
    for participant, part in frame.groupby("participant", sort=True):
        tags = part.task if by_task else [None] * len(part)
        done = set(zip(part.condition, tags, strict=True))
        missing = [
            c + ("" if t is None else f" in {t}") for t in tasks for c in CONDITIONS if (c, t) not in done
        ]
        if missing:
            dropped.append((participant, test, "missing " + ", ".join(missing)))
    table = pd.DataFrame(dropped, columns=["participant", "test", "reason"])
    return frame[~frame.participant.isin(table.participant)], table


def analyse_sessions(folder: str | os.PathLike[str], task: Any) -> dict[str, pd.DataFrame]:
    """People's sessions through the simulated cohort's measures and statistics: the tidy measure tables,
    ``means`` per condition, ``sa_effect``, ``time_tests``, ``likert`` and ``tlx`` (over participants who
    did every condition; ``tlx`` when ``tlx.csv`` is there), ``demographics`` (counts, when
    ``demographics.csv`` is there), ``left_out``, ``dropped`` and ``limit`` (one row: ``limit_s``, the
    shortest trial limit of the sessions read, H3's horizon in
    :func:`lasa.evidence.hypotheses.people_claims`)."""
    from lasa.evidence import stats
    from lasa.world.measures import measures

    episodes, left_out, limit_s = _episodes(folder, task, "analyse_sessions")
    frames = measures(task, episodes)
    out = {**frames, "left_out": left_out, "limit": pd.DataFrame({"limit_s": [limit_s]})}
    out["means"] = (
        frames["time"]
        .merge(frames["goal_error"], on=["robot", "participant", "condition", "assistance", "task", "order"])
        .groupby("condition")[["total_time", "idle_time", "mode_switches", "goal_error", "mean_distance"]]
        .mean()
        .reset_index()
    )
    err, dropped = complete_participants(frames["goal_error"], "sa_effect, time_tests")
    if err.participant.nunique() >= 2:
        rows = [stats.sa_effect_within(err, m) | {"measure": m} for m in ("goal_error", "mean_distance")]
        out["sa_effect"] = pd.DataFrame(rows)
        others = [("LA+SA", c) for c in CONDITIONS if c != "LA+SA"]
        time = frames["time"][frames["time"].participant.isin(set(err.participant))]
        out["time_tests"] = pd.concat(
            [
                stats.pairwise(time, m, agg="sum", pairs=others).assign(measure=m)
                for m in ("total_time", "idle_time")
            ],
            ignore_index=True,
        )
    # each questionnaire's paired tests, over those who answered after every condition
    for name, answers, tests in (
        ("likert", read_likert(folder), likert_tests),
        ("tlx", read_tlx(folder), tlx_tests),
    ):
        if answers is None:
            continue
        answers, left = complete_participants(answers, name, by_task=False)
        dropped = pd.concat([dropped, left], ignore_index=True)
        if answers.participant.nunique() >= 2:
            out[name] = tests(answers)
    demographics = read_demographics(folder)
    if demographics is not None:
        out["demographics"] = demographics_counts(demographics)
    out["dropped"] = dropped
    for row in dropped.itertuples():
        warnings.warn(f"left out participant {row.participant} from {row.test}: {row.reason}", stacklevel=2)
    return out


def write_session_tables(tables: dict[str, pd.DataFrame], folder: str | os.PathLike[str]) -> list[Path]:
    """Write one analysis's tables as ``<folder>/sessions_<name>.csv`` (the paths, in order), replacing the
    previous set whole: staged first, so the folder never mixes two analyses and a failure keeps the old."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    with locked(folder):
        with tempfile.TemporaryDirectory(
            prefix=".sessions.", dir=folder, ignore_cleanup_errors=True
        ) as stage:
            for name, table in tables.items():
                table.to_csv(Path(stage, f"sessions_{name}.csv"), index=False, float_format="%.6g")
            for old in folder.glob("sessions_*.csv"):
                old.unlink()
            paths = [folder / f"sessions_{name}.csv" for name in tables]
            for path in paths:
                os.replace(Path(stage, path.name), path)
    return paths
