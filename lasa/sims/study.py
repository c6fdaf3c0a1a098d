r"""The eating study (notebook 11): Figs. error, time and dessert (left), and claims H1-H3.

A cohort of simulated participants (:mod:`lasa.study`) does both eating tasks under R,
R+SA, LA and LA+SA. The first ten are the paper's study size; the whole cohort is the
larger one. Three tidy tables come out, one row per participant x condition x task (x
phase), each with its figure:

- ``study_goal_error``: Goal Error (Fig. error);
- ``study_time``: Total and Idle Time (Fig. time), with mode switches and completion;
- ``study_alignment``: Preference Alignment per phase (Fig. dessert, left panel).

The assisted conditions run under each member of ``Config.members`` (hindsight
optimisation, the paper's study, first: the headline), the unassisted ones once
(``assistance`` is ``none`` for them). The statistics are :mod:`lasa.stats`'s.

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
- **H3** (``study.h3``), LA+SA is the most efficient: Total and Idle Time, summed over the
  two tasks, lower with LA+SA than with each other condition (paired t-tests, Holm over
  the three comparisons of each measure): *yes* if all six comparisons are significant,
  *partly* if LA+SA has the lowest mean Total Time but not all six are, *no* otherwise.

Each claim has one row per reading: ``study.<claim>`` is the paper's (its measure, hindsight
optimisation, 10 participants), and ``study.<claim>@<reading>`` each other (:func:`claim_id`).
A verdict is settled when the 95% t-interval of its effect excludes zero, else ``undecided``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.figure import Figure
from scipy import stats as sps

from lasa import stats
from lasa.claims import Claim
from lasa.config import ASSISTANCE, ControlConfig, check_choice, from_dict
from lasa.decoder import ActionDecoder
from lasa.eating import EatingTask
from lasa.errors import ConfigError
from lasa.rules import UNDECIDED, rule
from lasa.study import (
    CONDITIONS,
    NO_ASSISTANCE,
    Episodes,
    ParticipantConfig,
    StudyConfig,
    draw_cohort,
    measures,
    simulate,
)

__all__ = [
    "Config",
    "FigureSpec",
    "GOAL_ERROR",
    "TIME",
    "ALIGNMENT",
    "PAPER_N",
    "run",
    "for_member",
    "analyse",
    "claims",
    "plot_goal_error",
    "plot_time",
    "plot_alignment",
]

PAPER_N = 10  # the paper's participants
PALETTE = {"R": "#8c8c8c", "R+SA": "#4c72b0", "LA": "#dd8452", "LA+SA": "#55a868"}


@dataclasses.dataclass(frozen=True)
class Config:
    """The simulated study (notebook 11); the participants' parameters are ``participant``."""

    n_participants: int = 40  # the larger cohort; its first 10 are the paper-sized study [-]
    members: tuple[str, ...] = ("hindsight", "grasp_set")  # SA readings; the first is the headline [-]
    horizon: int = 1500  # steps allowed per task (150 s) [-]
    seed: int = 0  # seed of the cohort and of the participants' choices [-]
    video_participant: int = 0  # whose Dessert the video shows [-]
    participant: dict[str, float] = dataclasses.field(default_factory=dict)  # ParticipantConfig overrides

    def __post_init__(self) -> None:
        if int(self.n_participants) != self.n_participants or self.n_participants < 2:
            raise ConfigError(f"n_participants must be an integer >= 2, got {self.n_participants!r}")
        object.__setattr__(self, "members", tuple(self.members))
        for name in self.members:
            check_choice("assistance", name, ASSISTANCE)
        if not 0 <= self.video_participant < self.n_participants:
            raise ConfigError(
                f"video_participant must be in [0, {self.n_participants}), got {self.video_participant}"
            )

    def study(self) -> StudyConfig:
        """The session settings for :func:`lasa.study.simulate`."""
        return StudyConfig(
            horizon=self.horizon,
            members=self.members,
            participant=from_dict(ParticipantConfig, self.participant),
        )


@dataclasses.dataclass(frozen=True)
class FigureSpec:
    """One of the study's figures, in the shape :func:`lasa.sims.publish.publish` takes."""

    NAME: str
    COLUMNS: tuple[str, ...]
    plot: Callable[..., Figure]


