"""Live teleoperation without a person or a gamepad: scripted sessions, logs, replay, safety, the viewer."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from reference_step import latent_step, softmax, step_with

from lasa.base.config import ControlConfig, to_dict
from lasa.base.errors import ArtifactError, CheckpointError, ConfigError, DamagedLogError
from lasa.evidence.sessionlog import read_session
from lasa.live.devices import KeyboardDevice, ScriptedDevice, StickSample, safe_axes
from lasa.live.session import open_log
from lasa.live.station import SessionConfig, Station
from lasa.live.teleop import replay, run_session
from lasa.method.decoder import DecoderConfig, LatentActionModel, save_checkpoint
from lasa.method.train import TrainConfig, train_decoder
from lasa.people.demos import DemoConfig, collect_eating_demonstrations
from lasa.world.eating import STUDY_BELIEF_CAP, make_eating_task

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def build(tmp_path_factory):
    """A build folder holding a small eating decoder, as `make figures` would leave a real one."""
    out = tmp_path_factory.mktemp("build")
    task = make_eating_task()
    demos = collect_eating_demonstrations(
        task, task.robot.control, DemoConfig(n_theta=2, n_starts=1, n_adjust=0, n_perturb=1)
    )
    model, _ = train_decoder(
        demos,
        task.robot.control,
        TrainConfig(steps=60, hidden=16, depth=2, z_dim=2, batch_size=128),
        progress=False,
    )
    save_checkpoint(model, out / "models" / "eating_decoder_panda.pt")
    return out


def script(n: int, seed: int = 0) -> np.ndarray:
    return np.clip(np.random.default_rng(seed).normal(0, 0.7, (n, 2)), -1.2, 1.2)


def station(build, condition="LA+SA", task="Dessert"):
    return Station(SessionConfig(task=task, condition=condition, participant="t01", build_dir=str(build)))


@pytest.mark.parametrize("condition", ["R+SA", "LA+SA"])
def test_a_scripted_session_round_trips_and_replays_exactly(build, tmp_path, condition):
    st = station(build, condition)
    axes = script(60)
    axes[5] = np.nan  # a faulty axis
    device = ScriptedDevice(axes, mode=np.arange(60) % 17 == 3, connected=np.arange(60) != 9)
    writer = open_log(st, tmp_path)
    timing = run_session(st, device, writer, 200, realtime=False)
    frame, meta = read_session(writer.csv)
    assert meta["status"] == "complete" and meta["steps"] == len(frame) == timing["steps"] == 60
    assert meta["condition"] == condition and meta["participant"] == "t01" and meta["lasa_version"]
    assert (meta["decoder_sha256"] is None) == condition.startswith("R")
    assert (tmp_path / f"{writer.stem}.xml").read_text().startswith("<mujoco")
    for col in ("time", "raw0", "z0", "mode", "s0", "b3", "a_h6", "a_r0", "a6", "late"):
        assert col in frame.columns
    assert frame.loc[9, ["z0", "z1"]].tolist() == [0.0, 0.0]  # disconnected: zero input
    assert np.isnan(frame.loc[5, "raw0"]) and frame.loc[5, "z0"] == 0.0  # NaN axis: zero input
    result = replay(writer.csv)
    assert result["exact"] and result["max_state_difference"] == 0.0


def test_the_scene_xml_beside_a_session_compiles(build, tmp_path):
    import mujoco

    st = station(build, "LA")
    writer = open_log(st, tmp_path)
    run_session(st, ScriptedDevice(script(3)), writer, 10, realtime=False)
    model = mujoco.MjModel.from_xml_path(str(tmp_path / f"{writer.stem}.xml"))
    assert model.nq == st.robot.model.nq and model.site("fork_tip")


def test_bad_axes_are_zero_input():
    assert_array_equal(safe_axes(np.array([np.nan, 0.5])), [0.0, 0.5])
    assert_array_equal(safe_axes(np.array([np.inf, -7.0])), [0.0, -1.0])
    assert_array_equal(safe_axes(np.array([0.3, 0.4]), connected=False), [0.0, 0.0])
    with pytest.raises(ConfigError, match="2 axes"):
        safe_axes(np.zeros(3))


def test_a_nan_or_lost_axis_never_becomes_a_human_action(build):
    st = station(build, "LA")
    for sample in (
        StickSample(raw=np.array([np.nan, np.nan])),
        StickSample(raw=np.array([0.9, 0.9]), connected=False),
    ):
        rec = st.step(sample)
        assert_array_equal(rec["a_h"], np.zeros(7))
        assert np.all(np.isfinite(rec["s"]))


def test_the_stop_input_holds_the_robot(build):
    st = station(build, "R+SA")
    for _ in range(5):
        st.step(StickSample(raw=np.array([1.0, 1.0])))
    held, belief = st.state.copy(), st.belief.copy()
    for _ in range(10):
        rec = st.step(StickSample(raw=np.array([1.0, -1.0]), mode=True, stop=True))
        assert_array_equal(rec["a"], np.zeros(7))
    assert_array_equal(st.state, held)
    assert_array_equal(st.belief, belief)
    assert st.mode == 0  # a mode press while stopped does nothing


def test_limits_and_speed_bound_hold_under_random_input(build):
    for condition in ("R", "LA+SA"):
        st = station(build, condition)
        rng = np.random.default_rng(1)
        before = st.state.copy()
        for _ in range(80):
            st.step(StickSample(raw=rng.uniform(-3, 3, 2), mode=bool(rng.random() < 0.2)))
            assert np.all(st.state >= st.robot.lower) and np.all(st.state <= st.robot.upper)
            step = np.abs(st.state - before).max()
            assert step <= st.control.dt * st.control.max_joint_speed + 1e-12
            before = st.state.copy()


def test_an_interrupted_session_is_marked_and_keeps_its_rows(build, tmp_path):
    st = station(build, "LA")

    def crash(step, rec):
        if step == 24:
            raise KeyboardInterrupt

    writer = open_log(st, tmp_path)
    with pytest.raises(KeyboardInterrupt):
        run_session(st, ScriptedDevice(script(100)), writer, 200, realtime=False, on_step=crash)
    frame, meta = read_session(writer.csv)
    assert meta["status"] == "interrupted" and len(frame) == 25


def test_a_crash_loses_at_most_a_second(build, tmp_path):
    """Rows reach the disk every 10 steps (1 s at 10 Hz): a process that dies keeps them."""
    st = station(build, "LA")
    writer = open_log(st, tmp_path)
    run_session(st, ScriptedDevice(script(25)), None, 25, realtime=False, on_step=lambda i, rec: None)
    for i in range(25):
        writer.append([float(i)] * len(writer.columns))
    on_disk = writer.part.read_text().count("\n") - 1  # what a crash now would leave
    assert on_disk == 20
    frame, meta = read_session(writer.part)  # never closed: read as interrupted
    assert meta["status"] == "interrupted" and len(frame) == 20
    writer.close()


def test_the_keyboard_holds_axes_by_press_to_set():
    kb = KeyboardDevice()
    for key in (262, 262, 265):  # right, right, up
        kb.key_callback(key)
    assert_array_equal(kb.poll().raw, [0.5, 0.25])
    kb.key_callback(77)  # M: one mode press, read once
    assert kb.poll().mode and not kb.poll().mode
    kb.key_callback(32)  # space recentres
    assert_array_equal(kb.poll().raw, [0.0, 0.0])
    kb.key_callback(83)  # S toggles stop
    assert kb.poll().stop


def test_bad_sessions_are_errors(build):
    with pytest.raises(ConfigError, match="Panda"):
        SessionConfig(robot="planar5", task="Dessert")
    with pytest.raises(ConfigError, match=r"LA\+SA\+Entropy is the cups. condition"):
        SessionConfig(task="Entree", condition="LA+SA+Entropy")
    with pytest.raises(ConfigError, match="participant"):
        SessionConfig(participant="a b")


def test_schedule_and_questionnaire(tmp_path):
    from lasa.evidence.sessions import SCALES, likert_tests, read_likert
    from lasa.live.studykit import survey, write_schedule

    with pytest.warns(UserWarning, match="unevenly"):  # six: one full round of four orders and two
        schedule = pd.read_csv(write_schedule(6, tmp_path / "schedule.csv"))
    assert len(schedule) == 24 and set(schedule.groupby("participant").condition.nunique()) == {4}
    for p, answers in (("p00", [7, 6, 6, 7, 7]), ("p01", [6, 6, 5, 6, 7]), ("p02", [7, 7, 6, 6, 6])):
        survey(tmp_path, p, "LA+SA", answers)
        for c in ("R", "R+SA", "LA"):
            survey(tmp_path, p, c, [3, 4, 3, 3, 2])
    survey(tmp_path, "p00", "R", [2, 4, 3, 3, 2], overwrite=True)  # a re-answer replaces the old one
    likert = read_likert(tmp_path)
    assert len(likert) == 3 * 4 * len(SCALES)
    tests = likert_tests(likert)
    assert set(tests.scale) == set(SCALES) and (tests["diff"] > 0).all()
    with pytest.raises(ConfigError, match="whole number from 1 to 7"):
        survey(tmp_path, "p09", "LA", [8, 1, 1, 1, 1])


def test_the_viewer_runs_under_xvfb_and_the_screen_is_not_blank(build, tmp_path, report_artifact):
    """MuJoCo's own viewer for real, on a virtual display: a few seconds of scripted input."""
    xvfb = shutil.which("xvfb-run")
    assert xvfb, "xvfb-run is missing: run `make setup` (it installs xvfb)"
    pd.DataFrame(script(30, seed=3), columns=["raw0", "raw1"]).to_csv(tmp_path / "script.csv", index=False)
    shot = ROOT / "build" / "tests" / "viewer_xvfb.png"  # kept after the run (build/ is not committed)
    shot.parent.mkdir(parents=True, exist_ok=True)
    shot.unlink(missing_ok=True)
    sessions = tmp_path / "sessions"
    env = {**os.environ, "MUJOCO_GL": "glfw"}
    command = [
        xvfb, "-a", "-s", "-screen 0 1024x768x24", sys.executable, "-m", "lasa.live.teleop", "run",
        "--task", "Dessert", "--condition", "R+SA", "--participant", "xvfb",
        "--device", f"scripted:{tmp_path / 'script.csv'}", "--sessions", str(sessions),
        "--build-dir", str(build), "--screenshot", str(shot),
    ]  # fmt: skip
    result = subprocess.run(command, capture_output=True, text=True, env=env, cwd=ROOT, timeout=240)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-3000:]
    report_artifact("MuJoCo viewer under Xvfb, screenshot", shot)
    logs = list(sessions.glob("xvfb_Dessert_R+SA_*.csv"))
    assert len(logs) == 1
    frame, meta = read_session(logs[0])
    assert meta["status"] == "complete" and len(frame) == 30
    assert json.loads(logs[0].with_suffix(".json").read_text())["deadline_misses"] >= 0
    from PIL import Image

    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert pixels.std() > 20 and pixels.mean() > 30  # a rendered scene, not a black or flat screen


