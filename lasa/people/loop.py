"""The eating study's loop, whichever participant model runs it: set up, observe, record.

Every model of participant (:mod:`lasa.people.participants`, :mod:`lasa.people.planning`) runs
the same study: the same episodes (:func:`lasa.people.design.layout`), each drawing from its
own random stream ``default_rng([seed, participant, condition, task])`` (shared by the SA
members: common random numbers, so the members' comparisons are paired), the same waypoints,
and the same record (:class:`lasa.people.design.Episodes`). At every step :func:`run_steps`
observes every episode (the record, the waypoints reached, the episodes that finished) and
then lets the model step the running ones.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import mujoco
import numpy as np
from tqdm.auto import tqdm

from lasa.base.conditions import CONDITIONS
from lasa.base.config import ControlConfig
from lasa.base.errors import ConfigError
from lasa.method.belief import belief, belief_targets, uniform_log_belief
from lasa.method.decoder import ActionDecoder
from lasa.method.retarget import MODES, Retargeting, twist
from lasa.method.step import advance, check_decoder, latent_grid
from lasa.people.cohort import Cohort
from lasa.people.design import TASK_NAMES, Episodes, Layout, StudyConfig, layout
from lasa.people.kinematics import tip_frames, waypoint_arrays, waypoint_reached
from lasa.world.eating import EatingTask

__all__ = ["Setting", "State", "prepare", "start", "move_robots", "run_steps"]


@dataclasses.dataclass(frozen=True)
class Setting:
    """What every step of a study reads and never changes (a model adds its own fields)."""

    task: EatingTask
    decoder: ActionDecoder
    control: ControlConfig
    config: StudyConfig
    layout: Layout
    streams: list[np.random.Generator]  # each episode's own random stream
    wp_pos: np.ndarray  # every task's waypoints (lasa.people.kinematics.waypoint_arrays)
    wp_dir: np.ndarray
    wp_phase: np.ndarray
    n_wp: np.ndarray
    grid: np.ndarray  # the stick's grid (K, 2), rest in the middle
    rest: int  # index of the rest position in grid
    unit: float  # the best translation one step of Retargeting makes [m]
    retarget: Retargeting
    r_twist: np.ndarray  # the fork twist of every (Retargeting mode, grid input) at full scale (M, K, 6)
    goal_sets: np.ndarray  # the belief's targets
    data: mujoco.MjData


@dataclasses.dataclass
class State:
    """The state of a running study, (E, ...) each: the robots, the participants, and the record.

    ``pos``, ``axis``, ``jp`` and ``jr`` are the fork's frames at the current joints
    (:func:`lasa.people.kinematics.tip_frames`), read when the step is observed.
    """

    s: np.ndarray  # joints (E, n)
    log_b: np.ndarray  # log belief (E, G)
    mode: np.ndarray  # Retargeting mode (E,)
    w: np.ndarray  # current waypoint (E,)
    end: np.ndarray  # step each episode ended (E,)
    waited: np.ndarray  # consecutive idle steps (E,)
    running: np.ndarray  # (E,) bool
    pos: np.ndarray  # tip position now (E, 3)
    axis: np.ndarray  # fork direction now (E, 3)
    jp: np.ndarray  # translational Jacobian now (E, 3, n)
    jr: np.ndarray  # rotational Jacobian now (E, 3, n)
    states: np.ndarray
    tip: np.ndarray
    direction: np.ndarray
    phase: np.ndarray
    beliefs: np.ndarray
    idle: np.ndarray
    switch: np.ndarray


def prepare(
    task: EatingTask,
    decoder: ActionDecoder,
    cohort: Cohort,
    control: ControlConfig,
    config: StudyConfig,
    seed: int,
    interfaces: tuple[str, ...],
) -> Setting:
    """Check the inputs and build the study's fixed parts.

    Raises:
        ConfigError: on a decoder that does not fit the task or the 2-axis stick, or
            interfaces that are not a non-empty subset of ``("R", "LA")``.
    """
    check_decoder(decoder, task)
    if not interfaces or not set(interfaces) <= {"R", "LA"}:
        raise ConfigError(f"interfaces must be a non-empty subset of ('R', 'LA'), got {interfaces!r}")
    if decoder.z_dim != 2:
        raise ConfigError(f"the study's joystick has 2 axes; the decoder has z_dim={decoder.z_dim}")
    episodes = layout(cohort, control, tuple(config.assistance), interfaces)
    streams = [
        np.random.default_rng([seed, int(p), int(c), int(k)])
        for p, c, k in zip(episodes.part, episodes.cond, episodes.tsk, strict=True)
    ]
    robot = task.robot
    wp_pos, wp_dir, wp_phase, n_wp = waypoint_arrays(robot)  # padded per task
    grid = latent_grid(config.n_z, 2)
    return Setting(
        task=task,
        decoder=decoder,
        control=control,
        config=config,
        layout=episodes,
        streams=streams,
        wp_pos=wp_pos,
        wp_dir=wp_dir,
        wp_phase=wp_phase,
        n_wp=n_wp,
        grid=grid,
        rest=int(np.flatnonzero(np.all(grid == 0.0, axis=1))[0]),
        unit=control.dt * config.retarget.linear_speed,
        retarget=Retargeting(robot, control.dt, config.retarget),
        r_twist=twist(np.arange(len(MODES))[:, None], grid, config.retarget),
        goal_sets=belief_targets(task, control.likelihood),
        data=mujoco.MjData(robot.model),
    )


def start(setting: Setting) -> State:
    """Every episode at the task's start, nothing recorded yet."""
    n_e, horizon = len(setting.layout.part), setting.config.horizon
    n, g = setting.task.robot.n_joints, setting.task.n_goals
    zeros = np.zeros(n_e, dtype=int)
    return State(
        s=np.broadcast_to(setting.task.start, (n_e, n)).copy(),
        log_b=uniform_log_belief(n_e, g),
        mode=zeros.copy(),
        w=zeros.copy(),
        end=np.full(n_e, horizon),
        waited=zeros.copy(),
        running=np.ones(n_e, dtype=bool),
        pos=np.zeros((n_e, 3)),
        axis=np.zeros((n_e, 3)),
        jp=np.zeros((n_e, 3, n)),
        jr=np.zeros((n_e, 3, n)),
        states=np.empty((horizon + 1, n_e, n)),
        tip=np.empty((horizon + 1, n_e, 3)),
        direction=np.empty((horizon + 1, n_e, 3)),
        phase=np.zeros((horizon + 1, n_e), dtype=int),
        beliefs=np.empty((horizon + 1, n_e, g)),
        idle=np.zeros((horizon, n_e), dtype=bool),
        switch=np.zeros((horizon, n_e), dtype=bool),
    )


