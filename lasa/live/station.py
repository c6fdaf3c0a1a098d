"""The robot side of a live session (teleop and web alike): its settings (:class:`SessionConfig`) and one
control step per sample (:class:`Station`: the episode runner with the device as its chooser)."""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.metadata
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from lasa.base.conditions import ALL, alpha_of
from lasa.base.conditions import parse as parse_condition
from lasa.base.config import ControlConfig, check_choice
from lasa.base.errors import CheckpointError, ConfigError
from lasa.base.paths import Paths
from lasa.live.devices import StickSample
from lasa.live.link import RobotLink, SimLink
from lasa.method.belief import belief, uniform_log_belief
from lasa.method.decoder import ActionDecoder, load_checkpoint
from lasa.method.retarget import Retargeting, retarget_action, twist
from lasa.method.runner import Chooser, Now, Runner, held_input
from lasa.method.step import Assist
from lasa.world.eating import TASK_NAMES, make_eating_task
from lasa.world.fork import WaypointTracker, tip_frames
from lasa.world.goals import GoalTask
from lasa.world.instructions import instruction
from lasa.world.robot import Robot, load_robot
from lasa.world.task import make_cup_task

SESSION_TASKS = ("cups", "Entree", "Dessert")  # the tasks a session runs
try:  # lasa.__version__, read as it reads it (without importing the package's exports)
    _LASA_VERSION = importlib.metadata.version("lasa")
except Exception:  # a source tree that was never installed
    _LASA_VERSION = "0.0.0+unknown"


@dataclasses.dataclass(frozen=True)
class SessionConfig:
    """What a session runs: robot, task, condition and who drives."""

    robot: str = "panda"  # "planar5" or "panda" (the eating tasks: the Panda)
    task: str = "Dessert"  # "cups", "Entree" or "Dessert"
    condition: str = "LA+SA"  # R, R+SA, LA, LA+SA (LA+SA+Entropy: cups only)
    participant: str = "p00"  # participant id, part of the session's name
    build_dir: str = "build"  # where `make figures` left the decoders

    def __post_init__(self) -> None:
        for name, choices in (("robot", ("planar5", "panda")), ("task", SESSION_TASKS), ("condition", ALL)):
            check_choice(name, getattr(self, name), choices)
        if self.task != "cups" and self.robot != "panda":
            raise ConfigError(f"the {self.task} task is built for the Panda, not {self.robot!r}")
        if self.task != "cups" and self.condition == "LA+SA+Entropy":
            raise ConfigError(
                "the eating study runs R, R+SA, LA or LA+SA (its LA conditions use notebook 10's headline "
                "decoder); LA+SA+Entropy is the cups' condition"
            )
        if not self.participant or any(c in self.participant for c in "/\\ "):
            raise ConfigError(
                f"participant must be a short id without spaces or slashes, got {self.participant!r}"
            )