def test_a_cups_session_with_the_simulations_decoder_replays_to_an_mp4(model, tmp_path):
    """The cup task on planar5 under LA+SA (1-D latent: the stick's first axis), replayed and rendered."""
    from lasa.evidence.video import read_video

    save_checkpoint(model, tmp_path / "build" / "models" / "decoder_planar5_lambda0.pt")
    config = SessionConfig(
        robot="planar5", task="cups", condition="LA+SA", participant="c01", build_dir=str(tmp_path / "build")
    )
    st = Station(config)
    writer = open_log(st, tmp_path / "sessions")
    run_session(st, ScriptedDevice(script(20, seed=5)), writer, 40, realtime=False)
    frame, meta = read_session(writer.csv)
    assert meta["decoder"] == "decoder_planar5_lambda0.pt" and len(frame) == 20 and (frame.phase == -1).all()
    assert not np.allclose(frame[[f"s{i}" for i in range(5)]].to_numpy()[-1], st.task.start)  # it moved
    result = replay(writer.csv, mp4=tmp_path / "replay.mp4")
    assert result["exact"]
    assert read_video(result["mp4"]).shape == (21, 240, 320, 3)  # the start and every step


def test_replay_refuses_another_decoder(build, tmp_path):

    st = station(build, "LA")
    writer = open_log(st, tmp_path)
    run_session(st, ScriptedDevice(script(5)), writer, 5, realtime=False)
    sidecar = tmp_path / f"{writer.stem}.json"
    meta = json.loads(sidecar.read_text())
    sidecar.write_text(json.dumps({**meta, "decoder_sha256": "0" * 64}))
    with pytest.raises(CheckpointError, match="checksum"):
        replay(writer.csv)


