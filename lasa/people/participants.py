"""The eating study (Sec. VI) with simulated participants who look one step ahead: each foresees every
input's motion of the fork's tip (a latent action's through the arm's Jacobian, a Retargeting input's
as its twist, after a press for another mode) and chooses by :mod:`lasa.people.policy`."""

from __future__ import annotations

import functools

import numpy as np

from lasa.base.config import ControlConfig
from lasa.method.decoder import ActionDecoder
from lasa.method.retarget import MODES
from lasa.method.runner import Now
from lasa.method.step import decode_candidates, human_action
from lasa.people.cohort import Cohort
from lasa.people.design import StudyConfig
from lasa.people.policy import choose
from lasa.people.simulation import Setting, State, act, prepare, progress, run_steps, start
from lasa.world.eating import EatingTask
from lasa.world.fork import normalise, tip_motion
from lasa.world.record import Episodes


def _choose(study: Setting, run: State, now: Now) -> np.ndarray:
    """The chooser: every running participant's input, one step ahead (or rest); a_h (A, n)."""
    n_k = len(study.grid)
    n_m = len(MODES)
    dt = study.control.dt
    idx = now.rows
    rest = study.rest
    la = study.layout.is_la[idx]
    r_rows = np.flatnonzero(~study.layout.is_la[idx])
    a_i = run.axis[idx]
    # phi of the stick positions (zero for Retargeting), and the foreseen tip motion of every (mode, z)
    # candidate: displacements and new directions, (A, M K, 3) each
    dp = np.zeros((len(idx), n_m * n_k, 3))
    new_dir = np.repeat(a_i[:, None, :], n_m * n_k, axis=1)
    phi = np.zeros((len(idx), n_k, study.task.robot.n_joints))
    if la.any():
        rows = idx[la]
        phi[la] = decode_candidates(study.decoder, study.grid, now.state[la], now.belief[la])
        dp[la, :n_k], new_dir[la, :n_k] = tip_motion(run.jp[rows], run.jr[rows], a_i[la], dt * phi[la])
    if len(r_rows):
        tw = study.r_twist.reshape(n_m * n_k, 6)
        dp[~la] = dt * tw[None, :, :3]
        new_dir[~la] = normalise(a_i[~la, None, :] + dt * np.cross(tw[None, :, 3:], a_i[~la, None, :]))
    # each candidate's progress in best-step units (-inf: no such input): LA's are the K stick
    # positions, R's every (mode, z) but other modes' rest, spread over the presses of the mode button
    gain = progress(study, run, idx, dp, new_dir) / study.unit
    valid = np.zeros_like(gain, dtype=bool)
    valid[la, :n_k] = True
    valid[r_rows] = True
    modes = np.arange(n_m)[None, :]
    r_mode = run.mode[idx[r_rows], None]
    valid[r_rows[:, None], modes * n_k + rest] = modes == r_mode
    rest_col = np.where(la, rest, run.mode[idx] * n_k + rest)
    gain[r_rows] /= np.repeat(1.0 + (modes - r_mode) % n_m, n_k, axis=1)
    gain = np.where(valid, gain, -np.inf)
    gain[np.arange(len(idx)), rest_col] = 0.0  # resting moves nothing
    pc = study.config.participant
    choice, wants = choose(gain, study.layout, idx, now.t, study.streams, run.waited, dt, pc)
    choice = np.where(wants, choice, rest_col)
    mode = choice // n_k
    k = choice % n_k
    z = study.grid[k]
    a_h = np.zeros((len(idx), study.task.robot.n_joints))
    a_h[la] = human_action(phi[la, k[la]], z[la], rest="zero")
    act(study, run, now, a_h, z, ~la & (mode != run.mode[idx]), choice == rest_col)
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
) -> Episodes:
    """Run every participant of ``cohort`` through both tasks under every condition of ``interfaces``
    (``("LA",)`` for another decoder variant), all episodes in one batch, with the 2-D ``decoder``;
    episode (i, condition, task) draws from its own stream of ``seed`` (ConfigError: as
    :func:`lasa.people.simulation.prepare`)."""
    study = prepare(task, decoder, cohort, control, config, seed, interfaces)
    run = start(study)
    desc = f"study: {len(cohort)} participants, {len(study.layout.part)} episodes"
    return run_steps(study, run, functools.partial(_choose, study, run), desc, progress)
