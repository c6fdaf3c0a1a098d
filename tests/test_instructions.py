"""The words a participant reads match the picture they see: the camera's projection (hand-computed
points), each phase's instruction naming the side on which its bowl appears, grammatical texts, the
goals' display names against the scene, and the fork in view throughout each task."""

import math

import mujoco
import numpy as np
import pytest

from lasa.base.errors import ConfigError
from lasa.live.web.app import ASPECT
from lasa.world.camera import camera_pose, project
from lasa.world.eating import GOALS, TASKS, load_eating_robot, make_eating_task, waypoints
from lasa.world.fork import tip_frames
from lasa.world.instructions import DISPLAY_NAMES, PICTURE_CAMERA, instruction

SIDE_WORDS = ("left", "middle", "right")


@pytest.fixture(scope="module")
def eating():
    return load_eating_robot()


def picture_x(robot, points):
    """Each point's horizontal place in the picture, up to a monotone map: the tangent of its angle right
    of the camera's axis, from the model's own camera fields (not lasa.world.camera)."""
    model = robot.model
    cam = model.camera(PICTURE_CAMERA).id
    assert model.cam_bodyid[cam] == 0 and model.cam_mode[cam] == 0  # fixed in the world: cam_*0 hold
    right, back = model.cam_mat0[cam].reshape(3, 3)[:, 0], model.cam_mat0[cam].reshape(3, 3)[:, 2]
    rel = points - model.cam_pos0[cam]
    return (rel @ right) / -(rel @ back)


def test_the_cameras_own_axis_lands_at_the_centre_and_its_edges_at_the_pictures(eating):
    """Hand-computed: the point one metre along the view axis is at (0.5, 0.5); tilted up by half the
    vertical field of view, at the top edge's middle (0.5, 0); right by the horizontal one's half (its
    tangent: aspect * tan(fovy / 2)), at the right edge's middle (1, 0.5); behind the camera, an error."""
    position, rotation = camera_pose(eating, PICTURE_CAMERA)
    right, up, back = rotation.T
    assert math.isclose(float(eating.model.cam_fovy[eating.model.camera(PICTURE_CAMERA).id]), 50.0)
    tan = math.tan(math.radians(25.0))
    points = np.stack([position - back, position - back + tan * up, position - back + ASPECT * tan * right])
    np.testing.assert_allclose(
        project(eating, points, PICTURE_CAMERA, ASPECT), [[0.5, 0.5], [0.5, 0.0], [1.0, 0.5]], atol=1e-12
    )
    # the aspect ratio moves x only: the right edge at aspect 4/3 is 2/3 of the half-width out at aspect 2
    np.testing.assert_allclose(
        project(eating, points[2:], PICTURE_CAMERA, 2.0), [[0.5 + 0.5 * ASPECT / 2.0, 0.5]], atol=1e-12
    )
    with pytest.raises(ConfigError, match="in front of it"):
        project(eating, (position + back)[None], PICTURE_CAMERA, ASPECT)
    with pytest.raises(ConfigError, match="no camera 'front'"):
        project(eating, points, "front", ASPECT)
    with pytest.raises(ConfigError, match="aspect"):
        project(eating, points, PICTURE_CAMERA, 0.0)
    with pytest.raises(ConfigError, match=r"shape \(N, 3\)"):
        project(eating, position, PICTURE_CAMERA, ASPECT)


