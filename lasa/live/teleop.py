r"""Live teleoperation: drive any condition yourself, in MuJoCo's viewer, and log the session.

``run`` steps :mod:`lasa.live.station` at a fixed rate from a gamepad or keyboard, against MuJoCo or, with
``--franka ADDRESS``, a Franka over libfranka (:mod:`lasa.live.franka`; ``--dry-run`` sends nothing);
``home`` moves the Franka to the start pose once confirmed, ``recover`` clears its errors; ``replay`` re-runs
a log and checks its states (a Franka's: its commands) bit for bit (``--mp4`` renders it); ``schedule``,
``survey``: :mod:`.studykit`."""

from __future__ import annotations

if __name__ == "__main__":  # the CLI: renderer and kernels pinned before mujoco, numpy and torch load
    from lasa.runtime import pin

    pin()

import argparse
import contextlib
import dataclasses
import json
import os
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from lasa.base.conditions import ALL
from lasa.base.config import check_range
from lasa.base.errors import ArtifactError, CheckpointError, ConfigError, LasaError
from lasa.evidence.sessionlog import SessionWriter, check_scene, read_session
from lasa.live import studykit
from lasa.live.devices import Device, ScriptedDevice, open_device
from lasa.live.franka import connect, franka_station, joints, move_home, recover, replay_link
from lasa.live.guard import Guard
from lasa.live.link import LinkError
from lasa.live.session import Session, StopOnSignals, Watchdog, open_log
from lasa.live.station import SESSION_TASKS, SessionConfig, Station
from lasa.method.retarget import MODES
from lasa.world.eating import make_eating_task


def _draw(station: Station, goals: np.ndarray, viewer: Any, data: mujoco.MjData, rec: dict[str, Any]) -> bool:
    """Pose the viewer's robot, draw a belief sphere (1 to 5 cm) over each goal and the text, and sync;
    False if the viewer was closed."""
    if not viewer.is_running():
        return False
    with viewer.lock():
        data.qpos[station.robot.qpos_adr] = rec["s"]
        mujoco.mj_forward(station.robot.model, data)
        scn = viewer.user_scn
        scn.ngeom = 0
        for g, (pos, p) in enumerate(zip(goals, rec["b"], strict=True)):
            if scn.ngeom >= scn.maxgeom:
                break
            mujoco.mjv_initGeom(
                scn.geoms[scn.ngeom],
                mujoco.mjtGeom.mjGEOM_SPHERE,
                np.array([0.01 + 0.04 * float(p), 0.0, 0.0]),
                pos + np.array([0.0, 0.0, 0.18]),
                np.eye(3).ravel(),
                np.array([0.95, 0.6 * (g % 2), 0.2, 0.55], dtype=np.float32),
            )
            scn.ngeom += 1
    mode = f"mode {'/'.join(MODES[rec['mode']])}" if station.retarget is not None else "latent z"
    status = "STOPPED (stop input held)" if rec["stop"] else station.config.condition
    z = f"z = ({rec['z'][0]:+.2f}, {rec['z'][1]:+.2f})"
    beliefs = "  ".join(f"{n} {p:.2f}" for n, p in zip(station.task.goal_names, rec["b"], strict=True))
    text = f"{station.phase_text()}\n{status}   {mode}   {z}\nbelief: {beliefs}"
    with contextlib.suppress(AttributeError, TypeError):  # an older viewer has no text overlays
        viewer.set_texts((None, mujoco.mjtGridPos.mjGRID_TOPLEFT, text, ""))  # its own lock: outside ours
    viewer.sync()
    return True


