r"""The eating study (notebook 11): Figs. error, time and dessert (left), and claims H1-H3.

A cohort of simulated participants (:mod:`lasa.people.cohort`) does both eating tasks under R,
R+SA, LA and LA+SA. The first ten are the paper's study size; the whole cohort is the
larger one. Three tidy tables come out, one row per participant x condition x task (x
phase), each with its figure:

- ``study_goal_error``: Goal Error (Fig. error);
- ``study_time``: Total and Idle Time (Fig. time), with mode switches and completion;
- ``study_alignment``: Preference Alignment per phase (Fig. dessert, left panel).

Each participant model of ``Config.participant_models`` (:data:`PARTICIPANT_MODELS`: ``planning``,
who plans over held inputs, the headline once :mod:`lasa.people.planning` exists, and ``one_step``,
:func:`lasa.people.participants.simulate`) runs the whole study; the tables' ``model`` column says
which. The assisted conditions run under each member of ``Config.members`` (hindsight
optimisation, the paper's study, first: the headline), the unassisted ones once
(``assistance`` is ``none`` for them). The LA conditions run under every decoder reading of
notebook 10 (:func:`run`; the headline, chosen there by the property alone, first), and the
tables' ``decoder`` column says which. The statistics are :mod:`lasa.evidence.stats`'s. Beside the
claims: :func:`completion` (episodes finished within the horizon), :func:`stuck` (where the
unfinished LA episodes were, and what the decoder offered there) and :func:`switch_share`
(Retargeting's mode-switch share of time, against Herlant et al. 2016's 17.4%).

**The claims and their rules.** They follow the paper's own tests and significance
level (p < .05), in the direction the paper reports; they were written after pilot runs
of 4 and 10 participants had been seen (the study was new). One reading was added after
the paper-scale run had been seen: ``study.h1_mean_distance``, because that run showed the
summed Goal Error tracking the time taken; it is reported beside the paper's measure, not
instead of it, and no rule was changed. Each is judged for the first 10 participants and for
the whole cohort, under each member.

- **H1** (``study.h1``), SA lowers Goal Error: *yes* if the within-subjects SA main
  effect (2x2 repeated-measures ANOVA, F(1, N-1)) is significant with lower error under SA
  and both pairwise comparisons (LA+SA < LA, R+SA < R; paired t-tests, Holm over the two)
  are significant too; *partly* if the main effect is but not both comparisons; *no*
  otherwise. ``study.h1_mean_distance`` applies the same rule to the mean distance (Goal
  Error divided by the task's time): a sum over the task also grows with the time taken, so
  a slower condition accrues more of it at the same distance. ``study.h1_paper_test``
  applies the same direction-and-significance rule to the paper's reading of F(1,18): a
  between-subjects one-way ANOVA on the 2N participant means with and without SA (which
  ignores that they come from the same people).
- **H2** (``study.h2``), LA lets users execute their preferences: in Dessert's scoop phase,
  the one where the preference changes, Preference Alignment is higher with LA+SA than
  with R+SA (paired t-test over the participants who reached that phase under both):
  *yes* if significant, *partly* if higher but not significant, *no* otherwise (also when
  fewer than two participants reached it under both).
- **H3** (``study.h3``), LA+SA is the most efficient: an episode not finished within the
  horizon has its time cut there (censored), so H3 is *not testable* when any of the four
  conditions finishes fewer than 95% of its episodes (among the participants analysed; the
  row names each such condition and its completion). Otherwise each participant's
  restricted time, ``min(T, horizon)`` summed over the two tasks, of LA+SA minus each other
  condition, Total and Idle Time, with a paired bootstrap over participants (10,000
  resamples, percentile 95% intervals, seeded): *yes* if all six intervals lie below 0,
  *partly* if LA+SA has the lowest restricted mean Total Time but not all six do, *no*
  otherwise; settled when the interval of LA+SA minus the fastest other condition's Total
  Time excludes 0. This test replaced paired t-tests on the capped times after the previous
  version's results were seen, because they were censored (``AFTER_RESULTS``).

**Not testable.** ``claims(untestable=...)`` marks every row ``not testable`` with the reason in
its note (e.g. no decoder has both halves of the property, :func:`untestable_reason`), and
``untestable_decoders`` does so per decoder reading; ``measured`` still shows the tests' numbers.

Each claim has one row per reading: ``study.<claim>`` is the paper's (its measure, hindsight
optimisation, 10 participants, the headline decoder, the headline participant model), and
``study.<claim>@<reading>`` each other (:func:`claim_id`: measure, decoder, participant model,
member, cohort, joined by ``+``, e.g. ``study.h2@transfers_entropy+one_step``); every other
decoder reading is judged on H1-H3 under the paper's measures and hindsight optimisation, and
every other participant model as the headline one.
A verdict is settled when the 95% interval of its effect (H1, H2: the t-interval; H3: the
bootstrap's) excludes zero, else ``undecided``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping

import matplotlib.patches as mpatches
import matplotlib.pyplot as plt
import mujoco
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.figure import Figure
from scipy import stats as sps

from lasa.base.conditions import CONDITIONS
from lasa.base.config import (
    ASSISTANCE,
    NO_ASSISTANCE,
    AtLeastTwo,
    ControlConfig,
    Integer,
    PositiveInt,
    check_choice,
    from_dict,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.evidence import latent_property, stats
from lasa.evidence.claims import Claim
from lasa.evidence.plots import wrap_to
from lasa.evidence.rules import NOT_TESTABLE, UNDECIDED, rule
from lasa.method.decoder import ActionDecoder
from lasa.method.step import decode_candidates, latent_grid
from lasa.people import participants, planning
from lasa.people.cohort import ParticipantConfig, draw_cohort
from lasa.people.design import TASK_NAMES, Episodes, StudyConfig, interface_of
from lasa.people.kinematics import tip_frames, tip_motion
from lasa.people.measures import measures
from lasa.people.policy import progress_gain
from lasa.world.eating import GOALS, TASKS, EatingTask, fork_frame, waypoints

__all__ = [
    "Config",
    "FigureSpec",
    "GOAL_ERROR",
    "TIME",
    "ALIGNMENT",
    "PAPER_N",
    "COMPLETION_BAR",
    "PARTICIPANT_MODELS",
    "Simulate",
    "run",
    "for_member",
    "completion",
    "headline_model",
    "switch_share",
    "stuck",
    "stuck_summary",
    "readings_table",
    "HERLANT_SHARE",
    "analyse",
    "claims",
    "claim_id",
    "untestable_reason",
    "plot_goal_error",
    "plot_time",
    "plot_alignment",
]

PAPER_N = 10  # the paper's participants
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
COMPLETION_BAR = 0.95  # H3 compares times only if every condition finishes this share of its episodes [-]
Simulate = Callable[..., Episodes]  # lasa.people.participants.simulate's signature and return type


# participant model name -> its simulate (the signature of lasa.people.participants.simulate);
# the headline first. A model of your own: add it here before building the Config that names it.
PARTICIPANT_MODELS: dict[str, Simulate] = {"planning": planning.simulate, "one_step": participants.simulate}


PALETTE = {"R": "#8c8c8c", "R+SA": "#4c72b0", "LA": "#dd8452", "LA+SA": "#55a868"}


@dataclasses.dataclass(frozen=True)
class Config:
    """The simulated study (notebook 11); the participants' parameters are ``participant``."""

    n_participants: AtLeastTwo = 40  # the larger cohort; its first 10 are the paper-sized study [-]
    members: tuple[str, ...] = ("hindsight", "grasp_set")  # SA readings; the first is the headline [-]
    horizon: PositiveInt = 1500  # steps allowed per task (150 s) [-]
    seed: Integer = 0  # seed of the cohort and of the participants' choices [-]
    video_participant: int = 0  # whose Dessert the video shows [-]
    participant: dict[str, float] = dataclasses.field(default_factory=dict)  # ParticipantConfig overrides
    # participant models (PARTICIPANT_MODELS); the first is the headline [-]
    participant_models: tuple[str, ...] = ("planning", "one_step")
    # decoder readings a model runs, the headline and the next ones in notebook 10's ranking (a
    # model not named runs every reading): a planning study costs ~5x a one-step one per reading
    readings_per_model: dict[str, PositiveInt] = dataclasses.field(default_factory=lambda: {"planning": 4})

    def __post_init__(self) -> None:
        validate(self)
        object.__setattr__(self, "members", tuple(self.members))
        object.__setattr__(self, "participant_models", tuple(self.participant_models))
        for name in self.members:
            check_choice("assistance", name, ASSISTANCE)
        models = self.participant_models
        if not models or len(set(models)) != len(models):
            raise ConfigError(f"participant_models must be non-empty and without repeats, got {models}")
        for name in models:
            check_choice("participant model", name, tuple(PARTICIPANT_MODELS))
        for name in self.readings_per_model:
            check_choice("readings_per_model's participant model", name, tuple(PARTICIPANT_MODELS))
        if not 0 <= self.video_participant < self.n_participants:
            raise ConfigError(
                f"video_participant must be in [0, {self.n_participants}), got {self.video_participant}"
            )

    def study(self) -> StudyConfig:
        """The session settings for :func:`lasa.people.participants.simulate`."""
        return StudyConfig(
            horizon=self.horizon,
            members=self.members,
            participant=from_dict(ParticipantConfig, self.participant),
        )


