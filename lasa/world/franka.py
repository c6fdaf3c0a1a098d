r"""Franka's official Panda conventions, the yardstick our ``panda`` is checked against: the modified
(Craig) Denavit-Hartenberg table, :math:`T_i = R_x(\alpha_{i-1}) T_x(a_{i-1}) R_z(\theta_i) T_z(d_i)`,
flange and TCP offsets, joint limits, "ready" pose, and the ``gymnasium-robotics`` Panda's chain."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pandas as pd

from lasa.base.errors import ConfigError
from lasa.world.chain import rot_z
from lasa.world.robot import Robot, mesh_dir

# (a_{i-1} [m], d_i [m], alpha_{i-1} [rad]) for joints 1..7, from Franka's documentation.
DH: tuple[tuple[float, float, float], ...] = (
    (0.0, 0.333, 0.0),
    (0.0, 0.0, -np.pi / 2),
    (0.0, 0.316, np.pi / 2),
    (0.0825, 0.0, np.pi / 2),
    (-0.0825, 0.384, -np.pi / 2),
    (0.0, 0.0, np.pi / 2),
    (0.088, 0.0, np.pi / 2),
)
FLANGE_D = 0.107  # flange, along z of frame 7 [m]
TCP_D = 0.1034  # Franka Hand TCP beyond the flange [m]
HAND_YAW = -np.pi / 4  # hand mounting rotation about the flange's z [rad]
LOWER = np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973])  # [rad]
UPPER = np.array([2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973])  # [rad]
# Franka's published limits of the Panda (velocity [rad/s], acceleration [rad/s^2]) and of the FR3
# (joints, velocity, acceleration), and the limits both arms share: a live station drives either
# (lasa.live.guard narrows these further).
VELOCITY = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
ACCELERATION = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
FR3_LOWER = np.array([-2.7437, -1.7837, -2.9007, -3.0421, -2.8065, 0.5445, -3.0159])
FR3_UPPER = np.array([2.7437, 1.7837, 2.9007, -0.1518, 2.8065, 4.5169, 3.0159])
FR3_VELOCITY = np.array([2.62, 2.62, 2.62, 2.62, 5.26, 4.18, 5.26])
FR3_ACCELERATION = np.full(7, 10.0)
SHARED_LOWER = np.maximum(LOWER, FR3_LOWER)
SHARED_UPPER = np.minimum(UPPER, FR3_UPPER)
SHARED_VELOCITY = np.minimum(VELOCITY, FR3_VELOCITY)
SHARED_ACCELERATION = np.minimum(ACCELERATION, FR3_ACCELERATION)
READY = np.array([0.0, -np.pi / 4, 0.0, -3 * np.pi / 4, 0.0, np.pi / 2, np.pi / 4])  # [rad]

# The packaged chain's joints 6 and 7 are re-framed: its q equals Franka's q minus these.
PACKAGED_OFFSETS = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.57, np.pi / 4])  # [rad]


def _rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _transform(rotation: np.ndarray | None = None, x: float = 0.0, z: float = 0.0) -> np.ndarray:
    """The 4 x 4 transform of ``rotation`` (3, 3; None: none) and the translation (x, 0, z)."""
    t = np.eye(4)
    if rotation is not None:
        t[:3, :3] = rotation
    t[0, 3], t[2, 3] = x, z
    return t


def dh_frames(q: np.ndarray) -> dict[str, np.ndarray]:
    """World transforms (4x4) ``link1`` .. ``link7``, ``flange`` and ``tcp`` at Franka's joints ``q`` (7,)."""
    q = np.asarray(q, dtype=float)
    if q.shape != (7,):
        raise ConfigError(f"q must have 7 entries, got shape {q.shape}")
    frames: dict[str, np.ndarray] = {}
    t = np.eye(4)
    for i, ((a, d, alpha), theta) in enumerate(zip(DH, q, strict=True), start=1):
        t = t @ _rot_x(alpha) @ _transform(x=a) @ _transform(rot_z(theta)) @ _transform(z=d)
        frames[f"link{i}"] = t
    frames["flange"] = flange = t @ _transform(z=FLANGE_D)
    frames["tcp"] = flange @ _transform(rot_z(HAND_YAW)) @ _transform(z=TCP_D)
    return frames