def run(
    task: EatingTask, decoder: ActionDecoder, control: ControlConfig, config: Config, progress: bool = True
) -> tuple[Episodes, dict[str, pd.DataFrame]]:
    """Simulate the cohort and measure it: the episodes and the three tidy tables."""
    cohort = draw_cohort(config.n_participants, config.study().participant, config.seed)
    episodes = simulate(task, decoder, cohort, control, config.study(), seed=config.seed, progress=progress)
    return episodes, measures(task, episodes)


def for_member(frame: pd.DataFrame, member: str, n: int | None = None) -> pd.DataFrame:
    """The rows of one SA reading (the unassisted conditions included), for the first ``n`` participants."""
    rows = frame[(frame.assistance == member) | (frame.assistance == NO_ASSISTANCE)]
    if n is not None:
        rows = rows[rows.participant < n]
    return rows.reset_index(drop=True)


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


def analyse(frames: dict[str, pd.DataFrame], member: str, n: int | None = None) -> dict[str, object]:
    """Every test the claims rest on, for one SA reading and the first ``n`` participants."""
    err = for_member(frames["goal_error"], member, n)
    time = for_member(frames["time"], member, n)
    align = for_member(frames["alignment"], member, n)
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
    others = [("LA+SA", c) for c in CONDITIONS if c != "LA+SA"]
    out["h3_total"] = stats.pairwise(time, "total_time", agg="sum", pairs=others)
    out["h3_idle"] = stats.pairwise(time, "idle_time", agg="sum", pairs=others)
    means = time.groupby("condition")[["total_time", "idle_time"]].sum().div(out["n"])
    out["means"] = means
    totals = time.pivot_table(index="participant", columns="condition", values="total_time", aggfunc="sum")
    best_other = str(means.total_time.drop("LA+SA").idxmin())
    out["h3_gap"] = (best_other, *_paired(totals["LA+SA"], totals[best_other]))
    return out


