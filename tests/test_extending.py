"""docs/extending.md, tested: a robot, an assistance member, a claim and a decoder of one's own.

tests/test_docs.py runs the page's code as written; this file does each extension again and
tests what the page only shows: the naming contract's errors (a missing name, a scene in
degrees, a cup out of reach), that a member is called by the step and the rollout, a claim's
verdict in the claims table, a checkpoint's round trip. Each test goes through the public API
only (``import lasa`` names and the documented functions of lasa.evidence), on the page's toy
3-joint planar arm with three cups, whose MJCF the test writes: what a user would write in
their own files, and nothing in the package. The fixtures put the registries back afterwards,
so that the other tests see the package's own (a robot is an object, in no registry).
"""

from __future__ import annotations

import dataclasses
import types
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch
from matplotlib.figure import Figure

import lasa
from lasa.evidence import decision, plots, rules, verdicts

# --- the user's MJCF: three hinge joints about y (a planar arm), a table, three cups --------

TOY_SCENE = """
<mujoco model="toy3">
  {compiler}
  <worldbody>
    {table}
    <body name="link1" pos="0 0 0.12">
      <joint name="j1" type="hinge" axis="0 1 0" range="-2.9 2.9"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.35" size="0.02" contype="0" conaffinity="0"/>
      <body name="link2" pos="0 0 0.35">
        <joint name="j2" type="hinge" axis="0 1 0" range="-2.9 2.9"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.30" size="0.02" contype="0" conaffinity="0"/>
        <body name="hand" pos="0 0 0.30">
          <joint name="j3" type="hinge" axis="0 1 0" range="-2.9 2.9"/>
          <geom type="capsule" fromto="0 0 0 0 0 0.10" size="0.015" contype="0" conaffinity="0"/>
          <site name="grasp" pos="0 0 0.10"/>
        </body>
      </body>
    </body>
    {cups}
    <camera name="front" pos="0 -2 0.5" xyaxes="1 0 0 0 0 1"/>
  </worldbody>
  {keyframe}
</mujoco>
"""
TABLE = '<geom name="table" type="box" size="0.8 0.3 0.02" pos="0 0 -0.02"/>'
CUP = (
    '<body pos="{x} 0 0"><geom name="{name}" type="cylinder" size="0.035 0.06" pos="0 0 0.06"'
    ' contype="0" conaffinity="0"/><site name="{name}" pos="0 0 0.07"/></body>'
)
HOME = '<keyframe><key name="home" qpos="0 0 0"/></keyframe>'
CUPS = {"cup_left": -0.45, "cup_mid": 0.30, "cup_right": 0.55}


RADIAN = '<compiler angle="radian" autolimits="true"/>'


def write_scene(
    folder: Path,
    table: bool = True,
    cup_geoms: bool = True,
    home: bool = True,
    compiler: str = RADIAN,
    cups_at: dict[str, float] = CUPS,
) -> Path:
    cups = "\n".join(CUP.format(x=x, name=name) for name, x in cups_at.items())
    if not cup_geoms:  # sites only
        cups = "\n".join(f'<site name="{name}" pos="{x} 0 0.07"/>' for name, x in cups_at.items())
    xml = TOY_SCENE.format(
        compiler=compiler, table=TABLE if table else "", cups=cups, keyframe=HOME if home else ""
    )
    path = folder / "toy3.xml"
    path.write_text(xml)
    return path


def toy_spec(scene: Path) -> lasa.RobotSpec:
    """The user's spec of the toy arm (docs/extending.md, "A robot")."""
    return lasa.RobotSpec(
        name="toy3",
        scene=scene,
        joints=("j1", "j2", "j3"),
        grasp_site="grasp",
        goal_sites=tuple(CUPS),
        camera="front",
        home_key="home",
        top_grasp_rotation=(-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0),  # fingers down
        grasp_standoff=0.05,
        side_azimuth=0.0,
        ik_guesses=((-0.5, -1.5, -1.0), (0.3, 1.5, 1.2), (0.5, 1.5, 1.0)),
        control=lasa.ControlConfig(),
    )


# --- the user's decoder: phi(z, s, b) heads for a point between the goals that z picks -------


