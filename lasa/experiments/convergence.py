r"""Sec. IV-A measured: the Lyapunov ball of LA+SA along simulated rollouts (notebook ``09_convergence``).

:math:`V = \tfrac12 \|e\|^2` falls if :math:`b^*\|e\| > \delta_\alpha := \frac{1-\alpha}{\alpha}\sigma_h
+ (1 - b^*)\sigma_r` (:func:`radius`), the paper's :math:`\delta` (T4) at :math:`\alpha = 0.5`; LA+SA runs at
``ControlConfig.alpha``, so both are measured. Derivation: ``docs/method-notes.md``.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lasa.base.config import (
    ASSISTANCE,
    ControlConfig,
    PositiveInt,
    Rationality,
    Seed,
    check_list,
    check_range,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.evidence.plots import robot_rows
from lasa.evidence.verdicts import USER
from lasa.experiments.sweep import check_assistance, check_record_every, draw_episodes
from lasa.method.decoder import ActionDecoder
from lasa.method.step import latent_grid
from lasa.people.rollout import rollout
from lasa.people.users import UserPopulation
from lasa.world.goals import GoalTask

NAME = "convergence"
# the contract's columns first, then what summary and plot read: ``error`` ||e(t)|| = ||g* - s(t)||
# [rad]; ``delta`` the paper's radius (alpha = 0.5), sigma_h + (1 - b*) sigma_r, and ``delta_alpha``
# the radius at the run's alpha, (1 - alpha)/alpha sigma_h + (1 - b*) sigma_r [rad/s]; ``v_dot`` the
# measured (V(t+1) - V(t)) / dt [rad^2/s], empty at t = T; ``v`` V(t) = ||e||^2 / 2 [rad^2]; ``belief``
# b(g*); ``sigma_r`` the largest distance to another goal [rad]; ``bound_holds`` b* ||e|| > delta_alpha
# (continuous-time V must fall) and ``bound_holds_half`` b* ||e|| > delta (the paper's condition, only
# sufficient at alpha = 0.5); ``v_rose`` v_dot > 0; ``slack`` the discretisation slack dt ||a||^2 / 2 of
# the commanded a [rad^2/s]; ``clipped`` the safety clip changed the step; ``error_target`` ||s* - s(t)||
# [rad]; ``goal``, ``theta`` the user's cup and grasp; then counts of steps in the row's window [t, next
# recorded t): all, with bound_holds, of those with V rising, rising beyond the slack, with
# bound_holds_half, of those with V rising
_STEP = tuple(  # measure's
    "error delta v_dot v belief sigma_r delta_alpha bound_holds bound_holds_half v_rose slack clipped "
    "error_target".split()
)
_COUNTS = ("steps", "bound_steps", "rises", "rises_beyond_slack", "bound_steps_half", "rises_half")
COLUMNS = ("robot", "assistance", "beta", USER, "t", *_STEP, "goal", "theta", *_COUNTS)
MEMBER_COLORS = {"point": "#1b9e77", "grasp_set": "#d95f02", "arbitrated": "#7570b3", "hindsight": "#e7298a"}


@dataclasses.dataclass(frozen=True)
class Config:
    """The Sec. IV-A ball along LA+SA rollouts of users of fixed rationality."""

    betas: tuple[Rationality, ...] = (10.0, 75.0, 1000.0)  # user rationalities, distinct, ascending [1/rad^2]
    assistance: tuple[str, ...] = ASSISTANCE  # members of lasa.method.assistance to run LA+SA under
    users: PositiveInt = 20  # simulated users per (member, beta) [-]
    horizon: PositiveInt = 200  # control steps per episode [-]
    record_every: PositiveInt = 10  # steps between recorded rows; event counts cover every step [steps]
    seed: Seed = 0  # seed of the users' cups, preferences and random streams [-]

    def __post_init__(self) -> None:
        validate(self)
        betas = check_list("betas", self.betas, ascending=True)
        object.__setattr__(self, "betas", tuple(float(b) for b in betas))
        object.__setattr__(self, "assistance", tuple(self.assistance))
        check_assistance(self.assistance)
        # the last step is recorded whatever record_every (run appends it): only the bound
        check_record_every(self.record_every, self.horizon, divides=False)


def radius(belief: np.ndarray, sigma_r: np.ndarray, sigma_h: float, alpha: float = 0.5) -> np.ndarray:
    """delta_alpha = (1 - alpha)/alpha sigma_h + (1 - b*) sigma_r; Eq. T4's delta at alpha = 0.5.

    ``belief`` b(g*) and ``sigma_r`` (the distance to the furthest other goal [rad]) broadcast;
    ``sigma_h`` bounds ||phi|| [rad/s]; ConfigError unless alpha is in (0, 1] (0 gives no bound).
    """
    check_range("alpha", alpha, 0.0, 1.0, low_open=True)
    return (1.0 - alpha) / alpha * sigma_h + (1.0 - np.asarray(belief)) * np.asarray(sigma_r)


def measure(
    states: np.ndarray,
    beliefs: np.ndarray,
    actions: np.ndarray,
    goal: np.ndarray,
    goals: np.ndarray,
    target: np.ndarray,
    dt: float,
    sigma_h: float,
    alpha: float,
) -> dict[str, np.ndarray]:
    """The Lyapunov quantities of a batch of trajectories, every step, shape (T+1, U).

    ``states`` s(t) (T+1, U, n), ``beliefs`` b(t) (T+1, U, G), ``actions`` the commanded a(t) before
    the safety clip (T, U, n), ``goal`` each user's cup (U,) into ``goals`` (G, n), ``target`` each
    user's s* (U, n), ``sigma_h`` the bound on ||phi||, ``alpha`` the run's blend weight in (0, 1].
    Returns the per-step columns of :data:`COLUMNS` (``error`` ... ``error_target``); quantities of
    a step (``v_dot``, ``slack``) are NaN at t = T, its flags False.
    """
    goal = np.asarray(goal)
    users = np.arange(len(goal))
    e = goals[goal][None] - states  # (T+1, U, n)
    error = np.linalg.norm(e, axis=-1)
    v = 0.5 * error**2
    b_star = beliefs[:, users, goal]
    dist = np.linalg.norm(goals[None, None] - states[:, :, None], axis=-1)  # (T+1, U, G)
    own = np.arange(len(goals))[None, None] == goal[None, :, None]
    others = np.where(own, -np.inf, dist)
    sigma_r = np.maximum(others.max(axis=-1), 0.0) if len(goals) > 1 else np.zeros_like(error)
    delta = radius(b_star, sigma_r, sigma_h, 0.5)
    delta_alpha = radius(b_star, sigma_r, sigma_h, alpha)
    pad = np.full((1, len(goal)), np.nan)
    v_dot = np.concatenate([(v[1:] - v[:-1]) / dt, pad])
    slack = np.concatenate([0.5 * dt * np.einsum("tun,tun->tu", actions, actions), pad])
    moved = states[1:] - states[:-1] - dt * actions
    clipped = np.concatenate([np.linalg.norm(moved, axis=-1) > 1e-9, np.zeros((1, len(goal)), bool)])
    holds = (b_star * error > delta_alpha, b_star * error > delta, v_dot > 0)
    values = (error, delta, v_dot, v, b_star, sigma_r, delta_alpha, *holds, slack, clipped)
    return dict(zip(_STEP, (*values, np.linalg.norm(target[None] - states, axis=-1)), strict=True))


def _window_counts(m: dict[str, np.ndarray], times: np.ndarray) -> dict[str, np.ndarray]:
    """Per recorded row, counts over the steps [times[i], times[i+1]) (none after the last)."""
    n_steps = m["v"].shape[0] - 1
    step = np.arange(n_steps + 1) < n_steps  # t = T is a state, not a step
    rose = m["v_rose"] & step[:, None]
    events = {
        "steps": np.broadcast_to(step[:, None], m["v"].shape),
        "bound_steps": m["bound_holds"] & step[:, None],
        "rises": m["bound_holds"] & rose,
        "rises_beyond_slack": m["bound_holds"] & (m["v_dot"] > m["slack"]) & step[:, None],
        "bound_steps_half": m["bound_holds_half"] & step[:, None],
        "rises_half": m["bound_holds_half"] & rose,
    }
    ends = np.append(times[1:], n_steps)
    out = {}
    for name, flags in events.items():
        cum = np.concatenate([np.zeros((1, flags.shape[1]), int), np.cumsum(flags, axis=0)])
        out[name] = cum[ends] - cum[times]
    return out


def run(
    decoder: ActionDecoder,
    task: GoalTask,
    control: ControlConfig,
    config: Config = Config(),
    progress: bool = False,
) -> pd.DataFrame:
    """LA+SA users of fixed rationality under each assistance member (replacing ``control.assistance``),
    with the T4 quantities: one row per (member, beta, user, recorded step), columns :data:`COLUMNS`;
    ``decoder`` is LA+SA's (``Workspace.sim_decoders()["base"]``); ConfigError if ``control.alpha`` is 0
    (LA alone: no assistance, no ball)."""
    if control.alpha <= 0:
        raise ConfigError("the Sec. IV-A bound needs alpha > 0 (LA+SA); control.alpha is 0")
    n_candidates = len(latent_grid(control.n_z, decoder.z_dim))
    goal, theta, noise = draw_episodes(task, config.users, config.horizon, n_candidates, config.seed)
    beta = np.repeat(np.asarray(config.betas), config.users)
    user = np.tile(np.arange(config.users), len(config.betas))
    target = task.target(goal[user], theta[user])
    users = UserPopulation(
        goal=goal[user], theta=theta[user], target=target, beta0=beta, slope=np.zeros(len(user)), user=user
    )
    times = np.unique(np.append(np.arange(0, config.horizon + 1, config.record_every), config.horizon))
    parts = []
    for assistance in config.assistance:
        ctl = dataclasses.replace(control, assistance=assistance)
        traj = rollout(decoder, task, users, control.alpha, ctl, config.horizon, noise, progress)
        bound = (control.dt, control.action_scale, control.alpha)
        m = measure(traj.states, traj.beliefs, traj.actions, users.goal, task.goals, target, *bound)
        per_user = {"beta": beta, USER: user, "goal": users.goal, "theta": users.theta}
        cols = {"robot": task.robot.name, "assistance": assistance, "t": np.tile(times, len(user))}
        cols |= {name: np.repeat(values, len(times)) for name, values in per_user.items()}
        cols |= {name: values[times].T.ravel() for name, values in m.items()}
        cols |= {name: values.T.ravel() for name, values in _window_counts(m, times).items()}
        parts.append(pd.DataFrame(cols))
    return pd.concat(parts, ignore_index=True)[list(COLUMNS)]


def summary(frame: pd.DataFrame, settle: float = 0.25, quantile: float = 0.95) -> pd.DataFrame:
    """Per (robot, assistance, beta) of :func:`run`'s rows: how often V rose where T4 held, and the
    ball: the ``quantile`` of the error over the last ``settle`` share of the horizon."""
    check_range("settle", settle, 0.0, 1.0, low_open=True)
    check_range("quantile", quantile, 0.0, 1.0)
    rows = []
    for (robot, assistance, beta), part in frame.groupby(["robot", "assistance", "beta"], sort=False):
        last = part.t.max()
        late = part[part.t >= (1.0 - settle) * last]
        end = part[part.t == last]
        sums = part[list(_COUNTS)].sum()
        den = sums.where(sums > 0)  # NaN where no step counts: its shares are NaN
        rows.append(
            {
                "robot": robot,
                "assistance": assistance,
                "beta": beta,
                "users": int(part[USER].nunique()),
                "steps": int(sums["steps"]),
                "bound_steps": int(sums["bound_steps"]),
                "bound_share": float(sums.bound_steps / den.steps),
                "rose_given_bound": float(sums.rises / den.bound_steps),
                "beyond_slack_given_bound": float(sums.rises_beyond_slack / den.bound_steps),
                "bound_share_half": float(sums.bound_steps_half / den.steps),
                "rose_given_bound_half": float(sums.rises_half / den.bound_steps_half),
                "ball": float(late.error.quantile(quantile)),
                "ball_target": float(late.error_target.quantile(quantile)),
                "radius_alpha": float((end.delta_alpha / end.belief).median()),
                "radius_half": float((end.delta / end.belief).median()),
                "tightness_alpha": float((late.belief * late.error / late.delta_alpha).quantile(quantile)),
                "tightness_half": float((late.belief * late.error / late.delta).quantile(quantile)),
                "late_outside_alpha": float(late.bound_holds.astype(bool).mean()),
                "late_outside_half": float(late.bound_holds_half.astype(bool).mean()),
                "belief_final": float(end.belief.median()),
            }
        )
    return pd.DataFrame(rows)


def _band(ax: Axes, part: pd.DataFrame, column: str, color: str, **line: object) -> None:
    """Median over users against t, with the 25-75% band."""
    q = part.groupby("t")[column].quantile([0.25, 0.5, 0.75]).unstack()
    ax.plot(q.index, q[0.5], color=color, **line)  # type: ignore[arg-type]
    ax.fill_between(q.index, q[0.25], q[0.75], color=color, alpha=0.15, lw=0)


def _bars(ax: Axes, table: pd.DataFrame, solid: str, hatched: str) -> None:
    """Columns ``solid`` and ``hatched`` of a summary as bars per beta (x) and member (colour)."""
    assistance = [m for m in ASSISTANCE if (table.assistance == m).any()]
    betas = sorted(table.beta.unique())
    width = 0.8 / len(assistance)
    for column, (i, sa) in itertools.product((solid, hatched), enumerate(assistance)):
        color = MEMBER_COLORS[sa]
        values = table[table.assistance == sa].set_index("beta").reindex(betas)[column].to_numpy()
        x = np.arange(len(betas)) - 0.4 + width * (i + 0.5)
        if column == hatched:
            ax.bar(x, values, width, fill=False, hatch="//", edgecolor=color, lw=0.8)
        else:
            ax.bar(x, values, width, color=color, alpha=0.85, label=sa)
            ax.plot(x, values, "o", color=color, ms=4, mec="0.2", mew=0.5)
    ax.set_xticks(np.arange(len(betas)), [f"{b:g}" for b in betas])
    ax.set_xlabel(r"user rationality $\beta$")


def plot(table: pd.DataFrame) -> Figure:
    """The Sec. IV-A ball: one row per robot present, four panels."""
    fig, rows = robot_rows(table, 4, (18, 3.8))
    stats = summary(table)
    for name, part, row in rows:
        beta = part.beta.max()
        top = part[part.beta == beta]
        for sa in [m for m in ASSISTANCE if (part.assistance == m).any()]:
            sub = top[top.assistance == sa]
            _band(row[0], sub, "v", MEMBER_COLORS[sa], label=sa)
            _band(row[1], sub, "error", MEMBER_COLORS[sa])
        for column, ls, label in (
            ("delta", "--", r"$\delta$ ($\alpha$ = 0.5)"),
            ("delta_alpha", "-.", r"$\delta_\alpha$"),
        ):
            med = top.groupby("t")[column].median()
            row[1].plot(med.index, med.to_numpy(), color="0.2", ls=ls, lw=1.2, label=label)
        row[1].legend(frameon=False, fontsize=8)
        v_title = rf"{name}: $V(t) = \|e\|^2/2$, $\beta$ = {beta:g}"
        row[0].set(yscale="log", title=v_title, xlabel="time step t", ylabel=r"$V$ [rad$^2$]")
        row[0].legend(frameon=False, fontsize=8)
        e_title = rf"{name}: $\|e(t)\|$ and the radii, $\beta$ = {beta:g}"
        row[1].set(title=e_title, xlabel="time step t", ylabel="[rad]")
        s = stats[stats.robot == name]
        _bars(row[2], s, "tightness_alpha", "tightness_half")
        row[2].axhline(1.0, color="0.3", lw=0.8)
        ratios = r"$b^*\|e\|/\delta_\alpha$ (solid), $b^*\|e\|/\delta$ (hatched)"
        ball = f"{name}: settled ball, 95th pct of\n" + ratios
        row[2].set(yscale="log", title=ball, ylabel="last 25% of steps [-]")
        _bars(row[3], s, "rose_given_bound", "rose_given_bound_half")
        bounds = r"$b^*\|e\| > \delta_\alpha$ (solid), $> \delta$ (hatched)"
        rose = f"{name}: V rose, of steps with\n" + bounds
        row[3].set(ylim=(0, 1), title=rose, ylabel="V rose [share of steps]")
    n = int(table.groupby(["robot", "assistance", "beta"])[USER].nunique().max())
    fig.suptitle(f"Sec. IV-A: the Lyapunov ball of LA+SA, {n} users per (member, beta)")
    fig.tight_layout()
    return fig
