"""The study on a Franka, against franky-sim (libfranka's protocol, MuJoCo inside) on a loopback address: a
session from the CLI, dry run, stop, watchdog, joint limits, workspace guard, a lost link, the start check.
The guard's invariants are checked as properties without the simulator."""

import time

import franky
import mujoco
import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lasa.base.errors import ConfigError
from lasa.evidence.sessionlog import read_session
from lasa.evidence.sessions import load_sessions
from lasa.live import guard as guards
from lasa.live.devices import ScriptedDevice
from lasa.live.franka import FrankaLink, check_start, connect, franka_station, move_home, simulator
from lasa.live.guard import Guard, Workspace, reasons
from lasa.live.link import LinkError
from lasa.live.session import open_log
from lasa.live.station import SessionConfig
from lasa.live.teleop import main, replay, run_session
from lasa.method.decoder import save_checkpoint
from lasa.method.step import safe_step
from lasa.method.train import TrainConfig, train_decoder
from lasa.people.demos import DemoConfig, collect_eating_demonstrations
from lasa.world.eating import make_eating_task
from lasa.world.fork import tip_frames
from lasa.world.franka import SHARED_LOWER, SHARED_UPPER

TASK = make_eating_task()
ROBOT = TASK.robot
DT = ROBOT.control.dt


def make_guard() -> Guard:
    return Guard.around(ROBOT, TASK.start)


@pytest.fixture
def server():
    """A franky-sim server of the test's own: it serves one client at a time, and a failed test's traceback
    keeps that test's client alive, so a shared server would refuse every test after a failure."""
    with simulator() as address:
        yield address


@pytest.fixture
def sim(server):
    """The server's address and a franky client, released after the test (the CLI connects on its own)."""
    robot = connect(server)
    yield server, robot
    del robot


@pytest.fixture(scope="module")
def build(tmp_path_factory):
    """A build folder holding a small eating decoder, as `make figures` would leave a real one."""
    out = tmp_path_factory.mktemp("build")
    demos = collect_eating_demonstrations(
        TASK, ROBOT.control, DemoConfig(n_theta=2, n_starts=1, n_adjust=0, n_perturb=1)
    )
    config = TrainConfig(steps=60, hidden=16, depth=2, z_dim=2, batch_size=128)
    model, _ = train_decoder(demos, ROBOT.control, config, progress=False)
    save_checkpoint(model, out / "models" / "eating_decoder_panda.pt")
    return out


def home(robot, target=None) -> None:
    move_home(robot, TASK.start if target is None else target, make_guard(), speed=0.5)


def measured(robot) -> np.ndarray:
    return np.array(robot.current_joint_state.position)


def comes_to_rest(robot, within: float = 5.0) -> bool:
    """Whether, within ``within`` seconds, no joint moves more than 2 mrad in 0.3 s (franky-sim's reported
    velocity of joint 7 chatters at +-0.08 rad/s while its position stands still, so positions are
    compared). The arm brakes in the simulator's time, which lags the wall clock on a loaded machine."""
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        before = measured(robot)
        time.sleep(0.3)
        if np.abs(measured(robot) - before).max() < 2e-3:
            return True
    return False


def write_script(path, n, axes=(0.0, 0.8), **flags) -> str:
    table = pd.DataFrame({"raw0": np.full(n, axes[0]), "raw1": np.full(n, axes[1]), **flags})
    table.to_csv(path, index=False)
    return f"scripted:{path}"


def cli_run(address, build, tmp_path, device, *extra) -> int:
    args = ["run", "--franka", address, "--task", "Dessert", "--condition", "LA+SA", "--device", device]
    return main([*args, "--no-viewer", "--sessions", str(tmp_path), "--build-dir", str(build), *extra])


def the_log(tmp_path):
    (csv,) = tmp_path.glob("*.csv")
    return csv, *read_session(csv)


def test_a_dessert_session_runs_through_franky_from_the_cli_and_replays(server, build, tmp_path):
    address = server
    assert main(["home", "--franka", address, "--yes"]) == 0
    assert cli_run(address, build, tmp_path, write_script(tmp_path / "s.txt", 25)) == 0
    csv, frame, meta = the_log(tmp_path)
    assert meta["status"] == "complete" and meta["steps"] == 25
    assert meta["link"] == f"franka {address}" and meta["state_logged"] == "measured"
    s = frame[[f"s{i}" for i in range(7)]].to_numpy()
    v = frame[[f"v{i}" for i in range(7)]].to_numpy()
    assert np.abs(s[-1] - s[0]).max() > 0.02  # the arm moved
    assert np.abs(s[0] - TASK.start).max() < 0.05  # from the start pose
    assert (frame.sent == 1).all()
    # the log holds measured states: near the commanded motion, never the integration itself
    predicted = s[:-1] + DT * v[:-1]
    assert 0.0 < np.abs(s[1:] - predicted).max() < 0.05
    result = replay(csv)
    assert result["exact"] and result["max_command_difference"] == 0.0 and result["steps"] == 25
    # the analysis reads it like a simulated session: from the start pose, then each row's state (here:
    # measured as the step began, one tick behind a simulated row's state after the step)
    episodes = load_sessions(tmp_path, TASK)
    assert episodes.participant.tolist() == ["p00"] and np.array_equal(episodes.states[1:26, 0], s)


