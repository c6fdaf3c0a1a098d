r"""The safety guard of a physical robot link: every joint velocity command is checked before it is sent.

In this order, on the command :math:`v = (s' - s)/\Delta` from the measured :math:`s` to the safe step's
:math:`s'`:

1. **speed**: the whole vector scaled down (its direction kept) until each joint is within ``speed_scale``
   of the slower of the Panda's and the FR3's published velocity limits;
2. **acceleration**: the change from the last command clipped per joint to ``accel_scale`` of the lower
   published acceleration limit times :math:`\Delta`;
3. **joint limits**: the joints the two arms share (:data:`lasa.world.franka.SHARED_LOWER`, ``UPPER``),
   narrowed by ``margin``: no command takes a joint further past them (one outside may come back);
4. **workspace**: the fork tip at :math:`s + \Delta v` must stay above the table plane and inside a box
   around the bowls and the plate; a command that takes it further out is refused (zero velocity).

A joint limit or the workspace may stop a joint faster than the ramp allows (a stop is always allowed;
franky's motion generator bounds the arm's own deceleration, and the margin takes the overshoot). Each is
stricter than the simulation's safe step (:func:`lasa.method.step.safe_step`), so a command the
simulation would refuse never passes (``tests/test_franka.py`` checks it as a property)."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from lasa.base.errors import ConfigError
from lasa.world.fork import tip_frames
from lasa.world.franka import (
    SHARED_ACCELERATION,
    SHARED_LOWER,
    SHARED_UPPER,
    SHARED_VELOCITY,
)
from lasa.world.robot import Robot

OK, SPEED, ACCELERATION, LIMIT, WORKSPACE = 0, 1, 2, 4, 8  # what changed a command (bit flags, logged)
REASONS = {SPEED: "speed", ACCELERATION: "acceleration", LIMIT: "joint limit", WORKSPACE: "workspace"}


def reasons(code: int) -> list[str]:
    """The names of the checks that changed a command, from its logged ``guard`` code."""
    return [name for bit, name in REASONS.items() if int(code) & bit]


@dataclasses.dataclass(frozen=True)
class Workspace:
    """Where the fork tip may go: above ``floor`` (the table plane) and within ``low``..``high`` (3,) [m]."""

    floor: float
    low: np.ndarray
    high: np.ndarray

    @classmethod
    def around(cls, robot: Robot, start: np.ndarray, pad: float = 0.15, headroom: float = 0.25) -> Workspace:
        """The box around the goals and the start pose's tip, ``pad`` wider in x and y and ``headroom``
        above the higher of them; the floor is the top of the scene's ``table``."""
        goals = robot.goal_positions()
        tip = tip_frames(robot, mujoco.MjData(robot.model), np.asarray(start, float)[None])[0][0]
        points = np.vstack([goals, tip])
        table = robot.model.geom("table")
        floor = float(table.pos[2] + table.size[2])
        low = np.r_[points[:, :2].min(0) - pad, floor]
        high = np.r_[points[:, :2].max(0) + pad, points[:, 2].max() + headroom]
        return cls(floor, low, high)

    def outside(self, tip: np.ndarray) -> np.ndarray:
        """How far each tip (..., 3) is outside the box and above the floor [m] (0: inside)."""
        below = np.maximum(self.low - tip, 0.0)
        above = np.maximum(tip - self.high, 0.0)
        return np.linalg.norm(below + above, axis=-1)


@dataclasses.dataclass
class Guard:
    """The checks of one physical link (see the module); ``last`` is the last command sent (rad/s)."""

    robot: Robot
    workspace: Workspace
    dt: float
    margin: float = 0.1  # [rad] inside the shared joint limits
    speed_scale: float = 0.3  # of the published velocity limits
    accel_scale: float = 0.3  # of the published acceleration limits
    last: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(7))

    @classmethod
    def around(cls, robot: Robot, start: np.ndarray) -> Guard:
        """The default guard of a session of ``robot`` from ``start``: :meth:`Workspace.around` them, the
        robot's control period."""
        return cls(robot, Workspace.around(robot, start), robot.control.dt)

    def __post_init__(self) -> None:
        for name in ("speed_scale", "accel_scale"):
            value = getattr(self, name)
            if not 0.0 < value <= 1.0:
                raise ConfigError(f"{name} must be in (0, 1], got {value}")
        if not 0.0 <= self.margin < 0.5:
            raise ConfigError(f"margin must be in [0, 0.5) rad, got {self.margin}")
        self.lower = SHARED_LOWER + self.margin
        self.upper = SHARED_UPPER - self.margin
        self.max_speed = np.minimum(SHARED_VELOCITY * self.speed_scale, self.robot.control.max_joint_speed)
        self.max_change = SHARED_ACCELERATION * self.accel_scale * self.dt
        self._data = mujoco.MjData(self.robot.model)

    def within_limits(self, state: np.ndarray) -> bool:
        """Whether ``state`` (n,) is within the shared joint limits narrowed by the margin."""
        return bool(np.all((state >= self.lower) & (state <= self.upper)))

    def check(self, state: np.ndarray, velocity: np.ndarray) -> tuple[np.ndarray, int]:
        """The command to send from measured ``state`` for the wanted ``velocity`` (n,), and a code of the
        checks that changed it (0: none); a non-finite wish is a zero command."""
        v = np.where(np.isfinite(velocity), velocity, 0.0)
        code = OK
        ratio = float(np.max(np.abs(v) / self.max_speed))
        if ratio > 1.0:
            v, code = v / ratio, code | SPEED
        change = np.clip(v - self.last, -self.max_change, self.max_change)
        if np.any(change != v - self.last):
            v, code = self.last + change, code | ACCELERATION
        low = np.minimum(0.0, (self.lower - state) / self.dt)
        high = np.maximum(0.0, (self.upper - state) / self.dt)
        clipped = np.clip(v, low, high)
        if np.any(clipped != v):
            v, code = clipped, code | LIMIT
        tips = tip_frames(self.robot, self._data, np.stack([state, state + self.dt * v]))[0]
        now, then = self.workspace.outside(tips)
        if then > 0.0 and then >= now:
            v, code = np.zeros_like(v), code | WORKSPACE
        self.last = v
        return v, code

    def stopped(self) -> None:
        """The arm was stopped: the next command ramps up from rest."""
        self.last = np.zeros_like(self.last)
