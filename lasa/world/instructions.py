"""The words a participant reads in the eating tasks: each phase's instruction and each goal's name over
the picture. A bowl is named by its food and by where it appears in the participant's picture (camera
:data:`PICTURE_CAMERA`): left, middle or right among the three bowls, from the projection
(:func:`lasa.world.camera.project`), never typed, so the words follow the camera. The scene's own names
(``bowl_left``, ...) are the robot's left and right; the camera faces the robot, so they are mirrored."""

from __future__ import annotations

import functools

import mujoco
import numpy as np

from lasa.base.config import check_choice
from lasa.base.errors import ConfigError
from lasa.world.camera import project
from lasa.world.eating import EATING, GOALS, TASK_NAMES, TASKS, load_eating_robot

PICTURE_CAMERA = EATING.camera  # the camera a participant sees: the web page's and the viewer's
PLATE = "plate"  # the goal that is not a bowl
SIDES = ("left", "middle", "right")  # the bowls' places in the picture, left to right

# what a participant reads for each goal (GOALS stay the logs' and the analysis' names): what is in
# each bowl (assets/panda/eating.xml) and the plate
DISPLAY_NAMES = {"rice": "rice", "middle": "tofu, marshmallows", "icing": "icing", PLATE: "plate"}

# what the fork takes from the middle bowl in each task, as first named and as then carried
PIECES = {"Entree": ("the tofu", "the tofu"), "Dessert": ("a marshmallow", "the marshmallow")}

# a phase's action, by its preference (None: the reach), from its piece, the goal's food and place
_ACTIONS: dict[str | None, str] = {
    None: "move the fork to {piece} in {place}",
    "cut": "cut {piece} in {place}",
    "stab": "stab {piece} in {place}",
    "scoop": "scoop some {food} from {place}",
    "dip": "dip it in the {food} in {place}",
    "place": "put {carried} on {place}",
}


@functools.cache
def bowl_sides(camera: str = PICTURE_CAMERA) -> dict[str, str]:
    """Each bowl's place in ``camera``'s picture: {goal: "left" | "middle" | "right"}, by its food
    surface's projected x (the order does not depend on the picture's aspect ratio)."""
    robot = load_eating_robot()
    bowls = [g for g in GOALS if g != PLATE]
    if len(bowls) != len(SIDES):
        raise ConfigError(f"the eating scene must have {len(SIDES)} bowls, has {len(bowls)}")
    data = mujoco.MjData(robot.model)  # its own: the shared robot's data is left to its users
    mujoco.mj_kinematics(robot.model, data)
    surfaces = np.stack([data.site(robot.spec.goal_sites[GOALS.index(b)]).xpos for b in bowls])
    x = project(robot, surfaces, camera, aspect=1.0)[:, 0]
    return {bowls[i]: side for i, side in zip(np.argsort(x), SIDES, strict=True)}


def place(goal: str) -> str:
    """Where ``goal`` is, as the participant sees it: "the plate", or e.g. "the left bowl"."""
    check_choice("goal", goal, GOALS)
    return f"the {PLATE}" if goal == PLATE else f"the {bowl_sides()[goal]} bowl"


def instruction(task: str, phase: int | None) -> str:
    """What a participant is asked to do in ``phase`` of ``task`` (None: the task is done), e.g.
    "Dessert, step 2 of 4: scoop some icing from the left bowl".

    Raises:
        ConfigError: An unknown task, or a phase it does not have.
    """
    check_choice("task", task, TASK_NAMES)
    phases = TASKS[task]
    if phase is None:
        return f"{task}: all {len(phases)} steps done"
    if not 0 <= phase < len(phases):
        raise ConfigError(f"{task} has phases 0 to {len(phases) - 1}, not {phase}")
    step = phases[phase]
    piece, carried = PIECES[task]
    action = _ACTIONS[step.preference].format(
        piece=piece, carried=carried, food=DISPLAY_NAMES[step.goal], place=place(step.goal)
    )
    return f"{task}, step {phase + 1} of {len(phases)}: {action}"