@dataclasses.dataclass(frozen=True)
class FigureSpec:
    """One of the study's figures, in the shape :func:`lasa.evidence.publish.publish` takes."""

    NAME: str
    COLUMNS: tuple[str, ...]
    plot: Callable[..., Figure]


def run(
    task: EatingTask,
    decoders: Mapping[str, ActionDecoder],
    control: ControlConfig,
    config: Config,
    progress: bool = True,
) -> tuple[dict[str, dict[str, Episodes]], dict[str, pd.DataFrame]]:
    """Simulate the cohort under each participant model and measure it.

    Each of ``config.participant_models`` (the headline first) runs the same cohort. The first
    of ``decoders`` is the headline: every condition under every member. Each other reading
    runs LA and LA+SA only, under the headline member (Retargeting does not use the decoder:
    its episodes are the headline run's, the same participants and random streams). A model
    named in ``config.readings_per_model`` runs only the first that many of ``decoders``.

    Returns:
        The episodes per participant model and decoder reading (``episodes[model][decoder]``),
        and the three tidy tables. Their ``decoder`` column names the reading of each LA row
        (``none`` for Retargeting), their ``model`` column the participant model.
    """
    if not decoders:
        raise ConfigError("run needs at least one decoder (the headline first)")
    cohort = draw_cohort(config.n_participants, config.study().participant, config.seed)
    episodes: dict[str, dict[str, Episodes]] = {}
    parts: dict[str, list[pd.DataFrame]] = {"goal_error": [], "time": [], "alignment": []}
    for model in config.participant_models:
        simulate = PARTICIPANT_MODELS[model]
        episodes[model] = {}
        limit = config.readings_per_model.get(model, len(decoders))
        for i, (name, decoder) in enumerate(list(decoders.items())[:limit]):
            settings = (
                config.study() if i == 0 else dataclasses.replace(config.study(), members=config.members[:1])
            )
            episodes[model][name] = simulate(
                task,
                decoder,
                cohort,
                control,
                settings,
                seed=config.seed,
                progress=progress,
                interfaces=("R", "LA") if i == 0 else ("LA",),
            )
            for key, frame in measures(task, episodes[model][name]).items():
                la = frame.condition.map({c: interface_of(c) == "LA" for c in CONDITIONS}).astype(bool)
                parts[key].append(frame.assign(decoder=np.where(la, name, NO_ASSISTANCE), model=model))
    return episodes, {key: pd.concat(frames, ignore_index=True) for key, frames in parts.items()}


