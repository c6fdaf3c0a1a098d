r"""Goals never seen in training: the context map h(s, b) of Sec. IV-C, :math:`a_h = J_h(s)^{-1}
\phi(z, \hat s, \hat b)`, :math:`\hat s = s + w(s)\,u(s)`, :math:`\hat b(\hat g) = b(g) + b(\hat g)`.
Offsets u: ``"straight_line"`` (the paper's), ``"grasp"`` (the default), or the straight line in the
gripper's space (:class:`TaskSpaceMap`). The derivation: ``docs/method-notes.md``.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable

import numpy as np

from lasa.base.config import check_choice
from lasa.base.errors import ConfigError, IKError
from lasa.method.decoder import ActionDecoder
from lasa.world.chain import rot_z
from lasa.world.ik import solve_grasp_ik
from lasa.world.robot import Robot
from lasa.world.task import CupTask, grasp_frame

JOINT_KINDS = ("grasp", "straight_line")  # the maps of :class:`ContextMap`, in joint space
MAP_KINDS = (*JOINT_KINDS, "straight_line_ee")  # and :class:`TaskSpaceMap`'s, in the gripper's space

_MAX_JUMP = 0.5  # largest joint-space step between neighbouring grasps of a smooth curve [rad]


def _turn(robot: Robot, new: np.ndarray, ref: np.ndarray) -> float:
    """The bearing of cup ``new`` less that of ``ref`` about the robot's base, in [-pi, pi) [rad]."""
    base = robot.base_position()
    delta = np.arctan2(new[1] - base[1], new[0] - base[0]) - np.arctan2(ref[1] - base[1], ref[0] - base[0])
    return float((float(delta) + np.pi) % (2 * np.pi) - np.pi)


def _check_grown(task: CupTask, n_train: int, ref_index: int) -> None:
    """A task of the training goals plus one new goal, and a training goal to refer it to."""
    if task.n_goals != n_train + 1:
        raise ConfigError(
            f"the task must have the {n_train} training goals plus one new goal, has {task.n_goals}"
        )
    if not 0 <= ref_index < n_train:
        raise ConfigError(f"ref_index must be in [0, {n_train}), got {ref_index}")


def _check_placement(task: CupTask, position: np.ndarray, ref_goal: int) -> tuple[np.ndarray, float]:
    """The new cup's position (3,), checked, and its bearing offset from the reference cup [rad]."""
    robot = task.robot
    cups = robot.goal_positions()
    pos = np.asarray(position, dtype=float).reshape(-1)
    if pos.shape not in ((2,), (3,)) or not np.all(np.isfinite(pos)):
        raise ConfigError(f"a new cup's position must be a finite (x, y) or (x, y, z) [m], got {position!r}")
    height = cups[ref_goal, 2]
    if pos.shape == (3,) and abs(pos[2] - height) > 1e-3:
        raise ConfigError(
            f"a new cup stands on the table: its grasp centre must be at z = {height:.3f} m "
            f"like the other cups, got z = {pos[2]:.3f} m"
        )
    pos = np.array([pos[0], pos[1], height])
    centre, half = robot.table_extent()
    if np.any(np.abs(pos[:2] - centre[:2]) > half[:2]):
        lo, hi = centre[:2] - half[:2], centre[:2] + half[:2]
        raise ConfigError(
            f"new cup at ({pos[0]:.3f}, {pos[1]:.3f}) is outside {robot.name}'s workspace: the table "
            f"spans x in [{lo[0]:.2f}, {hi[0]:.2f}], y in [{lo[1]:.2f}, {hi[1]:.2f}] m"
        )
    radius = robot.model.geom_size[robot.model.geom(robot.spec.goal_sites[ref_goal]).id][0]
    gaps = np.linalg.norm(cups[:, :2] - pos[:2], axis=1)
    if gaps.min() < 2 * radius:
        raise ConfigError(
            f"new cup at ({pos[0]:.3f}, {pos[1]:.3f}) overlaps goal "
            f"{robot.spec.goal_sites[int(gaps.argmin())]!r} "
            f"(centres {gaps.min():.3f} m apart, at least {2 * radius:.3f} m needed)"
        )
    delta = _turn(robot, pos, cups[ref_goal])
    if _yaw_axis(robot) == 0.0 and (abs(delta) > 1e-6 or abs(pos[1] - cups[ref_goal, 1]) > 1e-6):
        raise ConfigError(
            f"new cup at ({pos[0]:.3f}, {pos[1]:.3f}) is outside {robot.name}'s workspace: the arm moves "
            f"in a vertical plane, so a new cup must stand in it (y = {cups[ref_goal, 1]:.3f}) on the "
            "reference cup's side of the base"
        )
    return pos, delta


