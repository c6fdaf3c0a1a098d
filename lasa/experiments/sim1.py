"""Fig. sim1: users of fixed expertise (Sec. V-A): every method against users of fixed rationality beta
(Eq. S1), final state error and time to reach s* per beta. Notebook ``04_fixed_expertise``."""

from __future__ import annotations

import dataclasses
import textwrap
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.transforms import blended_transform_factory

from lasa.base.config import ControlConfig, Positive, PositiveInt, Rationality, check_list
from lasa.base.errors import ConfigError
from lasa.evidence import plots
from lasa.evidence.claims import Claim
from lasa.evidence.findings import side_of
from lasa.evidence.metrics import confidence, normalized_error, time_to_reach
from lasa.evidence.rules import rule
from lasa.evidence.verdicts import USER, group_means
from lasa.experiments import sweep
from lasa.people.rollout import Trajectories
from lasa.world.goals import GoalTask

NAME = "sim1_fixed_expertise"
# the contract's columns first, then what the notebook and the claims read
COLUMNS = (
    "robot",
    "method",
    "beta",
    USER,
    "final_error",
    "time",
    "completed",
    "goal",
    "theta",
    "confidence",
    "assistance",
    "look",
)
CLAIM_BETAS = (75.0, 1000.0)  # the rationalities the claims compare at (noisy, near optimal) [1/rad^2]


@dataclasses.dataclass(frozen=True)
class Config(sweep.SweepConfig):
    """Fig. sim1: users of fixed expertise."""

    # rationalities [1/rad^2]
    betas: tuple[Rationality, ...] = (0.3, 1, 3, 10, 30, 75, 200, 1000, 3000, 10000)
    horizon: PositiveInt = 200  # control steps per episode [-]
    tolerance: Positive = 0.05  # normalised error that counts as reaching s* [-]
    video_beta: Rationality = 75.0  # the noisy user notebook 04's video shows: one of betas [1/rad^2]

    def __post_init__(self) -> None:
        super().__post_init__()
        betas = tuple(float(b) for b in check_list("betas", self.betas, ascending=True))
        object.__setattr__(self, "betas", betas)
        sweep.check_needed("betas", betas, CLAIM_BETAS, "Fig. sim1's claims")
        if float(self.video_beta) not in betas:
            raise ConfigError(
                f"video_beta must be one of betas {list(betas)} (the video shows a user of the sweep), "
                f"got {self.video_beta!r}"
            )


def run(
    decoders: sweep.Decoders,
    task: GoalTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = False,
    look: int = 0,
    assistance: tuple[str, ...] | None = None,
) -> tuple[pd.DataFrame, Trajectories]:
    """Fig. sim1 for one look's users: one row per episode, and the trajectories in that order."""

    def fixed(beta: list[float], goal: np.ndarray, _: np.ndarray) -> dict[str, np.ndarray]:
        return {"beta0": np.array(beta, dtype=float), "slope": np.zeros(len(goal))}

    ran = sweep.run_look(decoders, task, control, config, config.betas, fixed, progress, look, assistance)
    users, traj = ran.users, ran.traj
    errors = normalized_error(traj.states, users.target[None], task.goal_distance)
    steps, completed = time_to_reach(errors, config.tolerance)
    return pd.DataFrame(
        {
            "robot": task.robot.name,
            "method": ran.method,
            "beta": users.beta0,
            USER: ran.user,
            "final_error": errors[-1],
            "time": steps,
            "completed": completed,
            "goal": users.goal,
            "theta": users.theta,
            "confidence": confidence(traj.beliefs[-1], users.goal),
            "assistance": ran.member,
            "look": look,
        }
    ), traj


