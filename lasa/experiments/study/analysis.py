"""Beside the study's claims: completion, the headline participant model, mode switches, stuck episodes,
and the cost per mode switch at which Retargeting would be as slow as LA+SA."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import mujoco
import numpy as np
import pandas as pd
from scipy import stats as sps

from lasa.base.config import NO_ASSISTANCE
from lasa.base.errors import ConfigError
from lasa.evidence.hypotheses import for_member
from lasa.evidence.rules import COMPLETION_BAR
from lasa.experiments.study.run import PAPER_N, Config
from lasa.method.decoder import ActionDecoder
from lasa.method.step import decode_candidates, latent_grid
from lasa.people.policy import progress_gain
from lasa.world.eating import GOALS, TASK_NAMES, TASKS, EatingTask, fork_frame, waypoints
from lasa.world.fork import tip_frames, tip_motion
from lasa.world.record import Episodes

HERLANT_SHARE = 0.174  # mode switching's share of execution time, JACO + joystick (Herlant et al. 2016) [-]
STUCK_COLUMNS = tuple(
    "participant condition assistance task phase goal distance_cm angle_deg belief_goal believed "
    "best_progress inputs_progressing".split()
)


def completion(time: pd.DataFrame) -> pd.DataFrame:
    """Share of episodes finished within the horizon, per model, decoder variant, SA member and condition."""
    keys = [k for k in ("model", "decoder", "assistance", "condition") if k in time.columns]
    return (
        time.groupby(keys, sort=False)
        .agg(
            episodes=("completed", "size"), finished=("completed", "mean"), total_time=("total_time", "mean")
        )
        .reset_index()
    )


def switch_share(time: pd.DataFrame, dt: float, n: int | None = None) -> pd.DataFrame:
    """Retargeting's mode-switch share of execution time (a switch a step, ``dt``) per condition and SA
    member: the participants' mean with its 95% t-interval, beside Herlant et al.'s (HRI 2016) 17.4%."""
    rows = time[time.condition.isin(["R", "R+SA"])]
    if n is not None:
        rows = rows[rows.participant < n]
    out = []
    for (cond, assistance), part in rows.groupby(["condition", "assistance"], sort=False):
        per = part.groupby("participant")[["mode_switches", "total_time"]].sum()
        share = per.mode_switches * dt / per.total_time
        sem = float(sps.sem(share)) if len(share) > 1 else np.nan
        mean = share.mean()
        ci = (mean,) * 2 if sem == 0 else sps.t.interval(0.95, len(share) - 1, loc=mean, scale=sem)
        who = {"condition": cond, "assistance": assistance, "participants": len(share)}
        shares = {"switch_share": float(mean), "ci_low": float(ci[0]), "ci_high": float(ci[1])}
        extra = {"switches_per_task": float(part.mode_switches.mean()), "herlant_2016": HERLANT_SHARE}
        out.append(who | shares | extra)
    return pd.DataFrame(out)


def switch_shares(time: pd.DataFrame, dt: float, models: Sequence[str]) -> pd.DataFrame:
    """:func:`switch_share` of each model (``model``), first 10 and cohort (``participants_of``)."""
    shares = (
        switch_share(time[time.model == m], dt, n).assign(model=m, participants_of=label)
        for m in models
        for label, n in (("first 10", PAPER_N), ("cohort", None))
    )
    return pd.concat(shares, ignore_index=True)


def stuck(task: EatingTask, episodes: Episodes, decoder: ActionDecoder, config: Config) -> pd.DataFrame:
    """Per unfinished LA episode: its waypoint, the tip's distance [cm] and angle [deg] to it at the horizon,
    the belief, and there the best progress any stick input makes (in best-step units; the participant
    rests below 0.1) and the share of inputs that make any."""
    if episodes.belief is None or episodes.waypoint is None:
        raise ConfigError("stuck needs simulated episodes (with beliefs and waypoints logged)")
    settings = config.session
    la = np.char.startswith(episodes.condition.astype(str), "LA") & ~episodes.completed
    idx = np.flatnonzero(la)
    if not len(idx):
        return pd.DataFrame(columns=STUCK_COLUMNS)
    robot, dt = task.robot, episodes.dt
    plans = {name: waypoints(name) for name in TASK_NAMES}
    wps = [plans[str(episodes.task[e])][int(episodes.waypoint[e])] for e in idx]
    frames = [fork_frame(robot, wp.goal, wp.theta, wp.depth) for wp in wps]
    p_star, d_star = np.stack([f[0] for f in frames]), np.stack([f[1][:, 2] for f in frames])
    s, b = episodes.states[-1, idx], episodes.belief[-1, idx]
    data = mujoco.MjData(robot.model)
    pos, axis, jp, jr = tip_frames(robot, data, s)
    grid = latent_grid(settings.n_z, 2)
    phi = decode_candidates(decoder, grid, s, b)
    dp, new_dir = tip_motion(jp, jr, axis, dt * phi)
    unit = dt * settings.retarget.linear_speed
    gain = progress_gain(pos, axis, dp, new_dir, p_star, d_star, settings.participant.rotation_weight) / unit
    goal_names = np.asarray(GOALS)
    who = {c: getattr(episodes, c)[idx] for c in ("participant", "condition", "assistance", "task")}
    return pd.DataFrame(
        {
            **who,
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
    """:func:`stuck` over every participant model of ``models`` and decoder variant of ``episodes``."""
    rows = (
        stuck(task, episodes[m][n], decoders[n], config).assign(decoder=n, model=m)
        for m in models
        for n in episodes[m]
    )
    return pd.concat(rows, ignore_index=True)


def break_even(time: pd.DataFrame, assistance: Sequence[str], decoder: str, model: str) -> pd.DataFrame:
    """Per SA member, R's and R+SA's time per mode switch at which they would be as slow as LA+SA."""
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
    """:func:`stuck`'s rows (with ``decoder``, and ``model`` if any) by where they stopped: medians."""
    where = ["decoder", "condition", "assistance", "task", "phase", "goal"]
    keys = ["model"] * ("model" in stuck_rows.columns) + where
    medians = ("distance_cm", "angle_deg", "belief_goal", "best_progress", "inputs_progressing")
    return stuck_rows.groupby(keys).agg(
        episodes=("participant", "size"), **{m: (m, "median") for m in medians}
    )