@dataclasses.dataclass(frozen=True)
class PointerConfig:
    robot: str
    goals: tuple[tuple[float, ...], ...]  # the goals it heads for, (G, n) [rad]
    speed: float = 0.375  # bound on ||phi|| [rad/s]


class GoalPointer(torch.nn.Module):
    """z = -1 heads for the first goal, z = 1 for the last, in between along the goals in turn."""

    config_class = PointerConfig

    def __init__(self, config: PointerConfig) -> None:
        super().__init__()
        self.config = config
        self.goals = torch.nn.Parameter(torch.tensor(config.goals, dtype=torch.float64))
        self.gain = torch.nn.Parameter(torch.ones((), dtype=torch.float64))

    @property
    def robot(self) -> str:
        return self.config.robot

    @property
    def n_goals(self) -> int:
        return len(self.config.goals)

    @property
    def z_dim(self) -> int:
        return 1

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        goals = self.goals.detach().numpy()
        u = (np.clip(np.asarray(z, dtype=float)[..., 0], -1.0, 1.0) + 1.0) / 2.0 * (len(goals) - 1)
        low = np.clip(np.floor(u).astype(int), 0, len(goals) - 2)
        w = (u - low)[..., None]
        v = (1.0 - w) * goals[low] + w * goals[low + 1] - s
        norm = np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)
        phi = float(self.gain.detach()) * self.config.speed * np.tanh(norm) * v / norm
        shape = np.broadcast_shapes(np.shape(z)[:-1], np.shape(s)[:-1], np.shape(b)[:-1])
        return np.broadcast_to(phi, (*shape, phi.shape[-1])).copy()


def pointer_for(task: lasa.GoalTask) -> GoalPointer:
    return GoalPointer(PointerConfig(task.robot.name, tuple(tuple(map(float, g)) for g in task.goals)))


# --- fixtures: the toy task; the registries as the package has them, before and after each test


@pytest.fixture(scope="module")
def toy_task(tmp_path_factory: pytest.TempPathFactory):
    return lasa.make_cup_task(
        lasa.load_robot(toy_spec(write_scene(tmp_path_factory.mktemp("toy")))), n_grid=9
    )


def users_at_each_goal(task: lasa.GoalTask, per_goal: int) -> lasa.UserPopulation:
    goal = np.repeat(np.arange(task.n_goals), per_goal)
    theta = np.tile(np.linspace(0.2, 0.8, per_goal), task.n_goals)
    n = len(goal)
    return lasa.UserPopulation(
        goal=goal,
        theta=theta,
        target=task.target(goal, theta),
        beta0=np.full(n, 1000.0),
        slope=np.zeros(n),
        user=np.arange(n),
    )


# --- 1. a robot ------------------------------------------------------------------------------


def test_a_robot_of_ones_own_builds_a_three_goal_task_and_runs_la_sa(toy_task, tmp_path):
    task = toy_task
    assert task.robot.name == "toy3" and "toy3" not in lasa.ROBOTS and task.robot.n_joints == 3
    assert task.n_goals == 3 and task.goal_names == ("left", "mid", "right")
    # s*(g, theta) puts the grasp site at each cup, from a top grasp to a side grasp
    robot = task.robot
    cups = robot.goal_positions()
    for g in range(3):
        top, side = robot.grasp_axes(task.target(g, np.array([0.0, 1.0])))
        np.testing.assert_allclose(top, [0.0, 0.0, -1.0], atol=1e-2)
        np.testing.assert_allclose(abs(side[0]), 1.0, atol=1e-2)
        tip = robot.grasp_positions(task.goals[g])
        assert np.linalg.norm(tip - cups[g]) == pytest.approx(0.05, abs=2e-3)  # the standoff
    # LA+SA with a hand-written decoder: every user ends near their own cup, and believed there
    users = users_at_each_goal(task, 4)
    horizon = 100
    noise = np.random.default_rng(0).random((len(users), horizon, task.robot.control.n_z))
    traj = lasa.rollout(pointer_for(task), task, users, 0.2, task.robot.control, horizon, noise)
    goal_points = task.goals[users.goal]  # the decoder heads for goals, not for every grasp
    start = np.linalg.norm(task.start - goal_points, axis=-1)
    end = np.linalg.norm(traj.states[-1] - goal_points, axis=-1)
    assert np.all(end < 0.3 * start), (start, end)
    assert np.all(traj.beliefs[-1][np.arange(len(users)), users.goal] > 0.5)
    # a scene that breaks the naming contract is refused, naming each missing element
    broken = write_scene(tmp_path, table=False, cup_geoms=False, home=False)
    with pytest.raises(lasa.ConfigError) as info:
        lasa.load_robot(dataclasses.replace(toy_spec(broken), name="toy3_broken"))
    message = str(info.value)
    for missing in ("geom 'table'", "geom 'cup_left'", "geom 'cup_right'", "keyframe 'home'"):
        assert missing in message, message
    with pytest.raises(lasa.ConfigError, match="one guess of 3 joint values per goal site"):
        lasa.load_robot(dataclasses.replace(toy_spec(broken), name="toy3_guesses", ik_guesses=((0.0,) * 3,)))
    with pytest.raises(lasa.ConfigError, match="one of the package's robots"):
        lasa.load_robot(dataclasses.replace(toy_spec(broken), name="planar5"))


