r"""The eating study with simulated participants (Sec. VI): conditions, participants, measures.

Ten people did the paper's study; here a cohort of simulated participants stands in for
them. Each does both tasks (:data:`lasa.world.eating.TASKS`) under the four conditions of the
2x2 design, in a counterbalanced order (a balanced Latin square, Williams 1949):

=========  =================================================================================
``R``      Retargeting: the stick commands a fork twist in one of three modes, realised by
           mink's differential IK (:mod:`lasa.method.retarget`); a button cycles the modes.
``R+SA``   the same human action a_h, blended with the assistance by Eq. M1.
``LA``     latent actions: a_h = phi(z, s, b), the 2-D decoder; alpha = 0.
``LA+SA``  Algorithm 1: latent actions blended with the assistance.
=========  =================================================================================

The assistance is a member of :mod:`lasa.method.assistance` (hindsight optimisation, the paper's
study, by default); the robot infers its belief from a_h in every condition.

**A simulated participant** looks one step ahead, in the fork's own terms: each candidate
input (a stick position z on a grid, and in Retargeting also each mode) would move the
fork's tip by some dp and turn its direction by some dw. Its value is the progress it makes
towards the current waypoint (:func:`lasa.world.eating.waypoints`) under the cost

.. math::  C = \|p - p^*\| + \ell\, \angle(d, d^*),

in units of the best translation one step of Retargeting makes (``dt * linear_speed``). The
participant predicts a latent action's effect through the arm's Jacobian at the current
state (what phi(z) would do), and a Retargeting input's effect as the twist it commands
(what the interface promises). They pick an input by a Boltzmann choice with their own
rationality beta (Gumbel-max); they give no input at all (idle) when no candidate would
make at least ``idle_threshold`` of that unit of progress (until their ``patience`` runs
out: then they try their Boltzmann choice anyway), and choosing the stick's rest position
is idle too. Choosing a Retargeting input of another mode presses the mode button
(one step, no motion; a mode switch), so such an input is worth its progress divided by the
steps it takes (the presses and the move). Rationality improves with experience,

.. math::  \beta(t) = \beta_\infty \big(1 - (1 - \rho)\, e^{-(E_0 + t\,\Delta)/\tau}\big),

where E_0 is the practice with this condition (the paper: up to 5 minutes) plus a share of
the practice with the conditions done before it, so the order of conditions matters, and
the counterbalancing has something to balance.

**What a simulated participant cannot stand in for.** Fatigue, frustration, trust, and
the strategies people invent; perception (they see the fork's pose exactly); anticipation
beyond one step (a person plans a path, they do not); the Likert questionnaire (not
simulated at all: people answer it, see the teleoperation kit). The measures below are
what such a participant can show: time, idleness, goal error and preference alignment.

**Measures**, as Sec. VI defines them: *Total Time* to finish the task, *Idle Time*
without stick input, *Goal Error* the tip's distance to the closest goal summed over the
task (times dt: metre-seconds), *Preference Alignment* the dot product between the fork's
direction and the direction the phase's preference needs, averaged over the phase.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from lasa.base.conditions import CONDITIONS, alpha_of
from lasa.base.conditions import parse as parse_condition
from lasa.base.config import (
    ASSISTANCE,
    NO_ASSISTANCE,
    ControlConfig,
    PositiveInt,
    check_choice,
    check_range,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.method.belief import belief, uniform_log_belief
from lasa.method.decoder import ActionDecoder
from lasa.method.retarget import MODES, RetargetConfig, Retargeting, retarget_action, twist
from lasa.method.step import advance, check_decoder, decode_candidates, human_action, latent_grid
from lasa.people.users import choose_latent, gumbel_noise
from lasa.world.eating import GOALS, PREFERENCES, TASKS, EatingTask, fork_direction, fork_frame, waypoints
from lasa.world.robot import Robot

__all__ = [
    "TASK_NAMES",
    "ParticipantConfig",
    "StudyConfig",
    "Cohort",
    "Episodes",
    "williams_square",
    "tip_motion",
    "progress_gain",
    "draw_cohort",
    "tip_frames",
    "waypoint_reached",
    "Layout",
    "layout",
    "waypoint_arrays",
    "simulate",
    "goal_error",
    "idle_time",
    "alignment",
    "measures",
]

TASK_NAMES = tuple(TASKS)


def interface_of(condition: str) -> str:
    """``R`` or ``LA``: the control interface of one of the study's conditions."""
    return parse_condition(condition, CONDITIONS).interface


