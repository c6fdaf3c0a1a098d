"""Kinesthetic demonstrations: recording, segmentation, labels, beliefs, the file's checks, the CLI, and one
recording on franky-sim that trains a decoder a station then drives."""

from __future__ import annotations

import dataclasses
import os
import signal
import threading
import time

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from lasa.base.config import to_dict
from lasa.base.errors import ArtifactError
from lasa.base.paths import Paths
from lasa.experiments import eating_task
from lasa.live import teleop
from lasa.live.devices import StickSample
from lasa.live.kinesthetic import JointReader, Recording, record, save_demonstrations_of
from lasa.live.link import LinkError, SimLink
from lasa.live.station import SessionConfig, Station
from lasa.method.dataset import REACH, STROKE, load_demonstrations, save_demonstrations
from lasa.method.decoder import save_checkpoint
from lasa.method.kinesthetic import (
    SegmentConfig,
    load_recorded,
    recorded_demonstrations,
    segment,
    stroke_distances,
    tilts,
)
from lasa.method.step import Assist, advance
from lasa.method.train import TrainConfig, train_decoder
from lasa.people.demos import EATING_DEMOS
from lasa.world.eating import fork_direction, fork_frame, make_eating_task


@pytest.fixture(scope="module")
def task():
    return make_eating_task()


def _line(a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """n samples from a (excluded) to b (included)."""
    return a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a)


def _script(task) -> tuple[np.ndarray, dict[str, slice]]:
    """Home at rest (4 samples), a reach to the middle bowl's stab entry (30), a stroke down and up (10 + 10),
    rest there (5), a reach to the icing's scoop entry (30), a stroke down and up, a return home (30)."""
    home, mid, ice = task.start, task.target(1, 0.0), task.target(2, 1.0)
    parts = {
        "rest0": np.repeat(home[None], 4, 0),
        "reach1": _line(home, mid, 30),
        "stroke1": np.concatenate(
            [task.pose(1, 0.0, np.linspace(0, 1, 11)[1:]), _line(task.pose(1, 0.0, 1.0), mid, 10)]
        ),
        "rest1": np.repeat(mid[None], 5, 0),
        "reach2": _line(mid, ice, 30),
        "stroke2": np.concatenate(
            [task.pose(2, 1.0, np.linspace(0, 1, 11)[1:]), _line(task.pose(2, 1.0, 1.0), ice, 10)]
        ),
        "back": _line(ice, home, 30),
    }
    where, k = {}, 0
    for name, part in parts.items():
        where[name] = slice(k, k + len(part))
        k += len(part)
    return np.concatenate(list(parts.values())), where


def test_stroke_distances_and_tilts_at_known_poses(task):
    for g, theta in ((0, 0.0), (1, 0.5), (2, 1.0), (3, 0.25)):
        tip, rotation = fork_frame(task.robot, g, theta, 0.5)
        end = fork_frame(task.robot, g, theta, 1.0)[0]  # every tilt's stroke ends here, 1 cm into the food
        dist = stroke_distances(task, np.array([tip, end + [0.0, 0.0, 0.2]]))
        assert dist[0, g] < 1e-9  # on the stroke: the surface holds it
        # 20 cm above the end: 15 cm above the stab's entry (its stroke is vertical, 5 cm long)
        assert_allclose(dist[1, g], 0.15, atol=1e-9)
        assert np.delete(dist[0], g).min() > 0.05  # the other goals are further than the radius
        direction = fork_direction(task.robot, g, theta)
        assert_allclose(rotation[:, 2], direction, atol=1e-12)
        assert_allclose(tilts(task, direction[None], np.array([g])), [theta], atol=1e-12)
    turned_away = fork_direction(task.robot, 1, 0.5) * [-1.0, -1.0, 1.0]  # tilted the other way
    assert tilts(task, turned_away[None], np.array([1]))[0] < 0.5


def test_segment_a_scripted_recording(task):
    states, at = _script(task)
    seg = segment(task, states, task.robot.control.dt)
    n = len(states) - 1
    assert seg.keep.shape == (n,)
    # at rest: the first three samples (the fourth moves off), the five at the middle bowl (the last of the
    # stroke arrives there and stays): dropped
    assert not seg.keep[:3].any() and seg.keep[3]
    assert not seg.keep[at["rest1"].start - 1 : at["rest1"].stop - 1].any()
    # the reach from home is a reach to the middle bowl, its early half far from any bowl
    early = slice(3, 3 + 15)
    assert_array_equal(seg.phase[early], REACH)
    assert_array_equal(seg.goal[early], 1)
    # the strokes are strokes at their bowls, at their tilts (0: stab; 1: scoop)
    for name, goal, theta in (("stroke1", 1, 0.0), ("stroke2", 2, 1.0)):
        part = slice(at[name].start, at[name].stop - 1)
        assert_array_equal(seg.phase[part], STROKE)
        assert_array_equal(seg.goal[part], goal)
        assert_allclose(seg.theta[part], theta, atol=0.05)
    # the reach to the icing is labelled with the icing and the median tilt of its stay there
    reach2 = slice(at["reach2"].start + 5, at["reach2"].start + 20)
    assert_array_equal(seg.goal[reach2], 2)
    assert_allclose(seg.theta[reach2], 1.0, atol=0.05)
    # two demonstrations: one per bowl; the return home arrives nowhere and is dropped past the icing
    assert_array_equal(np.unique(seg.demo[seg.keep]), [0, 1])
    assert_array_equal(np.unique(seg.goal[seg.demo == 0]), [1])
    assert not seg.keep[-10:].any() and (seg.goal[-10:] == -1).all()