def test_no_display_is_a_clear_error_and_leaves_no_session(build, tmp_path, monkeypatch, capsys):
    from lasa.live.teleop import main

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    args = [
        "run",
        "--task",
        "Dessert",
        "--condition",
        "LA",
        "--build-dir",
        str(build),
        "--sessions",
        str(tmp_path / "s"),
    ]
    assert main(args) == 2
    assert "no display" in capsys.readouterr().err
    assert not (tmp_path / "s").exists()


@pytest.fixture()
def logged(build, tmp_path):
    """A complete 40-step session on disk."""
    st = station(build, "LA")
    writer = open_log(st, tmp_path)
    run_session(st, ScriptedDevice(script(40)), writer, 40, realtime=False)
    return writer


def test_a_truncated_log_is_damaged_and_never_complete(logged):
    from lasa.base.errors import ArtifactError

    lines = logged.csv.read_text().splitlines()
    logged.csv.write_text("\n".join(lines[:10]) + "\n")  # the header and 9 of 40 rows
    with pytest.raises(
        ArtifactError, match=r"damaged: its sidecar records 40 steps, the log holds 9 rows"
    ) as err:
        replay(logged.csv)
    assert "\n" not in str(err.value)
    result = replay(logged.csv, allow_damaged=True)  # asked for: replayed, and said so
    assert result["steps"] == 9 and "40 steps" in result["damaged"]