@dataclasses.dataclass(frozen=True)
class ParticipantConfig:
    """The free parameters of a simulated participant, each with its reason.

    All were set before any study was simulated, from what they mean; none was changed
    after seeing which value makes a hypothesis hold (notebook 11 says so).
    """

    # Rationality in units of the best step's progress: at beta = 20 an input 0.1 of a
    # step worse than the best is chosen e^2 ~ 7x less often: people pick near-best stick
    # directions but not the exact best one. Spread across people: lognormal, sigma 0.5
    # (a factor ~1.6 either way), as the paper's users differed in skill.
    beta_median: float = 20.0  # median beta_inf across participants [-]
    beta_spread: float = 0.5  # sigma of log beta_inf [-]
    novice_fraction: float = 0.25  # rho: beta / beta_inf with no experience at all [-]
    # Joystick skills settle within minutes of practice; the paper gave up to 5 minutes.
    learning_median: float = 60.0  # median time constant tau of the improvement [s]
    learning_spread: float = 0.5  # sigma of log tau [-]
    practice_min: float = 120.0  # practice before a condition, uniform in [min, max] [s]
    practice_max: float = 300.0  # ... "up to 5 minutes" (the paper) [s]
    transfer: float = 0.5  # share of earlier conditions' practice that carries over [-]
    # A motion of under ~1.5 mm per step (10% of the best step) is not worth a push: the
    # participant rests the stick.
    idle_threshold: float = 0.1  # least progress, in best-step units, worth an input [-]
    # Resting is not forever: after about a second with nothing worth a push (a choice
    # reaction time with an unfamiliar mapping), a person tries an input anyway.
    patience: float = 1.0  # idle time after which the participant tries their Boltzmann choice [s]
    # A turn of the fork by 1 rad about its tip moves its grip by the fork's length (0.125 m):
    # orientation errors weigh like the displacement they cause at the hand.
    rotation_weight: float = 0.125  # l: metres of cost per radian of direction error [m/rad]

    def __post_init__(self) -> None:
        check_range("beta_median", self.beta_median, 0.0, low_open=True)
        check_range("beta_spread", self.beta_spread, 0.0)
        check_range("novice_fraction", self.novice_fraction, 0.0, 1.0)
        check_range("learning_median", self.learning_median, 0.0, low_open=True)
        check_range("learning_spread", self.learning_spread, 0.0)
        check_range("practice_min", self.practice_min, 0.0)
        check_range("practice_max", self.practice_max, self.practice_min)
        check_range("transfer", self.transfer, 0.0, 1.0)
        check_range("idle_threshold", self.idle_threshold, 0.0)
        check_range("rotation_weight", self.rotation_weight, 0.0)
        check_range("patience", self.patience, 0.0, low_open=True)


@dataclasses.dataclass(frozen=True)
class StudyConfig:
    """How a study session runs (the participants' parameters are in ``participant``)."""

    # steps allowed per task (150 s at dt = 0.1 s); unfinished tasks count the horizon [-]
    horizon: PositiveInt = 1500
    position_tol: float = 0.015  # a waypoint is reached this close to it (the tines' width) [m]
    angle_tol: float = 0.2  # ... with the fork's direction this close (~11 degrees) [rad]
    # The SA members the assisted conditions run under (lasa.method.assistance); the first is the
    # headline. The paper's study used hindsight optimisation.
    members: tuple[str, ...] = ("hindsight",)
    n_z: int = 5  # stick positions per axis the participant weighs (25 incl. rest) [-]
    participant: ParticipantConfig = ParticipantConfig()
    retarget: RetargetConfig = RetargetConfig()

    def __post_init__(self) -> None:
        validate(self)
        check_range("position_tol", self.position_tol, 0.0, low_open=True)
        check_range("angle_tol", self.angle_tol, 0.0, np.pi, low_open=True)
        if not self.members:
            raise ConfigError("members must name at least one assistance member")
        for name in self.members:
            check_choice("assistance", name, ASSISTANCE)
        if int(self.n_z) != self.n_z or self.n_z < 3 or self.n_z % 2 == 0:
            raise ConfigError(
                f"n_z must be an odd integer >= 3 (the rest position on the grid), got {self.n_z!r}"
            )


