"""Fig. sim2: users who change their mind (Sec. V-B): near-optimal users aim at the wrong cup for the
first N steps, then at the right one. Notebook ``05_changing_goals``."""

from __future__ import annotations

import dataclasses
import textwrap

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from lasa.base.config import ControlConfig, NonNegative, NonNegativeInt, Positive, PositiveInt, check_list
from lasa.base.errors import ConfigError
from lasa.evidence import plots
from lasa.evidence.claims import Claim
from lasa.evidence.metrics import confidence, normalized_error
from lasa.evidence.rules import rule
from lasa.evidence.verdicts import USER, group_means
from lasa.experiments import sweep
from lasa.people.rollout import Trajectories
from lasa.world.goals import GoalTask

NAME = "sim2_change_of_mind"
COLUMNS = (
    "robot",
    "method",
    "change_step",
    USER,
    "final_error",
    "confidence",
    "success",
    "goal",
    "theta",
    "assistance",
    "look",
)


@dataclasses.dataclass(frozen=True)
class Config(sweep.SweepConfig):
    """Fig. sim2: users who aim at the wrong cup until step N, then at the right one."""

    change_steps: tuple[NonNegativeInt, ...] = (0, 20, 40, 60, 80, 100, 120)  # N values [steps]
    beta: NonNegative = 1000.0  # rationality before and after the change (near optimal) [1/rad^2]
    settle: PositiveInt = 150  # steps after the largest N before the episode ends [steps]
    success: Positive = 0.1  # normalised final error that counts as reaching the right cup [-]

    def __post_init__(self) -> None:
        super().__post_init__()
        why = "the claims compare the smallest N with the largest"
        check_list("change_steps", self.change_steps, at_least=2, ascending=True, why=why)

    @property
    def horizon(self) -> int:
        """Steps per episode: the largest N plus the settling time."""
        return int(max(self.change_steps)) + self.settle


def run(
    decoders: sweep.Decoders,
    task: GoalTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = False,
    look: int = 0,
    assistance: tuple[str, ...] | None = None,
) -> tuple[pd.DataFrame, Trajectories]:
    """Fig. sim2: final error and confidence in the true cup against the change step N, per episode."""

    def changing(change: list[int], goal: np.ndarray, theta: np.ndarray) -> dict[str, np.ndarray]:
        first = task.target(wrong_goal(goal, task.n_goals), theta)
        n = len(goal)
        return {
            "beta0": np.full(n, config.beta),
            "slope": np.zeros(n),
            "first_target": first,
            "change_step": np.array(change, dtype=int),
        }

    ran = sweep.run_look(
        decoders, task, control, config, config.change_steps, changing, progress, look, assistance
    )
    users, traj = ran.users, ran.traj
    final = normalized_error(traj.states[-1], users.target, task.goal_distance)
    return pd.DataFrame(
        {
            "robot": task.robot.name,
            "method": ran.method,
            "change_step": users.change_step,
            USER: ran.user,
            "final_error": final,
            "confidence": confidence(traj.beliefs[-1], users.goal),
            "goal": users.goal,
            "theta": users.theta,
            "success": final <= config.success,
            "assistance": ran.member,
            "look": look,
        }
    ), traj