def test_recovery_is_an_explicit_command(server, capsys):
    assert main(["recover", "--franka", server]) == 0
    assert "no error now" in capsys.readouterr().out


def test_a_dry_run_computes_and_logs_every_command_and_sends_none(server, build, tmp_path):
    address = server
    home(connect(address))  # released at once: the CLI connects on its own
    assert cli_run(address, build, tmp_path, write_script(tmp_path / "s.txt", 15), "--dry-run") == 0
    _, frame, meta = the_log(tmp_path)
    s = frame[[f"s{i}" for i in range(7)]].to_numpy()
    v = frame[[f"v{i}" for i in range(7)]].to_numpy()
    assert meta["link"].endswith("(dry run)") and (frame.sent == 0).all()
    moved = np.abs(v).sum(axis=0).max() * DT  # what the commands would have moved a joint [rad] ...
    assert moved > 0.05 and np.abs(s - s[0]).max() < 0.1 * moved  # ... and what the arm did (settling)


def test_the_cli_refuses_a_dry_run_without_an_arm(tmp_path, capsys):
    assert main(["run", "--dry-run", "--no-viewer", "--device", write_script(tmp_path / "s.txt", 2)]) == 2
    assert "--franka" in capsys.readouterr().err


def test_the_cli_refuses_an_arm_out_of_real_time(tmp_path, capsys):
    device = write_script(tmp_path / "s.txt", 2)
    assert main(["run", "--franka", "127.255.255.254", "--fast", "--no-viewer", "--device", device]) == 2
    assert "real time" in capsys.readouterr().err and not list(tmp_path.glob("*.csv"))


def session(address, build, tmp_path, device, **kwargs):
    station = franka_station(SessionConfig(condition="LA+SA", build_dir=str(build)), address)
    writer = open_log(station, tmp_path)
    timing = run_session(station, device, writer, 100, **kwargs)
    return station, timing, read_session(writer.csv)


def test_the_stop_input_holds_the_arm(server, build, tmp_path):
    address = server
    home(connect(address))
    stop = np.arange(25) >= 10
    station, timing, (frame, meta) = session(
        address, build, tmp_path, ScriptedDevice(np.tile([0.0, 0.8], (25, 1)), stop=stop)
    )
    v = frame[[f"v{i}" for i in range(7)]].to_numpy()
    assert meta["status"] == "complete" and np.abs(v[:10]).max() > 0.01
    assert (v[10:] == 0.0).all() and (frame.stop[10:] == 1).all()
    assert comes_to_rest(station.link.robot)


@pytest.mark.parametrize("fault", ["no input", "late tick"])
def test_the_watchdog_stops_the_arm(server, build, tmp_path, fault):
    address = server
    home(connect(address))
    n = 30
    connected = np.arange(n) < 8 if fault == "no input" else None
    device = ScriptedDevice(np.tile([0.0, 0.8], (n, 1)), connected=connected)

    def slow(step, rec):
        if fault == "late tick" and step == 6:
            time.sleep(2.5 * DT)  # the next step ends past its period: late

    station, timing, (frame, meta) = session(address, build, tmp_path, device, on_step=slow)
    assert meta["status"] == "interrupted" and fault in meta["reason"]
    assert len(frame) == (
        8 + 3 if fault == "no input" else 8
    )  # 0.3 s of silence; the step after the late one
    assert comes_to_rest(station.link.robot)


def test_a_lost_link_stops_the_session_and_nothing_recovers_by_itself(build, tmp_path):
    with simulator() as address:
        home(connect(address))
        device = ScriptedDevice(np.tile([0.0, 0.8], (60, 1)))

        def cut(step, rec):
            if step == 5:
                address.process.kill()
                address.process.wait()

        _, timing, (frame, meta) = session(address, build, tmp_path, device, on_step=cut)
    assert meta["status"] == "interrupted" and meta["reason"].startswith("link:")
    assert 6 <= len(frame) < 60 and timing["reason"] == meta["reason"]


