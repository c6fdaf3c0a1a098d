"""Robots: a MuJoCo scene plus the named quantities the goal tasks need.

A :class:`RobotSpec` names what lasa reads from an MJCF scene (:func:`load_robot`); a :class:`Robot`
is that scene compiled. The state ``s`` is the arm's joint positions [rad]; the action a joint velocity."""

from __future__ import annotations

import dataclasses
import functools
import importlib.util
from pathlib import Path
from types import MappingProxyType

import mujoco
import numpy as np

from lasa.base.config import ControlConfig, check_choice
from lasa.base.errors import ArtifactError, ConfigError
from lasa.world.chain import SerialChain

ASSETS = Path(__file__).parent / "assets"


@dataclasses.dataclass(frozen=True)
class RobotSpec:
    """What lasa needs to know about a robot beyond its MJCF file, whose names it refers to."""

    name: str  # e.g. "planar5"; decoders and checkpoints are made for a robot of this name
    scene: Path  # MJCF scene: the arm, a table, the goals (cups, bowls) and a camera
    joints: tuple[str, ...]  # arm joints, in state order
    top_grasp_rotation: tuple[float, ...]  # 3x3 row-major grasp-site rotation of a top grasp
    grasp_standoff: float  # distance from cup centre to the grasp site [m]
    side_azimuth: float  # side-grasp approach: the radial direction turned this far towards the midline [rad]
    ik_guesses: tuple[tuple[float, ...], ...]  # one joint-space IK guess per cup [rad]
    grasp_site: str = "grasp"  # site between the finger tips; local +z is the approach direction
    # one site per goal (a cup's grasp centre, a bowl's surface), in goal order
    goal_sites: tuple[str, ...] = ("cup_left", "cup_right")
    camera: str = "front"  # fixed camera used for videos
    home_key: str = "home"  # keyframe of the start pose
    control: ControlConfig = ControlConfig()  # default units of the control loop for this robot
    mesh_package: tuple[str, str] | None = None  # (package, folder inside it) holding the meshes
    # cups added after training (Sec. IV-C), built like the first cup: (site name, grasp centre [m])
    extra_cups: tuple[tuple[str, tuple[float, float, float]], ...] = ()
    # a tool in the hand (the fork): an MJCF file whose first body is attached to body "hand" at site
    # "grasp" (axes aligned), its names prefixed with "fork_" (its site "tip" becomes "fork_tip")
    tool: Path | None = None


# The package's robots, by name.
ROBOTS: MappingProxyType[str, RobotSpec] = MappingProxyType(
    {
        "planar5": RobotSpec(
            name="planar5",
            scene=ASSETS / "planar5" / "scene.xml",
            joints=("joint1", "joint2", "joint3", "joint4", "joint5"),
            # Fingers pointing down (-z); the hand's x axis along -x, its y along +y.
            top_grasp_rotation=(-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0),
            grasp_standoff=0.10,
            side_azimuth=0.0,  # in the arm's plane the side grasp points away from the base
            ik_guesses=((-0.9, -0.9, -0.7, -0.3, 0.0), (0.9, 0.9, 0.7, 0.3, 0.0)),
            # control: a step <= dt sigma_h = 0.0375 rad; beta = 75 is noisy, 1000 near optimal (notebook 04)
        ),
        "panda": RobotSpec(
            name="panda",
            scene=ASSETS / "panda" / "scene.xml",
            joints=tuple(f"joint{i}" for i in range(1, 8)),
            # Hand pointing down, fingers closing along world y: the TCP frame of the ready pose.
            top_grasp_rotation=(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0),
            grasp_standoff=0.0,  # the TCP at the cup's grasp point: the preference is the orientation
            # each cup approached from its outer side (radially outward flips the wrist; notebook 01)
            side_azimuth=1.5707963267948966,  # pi/2
            ik_guesses=((0.0, -0.7854, 0.0, -2.3562, 0.0, 1.5708, 0.7854),) * 2,  # the ready pose
            mesh_package=("gymnasium_robotics", "envs/assets/kitchen_franka/franka_assets/meshes"),
        ),
    }
)


def mesh_dir(package: str, folder: str) -> Path:
    """The folder of meshes that an installed package ships, found without importing it."""
    spec = importlib.util.find_spec(package)
    if spec is None or not spec.submodule_search_locations:
        raise ArtifactError(
            f"package {package!r}, which ships this robot's meshes, is not installed; run: make setup"
        )
    path = Path(next(iter(spec.submodule_search_locations))) / folder
    if not path.is_dir():
        raise ArtifactError(f"{path} is missing from package {package!r}; reinstall it with: make setup")
    return path


NEW_CUP_RGBA = (0.25, 0.45, 0.85, 1.0)  # new cups are blue


