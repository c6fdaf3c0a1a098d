"""The simulated eating study's driver, whichever participant model chooses: the same episodes
(:func:`lasa.people.design.layout`), each with its stream ``default_rng([seed, participant, condition,
task])`` (the SA members' paired), waypoints tracked, the record kept, the episode runner stepping them."""

from __future__ import annotations

import dataclasses
import functools

import mujoco
import numpy as np

from lasa.base.conditions import CONDITIONS
from lasa.base.config import ControlConfig
from lasa.base.errors import ConfigError
from lasa.method.belief import belief_targets, uniform_log_belief
from lasa.method.decoder import ActionDecoder
from lasa.method.retarget import MODES, Retargeting, retarget_action, twist
from lasa.method.runner import Chooser, Now, Runner
from lasa.method.step import Assist, check_decoder, latent_grid
from lasa.people.cohort import Cohort
from lasa.people.design import Layout, StudyConfig, layout
from lasa.people.policy import progress_gain
from lasa.world.eating import TASK_NAMES, EatingTask
from lasa.world.fork import WaypointTracker, tip_frames
from lasa.world.record import Episodes


@dataclasses.dataclass(frozen=True)
class Setting:
    """What every step of a study reads and never changes (a model adds its own fields)."""

    task: EatingTask
    decoder: ActionDecoder
    control: ControlConfig
    config: StudyConfig
    layout: Layout
    streams: list[np.random.Generator]  # each episode's own random stream
    waypoints: WaypointTracker  # every task's waypoints, with the study's tolerances
    grid: np.ndarray  # the stick's grid (K, 2), rest in the middle
    rest: int  # index of the rest position in grid
    unit: float  # the best translation one step of Retargeting makes [m]
    retarget: Retargeting
    r_twist: np.ndarray  # the fork twist of every (Retargeting mode, grid input) at full scale (M, K, 6)
    goal_sets: np.ndarray  # the belief's targets
    data: mujoco.MjData


@dataclasses.dataclass
class State:
    """The participants' side of a running study, (E, ...) each, the fork's frames now (:func:`tip_frames`)
    and its record."""

    mode: np.ndarray  # Retargeting mode (E,)
    w: np.ndarray  # current waypoint (E,)
    waited: np.ndarray  # consecutive idle steps (E,)
    pos: np.ndarray  # tip position now (E, 3)
    axis: np.ndarray  # fork direction now (E, 3)
    jp: np.ndarray  # translational Jacobian now (E, 3, n)
    jr: np.ndarray  # rotational Jacobian now (E, 3, n)
    tip: np.ndarray
    direction: np.ndarray
    phase: np.ndarray
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
    """The study's fixed parts; ConfigError on a decoder that does not fit the task or the 2-axis stick,
    or interfaces that are not a non-empty subset of ``("R", "LA")``."""
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
    grid = latent_grid(config.n_z, 2)
    return Setting(
        task=task,
        decoder=decoder,
        control=control,
        config=config,
        layout=episodes,
        streams=streams,
        waypoints=WaypointTracker.of(task.robot, config.position_tol, config.angle_tol),
        grid=grid,
        rest=int(np.flatnonzero(np.all(grid == 0.0, axis=1))[0]),
        unit=control.dt * config.retarget.linear_speed,
        retarget=Retargeting(task.robot, control.dt, config.retarget),
        r_twist=twist(np.arange(len(MODES))[:, None], grid, config.retarget),
        goal_sets=belief_targets(task, control.likelihood),
        data=mujoco.MjData(task.robot.model),
    )


def start(setting: Setting) -> State:
    """Every episode at the task's start, nothing recorded yet."""
    n_e = len(setting.layout.part)
    horizon = setting.config.horizon
    n = setting.task.robot.n_joints
    return State(
        **{k: np.zeros(n_e, dtype=int) for k in ("mode", "w", "waited")},
        **{k: np.zeros((n_e, 3)) for k in ("pos", "axis")},
        **{k: np.zeros((n_e, 3, n)) for k in ("jp", "jr")},
        **{k: np.empty((horizon + 1, n_e, 3)) for k in ("tip", "direction")},
        phase=np.zeros((horizon + 1, n_e), dtype=int),
        **{k: np.zeros((horizon, n_e), dtype=bool) for k in ("idle", "switch")},
    )


