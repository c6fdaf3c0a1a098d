"""Retargeting: direct teleoperation of the end effector (Rakita et al. 2017), the study's baseline R.

A 2-axis stick, its *modes* (:data:`MODES`) switched by a button, commands a twist; each step is one
QP of mink's differential IK (:class:`Retargeting`): a frame task, a light posture task, the limits.
"""

from __future__ import annotations

import dataclasses

import mink
import numpy as np

from lasa.base.config import NonNegative, Positive, check_range, validate
from lasa.base.errors import ConfigError
from lasa.world.robot import Robot

# The twist components in order (vx, vy, vz, wx, wy, wz), world frame, the site's
TWIST_COMPONENTS: tuple[str, ...] = ("x", "y", "z", "roll", "pitch", "yaw")

# Joystick modes: stick axis 0 drives the first component, axis 1 the second.
MODES: tuple[tuple[str, str], ...] = (("x", "y"), ("z", "yaw"), ("roll", "pitch"))
_MODE_COMPONENTS = [[TWIST_COMPONENTS.index(name) for name in names] for names in MODES]  # their indices


@dataclasses.dataclass(frozen=True)
class RetargetConfig:
    """Units of the Retargeting baseline: how fast a full stick deflection moves the hand."""

    # home to a cup (~0.54 m on the Panda) in under 4 s, 1.5 cm per 0.1 s: about the hand speed
    # of the latent actions' sigma_h = 0.375 rad/s, so neither interface wins by being faster
    linear_speed: Positive = 0.15  # speed of the site at full stick deflection [m/s]
    angular_speed: Positive = 0.6  # at full deflection: a quarter turn in ~2.6 s, 3.4 deg per 0.1 s [rad/s]
    damping: Positive = 1e-3  # Levenberg-Marquardt damping of mink's QP [-]
    posture_cost: NonNegative = 1e-3  # weight of the posture task towards the current q (redundancy) [-]

    def __post_init__(self) -> None:
        validate(self)


def _modes(mode: int | np.ndarray) -> np.ndarray:
    """``mode`` as an integer array, or ConfigError if any entry is not a valid mode."""
    arr = np.asarray(mode)
    ints = arr.astype(np.int64) if arr.dtype != bool and np.issubdtype(arr.dtype, np.integer) else None
    if ints is None or np.any((ints < 0) | (ints >= len(MODES))):
        raise ConfigError(f"mode must be an integer in [0, {len(MODES)}), got {mode!r}")
    return ints


def twist(mode: int | np.ndarray, z: np.ndarray, config: RetargetConfig = RetargetConfig()) -> np.ndarray:
    """The end-effector twist (..., 6) [m/s, rad/s] that stick deflections z (..., 2), clipped to
    [-1, 1] (not finite: zero), command in ``mode`` (...,); ConfigError for a bad mode or shape."""
    modes = _modes(mode)
    zs = np.asarray(z, dtype=float)
    if zs.ndim == 0 or zs.shape[-1] != 2:
        raise ConfigError(f"z must have shape (..., 2), got {zs.shape}")
    finite = np.all(np.isfinite(zs), axis=-1, keepdims=True)
    zs = np.where(finite, np.clip(np.nan_to_num(zs), -1.0, 1.0), 0.0)
    lead = np.broadcast_shapes(modes.shape, zs.shape[:-1])
    per_unit = np.eye(6)[_MODE_COMPONENTS] * np.repeat([config.linear_speed, config.angular_speed], 3)
    table = per_unit[np.broadcast_to(modes, lead)]  # twist per unit deflection: [..., axis] -> twist
    return np.asarray(np.einsum("...a,...ak->...k", np.broadcast_to(zs, (*lead, 2)), table))


def next_mode(mode: int | np.ndarray, presses: int | np.ndarray = 1) -> int | np.ndarray:
    """The mode after ``presses`` presses of the mode button (cyclic; negative goes back); an int
    for scalars. ConfigError if a mode is not valid or ``presses`` not an integer."""
    modes = _modes(mode)
    steps = np.asarray(presses)
    if not np.issubdtype(steps.dtype, np.integer) or steps.dtype == bool:
        raise ConfigError(f"presses must be an integer, got {presses!r}")
    out = (modes + steps) % len(MODES)
    return int(out) if out.ndim == 0 else out