def test_a_scene_in_degrees_is_refused_in_one_line_that_says_how_to_fix_it(tmp_path):
    """MJCF's default unit is the degree: the page's ranges (-2.9, 2.9) would compile to +-0.05 rad,
    where no grasp can be reached. load_robot refuses the scene rather than guess."""
    for compiler in ("", '<compiler autolimits="true"/>', '<compiler angle="degree" autolimits="true"/>'):
        scene = write_scene(tmp_path, compiler=compiler)
        with pytest.raises(lasa.ConfigError) as info:
            lasa.load_robot(dataclasses.replace(toy_spec(scene), name="toy3_degrees"))
        message = str(info.value)
        assert "\n" not in message and "angles are in degrees" in message, message
        assert '<compiler angle="radian"/>' in message, message


def test_a_cup_out_of_reach_is_an_ik_error_naming_the_cup_and_theta(tmp_path):
    """The toy arm reaches 0.75 m from its shoulder; a cup 0.78 m out, grasped from 0.05 m above,
    is beyond it. The error says which cup, and at which preference, the solve gave up."""
    far = {"cup_left": -0.45, "cup_mid": 0.30, "cup_right": 0.78}
    spec = dataclasses.replace(toy_spec(write_scene(tmp_path, cups_at=far)), name="toy3_far")
    with pytest.raises(lasa.IKError, match=r"toy3_far \(cup 'cup_right', theta = 0\.000\) did not converge"):
        lasa.make_cup_task(lasa.load_robot(spec), n_grid=5)


# --- 2. an assistance member -----------------------------------------------------------------


def test_an_assistance_member_of_ones_own_is_called_by_the_step_and_the_rollout(toy_task):
    task = toy_task
    calls: list[tuple[int, ...]] = []

    def likeliest(belief, state, goals, goal_sets, dt, action_scale):
        """Straight to the likeliest goal at the human's speed, with full say in the blend."""
        calls.append(belief.shape)
        diff = goals[belief.argmax(axis=1)] - state
        norm = np.maximum(np.linalg.norm(diff, axis=1, keepdims=True), 1e-9)
        return action_scale * diff / norm, np.ones(len(state))

    assert isinstance(likeliest, lasa.Member)
    with pytest.raises(lasa.ConfigError, match="unknown assistance 'likeliest'"):
        lasa.ControlConfig(assistance="likeliest")  # a config names a built-in member only
    control = lasa.ControlConfig()
    decoder = pointer_for(task)
    n = 3
    state = np.broadcast_to(task.start, (n, 3)).copy()
    log_b = np.log(np.array([[0.7, 0.2, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8]]))
    z = np.zeros((n, 1))
    la = lasa.shared_autonomy_step(decoder, task, control, state, log_b, z, 0.0, assistance=likeliest)
    sa = lasa.shared_autonomy_step(decoder, task, control, state, log_b, z, 0.5, assistance=likeliest)
    assert calls and all(shape == (n, 3) for shape in calls)
    a_r, _ = likeliest(np.exp(log_b), state, task.goals, task.curves, control.dt, control.action_scale)
    np.testing.assert_allclose(sa.action, 0.5 * la.human_action + 0.5 * a_r)
    assert not np.allclose(sa.action, la.action)
    # per user in a rollout, beside a built-in member named as configs name it
    users = users_at_each_goal(task, 2)
    horizon = 5
    noise = np.random.default_rng(1).random((len(users), horizon, control.n_z))
    before = len(calls)
    assistance = np.array([likeliest, "point"] * 3, dtype=object)
    traj = lasa.rollout(decoder, task, users, 0.2, control, horizon, noise, assistance=assistance)
    assert len(calls) == before + horizon and all(shape == (3, 3) for shape in calls[before:])
    assert np.all(np.isfinite(traj.states))
    with pytest.raises(lasa.ConfigError, match="unknown assistance 'likeliest'"):
        named = np.array(["likeliest"] * 6)
        lasa.rollout(decoder, task, users, 0.2, control, horizon, noise, assistance=named)
    with pytest.raises(lasa.ConfigError, match="built-in's name or a function, got 3"):
        lasa.shared_autonomy_step(decoder, task, control, state, log_b, z, 0.5, assistance=3)