def claims(frame: pd.DataFrame) -> list[Claim]:
    """Evaluate Fig. sim2's claims: LA+SA is trapped at the wrong cup, LA+SA+Entropy is not."""
    robot = str(frame.robot.iloc[0])
    lo, hi = int(frame.change_step.min()), int(frame.change_step.max())
    by = ["method", "change_step"]
    rate, err, conf = (frame.groupby(by)[c].mean() for c in ("success", "final_error", "confidence"))
    sa_lo, sa_hi, en_hi = rate["LA+SA", lo], rate["LA+SA", hi], rate["LA+SA+Entropy", hi]
    values = {
        "error_growth": float(err["LA+SA", hi] - err["LA+SA", lo]),
        "confidence_drop": float(conf["LA+SA", lo] - conf["LA+SA", hi]),
    }
    return [
        sweep.sim_claim(
            "sim2.sa_trapped",
            robot,
            values,
            claim="LA+SA cannot escape the wrong goal as N grows",
            paper="LA+SA's final error grows and its confidence falls as N grows",
            measured=f"LA+SA's mean final error {err['LA+SA', lo]:.3f} at N={lo} -> {err['LA+SA', hi]:.3f} "
            f"at N={hi} (the interval is for this growth); mean confidence in the true cup "
            f"{conf['LA+SA', lo]:.3f} -> {conf['LA+SA', hi]:.3f}; it reaches the right cup in "
            f"{sa_lo:.0%} -> {sa_hi:.0%} of episodes",
        ),
        sweep.sim_claim(
            "sim2.entropy_escapes",
            robot,
            {"success_entropy": float(en_hi), "margin": float(en_hi - sa_hi)},
            claim="LA+SA+Entropy can escape the wrong goal",
            paper="LA+SA+Entropy users switch goals",
            measured=f"LA+SA+Entropy reaches the right cup in {en_hi:.0%} at N={hi} (LA+SA {sa_hi:.0%}); "
            f"mean final error {err['LA+SA+Entropy', hi]:.3f} vs {err['LA+SA', hi]:.3f}",
        ),
    ]