def _sa_claims(frame: pd.DataFrame) -> list[Claim]:
    """The paper's Fig. sim1 claims on a sim1 frame, comparing LA with LA+SA (at beta = 75 and 1000)."""
    robot, a, b = str(frame.robot.iloc[0]), "LA", "LA+SA"
    if not set(CLAIM_BETAS) <= set(frame.beta):
        raise ConfigError("sim1 claims need beta = 75 and beta = 1000 in the sweep")
    means = frame.groupby(["beta", "method"])[["final_error", "time"]].mean().unstack("method")
    err, tim = means["final_error"][[a, b]], means["time"][[a, b]]
    r75, r1000 = (tim.loc[beta, a] / tim.loc[beta, b] for beta in CLAIM_BETAS)
    lower = err[b] < err[a]
    n_lower, n_total = int(lower.sum()), len(lower)
    share = {"share_lower": n_lower / n_total}
    worst = (err[b] - err[a]).idxmax()
    d75, d1000 = err.loc[75.0, a] - err.loc[75.0, b], err.loc[1000.0, a] - err.loc[1000.0, b]
    gap = _gap_values(r75, r1000, d75, d1000)
    return [
        sweep.sim_claim(
            "sim1.final_error",
            robot,
            share,
            claim=f"SA lowers the final state error at every beta ({b} vs {a})",
            paper="LA+SA below LA at every beta",
            measured=f"{b} lower at {n_lower}/{n_total} betas (the interval is for this share); "
            f"mean final error {a} vs {b}: "
            f"{err.loc[75.0, a]:.3f} vs {err.loc[75.0, b]:.3f} at beta=75, "
            f"{err.loc[1000.0, a]:.3f} vs {err.loc[1000.0, b]:.3f} at beta=1000",
            note=""
            if rule("sim1.final_error").verdict(share) == "yes"
            else f"Largest excess of {b} at beta={worst:g} "
            f"({err.loc[worst, b]:.3f} vs {err.loc[worst, a]:.3f}).",
        ),
        sweep.sim_claim(
            "sim1.time_ratio",
            robot,
            {"ratio_75": float(r75), "ratio_1000": float(r1000)},
            claim=f"{a} takes 45% more time than {b} at beta=75 and 30% more at beta=1000",
            paper="time ratio 1.45 at beta=75, 1.30 at beta=1000 (7-DoF Panda)",
            measured=f"time ratio {r75:.2f} at beta=75 "
            f"({tim.loc[75.0, a]:.1f} vs {tim.loc[75.0, b]:.1f} steps), {r1000:.2f} at beta=1000 "
            f"({tim.loc[1000.0, a]:.1f} vs {tim.loc[1000.0, b]:.1f} steps)",
        ),
        sweep.sim_claim(
            "sim1.gap_narrows",
            robot,
            gap,
            claim=f"the gap between {a} and {b} narrows as beta grows",
            paper="time gap 45% at beta=75 -> 30% at beta=1000",
            measured=f"time gap (ratio - 1) {r75 - 1:+.2f} -> {r1000 - 1:+.2f}, "
            f"narrowing {gap['time_narrowing']:+.2f} (g75 - |g1000|); final-error gap {a}-{b} "
            f"{d75:+.3f} -> {d1000:+.3f} (beta 75 -> 1000)",
        ),
    ]


def _gap_values(r75: Any, r1000: Any, d75: Any, d1000: Any) -> dict[str, Any]:
    """sim1.gap_narrows' numbers from the time ratios and final-error gaps (floats or arrays)."""
    g75, g1000 = r75 - 1.0, r1000 - 1.0
    return {
        "time_narrowing": g75 - abs(g1000),
        "time_gap_75": g75,
        "error_narrowing": d75 - abs(d1000),
        "error_gap_75": d75,
    }


def claims(frame: pd.DataFrame) -> list[Claim]:
    """Fig. sim1's claims on one robot's frame: LA against LA+SA, and SA with or without entropy."""
    sa = _sa_claims(frame)
    err = frame.groupby(["beta", "method"]).final_error.mean().unstack("method")
    counts = {m: int((err[m] < err["LA"]).sum()) for m in ("LA+SA", "LA+SA+Entropy")}
    total = len(err)
    entropy = sweep.sim_claim(
        "sim1.entropy_sa",
        str(frame.robot.iloc[0]),
        {"share_weaker": min(counts.values()) / total},
        claim="SA improves on LA whether or not the decoder was trained with entropy",
        paper="LA+SA and LA+SA+Entropy both below LA (final error)",
        measured=f"the weaker of the two below LA at {min(counts.values())}/{total} betas "
        "(the interval is for this share); "
        f"final error below LA's at {counts['LA+SA']}/{total} betas (LA+SA) and "
        f"{counts['LA+SA+Entropy']}/{total} (LA+SA+Entropy); at beta=1000: "
        + ", ".join(
            f"{m} {err.loc[1000.0, m]:.3f}" for m in ("LA", "LA+SA", "LA+SA+Entropy") if 1000.0 in err.index
        ),
    )
    return [*sa, entropy]