# --- 3. a claim ------------------------------------------------------------------------------


def _toy_rule() -> decision.Rule:
    def decide(v):
        return "yes" if v["share_lower"] >= 1.0 else "partly" if v["share_lower"] > 0.5 else "no"

    return decision.Rule(
        id="toy.sa_lower",
        text="yes if LA+SA's mean final error is below LA's at every cup, partly if at more than half",
        quantities=(decision.Quantity("share_lower", (0.5, 1.0), "share of cups where LA+SA is below LA"),),
        decide=decide,
    )


TOY_RULE = _toy_rule()


def _toy_claims(frame: pd.DataFrame) -> list[lasa.Claim]:
    means = frame.groupby(["goal", "method"]).final_error.mean().unstack()
    share = float((means["LA+SA"] < means["LA"]).mean())
    verdict = TOY_RULE.verdict({"share_lower": share})
    return [
        lasa.Claim(
            id="toy.sa_lower",
            claim="shared autonomy lowers the final error at every cup",
            figure="toy",
            paper="LA+SA below LA",
            measured=f"below at {share:.0%} of the cups",
            reproduced=verdict,
            note="hand-made numbers",
            robot=str(frame.robot.iloc[0]),
            values={"share_lower": share},
            rule=TOY_RULE,
        )
    ]


def _plot(table: pd.DataFrame, task: lasa.GoalTask) -> Figure:
    fig = Figure(figsize=(6, 3))
    scene, bars = fig.subplots(1, 2)
    plots.draw_scene(task, scene)  # three cups, each in its colour
    plots.frame_around(task, scene, np.zeros((0, 2)))
    means = table.groupby(["goal", "method"]).final_error.mean().unstack()
    colors = plots.goal_colors(task.n_goals)
    bars.bar(means.index, means["LA"] - means["LA+SA"], color=[colors[g] for g in means.index])
    return fig


def test_a_claim_of_ones_own_is_judged_by_its_rule_and_lands_in_the_claims_table(toy_task, tmp_path):
    task = toy_task
    # the claim carries its rule; none replaces a paper claim's, and the paper's table is read-only
    paper_id = dataclasses.replace(TOY_RULE, id="sim1.final_error")
    with pytest.raises(lasa.ConfigError, match="exists already"):
        lasa.Claim("sim1.final_error", "c", "sim1", "p", "m", "yes", "", "toy3", rule=paper_id)
    with pytest.raises(TypeError):
        rules.RULES["toy.sa_lower"] = TOY_RULE  # type: ignore[index]
    assert "toy.sa_lower" not in rules.RULES
    assert TOY_RULE.verdict({"share_lower": 2 / 3}) == "partly"
    reading = lasa.Claim("toy.sa_lower@point", "c", "toy", "p", "m", "yes", "", "toy3", rule=TOY_RULE)
    assert reading.judged_by is TOY_RULE
    # hand-made numbers: 20 users per cup, LA+SA well below LA at all three
    rng = np.random.default_rng(0)
    rows = [
        {"robot": "toy3", "seed": u, "goal": g, "method": m, "final_error": mean + rng.normal(0, 0.02)}
        for u in range(60)
        for g in [u % 3]
        for m, mean in (("LA", 0.4), ("LA+SA", 0.1))
    ]
    frame = pd.DataFrame(rows)
    claims = verdicts.assess(_toy_claims, frame, n_boot=200, seed=0)
    figure = types.SimpleNamespace(NAME="toy_sa", COLUMNS=tuple(frame.columns), plot=_plot)
    paths = lasa.Paths.of(tmp_path / "build", tmp_path / "figures")
    lasa.publish(figure, frame, paths, claims, task=task)
    table = pd.read_csv(paths.claims, dtype=str, keep_default_na=False)
    row = table.set_index("id").loc["toy.sa_lower"]
    assert (row.robot, row.reproduced, row.settled, row.n_users) == ("toy3", "reproduced", "yes", "60")
    assert float(row.ci_low) == float(row.ci_high) == 1.0
    assert paths.figure("toy_sa.png").stat().st_size > 0
    assert len(pd.read_csv(paths.figure("toy_sa.csv"))) == len(frame)


