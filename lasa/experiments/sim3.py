"""Fig. sim3: users who learn within the task (Sec. V-C): rationality grows from random, beta(t) = m t,
for a fast and a slow learner. Notebook ``06_learning_users``."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from lasa.base.config import ControlConfig, Positive, PositiveInt
from lasa.base.errors import ConfigError
from lasa.evidence.claims import Claim
from lasa.evidence.metrics import normalized_error
from lasa.evidence.plots import band_handle, legend_below, method_lineplot, paper_handle
from lasa.evidence.verdicts import USER, group_means
from lasa.experiments import sweep
from lasa.people.rollout import Trajectories
from lasa.world.goals import GoalTask

NAME = "sim3_learning_users"
COLUMNS = ("robot", "method", "learner", "slope", USER, "t", "error", "assistance", "look")
LEARNERS = ("fast", "slow")


@dataclasses.dataclass(frozen=True)
class Config(sweep.SweepConfig):
    """Fig. sim3: users who learn within the task, beta(t) = m t from beta = 0."""

    fast_slope: Positive = 20.0  # m of the fast learner, beta(t) = m t [1/(rad^2 step)]
    slow_slope: Positive = 2.0  # m of the slow learner: below fast_slope [1/(rad^2 step)]
    horizon: PositiveInt = 200  # control steps per episode [-]
    record_every: PositiveInt = 5  # record the error every this many steps: divides horizon [steps]

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.fast_slope > self.slow_slope:
            raise ConfigError(
                f"fast_slope must be above slow_slope ({self.slow_slope!r}): the fast learner learns "
                f"faster, got {self.fast_slope!r}"
            )
        sweep.check_record_every(self.record_every, self.horizon)


def run(
    decoders: sweep.Decoders,
    task: GoalTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = False,
    look: int = 0,
    assistance: tuple[str, ...] | None = None,
) -> tuple[pd.DataFrame, Trajectories]:
    """Fig. sim3 for one look's users: one row per (episode, recorded step), and the trajectories."""

    def learning(learners: list[tuple[str, float]], goal: np.ndarray, _: np.ndarray) -> dict[str, np.ndarray]:
        return {"beta0": np.zeros(len(goal)), "slope": np.array([m for _, m in learners], dtype=float)}

    learners = (("fast", float(config.fast_slope)), ("slow", float(config.slow_slope)))  # (name, slope m)
    ran = sweep.run_look(decoders, task, control, config, learners, learning, progress, look, assistance)
    errors = normalized_error(ran.traj.states, ran.users.target[None], task.goal_distance)  # (T+1, U)
    steps = np.arange(0, config.horizon + 1, config.record_every)
    k = len(steps)
    return pd.DataFrame(
        {
            "robot": task.robot.name,
            "method": np.repeat(ran.method, k),
            "learner": np.repeat(np.array([name for name, _ in ran.condition]), k),
            "slope": np.repeat(ran.users.slope, k),
            USER: np.repeat(ran.user, k),
            "t": np.tile(steps, len(ran.user)),
            "error": errors[steps].T.ravel(),
            "assistance": np.repeat(ran.member, k),
            "look": look,
        }
    ), ran.traj


def episode_means(frame: pd.DataFrame) -> pd.DataFrame:
    """One row per episode: its mean error over the recorded steps (the claim's measure)."""
    keys = ["robot", "method", "learner", USER, "assistance", "look"]
    return frame.groupby(keys, sort=False, as_index=False).error.mean()


def claims(frame: pd.DataFrame) -> list[Claim]:
    """Evaluate Fig. sim3's claim: entropy improves in-task performance of learning users."""
    mean = frame.groupby(["learner", "method", USER]).error.mean().groupby(["learner", "method"]).mean()
    learners = sorted(set(frame.learner))
    gain = {name: mean[name, "LA+SA"] - mean[name, "LA+SA+Entropy"] for name in learners}
    values = {f"gain_{name}": float(gain[name]) for name in learners}
    return [
        sweep.sim_claim(
            "sim3.entropy_learners",
            str(frame.robot.iloc[0]),
            values,
            claim="entropy improves in-task performance for both fast and slow learners",
            paper="LA+SA+Entropy below LA+SA in error over time, fast and slow",
            measured="gain of entropy, LA+SA minus LA+SA+Entropy (the interval is for the fast learner's): "
            + ", ".join(f"{name} {gain[name]:+.3f}" for name in learners)
            + "; "
            + "; ".join(
                f"{name}: mean error over the episode LA+SA {mean[name, 'LA+SA']:.3f}, "
                f"LA+SA+Entropy {mean[name, 'LA+SA+Entropy']:.3f}, LA {mean[name, 'LA']:.3f}"
                for name in learners
            ),
        )
    ]