@functools.lru_cache(maxsize=16)
def _scene_xml(spec: RobotSpec) -> str:
    """:func:`_scene_spec`'s MJCF text, written once per spec (the web study logs it every trial)."""
    return _scene_spec(spec).to_xml()


def _scene_spec(spec: RobotSpec) -> mujoco.MjSpec:
    """The robot's scene as a new MjSpec (it cannot be pickled): meshes found, tool, new cups."""
    mj_spec = mujoco.MjSpec.from_file(str(spec.scene))
    if spec.mesh_package is not None:  # mesh paths in the MJCF are relative to the package's folder
        root = mesh_dir(*spec.mesh_package)
        for mesh in mj_spec.meshes:
            file = Path(mesh.file)
            rel = file.relative_to(spec.scene.parent) if file.is_absolute() else file
            if not (root / rel).is_file():
                raise ArtifactError(f"{root} lacks mesh {rel}; reinstall its package with: make setup")
            mesh.file = str(root / rel)
    if spec.tool is not None:
        tool = mujoco.MjSpec.from_file(str(spec.tool))
        site = mj_spec.site("grasp")
        frame = mj_spec.body("hand").add_frame(pos=site.pos, quat=site.quat)
        frame.attach_body(tool.worldbody.first_body(), "fork_", "")
    for name, position in spec.extra_cups:  # shaped like the first cup, its site at `position`
        site, geom = mj_spec.site(spec.goal_sites[0]), mj_spec.geom(spec.goal_sites[0])
        offset = np.asarray(position, dtype=float) - np.asarray(site.pos)
        body = mj_spec.worldbody.add_body(name=name, pos=offset)
        kw = {"size": geom.size, "pos": geom.pos, "rgba": NEW_CUP_RGBA, "contype": 0, "conaffinity": 0}
        body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_CYLINDER, **kw)
        body.add_site(name=name, pos=site.pos, size=site.size, rgba=site.rgba)
    return mj_spec