def for_member(
    frame: pd.DataFrame,
    member: str,
    n: int | None = None,
    decoder: str | None = None,
    model: str | None = None,
) -> pd.DataFrame:
    """The rows of one SA reading (the unassisted conditions included), for the first ``n`` participants.

    With ``decoder``, the LA rows are that decoder reading's (a frame without a ``decoder``
    column holds one reading); with ``model``, the rows are that participant model's (a frame
    without a ``model`` column holds one model).
    """
    rows = frame[(frame.assistance == member) | (frame.assistance == NO_ASSISTANCE)]
    if decoder is not None and "decoder" in rows.columns:
        rows = rows[(rows.decoder == decoder) | (rows.decoder == NO_ASSISTANCE)]
    if model is not None and "model" in rows.columns:
        rows = rows[rows.model == model]
    if n is not None:
        rows = rows[rows.participant < n]
    return rows.reset_index(drop=True)


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
    :data:`COMPLETION_BAR` of the time is the headline; if none does, the first of ``models``.

    Args:
        time: The study's time table (:func:`run`), with its ``model`` column.
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
    for (cond, member), part in rows.groupby(["condition", "assistance"], sort=False):
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
                "assistance": member,
                "participants": len(share),
                "switch_share": float(share.mean()),
                "ci_low": float(ci[0]),
                "ci_high": float(ci[1]),
                "switches_per_task": float(part.mode_switches.mean()),
                "herlant_2016": HERLANT_SHARE,
            }
        )
    return pd.DataFrame(out)


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
    settings = config.study()
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


def _paired(a: pd.Series, b: pd.Series) -> tuple[float, float, float, float, int]:
    """Mean of a - b, its 95% t interval, the paired t-test's p, and the pairs used.

    Participants without a value under either condition (a phase never reached) are left
    out; with fewer than two pairs left, everything but the count is NaN.
    """
    keep = a.notna() & b.notna()
    a, b = a[keep], b[keep]
    if len(a) < 2:
        return np.nan, np.nan, np.nan, np.nan, int(len(a))
    res = sps.ttest_rel(a, b)
    ci = res.confidence_interval()
    return float((a - b).mean()), float(ci.low), float(ci.high), float(res.pvalue), int(len(a))


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


def readings_table(
    prop: pd.DataFrame,
    done: pd.DataFrame,
    rows: list[Claim],
    decoders: list[str],
    member: str,
    models: tuple[str, ...] = (),
) -> pd.DataFrame:
    """One row per participant model and decoder reading, the headlines first: property, completion, verdicts.

    Args:
        prop: :func:`lasa.evidence.latent_property.summary` of the eating decoders.
        done: :func:`completion` of the study's time table.
        rows: The study's claims rows (:func:`claims`).
        decoders: The decoder readings, the headline first.
        member: The headline SA member (the assisted conditions' completion is under it).
        models: The participant models, the headline first; default: ``done``'s ``model``
            column in order of appearance (none: one model, and no ``model`` column).

    Columns: ``model`` (with models), ``decoder``, ``headline`` (the headline decoder),
    ``goals with the property``, ``least share staying``, ``R finished``, ``R+SA finished``,
    ``LA finished``, ``LA+SA finished`` (that model's; Retargeting's do not depend on the
    decoder), and H1-H3's verdicts for 10 participants / the cohort (``-`` where the study
    had no cohort).
    """
    if not models and "model" in done.columns:
        models = tuple(dict.fromkeys(done.model))
    verdict = {c.id: c.reproduced for c in rows}
    keys = [k for k in ("model", "decoder", "assistance", "condition") if k in done.columns]
    finished = done.set_index(keys).finished
    out = []
    for k, model in enumerate(models or (None,)):
        lead = () if model is None else (model,)
        for d in decoders:
            if not _ran(done, model, d):
                continue
            other = None if d == decoders[0] else d
            mine = prop[prop.decoder == d]
            arms = {
                c: (NO_ASSISTANCE if interface_of(c) == "R" else d, member if "+" in c else NO_ASSISTANCE)
                for c in CONDITIONS
            }
            out.append(
                {
                    **({} if model is None else {"model": model}),
                    "decoder": d,
                    "headline": other is None,
                    "goals with the property": int(mine.has_property.sum()),
                    "least share staying": mine.stay_share.min(),
                    **{f"{c} finished": finished.get((*lead, *arms[c], c)) for c in CONDITIONS},
                    **{
                        f"{h.upper()} (10 / all)": " / ".join(
                            verdict.get(claim_id(h, 0, member, cohort, other, model if k else None), "-")
                            for cohort in (False, True)
                        )
                        for h in DECODER_KEYS
                    },
                }
            )
    return pd.DataFrame(out)


