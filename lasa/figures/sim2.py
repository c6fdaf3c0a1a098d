"""Fig. sim2: users who change their mind (Sec. V-B).

Near-optimal users aim at the wrong cup for the first N steps, then at the right one.
Without the entropy term (LA+SA) the paper finds them trapped as N grows; with it
(LA+SA+Entropy) they escape. Notebook ``05_changing_goals``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lasa.base.config import (
    ControlConfig,
    NonNegative,
    NonNegativeInt,
    Positive,
    PositiveInt,
)
from lasa.base.errors import ConfigError
from lasa.evidence.claims import Claim
from lasa.evidence.metrics import confidence, normalized_error
from lasa.evidence.plots import method_lineplot, paper_note, robot_rows, wrap_to
from lasa.evidence.rules import rule
from lasa.evidence.verdicts import (
    USER,
    Design,
    block_seed,
    block_users,
    group_means,
    member_frame,
)
from lasa.figures.common import (
    Decoders,
    SweepConfig,
    episodes,
    members_of,
    run_population,
    sweep_grid,
)
from lasa.people.rollout import Trajectories
from lasa.people.users import UserPopulation
from lasa.world.goals import GoalTask

__all__ = ["NAME", "COLUMNS", "Config", "run", "claims", "boot_values", "plot", "plot_metric"]

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
DPI = 150


@dataclasses.dataclass(frozen=True)
class Config(SweepConfig):
    """Fig. sim2: users who aim at the wrong cup until step N, then at the right one."""

    change_steps: tuple[NonNegativeInt, ...] = (0, 20, 40, 60, 80, 100, 120)  # N values [steps]
    beta: NonNegative = 1000.0  # rationality before and after the change (near optimal) [1/rad^2]
    settle: PositiveInt = 150  # steps after the largest N before the episode ends [steps]
    success: Positive = 0.1  # normalised final error that counts as reaching the right cup [-]

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.change_steps:
            raise ConfigError("change_steps must not be empty")

    @property
    def horizon(self) -> int:
        """Steps per episode: the largest N plus the settling time."""
        return int(max(self.change_steps)) + self.settle


def run(
    decoders: Decoders,
    task: GoalTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = False,
    look: int = 0,
    members: tuple[str, ...] | None = None,
) -> tuple[pd.DataFrame, Trajectories]:
    """Fig. sim2: final error and confidence in the true cup against the change step N.

    Each user wants cup g* with preference theta. For the steps t < N they aim at the
    *other* cup with the same preference, from step N on at g*; both near-optimally.

    Args:
        look: Which look's new users (:func:`lasa.evidence.verdicts.block_users`).
        members: The members the assisted methods run under; default every member of
            ``config.assistance``. The other arguments are :func:`lasa.figures.sim1.run`'s.

    Returns:
        One row per episode with the columns of :data:`COLUMNS` plus ``goal`` and
        ``theta`` (for the video); and the trajectories.
    """
    start, n_users = block_users(Design(config.users, config.block, config.cap), look)
    seed_ = block_seed(config.seed, look)
    goal, theta, noise = episodes(decoders, task, control, n_users, config.horizon, seed_)
    members = members_of(control, config.assistance) if members is None else members
    method, member, conditions, user = sweep_grid(config.methods, members, config.change_steps, n_users)
    change = np.array(conditions, dtype=int)
    wrong = (goal[user] + 1) % task.n_goals
    users = UserPopulation(
        goal=goal[user],
        theta=theta[user],
        target=task.target(goal[user], theta[user]),
        beta0=np.full(len(user), config.beta),
        slope=np.zeros(len(user)),
        stream=user,
        pilot=config.pilot,
        pilot_prob=config.pilot_prob,
        first_target=task.target(wrong, theta[user]),
        change_step=change,
    )
    traj = run_population(
        decoders, task, control, users, method, config.horizon, noise, progress, member, seed_
    )
    final = normalized_error(traj.states[-1], users.target, task.goal_distance)
    frame = pd.DataFrame(
        {
            "robot": task.robot.name,
            "method": method,
            "change_step": change,
            USER: start + user,
            "final_error": final,
            "confidence": confidence(traj.beliefs[-1], users.goal),
            "goal": users.goal,
            "theta": users.theta,
            "success": final <= config.success,
            "assistance": member,
            "look": look,
        }
    )
    return frame, traj


def claims(frame: pd.DataFrame) -> list[Claim]:
    """Evaluate Fig. sim2's claims: LA+SA is trapped at the wrong cup, LA+SA+Entropy is not.

    Success is a final error within the frame's ``success`` criterion (the config's
    tolerance, 0.1 of the goal distance by default), measured at the largest N.

    - *LA+SA cannot escape the wrong goal as N grows*, in the paper's two parts: LA+SA's
      mean final error grows from the smallest N to the largest, and its mean confidence
      in the true cup falls; ``yes`` if both hold, ``partly`` if one, else ``no``.
    - *LA+SA+Entropy can*: ``yes`` if its success rate at the largest N is at least 80%
      and at least 20 points above LA+SA's; ``partly`` if it is above LA+SA's; else ``no``.
    """
    robot = str(frame.robot.iloc[0])
    lo, hi = int(frame.change_step.min()), int(frame.change_step.max())
    rate = frame.groupby(["method", "change_step"]).success.mean()
    err = frame.groupby(["method", "change_step"]).final_error.mean()
    conf = frame.groupby(["method", "change_step"]).confidence.mean()
    sa_lo, sa_hi = rate["LA+SA", lo], rate["LA+SA", hi]
    en_hi = rate["LA+SA+Entropy", hi]
    values1 = {
        "error_growth": float(err["LA+SA", hi] - err["LA+SA", lo]),
        "confidence_drop": float(conf["LA+SA", lo] - conf["LA+SA", hi]),
    }
    values2 = {"success_entropy": float(en_hi), "margin": float(en_hi - sa_hi)}
    v1 = rule("sim2.sa_trapped").verdict(values1)
    v2 = rule("sim2.entropy_escapes").verdict(values2)
    return [
        Claim(
            id="sim2.sa_trapped",
            claim="LA+SA cannot escape the wrong goal as N grows",
            figure="sim2",
            paper="LA+SA's final error grows and its confidence falls as N grows",
            values=values1,
            measured=(
                f"LA+SA's mean final error {err['LA+SA', lo]:.3f} at N={lo} -> {err['LA+SA', hi]:.3f} "
                f"at N={hi} (the interval is for this growth); mean confidence in the true cup "
                f"{conf['LA+SA', lo]:.3f} -> {conf['LA+SA', hi]:.3f}; it reaches the right cup in "
                f"{sa_lo:.0%} -> {sa_hi:.0%} of episodes"
            ),
            reproduced=v1,
            note="",
            robot=robot,
        ),
        Claim(
            id="sim2.entropy_escapes",
            claim="LA+SA+Entropy can escape the wrong goal",
            figure="sim2",
            paper="LA+SA+Entropy users switch goals",
            values=values2,
            measured=(
                f"LA+SA+Entropy reaches the right cup in {en_hi:.0%} at N={hi} (LA+SA {sa_hi:.0%}); "
                f"mean final error {err['LA+SA+Entropy', hi]:.3f} vs {err['LA+SA', hi]:.3f}"
            ),
            reproduced=v2,
            note="",
            robot=robot,
        ),
    ]


def boot_values(frame: pd.DataFrame, counts: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """:func:`claims`' numbers in every resample of users (``counts``, :mod:`lasa.evidence.verdicts`)."""
    lo, hi = int(frame.change_step.min()), int(frame.change_step.max())
    rate = group_means(
        frame.assign(success=frame.success.astype(float)), ["method", "change_step"], "success", counts
    )
    err = group_means(frame, ["method", "change_step"], "final_error", counts)
    conf = group_means(frame, ["method", "change_step"], "confidence", counts)
    sa_hi, en_hi = rate[("LA+SA", hi)], rate[("LA+SA+Entropy", hi)]
    return {
        "sim2.sa_trapped": {
            "error_growth": err[("LA+SA", hi)] - err[("LA+SA", lo)],
            "confidence_drop": conf[("LA+SA", lo)] - conf[("LA+SA", hi)],
        },
        "sim2.entropy_escapes": {"success_entropy": en_hi, "margin": en_hi - sa_hi},
    }