def test_every_phase_names_the_side_its_bowl_appears_on_in_the_picture(eating):
    """A phase at a bowl says "left" iff that bowl's projected x is the smallest of the three bowls',
    "right" iff the largest, "middle" iff neither; a phase at the plate names no side. In the study's
    camera the rice (the scene's bowl_left, the robot's left) is the right-most bowl: the old texts'
    "the rice (left bowl)" sent participants the wrong way."""
    x = dict(zip(GOALS, picture_x(eating, eating.goal_positions()), strict=True))
    bowls = [g for g in GOALS if g != "plate"]
    assert max(bowls, key=x.get) == "rice" and min(bowls, key=x.get) == "icing"
    for task, phases in TASKS.items():
        for i, phase in enumerate(phases):
            words = set(instruction(task, i).replace(",", " ").replace(":", " ").split())
            named = {w for w in SIDE_WORDS if w in words}
            if phase.goal == "plate":
                assert named == set() and instruction(task, i).endswith(" on the plate"), (task, i)
                continue
            others = [x[b] for b in bowls if b != phase.goal]
            expected = (
                "left"
                if x[phase.goal] < min(others)
                else "right"
                if x[phase.goal] > max(others)
                else "middle"
            )
            assert named == {expected} and f"the {expected} bowl" in instruction(task, i), (task, i)


def test_the_texts_are_grammatical_and_name_the_food(eating):
    """Each text is "<Task>, step k of n: <action>", a verb first, the food named, none of the old forms
    (" at the plate", "reach at", "k/n"); the done text; a phase the task lacks is an error."""
    verbs = {"move", "cut", "stab", "scoop", "dip", "put"}
    assert instruction("Dessert", 1) == "Dessert, step 2 of 4: scoop some icing from the left bowl"
    assert instruction("Entree", 0) == "Entree, step 1 of 4: move the fork to the tofu in the middle bowl"
    for task, phases in TASKS.items():
        for i, phase in enumerate(phases):
            text = instruction(task, i)
            head, action = text.split(": ")
            assert head == f"{task}, step {i + 1} of {len(phases)}"
            assert action.split()[0] in verbs and action == action.strip() and "  " not in action, text
            assert " at the " not in text and "reach" not in text and "/" not in text, text
            food = {"middle": "tofu" if task == "Entree" else "marshmallow"}.get(phase.goal, phase.goal)
            assert food in action, text
        assert instruction(task, None) == f"{task}: all {len(phases)} steps done"
        with pytest.raises(ConfigError, match="phases 0 to 3"):
            instruction(task, len(phases))
    with pytest.raises(ConfigError, match="task"):
        instruction("Soup", 0)


def test_the_display_names_name_what_the_scene_puts_at_each_goal(eating):
    """Every food geom in a goal's body (eating.xml; ``marshmallow_2`` is a marshmallow) is in that goal's
    display name, which is all a participant reads for it (the label over the picture)."""
    model = eating.model
    assert set(DISPLAY_NAMES) == set(GOALS)
    for goal, site in zip(GOALS, eating.spec.goal_sites, strict=True):
        body = model.site(site).bodyid[0]
        geoms = [model.geom(k).name for k in range(model.ngeom) if model.geom_bodyid[k] == body]
        foods = {name.rsplit("_", 1)[0] for name in geoms if not name.startswith("bowl")}
        assert foods and all(food in DISPLAY_NAMES[goal] for food in foods), (goal, foods)
    assert "middle" not in DISPLAY_NAMES.values()


def test_the_fork_stays_in_the_picture_throughout_each_task(eating):
    """The fork's tip, along each task's scripted path (home, then a straight joint-space line to each
    waypoint's pose in turn) and at every solved stroke pose of every goal, tilt and depth, stays inside
    the page's picture (its aspect ratio) with a tenth of it to spare on every side."""
    task = make_eating_task()
    data = mujoco.MjData(eating.model)
    poses = [task.strokes.reshape(-1, eating.n_joints)]
    for name in TASKS:
        stops = [task.start] + [task.pose(w.goal, w.theta, w.depth) for w in waypoints(name)]
        s = np.linspace(0.0, 1.0, 21)[:, None]
        poses += [(1.0 - s) * a + s * b for a, b in zip(stops[:-1], stops[1:], strict=True)]
    where = project(eating, tip_frames(eating, data, np.concatenate(poses))[0], PICTURE_CAMERA, ASPECT)
    assert where.min() > 0.1 and where.max() < 0.9, (where.min(axis=0), where.max(axis=0))
