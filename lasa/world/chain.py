r"""The grasp site's kinematics for many configurations at once, and rotations about z: for a serial
chain of hinges, MuJoCo's ``mj_kinematics`` and ``mj_jacSite`` as batched numpy products of the model's
numbers (a hinge with axis :math:`a` at :math:`p_j` moves the site at :math:`p` by :math:`a \times (p - p_j)`
per radian), equal to MuJoCo's up to the last bits (``tests/test_chain.py``)."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np


def rot_z(angle: float | np.ndarray) -> np.ndarray:
    """The rotation by ``angle`` [rad] about z, (3, 3); for angles of shape (...,), (..., 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    zero, one = np.zeros_like(c), np.ones_like(c)
    rows = [np.stack([c, -s, zero], -1), np.stack([s, c, zero], -1), np.stack([zero, zero, one], -1)]
    return np.stack(rows, -2)


def _quat_to_mat(quat: np.ndarray) -> np.ndarray:
    """A unit quaternion (w, x, y, z) as a rotation matrix (3, 3), as MuJoCo's ``mju_quat2Mat``."""
    out = np.empty(9)
    mujoco.mju_quat2Mat(out, np.asarray(quat, dtype=float))
    return out.reshape(3, 3)


def _axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotations by ``angle`` (B,) about the unit ``axis`` (3,): Rodrigues' formula, (B, 3, 3)."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


@dataclasses.dataclass(frozen=True)
class _Link:
    """One body of the chain: its offset from its parent, and its hinge (if any)."""

    pos: np.ndarray  # body_pos, in the parent's frame (3,)
    rot: np.ndarray  # body_quat as a matrix (3, 3)
    arm: int  # the hinge's index among the arm joints, -1 for a rigid body
    anchor: np.ndarray  # jnt_pos, in the body's frame (3,)
    axis: np.ndarray  # jnt_axis, unit, in the body's frame (3,)
    zero: float  # qpos0 of the hinge [rad]


@dataclasses.dataclass(frozen=True)
class SerialChain:
    """The bodies from the world to the grasp site's body, and the site's offset on the last."""

    links: tuple[_Link, ...]
    site_pos: np.ndarray  # (3,)
    site_rot: np.ndarray  # (3, 3)
    n_joints: int

    @classmethod
    def of(cls, model: mujoco.MjModel, site: int, qpos_adr: np.ndarray) -> SerialChain | None:
        """The chain of ``site`` in ``model``, or None if it holds anything but hinges of the arm
        (the callers then keep MuJoCo's loop)."""
        arm = {int(a): i for i, a in enumerate(qpos_adr)}
        bodies, body = [], int(model.site_bodyid[site])
        while body != 0:
            bodies.append(body)
            body = int(model.body_parentid[body])
        links = []
        for b in reversed(bodies):
            n, j = int(model.body_jntnum[b]), int(model.body_jntadr[b])
            offset = (model.body_pos[b].copy(), _quat_to_mat(model.body_quat[b]))
            if n == 0:
                links.append(_Link(*offset, -1, np.zeros(3), np.zeros(3), 0.0))
                continue
            if n > 1 or model.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE or model.jnt_qposadr[j] not in arm:
                return None
            adr, axis = int(model.jnt_qposadr[j]), model.jnt_axis[j]
            unit = axis / np.linalg.norm(axis)
            zero = float(model.qpos0[adr])
            links.append(_Link(*offset, arm[adr], model.jnt_pos[j].copy(), unit, zero))
        if sorted(link.arm for link in links if link.arm >= 0) != list(range(len(qpos_adr))):
            return None
        return cls(tuple(links), model.site_pos[site].copy(), _quat_to_mat(model.site_quat[site]), len(arm))

    def _walk(self, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Each hinge's world anchor and axis (B, n, 3), and the last body's position and rotation."""
        b = len(qs)
        pos, rot = np.zeros((b, 3)), np.broadcast_to(np.eye(3), (b, 3, 3))
        anchors, axes = np.empty((b, self.n_joints, 3)), np.empty((b, self.n_joints, 3))
        for link in self.links:
            pos = pos + rot @ link.pos
            rot = rot @ link.rot
            if link.arm < 0:
                continue
            anchor = pos + rot @ link.anchor
            anchors[:, link.arm], axes[:, link.arm] = anchor, rot @ link.axis
            rot = rot @ _axis_angle(link.axis, qs[:, link.arm] - link.zero)
            pos = anchor - rot @ link.anchor  # the body turns about the anchor, not its origin
        return anchors, axes, pos, rot

    def site_frames(self, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The site's positions (B, 3) and rotations (B, 3, 3) at joint vectors ``qs`` (B, n)."""
        _, _, pos, rot = self._walk(np.asarray(qs, dtype=float))
        return pos + rot @ self.site_pos, rot @ self.site_rot

    def site_jacobians(self, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (B, 3), rotations (B, 3, 3) and Jacobians (B, 6, n): translation over rotation."""
        anchors, axes, pos, rot = self._walk(np.asarray(qs, dtype=float))
        site = pos + rot @ self.site_pos
        jp = np.cross(axes, site[:, None, :] - anchors)  # (B, n, 3)
        return site, rot @ self.site_rot, np.concatenate([jp, axes], axis=-1).transpose(0, 2, 1)