def williams_square(n: int) -> np.ndarray:
    """A balanced Latin square (Williams design) for an even number n of conditions, (n, n).

    Every condition appears once in every position, and follows every other condition
    exactly once, so first-order carry-over effects are balanced.
    """
    if n < 2 or n % 2:
        raise ConfigError(f"a Williams square needs an even number of conditions >= 2, got {n}")
    first = [0]
    low, high = 1, n - 1
    while len(first) < n:
        first.append(low)
        low += 1
        if len(first) < n:
            first.append(high)
            high -= 1
    return (np.asarray(first)[None, :] + np.arange(n)[:, None]) % n


@dataclasses.dataclass(frozen=True)
class Cohort:
    """Simulated participants: each one's rationality, learning and order of conditions.

    Attributes:
        beta: beta_inf per participant, shape (N,).
        learning_time: tau per participant, shape (N,) [s].
        practice: Practice before each condition (in :data:`CONDITIONS` order), (N, 4) [s].
        order: The conditions each participant does, in order (indices), (N, 4).
        config: The parameters they were drawn with.
    """

    beta: np.ndarray
    learning_time: np.ndarray
    practice: np.ndarray
    order: np.ndarray
    config: ParticipantConfig

    def __len__(self) -> int:
        return len(self.beta)

    def experience(self) -> np.ndarray:
        """E_0: practice with each condition plus the carried-over practice of earlier ones, (N, 4) [s]."""
        out = self.practice.copy()
        for i, order in enumerate(self.order):
            carried = 0.0
            for c in order:
                out[i, c] += self.config.transfer * carried
                carried += self.practice[i, c]
        return out


def draw_cohort(n: int, config: ParticipantConfig = ParticipantConfig(), seed: int = 0) -> Cohort:
    """Draw ``n`` participants; participant i is the same whatever n is (its own random stream).

    Participant i runs row ``i mod 4`` of :func:`williams_square`, so any 4 consecutive
    participants balance order and carry-over.
    """
    if int(n) != n or n < 1:
        raise ConfigError(f"the number of participants must be a positive integer, got {n!r}")
    square = williams_square(len(CONDITIONS))
    beta, tau, practice = np.empty(n), np.empty(n), np.empty((n, len(CONDITIONS)))
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        beta[i] = config.beta_median * np.exp(config.beta_spread * rng.standard_normal())
        tau[i] = config.learning_median * np.exp(config.learning_spread * rng.standard_normal())
        practice[i] = rng.uniform(config.practice_min, config.practice_max, len(CONDITIONS))
    order = square[np.arange(n) % len(CONDITIONS)]
    return Cohort(beta=beta, learning_time=tau, practice=practice, order=order, config=config)


