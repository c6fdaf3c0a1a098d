r"""Planning participants of the eating study: the one-step participants' people, who every ``replan``
seconds choose an input z and a hold h by the Boltzmann rule on the progress rate :math:`V(z, h) =
(C_\text{now} - C_\text{after}(z, h)) / (n\, \Delta t\, v_\text{lin})`, :math:`n = \max(\text{presses} +
h/\Delta t, \text{replan}/\Delta t)`; latent plans rolled by the real step, Retargeting's by its twist."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from lasa.base.config import ControlConfig, Positive, PositiveInt, check_list, validate
from lasa.base.errors import ConfigError
from lasa.method.belief import belief
from lasa.method.decoder import ActionDecoder
from lasa.method.retarget import MODES
from lasa.method.runner import Now
from lasa.method.step import Assist, advance, human_action
from lasa.people.cohort import Cohort
from lasa.people.design import StudyConfig
from lasa.people.policy import choose
from lasa.people.simulation import Setting, State, act, prepare, progress, run_steps, start
from lasa.world.eating import EatingTask
from lasa.world.fork import tip_frames
from lasa.world.record import Episodes


@dataclasses.dataclass(frozen=True)
class PlanConfig:
    """How a planning participant plans, each setting from what it means, before any run."""

    # a choice reaction time (~0.3-0.5 s) plus the time to see the fork respond
    replan: Positive = 0.5  # time between re-plans [s]
    # a tap, a re-plan's worth, a short push and a long one (6 s: from a bowl to the plate)
    holds: tuple[Positive, ...] = (0.1, 0.5, 2.0, 6.0)  # hold times a plan chooses from [s]
    # the roll is exact up to the re-plan; beyond it one rolled step spans `coarse` control steps
    # (a person's foresight is no finer; 1 rolls every step exactly, at >10x the cost)
    coarse: PositiveInt = 5  # control steps per rolled step beyond the re-plan period [-]

    def __post_init__(self) -> None:
        validate(self)
        object.__setattr__(self, "holds", check_list("holds", self.holds, ascending=True))

    def steps(self, dt: float) -> tuple[int, np.ndarray]:
        """The re-plan period and the holds in control steps of ``dt``; ConfigError unless each is a whole
        number (>= 1) of steps and a long hold's excess a multiple of ``coarse``."""
        out = []
        for name, value in [("replan", self.replan)] + [("holds", h) for h in self.holds]:
            n = round(value / dt)
            if n < 1 or abs(n * dt - value) > 1e-6 * max(1.0, value):
                raise ConfigError(
                    f"{name} must be a whole number of control steps (dt = {dt} s), got {value}"
                )
            out.append(n)
        replan, holds = out[0], np.asarray(out[1:])
        for hold, n in zip(self.holds, holds, strict=True):
            if n > replan and (n - replan) % self.coarse:
                raise ConfigError(
                    f"holds longer than replan must exceed it by a multiple of coarse = {self.coarse} "
                    f"steps (dt = {dt} s), got {hold}"
                )
        return replan, holds