def boot_values(frame: pd.DataFrame, counts: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """:func:`claims`' numbers in every resample of users (``counts``, :mod:`lasa.evidence.verdicts`)."""
    mean = group_means(frame, ["learner", "method"], "error", counts)
    learners = sorted({name for name, _ in mean})
    gains = {f"gain_{n}": mean[(n, "LA+SA")] - mean[(n, "LA+SA+Entropy")] for n in learners}
    return {"sim3.entropy_learners": gains}


PAPER_SHAPE = "paper: LA+SA+Entropy below LA+SA over time"  # Fig. sim3, fast and slow (Sec. V-C)


def plot(table: pd.DataFrame, assistance: str = "point") -> Figure:
    """Fig. sim3 under member ``assistance``: per robot, the fast and the slow learner's error over time per
    method, with bands at the verdicts' level."""

    def draw(name: str, part: pd.DataFrame, row: np.ndarray) -> None:
        for ax, learner in zip(row, LEARNERS, strict=True):
            one = part[part.learner == learner]
            method_lineplot(one, "t", "error", ax, level=sweep.LEVEL)
            ax.set_title(f"{name}: {learner} learner: beta(t) = {one.slope.iloc[0]:g} t")
            ax.set_xlabel("time step t")
            ax.set_ylabel("state error (normalised)")
            mean = one.groupby(["method", USER]).error.mean().groupby("method").mean()
            for handle in ax.get_legend_handles_labels()[0]:
                if (method := handle.get_label()) in mean:
                    handle.set_label(f"{method}: mean over the episode {mean[method]:.3f}")
            legend_below(ax, [band_handle(sweep.LEVEL), paper_handle(PAPER_SHAPE)])

    title, keys = "Fig. sim3: users who learn", ["method", "learner", "t"]
    return sweep.sim_figure(table, assistance, title, (2, (11, 5.2), draw), keys, "curve")


def findings(claims: list[Claim], head: pd.DataFrame) -> str:
    """Fig. sim3's result on ``head``'s robot and member (its rows and LA's) as Markdown bullets."""
    claim = sweep.headline_claim(claims, "sim3.entropy_learners", head)
    mean = head.groupby(["learner", "method", USER]).error.mean().groupby(["learner", "method"]).mean()
    lines = []
    learners = sorted(set(head.learner))
    for learner in learners:
        gain, low, high = sweep.number(claim, f"gain_{learner}")
        word = "lowers" if gain > 0 else "raises"
        said = sweep.interval_text(gain, low, high, "{:+.3f}")
        sure = "" if low > 0 or high < 0 else "; its interval contains 0"
        errors = ", ".join(f"{m} {mean[learner, m]:.3f}" for m in ("LA", "LA+SA", "LA+SA+Entropy"))
        lines.append(
            f"- **The {learner} learner.** Mean error over the episode: {errors}. The entropy term {word} "
            f"LA+SA's (gain LA+SA − LA+SA+Entropy {said}{sure})."
        )
    lower = [learner for learner in learners if sweep.number(claim, f"gain_{learner}")[0] > 0]
    if not lower:
        which = "neither learner"
    elif len(lower) == len(learners):
        which = "every learner" if len(learners) > 2 else "both learners"
    else:
        which = f"the {' and '.join(lower)} learner only"
    lines.append(
        f"- **The claim ({claim.robot}, {claim.n_users} users per point)** reads *{claim.reproduced}*: "
        f"the term lowers the mean error for {which}."
    )
    return "\n".join(lines)