def tip_frames(
    robot: Robot, data: mujoco.MjData, qs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The grasp site's position, direction (+z) and Jacobians at joint vectors ``qs`` (B, n).

    Returns:
        position (B, 3), direction (B, 3), translational Jacobian (B, 3, n) and rotational
        Jacobian (B, 3, n) with respect to the arm joints.
    """
    model = robot.model
    site = model.site(robot.spec.grasp_site).id
    dofs = np.array([model.jnt_dofadr[model.joint(j).id] for j in robot.spec.joints])
    b = len(qs)
    pos, axis = np.empty((b, 3)), np.empty((b, 3))
    jp, jr = np.empty((b, 3, len(dofs))), np.empty((b, 3, len(dofs)))
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    for i, q in enumerate(qs):  # MuJoCo's kinematics take one configuration at a time
        data.qpos[robot.qpos_adr] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        mujoco.mj_jacSite(model, data, jacp, jacr, site)
        pos[i] = data.site_xpos[site]
        axis[i] = data.site_xmat[site].reshape(3, 3)[:, 2]
        jp[i], jr[i] = jacp[:, dofs], jacr[:, dofs]
    return pos, axis, jp, jr


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between unit vectors along the last axis [rad]."""
    return np.arccos(np.clip(np.einsum("...i,...i->...", a, b), -1.0, 1.0))


def tip_motion(
    jp: np.ndarray, jr: np.ndarray, axis: np.ndarray, dq: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The tip's displacement and new direction for joint steps ``dq`` (A, K, n), to first order.

    Args:
        jp, jr: Translational and rotational Jacobians, (A, 3, n).
        axis: The fork's direction now, (A, 3).
        dq: Candidate joint steps, (A, K, n) [rad].

    Returns:
        Displacements (A, K, 3) [m] and unit directions (A, K, 3).
    """
    dp = np.einsum("aij,akj->aki", jp, dq)
    rot = np.einsum("aij,akj->aki", jr, dq)
    return dp, _normalise(axis[:, None, :] + np.cross(rot, axis[:, None, :]))


def progress_gain(
    pos: np.ndarray,
    axis: np.ndarray,
    dp: np.ndarray,
    new_dir: np.ndarray,
    p_star: np.ndarray,
    d_star: np.ndarray,
    rotation_weight: float,
) -> np.ndarray:
    """How much each candidate lowers a participant's cost to the waypoint, (A, K) [m].

    The cost of a tip pose is its distance to the waypoint plus ``rotation_weight`` times
    the angle between its direction and the waypoint's (:class:`ParticipantConfig`).
    """
    c_now = np.linalg.norm(pos - p_star, axis=1) + rotation_weight * _angle(axis, d_star)
    c_new = np.linalg.norm(pos[:, None, :] + dp - p_star[:, None, :], axis=2)
    c_new = c_new + rotation_weight * _angle(new_dir, d_star[:, None, :])
    return c_now[:, None] - c_new


def waypoint_reached(
    tip: np.ndarray,
    direction: np.ndarray,
    target: np.ndarray,
    target_direction: np.ndarray,
    config: StudyConfig,
) -> np.ndarray:
    """Whether the fork tip is within ``config.position_tol`` of its waypoint and its direction within
    ``config.angle_tol`` of the waypoint's, vectorised over leading dimensions (the study and live
    teleoperation share this test)."""
    close = np.linalg.norm(tip - target, axis=-1) < config.position_tol
    return close & (_angle(direction, target_direction) < config.angle_tol)


def _normalise(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


@dataclasses.dataclass(frozen=True)
class Episodes:
    """The record of a simulated study: one episode per participant x condition x task.

    Attributes:
        participant, condition, task: Who, under which condition (name), which task (name), (E,).
        assistance: The SA member of each episode (``"none"`` for R and LA), (E,).
        order: The position of the condition in the participant's session (0-3), (E,).
        states: Joint positions, (T+1, E, n) [rad] (held after an episode ends).
        tip: Fork-tip positions, (T+1, E, 3) [m].
        direction: Fork directions (unit), (T+1, E, 3).
        phase: Index of the phase each step belongs to, (T+1, E).
        idle: Whether the participant gave no stick input at each step, (T, E).
        switch: Whether the step was a mode switch (Retargeting), (T, E).
        end: The step each episode ended (its Total Time in steps; the horizon if unfinished), (E,).
        completed: Whether it finished within the horizon, (E,).
        dt: The control period [s].
        belief: The robot's belief over the goals at each step, (T+1, E, G) (None: not logged).
        waypoint: The waypoint each episode was working towards when it ended, (E,) (None: not logged).
    """

    participant: np.ndarray
    condition: np.ndarray
    assistance: np.ndarray
    task: np.ndarray
    order: np.ndarray
    states: np.ndarray
    tip: np.ndarray
    direction: np.ndarray
    phase: np.ndarray
    idle: np.ndarray
    switch: np.ndarray
    end: np.ndarray
    completed: np.ndarray
    dt: float
    belief: np.ndarray | None = None
    waypoint: np.ndarray | None = None

    def active(self) -> np.ndarray:
        """(T, E): whether each episode was still running at each step."""
        steps = np.arange(self.idle.shape[0])[:, None]
        return steps < self.end[None, :]


@dataclasses.dataclass(frozen=True)
class Layout:
    """The episodes of a study and each one's fixed settings, (E,) each (participants' order)."""

    part: np.ndarray  # participant index
    tsk: np.ndarray  # task index into TASK_NAMES
    cond: np.ndarray  # condition index into CONDITIONS
    member: np.ndarray  # SA member, NO_ASSISTANCE for R and LA
    members_run: np.ndarray  # the member advance() runs (alpha = 0 where there is none)
    is_la: np.ndarray  # latent actions (else Retargeting)
    alpha: np.ndarray  # blend weight
    order: np.ndarray  # position of the condition in the participant's session
    e0: np.ndarray  # experience before the condition [s]
    beta_inf: np.ndarray
    tau: np.ndarray  # learning time constant [s]


def layout(
    cohort: Cohort, control: ControlConfig, members: tuple[str, ...], interfaces: tuple[str, ...]
) -> Layout:
    """The study's episodes, participant-major, then arm (the unassisted conditions once, each
    assisted one under every member), then task; every model of participant runs this order."""
    arms: list[tuple[str, str]] = [(c, NO_ASSISTANCE) for c in ("R", "LA") if c in interfaces]
    arms += [(c, m) for m in members for c in ("R+SA", "LA+SA") if interface_of(c) in interfaces]
    n_a, n_t = len(arms), len(TASK_NAMES)
    part = np.repeat(np.arange(len(cohort)), n_a * n_t)
    arm = np.tile(np.repeat(np.arange(n_a), n_t), len(cohort))
    cond = np.array([CONDITIONS.index(arms[a][0]) for a in arm])
    member = np.array([arms[a][1] for a in arm])
    return Layout(
        part=part,
        tsk=np.tile(np.arange(n_t), len(cohort) * n_a),
        cond=cond,
        member=member,
        members_run=np.where(member == NO_ASSISTANCE, members[0], member),
        is_la=np.array([interface_of(c) == "LA" for c in CONDITIONS])[cond],
        alpha=np.array([alpha_of(c, control.alpha, CONDITIONS) for c in CONDITIONS])[cond],
        order=np.argsort(cohort.order, axis=1)[part, cond],
        e0=cohort.experience()[part, cond],
        beta_inf=cohort.beta[part],
        tau=cohort.learning_time[part],
    )


def waypoint_arrays(robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every task's waypoints, padded: positions (T, W, 3), directions (T, W, 3), phases (T, W),
    counts (T,)."""
    plans = [waypoints(name) for name in TASK_NAMES]
    n_wp = np.array([len(p) for p in plans])
    w_max, n_t = int(n_wp.max()), len(plans)
    wp_pos, wp_dir = np.zeros((n_t, w_max, 3)), np.zeros((n_t, w_max, 3))
    wp_phase = np.zeros((n_t, w_max), dtype=int)
    for k, plan in enumerate(plans):
        for j, wp in enumerate(plan):
            pos, rot = fork_frame(robot, wp.goal, wp.theta, wp.depth)
            wp_pos[k, j], wp_dir[k, j], wp_phase[k, j] = pos, rot[:, 2], wp.phase
    return wp_pos, wp_dir, wp_phase, n_wp