def boot_values(frame: pd.DataFrame, counts: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """:func:`claims`' numbers in every resample of users (``counts``, :mod:`lasa.evidence.verdicts`)."""
    err = group_means(frame, ["beta", "method"], "final_error", counts)
    tim = group_means(frame, ["beta", "method"], "time", counts)
    betas = sorted({b for b, _ in err})

    def lower(m: str) -> np.ndarray:
        return np.mean([err[(b, m)] < err[(b, "LA")] for b in betas], axis=0)

    r75, r1000 = (tim[(beta, "LA")] / tim[(beta, "LA+SA")] for beta in CLAIM_BETAS)
    d75, d1000 = (err[(beta, "LA")] - err[(beta, "LA+SA")] for beta in CLAIM_BETAS)
    out = {
        "sim1.final_error": {"share_lower": lower("LA+SA")},
        "sim1.time_ratio": {"ratio_75": r75, "ratio_1000": r1000},
        "sim1.gap_narrows": _gap_values(r75, r1000, d75, d1000),
    }
    if any(m == "LA+SA+Entropy" for _, m in err):
        out["sim1.entropy_sa"] = {"share_weaker": np.minimum(lower("LA+SA"), lower("LA+SA+Entropy"))}
    return out


METRIC_LABELS = {"final_error": "final state error (normalised)", "time": "time to reach s* [steps]"}
# the paper's time ratio LA / LA+SA at these betas (Panda) and the rule's tolerance, from its rule [-]
PAPER_RATIOS = {float(p.where.split("=")[1]): p.value for p in rule("sim1.time_ratio").paper}
RATIO_TOLERANCE = rule("sim1.time_ratio").paper[0].tolerance
PAPER_FINAL_ERROR = "paper: LA+SA below LA at every β"  # Fig. sim1 (Sec. V-A), rule sim1.final_error
OPEN: dict[str, Any] = {"marker": "o", "ms": 6, "mfc": "white", "ls": "none", "zorder": 6}  # a censored point


def plot_metric(frame: pd.DataFrame, metric: str, ax: Axes | None = None) -> Axes:
    """One panel: ``final_error`` or ``time`` against beta per method, with bands at the verdicts' level."""
    ax = plots.method_lineplot(frame, "beta", metric, ax, level=sweep.LEVEL)
    ax.set_xscale("log")
    ax.set_xlabel(r"user rationality $\beta$")
    ax.set_ylabel(METRIC_LABELS.get(metric, metric))
    for i, beta in enumerate(PAPER_RATIOS):
        label = "β = 75, 1000: the paper's time ratios" if i == 0 else None
        ax.axvline(beta, color="0.8", lw=0.8, zorder=0, label=label)
    extra: list[Artist] = [plots.band_handle(sweep.LEVEL)]
    if metric == "final_error" and {"LA", "LA+SA"} <= set(frame.method):
        # mark, at the top, each beta where LA+SA's mean final error is below LA's
        err = frame.groupby(["beta", "method"]).final_error.mean().unstack("method")
        lower = err.index[err["LA+SA"] < err["LA"]].to_numpy(dtype=float)
        top = blended_transform_factory(ax.transData, ax.transAxes)
        label = f"ours: LA+SA below LA at {len(lower)} of {len(err)} β (marked ▼)"
        color = plots.METHOD_COLORS["LA+SA"]
        ax.plot(lower, np.full(len(lower), 0.97), "v", color=color, ms=6, transform=top, label=label)
        extra.append(plots.paper_handle(PAPER_FINAL_ERROR))
    if metric == "time" and "completed" in frame:  # redraw open each mean time with episodes cut short
        stats = frame.groupby(["method", "beta"]).agg(time=("time", "mean"), done=("completed", "mean"))
        cut = stats[stats.done < 1.0]
        for method, part in cut.groupby(level="method"):
            betas = part.index.get_level_values("beta")
            color = plots.METHOD_COLORS[str(method)]
            ax.plot(betas, part.time, mec=color, **OPEN)
        if not cut.empty:
            horizon = int(frame.loc[~frame.completed.astype(bool), "time"].max())
            label = (
                f"open: episodes cut at the horizon ({horizon} steps) count {horizon}, so the mean is a "
                f"lower bound; completion there {cut.done.min():.0%}–{cut.done.max():.0%}"
            )
            extra.append(Line2D([], [], mec="0.3", label=textwrap.fill(label, 60), **OPEN))
    plots.legend_below(ax, extra)
    return ax


def time_ratio_band(frame: pd.DataFrame, a: str = "LA", b: str = "LA+SA", n_boot: int = 1000) -> pd.DataFrame:
    """Mean time of ``a`` over ``b``'s per beta (``ratio``), with a percentile bootstrap interval at the
    verdicts' level (users resampled, seed 0; ``low``, ``high``)."""
    rng = np.random.default_rng(0)
    tail = 50.0 * (1.0 - sweep.LEVEL)
    times = frame.pivot_table(index=["beta", USER], columns="method", values="time", aggfunc="mean")
    means = frame.groupby(["beta", "method"]).time.mean()
    rows = []
    for beta, part in times.groupby(level="beta"):
        if a not in part or b not in part:
            continue
        pair = part[[a, b]].dropna().to_numpy()
        low = high = np.nan  # no user ran under both: no interval
        if len(pair):
            pick = rng.integers(0, len(pair), (n_boot, len(pair)))
            boot = pair[pick, 0].mean(axis=1) / pair[pick, 1].mean(axis=1)
            low, high = np.percentile(boot, [tail, 100.0 - tail])
        rows.append({"beta": beta, "ratio": means[beta, a] / means[beta, b], "low": low, "high": high})
    return pd.DataFrame(rows, columns=["beta", "ratio", "low", "high"])


def plot(table: pd.DataFrame, assistance: str = "point") -> Figure:
    """Fig. sim1 under member ``assistance``: per robot, final error (log), time, time ratio against beta."""

    def draw(name: str, part: pd.DataFrame, row: np.ndarray) -> None:
        plot_metric(part, "final_error", ax=row[0])
        plot_metric(part, "time", ax=row[1])
        ax = row[2]
        band = time_ratio_band(part)
        color = plots.METHOD_COLORS["LA+SA"]
        label = f"ours: {100 * sweep.LEVEL:.4g}% bootstrap CI (the verdicts' level)"
        ax.fill_between(band.beta, band.low, band.high, color=color, alpha=0.25, lw=0, label=label)
        ax.plot(band.beta, band.ratio, "o-", color=color, ms=4, label="ours: mean time LA / LA+SA")
        if "completed" in part:
            done = part[part.method.isin(["LA", "LA+SA"])].groupby("beta").completed.mean()
            cut = band[band.beta.map(done).lt(1.0).to_numpy()]
            if len(cut):
                label = "open: some LA or LA+SA episodes cut at the horizon (their times are lower bounds)"
                ax.plot(cut.beta, cut.ratio, mec=color, label=textwrap.fill(label, 60), **OPEN)
        ax.axhline(1.0, color="0.6", ls="--", lw=0.8, zorder=0, label="ratio 1: LA as fast as LA+SA")
        for i, (beta, value) in enumerate(PAPER_RATIOS.items()):
            tol = f"rule's tolerance: paper ± {RATIO_TOLERANCE:g}" if i == 0 else None
            plots.paper_point(ax, beta, value, f"paper: {value:.2f} (β = {beta:g})", RATIO_TOLERANCE, tol)
        ax.set_xscale("log")
        ax.set_xlabel(r"user rationality $\beta$")
        ax.set_ylabel("time ratio LA / LA+SA [-]")
        plots.legend_below(ax)
        row[0].set_yscale("log")
        row[0].set_title(f"{name}: final state error")
        row[1].set_title(f"{name}: time to reach s*")
        paper = "\n(the paper's numbers are its 7-DoF Panda's)" if name != "panda" else ""
        row[2].set_title(f"{name}: time ratio LA / LA+SA{paper}")

    title = "Fig. sim1: users of fixed expertise"
    return sweep.sim_figure(table, assistance, title, (3, (16, 6.4), draw), ["method", "beta"])


def _side(low: float, high: float, at: float, below: str, above: str) -> str:
    """``below`` or ``above`` when the interval lies on one side of ``at``; otherwise that it contains it."""
    return {"below": below, "above": above}.get(side_of((low, high), at), f"its interval contains {at:g}")


def findings(claims: list[Claim], robot: str, assistance: str = "point") -> str:
    """Fig. sim1's time ratios and gaps on ``robot``, from its claims under ``assistance``, in Markdown."""
    rows = {c.id: c for c in claims if c.robot == robot and c.assistance == assistance}
    ratio, gap = rows["sim1.time_ratio"], rows["sim1.gap_narrows"]
    r75, r1000 = sweep.number(ratio, "ratio_75"), sweep.number(ratio, "ratio_1000")
    e75, t75 = sweep.number(gap, "error_gap_75"), sweep.number(gap, "time_gap_75")
    slower, faster = "LA is slower than LA+SA", "LA is faster than LA+SA"
    said = sweep.interval_text
    return "\n".join(
        [
            f"- **Time ({robot}, {ratio.n_users} users per point).** LA's time over LA+SA's is "
            f"{said(*r75, '{:.2f}')} at β = 75 ({_side(r75[1], r75[2], 1.0, faster, slower)}) and "
            f"{said(*r1000, '{:.2f}')} at β = 1000 ({_side(r1000[1], r1000[2], 1.0, faster, slower)}); "
            f"the claim reads *{ratio.reproduced}*.",
            f"- **The gap at β = 75.** The final-error gap LA − LA+SA is {said(*e75)} "
            f"({_side(e75[1], e75[2], 0.0, 'LA+SA ends farther from s*', 'LA+SA ends closer to s*')}); "
            f"the time gap (ratio − 1) is {said(*t75, '{:.2f}')} "
            f"({_side(t75[1], t75[2], 0.0, 'LA+SA is slower', 'LA+SA is faster')}); "
            f"the claim reads *{gap.reproduced}*.",
        ]
    )