def scene_problems(spec: RobotSpec) -> list[str]:
    """What ``spec`` and its scene lack of the naming contract (:func:`load_robot`), one entry per
    missing or unfit element naming what lasa reads it for; ConfigError if the scene does not compile."""
    if not Path(spec.scene).is_file():
        raise ConfigError(f"robot {spec.name!r}: its scene {spec.scene} is not a file")
    out = []
    if len(spec.goal_sites) < 2:
        out.append(f"{len(spec.goal_sites)} goal sites: at least two are needed")
    if [len(q) for q in spec.ik_guesses] != [len(spec.joints)] * len(spec.goal_sites):
        out.append(f"ik_guesses must hold one guess of {len(spec.joints)} joint values per goal site")
    if len(spec.top_grasp_rotation) != 9:
        out.append("top_grasp_rotation must hold 9 values (3 x 3, row-major)")
    try:
        model = _scene_spec(spec).compile()
    except ValueError as err:  # MuJoCo's parse and compile errors
        raise ConfigError(f"robot {spec.name!r}: MuJoCo cannot load {spec.scene}: {err}") from None
    if mujoco.MjSpec.from_file(str(spec.scene)).compiler.degree:
        out.append(
            'its angles are in degrees (MJCF\'s default: the scene has no <compiler angle="radian"/>), '
            "while lasa's are radians (the state, the keyframe, RobotSpec.ik_guesses); add "
            '<compiler angle="radian"/> and write the joint ranges in radians'
        )
    obj = mujoco.mjtObj

    def missing(kind: mujoco.mjtObj, word: str, name: str, why: str) -> bool:
        if mujoco.mj_name2id(model, kind, name) >= 0:
            return False
        out.append(f"no {word} {name!r} ({why})")
        return True

    for joint in spec.joints:
        if missing(obj.mjOBJ_JOINT, "joint", joint, "an arm joint of the state, RobotSpec.joints"):
            continue
        j = model.joint(joint).id
        if int(model.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            out.append(f"joint {joint!r} must be a hinge or a slide joint (one coordinate of the state)")
        elif not model.jnt_limited[j]:
            out.append(f"joint {joint!r} needs a range (its limits clip every step)")
    why_grasp = "the grasp site, RobotSpec.grasp_site; its +z is the approach"
    missing(obj.mjOBJ_SITE, "site", spec.grasp_site, why_grasp)
    for site in spec.goal_sites:
        missing(obj.mjOBJ_SITE, "site", site, "a goal's site, RobotSpec.goal_sites")
        missing(obj.mjOBJ_GEOM, "geom", site, "the goal's body, beside its site: new cups copy it")
    if not missing(obj.mjOBJ_GEOM, "geom", "table", "a box: the table new cups must stand on"):
        if int(model.geom_type[model.geom("table").id]) != int(mujoco.mjtGeom.mjGEOM_BOX):
            out.append("geom 'table' must be a box (new cups must stand within its extent)")
    missing(obj.mjOBJ_CAMERA, "camera", spec.camera, "the videos' camera, RobotSpec.camera")
    missing(obj.mjOBJ_KEY, "keyframe", spec.home_key, "the start pose, RobotSpec.home_key")
    return out


def load_robot(robot: str | RobotSpec) -> Robot:
    """Build one of the package's robots by name (:data:`ROBOTS`), or yours from its spec, checked
    (ConfigError names what an unknown name, a spec named like one of ours, or its scene gets wrong).

    **The naming contract** of ``spec.scene``: a hinge (or slide) joint with a ``range`` per name of
    ``spec.joints`` (the state, in that order, clipped to the ranges); a site ``spec.grasp_site``, its
    +z the approach (``spec.top_grasp_rotation``, 9 values, its rotation in a top grasp, pointing down);
    per name of ``spec.goal_sites`` (two or more, in goal order) a site (a cup's grasp centre) and a geom
    (the cup, ``size[0]`` its radius; new cups copy it; ``cup_<x>`` names goal ``<x>``); a box geom
    ``table``, a camera ``spec.camera``, a keyframe ``spec.home_key`` (every episode's start, within the
    ranges); ``<compiler angle="radian"/>`` (else MJCF reads ranges, ``euler`` and ``axisangle`` in
    degrees, a keyframe's ``qpos`` in radians). The spec gives one IK guess per cup and control units."""
    if isinstance(robot, str):
        check_choice("robot", robot, tuple(ROBOTS))
        return Robot(ROBOTS[robot])
    if robot == ROBOTS.get(robot.name):
        return Robot(robot)
    if robot.name in ROBOTS:
        raise ConfigError(f"{robot.name!r} is one of the package's robots; name yours otherwise")
    if problems := scene_problems(robot):
        raise ConfigError(
            f"robot {robot.name!r} ({robot.scene}) breaks the naming contract of load_robot: "
            + "; ".join(problems)
        )
    built = Robot(robot)
    if np.any(built.home < built.lower) or np.any(built.home > built.upper):
        raise ConfigError(f"robot {robot.name!r}: keyframe {robot.home_key!r} lies outside the joint ranges")
    return built


class Robot:
    """A compiled MuJoCo scene answering in the task's terms: ``spec`` (its ``name``, default ``control``),
    ``model`` and an ``MjData`` ``data`` for kinematics (not thread safe), ``n_joints`` n (of the state and
    the action), and per arm joint its index in ``data.qpos``, ``qpos_adr``, and limits ``lower``, ``upper``
    [rad]."""

    def __init__(self, spec: RobotSpec) -> None:
        self.spec, self.name, self.n_joints, self.control = spec, spec.name, len(spec.joints), spec.control
        self.model = _scene_spec(spec).compile()
        self.data = mujoco.MjData(self.model)
        joint_ids = [self.model.joint(name).id for name in spec.joints]
        self.qpos_adr = self.model.jnt_qposadr[joint_ids]
        self._dofs = self.model.jnt_dofadr[joint_ids]
        self.lower, self.upper = self.model.jnt_range[joint_ids].T.copy()
        self._site = self.model.site(spec.grasp_site).id
        self._home = self.model.key(spec.home_key).qpos[self.qpos_adr].copy()
        self.top_rotation = np.asarray(spec.top_grasp_rotation, dtype=float).reshape(3, 3)  # of a top grasp
        # the site's kinematics for a whole batch at once; None unless the arm is a chain of hinges
        self._chain = SerialChain.of(self.model, self._site, self.qpos_adr)

    @property
    def home(self) -> np.ndarray:
        """The start pose of every episode (keyframe ``spec.home_key``), shape (n,) [rad]."""
        return self._home.copy()

    def clip(self, q: np.ndarray) -> np.ndarray:
        """Clip joint positions of any leading shape to the joint limits."""
        return np.clip(q, self.lower, self.upper)

    def set_state(self, q: np.ndarray) -> None:
        """Write arm joint positions into ``data`` and update kinematics."""
        self.data.qpos[self.qpos_adr] = q
        mujoco.mj_kinematics(self.model, self.data)

    def grasp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation (3, 3) of the grasp site at joints ``q``."""
        self.set_state(q)
        return self.data.site_xpos[self._site].copy(), self.data.site_xmat[self._site].reshape(3, 3).copy()

    def grasp_frames(self, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Grasp-site positions (..., 3) and rotations (..., 3, 3) for a batch of joint vectors."""
        qs = np.asarray(qs, dtype=float)
        flat, lead = qs.reshape(-1, self.n_joints), qs.shape[:-1]
        if self._chain is not None:  # the batch at once (lasa.world.chain)
            pos, rot = self._chain.site_frames(flat)
            return pos.reshape(*lead, 3), rot.reshape(*lead, 3, 3)
        pos, rot = np.empty((len(flat), 3)), np.empty((len(flat), 3, 3))
        for i, q in enumerate(flat):  # MuJoCo's kinematics takes one configuration at a time
            self.set_state(q)
            pos[i] = self.data.site_xpos[self._site]
            rot[i] = self.data.site_xmat[self._site].reshape(3, 3)
        return pos.reshape(*lead, 3), rot.reshape(*lead, 3, 3)

    def grasp_jacobians(
        self, qs: np.ndarray, data: mujoco.MjData | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Grasp-site positions (B, 3), rotations (B, 3, 3) and Jacobians (B, 6, n), translation over
        rotation (world frame), at joints ``qs`` (B, n); an arm that is not a chain of hinges goes through
        MuJoCo one configuration at a time, writing ``data`` (default: this robot's own)."""
        qs = np.asarray(qs, dtype=float).reshape(-1, self.n_joints)
        if self._chain is not None:  # the batch at once (lasa.world.chain)
            return self._chain.site_jacobians(qs)
        data = self.data if data is None else data
        jacp, jacr = np.zeros((3, self.model.nv)), np.zeros((3, self.model.nv))
        pos, rot = np.empty((len(qs), 3)), np.empty((len(qs), 3, 3))
        jac = np.empty((len(qs), 6, self.n_joints))
        for i, q in enumerate(qs):  # MuJoCo's kinematics take one configuration at a time
            data.qpos[self.qpos_adr] = q
            mujoco.mj_kinematics(self.model, data)
            mujoco.mj_comPos(self.model, data)
            mujoco.mj_jacSite(self.model, data, jacp, jacr, self._site)
            pos[i] = data.site_xpos[self._site]
            rot[i] = data.site_xmat[self._site].reshape(3, 3)
            jac[i, :3], jac[i, 3:] = jacp[:, self._dofs], jacr[:, self._dofs]
        return pos, rot, jac

    def grasp_positions(self, qs: np.ndarray) -> np.ndarray:
        """Grasp-site positions for a batch of joint vectors, shape (..., 3)."""
        return self.grasp_frames(qs)[0]

    def grasp_axes(self, qs: np.ndarray) -> np.ndarray:
        """Approach direction (the site's +z axis) for a batch of joint vectors, (..., 3)."""
        return self.grasp_frames(qs)[1][..., :, 2]

    def goal_positions(self) -> np.ndarray:
        """World positions of the goals' sites, shape (G, 3), in goal order."""
        mujoco.mj_kinematics(self.model, self.data)
        return np.stack([self.data.site(name).xpos.copy() for name in self.spec.goal_sites])

    def radial(self, goal: int) -> np.ndarray:
        """The unit horizontal direction from the arm's base to goal ``goal``'s site, (3,)."""
        out = self.goal_positions()[goal] - self.base_position()
        out[2] = 0.0
        norm = np.linalg.norm(out)
        if norm < 1e-6:
            raise ConfigError(f"goal {goal} stands above the robot's base: no direction towards it")
        return out / norm

    def with_cup(self, position: np.ndarray, name: str = "cup_new") -> Robot:
        """The same robot in a scene with one more cup, the last goal, its grasp centre at ``position``
        (workspace checks: :func:`lasa.method.context_map.extend_task`); ConfigError if the name is taken."""
        if name in self.spec.goal_sites:
            raise ConfigError(f"the scene already has a cup named {name!r}")
        x, y, z = (float(v) for v in np.asarray(position, dtype=float).reshape(3))
        cups = (*self.spec.extra_cups, (name, (x, y, z)))
        spec = dataclasses.replace(self.spec, goal_sites=(*self.spec.goal_sites, name), extra_cups=cups)
        return Robot(spec)

    def xml(self) -> str:
        """The scene as one MJCF document (meshes by absolute path), for a session log to replay."""
        return _scene_xml(self.spec)

    def table_extent(self) -> tuple[np.ndarray, np.ndarray]:
        """Centre (3,) and half-sizes (3,) of the table box (geom ``table``)."""
        geom = self.model.geom("table")
        return self.model.geom_pos[geom.id].copy(), self.model.geom_size[geom.id].copy()

    def first_joint_axis(self) -> np.ndarray:
        """World direction of the first arm joint's axis at the home pose, shape (3,)."""
        self.set_state(self.home)
        return self.data.xaxis[self.model.joint(self.spec.joints[0]).id].copy()

    def base_position(self) -> np.ndarray:
        """World position of the arm's base (the first joint's anchor), shape (3,)."""
        self.set_state(self.home)
        return self.data.xanchor[self.model.joint(self.spec.joints[0]).id].copy()