# --- 4. a decoder ----------------------------------------------------------------------------


def test_a_decoder_of_ones_own_round_trips_through_a_checkpoint_and_drives_the_step(toy_task, tmp_path):
    task = toy_task
    model = pointer_for(task)
    assert isinstance(model, lasa.ActionDecoder)
    with torch.no_grad():
        model.gain.fill_(0.5)  # not the constructor's value: the state dict must carry it
    path = lasa.save_checkpoint(model, tmp_path / "pointer.pt", note="hand-written")
    loaded, extra = lasa.load_checkpoint(path, robot="toy3", decoder=GoalPointer, n_goals=3)
    assert isinstance(loaded, GoalPointer) and extra == {"note": "hand-written"}
    assert loaded.config == model.config and float(loaded.gain.detach()) == 0.5
    with pytest.raises(lasa.ArtifactError, match="load_checkpoint\\(..., decoder=GoalPointer\\)"):
        lasa.load_checkpoint(path)  # the default class is LatentActionModel
    with pytest.raises(lasa.ArtifactError, match="trained for robot 'toy3', not 'planar5'"):
        lasa.load_checkpoint(path, robot="planar5", decoder=GoalPointer)
    with pytest.raises(lasa.ArtifactError, match="over 3 goals, not 2"):
        lasa.load_checkpoint(path, decoder=GoalPointer, n_goals=2)
    # the step decodes with it: LA's human action is its phi, and z = 1 heads for the last cup
    control = task.robot.control
    state = np.broadcast_to(task.start, (2, 3)).copy()
    log_b = np.log(np.full((2, 3), 1.0 / 3.0))
    z = np.array([[1.0], [-1.0]])
    step = lasa.shared_autonomy_step(loaded, task, control, state, log_b, z, 0.0)
    np.testing.assert_array_equal(step.human_action, loaded.decode_numpy(z, state, np.exp(log_b)))
    speed = np.linalg.norm(step.human_action, axis=1)
    assert np.all((speed > 0.45 * control.action_scale) & (speed <= 0.5 * control.action_scale))  # gain 0.5
    s, lb = state, log_b
    for _ in range(200):
        step = lasa.shared_autonomy_step(loaded, task, control, s, lb, z, 0.0)
        s, lb = step.state, step.log_belief
    start, end = (np.linalg.norm(x - task.goals[[2, 0]], axis=1) for x in (state, s))
    assert np.all(end < 0.2 * start), (start, end)
    assert list(np.exp(lb).argmax(axis=1)) == [2, 0]


def test_a_decoder_class_of_the_script_being_run_is_refused_before_anything_is_written(toy_task, tmp_path):
    """A class defined in ``__main__`` would be recorded as ``__main__.Class``: no other process loads it."""
    in_main = type("GoalPointer", (GoalPointer,), {"__module__": "__main__"})  # as if defined in the script
    model = in_main(pointer_for(toy_task).config)
    with pytest.raises(lasa.ConfigError, match=r"GoalPointer is defined in __main__.*module of its own"):
        lasa.save_checkpoint(model, tmp_path / "pointer.pt")
    assert list(tmp_path.iterdir()) == []
