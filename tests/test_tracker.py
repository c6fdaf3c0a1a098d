"""One waypoint tracker: the simulation's observer and the live station see the same phases and times."""

import types

import numpy as np
from stand_ins import LinearDecoder

from lasa.live.station import SessionConfig, Station
from lasa.people.cohort import draw_cohort
from lasa.people.design import StudyConfig
from lasa.people.simulation import _observe, prepare, start
from lasa.world.eating import TASK_NAMES, make_eating_task, waypoints


def scripted_path(task, name: str) -> np.ndarray:
    """Joint states from the start through every waypoint of task ``name``: 4 steps there, 2 held."""
    path, q = [task.start], task.start
    for wp in waypoints(name):
        pose = task.pose(wp.goal, wp.theta, wp.depth)
        path += [q + (pose - q) * k / 4 for k in range(1, 5)] + [pose, pose]
        q = pose
    return np.array(path)


def test_the_simulation_and_the_live_station_track_the_same_phases_and_times():
    task = make_eating_task()
    path = scripted_path(task, "Dessert")
    station = Station(SessionConfig(task="Dessert", condition="R"))
    live_phase, live_done = [], []
    for q in path:
        station.track(q)
        live_phase.append(station.phase)
        live_done.append(station.done)

    config = StudyConfig(horizon=len(path))
    setting = prepare(task, LinearDecoder(), draw_cohort(1, seed=1), task.robot.control, config, 0, ("R",))
    state = start(setting)
    n_e = len(setting.layout.part)
    runner = types.SimpleNamespace(running=np.ones(n_e, bool))
    sim_done = np.zeros((len(path), n_e), bool)
    for t, q in enumerate(path):
        runner.state = np.tile(q, (n_e, 1))
        finished = _observe(setting, state, t, runner)
        runner.running = runner.running & ~finished
        sim_done[t] = ~runner.running
    dessert = np.flatnonzero(setting.layout.tsk == TASK_NAMES.index("Dessert"))
    assert len(dessert) == 2  # R and R+SA: the tracker reads the fork, not the condition
    for e in dessert:
        assert state.phase[: len(path), e].tolist() == live_phase
        assert sim_done[:, e].tolist() == live_done
    assert (
        live_done.index(True) == 45 and live_phase[8:10] == [0, 1] and sorted(set(live_phase)) == [0, 1, 2, 3]
    )