class Retargeting:
    """Joystick twist -> joint velocity by mink differential IK at ``robot``'s grasp site, one QP per
    configuration over ``dt`` [s] (its mink objects reused: not thread safe)."""

    def __init__(self, robot: Robot, dt: float, config: RetargetConfig = RetargetConfig()) -> None:
        self.robot = robot
        self.dt = check_range("dt", dt, 0.0, low_open=True)
        self.config = config
        model = robot.model
        self._site = robot.spec.grasp_site
        self.n_joints = robot.n_joints  # n, the arm joints
        self._qpos_adr = np.asarray(robot.qpos_adr, dtype=int)
        self._dof_adr = np.array([model.jnt_dofadr[model.joint(name).id] for name in robot.spec.joints])
        self._q_full = model.qpos0.copy()
        self._configuration = mink.Configuration(model)
        self._frame = mink.FrameTask(self._site, "site", position_cost=1.0, orientation_cost=1.0)
        self._posture = mink.PostureTask(model, cost=config.posture_cost)
        self._tasks = [self._frame, self._posture]
        self._limits = [mink.ConfigurationLimit(model)]

    def _set(self, q: np.ndarray) -> None:
        """Put the mink configuration at arm joints ``q`` (the rest from the model's qpos0)."""
        self._q_full[self._qpos_adr] = q
        self._configuration.update(self._q_full)

    def _solve(self, q: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """Joint velocity (n,) realising twist ``xi`` (6,) from ``q`` (n,): one QP."""
        if not np.all(np.isfinite(xi)) or not np.any(xi):
            return np.zeros(self.n_joints)
        self._set(q)
        pose = self._configuration.get_transform_frame_to_world(self._site, "site")
        rotation = mink.SO3.exp(xi[3:] * self.dt) @ pose.rotation()  # world-frame rotation: left
        target = mink.SE3.from_rotation_and_translation(rotation, pose.translation() + xi[:3] * self.dt)
        self._frame.set_target(target)
        self._posture.set_target(self._q_full)
        problem = (self._configuration, self._tasks, self.dt, "daqp")
        velocity = mink.solve_ik(*problem, damping=self.config.damping, limits=self._limits)
        return np.asarray(velocity[self._dof_adr])

    def joint_velocity(self, q: np.ndarray, twist: np.ndarray) -> np.ndarray:
        """Joint velocities [rad/s] moving the grasp site with ``twist`` ((6,) or (B, 6)) from ``q``
        ((n,) or (B, n)) for one period; zero for a zero or non-finite twist row. ConfigError for
        a non-finite ``q`` or a bad shape; mink.NoSolutionFound if the QP fails."""
        qs = np.asarray(q, dtype=float)
        if qs.ndim == 0 or qs.shape[-1] != self.n_joints:
            raise ConfigError(f"q must have shape (..., {self.n_joints}), got {qs.shape}")
        if not np.all(np.isfinite(qs)):
            raise ConfigError("q must be finite; got NaN or infinite joint positions")
        xis = np.asarray(twist, dtype=float)
        if xis.ndim == 0 or xis.shape[-1] != 6:
            raise ConfigError(f"twist must have shape (..., 6), got {xis.shape}")
        lead = np.broadcast_shapes(qs.shape[:-1], xis.shape[:-1])
        q_rows = np.broadcast_to(qs, (*lead, self.n_joints)).reshape(-1, self.n_joints)
        xi_rows = np.broadcast_to(xis, (*lead, 6)).reshape(-1, 6)
        out = [self._solve(q_row, xi) for q_row, xi in zip(q_rows, xi_rows, strict=True)]  # one QP each
        return np.array(out, dtype=float).reshape(*lead, self.n_joints)


def retarget_action(
    retarget: Retargeting, state: np.ndarray, mode: np.ndarray, z: np.ndarray, press: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Retargeting's a_h for a batch, and each row's mode after the step: a press cycles the mode and
    moves nothing, a stick at rest nothing, else z (U, 2) is a twist in the row's mode."""
    state, z = np.asarray(state, dtype=float), np.asarray(z, dtype=float)
    mode, press = np.asarray(mode, dtype=int), np.asarray(press, dtype=bool)
    a_h = np.zeros(state.shape)
    move = ~press & np.any(z != 0.0, axis=-1)
    if move.any():
        a_h[move] = retarget.joint_velocity(state[move], twist(mode[move], z[move], retarget.config))
    return a_h, np.where(press, np.asarray(next_mode(mode)), mode)