def analyse(
    frames: dict[str, pd.DataFrame],
    member: str,
    n: int | None = None,
    decoder: str | None = None,
    model: str | None = None,
    horizon: float = math.inf,
    n_resamples: int = 10_000,
) -> dict[str, object]:
    """Every test the claims rest on, for one SA reading, decoder reading, participant model and first ``n``.

    ``horizon`` [s] is where an unfinished episode's time was cut (H3's restricted times);
    ``n_resamples`` the paired bootstrap's resamples for H3.
    """
    err = for_member(frames["goal_error"], member, n, decoder, model)
    time = for_member(frames["time"], member, n, decoder, model)
    align = for_member(frames["alignment"], member, n, decoder, model)
    out: dict[str, object] = {
        "n": int(err.participant.nunique()),
        "h1_within": stats.sa_effect_within(err, "goal_error"),
        "h1_between": stats.sa_effect_between(err, "goal_error"),
        "h1_rm": stats.rm_anova(err, "goal_error"),
        "h1_pairs": stats.pairwise(err, "goal_error", pairs=[("LA+SA", "LA"), ("R+SA", "R")]),
        "h1_mean_within": stats.sa_effect_within(err, "mean_distance"),
        "h1_mean_pairs": stats.pairwise(err, "mean_distance", pairs=[("LA+SA", "LA"), ("R+SA", "R")]),
    }
    scoop = align[(align.task == "Dessert")]
    wide = scoop.pivot_table(index="participant", columns=["phase", "condition"], values="alignment")
    missing = pd.Series(np.nan, index=wide.index)
    out["h2_phases"] = {
        phase: _paired(wide.get((phase, "LA+SA"), missing), wide.get((phase, "R+SA"), missing))
        for phase in ("stab", "scoop", "dip")
    }
    out.update(_h3(time, horizon, n_resamples))
    return out


def _h3(time: pd.DataFrame, horizon: float, n_resamples: int) -> dict[str, object]:
    """H3's numbers: completion per condition, restricted means, and LA+SA's bootstrap contrasts.

    ``h3_short`` names each condition that finishes fewer than :data:`COMPLETION_BAR` of its
    episodes (``"LA 0%, LA+SA 0%"``; empty if none): then H3 is not testable. ``h3_total`` and
    ``h3_idle`` are :func:`lasa.evidence.stats.rmst_contrasts` (LA+SA minus each other
    condition), ``means`` the restricted means per participant over both tasks, and
    ``h3_gap`` the contrast with the fastest other condition (by restricted mean Total Time).
    """
    done = time.groupby("condition").completed.mean().reindex(list(CONDITIONS))
    short = done[~(done >= COMPLETION_BAR)]  # an arm without episodes (NaN) is short too
    contrasts = {
        m: stats.rmst_contrasts(time, m, horizon, n_resamples=n_resamples)
        for m in ("total_time", "idle_time")
    }
    means = pd.DataFrame(
        {m: stats.restricted_times(time, m, horizon).mean() for m in ("total_time", "idle_time")}
    )
    best = str(means.total_time.drop("LA+SA").idxmin())
    gap = contrasts["total_time"].set_index("b").loc[best]
    return {
        "h3_completion": done,
        "h3_short": ", ".join(f"{c} {100 * v:.3g}%" for c, v in short.fillna(0.0).items()),
        "h3_total": contrasts["total_time"],
        "h3_idle": contrasts["idle_time"],
        "means": means,
        "h3_gap": (best, float(gap["diff"]), float(gap.ci_low), float(gap.ci_high)),
        "horizon": horizon,
    }


def _verdicts(result: dict[str, object]) -> dict[str, tuple[str, float, float, float, str]]:
    """(the tests' verdict, value, 95% ci_low, ci_high, measured) per claim key.

    The value is the effect the verdict rests on, and its interval is the t-interval of the
    same test (paired over participants, or two-sample for the paper's F(1,18) reading); for
    H3 the percentile interval of the paired bootstrap (:func:`_h3_verdict`).
    """
    out: dict[str, tuple[str, float, float, float, str]] = {}
    for key, suffix, unit, scale in (("h1", "", "m s", 1.0), ("h1_mean_distance", "_mean", "cm", 100.0)):
        within, pairs = result[f"h1{suffix}_within"], result[f"h1{suffix}_pairs"]
        assert isinstance(within, dict) and isinstance(pairs, pd.DataFrame)
        diff = within["mean_sa"] - within["mean_no_sa"]
        main = diff < 0 and within["p"] < 0.05
        both = bool(((pairs["diff"] < 0) & (pairs.p_corr < 0.05)).all())
        verdict = "yes" if main and both else "partly" if main else "no"
        pair_text = "; ".join(
            f"{r.a} - {r.b} = {scale * r.diff:+.2f} {unit} (p_holm = {r.p_corr:.3g})"
            for r in pairs.itertuples()
        )
        out[key] = (
            verdict,
            diff,
            within["ci_low"],
            within["ci_high"],
            f"SA - no SA = {scale * diff:+.2f} {unit}; {stats.format_f(within)} (within); {pair_text}",
        )
    between = result["h1_between"]
    assert isinstance(between, dict)
    b_diff = between["mean_sa"] - between["mean_no_sa"]
    verdict = "yes" if b_diff < 0 and between["p"] < 0.05 else "no"
    out["h1_paper_test"] = (
        verdict,
        b_diff,
        between["ci_low"],
        between["ci_high"],
        f"SA - no SA = {b_diff:+.2f} m s; {stats.format_f(between)} (between, the paper's df)",
    )
    phases = result["h2_phases"]
    assert isinstance(phases, dict)
    mean, low, high, p, _ = phases["scoop"]
    verdict = "yes" if mean > 0 and p < 0.05 else "partly" if mean > 0 else "no"  # NaN: "no"
    text = "; ".join(
        f"{ph}: {m:+.3f} (p = {pp:.3g}, {k} pairs)" if np.isfinite(pp) else f"{ph}: no test ({k} pairs)"
        for ph, (m, _, _, pp, k) in phases.items()
    )
    out["h2"] = (verdict, mean, low, high, f"alignment LA+SA - R+SA, Dessert phases: {text}")
    out["h3"] = _h3_verdict(result)
    return _censored_goal_error(out, str(result["h3_short"]))