def _rotate(v: np.ndarray, rotvec: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v`` (..., 3) by rotation vectors ``rotvec`` (..., 3) (Rodrigues), broadcast."""
    angle = np.linalg.norm(rotvec, axis=-1, keepdims=True)
    k = rotvec / np.maximum(angle, 1e-12)
    kv = np.sum(k * v, axis=-1, keepdims=True)
    return v * np.cos(angle) + np.cross(k, v) * np.sin(angle) + k * kv * (1.0 - np.cos(angle))


@dataclasses.dataclass(frozen=True)
class _Study(Setting):
    """A planning study's fixed parts: the loop's, and the plans' inputs and holds."""

    moves: np.ndarray  # grid indices of the plans' inputs (every one but rest), (K',)
    replan_steps: int
    coarse: int  # control steps per rolled step beyond the re-plan period
    hold_steps: np.ndarray  # (H,)


@dataclasses.dataclass
class _Run(State):
    """A running planning study: the loop's state, and each episode's plan."""

    z_plan: np.ndarray  # grid index of the held input (E,)
    presses_left: np.ndarray  # mode presses before the hold (E,)
    hold_left: np.ndarray  # steps of the hold left (E,)


def _prepare(setting: Setting, plan: PlanConfig) -> _Study:
    """The study's fixed parts: the loop's (:func:`lasa.people.simulation.prepare`) and the plans'."""
    replan_steps, hold_steps = plan.steps(setting.control.dt)
    moves = np.flatnonzero(np.arange(len(setting.grid)) != setting.rest)
    return _Study(
        **vars(setting), moves=moves, replan_steps=replan_steps, coarse=plan.coarse, hold_steps=hold_steps
    )


def _rollout_states(study: _Study, idx: np.ndarray, state: np.ndarray, log_b: np.ndarray) -> np.ndarray:
    """The joints (A, K', H, n) at the end of each hold of every move from latent-action episodes
    ``idx`` (at ``state``, ``log_b``), each rolled step the executed one (decode, stick at rest,
    :func:`lasa.method.step.advance` with the episode's alpha and member), in one batch."""
    lay, moves, holds = study.layout, study.moves, study.hold_steps
    k = len(moves)
    s = np.repeat(state, k, axis=0)
    log_b = np.repeat(log_b, k, axis=0)
    alpha, assistance = np.repeat(lay.alpha[idx], k), np.repeat(lay.assistance_run[idx], k)
    z = np.tile(study.grid[moves], (len(idx), 1))
    snaps = np.empty((len(s), len(holds), s.shape[1]))
    coarse = dataclasses.replace(study.control, dt=study.control.dt * study.coarse)
    j = 0
    while j < holds[-1]:
        control = study.control if j < study.replan_steps else coarse
        b = belief(log_b)
        a_h = human_action(study.decoder.decode_numpy(z, s, b), z, rest="zero")
        assist = Assist(study.task, control, alpha, assistance, study.goal_sets, only_blended=True)
        step = advance(assist, s, log_b, a_h, b)
        s, log_b = step.state, step.log_belief
        j += 1 if j < study.replan_steps else study.coarse
        snaps[:, holds == j] = s[:, None]
    return snaps.reshape(len(idx), k, len(holds), -1)


def _latent_values(
    study: _Study, run: _Run, idx: np.ndarray, state: np.ndarray, log_b: np.ndarray
) -> np.ndarray:
    """Progress rate of every (move, hold) plan of latent-action episodes ``idx``, (A, K' H)."""
    q = _rollout_states(study, idx, state, log_b)
    pos, axis, _, _ = tip_frames(study.task.robot, study.data, q.reshape(-1, q.shape[-1]))
    pos, axis = pos.reshape(len(idx), -1, 3), axis.reshape(len(idx), -1, 3)
    steps = np.maximum(np.tile(study.hold_steps, len(study.moves)), study.replan_steps)
    return progress(study, run, idx, pos - run.pos[idx, None], axis) / (steps * study.unit)


def _retarget_values(study: _Study, run: _Run, idx: np.ndarray) -> np.ndarray:
    """Progress rate of every (mode, move, hold) plan of Retargeting episodes ``idx``, (A, M K' H):
    the twist held for h moves the tip by h v and turns it by exp(h omega), after a step per press."""
    h = study.hold_steps * study.control.dt  # (H,)
    tw = study.r_twist[:, study.moves, None, :] * h[None, None, :, None]  # (M, K', H, 6)
    dp = tw[..., :3].reshape(1, -1, 3)
    new_dir = _rotate(run.axis[idx, None, :], tw[..., 3:].reshape(1, -1, 3))
    n_m, n_k, n_h = tw.shape[:3]
    presses = (np.arange(n_m)[None, :] - run.mode[idx, None]) % n_m  # (A, M)
    steps = np.maximum(presses[:, :, None, None] + study.hold_steps, study.replan_steps)  # (A, M, 1, H)
    steps = np.broadcast_to(steps, (len(idx), n_m, n_k, n_h)).reshape(len(idx), -1)
    return progress(study, run, idx, np.broadcast_to(dp, new_dir.shape), new_dir) / (steps * study.unit)


def _plan(study: _Study, run: _Run, now: Now) -> None:
    """Every running episode chooses its next plan (or to rest until the next re-plan)."""
    t, idx = now.t, now.rows
    lay, pc, n_h = study.layout, study.config.participant, len(study.hold_steps)
    n_la = len(study.moves) * n_h  # latent actions' plans: the first of Retargeting's, every mode's
    values = np.full((len(idx), len(MODES) * n_la), -np.inf)
    la = lay.is_la[idx]
    if la.any():
        values[la, :n_la] = _latent_values(study, run, idx[la], now.state[la], now.log_belief[la])
    if (~la).any():
        values[~la] = _retarget_values(study, run, idx[~la])
    choice, wants = choose(values, lay, idx, t, study.streams, run.waited, study.control.dt, pc)
    plan_mode, rem = np.divmod(choice, len(study.moves) * n_h)
    move, hold = np.divmod(rem, n_h)
    run.z_plan[idx] = np.where(wants, study.moves[move], study.rest)
    run.hold_left[idx] = np.where(wants, study.hold_steps[hold], 0)
    run.presses_left[idx] = np.where(wants & ~la, (plan_mode - run.mode[idx]) % len(MODES), 0)


def _choose(study: _Study, run: _Run, now: Now) -> np.ndarray:
    """The chooser: a re-plan when one is due, then one real step of the running episodes (a press, the
    held input, or rest); their human actions a_h (A, n)."""
    if now.t % study.replan_steps == 0:
        _plan(study, run, now)
    idx, la = now.rows, study.layout.is_la[now.rows]
    press = run.presses_left[idx] > 0
    moving = ~press & (run.hold_left[idx] > 0)
    z = study.grid[np.where(moving, run.z_plan[idx], study.rest)]
    a_h = np.zeros((len(idx), study.task.robot.n_joints))
    if la.any():
        phi = study.decoder.decode_numpy(z[la], now.state[la], now.belief[la])
        a_h[la] = human_action(phi, z[la], rest="zero")
    act(study, run, now, a_h, z, press, ~press & ~moving)
    run.presses_left[idx] -= press
    run.hold_left[idx] -= moving
    return a_h


def simulate(
    task: EatingTask,
    decoder: ActionDecoder,
    cohort: Cohort,
    control: ControlConfig,
    config: StudyConfig = StudyConfig(),
    seed: int = 0,
    progress: bool = True,
    interfaces: tuple[str, ...] = ("R", "LA"),
    *,
    plan: PlanConfig = PlanConfig(),
) -> Episodes:
    """:func:`lasa.people.participants.simulate` (the same study, record, random streams and errors)
    with planning participants, who plan as ``plan`` says (:meth:`PlanConfig.steps`)."""
    study = _prepare(prepare(task, decoder, cohort, control, config, seed, interfaces), plan)
    n_e = len(study.layout.part)
    none_left = {k: np.zeros(n_e, dtype=int) for k in ("presses_left", "hold_left")}
    run = _Run(**vars(start(study)), z_plan=np.full(n_e, study.rest), **none_left)
    desc = f"planning study: {len(cohort)} participants, {n_e} episodes"
    return run_steps(study, run, functools.partial(_choose, study, run), desc, progress)