def _verdicts(result: dict[str, object]) -> dict[str, tuple[str, float, float, float, str]]:
    """(the tests' verdict, value, 95% ci_low, ci_high, measured) per claim key.

    The value is the effect the verdict rests on, and its interval is the t-interval of the
    same test (paired over participants, or two-sample for the paper's F(1,18) reading).
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
    text = "; ".join(f"{ph}: {m:+.3f} (p = {pp:.3g}, {k} pairs)" for ph, (m, _, _, pp, k) in phases.items())
    out["h2"] = (verdict, mean, low, high, f"alignment LA+SA - R+SA, Dessert phases: {text}")
    total, idle, means, gap = result["h3_total"], result["h3_idle"], result["means"], result["h3_gap"]
    assert (
        isinstance(total, pd.DataFrame)
        and isinstance(idle, pd.DataFrame)
        and isinstance(means, pd.DataFrame)
        and isinstance(gap, tuple)
    )
    all_sig = bool(
        ((total["diff"] < 0) & (total.p_corr < 0.05)).all()
        and ((idle["diff"] < 0) & (idle.p_corr < 0.05)).all()
    )
    fastest = means.total_time.idxmin() == "LA+SA"
    verdict = "yes" if all_sig else "partly" if fastest else "no"
    best, g_mean, g_low, g_high = gap[0], gap[1], gap[2], gap[3]
    text = ", ".join(f"{c} {means.total_time[c]:.0f} s (idle {means.idle_time[c]:.0f} s)" for c in CONDITIONS)
    out["h3"] = (
        verdict,
        float(g_mean),
        float(g_low),
        float(g_high),
        f"LA+SA - {best} (the fastest other) = {g_mean:+.1f} s; total (idle) time over both tasks: {text}",
    )
    return out


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


def claim_id(key: str, member_index: int, member: str, cohort: bool) -> str:
    """``study.<claim>`` for the paper's reading, ``study.<claim>@<reading>`` for the others.

    The paper's reading is its measure, the headline member (hindsight, index 0) and its 10
    participants; every other reading names what differs, joined by ``+``:
    ``study.h1@mean_distance+grasp_set+cohort``.
    """
    base, measure = _KEYS[key]
    parts = [p for p in (measure, None if member_index == 0 else member, "cohort" if cohort else None) if p]
    return f"study.{base}" + (f"@{'+'.join(parts)}" if parts else "")


def claims(
    frames: dict[str, pd.DataFrame], members: tuple[str, ...], n_total: int
) -> tuple[list[Claim], dict[tuple[str, int], dict[str, object]]]:
    """The claims rows under every reading (measure, member, 10 participants or the cohort).

    A verdict is settled when the 95% t-interval of its effect lies on one side of zero
    (:data:`lasa.rules.RULES`), which is the test's own significance at p < .05; then it is
    the tests' verdict (yes / partly / no, the rules of this module's docstring), otherwise
    ``undecided``: a study of that size cannot tell.
    """
    analyses: dict[tuple[str, int], dict[str, object]] = {}
    rows: list[Claim] = []
    for m_i, member in enumerate(members):
        sizes = [(PAPER_N, False)] + ([(n_total, True)] if n_total > PAPER_N else [])
        for n, cohort in sizes:
            result = analyse(frames, member, n)
            analyses[(member, n)] = result
            for key, (verdict, value, low, high, measured) in _verdicts(result).items():
                cid = claim_id(key, m_i, member, cohort)
                r = rule(cid)
                settled = r.settled({"effect": (low, high)})
                claim, paper = CLAIM_TEXT[key]
                interval = f"95% t-interval of the effect [{low:.3g}, {high:.3g}]"
                note = (
                    f"{result['n']} simulated participants; SA = {member}; {interval}"
                    + ("" if settled else f", which straddles 0; the tests read {verdict!r}")
                    + f". Rule: {r.text}."
                )
                rows.append(
                    Claim(
                        id=cid,
                        claim=claim,
                        figure="study",
                        paper=paper,
                        measured=measured,
                        reproduced=verdict if settled else UNDECIDED,
                        note=note,
                        robot="panda",
                        assistance=member,
                        value=float(value),
                        ci_low=float(low),
                        ci_high=float(high),
                        settled=settled,
                        n_users=int(result["n"]),  # type: ignore[call-overload]
                        values={"effect": float(value)},
                    )
                )
    heads = {c.id: c for c in rows if "@" not in c.id}
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
    return out, analyses


# every interval the study's figures draw: a 95% bootstrap CI, seeded so the PNG is the same run after run
CI = {"errorbar": ("ci", 95), "seed": 0}


def plot_goal_error(frame: pd.DataFrame, member: str = "hindsight") -> Figure:
    """Fig. error: Goal Error per condition and task (bars: mean, 95% CI; dots: participants)."""
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member)
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
    ax.set_title(f"Goal Error ({data.participant.nunique()} simulated participants; SA = {member})")
    return fig


def plot_time(frame: pd.DataFrame, member: str = "hindsight") -> Figure:
    """Fig. time: Total Time (solid) and Idle Time (light) per condition and task, means with 95% CI."""
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member)
    fig, axes = plt.subplots(1, 2, figsize=(9, 4.2), sharey=True, layout="constrained")
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
        ax.set_title(f"{task}: total (solid) and idle (light)")
        ax.set_ylabel("time [s]")
    fig.suptitle(f"{data.participant.nunique()} simulated participants; SA = {member}")
    return fig


def plot_alignment(frame: pd.DataFrame, member: str = "hindsight") -> Figure:
    """Fig. dessert (left): Preference Alignment per Dessert phase, every condition (the paper: 2 of them)."""
    sns.set_theme(style="whitegrid")
    data = for_member(frame, member)
    data = data[(data.task == "Dessert") & data.phase.isin(["stab", "scoop", "dip"])]
    fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
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
    ax.set_title(f"Dessert: alignment with each phase's preference (SA = {member})")
    return fig


GOAL_ERROR = FigureSpec(
    "study_goal_error",
    (
        "robot",
        "participant",
        "condition",
        "assistance",
        "task",
        "order",
        "goal_error",
        "goal_error_bowls",
        "mean_distance",
    ),
    plot_goal_error,
)
TIME = FigureSpec(
    "study_time",
    (
        "robot",
        "participant",
        "condition",
        "assistance",
        "task",
        "order",
        "total_time",
        "idle_time",
        "mode_switches",
        "completed",
    ),
    plot_time,
)
ALIGNMENT = FigureSpec(
    "study_alignment",
    ("robot", "participant", "condition", "assistance", "task", "phase", "preference", "alignment", "steps"),
    plot_alignment,
)