def _censored_goal_error(
    out: dict[str, tuple[str, float, float, float, str]], short: str
) -> dict[str, tuple[str, float, float, float, str]]:
    """H1's readings are not testable when a condition finishes too few episodes (``short``).

    Goal Error is summed over the task's steps (and the mean distance is that sum over the
    task's time): an episode cut at the horizon has its sum cut there too, a censored measure
    like its time, so H1 takes H3's completion guard. H2 compares the alignment within the
    scoop phase among the participants who reached it under both conditions, with its pairs
    counted, and keeps its verdict.
    """
    if not short:
        return out
    for key in ("h1", "h1_mean_distance", "h1_paper_test"):
        measured = out[key][4]
        out[key] = (
            NOT_TESTABLE,
            math.nan,
            math.nan,
            math.nan,
            f"{NOT_TESTABLE} (completion: {short}); {measured}",
        )
    return out


def _h3_verdict(result: Mapping[str, object]) -> tuple[str, float, float, float, str]:
    """H3's verdict, the LA+SA gap to the fastest other condition, its bootstrap interval, measured.

    Not testable (the value and interval NaN) when a condition finishes fewer than
    :data:`COMPLETION_BAR` of its episodes; else yes if every restricted-mean contrast of
    LA+SA (Total and Idle Time, against R, R+SA and LA) has its 95% interval below 0, partly
    if LA+SA has the lowest restricted mean Total Time, no otherwise.
    """
    total, idle, means, gap = result["h3_total"], result["h3_idle"], result["means"], result["h3_gap"]
    short, done, horizon = result["h3_short"], result["h3_completion"], result["horizon"]
    assert isinstance(total, pd.DataFrame) and isinstance(idle, pd.DataFrame)
    assert isinstance(means, pd.DataFrame) and isinstance(gap, tuple) and isinstance(done, pd.Series)
    assert isinstance(horizon, float | int)
    to = "uncut" if math.isinf(horizon) else f"restricted to the {horizon:g} s horizon"
    times = ", ".join(
        f"{c} {means.total_time[c]:.0f} s (idle {means.idle_time[c]:.0f} s)" for c in CONDITIONS
    )
    finished = ", ".join(f"{c} {100 * v:.3g}%" for c, v in done.fillna(0.0).items())
    tail = f"mean total (idle) time over both tasks, {to}: {times}; completion: {finished}"
    if short:
        return NOT_TESTABLE, math.nan, math.nan, math.nan, f"{NOT_TESTABLE} (completion: {short}); {tail}"
    all_below = bool((total.ci_high < 0).all() and (idle.ci_high < 0).all())
    fastest = means.total_time.idxmin() == "LA+SA"
    verdict = "yes" if all_below else "partly" if fastest else "no"
    best, g_mean, g_low, g_high = gap
    return (
        verdict,
        float(g_mean),
        float(g_low),
        float(g_high),
        f"LA+SA - {best} (the fastest other) = {g_mean:+.1f} s [{g_low:+.1f}, {g_high:+.1f}] (restricted "
        f"means, paired bootstrap); {tail}",
    )


CLAIM_TEXT = {
    "h1": (
        "H1: users with SA maintain their goals more accurately (Goal Error)",
        "F(1,18) = 29.9, p < .001; LA+SA < LA p < .001; R+SA < R p < .05",
    ),
    "h1_mean_distance": (
        "H1 with Goal Error read as the mean distance to the closest goal (the sum over the task / its time)",
        "F(1,18) = 29.9, p < .001 (for the summed distance)",
    ),
    "h1_paper_test": (
        "H1 under the paper's F(1,18) reading (participant means as independent groups)",
        "F(1,18) = 29.9, p < .001",
    ),
    "h2": (
        "H2: LA lets users execute their preferences (Dessert scoop alignment, LA+SA vs R+SA)",
        "R+SA stays in a stabbing orientation; LA+SA adjusts to scoop",
    ),
    "h3": (
        "H3: LA+SA completes the tasks most efficiently (Total and Idle Time)",
        "LA+SA fastest, Total and Idle Time, p < .05 vs each",
    ),
}


# readings of each claim key: the claim it belongs to, and the reading's name (None: the paper's)
_KEYS = {
    "h1": ("h1", None),
    "h1_mean_distance": ("h1", "mean_distance"),
    "h1_paper_test": ("h1", "paper_test"),
    "h2": ("h2", None),
    "h3": ("h3", None),
}