class Station:
    """The robot side of a session: ``robot``, ``task``, ``control``, ``decoder`` (None: Retargeting), its
    ``mode``, the ``waypoint`` worked towards, ``done``, and the ``link`` it steps against (default: MuJoCo's
    transition). The stick at rest commands nothing, the mode button cycles Retargeting's modes, the stop
    input holds the robot (no action, the belief frozen)."""

    def __init__(self, config: SessionConfig, link: RobotLink | None = None) -> None:
        self.config = config
        paths = Paths.of(config.build_dir, "figures")
        self.decoder: ActionDecoder | None = None
        self.decoder_path: Path | None = None
        self.tracker: WaypointTracker | None = None  # the eating tasks' waypoints (cups: none)
        condition = parse_condition(config.condition)
        if config.task == "cups":
            self.robot: Robot = load_robot(config.robot)
            self.task: GoalTask = make_cup_task(self.robot)
            name = "decoder_entropy" if condition.decoder == "entropy" else "decoder_lambda0"
        else:
            self.task = make_eating_task()
            self.robot = self.task.robot
            self.tracker = WaypointTracker.of(self.robot)
            name = "eating_decoder"
        self.control: ControlConfig = self.robot.control
        if condition.interface == "LA":
            self.decoder_path = paths.artifact(name, self.robot.name)
            self.decoder, meta = load_checkpoint(
                self.decoder_path, robot=self.robot.name, make_hint=Paths.make_hint(name, self.robot.name)
            )
            self._check_decoder(self.decoder, meta, self.decoder_path)
        self.retarget = Retargeting(self.robot, self.control.dt) if condition.interface == "R" else None
        self.alpha = alpha_of(condition.name, self.control.alpha)
        self._data = mujoco.MjData(self.robot.model)
        self.link: RobotLink = SimLink(self.task.start) if link is None else link
        self.reset()

    def _check_decoder(self, decoder: ActionDecoder, meta: dict[str, Any], path: Path) -> None:
        """Refuse, before any session starts, a decoder made for another task's goals or joints, or trained
        with another belief cap (a belief it never saw is an unknown context; none recorded: taken as is)."""
        config = getattr(decoder, "config", None)
        shape = (getattr(config, "n_joints", None), getattr(config, "n_goals", None))
        if shape != (self.robot.n_joints, self.task.n_goals) or decoder.z_dim > 2:
            raise CheckpointError(
                f"{path} does not fit the {self.config.task} task: it decodes {decoder.z_dim}-D z for "
                f"{shape[0]} joints and {shape[1]} goals, the task needs at most 2-D z, "
                f"{self.robot.n_joints} joints and {self.task.n_goals} goals"
            )
        control = meta.get("control")
        if isinstance(control, dict) and control.get("belief_cap", None) != self.control.belief_cap:
            raise CheckpointError(
                f"{path} was trained with belief_cap {control.get('belief_cap')}, this station's belief is "
                f"capped at {self.control.belief_cap}: train it with the station's belief (make figures)"
            )

    def warm_up(self) -> None:
        """Run the step's heavy calls once, off the record (torch's and mink's first calls are slow)."""
        if self.decoder is not None:
            self.decoder.decode_numpy(np.zeros((1, self.decoder.z_dim)), self.state[None], self.belief[None])
        if self.retarget is not None:
            self.retarget.joint_velocity(self.state, twist(0, np.array([1.0, 0.0])))

    def reset(self) -> None:
        """Back to the start pose (a physical link: the arm where it is), a uniform belief, mode 0, the first
        waypoint."""
        assist = Assist(self.task, self.control, np.array([self.alpha]))
        self.link.reset(self.task.start)
        start = self.link.read()[None]
        self.runner = Runner(assist, start, uniform_log_belief(1, self.task.n_goals))
        self.mode = 0
        self.waypoint = 0
        self.done = False

    @property
    def state(self) -> np.ndarray:
        """s, shape (n,) [rad]."""
        return self.runner.state[0]

    @property
    def belief(self) -> np.ndarray:
        """b over the task's goals, shape (G,)."""
        return belief(self.runner.log_belief[0])

    def meta(self) -> dict[str, Any]:
        """The sidecar's description of this station."""
        path = self.decoder_path
        return {
            **dataclasses.asdict(self.config),
            "goals": list(self.task.goal_names),
            "joints": list(self.robot.spec.joints),
            "dt": self.control.dt,
            "control": dataclasses.asdict(self.control),
            "alpha": self.alpha,
            "decoder": None if path is None else path.name,
            "decoder_sha256": None if path is None else hashlib.sha256(path.read_bytes()).hexdigest(),
            "decoder_config": None if self.decoder is None else dataclasses.asdict(self.decoder.config),  # type: ignore[attr-defined]
            "lasa_version": _LASA_VERSION,
            "link": self.link.name,
            # s: a physical link's measured joints as each step began; MuJoCo's: the state each step reached
            "state_logged": "measured" if self.link.physical else "stepped",
        }

    def columns(self) -> list[str]:
        """The log's step columns."""
        n, g = self.robot.n_joints, self.task.n_goals
        sizes = (("s", n), ("b", g), ("a_h", n), ("a_r", n), ("a", n))
        cols = "step time late raw0 raw1 connected mode_press stop z0 z1 mode phase waypoint".split()
        return cols + [f"{name}{i}" for name, size in sizes for i in range(size)] + self.link.columns()

    @property
    def phase(self) -> int:
        """The current phase of an eating task (-1: the cups)."""
        if self.tracker is None:
            return -1
        return int(self.tracker.phase[TASK_NAMES.index(self.config.task), self.waypoint])

    def phase_text(self) -> str:
        """The instruction of the current phase."""
        if self.tracker is None:
            return "Reach the cup you want, with the grasp you want"
        return instruction(self.config.task, None if self.done else self.phase)

    def track(self, state: np.ndarray) -> None:
        """Move past the waypoint the fork at ``state`` reached (:class:`lasa.world.fork.WaypointTracker`)."""
        if self.tracker is None or self.done:
            return
        tip, axis, _, _ = tip_frames(self.robot, self._data, state[None])
        task = np.array([TASK_NAMES.index(self.config.task)])
        waypoint, done = self.tracker.advance(task, np.array([self.waypoint]), tip, axis)
        self.waypoint, self.done = int(waypoint[0]), bool(done[0])

    def step(self, sample: StickSample) -> dict[str, Any]:
        """One control step from one sample against the link: read the joints, Algorithm 1's step, command
        the link; returns what the log records of it, in its columns' order."""
        z = sample.z  # safe: zero if disconnected or not finite, within [-1, 1]
        n = self.robot.n_joints
        a_h, a_r, a = np.zeros(n), np.zeros(n), np.zeros(n)
        measured = self.link.read()
        self.runner.state[0] = measured
        if sample.stop:  # stop holds: no human action, no assistance, the belief frozen
            command = self.link.hold()
        else:
            result = self.runner.step(self._chooser(z, bool(sample.mode) and self.retarget is not None))
            a_h, a = result.human_action[0], result.action[0]
            if result.robot_action is not None:
                a_r = result.robot_action[0]
            command = self.link.command(measured, self.state, self.control.dt)
            self.track(measured if self.link.physical else self.state)
        return {
            "raw": np.asarray(sample.raw, float),
            "connected": sample.connected,
            "mode_press": bool(sample.mode),
            "stop": bool(sample.stop),
            "z": z,
            "mode": self.mode,
            "phase": self.phase,
            "waypoint": self.waypoint,
            "s": (measured if self.link.physical else self.state).copy(),
            "b": self.belief,
            "a_h": a_h,
            "a_r": a_r,
            "a": a,
            **command,
        }

    def _chooser(self, z: np.ndarray, pressed: bool) -> Chooser:
        """The device as the runner's chooser: latent actions decode ``z`` (rest: nothing); Retargeting
        turns a press, rest or a twist in the mode into a human action by mink's IK."""
        if self.decoder is not None:
            return held_input(self.decoder, z[: self.decoder.z_dim][None], rest="zero")
        retarget = self.retarget
        assert retarget is not None  # a condition is latent actions or Retargeting

        def choose(now: Now) -> np.ndarray:
            a_h, modes = retarget_action(
                retarget, now.state, np.array([self.mode]), z[None, :2], np.array([pressed])
            )
            self.mode = int(modes[0])
            return a_h

        return choose