def _yaw_axis(robot: Robot) -> float:
    """+1 or -1 if the first joint turns the arm about the vertical (its sign), else 0."""
    axis = robot.first_joint_axis()
    return float(np.sign(axis[2])) if np.allclose(np.abs(axis), [0.0, 0.0, 1.0], atol=1e-6) else 0.0


def new_goal_frames(task: CupTask, ref_goal: int, position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A new cup's grasps (K, 3), (K, 3, 3): the reference cup's, turned and moved to it."""
    pos, delta = _check_placement(task, position, ref_goal)
    ref_cup, turn = task.robot.goal_positions()[ref_goal], rot_z(delta)
    frames = [grasp_frame(task.robot, ref_goal, float(theta)) for theta in task.theta_grid]
    return np.array([pos + turn @ (p - ref_cup) for p, _ in frames]), np.array([turn @ r for _, r in frames])


def extend_task(task: CupTask, position: np.ndarray, ref_goal: int = 1) -> CupTask:
    """The task with a new cup at ``position`` ((x, y) or (x, y, z) [m]) as its last goal, its
    grasps solved by IK from ``ref_goal``'s (turned about the base); ConfigError if misplaced,
    IKError if out of reach or not a smooth curve."""
    if not 0 <= ref_goal < task.n_goals:
        raise ConfigError(f"ref_goal must be a training goal in [0, {task.n_goals}), got {ref_goal}")
    pos, delta = _check_placement(task, position, ref_goal)
    positions, rotations = new_goal_frames(task, ref_goal, pos)
    robot = task.robot.with_cup(pos)
    guesses = task.curves[ref_goal].copy()
    guesses[:, 0] += delta * _yaw_axis(robot)  # turn the arm to the new bearing (no-op for a planar arm)
    curve = np.empty_like(guesses)
    for k, (p, r) in enumerate(zip(positions, rotations, strict=True)):
        try:
            curve[k] = solve_grasp_ik(robot, p, r, robot.clip(guesses[k]))
        except IKError as err:
            raise IKError(
                f"new cup at ({pos[0]:.3f}, {pos[1]:.3f}) is out of {robot.name}'s reach: no grasp at "
                f"theta = {task.theta_grid[k]:.2f} ({err})"
            ) from err
    jump = float(np.linalg.norm(np.diff(curve, axis=0), axis=1).max())
    if jump > _MAX_JUMP:
        raise IKError(
            f"new cup at ({pos[0]:.3f}, {pos[1]:.3f}): {robot.name}'s grasps there do not form a smooth "
            f"curve (a {jump:.2f} rad jump between neighbouring preferences); move the cup"
        )
    curves = np.concatenate([task.curves, curve[None]])
    goals = np.concatenate([task.goals, curve[None, len(task.theta_grid) // 2]])
    return CupTask(robot, (*task.goal_names, "new"), task.theta_grid, curves, goals, task.start)


def _saturation(start: np.ndarray, goal: np.ndarray, points: np.ndarray, same: str) -> float:
    """lambda_1: the least progress of ``points`` along start -> goal, at most 1; ConfigError (``same``)
    if goal is start, or if lambda_1 < 0.2 (the new cup's grasps not far enough ahead)."""
    line = goal - start
    if np.linalg.norm(line) < 1e-6:
        raise ConfigError(f"{same}: no path to map")
    progress = (points - start) @ line / (line @ line)
    saturation = float(min(progress.min(), 1.0))
    if saturation < 0.2:
        raise ConfigError(
            f"the new cup's grasps do not lie far enough ahead of the start (least progress {saturation:.2f})"
        )
    return saturation


class _MergedBelief:
    """What both maps share: b_hat, and h(s, b) = (s_hat, b_hat)."""

    n_train: int  # G
    ref_index: int  # the reference goal among the G training goals
    state: Callable[[np.ndarray], np.ndarray]  # s_hat

    def belief(self, belief: np.ndarray) -> np.ndarray:
        """b_hat over the training goals: the new goal's belief (the last) joins the reference's, (..., G)."""
        belief = np.asarray(belief, dtype=float)
        if belief.shape[-1] != self.n_train + 1:
            raise ConfigError(f"belief must be over {self.n_train + 1} goals, got shape {belief.shape}")
        out = belief[..., : self.n_train].copy()
        out[..., self.ref_index] += belief[..., self.n_train]
        return out

    def __call__(self, state: np.ndarray, belief: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """h(s, b) = (s_hat, b_hat)."""
        return self.state(state), self.belief(belief)


@dataclasses.dataclass(frozen=True)
class ContextMap(_MergedBelief):
    """The context map h(s, b) -> (s_hat, b_hat) from a new goal's context onto a training goal's
    (:meth:`for_task`); states (..., n), beliefs (..., G + 1) with the new goal last."""

    start: np.ndarray  # s_0, (n,) [rad]
    new_curve: np.ndarray  # the new cup's grasps s*(g, theta) on the theta grid, (K, n) [rad]
    ref_curve: np.ndarray  # where each maps: the reference cup's grasps, or ("straight_line") shifted
    ref_index: int
    n_train: int
    saturation: float  # lambda_1 in (0, 1], the progress from which w = 1
    width: float = 0.1  # tau, the joint-space width of the soft assignment to grasps [rad]
    kind: str = "grasp"  # one of JOINT_KINDS

    @classmethod
    def for_task(cls, task: CupTask, n_train: int, ref_index: int, kind: str = "grasp") -> ContextMap:
        """The map for the last goal of ``task`` (the new one) onto training goal ``ref_index``;
        ConfigError if the task has no new goal or the map would not be invertible."""
        _check_grown(task, n_train, ref_index)
        check_choice("kind", kind, JOINT_KINDS)
        start, g = task.start, task.goals[-1]
        line = g - start
        offset = task.goals[ref_index] - g
        saturation = _saturation(start, g, task.curves[-1], "the new goal coincides with the start pose")
        # along the straight line to g, d(s_hat)/d(lambda) must keep pointing forwards
        shift = float(line @ offset) / (float(line @ line) * saturation)
        if 1.0 + shift < 0.2:
            raise ConfigError(
                "the new cup is too far from the reference one for the map to be invertible; put it nearer"
            )
        ref_curve = task.curves[-1] + offset if kind == "straight_line" else task.curves[ref_index].copy()
        return cls(start.copy(), task.curves[-1].copy(), ref_curve, ref_index, n_train, saturation, kind=kind)

    @property
    def new_goal(self) -> np.ndarray:
        """The new goal g (its mid-preference grasp), shape (n,)."""
        return self.new_curve[len(self.new_curve) // 2]

    def _progress(self, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """lambda(s) / lambda_1, shape (...), and its gradient direction, shape (n,)."""
        line = self.new_goal - self.start
        grad = line / (float(line @ line) * self.saturation)
        return (np.asarray(state) - self.start) @ grad, grad

    def weight(self, state: np.ndarray) -> np.ndarray:
        """w(s) in [0, 1]: 0 at the start, 1 from progress lambda_1 on; shape (...)."""
        return np.clip(self._progress(state)[0], 0.0, 1.0)

    def _assignment(self, state: np.ndarray) -> np.ndarray:
        """p_k(s): soft assignment of each state to the new cup's grasps, shape (..., K)."""
        d2 = np.sum((np.asarray(state)[..., None, :] - self.new_curve) ** 2, axis=-1)
        logits = -0.5 * d2 / self.width**2
        p = np.exp(logits - logits.max(axis=-1, keepdims=True))
        return p / p.sum(axis=-1, keepdims=True)

    def state(self, state: np.ndarray) -> np.ndarray:
        """s_hat = s + w(s) u(s), u(s) = sum_k p_k(s) (s*(g_hat, theta_k) - s*(g, theta_k)), (..., n)."""
        return state + self.weight(state)[..., None] * (
            self._assignment(state) @ (self.ref_curve - self.new_curve)
        )

    def jacobian(self, state: np.ndarray) -> np.ndarray:
        """J_h(s) = I + u grad(w)^T + w sum_k p_k (u_k - u)(c_k - c_bar)^T / tau^2, (..., n, n)."""
        state = np.asarray(state, dtype=float)
        lam, grad = self._progress(state)
        w = np.clip(lam, 0.0, 1.0)
        inside = ((lam > 0.0) & (lam < 1.0))[..., None]
        p = self._assignment(state)
        offsets = self.ref_curve - self.new_curve
        u = p @ offsets
        c_bar = p @ self.new_curve
        du = np.einsum(
            "...k,...ki,...kj->...ij", p, offsets - u[..., None, :], self.new_curve - c_bar[..., None, :]
        )
        du /= self.width**2
        eye = np.eye(state.shape[-1])
        return eye + u[..., :, None] * np.where(inside, grad, 0.0)[..., None, :] + w[..., None, None] * du

    def action_to_training(self, action: np.ndarray, state: np.ndarray) -> np.ndarray:
        """a_hat = J_h(s) a, (..., n) (``s[:, None]`` for (U, K, n) candidates)."""
        return np.einsum("...ij,...j->...i", self.jacobian(state), action)

    def action_from_training(self, action: np.ndarray, state: np.ndarray) -> np.ndarray:
        """a = J_h(s)^{-1} a_hat, (..., n) (``s[:, None]`` for (U, K, n) candidates)."""
        return np.linalg.solve(self.jacobian(state), np.asarray(action, dtype=float)[..., None])[..., 0]


class TaskSpaceMap(_MergedBelief):
    r"""The paper's straight-line map in the gripper's space (kind ``"straight_line_ee"``) for the last
    goal of ``task`` (the new cup) onto training goal ``ref_index``.

    :math:`\hat p = p + w\,(T^{-1} p - p)`, :math:`\hat R = R_z(-w\delta)\,R` (T the table's turn
    back to the training cup); :math:`\hat s` is their IK seeded at :math:`s + w(\hat g - g)` (kept
    where IK fails: ``fallbacks``); actions map back in least squares, keeping null-space motion.
    """

    def __init__(self, task: CupTask, n_train: int, ref_index: int) -> None:
        _check_grown(task, n_train, ref_index)
        self.robot = task.robot
        self.n_train = n_train
        self.ref_index = ref_index
        cups = self.robot.goal_positions()
        self.delta = _turn(self.robot, cups[-1], cups[ref_index]) * abs(_yaw_axis(self.robot))
        self.start = task.start.copy()
        self.new_goal = task.goals[-1].copy()
        self.ref_goal = task.goals[ref_index].copy()
        self.new_cup = cups[-1].copy()
        self.ref_cup = cups[ref_index].copy()
        sites = self.robot.grasp_positions(
            np.concatenate([task.start[None], task.goals[-1][None], task.curves[-1]])
        )
        self.site_start = sites[0]
        self.site_goal = sites[1]
        self.saturation = _saturation(
            sites[0], sites[1], sites[2:], "the new goal's grasp site coincides with the start's"
        )
        self.fallbacks = 0  # states whose IK failed, kept at their seed
        self._cache: tuple[bytes, np.ndarray] | None = None  # the last state's bytes and s_hat

    def _poses(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        """Site positions, rotations and Jacobians at s (B, n); w, inside; p_hat and R_hat."""
        p, rot, jac = self.robot.grasp_jacobians(s)
        line = self.site_goal - self.site_start
        lam = (p - self.site_start) @ line / (float(line @ line) * self.saturation)
        w, inside = np.clip(lam, 0.0, 1.0), (lam > 0.0) & (lam < 1.0)  # and whether strictly inside (0, 1)
        back = self.ref_cup + (p - self.new_cup) @ rot_z(-self.delta).T  # T^-1 p
        p_hat = p + w[:, None] * (back - p)
        r_hat = np.einsum("bij,bjk->bik", rot_z(-w * self.delta), rot)
        return p, rot, jac, w, inside, back, p_hat, r_hat

    def state(self, state: np.ndarray) -> np.ndarray:
        """s_hat: the IK of the equivalent site pose, shape (..., n)."""
        state = np.asarray(state, dtype=float)
        key = state.tobytes()
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1]
        flat = state.reshape(-1, state.shape[-1])
        _, _, _, w, _, _, p_hat, r_hat = self._poses(flat)
        seeds = self.robot.clip(flat + w[:, None] * (self.ref_goal - self.new_goal))
        out = np.empty_like(flat)
        solve = functools.partial(solve_grasp_ik, position_tol=1e-5, rotation_tol=1e-4, max_iters=200)
        for i in range(len(flat)):
            try:
                out[i] = solve(self.robot, p_hat[i], r_hat[i], seeds[i])
            except IKError:
                out[i] = seeds[i]
                self.fallbacks += 1
        out = out.reshape(state.shape)
        self._cache = (key, out)
        return out

    def differential(self, state: np.ndarray) -> np.ndarray:
        """M(s) = d X_hat / ds, the equivalent site pose's (translation over rotation), (B, 6, n)."""
        flat = np.asarray(state, dtype=float).reshape(-1, self.robot.n_joints)
        p, _, jac, w, inside, back, _, _ = self._poses(flat)
        line = self.site_goal - self.site_start
        grad = np.einsum("bin,i->bn", jac[:, :3], line) / (float(line @ line) * self.saturation)
        grad *= inside[:, None]
        a_pos = (1.0 - w)[:, None, None] * np.eye(3) + w[:, None, None] * rot_z(-self.delta)
        top = np.einsum("bij,bjn->bin", a_pos, jac[:, :3]) + (back - p)[:, :, None] * grad[:, None, :]
        bottom = np.einsum("bij,bjn->bin", rot_z(-w * self.delta), jac[:, 3:])
        bottom[:, 2] -= self.delta * grad
        return np.concatenate([top, bottom], axis=1)

    def action_from_training(self, action: np.ndarray, state: np.ndarray) -> np.ndarray:
        """a from a decoded a_hat: the same motion of the equivalent site pose, (..., n); ``state``
        (U, n), or (U, 1, n) for (U, K, n) candidates."""
        state = np.asarray(state, dtype=float)
        action = np.asarray(action, dtype=float)
        n = state.shape[-1]
        users = state.reshape(-1, n)
        s_hat = self.state(state).reshape(-1, n)
        m = self.differential(users)
        _, _, j_hat = self.robot.grasp_jacobians(s_hat)
        _, sv, vt = np.linalg.svd(j_hat)
        rank = int(np.median((sv > 1e-8 * sv[:, :1]).sum(axis=1)))
        null = vt[:, rank:, :]  # (U, n - rank, n)
        solve = np.linalg.pinv(np.concatenate([m, null], axis=1))  # (U, n, 6 + n - rank)
        a_hat = action.reshape(len(users), -1, n)
        rhs = np.concatenate(
            [np.einsum("uin,ukn->uki", j_hat, a_hat), np.einsum("uin,ukn->uki", null, a_hat)], axis=-1
        )
        return np.einsum("unr,ukr->ukn", solve, rhs).reshape(action.shape)


def context_map(
    task: CupTask, n_train: int, ref_index: int, kind: str = "grasp"
) -> ContextMap | TaskSpaceMap:
    """The context map of ``kind`` (:data:`MAP_KINDS`) for the last goal of ``task`` onto ``ref_index``."""
    check_choice("kind", kind, MAP_KINDS)
    if kind == "straight_line_ee":
        return TaskSpaceMap(task, n_train, ref_index)
    return ContextMap.for_task(task, n_train, ref_index, kind)


class MappedDecoder:
    """The decoder through a context map: a_h = J_h(s)^-1 phi(z, h(s, b)) over the grown task's G + 1."""

    def __init__(self, model: ActionDecoder, context_map: ContextMap | TaskSpaceMap) -> None:
        if model.n_goals != context_map.n_train:
            raise ConfigError(
                f"the decoder reads {model.n_goals} goals, the context map maps onto "
                f"{context_map.n_train} training goals"
            )
        self.model, self.context_map = model, context_map
        self.robot: str = model.robot  # the wrapped decoder's
        self.n_goals: int = context_map.n_train + 1  # the training goals and the new one
        self.z_dim: int = model.z_dim  # d, the wrapped decoder's

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        """phi(z, h(s, b)) mapped back to the real context, (..., n); ``s`` (U, 1, n) for (U, K) z."""
        s = np.asarray(s, dtype=float)
        s_hat, b_hat = self.context_map(s, b)
        return self.context_map.action_from_training(self.model.decode_numpy(z, s_hat, b_hat), s)