def claim_id(
    key: str,
    member_index: int,
    member: str,
    cohort: bool,
    decoder: str | None = None,
    model: str | None = None,
) -> str:
    """``study.<claim>`` for the paper's reading, ``study.<claim>@<reading>`` for the others.

    The paper's reading is its measure, the headline decoder, the headline participant model,
    the headline member (hindsight, index 0) and its 10 participants; every other reading
    names what differs, joined by ``+`` in that order: ``study.h1@mean_distance+grasp_set+cohort``,
    ``study.h3@home_entropy``, ``study.h3@one_step``, ``study.h2@transfers_entropy+one_step+cohort``
    (``decoder``: a decoder reading other than the headline; ``model``: a participant model
    other than the headline).
    """
    base, measure = _KEYS[key]
    reading = (measure, decoder, model, None if member_index == 0 else member, "cohort" if cohort else None)
    parts = [p for p in reading if p]
    return f"study.{base}" + (f"@{'+'.join(parts)}" if parts else "")


DECODER_KEYS = ("h1", "h2", "h3")  # the claims judged for every other decoder reading (the paper's measures)


def claims(
    frames: dict[str, pd.DataFrame],
    members: tuple[str, ...],
    n_total: int,
    decoders: tuple[str, ...] = (),
    *,
    models: tuple[str, ...] = (),
    horizon: float = math.inf,
    untestable: str | None = None,
    untestable_decoders: Mapping[str, str] | None = None,
    n_resamples: int = 10_000,
) -> tuple[list[Claim], dict[tuple, dict[str, object]]]:
    """The claims rows under every reading (measure, member, decoder, participant model, 10 or the cohort).

    Args:
        frames: :func:`run`'s tables.
        members: The SA members, the headline first.
        n_total: The cohort's size (its first :data:`PAPER_N` are the paper's study).
        decoders: The decoder readings in the frames' ``decoder`` column, the headline first
            (empty: the frames hold one reading). The headline decoder is judged under every
            measure and member; each other one under the paper's measures
            (:data:`DECODER_KEYS`) and the headline member.
        models: The participant models in the frames' ``model`` column, the headline first
            (default: that column's, in order of appearance; none: one model). Each is judged
            as the headline is, its ids naming it (:func:`claim_id`).
        horizon: Where an unfinished episode's time was cut [s] (H3's restricted times).
        untestable: If given, why the study cannot test its hypotheses at all (e.g. no
            decoder has both halves of the property): every row reads ``not testable`` with
            this reason in its note; ``measured`` keeps the numbers.
        untestable_decoders: Decoder reading -> why its rows are not testable, the same way.
        n_resamples: The paired bootstrap's resamples (H3).

    Returns:
        The rows, and the analyses keyed ``(member, n)`` for the headline decoder and model,
        ``(member, n, decoder)`` for another decoder under the headline model, and
        ``(member, n, decoder, model)`` under every other model (``decoder`` None when the
        frames hold one reading).

    A verdict is settled when the 95% interval of its effect lies on one side of zero
    (:data:`lasa.evidence.rules.RULES`): then it is the tests' verdict (yes / partly / no, the
    rules of this module's docstring), otherwise ``undecided``; ``not testable`` is never settled.
    """
    if not models and "model" in frames["time"].columns:
        models = tuple(dict.fromkeys(frames["time"].model))
    head = decoders[0] if decoders else None
    runs = [(m_i, member, head) for m_i, member in enumerate(members)]
    runs += [(0, members[0], d) for d in decoders[1:]]
    sizes = [(PAPER_N, False)] + ([(n_total, True)] if n_total > PAPER_N else [])
    analyses: dict[tuple, dict[str, object]] = {}
    rows: list[Claim] = []
    for k, model in enumerate(models or (None,)):
        other_model = model if k else None
        for m_i, member, decoder in runs:
            if not _ran(frames["time"], model, decoder):
                continue
            other = decoder if decoder != head else None
            reason = untestable or (untestable_decoders or {}).get(str(decoder))
            for n, cohort in sizes:
                result = analyse(frames, member, n, decoder, model, horizon, n_resamples)
                key = (member, n) + ((other,) if other else ()) if not k else (member, n, decoder, model)
                analyses[key] = result
                for name, judged in _verdicts(result).items():
                    if other is not None and name not in DECODER_KEYS:
                        continue
                    cid = claim_id(name, m_i, member, cohort, other, other_model)
                    rows.append(_claim_row(cid, name, judged, result, member, decoder, model, reason))
    return _with_flips(rows), analyses


def _ran(time: pd.DataFrame, model: str | None, decoder: str | None) -> bool:
    """Whether the time table holds LA episodes of this participant model and decoder reading."""
    rows = time
    if model is not None and "model" in time.columns:
        rows = rows[rows.model == model]
    if decoder is not None and "decoder" in time.columns:
        rows = rows[rows.decoder == decoder]
    return len(rows) > 0