def _observe(setting: Setting, state: State, t: int, runner: Runner) -> np.ndarray:
    """Record the fork at step t, move on past reached waypoints; the episodes that finished."""
    tsk = setting.layout.tsk
    state.pos, state.axis, state.jp, state.jr = tip_frames(setting.task.robot, setting.data, runner.state)
    state.tip[t], state.direction[t] = state.pos, state.axis
    state.w, finished = setting.waypoints.advance(tsk, state.w, state.pos, state.axis, runner.running)
    state.phase[t] = setting.waypoints.phase[tsk, state.w]
    return finished


def progress(study: Setting, run: State, idx: np.ndarray, dp: np.ndarray, new_dir: np.ndarray) -> np.ndarray:
    """How far tip motions ``dp`` to directions ``new_dir`` (A, P, 3) of episodes ``idx`` lower the cost to
    their waypoints (:func:`lasa.people.policy.progress_gain`), (A, P) [m]."""
    tsk, w = study.layout.tsk[idx], run.w[idx]
    p_star, d_star = study.waypoints.position[tsk, w], study.waypoints.direction[tsk, w]
    weight = study.config.participant.rotation_weight
    return progress_gain(run.pos[idx], run.axis[idx], dp, new_dir, p_star, d_star, weight)


def act(
    study: Setting, run: State, now: Now, a_h: np.ndarray, z: np.ndarray, press: np.ndarray, rest: np.ndarray
) -> None:
    """Fill in the Retargeting rows of the human actions ``a_h`` (A, n) from stick inputs ``z`` (A, 2) and
    mode ``press``es (the latent actions' are the caller's), and record the idle and switch steps."""
    t, idx = now.t, now.rows
    r = ~study.layout.is_la[idx]
    if r.any():
        a_h[r], run.mode[idx[r]] = retarget_action(
            study.retarget, now.state[r], run.mode[idx[r]], z[r], press[r]
        )
    run.idle[t, idx], run.switch[t, idx] = rest, press
    run.waited[idx] = np.where(rest, run.waited[idx] + 1, 0)


def run_steps(setting: Setting, state: State, choose: Chooser, desc: str, progress: bool) -> Episodes:
    """The study's record, the runner stepping the running episodes by ``choose`` (the participant model)
    from ``state`` (:func:`start`, advanced in place); ``desc`` labels the progress bar."""
    lay, task, n_e = setting.layout, setting.task, len(setting.layout.part)
    # the rows without assistance (R, LA) skip its computation: the same steps (Assist.only_blended)
    assist = Assist(
        task, setting.control, lay.alpha, lay.assistance_run, setting.goal_sets, only_blended=True
    )
    start_state = np.broadcast_to(task.start, (n_e, task.robot.n_joints))
    runner = Runner(assist, start_state, uniform_log_belief(n_e, task.n_goals))
    observe = functools.partial(_observe, setting, state)
    record = runner.run(choose, setting.config.horizon, observe, progress, desc)
    last = int(record.end.max())
    state.tip[last + 1 :], state.direction[last + 1 :] = state.tip[last], state.direction[last]
    state.phase[last + 1 :] = state.phase[last]
    return Episodes(
        participant=lay.part,
        condition=np.asarray(CONDITIONS)[lay.cond],
        assistance=lay.assistance,
        task=np.asarray(TASK_NAMES)[lay.tsk],
        order=lay.order,
        states=record.states,
        **{k: getattr(state, k) for k in ("tip", "direction", "phase", "idle", "switch")},
        end=record.end,
        completed=record.end < setting.config.horizon,
        dt=setting.control.dt,
        belief=record.beliefs,
        waypoint=state.w,
    )