def _observe(setting: Setting, state: State, t: int) -> bool:
    """Record step t, move on past reached waypoints; True when the study is over."""
    tsk = setting.layout.tsk
    pos, axis, jp, jr = tip_frames(setting.task.robot, setting.data, state.s)
    state.pos, state.axis, state.jp, state.jr = pos, axis, jp, jr
    state.states[t], state.tip[t], state.direction[t] = state.s, pos, axis
    state.beliefs[t] = belief(state.log_b)
    # a waypoint reached: on to the next one, or the task is done
    here = setting.wp_pos[tsk, state.w]
    reached = state.running & waypoint_reached(pos, axis, here, setting.wp_dir[tsk, state.w], setting.config)
    state.w = np.where(reached, state.w + 1, state.w)
    finished = reached & (state.w >= setting.n_wp[tsk])
    state.end[finished] = t
    state.running &= ~finished
    state.w = np.minimum(state.w, setting.n_wp[tsk] - 1)
    state.phase[t] = setting.wp_phase[tsk, state.w]
    if t < setting.config.horizon and state.running.any():
        return False
    state.states[t + 1 :], state.tip[t + 1 :], state.direction[t + 1 :] = state.s, pos, axis
    state.beliefs[t + 1 :], state.phase[t + 1 :] = state.beliefs[t], state.phase[t]
    return True


def move_robots(setting: Setting, state: State, idx: np.ndarray, a_h: np.ndarray, b: np.ndarray) -> None:
    """The robots of episodes ``idx`` take their step under the human actions ``a_h`` (A, n):
    assistance, blend, belief update (:func:`lasa.method.step.advance`, ``b`` the beliefs now)."""
    lay = setting.layout
    result = advance(
        setting.task,
        setting.control,
        state.s[idx],
        state.log_b[idx],
        a_h,
        lay.alpha[idx],
        setting.goal_sets,
        b,
        lay.assistance_run[idx],
    )
    state.s[idx], state.log_b[idx] = result.state, result.log_belief


def _episodes(setting: Setting, state: State) -> Episodes:
    """The record of a finished study."""
    lay = setting.layout
    return Episodes(
        participant=lay.part,
        condition=np.asarray(CONDITIONS)[lay.cond],
        assistance=lay.assistance,
        task=np.asarray(TASK_NAMES)[lay.tsk],
        order=lay.order,
        states=state.states,
        tip=state.tip,
        direction=state.direction,
        phase=state.phase,
        idle=state.idle,
        switch=state.switch,
        end=state.end,
        completed=state.end < setting.config.horizon,
        dt=setting.control.dt,
        belief=state.beliefs,
        waypoint=state.w,
    )


def run_steps(
    setting: Setting,
    state: State,
    step: Callable[[int, np.ndarray], None],
    desc: str,
    progress: bool,
) -> Episodes:
    """Run the study to its end: observe every step, then ``step(t, running episodes)``.

    Args:
        setting: The study's fixed parts (:func:`prepare`).
        state: Its state at the start (:func:`start`), advanced in place.
        step: The participant model's step of the running episodes (their indices) at step t.
        desc: The progress bar's label.
        progress: Show a progress bar.

    Returns:
        The study's record.
    """
    bar = tqdm(total=setting.config.horizon, desc=desc, disable=not progress)
    for t in range(setting.config.horizon + 1):
        if _observe(setting, state, t):
            break
        step(t, np.flatnonzero(state.running))
        bar.update(1)
    bar.close()
    return _episodes(setting, state)