def packaged_chain() -> mujoco.MjModel:
    """The Panda chain that ``gymnasium-robotics`` ships, compiled for kinematics only: bodies, joints and
    sites (``end_effector``: the packaged TCP) exactly, without geoms, inertias and classes (they need the
    package's defaults and meshes)."""
    root = mesh_dir("gymnasium_robotics", "envs/assets/kitchen_franka/franka_assets")
    chain = ET.parse(root / "chain.xml").getroot()
    for parent in list(chain.iter()):
        for child in list(parent):
            if child.tag in ("geom", "inertial"):
                parent.remove(child)
    for element in chain.iter():
        element.attrib.pop("class", None)
        element.attrib.pop("childclass", None)
        if element.tag == "joint" and "axis" not in element.attrib:
            element.set("axis", "0 0 1")
        if element.tag == "body":
            ET.SubElement(element, "inertial", pos="0 0 0", mass="0.1", diaginertia="1e-3 1e-3 1e-3")
    world = "".join(ET.tostring(body, encoding="unicode") for body in chain)
    xml = f'<mujoco><compiler angle="radian" autolimits="true"/><worldbody>{world}</worldbody></mujoco>'
    return mujoco.MjModel.from_xml_string(xml)


def check_against_dh(robot: Robot, n: int = 200, seed: int = 0) -> pd.DataFrame:
    """How far models' forward kinematics are from Franka's DH table at ``n`` uniform joint vectors: per
    model (``robot``; the packaged chain at the same q; with its joint-6/7 offsets undone), the largest
    TCP position [m] and orientation [rad] errors, and over frames 1..7 [m] (``robot`` only)."""
    qs = np.random.default_rng(seed).uniform(LOWER, UPPER, size=(n, 7))
    ours = mujoco.MjData(robot.model)
    packaged = packaged_chain()
    pdata = mujoco.MjData(packaged)
    site = robot.model.site(robot.spec.grasp_site).id
    records = []
    for q in qs:
        ref = dh_frames(q)
        tcp = ref["tcp"]
        ours.qpos[robot.qpos_adr] = q
        mujoco.mj_kinematics(robot.model, ours)
        frames = max(
            float(np.linalg.norm(ours.body(f"link{i}").xpos - ref[f"link{i}"][:3, 3])) for i in range(1, 8)
        )
        cases = [("lasa panda", ours.site_xpos[site].copy(), ours.site_xmat[site].copy(), frames)]
        for name, qq in (("packaged, same q", q), ("packaged, q - offsets", q - PACKAGED_OFFSETS)):
            pdata.qpos[:7] = qq
            mujoco.mj_kinematics(packaged, pdata)
            s = pdata.site("end_effector")
            cases.append((name, s.xpos.copy(), s.xmat.copy(), float("nan")))
        for name, pos, mat, fr in cases:
            cos = (np.trace(mat.reshape(3, 3).T @ tcp[:3, :3]) - 1) / 2
            rot_err = float(np.arccos(np.clip(cos, -1.0, 1.0)))
            records.append((name, float(np.linalg.norm(pos - tcp[:3, 3])), rot_err, fr))
    columns = ("max_tcp_position_error_m", "max_tcp_rotation_error_rad", "max_frame_position_error_m")
    frame = pd.DataFrame(records, columns=("model", *columns))
    return frame.groupby("model", sort=False, as_index=False).max()


# ---- The connected arm's forward kinematics against the package's Panda ---------------------------------
# The package's Panda (the decoders' robot) is built on the DH table above; Franka's FR3 shares that table,
# flange and Franka Hand TCP, and differs in joint limits (FR3_LOWER, FR3_UPPER) and dynamics. libfranka
# reports the end effector as O_T_EE (base to EE, with F_T_EE the configured hand: TCP_D along the flange's
# z, HAND_YAW about it), which is the package Panda's EE_SITE; both put the arm's base at the world origin.
# lasa.live.kinematics moves a connected arm and compares.
EE_SITE = "grasp"  # the package Panda's site at Franka's EE (flange + Franka Hand TCP), every scene's


