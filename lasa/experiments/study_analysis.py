"""Beside the study's claims: completion, the headline participant model, mode switches, stuck episodes.

:func:`completion` gives the share of episodes finished within the horizon per reading, and
:func:`headline_model` picks the headline participant model by it (a criterion fixed before any
verdict). :func:`switch_share` is Retargeting's mode-switch share of time, against Herlant et
al. 2016's 17.4% (:data:`HERLANT_SHARE`); :func:`stuck` says where the unfinished LA episodes
were and what the decoder offered there, :func:`stuck_summary` groups them;
:func:`stuck_episodes` and :func:`switch_shares` run them over every reading, and
:func:`break_even` is the cost per mode switch that would make Retargeting as slow as LA+SA.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import mujoco
import numpy as np
import pandas as pd
from scipy import stats as sps

from lasa.base.config import NO_ASSISTANCE
from lasa.base.errors import ConfigError
from lasa.evidence.rules import COMPLETION_BAR
from lasa.experiments.study import PAPER_N, Config, for_member
from lasa.method.decoder import ActionDecoder
from lasa.method.step import decode_candidates, latent_grid
from lasa.people.policy import progress_gain
from lasa.world.eating import GOALS, TASK_NAMES, TASKS, EatingTask, fork_frame, waypoints
from lasa.world.fork import tip_frames, tip_motion
from lasa.world.record import Episodes

__all__ = [
    "HERLANT_SHARE",
    "STUCK_COLUMNS",
    "completion",
    "headline_model",
    "switch_share",
    "switch_shares",
    "stuck",
    "stuck_episodes",
    "stuck_summary",
    "break_even",
    "completion_sentence",
    "switch_sentence",
]

HERLANT_SHARE = 0.174  # mode switching's share of execution time, JACO + joystick (Herlant et al. 2016) [-]
STUCK_COLUMNS = (
    "participant",
    "condition",
    "assistance",
    "task",
    "phase",
    "goal",
    "distance_cm",
    "angle_deg",
    "belief_goal",
    "believed",
    "best_progress",
    "inputs_progressing",
)


def completion(time: pd.DataFrame) -> pd.DataFrame:
    """Share of episodes finished within the horizon, per model, decoder reading, SA member and condition."""
    keys = [k for k in ("model", "decoder", "assistance", "condition") if k in time.columns]
    return (
        time.groupby(keys, sort=False)
        .agg(
            episodes=("completed", "size"), finished=("completed", "mean"), total_time=("total_time", "mean")
        )
        .reset_index()
    )


def headline_model(time: pd.DataFrame, models: tuple[str, ...]) -> str:
    """The headline participant model, by a criterion fixed before any H1-H3 verdict of 0.10 was seen.

    The paper's people "practised up to 5 minutes per condition" and held the stick, which
    the planning model does and the one-step model does not: ``models`` lists them in that
    order of preference. A model stands in for people only if it can do what the paper's
    people did with the interface that does not depend on the decoder: the first model whose
    Retargeting episodes (R, and R+SA under every member) each finish at least
    :data:`lasa.evidence.rules.COMPLETION_BAR` of the time is the headline; if none does,
    the first of ``models``.

    Args:
        time: The study's time table (:func:`lasa.experiments.study.run`), with its ``model`` column.
        models: The participant models, in order of preference.
    """
    if not models:
        raise ConfigError("headline_model needs at least one participant model")
    retarget = time[time.condition.isin(["R", "R+SA"])]
    for model in models:
        done = retarget[retarget.model == model].groupby(["condition", "assistance"]).completed.mean()
        if len(done) and (done >= COMPLETION_BAR).all():
            return model
    return models[0]


def switch_share(time: pd.DataFrame, dt: float, n: int | None = None) -> pd.DataFrame:
    """Retargeting's mode-switch share of execution time, per condition and SA member.

    Each participant's time spent pressing the mode button (one control step, ``dt``, per
    switch) over their Total Time, summed over both tasks; the mean over participants and
    its 95% t-interval. Herlant, Holladay & Srinivasa (HRI 2016) measured 17.4% for
    able-bodied users of a JACO arm with a joystick.
    """
    rows = time[time.condition.isin(["R", "R+SA"])]
    if n is not None:
        rows = rows[rows.participant < n]
    out = []
    for (cond, assistance), part in rows.groupby(["condition", "assistance"], sort=False):
        per = part.groupby("participant")[["mode_switches", "total_time"]].sum()
        share = per.mode_switches * dt / per.total_time
        sem = float(sps.sem(share)) if len(share) > 1 else np.nan
        ci = (
            (share.mean(),) * 2
            if sem == 0
            else sps.t.interval(0.95, len(share) - 1, loc=share.mean(), scale=sem)
        )
        out.append(
            {
                "condition": cond,
                "assistance": assistance,
                "participants": len(share),
                "switch_share": float(share.mean()),
                "ci_low": float(ci[0]),
                "ci_high": float(ci[1]),
                "switches_per_task": float(part.mode_switches.mean()),
                "herlant_2016": HERLANT_SHARE,
            }
        )
    return pd.DataFrame(out)


def switch_shares(time: pd.DataFrame, dt: float, models: Sequence[str]) -> pd.DataFrame:
    """:func:`switch_share` of each participant model, for the first :data:`~lasa.experiments.study.PAPER_N`
    participants and for the cohort; columns ``model`` and ``participants_of`` (``first 10``, ``cohort``)
    added, one block per model in the order of ``models``."""
    parts = [("first 10", time[time.participant < PAPER_N]), ("cohort", time)]
    return pd.concat(
        [
            switch_share(for_n[for_n.model == m], dt).assign(model=m, participants_of=label)
            for m in models
            for label, for_n in parts
        ],
        ignore_index=True,
    )


def stuck(
    task: EatingTask,
    episodes: Episodes,
    decoder: ActionDecoder,
    config: Config,
) -> pd.DataFrame:
    """Why the unfinished LA episodes did not finish: where they were, and what the decoder offered there.

    One row per unfinished LA episode: the phase and goal of the waypoint it was working
    towards, the tip's distance to it [cm] and the angle to its direction [deg] at the
    horizon, the belief in that goal, the goal the belief favoured, and, at that final
    state and belief, the best progress any of the participant's stick inputs makes towards
    the waypoint (in best-step units; the participant rests below the idle threshold, 0.1)
    and the share of inputs that make any progress.
    """
    if episodes.belief is None or episodes.waypoint is None:
        raise ConfigError("stuck needs simulated episodes (with beliefs and waypoints logged)")
    settings = config.session
    pc = settings.participant
    la = np.char.startswith(episodes.condition.astype(str), "LA") & ~episodes.completed
    idx = np.flatnonzero(la)
    if not len(idx):
        return pd.DataFrame(columns=STUCK_COLUMNS)
    robot, dt = task.robot, episodes.dt
    plans = {name: waypoints(name) for name in TASK_NAMES}
    wps = [plans[str(episodes.task[e])][int(episodes.waypoint[e])] for e in idx]
    frames = [fork_frame(robot, wp.goal, wp.theta, wp.depth) for wp in wps]
    p_star = np.stack([f[0] for f in frames])
    d_star = np.stack([f[1][:, 2] for f in frames])
    s = episodes.states[-1, idx]
    b = episodes.belief[-1, idx]
    data = mujoco.MjData(robot.model)
    pos, axis, jp, jr = tip_frames(robot, data, s)
    grid = latent_grid(settings.n_z, 2)
    phi = decode_candidates(decoder, grid, s, b)
    dp, new_dir = tip_motion(jp, jr, axis, dt * phi)
    unit = dt * settings.retarget.linear_speed
    gain = progress_gain(pos, axis, dp, new_dir, p_star, d_star, pc.rotation_weight) / unit
    goal_names = np.asarray(GOALS)
    return pd.DataFrame(
        {
            "participant": episodes.participant[idx],
            "condition": episodes.condition[idx],
            "assistance": episodes.assistance[idx],
            "task": episodes.task[idx],
            "phase": [TASKS[str(episodes.task[e])][wp.phase].name for e, wp in zip(idx, wps, strict=True)],
            "goal": [GOALS[wp.goal] for wp in wps],
            "distance_cm": 100 * np.linalg.norm(pos - p_star, axis=1),
            "angle_deg": np.degrees(np.arccos(np.clip(np.einsum("ai,ai->a", axis, d_star), -1, 1))),
            "belief_goal": b[np.arange(len(idx)), [wp.goal for wp in wps]],
            "believed": goal_names[b.argmax(axis=1)],
            "best_progress": gain.max(axis=1),
            "inputs_progressing": (gain > 0).mean(axis=1),
        }
    )


def stuck_episodes(
    task: EatingTask,
    episodes: Mapping[str, Mapping[str, Episodes]],
    decoders: Mapping[str, ActionDecoder],
    config: Config,
    models: Sequence[str],
) -> pd.DataFrame:
    """:func:`stuck` over every participant model and decoder reading, with ``decoder`` and ``model`` columns.

    Args:
        task: The eating task.
        episodes: :func:`lasa.experiments.study.run`'s episodes, by model, then decoder reading.
        decoders: The decoder of each reading.
        config: The study's configuration.
        models: The participant models, in the order of the rows.
    """
    return pd.concat(
        [
            stuck(task, episodes[m][n], decoders[n], config).assign(decoder=n, model=m)
            for m in models
            for n in episodes[m]
        ],
        ignore_index=True,
    )


def break_even(time: pd.DataFrame, assistance: Sequence[str], decoder: str, model: str) -> pd.DataFrame:
    """The time per mode switch at which Retargeting would be as slow as LA+SA, per SA member.

    One row per member and Retargeting condition (R, and R+SA under that member), indexed
    ``(member, condition)``, for the headline decoder and participant model: the mean total
    time per task of R or R+SA and of LA+SA under the member [s], R's mode switches per task, and
    ``break-even cost per switch [s]``, the time gap divided by the switches.

    Args:
        time: :func:`lasa.experiments.study.run`'s time table.
        assistance: The SA members, the headline first.
        decoder: The headline decoder reading (the LA conditions' rows).
        model: The headline participant model.
    """
    head = for_member(time, assistance[0], decoder=decoder, model=model)
    others = time.assistance.isin(assistance[1:]) & time.decoder.isin([decoder, NO_ASSISTANCE])
    rows = pd.concat([head, time[others & (time.model == model)]])
    means = rows.groupby(["assistance", "condition"])[["total_time", "mode_switches"]].mean()
    gap = {}
    for sa in assistance:
        la_sa = means.loc[(sa, "LA+SA"), "total_time"]
        for cond, asst in (("R", NO_ASSISTANCE), ("R+SA", sa)):
            r = means.loc[(asst, cond)]
            gap[(sa, cond)] = {
                "R time [s]": r.total_time,
                "LA+SA time [s]": la_sa,
                "switches per task": r.mode_switches,
                "break-even cost per switch [s]": (la_sa - r.total_time) / max(r.mode_switches, 1e-9),
            }
    return pd.DataFrame(gap).T


def stuck_summary(stuck_rows: pd.DataFrame) -> pd.DataFrame:
    """:func:`stuck`'s rows (with ``decoder``, and ``model`` if any) grouped by where they stopped.

    Medians per group.
    """
    keys = ["model"] * ("model" in stuck_rows.columns) + [
        "decoder",
        "condition",
        "assistance",
        "task",
        "phase",
        "goal",
    ]
    medians = ("distance_cm", "angle_deg", "belief_goal", "best_progress", "inputs_progressing")
    return stuck_rows.groupby(keys).agg(
        episodes=("participant", "size"), **{m: (m, "median") for m in medians}
    )


def _pct(x: float) -> str:
    return f"{100 * x:.3g}%"


def completion_sentence(done: pd.DataFrame, model: str, decoder: str, assistance: str) -> str:
    """The share of episodes each condition finishes under one model, decoder and SA member, in words.

    Args:
        done: :func:`completion`'s table (its ``episodes`` count the episodes of every participant run).
        model: The participant model.
        decoder: The decoder reading of the LA conditions (Retargeting's rows have none).
        assistance: The SA member of the +SA conditions.
    """
    rows = done[(done.model == model) & done.decoder.isin([decoder, "none"])]
    rows = rows[rows.assistance.isin([assistance, NO_ASSISTANCE])].set_index("condition")
    if rows.empty:
        raise ConfigError(f"no completion rows for {model!r}, decoder {decoder!r}, member {assistance!r}")
    parts = ", ".join(f"{c} {_pct(rows.finished[c])}" for c in rows.index)
    below = [c for c in rows.index if rows.finished[c] < COMPLETION_BAR]
    verdict = (
        f"{', '.join(below)} below the {_pct(COMPLETION_BAR)} that H1 and H3 need"
        if below
        else f"every condition at or above the {_pct(COMPLETION_BAR)} that H1 and H3 need"
    )
    episodes = int(rows.episodes.max())
    return f"{model} participants, `{decoder}`, {episodes} episodes per condition: {parts}; {verdict}."


def switch_sentence(
    shares: pd.DataFrame, model: str, assistance: str, participants_of: str = "cohort"
) -> str:
    """Retargeting's mode-switch share (:func:`switch_shares`) of a model against Herlant et al.'s, in words.

    R's share, and R+SA's under the SA member ``assistance``; each "below", "above" or "about"
    Herlant et al.'s 17.4% by whether its 95% interval lies below, above or around it.
    """
    rows = shares[(shares.model == model) & (shares.participants_of == participants_of)]
    rows = rows[rows.assistance.isin([NO_ASSISTANCE, assistance])]
    if rows.empty:
        raise ConfigError(f"no mode-switch rows for model {model!r} ({participants_of})")
    said = " and ".join(
        f"{_pct(r.switch_share)} [{_pct(r.ci_low)}, {_pct(r.ci_high)}] ({r.condition})"
        for r in rows.itertuples()
    )
    side = [
        "below" if r.ci_high < HERLANT_SHARE else "above" if r.ci_low > HERLANT_SHARE else "about"
        for r in rows.itertuples()
    ]
    where = side[0] if len(set(side)) == 1 else "partly " + " and partly ".join(dict.fromkeys(side))
    return (
        f"{model} participants ({participants_of}) switch modes {said} of their time: {where} "
        f"Herlant et al.'s {_pct(HERLANT_SHARE)}."
    )