def test_recorded_demonstrations_tuples_copies_and_beliefs(task):
    control = task.robot.control
    states, at = _script(task)
    demos, seg = recorded_demonstrations(task, control, states)
    clean = demos.clean()
    keep = seg.keep
    assert len(clean) == keep.sum() and len(demos) == 3 * len(clean)  # two noisy copies of each
    assert_allclose(clean.states, states[:-1][keep])
    assert_allclose(clean.actions, (states[1:] - states[:-1])[keep] / control.dt)
    assert_array_equal(demos.perturbed, np.arange(len(demos)) >= len(clean))
    # the belief is the station's online update along the kept samples (Assist/advance, the runner's step)
    assist = Assist(task, control, np.array([0.0]))
    log_b = np.full((1, task.n_goals), -np.log(task.n_goals))
    for k in range(len(clean)):
        assert_allclose(clean.beliefs[k], np.exp(log_b[0]), rtol=1e-12, atol=1e-15)
        log_b = advance(assist, clean.states[k][None], log_b, clean.actions[k][None]).log_belief
    assert clean.beliefs.max() <= control.belief_cap + 1e-12  # the study's cap
    idx = np.flatnonzero(keep)
    for name, goal in (("stroke1", 1), ("stroke2", 2)):  # confident in each bowl by its stroke's end
        assert clean.beliefs[np.searchsorted(idx, at[name].stop - 2), goal] > 0.9


def test_copies_default_as_the_synthetic_demonstrations():
    config = SegmentConfig()
    for name in ("n_perturb", "perturb_std", "perturb_gain", "seed"):
        assert getattr(config, name) == getattr(EATING_DEMOS, name), name


def test_load_recorded_checks_the_file(task, tmp_path):
    demos, _ = recorded_demonstrations(task, task.robot.control, _script(task)[0])
    good = save_demonstrations(demos, tmp_path / "good.npz")
    assert len(load_recorded(good, task)) == len(demos)
    with pytest.raises(ArtifactError, match="does not exist"):
        load_recorded(tmp_path / "missing.npz", task)
    with pytest.raises(ArtifactError, match="not 'panda'"):
        load_recorded(
            save_demonstrations(dataclasses.replace(demos, robot="planar5"), tmp_path / "r.npz"), task
        )
    three = dataclasses.replace(demos, beliefs=demos.beliefs[:, :3])
    with pytest.raises(ArtifactError, match=r"beliefs has shape .*, not \(\d+, 4\)"):
        load_recorded(save_demonstrations(three, tmp_path / "g.npz"), task)
    wrong_goal = dataclasses.replace(demos, goal=demos.goal + 4)
    with pytest.raises(ArtifactError, match="goals are not all"):
        load_recorded(save_demonstrations(wrong_goal, tmp_path / "w.npz"), task)


def test_the_config_trains_from_a_recorded_file(task, tmp_path):
    demos, _ = recorded_demonstrations(task, task.robot.control, _script(task)[0])
    path = save_demonstrations(demos, tmp_path / "rec.npz")
    config = eating_task.Config(recorded_demos=str(path))
    assert "recorded" in eating_task.demonstrations_used(config)
    used = eating_task.demonstrations(task, task.robot.control, config)
    assert_array_equal(used.states, demos.states)
    uncapped = dataclasses.replace(task.robot.control, belief_cap=None)
    relabelled = eating_task.demonstrations(task, uncapped, config)
    assert relabelled.beliefs.max() > task.robot.control.belief_cap  # recomputed without the cap
    assert eating_task.Config().recorded_demos is None
    assert "synthetic" in eating_task.demonstrations_used(eating_task.Config())


class _Flaky:
    """A link that reads ``good`` times, then fails."""

    def __init__(self, good: int) -> None:
        self.left = good

    def read(self) -> np.ndarray:
        if self.left == 0:
            raise LinkError("lost")
        self.left -= 1
        return np.zeros(7)