def simulate(
    task: EatingTask,
    decoder: ActionDecoder,
    cohort: Cohort,
    control: ControlConfig,
    config: StudyConfig = StudyConfig(),
    seed: int = 0,
    progress: bool = True,
    interfaces: tuple[str, ...] = ("R", "LA"),
) -> Episodes:
    """Run every participant through both tasks under every condition, all episodes in one batch.

    Args:
        task: The eating task.
        decoder: The 2-D latent-action decoder phi(z, s, b) trained on the eating demonstrations.
        cohort: The simulated participants (:func:`draw_cohort`).
        control: Control-loop units (dt, sigma_h, belief model, alpha); the assisted
            conditions run under each of ``config.members``.
        config: Session settings and the participants' free parameters.
        seed: Seed of the participants' choices; episode (i, condition, task) draws from its
            own stream, so participant i's episodes do not depend on the cohort's size.
        progress: Show a progress bar.
        interfaces: The control interfaces whose conditions run (``("LA",)``: only LA and
            LA+SA, for another reading of the decoder; Retargeting does not use it).
    """
    check_decoder(decoder, task)
    if not interfaces or not set(interfaces) <= {"R", "LA"}:
        raise ConfigError(f"interfaces must be a non-empty subset of ('R', 'LA'), got {interfaces!r}")
    if decoder.z_dim != 2:
        raise ConfigError(f"the study's joystick has 2 axes; the decoder has z_dim={decoder.z_dim}")
    members = tuple(config.members)
    robot, dt, pc = task.robot, control.dt, config.participant
    lay = layout(cohort, control, members, interfaces)
    part, tsk, cond, member = lay.part, lay.tsk, lay.cond, lay.member
    is_la, alpha, members_run, order = lay.is_la, lay.alpha, lay.members_run, lay.order
    e0, beta_inf, tau = lay.e0, lay.beta_inf, lay.tau
    n_e = len(part)
    # episode (participant, condition, task) draws from its own stream, shared by the members
    # (common random numbers: the members' comparisons are paired)
    streams = [
        np.random.default_rng([seed, int(p), int(c), int(k)]) for p, c, k in zip(part, cond, tsk, strict=True)
    ]
    wp_pos, wp_dir, wp_phase, n_wp = waypoint_arrays(robot)  # padded per task

    grid = latent_grid(config.n_z, 2)  # (K, 2), the rest position in the middle
    rest = int(np.flatnonzero(np.all(grid == 0.0, axis=1))[0])
    n_k, n_m = len(grid), len(MODES)
    # Retargeting's candidates: (mode, z) for every mode, one rest position (the current mode's)
    r_twist = np.stack([twist(np.full(n_k, m), grid, config.retarget) for m in range(n_m)])  # (M, K, 6)
    unit = dt * config.retarget.linear_speed  # the best translation one step makes [m]
    retarget = Retargeting(robot, dt, config.retarget)
    sets = task.belief_targets(control.likelihood)
    data = mujoco.MjData(robot.model)

    horizon, n = config.horizon, robot.n_joints
    states = np.empty((horizon + 1, n_e, n))
    tip, direction = np.empty((horizon + 1, n_e, 3)), np.empty((horizon + 1, n_e, 3))
    phase = np.zeros((horizon + 1, n_e), dtype=int)
    beliefs = np.empty((horizon + 1, n_e, task.n_goals))
    idle = np.zeros((horizon, n_e), dtype=bool)
    switch = np.zeros((horizon, n_e), dtype=bool)
    s = np.broadcast_to(task.start, (n_e, n)).copy()
    log_b = uniform_log_belief(n_e, task.n_goals)
    mode = np.zeros(n_e, dtype=int)
    w = np.zeros(n_e, dtype=int)
    end = np.full(n_e, horizon)
    waited = np.zeros(n_e, dtype=int)  # consecutive idle steps
    patience_steps = max(1, round(pc.patience / dt))
    running = np.ones(n_e, dtype=bool)
    bar = tqdm(total=horizon, desc=f"study: {len(cohort)} participants, {n_e} episodes", disable=not progress)
    for t in range(horizon + 1):
        pos, axis, jp, jr = tip_frames(robot, data, s)
        states[t], tip[t], direction[t], beliefs[t] = s, pos, axis, belief(log_b)
        # a waypoint reached: on to the next one, or the task is done
        here = wp_pos[tsk, w]
        reached = running & waypoint_reached(pos, axis, here, wp_dir[tsk, w], config)
        w = np.where(reached, w + 1, w)
        finished = reached & (w >= n_wp[tsk])
        end[finished] = t
        running &= ~finished
        w = np.minimum(w, n_wp[tsk] - 1)
        phase[t] = wp_phase[tsk, w]
        if t == horizon or not running.any():
            states[t + 1 :], tip[t + 1 :], direction[t + 1 :] = s, pos, axis
            beliefs[t + 1 :], phase[t + 1 :] = beliefs[t], phase[t]
            break
        idx = np.flatnonzero(running)
        p_star, d_star = wp_pos[tsk[idx], w[idx]], wp_dir[tsk[idx], w[idx]]
        p_i, a_i = pos[idx], axis[idx]
        b = belief(log_b[idx])
        # predicted tip motion of every candidate: (A, M*K, 3) each
        dp = np.zeros((len(idx), n_m * n_k, 3))
        new_dir = np.repeat(a_i[:, None, :], n_m * n_k, axis=1)
        la = is_la[idx]
        phi = np.zeros((len(idx), n_k, n))
        if la.any():
            phi[la] = decode_candidates(decoder, grid, s[idx[la]], b[la])
            dp[la, :n_k], new_dir[la, :n_k] = tip_motion(jp[idx[la]], jr[idx[la]], a_i[la], dt * phi[la])
        if (~la).any():
            tw = r_twist.reshape(n_m * n_k, 6)
            dp[~la] = dt * tw[None, :, :3]
            new_dir[~la] = _normalise(a_i[~la, None, :] + dt * np.cross(tw[None, :, 3:], a_i[~la, None, :]))
        gain = progress_gain(p_i, a_i, dp, new_dir, p_star, d_star, pc.rotation_weight) / unit
        # which candidates exist: LA the K stick positions; R every (mode, z) except other modes' rest
        valid = np.zeros_like(gain, dtype=bool)
        valid[la, :n_k] = True
        r_rows = np.flatnonzero(~la)
        valid[r_rows] = True
        other_rest = np.arange(n_m)[None, :] != mode[idx[r_rows], None]  # (R, M)
        valid[r_rows[:, None], np.arange(n_m)[None, :] * n_k + rest] = ~other_rest
        rest_col = np.where(la, rest, mode[idx] * n_k + rest)
        # another mode's input takes a press (or two) of the mode button first: its progress
        # is spread over the steps it takes, the presses and the move
        presses_needed = (np.arange(n_m)[None, :] - mode[idx[r_rows], None]) % n_m  # (R, M)
        gain[r_rows] /= np.repeat(1.0 + presses_needed, n_k, axis=1)
        gain = np.where(valid, gain, -np.inf)
        gain[np.arange(len(idx)), rest_col] = 0.0  # resting moves nothing
        experience = e0[idx] + t * dt
        beta = beta_inf[idx] * (1.0 - (1.0 - pc.novice_fraction) * np.exp(-experience / tau[idx]))
        uniforms = np.stack([streams[e].random(n_m * n_k) for e in idx])
        choice = choose_latent(-gain, beta, gumbel_noise(uniforms))
        # nothing worth a push: rest, unless the participant has waited out their patience
        # (then they try the input their Boltzmann choice gives, as a person tries things)
        wants = (gain.max(axis=1) >= pc.idle_threshold) | (waited[idx] >= patience_steps)
        choice = np.where(wants, choice, rest_col)
        chosen_mode, chosen_z = choice // n_k, choice % n_k
        is_rest = choice == rest_col
        # the human action, as the live step makes it from the same input: latent actions with
        # the stick at rest commanding nothing; Retargeting's press, rest or twist by IK
        a_h = np.zeros((len(idx), n))
        a_h[la] = human_action(phi[la, chosen_z[la]], grid[chosen_z[la]], rest="zero")
        presses = ~la & (chosen_mode != mode[idx])
        r = ~la
        if r.any():
            a_h[r], mode[idx[r]] = retarget_action(
                retarget, s[idx[r]], mode[idx[r]], grid[chosen_z[r]], presses[r]
            )
        idle[t, idx] = is_rest
        waited[idx] = np.where(is_rest, waited[idx] + 1, 0)
        switch[t, idx] = presses
        step = advance(task, control, s[idx], log_b[idx], a_h, alpha[idx], sets, b, members_run[idx])
        s[idx], log_b[idx] = step.state, step.log_belief
        bar.update(1)
    bar.close()
    return Episodes(
        participant=part,
        condition=np.asarray(CONDITIONS)[cond],
        assistance=member,
        task=np.asarray(TASK_NAMES)[tsk],
        order=order,
        states=states,
        tip=tip,
        direction=direction,
        phase=phase,
        idle=idle,
        switch=switch,
        end=end,
        completed=end < horizon,
        dt=dt,
        belief=beliefs,
        waypoint=w,
    )