def test_a_corrupt_cell_names_its_row_and_column(logged):

    lines = logged.csv.read_text().splitlines()
    cells = lines[5].split(",")
    cells[3] = "x"
    lines[5] = ",".join(cells)
    logged.csv.write_text("\n".join(lines) + "\n")
    column = lines[0].split(",")[3]
    with pytest.raises(DamagedLogError, match=rf"row 5, column '{column}' holds 'x', not a number"):
        read_session(logged.csv)
    frame, meta = read_session(logged.csv, allow_damaged=True)
    assert np.isnan(frame.iloc[4, 3]) and "not a number" in meta["damaged"]


def test_a_row_with_missing_fields_is_damaged(logged):

    lines = logged.csv.read_text().splitlines()
    lines[7] = lines[7] + ",1.0"  # one field too many
    logged.csv.write_text("\n".join(lines) + "\n")
    with pytest.raises(DamagedLogError, match="wrong number of fields"):
        read_session(logged.csv)


def test_load_sessions_analyses_nothing_from_a_damaged_log(logged):
    from lasa.evidence.sessions import load_sessions

    lines = logged.csv.read_text().splitlines()
    logged.csv.write_text("\n".join(lines[:-3]) + "\n")
    with pytest.raises(ArtifactError, match="damaged"):  # no sound session left: the folder's error
        load_sessions(logged.folder, make_eating_task())
    episodes = load_sessions(logged.folder, make_eating_task(), include_damaged=True)
    assert int(episodes.end[0]) == 37


@pytest.mark.parametrize("module", ["lasa.live.teleop", "lasa.pipeline.execute", "lasa.pipeline.book"])
def test_every_cli_option_has_help_text(module, monkeypatch, capsys):
    """Every option and argument of each command says what it is (argparse's --help)."""
    import argparse
    import importlib

    parsers: list[argparse.ArgumentParser] = []
    original = argparse.ArgumentParser.parse_args

    def capture(self, args=None, namespace=None):
        parsers.append(self)
        raise SystemExit(0)

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", capture)
    with pytest.raises(SystemExit):
        importlib.import_module(module).main(["--help"])
    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", original)
    seen = 0
    for parser in parsers:
        for action in parser._actions:
            subs = getattr(action, "choices", None)
            if isinstance(action, argparse._SubParsersAction):
                for sub in subs.values():
                    for a in sub._actions:
                        if not isinstance(a, argparse._HelpAction):
                            seen += 1
                            assert a.help, f"{module} {sub.prog}: {a.option_strings or a.dest} has no help"
            elif not isinstance(action, argparse._HelpAction):
                seen += 1
                assert action.help, f"{module}: {action.option_strings or action.dest} has no help"
    assert seen >= 3


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    condition=st.sampled_from(["LA", "LA+SA"]),
    axes=st.lists(
        st.tuples(
            st.sampled_from([0.0, 0.0, -1.0, 1.0, 0.3]) | st.floats(-1.0, 1.0),
            st.sampled_from([0.0, 0.0, -1.0, 1.0, -0.4]) | st.floats(-1.0, 1.0),
        ),
        min_size=1,
        max_size=25,
    ),
)
def test_the_live_step_is_algorithm_1_by_hand(build, condition, axes):
    """Station.step (latent actions) against Algorithm 1 written out by hand (tests/reference_step.py):
    phi of the stick (nothing for a stick at rest), Eq. M2, the blend, the belief's update and the
    safe transition, from the state and belief the station held before each step.

    Tolerance: phi runs in float32 (its ulp near sigma_h = 0.375 is 3e-8), and the reference's belief,
    computed in another order, may move phi by a few ulps; a_h to 1e-7, the state (dt a) to 1e-8,
    the belief (beta_b dt a_h in its exponent) to 1e-6. A wrong formula misses by 1e-3 or more."""
    st_ = station(build, condition)
    for z in axes:
        s, b = st_.state.copy(), softmax(st_.runner.log_belief[0])
        rec = st_.step(StickSample(raw=np.asarray(z, dtype=float)))
        ref = latent_step(st_.decoder, st_.task, st_.control, s, b, z, st_.alpha, rest="zero")
        assert_allclose(rec["a_h"], ref["a_h"], rtol=0, atol=1e-7)
        assert_allclose(rec["a_r"], ref["a_r"], rtol=0, atol=1e-12)
        assert_allclose(rec["s"], ref["s"], rtol=0, atol=1e-8)
        assert_allclose(rec["b"], ref["b"], rtol=0, atol=1e-6)
        if not np.any(z):
            assert not rec["a_h"].any()  # a stick at rest commands nothing