def pct(x: float) -> str:
    """A share as a percentage to 3 significant digits: ``0.25`` -> ``25%``."""
    return f"{100 * x:.3g}%"


def completion_sentence(done: pd.DataFrame, model: str, decoder: str, assistance: str) -> str:
    """The share of episodes each condition finishes (:func:`completion`) for a model, decoder and member."""
    rows = done[(done.model == model) & done.decoder.isin([decoder, "none"])]
    rows = rows[rows.assistance.isin([assistance, NO_ASSISTANCE])].set_index("condition")
    if rows.empty:
        raise ConfigError(f"no completion rows for {model!r}, decoder {decoder!r}, member {assistance!r}")
    parts = ", ".join(f"{c} {pct(rows.finished[c])}" for c in rows.index)
    below = [c for c in rows.index if rows.finished[c] < COMPLETION_BAR]
    where = f"{', '.join(below)} below" if below else "every condition at or above"
    verdict = f"{where} the {pct(COMPLETION_BAR)} that H1 and H3 need"
    episodes = int(rows.episodes.max())
    return f"{model} participants, `{decoder}`, {episodes} episodes per condition: {parts}; {verdict}."


def switch_sentence(
    shares: pd.DataFrame, model: str, assistance: str, participants_of: str = "cohort"
) -> str:
    """R's and R+SA's mode-switch share (:func:`switch_shares`) against Herlant et al.'s 17.4%, in words."""
    rows = shares[(shares.model == model) & (shares.participants_of == participants_of)]
    rows = rows[rows.assistance.isin([NO_ASSISTANCE, assistance])]
    if rows.empty:
        raise ConfigError(f"no mode-switch rows for model {model!r} ({participants_of})")
    said = " and ".join(
        f"{pct(r.switch_share)} [{pct(r.ci_low)}, {pct(r.ci_high)}] ({r.condition})"
        for r in rows.itertuples()
    )
    side = [
        "below" if r.ci_high < HERLANT_SHARE else "above" if r.ci_low > HERLANT_SHARE else "about"
        for r in rows.itertuples()
    ]
    where = side[0] if len(set(side)) == 1 else "partly " + " and partly ".join(dict.fromkeys(side))
    return (
        f"{model} participants ({participants_of}) switch modes {said} of their time: {where} "
        f"Herlant et al.'s {pct(HERLANT_SHARE)}."
    )