def _claim_row(
    cid: str,
    key: str,
    judged: tuple[str, float, float, float, str],
    result: Mapping[str, object],
    member: str,
    decoder: str | None,
    model: str | None,
    reason: str | None,
) -> Claim:
    """One claims row: the tests' verdict, settled or undecided, or not testable with its reason."""
    verdict, value, low, high, measured = judged
    r = rule(cid)
    if verdict != NOT_TESTABLE and not (math.isfinite(low) and math.isfinite(high)):
        verdict, measured = NOT_TESTABLE, f"{NOT_TESTABLE} (too few pairs for an interval); {measured}"
    testable = verdict != NOT_TESTABLE and reason is None
    settled = testable and r.settled({"effect": (low, high)})
    n = int(result["n"])  # type: ignore[call-overload]
    if verdict == NOT_TESTABLE and "too few pairs" in measured:
        why = f"{NOT_TESTABLE} (too few pairs for an interval): fewer than two participants "
        why += "reached the compared phase under both conditions"
    elif verdict == NOT_TESTABLE:
        why = measured.split(";", 1)[0] + ": every condition must finish "
        why += f"{100 * COMPLETION_BAR:.0f}% of its episodes before its times are compared"
    else:
        why = f"95% interval of the effect [{low:.3g}, {high:.3g}]" + (
            "" if settled else f", which straddles 0; the tests read {verdict!r}"
        )
    note = (
        (f"{NOT_TESTABLE} ({reason}). " if reason else "")
        + f"{n} simulated participants; SA = {member}; "
        + (f"decoder = {decoder}; " if decoder else "")
        + (f"participant model = {model}; " if model else "")
        + f"{why}. Rule: {r.text}."
    )
    claim, paper = CLAIM_TEXT[key]
    return Claim(
        id=cid,
        claim=claim,
        figure="study",
        paper=paper,
        measured=measured,
        reproduced=verdict if settled else NOT_TESTABLE if not testable else UNDECIDED,
        note=note,
        robot="panda",
        assistance=member,
        value=float(value),
        ci_low=float(low),
        ci_high=float(high),
        settled=settled,
        n_users=n,
        values={"effect": float(value)},
        intervals={"effect": (float(low), float(high))},
    )


def _with_flips(rows: list[Claim]) -> list[Claim]:
    """Each headline row's note led by the readings whose verdict differs from it."""
    heads = {c.id for c in rows if "@" not in c.id}
    out = []
    for c in rows:
        if c.id in heads:
            flips = [
                f"{o.id.split('@')[1]} {o.reproduced}"
                for o in rows
                if o.id.startswith(c.id + "@") and o.reproduced != c.reproduced
            ]
            lead = (
                f"Readings with another verdict: {', '.join(flips)}. "
                if flips
                else "Every reading gives the same verdict. "
            )
            c = dataclasses.replace(c, note=lead + c.note)
        out.append(c)
    return out


def untestable_reason(prop: pd.DataFrame) -> str | None:
    """Why the study cannot test H1-H3, or None: does a decoder meet the property's rule?

    Args:
        prop: :func:`lasa.evidence.latent_property.summary` of the eating decoders.

    Returns:
        None if some decoder has both halves of the property at every goal and reaches every
        goal from home (:func:`lasa.evidence.latent_property.holds`); else a reason naming the
        best reading (:func:`lasa.evidence.latent_property.choose`) and its numbers: the goals
        with both halves and with the stay half, whether every goal is reached from home, its
        least share staying and the fewest inputs that leave a goal for another (LA+SA).
    """
    if latent_property.holds(prop).any():
        return None
    best = latent_property.choose(prop)
    mine = prop[prop.decoder == best]
    both, stay = int(mine.has_property.sum()), int(mine.stay_holds.sum())
    reached = "every" if mine.all_reached.all() else "not every"
    return (
        f"no decoder with both halves of the property; best reading {best}: both halves at {both} of "
        f"{len(mine)} goals, the stay half at {stay}, {reached} goal reached from home, least share staying "
        f"{mine.stay_share.min():.2f}, fewest inputs leaving a goal for another {mine.leave_min.min():.0f} "
        f"of {int(mine.n_inputs.max())}"
    )


# every interval the study's figures draw: a 95% bootstrap CI, seeded so the PNG is the same run after run
CI = {"errorbar": ("ci", 95), "seed": 0}


# what the paper reports for each hypothesis (Sec. VI), as the figures label their reference
PAPER_H = {
    "h1": "paper: F(1,18) = 29.9, p < .001 (H1: the SA conditions lower Goal Error, R+SA < R and LA+SA < LA)",
    "h2": "paper (H2): in the scoop phase LA+SA's alignment is above R+SA's",
    "h3": "paper (H3): LA+SA fastest, Total and Idle Time (p < .05)",
}


def _reading(member: str, decoder: str | None) -> str:
    """The figures' caption of what they show: the SA member, and the decoder reading if named."""
    return f"SA = {member}" + (f"; decoder = {decoder}" if decoder else "")


def plot_goal_error(
    frame: pd.DataFrame, member: str = "hindsight", decoder: str | None = None, model: str | None = None
) -> Figure:
    """Fig. error: Goal Error per condition and task (bars: mean, 95% CI; dots: participants).

    The title's second line is the paper's H1 result and ordering (:data:`PAPER_H`).
    """
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member, decoder=decoder, model=model)
    fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
    sns.barplot(
        data=data,
        x="task",
        y="goal_error",
        hue="condition",
        hue_order=CONDITIONS,
        palette=PALETTE,
        **CI,
        ax=ax,
        alpha=0.85,
    )
    sns.stripplot(
        data=data,
        x="task",
        y="goal_error",
        hue="condition",
        hue_order=CONDITIONS,
        palette=PALETTE,
        dodge=True,
        size=2.5,
        jitter=False,  # seaborn jitters with an unseeded generator: the PNG would change run to run
        color="k",
        ax=ax,
        legend=False,
        alpha=0.5,
    )
    ax.set_ylabel("Goal Error [m s]")
    what = f"Goal Error ({data.participant.nunique()} simulated participants; {_reading(member, decoder)})"
    ax.set_title(f"{wrap_to(what, 5.0, 10)}\n{wrap_to(PAPER_H['h1'], 5.0, 10)}", fontsize=10)
    return fig