def test_replay_finds_a_state_the_log_does_not_share(logged):
    """Replay compares the re-run with the log, not the code with itself: a logged state off by
    0.001 rad at one step is found, with that difference."""
    frame = pd.read_csv(logged.csv)
    frame.loc[10, "s3"] += 1e-3
    lines = logged.csv.read_text().splitlines()
    cells = lines[11].split(",")
    column = lines[0].split(",").index("s3")
    cells[column] = repr(float(frame.loc[10, "s3"]))
    lines[11] = ",".join(cells)
    logged.csv.write_text("\n".join(lines) + "\n")
    result = replay(logged.csv)
    assert not result["exact"]
    assert result["max_state_difference"] == pytest.approx(1e-3, rel=1e-9)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    condition=st.sampled_from(["R", "R+SA"]),
    inputs=st.lists(
        st.tuples(
            st.sampled_from([0.0, 0.0, -1.0, 1.0]) | st.floats(-1.0, 1.0),
            st.sampled_from([0.0, 0.0, 1.0, -0.5]) | st.floats(-1.0, 1.0),
            st.booleans(),
        ),
        min_size=1,
        max_size=12,
    ),
)
def test_the_live_retargeting_step_moves_the_hand_by_the_twist_of_its_mode(build, condition, inputs):
    """Station.step (Retargeting) against the baseline's definition: a press switches to the next of
    the three modes and moves nothing; otherwise the stick's two axes are two components of the
    hand's twist (x, y; z, yaw; roll, pitch) at 0.15 m/s and 0.6 rad/s full deflection, and the
    joint velocity a_h realises it: J(s) a_h = twist, J the grasp site's Jacobian from MuJoCo.
    The rest of the step (Eq. M2, blend, belief, transition) is Algorithm 1 by hand.

    Tolerance of J a_h: the QP trades the twist against a posture task and damping (both 1e-3)
    and realises a displacement over dt rather than the instantaneous twist; it misses by under
    3% of a full deflection's speed here, 5% is allowed. A wrong mode or axis misses by 100%."""
    import mujoco

    st_ = station(build, condition)
    robot = st_.robot
    model, data = robot.model, mujoco.MjData(robot.model)
    site = model.site(robot.spec.grasp_site).id
    dofs = [model.jnt_dofadr[model.joint(j).id] for j in robot.spec.joints]
    components = {0: (0, 1), 1: (2, 5), 2: (3, 4)}  # mode -> twist components (vx vy vz wx wy wz)
    speed = np.array([0.15, 0.15, 0.15, 0.6, 0.6, 0.6])
    for z0, z1, press in inputs:
        s, b, mode = st_.state.copy(), softmax(st_.runner.log_belief[0]), st_.mode
        rec = st_.step(StickSample(raw=np.array([z0, z1]), mode=press))
        if press or not (z0 or z1):
            assert not rec["a_h"].any()  # a press or a stick at rest moves nothing
            assert rec["mode"] == ((mode + 1) % 3 if press else mode)
        else:
            assert rec["mode"] == mode
            wanted = np.zeros(6)
            wanted[list(components[mode])] = [z0, z1]
            wanted *= speed
            data.qpos[robot.qpos_adr] = s
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)
            jp, jr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
            mujoco.mj_jacSite(model, data, jp, jr, site)
            moved = np.vstack([jp, jr])[:, dofs] @ rec["a_h"]
            assert np.all(np.abs(moved - wanted) <= 0.05 * speed), (mode, moved, wanted)
        ref = step_with(st_.task, st_.control, s, b, rec["a_h"], st_.alpha)
        assert_allclose(rec["a_r"], ref["a_r"], rtol=0, atol=1e-12)
        assert_allclose(rec["s"], ref["s"], rtol=0, atol=1e-12)
        assert_allclose(rec["b"], ref["b"], rtol=0, atol=1e-9)