def goal_error(tip: np.ndarray, goals: np.ndarray, active: np.ndarray, dt: float) -> np.ndarray:
    """Goal Error: the tip's distance to the closest goal, summed over the task's steps, times dt.

    Args:
        tip: Tip positions, (T, E, 3) [m].
        goals: Goal positions, (G, 3) [m].
        active: Which steps count (the episode was running), (T, E).
        dt: Control period [s].

    Returns:
        Per episode [m s], shape (E,).
    """
    dist = np.linalg.norm(tip[:, :, None, :] - goals[None, None], axis=-1).min(axis=-1)
    return (dist * active).sum(axis=0) * dt


def idle_time(idle: np.ndarray, active: np.ndarray, dt: float) -> np.ndarray:
    """Idle Time: time without stick input while the task ran, per episode [s], (E,)."""
    return (idle & active).sum(axis=0) * dt


def alignment(direction: np.ndarray, desired: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Preference Alignment: mean of d . d* over the masked steps, per episode (NaN if none), (E,).

    Args:
        direction: The fork's direction (unit), (T, E, 3).
        desired: The preference's direction d(theta) (unit), (E, 3) or (T, E, 3).
        mask: The steps of the phase, (T, E).
    """
    dots = np.einsum("tei,tei->te", direction, np.broadcast_to(desired, direction.shape))
    count = mask.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, (dots * mask).sum(axis=0) / count, np.nan)


def measures(task: EatingTask, episodes: Episodes) -> dict[str, pd.DataFrame]:
    """The study's tidy tables from a simulated (or logged) session.

    Returns:
        ``{"goal_error": ..., "time": ..., "alignment": ...}``: one row per participant x
        condition x task (x phase for alignment). Goal Error is given under two readings of
        "the closest goal": all four goals, the three bowls and the plate, whichever the task
        visits (``goal_error``), and the three bowls only (``goal_error_bowls``);
        ``mean_distance`` is Goal Error divided by the task's time [m].
    """
    robot = task.robot
    goals = robot.cup_positions()
    active = episodes.active()
    tip, direction = episodes.tip[:-1], episodes.direction[:-1]
    keys = {
        "robot": robot.name,
        "participant": episodes.participant,
        "condition": episodes.condition,
        "assistance": episodes.assistance,
        "task": episodes.task,
        "order": episodes.order,
    }
    bowls = [i for i, g in enumerate(GOALS) if g != "plate"]
    error = pd.DataFrame(
        {
            **keys,
            "goal_error": goal_error(tip, goals, active, episodes.dt),
            "goal_error_bowls": goal_error(tip, goals[bowls], active, episodes.dt),
        }
    )
    error["mean_distance"] = error.goal_error / np.maximum(episodes.end * episodes.dt, episodes.dt)
    time = pd.DataFrame(
        {
            **keys,
            "total_time": episodes.end * episodes.dt,
            "idle_time": idle_time(episodes.idle, active, episodes.dt),
            "mode_switches": (episodes.switch & active).sum(axis=0),
            "completed": episodes.completed,
        }
    )
    rows = []
    for name in TASK_NAMES:
        cols = episodes.task == name
        for i, ph in enumerate(TASKS[name]):
            pref = PREFERENCES[ph.preference or "stab"]
            desired = fork_direction(robot, GOALS.index(ph.goal), pref.theta)
            mask = (episodes.phase[:-1, cols] == i) & active[:, cols]
            rows.append(
                pd.DataFrame(
                    {
                        "robot": robot.name,
                        "participant": episodes.participant[cols],
                        "condition": episodes.condition[cols],
                        "assistance": episodes.assistance[cols],
                        "task": name,
                        "phase": ph.name,
                        "preference": pref.name,
                        "alignment": alignment(direction[:, cols], desired, mask),
                        "steps": mask.sum(axis=0),
                    }
                )
            )
    align = pd.concat(rows, ignore_index=True)
    return {"goal_error": error, "time": time, "alignment": align}