def test_the_joint_limits_hold_and_the_start_check_refuses_outside_them(sim):
    address, robot = sim
    guard = make_guard()
    edge = TASK.start.copy()
    edge[0] = SHARED_UPPER[0] - 0.05  # inside the FR3's range, outside the margin
    robot.move(franky.JointMotion(franky.JointState(edge.tolist()), relative_dynamics_factor=0.5))
    time.sleep(0.5)  # franky-sim's tracking settles
    with pytest.raises(ConfigError, match="outside the joint limits"):
        check_start(measured(robot), TASK.start, guard)
    link = FrankaLink(robot, guard, address)
    codes = []
    for _ in range(12):  # push joint 1 further out: refused; bring it back: allowed
        q = link.read()
        codes.append(link.command(q, q + DT * np.r_[0.5, np.zeros(6)], DT)["guard"])
        time.sleep(DT)
    assert measured(robot)[0] <= edge[0] + 0.005 and all("joint limit" in reasons(c) for c in codes)
    q = link.read()
    assert link.command(q, q - DT * np.r_[0.2, np.zeros(6)], DT)["guard"] == 0
    link.hold()
    assert SHARED_LOWER[5] > ROBOT.lower[5]  # the FR3's joint 6 is the narrower one


def test_the_start_check_says_how_to_reach_the_start_pose(server, build, tmp_path, capsys):
    address = server
    away = TASK.start + np.r_[0.0, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0]
    home(connect(address), away)
    assert cli_run(address, build, tmp_path, write_script(tmp_path / "s.txt", 5)) == 2
    err = capsys.readouterr().err
    assert "home --franka" in err and "joint 4" in err
    assert not list(tmp_path.glob("*.csv"))  # no session started


def test_the_workspace_guard_keeps_the_fork_above_the_table(sim):
    address, robot = sim
    home(robot)
    guard = make_guard()
    link = FrankaLink(robot, guard, address)
    data = mujoco.MjData(ROBOT.model)
    tips, codes = [], []
    refused = 0
    # the tip straight down at 0.15 m/s, through the table if nothing stopped it: until the guard has
    # refused 10 ticks in a row (the arm reaches the floor later in wall time on a loaded machine; 200
    # ticks, 20 s, bound the wait)
    while refused < 10 and len(codes) < 200:
        q = link.read()
        tip, _, jp, _ = tip_frames(ROBOT, data, q[None])
        v = np.linalg.pinv(jp[0]) @ np.array([0.0, 0.0, -0.15])
        codes.append(link.command(q, q + DT * v, DT)["guard"])
        tips.append(tip[0])
        refused = refused + 1 if "workspace" in reasons(codes[-1]) else 0
        time.sleep(DT)
    link.hold()
    heights = np.array(tips)[:, 2]
    assert heights[0] > 0.3 and heights.min() >= guard.workspace.floor - 0.005
    assert refused == 10  # held at the floor, 10 ticks running


def test_a_hand_computed_command_is_scaled_then_ramped():
    guard = make_guard()
    v, code = guard.check(TASK.start, np.r_[1.0, np.zeros(6)])
    # speed: 1 rad/s > 0.3 x 2.175 (the Panda's joint 1) -> 0.6525; ramp: 0.3 x 10 rad/s^2 x 0.1 s = 0.3
    assert v[0] == pytest.approx(0.3) and (v[1:] == 0).all()
    assert reasons(code) == ["speed", "acceleration"]


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-1.0, 1.0), min_size=7, max_size=7),
    st.lists(st.one_of(st.floats(-50.0, 50.0), st.just(float("nan"))), min_size=7, max_size=7),
    st.lists(st.floats(-1.0, 1.0), min_size=7, max_size=7),
)
def test_no_command_passes_that_the_simulations_safe_step_would_refuse(where, wish, last):
    guard = make_guard()
    guard.last = np.array(last) * guard.max_speed
    previous = guard.last.copy()
    mid, half = (guard.lower + guard.upper) / 2, (guard.upper - guard.lower) / 2
    state = mid + np.array(where) * half  # inside the shared limits and the margin
    v, code = guard.check(state, np.array(wish))
    stepped = safe_step(state, v, DT, ROBOT.lower, ROBOT.upper, ROBOT.control.max_joint_speed)
    assert np.array_equal(stepped, state + DT * v)  # the safe step changes nothing
    assert np.all(np.abs(v) <= guard.max_speed + 1e-12)
    assert np.all((state + DT * v >= guard.lower - 1e-12) & (state + DT * v <= guard.upper + 1e-12))
    if not code & (guards.WORKSPACE | guards.LIMIT):  # a limit or the workspace may stop harder
        assert np.all(np.abs(v - previous) <= guard.max_change + 1e-12)
    tips = tip_frames(ROBOT, mujoco.MjData(ROBOT.model), np.stack([state, state + DT * v]))[0]
    now, then = guard.workspace.outside(tips)
    assert then == 0.0 or then < now or (v == 0).all()


def test_a_guard_refuses_bad_settings():
    with pytest.raises(ConfigError, match="speed_scale"):
        Guard(ROBOT, Workspace.around(ROBOT, TASK.start), DT, speed_scale=1.5)
    with pytest.raises(ConfigError, match="margin"):
        Guard(ROBOT, Workspace.around(ROBOT, TASK.start), DT, margin=-0.1)


def test_a_missing_robot_is_one_clear_error():
    with pytest.raises(LinkError, match="cannot connect"):
        connect("127.255.255.254")  # loopback, nothing listens