def _start_live_session(build, tmp_path, device, participant):
    """A headless, real-time teleop run (60 s at most) in a subprocess, once its log has rows on disk."""
    import time

    if device == "scripted":
        pd.DataFrame(script(600, seed=4), columns=["raw0", "raw1"]).to_csv(tmp_path / "s.csv", index=False)
        device = f"scripted:{tmp_path / 's.csv'}"
    sessions = tmp_path / "sessions"
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy", "MUJOCO_GL": "disable"}
    env.pop("SDL_NO_SIGNAL_HANDLERS", None)  # what SDL does by default is what is tested
    command = [
        sys.executable, "-m", "lasa.live.teleop", "run", "--task", "Dessert", "--condition", "R+SA",
        "--participant", participant, "--device", device, "--sessions", str(sessions),
        "--build-dir", str(build), "--no-viewer", "--duration", "60",
    ]  # fmt: skip
    proc = subprocess.Popen(
        command, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline and proc.poll() is None:
        parts = list(sessions.glob("*.csv.part"))
        if parts and parts[0].read_text().count("\n") > 11:  # the header and 10 flushed rows
            return proc, sessions
        time.sleep(0.2)
    proc.kill()
    out, err = proc.communicate()
    raise AssertionError(f"the session never logged a row: {out[-1000:]} {err[-2000:]}")


@pytest.mark.parametrize(
    ("device", "name"),
    [("auto", "SIGTERM"), ("auto", "SIGINT"), ("auto", "SIGHUP"), ("scripted", "SIGTERM")],
)
def test_a_killed_session_reads_interrupted_and_keeps_its_rows(build, tmp_path, device, name):
    """SDL (``--device auto`` starts it to look for a gamepad) would swallow SIGTERM and the
    session would run its full length and read complete: a signal stops it at the next step."""
    import signal

    proc, sessions = _start_live_session(build, tmp_path, device, "k01")
    proc.send_signal(getattr(signal, name))
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + getattr(signal, name), out[-1000:] + err[-2000:]
    assert err.strip().splitlines()[-1].endswith("(its rows are kept; it reads interrupted)")
    assert f"interrupted by {name} after" in err
    frame, meta = read_session(next(sessions.glob("k01_*.json")))
    assert meta["status"] == "interrupted" and meta["signal"] == name
    assert 10 <= len(frame) == meta["steps"] < 600
    assert not list(sessions.glob("*.part"))


@pytest.fixture(scope="module")
def cohort(build, tmp_path_factory):
    """Three participants' complete Dessert sessions: p1 and p2 every condition, p3 all but LA."""
    folder = tmp_path_factory.mktemp("cohort")
    for i, participant in enumerate(("p1", "p2", "p3")):
        for k, condition in enumerate(("R", "R+SA", "LA", "LA+SA")):
            if participant == "p3" and condition == "LA":
                continue
            config = SessionConfig(
                task="Dessert", condition=condition, participant=participant, build_dir=str(build)
            )
            st_ = Station(config)
            device = ScriptedDevice(np.random.default_rng([i, k]).uniform(-1, 1, (12, 2)))
            run_session(st_, device, open_log(st_, folder), 12, realtime=False)
    return folder


def _copy(folder, tmp_path):
    out = tmp_path / "sessions"
    shutil.copytree(folder, out)
    return out


def _stem(folder, participant, condition):
    return next(p for p in folder.glob(f"{participant}_Dessert_{condition}_*.json")).stem


def _edit_cell(csv, row, column, value):
    lines = csv.read_text().splitlines()
    cells = lines[row].split(",")
    cells[lines[0].split(",").index(column)] = value
    lines[row] = ",".join(cells)
    csv.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize(
    ("value", "reason"), [("nan", "holds nan, not a finite"), ("inf", "holds inf, not a finite")]
)
def test_a_non_finite_state_is_damaged(logged, value, reason):

    _edit_cell(logged.csv, 4, "s2", value)
    with pytest.raises(DamagedLogError, match=rf"damaged: row 4, column 's2' {reason}"):
        read_session(logged.csv)


def test_rows_out_of_time_order_are_damaged(logged):
    from lasa.base.errors import ArtifactError

    lines = logged.csv.read_text().splitlines()
    lines[6], lines[7] = lines[7], lines[6]
    logged.csv.write_text("\n".join(lines) + "\n")
    with pytest.raises(
        ArtifactError, match=r"damaged: rows out of time order: row 7's step does not come after row 6's"
    ):
        read_session(logged.csv)


def test_a_bad_sidecar_or_empty_log_is_one_line(logged):

    text = logged.sidecar.read_text()
    logged.sidecar.write_text(text[: len(text) // 2])  # torn
    with pytest.raises(DamagedLogError, match=r"sidecar .* is damaged: not JSON") as err:
        read_session(logged.csv)
    assert "\n" not in str(err.value)
    logged.sidecar.write_text(text)
    logged.csv.write_text("")
    with pytest.raises(DamagedLogError, match=r"damaged: its log .* is empty \(not even a header\)"):
        read_session(logged.csv, allow_damaged=True)


def test_replay_checks_the_scene(logged):
    from lasa.base.errors import ArtifactError

    scene = logged.folder / f"{logged.stem}.xml"
    scene.write_text(scene.read_text().replace("<mujoco", "<mujoco ", 1))
    with pytest.raises(DamagedLogError, match="is not the scene session .* logged"):
        replay(logged.csv)
    scene.unlink()
    with pytest.raises(ArtifactError, match="has no scene"):
        replay(logged.csv)


def test_replay_requires_the_decoder_record(logged):
    from lasa.base.errors import ArtifactError

    meta = json.loads(logged.sidecar.read_text())
    logged.sidecar.write_text(json.dumps({k: v for k, v in meta.items() if k != "decoder_sha256"}))
    with pytest.raises(ArtifactError, match="records no decoder_sha256: replay cannot tell what it ran"):
        replay(logged.csv)
    logged.sidecar.write_text(json.dumps({**meta, "decoder_sha256": None}))
    with pytest.raises(ArtifactError, match="records no decoder checksum for LA"):
        replay(logged.csv)
    logged.sidecar.write_text(
        json.dumps({**meta, "decoder_config": {**meta["decoder_config"], "hidden": 99}})
    )
    with pytest.raises(
        ArtifactError, match="decoder's config differs from the one session .* logged in hidden"
    ):
        replay(logged.csv)


def test_a_decoder_for_another_task_is_refused_before_the_session(tmp_path):
    """A Panda decoder for the cups under the eating decoder's name: refused when the station is
    built, before any log exists (it used to fail in the loop, leaving a session at running)."""
    from lasa.method.decoder import DecoderConfig, LatentActionModel
    from lasa.world.robot import load_robot
    from lasa.world.task import make_cup_task

    cups = make_cup_task(load_robot("panda"))
    config = DecoderConfig(robot="panda", n_joints=7, n_goals=cups.n_goals, z_dim=1, hidden=8, depth=1)
    save_checkpoint(LatentActionModel(config), tmp_path / "models" / "eating_decoder_panda.pt")
    with pytest.raises(CheckpointError, match="does not fit the Dessert task"):
        Station(SessionConfig(task="Dessert", condition="LA", participant="t", build_dir=str(tmp_path)))


def test_one_bad_session_is_left_out_by_name(cohort, tmp_path):
    """A crashed session with a torn last line, a damaged one and an interrupted one are left
    out by name; the others are analysed."""
    from lasa.evidence.sessions import load_sessions, scan_sessions

    folder = _copy(cohort, tmp_path)
    torn = _stem(folder, "p1", "R")
    os.replace(folder / f"{torn}.csv", folder / f"{torn}.csv.part")  # it crashed: never renamed
    part = folder / f"{torn}.csv.part"
    text = part.read_text()
    part.write_text(text[: text.rindex("\n", 0, -1) + 60])  # ... mid-row
    meta = json.loads((folder / f"{torn}.json").read_text())
    (folder / f"{torn}.json").write_text(json.dumps({**meta, "status": "running"}))
    bad = _stem(folder, "p2", "LA")
    _edit_cell(folder / f"{bad}.csv", 3, "s0", "inf")
    logs, left_out = scan_sessions(folder)
    assert len(logs) == 11 - 2
    reasons = dict(zip(left_out.session, left_out.reason, strict=True))
    assert set(reasons) == {torn, bad}
    assert "not a number" in reasons[torn] and "not a finite number" in reasons[bad]
    with pytest.warns(
        UserWarning, match=f"left out session {bad}: a damaged log.* \\(session {bad} is damaged"
    ):
        episodes = load_sessions(folder, make_eating_task())
    assert len(episodes.participant) == 9


def test_the_same_participant_condition_and_task_twice_is_refused(cohort, tmp_path):
    from lasa.base.errors import ArtifactError
    from lasa.evidence.sessions import load_sessions

    folder = _copy(cohort, tmp_path)
    stem = _stem(folder, "p1", "LA")
    for suffix in (".json", ".csv", ".xml"):
        shutil.copy(folder / f"{stem}{suffix}", folder / f"{stem}9{suffix}")
    with pytest.raises(
        ArtifactError,
        match=rf"sessions {stem}.json and {stem}9.json .* both log participant p1, condition LA",
    ):
        load_sessions(folder, make_eating_task())


def test_the_analysis_names_who_it_dropped_and_replaces_its_tables_whole(cohort, tmp_path):
    from lasa.evidence.sessions import analyse_sessions, write_session_tables

    with pytest.warns(
        UserWarning, match="left out participant p3 from sa_effect, time_tests: missing LA in Dessert"
    ):
        people = analyse_sessions(cohort, make_eating_task())
    assert people["dropped"].to_dict("records") == [
        {"participant": "p3", "test": "sa_effect, time_tests", "reason": "missing LA in Dessert"}
    ]
    assert people["sa_effect"].n.tolist() == [2, 2] and set(people["time_tests"].measure) == {
        "total_time",
        "idle_time",
    }
    figures = tmp_path / "figures"
    write_session_tables(people, figures)
    assert (figures / "sessions_sa_effect.csv").is_file()
    (figures / "other.csv").write_text("kept\n")
    fewer = {
        k: v for k, v in people.items() if k not in ("sa_effect", "time_tests")
    }  # as one participant less
    write_session_tables(fewer, figures)
    assert sorted(p.name for p in figures.iterdir()) == sorted(
        ["other.csv", *(f"sessions_{k}.csv" for k in fewer)]
    )


def _cli(args, capsys):
    from lasa.live.teleop import main

    code = main(args)
    err = capsys.readouterr().err.strip()
    return code, err


def test_a_bad_likert_answer_is_one_line(tmp_path, capsys):
    from lasa.live.studykit import survey

    for answers in ("7,6,4.5,7,7", "7,,6,7,7", "7,6,five,7,7"):
        code, err = _cli(
            [
                "survey",
                "--participant",
                "p1",
                "--condition",
                "LA",
                "--answers",
                answers,
                "--sessions",
                str(tmp_path),
            ],
            capsys,
        )
        assert code == 2 and len(err.splitlines()) == 1
        assert err.startswith("error: a Likert answer is a whole number from 1 to 7, got")
    with pytest.raises(ConfigError, match="whole number from 1 to 7, got '5.7'"):
        survey(tmp_path, "p1", "LA", [7, 6, 5.7, 7, 7])
    assert not (tmp_path / "likert.csv").exists()


def test_the_prompt_asks_again_and_keeps_the_answers_given(tmp_path, monkeypatch, capsys):
    from lasa.evidence.sessions import read_likert
    from lasa.live.studykit import survey

    typed = iter(["7", "6", "five", "4.5", "", "5", "3", "2"])
    monkeypatch.setattr("builtins.input", lambda prompt: next(typed))
    survey(tmp_path, "p1", "LA", None)
    assert read_likert(tmp_path).answer.tolist() == [7, 6, 5, 3, 2]
    assert capsys.readouterr().out.count("please answer again") == 3


def test_a_second_survey_or_schedule_needs_overwrite(tmp_path, capsys):
    from lasa.evidence.sessions import read_likert

    survey = ["survey", "--participant", "p1", "--condition", "LA", "--sessions", str(tmp_path), "--answers"]
    assert _cli([*survey, "7,6,5,4,3"], capsys)[0] == 0
    code, err = _cli([*survey, "1,1,1,1,1"], capsys)
    likert = tmp_path / "likert.csv"
    assert (
        code == 2
        and err == f"error: p1 answered for LA already in {likert}: pass --overwrite to replace those answers"
    )
    assert read_likert(tmp_path).answer.tolist() == [7, 6, 5, 4, 3]
    assert _cli([*survey, "1,1,1,1,1", "--overwrite"], capsys)[0] == 0
    assert read_likert(tmp_path).answer.tolist() == [1, 1, 1, 1, 1]
    out = tmp_path / "schedule.csv"
    assert _cli(["schedule", "--participants", "4", "--out", str(out)], capsys)[0] == 0
    code, err = _cli(["schedule", "--participants", "6", "--out", str(out)], capsys)
    assert code == 2 and err == f"error: {out} exists already: pass --overwrite to replace the schedule"
    assert len(pd.read_csv(out)) == 16
    assert _cli(["schedule", "--participants", "6", "--out", str(out), "--overwrite"], capsys)[0] == 0
    assert len(pd.read_csv(out)) == 24


def test_a_schedule_is_bounded(tmp_path, capsys):
    code, err = _cli(["schedule", "--participants", "1000000", "--out", str(tmp_path / "s.csv")], capsys)
    assert (
        code == 2
        and err == "error: the number of participants must be a whole number in 1..1000, got 1000000"
    )
    assert not (tmp_path / "s.csv").exists()


@pytest.mark.parametrize("content", [None, "", "a,b\n1,2\n"])
def test_a_bad_script_file_is_one_line(build, tmp_path, capsys, content):
    script_file = tmp_path / "script.csv"
    if content is not None:
        script_file.write_text(content)
    args = ["run", "--task", "Dessert", "--condition", "R", "--build-dir", str(build), "--no-viewer"]
    code, err = _cli(
        [*args, "--device", f"scripted:{script_file}", "--sessions", str(tmp_path / "s")], capsys
    )
    assert code == 2 and len(err.splitlines()) == 1 and "script" in err
    assert not (tmp_path / "s").exists()


def test_a_scripted_session_never_shows_a_belief_above_the_studys_cap(build, tmp_path):
    """The live station's belief is the study's: Javdani et al.'s cap, through a logged session."""
    st_ = station(build, "LA+SA")
    assert st_.control.belief_cap == STUDY_BELIEF_CAP == 0.99
    axes = np.tile([[0.0, -1.0]], (150, 1))  # one direction held: the belief commits to a goal
    writer = open_log(st_, tmp_path)
    run_session(st_, ScriptedDevice(axes), writer, 150, realtime=False)
    frame, meta = read_session(writer.csv)
    beliefs = frame[[f"b{g}" for g in range(st_.task.n_goals)]].to_numpy()
    assert np.allclose(beliefs.sum(axis=1), 1.0) and meta["control"]["belief_cap"] == 0.99
    assert beliefs.max() <= 0.99 + 1e-12
    assert beliefs.max() > 0.99 - 1e-9  # it got there: the cap held it, not a lack of evidence


def test_a_decoder_trained_with_another_belief_is_refused(tmp_path):
    """A checkpoint that records an uncapped belief is refused by the capped station before a session."""
    config = DecoderConfig(robot="panda", n_joints=7, n_goals=4, z_dim=2, hidden=8, depth=1)
    uncapped = ControlConfig(assistance="hindsight")
    save_checkpoint(
        LatentActionModel(config), tmp_path / "models" / "eating_decoder_panda.pt", control=to_dict(uncapped)
    )
    with pytest.raises(CheckpointError, match="belief_cap None"):
        station(tmp_path, "LA")