def plot_time(
    frame: pd.DataFrame,
    member: str = "hindsight",
    decoder: str | None = None,
    model: str | None = None,
    horizon: float | None = None,
) -> Figure:
    """Fig. time: Total Time (solid) and Idle Time (light) per condition and task, means with 95% CI.

    A bar whose episodes did not all finish within the horizon is hatched (censored: cut at
    the horizon), and every bar says which share finished. ``horizon`` [s] names the horizon
    (default: the longest unfinished episode's time); the last line is the paper's H3 (:data:`PAPER_H`).
    """
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member, decoder=decoder, model=model)
    if horizon is None:
        cut = data.total_time[~data.completed.astype(bool)]
        horizon = float(cut.max()) if len(cut) else math.nan
    fig, axes = plt.subplots(1, 2, figsize=(9, 4.6), sharey=True, layout="constrained")
    for ax, task in zip(axes, ("Entree", "Dessert"), strict=True):
        part = data[data.task == task]
        sns.barplot(
            data=part,
            x="condition",
            y="total_time",
            order=CONDITIONS,
            palette=PALETTE,
            hue="condition",
            **CI,
            ax=ax,
            legend=False,
        )
        _mark_censored(ax, part.groupby("condition").completed.mean())
        sns.barplot(
            data=part,
            x="condition",
            y="idle_time",
            order=CONDITIONS,
            color="white",
            **CI,
            ax=ax,
            alpha=0.6,
        )
        ax.set_title(f"{task}: total (solid) and idle (light)", fontsize=10)
        ax.set_ylabel("time [s]")
    axes[0].set_ylim(top=1.08 * axes[0].get_ylim()[1])  # room for the labels above the tallest bar
    censored = mpatches.Patch(facecolor="white", edgecolor="0.3", hatch="///", label="")
    when = "" if math.isnan(horizon) else f" {horizon:g} s"
    fig.legend(
        [censored],
        [f"hatched: censored at the{when} horizon (not every episode finished); text: share finished"],
        loc="outside lower center",
        frameon=False,
        fontsize=8,
    )
    what = _reading(member, decoder) + (f"; participant model = {model}" if model else "")
    title = wrap_to(f"{data.participant.nunique()} simulated participants; {what}", 9, 10)
    fig.suptitle(f"{title}\n{wrap_to(PAPER_H['h3'], 9, 10)}", fontsize=10)
    return fig


def _mark_censored(ax: plt.Axes, done: pd.Series) -> None:
    """Hatch each bar (the axes' patches, one per condition) whose share finished is below 1; label each."""
    for bar in [p for p in ax.patches if isinstance(p, mpatches.Rectangle)]:
        i = round(bar.get_x() + bar.get_width() / 2)
        if math.isnan(bar.get_height()) or not 0 <= i < len(CONDITIONS) or CONDITIONS[i] not in done:
            continue
        share = float(done[CONDITIONS[i]])
        if share < 1:
            bar.set_hatch("///")
            bar.set_edgecolor("0.3")
        ax.annotate(
            f"{100 * share:.0f}% done",
            (bar.get_x() + bar.get_width() / 2, bar.get_height()),
            xytext=(0, 2),
            textcoords="offset points",
            ha="center",
            va="bottom",
            fontsize=7,
        )


def plot_alignment(
    frame: pd.DataFrame, member: str = "hindsight", decoder: str | None = None, model: str | None = None
) -> Figure:
    """Fig. dessert (left): Preference Alignment per Dessert phase, every condition (the paper: 2 of them).

    The shaded scoop phase is labelled with the paper's H2 ordering there (:data:`PAPER_H`).
    """
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member, decoder=decoder, model=model)
    data = data[(data.task == "Dessert") & data.phase.isin(["stab", "scoop", "dip"])]
    fig, ax = plt.subplots(figsize=(7.6, 4.0), layout="constrained")
    sns.pointplot(
        data=data,
        x="phase",
        y="alignment",
        hue="condition",
        hue_order=CONDITIONS,
        order=["stab", "scoop", "dip"],
        palette=PALETTE,
        **CI,
        dodge=0.3,
        ax=ax,
    )
    ax.set_ylabel("Preference Alignment (d · d*)")
    ax.axvspan(0.6, 1.4, color="0.92", zorder=0, label=wrap_to(PAPER_H["h2"], 1.8, 8))  # the scoop phase
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    what = f"Dessert: alignment with each phase's preference ({_reading(member, decoder)})"
    ax.set_title(wrap_to(what, 4.5, 10), fontsize=10)
    return fig


# every table's keys: who, under which condition, SA member, decoder reading and participant model, which task
ROW_KEYS = ("robot", "participant", "condition", "assistance", "decoder", "model", "task")
GOAL_ERROR = FigureSpec(
    "study_goal_error",
    (*ROW_KEYS, "order", "goal_error", "goal_error_bowls", "mean_distance"),
    plot_goal_error,
)
TIME = FigureSpec(
    "study_time", (*ROW_KEYS, "order", "total_time", "idle_time", "mode_switches", "completed"), plot_time
)
ALIGNMENT = FigureSpec(
    "study_alignment", (*ROW_KEYS, "phase", "preference", "alignment", "steps"), plot_alignment
)