METRIC_LABELS = {"final_error": "final state error (normalised)", "confidence": "confidence b(g*) at the end"}


# what the paper's Fig. sim2 shows, per panel (Sec. V-B), drawn as a labelled note
PAPER_SHAPES = {
    "final_error": "paper: LA+SA's error grows with N; LA+SA+Entropy stays low",
    "confidence": "paper: LA+SA's confidence in the true cup falls with N; LA+SA+Entropy's stays high",
}


def plot_metric(frame: pd.DataFrame, metric: str, ax: Axes | None = None) -> Axes:
    """One panel: final error or confidence in the true cup against the change step N.

    The paper's shape (:data:`PAPER_SHAPES`) is stated in a note above the curves.
    """
    ax = method_lineplot(frame, "change_step", metric, ax)
    ax.set_xlabel("change of mind at step N")
    ax.set_ylabel(METRIC_LABELS.get(metric, metric))
    if metric in PAPER_SHAPES:
        paper_note(ax, PAPER_SHAPES[metric], loc="upper center", width=44)
        ax.set_ylim(top=ax.get_ylim()[1] + 0.3 * np.ptp(ax.get_ylim()))  # room for the note
    return ax


def plot(table: pd.DataFrame, assistance: str = "point") -> Figure:
    """Fig. sim2: one row per robot present, final error and confidence against N.

    Args:
        table: Rows of every robot and member.
        assistance: The member drawn (the headline one); LA's rows are shared.
    """
    table = member_frame(table, assistance)
    fig, rows = robot_rows(table, 2, (11, 3.8))
    for name, part, row in rows:
        plot_metric(part, "final_error", ax=row[0])
        plot_metric(part, "confidence", ax=row[1])
        row[0].set_title(f"{name}: final state error")
        row[1].set_title(f"{name}: confidence in the true cup")
    n = int(table.groupby(["robot", "method", "change_step"]).size().max())
    fig.suptitle(
        wrap_to(
            f"Fig. sim2: users who change their mind, {n} users per point, assistance: {assistance}",
            fig.get_figwidth(),
        )
    )
    fig.tight_layout()
    return fig