def boot_values(frame: pd.DataFrame, counts: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """:func:`claims`' numbers in every resample of users (``counts``, :mod:`lasa.evidence.verdicts`)."""
    lo, hi = int(frame.change_step.min()), int(frame.change_step.max())
    by = ["method", "change_step"]
    rate, err, conf = (group_means(frame, by, c, counts) for c in ("success", "final_error", "confidence"))
    sa_hi, en_hi = rate[("LA+SA", hi)], rate[("LA+SA+Entropy", hi)]
    return {
        "sim2.sa_trapped": {
            "error_growth": err[("LA+SA", hi)] - err[("LA+SA", lo)],
            "confidence_drop": conf[("LA+SA", lo)] - conf[("LA+SA", hi)],
        },
        "sim2.entropy_escapes": {"success_entropy": en_hi, "margin": en_hi - sa_hi},
    }


METRIC_LABELS = {
    "final_error": "final state error (normalised)",
    "success": "success: share that reach the true cup",
    "confidence": "confidence b(g*) at the end",
}
# what the paper's Fig. sim2 shows, per panel (Sec. V-B), drawn as a labelled legend entry
PAPER_SHAPES = {
    "final_error": "paper: LA+SA's error grows with N; LA+SA+Entropy stays low",
    "success": "paper: LA+SA users cannot escape the wrong cup as N grows; LA+SA+Entropy users switch",
    "confidence": "paper: LA+SA's confidence in the true cup falls with N; LA+SA+Entropy's stays high",
}


def plot(table: pd.DataFrame, assistance: str = "point") -> Figure:
    """Fig. sim2 under member ``assistance``: per robot, final error, success and confidence in the true
    cup against the change step N, with bands at the verdicts' level."""

    def draw(name: str, part: pd.DataFrame, row: np.ndarray) -> None:
        part, n_max = part.assign(success=part.success.astype(float)), int(part.change_step.max())
        titles = ("final state error", "success (sim2.entropy_escapes' number)", "confidence in the true cup")
        for ax, metric, title in zip(row, METRIC_LABELS, titles, strict=True):
            plots.method_lineplot(part, "change_step", metric, ax, level=sweep.LEVEL)
            ax.set_xlabel("change of mind at step N")
            ax.set_ylabel(METRIC_LABELS[metric])
            if metric == "success":  # short dashed marks at the largest N: LA+SA+Entropy's success thresholds
                rule_id = "sim2.entropy_escapes"
                limits = {q.name: q.thresholds for q in rule(rule_id).quantities}["success_entropy"]
                for i, level in enumerate(limits):
                    label = f"{rule_id}: LA+SA+Entropy's threshold at N = {n_max}" if i == 0 else None
                    color = plots.METHOD_COLORS["LA+SA+Entropy"]
                    ax.plot(
                        [n_max * 0.93, n_max * 1.07], [level, level], "--", color=color, lw=1.5, label=label
                    )
            if metric != "final_error":  # a share or a probability: [0, 1] and a margin for the markers
                ax.set_ylim(-0.02, 1.02)
            paper = plots.paper_handle(textwrap.fill(PAPER_SHAPES[metric], 56))
            plots.legend_below(ax, [plots.band_handle(sweep.LEVEL), paper])
            ax.set_title(f"{name}: {title}")

    title = "Fig. sim2: users who change their mind"
    return sweep.sim_figure(table, assistance, title, (3, (16, 5.6), draw), ["method", "change_step"])


STILL = 0.01  # an arm that moves less than this (normalised) in its last STILL_STEPS steps stands still [-]
STILL_STEPS = 50  # [steps]


def wrong_goal(goal: int | np.ndarray, n_goals: int) -> int | np.ndarray:
    """The cup a user who wants ``goal`` (one or many) aims at before the change: ``(goal + 1) % n_goals``."""
    goals = np.asarray(goal)
    if goals.size and (goals.min() < 0 or goals.max() >= n_goals):
        raise ConfigError(f"goal must be in [0, {n_goals}), got {goal}")
    wrong = (goals + 1) % n_goals
    return int(wrong) if wrong.ndim == 0 else wrong


def after_the_change(frame: pd.DataFrame, traj: Trajectories, task: GoalTask, success: float) -> pd.DataFrame:
    """Per episode of ``frame`` (the rows of ``traj``), what happens after the change of mind at step N.

    Adds ``steps_left``, ``away_at_n`` (from home), ``belief_at_n`` (b(g*)), ``turn`` and ``reach`` (steps
    after N until b(g*) > 0.5 and until the error is at most ``success``, NaN if never), ``still`` (moved
    less than :data:`STILL` in the last :data:`STILL_STEPS` steps) and ``wrong_error`` (to the wrong cup's
    grasp of the same preference); distances over the goal distance."""
    n_steps, goal = len(traj.states) - 1, frame.goal.to_numpy()
    rows = np.arange(len(frame))
    states, change = traj.states, frame.change_step.to_numpy()
    target = task.target(goal, frame.theta.to_numpy())
    error = normalized_error(states, target[None], task.goal_distance)  # (T+1, U)
    belief = traj.beliefs[:, rows, goal]  # (T+1, U)
    after = np.arange(n_steps + 1)[:, None] >= change[None]
    moved = np.linalg.norm(states[-1] - states[-1 - min(STILL_STEPS, n_steps)], axis=-1)
    wrong = task.target(wrong_goal(goal, task.n_goals), frame.theta.to_numpy())
    return frame.assign(
        steps_left=n_steps - change,
        away_at_n=np.linalg.norm(states[change, rows] - task.start, axis=-1) / task.goal_distance,
        belief_at_n=belief[change, rows],
        turn=_first(after & (belief > 0.5)) - change,
        reach=_first(after & (error <= success)) - change,
        still=moved / task.goal_distance < STILL,
        wrong_error=normalized_error(states[-1], wrong, task.goal_distance),
    )


def _first(mask: np.ndarray) -> np.ndarray:
    """Per column of ``mask`` (T, U), the first row that is True; NaN where none is."""
    return np.where(mask.any(axis=0), mask.argmax(axis=0), np.nan)


def failures(after: pd.DataFrame) -> list[str]:
    """One line per (method, N) where under half the users succeed: what the episodes show."""
    lines = []
    for (method, n), part in after.groupby(["method", "change_step"]):
        if part.success.mean() >= 0.5:
            continue
        lost, left = part[~part.success.astype(bool)], int(part.steps_left.iloc[0])
        lines.append(
            f"{method}, N = {n}: {part.success.mean():.0%} succeed, {left} steps left. "
            f"At step N the arm is {part.away_at_n.median():.2f} from home, "
            f"b(g*) = {part.belief_at_n.median():.1e}; b(g*) passes 0.5 after {_median(part.turn, left)} "
            f"steps ({part.turn.isna().mean():.0%} never), the error reaches the tolerance after "
            f"{_median(part.reach, left)}. The unsuccessful end at error {lost.final_error.median():.2f} "
            f"with b(g*) = {lost.confidence.median():.6f}, {lost.still.mean():.0%} standing still."
        )
    return lines


def escape_times(after: pd.DataFrame) -> pd.DataFrame:
    """Median steps after N until b(g*) > 0.5 (``turn``) and until success (``reach``), per method and N."""
    times = after.fillna({"turn": np.inf, "reach": np.inf})
    out = times.groupby(["method", "change_step"])[["turn", "reach"]].median()
    return out.join(after.groupby(["method", "change_step"])[["steps_left", "success"]].mean())


def _median(values: pd.Series, left: int) -> str:
    """The median of ``values`` (NaN: never) as a whole number, or "more than ``left``"."""
    median = values.fillna(np.inf).median()
    return f"more than {left}" if not np.isfinite(median) else f"{median:.0f}"


def _prob(p: float) -> str:
    """A probability with two significant digits of its distance to 0 or 1 (below 1e-4: ``3.4e-06``)."""
    near = min(p, 1.0 - p)
    if near <= 0.0:
        return f"{p:.0f}"
    if p < 1e-4:
        return f"{p:.1e}"
    digits = max(2, int(np.ceil(-np.log10(near))) + 1)
    return f"{p:.{digits}f}".rstrip("0").rstrip(".")


def claim_sentence(claim: Claim, steps: tuple[int, int]) -> str:
    """sim2.sa_trapped's two parts as a Markdown bullet: LA+SA's error and confidence from N = ``steps``."""
    if claim.id != "sim2.sa_trapped":
        raise ConfigError(f"claim_sentence reads sim2.sa_trapped, got {claim.id!r}")
    parts = []
    for name, up, down in (("error_growth", "grows", "falls"), ("confidence_drop", "falls", "rises")):
        value, low, high = sweep.number(claim, name)
        holds = value > 0
        sure = "" if low > 0 or high < 0 else " (its interval contains 0)"
        if not holds:  # the same interval, said the other way round
            up, value, low, high = down, -value, -high, -low
        parts.append((holds, f"{up} by {sweep.interval_text(value, low, high, '{:.2f}')}{sure}"))
    count = ("neither part holds", "one part holds", "both parts hold")[sum(h for h, _ in parts)]
    return (
        f"- **The claim, as the paper states it ({claim.robot}, {claim.n_users} users per point).** From "
        f"N = {steps[0]} to N = {steps[1]} LA+SA's mean final error {parts[0][1]}, and its mean confidence "
        f"in the true cup {parts[1][1]}: {count}; the claim reads *{claim.reproduced}*."
    )


def _rates(head: pd.DataFrame) -> pd.DataFrame:
    """Success share per N (rows) and method (columns)."""
    return head.assign(success=head.success.astype(float)).pivot_table(
        index="change_step", columns="method", values="success", aggfunc="mean"
    )


def success_sentence(head: pd.DataFrame) -> str:
    """Each method's success share at every N in ``head`` (one member's rows and LA's), and its trend."""
    rates = _rates(head)
    lines = []
    for m in rates.columns:  # how the share moves from the first N to the last (in whole percent)
        first = rates[m].iloc[0]
        last = rates[m].iloc[-1]
        a = f"{first:.0%}"
        b = f"{last:.0%}"
        word = "falls" if last < first else "rises"
        trend = f"stays at {a}" if a == b else f"{word} from {a} to {b}"
        lines.append(f"{m} {', '.join(f'{r:.0%}' for r in rates[m])} ({trend})")
    return f"- **Success at N = {', '.join(str(n) for n in rates.index)}.** " + "; ".join(lines) + "."


def belief_sentence(head: pd.DataFrame, after: pd.DataFrame, tolerance: float, method: str = "LA+SA") -> str:
    """Where ``method``'s belief ends (``head``: one member's rows and LA's, every look), and what its
    users who fail at the largest N do (``after``: :func:`after_the_change`'s, first look)."""
    conf = head[head.method == method].groupby("change_step").confidence
    median, n_max = conf.median(), int(head.change_step.max())
    last = head[(head.method == method) & (head.change_step == n_max)].confidence
    share = f"{(last < 0.5).mean():.0%} of its users at N = {n_max} end with b(g*) below one half"
    mean = f"at N = {n_max} the mean end confidence is {_prob(last.mean())}, median {_prob(last.median())}"
    if median.iloc[-1] > 0.5:
        head_ = (
            f"- **{method}'s belief follows the user.** Its median end confidence in the true cup is at "
            f"least {_prob(median.min())} at every N; {mean} ({share})."
        )
    else:
        above = median[median > 0.5].index
        since = median.index[median.index > above.max()][0] if len(above) else median.index[0]
        head_ = (
            f"- **{method}'s belief stays with the wrong cup.** From N = {since} on its median end "
            f"confidence in the true cup is at most {_prob(median[median.index >= since].max())}; "
            f"{mean} ({share})."
        )
    # where its unsuccessful users end at the largest N, and how long the belief takes to turn
    part = after[(after.method == method) & (after.change_step == n_max)]
    if part.empty:
        raise ConfigError(f"no {method} episodes at N = {n_max} in the after-the-change rows")
    lost, left = part[~part.success.astype(bool)], int(part.steps_left.iloc[0])
    turn = after[after.change_step == n_max].fillna({"turn": np.inf}).groupby("method").turn.median()
    times = ", ".join(
        f"in {t:.0f} steps under {m}" if np.isfinite(t) else f"never under {m}" for m, t in turn.items()
    )
    won = after[(after.method == method) & after.success.astype(bool)].reach
    reach = (
        f"{method}'s successful users reach the true cup a median {won.median():.0f} steps after N "
        f"(over every N), {'more' if won.median() > left else 'fewer'} than the {left} left at N = {n_max}"
        if len(won)
        else f"no {method} user reaches the true cup"
    )
    where = f"{head_} After N = {n_max} the median user's b(g*) passes 0.5 {times}; {reach}."
    if lost.empty:
        return f"{where} Every {method} user succeeds at N = {n_max}."
    near, err = int((lost.wrong_error <= tolerance).sum()), lost.final_error
    return (
        f"{where} Its {len(lost)} unsuccessful users there (of {len(part)}) end at final errors "
        f"{err.min():.2f} to {err.max():.2f} (median {err.median():.2f}); {near} of them end within "
        f"{tolerance:g} of the wrong cup's grasp, and {lost.still.mean():.0%} stand still."
    )


def dip_sentence(head: pd.DataFrame, after: pd.DataFrame, method: str = "LA") -> str:
    """Where ``method``'s success is lowest (LA's dip at a small N, by default), and what its unsuccessful
    users there show (``head`` and ``after`` as in :func:`belief_sentence`)."""
    rate = _rates(head)[method]
    n, n_max = int(rate.idxmin()), int(rate.index.max())
    part = head[(head.method == method) & (head.change_step == n)]
    lost = part[~part.success.astype(bool)]
    first = after[(after.method == method) & (after.change_step == n)]
    where = "at the largest N" if n == n_max else f"at N = {n}, not at the largest N"
    said = (
        f"- **{method}'s success is lowest {where}:** {int(part.success.sum())} of {len(part)} users succeed"
    )
    if lost.empty or first.empty:
        return said + "."
    err = lost.final_error
    return (
        f"{said}, with {int(first.steps_left.iloc[0])} steps left. The unsuccessful end at final errors "
        f"{err.min():.2f} to {err.max():.2f} (mean {err.mean():.2f}) with an end confidence in the true "
        f"cup of at most {_prob(lost.confidence.max())}. At step N the arm is a median "
        f"{first.away_at_n.median():.2f} from home and b(g*) = {_prob(first.belief_at_n.median())}; "
        f"{first[~first.success.astype(bool)].still.mean():.0%} of the unsuccessful stand still at the end."
    )


def findings(claims: list[Claim], head: pd.DataFrame, after: pd.DataFrame, tolerance: float) -> str:
    """Fig. sim2's results on one robot and member as Markdown bullets (``head``, ``after`` as in
    :func:`belief_sentence`; ``tolerance``: ``Config.success``)."""
    steps = (int(head.change_step.min()), int(head.change_step.max()))
    return "\n".join(
        [
            claim_sentence(sweep.headline_claim(claims, "sim2.sa_trapped", head), steps),
            success_sentence(head),
            belief_sentence(head, after, tolerance),
            dip_sentence(head, after),
        ]
    )