_ABOVE_FLOOR = ("link3", "link4", "link5", "link6", "link7", "flange", "tcp")  # the frames kept off the table


def shared_configurations(n: int, seed: int, margin: float = 0.2, floor: float = 0.1) -> np.ndarray:
    """``n`` uniform joint vectors (n, 7) [rad] inside the limits the Panda and the FR3 share, ``margin``
    [rad] from each, whose frames (:func:`dh_frames`: link 3 to the TCP) stay ``floor`` [m] above the base's
    plane (the table a real arm stands on); ``seed`` the generator's. Self-collisions are not checked."""
    lower, upper = SHARED_LOWER + margin, SHARED_UPPER - margin
    if n < 1 or np.any(lower >= upper):
        raise ConfigError(f"need n >= 1 and a margin below half the shared range, got n={n}, margin={margin}")
    rng = np.random.default_rng(seed)
    kept: list[np.ndarray] = []
    for _ in range(1000 * n):
        q = rng.uniform(lower, upper)
        frames = dh_frames(q)
        if min(frames[k][2, 3] for k in _ABOVE_FLOOR) >= floor:
            kept.append(q)
            if len(kept) == n:
                return np.array(kept)
    raise ConfigError(f"fewer than {n} of {1000 * n} samples keep {floor} m above the base: lower the floor")


def ee_poses(robot: Robot, q: np.ndarray) -> np.ndarray:
    """The package Panda's EE (site :data:`EE_SITE`) at joint vectors ``q`` (n, 7), (n, 4, 4) transforms."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    data = mujoco.MjData(robot.model)
    site = robot.model.site(EE_SITE).id
    out = np.tile(np.eye(4), (len(q), 1, 1))
    for pose, qq in zip(out, q, strict=True):
        data.qpos[robot.qpos_adr] = qq
        mujoco.mj_kinematics(robot.model, data)
        pose[:3, :3] = data.site_xmat[site].reshape(3, 3)
        pose[:3, 3] = data.site_xpos[site]
    return out


def rotation_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""The angle [rad] of the rotation between (..., 3, 3) rotations ``a`` and ``b``,
    :math:`\theta = \operatorname{atan2}(\|\operatorname{vee}(R - R^T)\| / 2, (\operatorname{tr} R - 1) / 2)`
    with :math:`R = a^T b` (accurate near 0, where arccos of the trace is not)."""
    r = np.swapaxes(a, -1, -2) @ b
    skew = np.stack(
        [r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]], -1
    )
    return np.arctan2(np.linalg.norm(skew, axis=-1) / 2, (np.trace(r, axis1=-2, axis2=-1) - 1) / 2)


def fk_errors(robot: Robot, q: np.ndarray, measured: np.ndarray) -> pd.DataFrame:
    """How far the package Panda's EE at joint vectors ``q`` (n, 7) [rad] is from the ``measured`` EE poses
    (n, 4, 4; libfranka's O_T_EE read with ``q``): one row per configuration, ``q0``..``q6``,
    ``position_error_m`` and ``orientation_error_rad``."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    measured = np.asarray(measured, dtype=float).reshape(-1, 4, 4)
    if q.shape != (len(measured), 7):
        raise ConfigError(f"q must be (n, 7) with one row per pose, got {q.shape} for {len(measured)} poses")
    ours = ee_poses(robot, q)
    table = pd.DataFrame(q, columns=[f"q{i}" for i in range(7)])
    table["position_error_m"] = np.linalg.norm(ours[:, :3, 3] - measured[:, :3, 3], axis=-1)
    table["orientation_error_rad"] = rotation_angle(ours[:, :3, :3], measured[:, :3, :3])
    return table