def test_record_schedule_stop_and_signals():
    start = time.perf_counter()
    rec = record(SimLink(np.arange(7.0)), 0.02, duration=0.2)
    assert rec.stopped == "duration" and rec.states.shape == (11, 7)
    assert time.perf_counter() - start >= 0.2
    assert_allclose(np.diff(rec.times), 0.02, atol=0.015)
    calls: list[int] = []
    rec = record(
        SimLink(np.zeros(7)), 0.01, stop=lambda: len(calls) >= 5, on_sample=lambda k, s: calls.append(k)
    )
    assert rec.stopped == "stopped" and len(rec.states) == 5
    assert record(_Flaky(3), 0.01).stopped == "link: lost"
    assert len(record(_Flaky(3), 0.01).states) == 3

    def interrupt(k: int, s: np.ndarray) -> None:
        if k == 2:
            os.kill(os.getpid(), signal.SIGINT)

    rec = record(SimLink(np.zeros(7)), 0.01, on_sample=interrupt)
    assert rec.stopped == "SIGINT" and len(rec.states) == 3  # what was read is kept


def test_save_refuses_a_recording_without_demonstrations(task, tmp_path):
    still = Recording(np.repeat(task.start[None], 20, 0), np.arange(20) * 0.1, 0.1, "duration")
    with pytest.raises(Exception, match="no demonstration"):
        save_demonstrations_of(still, tmp_path / "d.npz")
    assert (tmp_path / "d.raw.npz").is_file() and not (tmp_path / "d.npz").exists()  # the raw stream kept


def test_cli_errors_are_one_line(tmp_path, capsys):
    assert teleop.main(["demos", "--franka", "127.0.0.1", "--out", str(tmp_path / "x.txt")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --out must name a .npz file") and "\n" not in err
    with pytest.raises(SystemExit) as exc:
        teleop.main(["demos", "--out", "x.npz"])
    assert exc.value.code == 2
    with pytest.raises(SystemExit):
        teleop.main(["demos", "--franka", "127.0.0.1", "--out", "x.npz", "--realtime", "maybe"])


# ---- one recording on franky-sim, end to end ----


@pytest.fixture(scope="module")
def franky_sim():
    from lasa.live.franka import simulator  # franky-sim is pinned in environment.lock: never skipped

    with simulator() as address:
        yield address


def _guide(robot, waypoints: list[np.ndarray], done: threading.Event) -> None:
    """Move the simulated arm through ``waypoints`` (a person's guiding hand), then say so."""
    import franky

    try:
        for q in waypoints:
            robot.move(franky.JointMotion(franky.JointState(q.tolist()), relative_dynamics_factor=0.6))
    finally:
        done.set()


def test_record_on_franky_sim_train_and_drive(task, franky_sim, tmp_path, capsys):
    from lasa.live.franka import connect

    robot = connect(franky_sim)
    control = task.robot.control
    import franky

    robot.move(franky.JointMotion(franky.JointState(task.start.tolist()), relative_dynamics_factor=0.6))
    entry1, entry2 = task.target(1, 0.0), task.target(2, 1.0)
    script = [entry1, task.pose(1, 0.0, 1.0), entry1, entry2, task.pose(2, 1.0, 1.0), entry2]
    done = threading.Event()
    mover = threading.Thread(target=_guide, args=(robot, script, done))
    mover.start()
    recording = record(JointReader(robot), control.dt, duration=30.0, stop=done.is_set)
    mover.join()
    assert recording.stopped == "stopped" and len(recording.states) > 20
    path, seg = save_demonstrations_of(recording, tmp_path / "demos.npz")
    demos = load_recorded(path, task)
    clean = demos.clean()
    assert_array_equal(np.unique(clean.goal), [1, 2])  # the middle bowl, then the icing
    assert set(np.unique(clean.phase)) == {REACH, STROKE}
    assert_allclose([np.median(clean.theta[clean.goal == g]) for g in (1, 2)], [0.0, 1.0], atol=0.15)
    assert (tmp_path / "demos.raw.npz").is_file()
    # a quick decoder from the file (the QUICK config's sizes), saved where a station looks for it
    train = TrainConfig(z_dim=2, steps=60, batch_size=64, hidden=32, depth=2, log_every=20)
    model, _ = train_decoder(load_demonstrations(path, "panda"), control, train, progress=False)
    paths = Paths.of(tmp_path / "build", tmp_path / "figures")
    save_checkpoint(
        model, paths.artifact("eating_decoder", "panda"), train=to_dict(train), control=to_dict(control)
    )
    station = Station(
        SessionConfig(task="Dessert", condition="LA+SA", build_dir=str(tmp_path / "build")),
        link=SimLink(task.start),
    )
    start = station.state.copy()
    for _ in range(15):
        rec = station.step(StickSample(raw=np.array([0.8, -0.3])))
    assert np.abs(rec["a_h"]).max() > 0  # the recorded decoder drives the arm
    assert np.linalg.norm(station.state - start) > 0.01
    assert_allclose(rec["b"].sum(), 1.0)