def run_session(
    station: Station,
    device: Device,
    writer: SessionWriter | None,
    max_steps: int,
    *,
    realtime: bool = True,
    show: Callable[[dict[str, Any]], bool] | None = None,
    on_step: Callable[[int, dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """Run a :class:`lasa.live.session.Session` into ``writer`` (None: no log), one step per Delta unless not
    ``realtime``, each record to ``show`` (False: the viewer closed) and ``on_step(step, record)``, until
    ``max_steps``, the task done, a scripted device's end or a closed viewer; a signal (at the next step) or
    an exception (raised on) closes the log ``interrupted``. Returns :meth:`~lasa.live.session.Session.timing`
    and the stopping ``signal``."""
    session = Session(station, writer, max_steps, realtime)
    status, reason = "complete", None
    watchdog = Watchdog(station.control.dt) if station.link.physical else None
    with StopOnSignals() as stop:
        station.warm_up()  # so that the first deadlines measure the loop, not one-off start-up costs
        with session.guard():
            while session.steps < max_steps:
                sample = device.poll()
                try:
                    rec = None if stop.received is not None else session.step(sample, show)
                except LinkError as exc:  # the arm is stopped; the operator recovers it by hand
                    rec, reason = None, f"link: {exc}"
                if rec is not None and watchdog is not None:
                    reason = watchdog.check(sample, session.late)
                if rec is None or reason is not None:
                    status = "interrupted"
                    station.link.hold()
                    break
                if on_step is not None:
                    on_step(session.steps - 1, rec)
                if station.done or (isinstance(device, ScriptedDevice) and device.finished):
                    break
                if realtime:
                    time.sleep(max(0.0, session.pause()))
    station.link.hold()
    session.close(status, signal=stop.received, reason=reason)
    return {**session.timing(), "signal": stop.received, "reason": reason}


def replay(session: str | Path, mp4: str | Path | None = None, allow_damaged: bool = False) -> dict[str, Any]:
    """Re-run a logged session from its inputs: ``{"steps", "max_state_difference", "exact", "status"}``,
    ``mp4`` if rendered, ``damaged`` (why) if ``allow_damaged``; ArtifactError if the sidecar cannot tell
    what ran, the decoder or scene is not the logged one, or the log is damaged. A Franka's session (its
    states measured) re-computes each step from the measured state and compares the commands sent
    (``max_command_difference``)."""
    frame, meta = read_session(session, allow_damaged=allow_damaged)
    check_scene(session, meta)
    fields = ("robot", "task", "condition", "participant", "build_dir", "decoder_sha256", "decoder_config")
    missing = [k for k in fields if k not in meta]
    if missing:
        raise ArtifactError(
            f"session {session}'s sidecar records no {', '.join(missing)}: replay cannot tell what it ran"
        )
    states = frame[[f"s{i}" for i in range(len(meta.get("joints", [])) or 7)]].to_numpy()
    physical = meta.get("state_logged") == "measured"  # a Franka's session: its commands are re-computed
    link = replay_link(states) if physical else None
    station = Station(SessionConfig(**{k: meta[k] for k in fields[:5]}), link)
    logged, here = meta["decoder_sha256"], station.meta()  # the decoder on disk must be the logged one
    if logged is None and station.decoder_path is not None:
        raise ArtifactError(
            f"session {session}'s sidecar records no decoder checksum for {station.config.condition}: "
            "replay cannot tell which decoder it used"
        )
    if logged != here["decoder_sha256"]:
        raise CheckpointError(
            f"{station.decoder_path} is not the decoder session {session} used (checksum differs); "
            "replay needs the same decoder"
        )
    now = json.loads(json.dumps(here["decoder_config"])) or {}  # tuples as the sidecar's lists
    then = meta["decoder_config"] or {}
    diff = sorted(k for k in set(now) | set(then) if now.get(k) != then.get(k))
    if diff:
        raise CheckpointError(
            f"the decoder's config differs from the one session {session} logged in {', '.join(diff)}"
        )
    device = ScriptedDevice.from_table(frame, mode="mode_press")
    key = "v" if physical else "s"
    logged = frame[[f"{key}{i}" for i in range(station.robot.n_joints)]].to_numpy()
    replayed = np.asarray([station.step(device.poll())[key] for _ in range(len(frame))])
    difference = float(np.abs(replayed - logged).max()) if len(logged) else 0.0
    out: dict[str, Any] = {
        "steps": len(frame),
        "max_command_difference" if physical else "max_state_difference": difference,
        "exact": bool(np.array_equal(replayed, logged)),
        "status": meta["status"],
        **{k: meta[k] for k in ("damaged",) if k in meta},
    }
    if mp4 is not None:
        from lasa.evidence.video import label_frames, render_states, write_video

        shown = states if physical else np.concatenate([station.task.start[None], replayed])
        frames = render_states(station.robot, shown, 240, 320)
        frames = label_frames(frames, f"replay {Path(session).name}")
        out["mp4"] = str(write_video(mp4, frames, fps=1.0 / station.control.dt))
    return out


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m lasa.live.teleop", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="drive the robot live and log the session")
    run.add_argument("--robot", default="panda", help="the robot (panda: the eating scene) [%(default)s]")
    run.add_argument("--task", default="Dessert", choices=SESSION_TASKS, help="the eating task [%(default)s]")
    run.add_argument(
        "--condition", default="LA+SA", choices=ALL, help="interface and assistance [%(default)s]"
    )
    run.add_argument(
        "--participant", default="p00", help="participant id, part of the log's name [%(default)s]"
    )
    run.add_argument("--device", default="auto", help="auto, gamepad, keyboard, or scripted:<file.csv>")
    run.add_argument("--duration", type=float, default=300.0, help="longest session [s]")
    run.add_argument("--sessions", default="build/sessions", help="folder of the session logs")
    run.add_argument("--build-dir", default="build", help="where make figures left the decoder [%(default)s]")
    run.add_argument("--no-viewer", action="store_true", help="run without a window (scripted input)")
    run.add_argument(
        "--fast", action="store_true", help="do not wait for wall-clock time (no viewer; MuJoCo only)"
    )
    run.add_argument("--screenshot", help="save a screenshot of the display when the session ends")
    _franka_arguments(run)
    run.add_argument(
        "--dry-run", action="store_true", help="with --franka: read the arm, compute and log, send nothing"
    )
    home = sub.add_parser("home", help="move a Franka to the task's start pose (a joint motion you confirm)")
    _franka_arguments(home, required=True)
    home.add_argument("--yes", action="store_true", help="move without asking (you watch the arm)")
    recover = sub.add_parser("recover", help="clear a Franka's error state, after checking the arm")
    _franka_arguments(recover, required=True)
    rep = sub.add_parser("replay", help="re-run a session from its inputs; check its states")
    rep.add_argument("session", help="a session's .csv, .json or stem")
    rep.add_argument("--mp4", help="render the replay to this MP4 (off-screen)")
    rep.add_argument(
        "--allow-damaged",
        action="store_true",
        help="replay a damaged log's rows anyway (say so in the result)",
    )
    sch = sub.add_parser("schedule", help="a counterbalanced order of conditions for N participants")
    sch.add_argument("--participants", type=int, default=10, help="participants to schedule [%(default)s]")
    sch.add_argument("--out", default="build/sessions/schedule.csv", help="the schedule CSV [%(default)s]")
    sch.add_argument("--overwrite", action="store_true", help="replace an existing schedule")
    sur = sub.add_parser("survey", help="the 7-point Likert questionnaire after a condition")
    sur.add_argument("--participant", required=True, help="participant id, as in their sessions")
    sur.add_argument("--condition", required=True, choices=ALL, help="the condition just done")
    sur.add_argument("--answers", help="comma-separated answers 1-7 (Easy,Helpful,Precise,Intuitive,Prefer)")
    sur.add_argument("--sessions", default="build/sessions", help="folder of likert.csv [%(default)s]")
    sur.add_argument("--overwrite", action="store_true", help="replace answers given for this condition")
    dem = sub.add_parser("demos", help="record kinesthetic demonstrations (guiding mode) into a dataset")
    _franka_arguments(dem, required=True)
    dem.add_argument("--out", required=True, help="the demonstrations file, .npz (the raw stream beside it)")
    dem.add_argument("--duration", type=float, help="seconds to record (default: until Ctrl-C)")
    return parser


def _franka_arguments(parser: argparse.ArgumentParser, required: bool = False) -> None:
    parser.add_argument(
        "--franka",
        required=required,
        metavar="ADDRESS",
        help="drive a Franka at this address over libfranka (franky-sim: its loopback address)",
    )
    parser.add_argument(
        "--realtime",
        choices=("enforce", "ignore"),
        help="libfranka's real-time check [enforce; ignore on a loopback address]",
    )


def _home(args: argparse.Namespace) -> int:
    """``home``: how far the arm is from the eating tasks' start pose; move it there once confirmed."""
    task = make_eating_task()
    guard = Guard.around(task.robot, task.start)
    robot = connect(args.franka, args.realtime)
    now = joints(robot)
    print(f"the arm is at {np.round(now, 3).tolist()}; the start pose is {np.round(task.start, 3).tolist()}")
    print(
        f"the largest joint move is {np.abs(now - task.start).max():.3f} rad, at franky's dynamics factor 0.1"
    )
    if not args.yes and input("clear the space around the arm; type yes to move: ").strip() != "yes":
        print("not moved")
        return 1
    print(f"at the start pose after {move_home(robot, task.start, guard):.1f} s")
    return 0


def _recover(args: argparse.Namespace) -> int:
    """``recover``: libfranka's error recovery, the only way a session's stop is undone."""
    robot = connect(args.franka, args.realtime)
    recover(robot)
    print(f"the Franka at {args.franka} has no error now: check the arm, then `home` and `run` again")
    return 0


def _demos(args: argparse.Namespace) -> int:
    """``demos``: :func:`lasa.live.kinesthetic.run_demos` (imported here: franky loads only for it)."""
    from lasa.live.kinesthetic import run_demos

    return run_demos(args.franka, args.out, args.duration, args.realtime)


def _in_viewer(
    station: Station, device: Device, writer: SessionWriter, max_steps: int, screenshot: str | None
) -> dict[str, Any]:
    """Run the session in MuJoCo's passive viewer, on the scene's own camera."""
    import mujoco.viewer

    key_callback = getattr(device, "key_callback", None)
    data = mujoco.MjData(station.robot.model)
    data.qpos[station.robot.qpos_adr] = station.state
    with mujoco.viewer.launch_passive(
        station.robot.model, data, key_callback=key_callback, show_left_ui=False, show_right_ui=False
    ) as viewer:
        with viewer.lock():  # the scene's own camera, as in the videos
            viewer.cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
            viewer.cam.fixedcamid = station.robot.model.camera(station.robot.spec.camera).id
        goals = station.robot.goal_positions()
        timing = run_session(
            station, device, writer, max_steps, show=lambda rec: _draw(station, goals, viewer, data, rec)
        )
        deadline = time.perf_counter() + 30.0
        while screenshot:  # grabbed every 0.5 s until the display is not flat (or 30 s went by)
            from PIL import ImageGrab

            image = ImageGrab.grab(xdisplay=None)
            drawn = float(np.asarray(image.convert("L"), dtype=float).std()) > 20.0
            if drawn or time.perf_counter() > deadline:
                image.save(screenshot)
                break
            time.sleep(0.5)
    # let the viewer's thread finish closing its window before Python tears down:
    # exiting while it still holds the GL context can crash the interpreter's exit
    deadline = time.perf_counter() + 5.0
    while viewer.is_running() and time.perf_counter() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)
    return timing


def _run(args: argparse.Namespace) -> int:
    """``run``: one live session; 128 + the signal's number when a signal stopped it."""
    check_range("duration", args.duration, 0.0, low_open=True)
    config = SessionConfig(**{f.name: getattr(args, f.name) for f in dataclasses.fields(SessionConfig)})
    display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    if not args.no_viewer and sys.platform.startswith("linux") and not display:
        raise ConfigError(
            "no display for MuJoCo's viewer: run on a desktop, under `xvfb-run -a`, "
            "or with --no-viewer and scripted input"
        )
    if args.franka and args.fast:  # each tick's command lasts one period: faster ticks would not ramp
        raise ConfigError("--fast does not wait for wall-clock time; a session on an arm runs in real time")
    if args.franka:
        station = franka_station(config, args.franka, dry_run=args.dry_run, realtime=args.realtime)
        print(f"robot: {station.link.name}, at the start pose")
    elif args.dry_run:
        raise ConfigError("--dry-run reads a real arm: give its address with --franka")
    else:
        station = Station(config)
    device, message = open_device(args.device)
    print(message)
    writer = open_log(station, args.sessions)
    max_steps = int(round(args.duration / station.control.dt))
    with contextlib.closing(device), contextlib.closing(station.link):
        if args.no_viewer:
            timing = run_session(station, device, writer, max_steps, realtime=not args.fast)
        else:
            timing = _in_viewer(station, device, writer, max_steps, args.screenshot)
    if timing["signal"] is not None:
        print(
            f"session {writer.csv} interrupted by {timing['signal']} after {timing['steps']} steps "
            "(its rows are kept; it reads interrupted)",
            file=sys.stderr,
        )
        return 128 + int(getattr(signal, timing["signal"]))
    if timing["reason"] is not None:
        print(
            f"session {writer.csv} stopped after {timing['steps']} steps: {timing['reason']}", file=sys.stderr
        )
        return 3
    print(f"session {writer.csv}: {timing}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Command line: ``run``, ``replay``, ``home``, ``recover``, ``demos``, ``schedule`` and ``survey``; a bad
    input is one line, exit 2; a session the watchdog or the robot link stopped, exit 3."""
    args = _parser().parse_args(argv)
    try:
        if args.command == "replay":
            result = replay(args.session, args.mp4, allow_damaged=args.allow_damaged)
            print(result)
            return 0 if result["exact"] else 1
        if args.command == "run":
            return _run(args)
        if args.command in ("home", "recover"):
            return _home(args) if args.command == "home" else _recover(args)
        if args.command == "demos":
            return _demos(args)
        if args.command == "schedule":  # the study kit
            print(studykit.write_schedule(args.participants, args.out, overwrite=args.overwrite))
        else:
            answers = None if args.answers is None else args.answers.split(",")
            print(studykit.survey(args.sessions, args.participant, args.condition, answers, args.overwrite))
        return 0
    except LasaError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
