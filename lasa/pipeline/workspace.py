"""A notebook's workspace: one robot's task and units, the run's folders, its artifacts (by name)."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any, Generic, TypeVar

from lasa.base.config import ControlConfig, cap_setting, check_choice, set_threads
from lasa.base.paths import Paths
from lasa.method.dataset import Demonstrations, load_demonstrations
from lasa.method.decoder import LatentActionModel, load_checkpoint
from lasa.runtime import pin
from lasa.world.eating import STUDY_BELIEF_CAP, EatingTask, make_eating_task
from lasa.world.goals import GoalTask
from lasa.world.robot import Robot, load_robot
from lasa.world.task import CupTask, make_cup_task

EATING_ROBOTS = ("panda",)  # the robots the eating scene is built for
TaskT = TypeVar("TaskT", bound=GoalTask)


@dataclasses.dataclass(frozen=True)
class Workspace(Generic[TaskT]):
    """One robot (its MuJoCo scene), its cup or eating task, its control-loop units, the run's folders."""

    robot: Robot
    task: TaskT
    control: ControlConfig
    paths: Paths

    @staticmethod
    def open(
        robot: str,
        build_dir: str | os.PathLike[str] = "build",
        figures_dir: str | os.PathLike[str] = "figures",
    ) -> Workspace[CupTask]:
        """The cup task's workspace of ``robot``, its folders resolved (the figures' made)."""
        paths = _folders(build_dir, figures_dir)
        arm = load_robot(robot)
        return Workspace(arm, make_cup_task(arm), arm.control, paths)

    @staticmethod
    def eating(
        robot: str = "panda",
        build_dir: str | os.PathLike[str] = "build",
        figures_dir: str | os.PathLike[str] = "figures",
        belief_cap: float | str | None = STUDY_BELIEF_CAP,
    ) -> Workspace[EatingTask]:
        """:meth:`open` for the eating study: the robot with its fork, its task, the belief's cap ("none")."""
        check_choice("robot", robot, EATING_ROBOTS)
        paths = _folders(build_dir, figures_dir)
        task = make_eating_task()  # mink IK over every goal's tilts and strokes (once per process)
        control = dataclasses.replace(task.robot.control, belief_cap=cap_setting(belief_cap))
        return Workspace(task.robot, task, control, paths)

    @property
    def name(self) -> str:
        """The robot's name."""
        return self.robot.name

    def artifact(self, name: str, **fields: str) -> Path:
        """This robot's artifact ``name`` (:data:`lasa.base.paths.ARTIFACTS`), ``fields`` filling the rest."""
        return self.paths.artifact(name, self.name, **fields)

    def demonstrations(self) -> Demonstrations:
        """The dataset of notebook 01."""
        return load_demonstrations(
            self.artifact("demos"), robot=self.name, make_hint=Paths.make_hint("demos", self.name)
        )

    def decoder(self, name: str = "decoder", **fields: str) -> tuple[LatentActionModel, dict[str, Any]]:
        """A checkpoint (a decoder of :data:`lasa.base.paths.ARTIFACTS`, ``fields`` filling it), metadata."""
        return load_checkpoint(
            self.artifact(name, **fields), robot=self.name, make_hint=Paths.make_hint(name, self.name)
        )

    def sim_decoders(self) -> dict[str, LatentActionModel]:
        """The sims' pair (notebook 03): ``base`` (lambda = 0) and ``entropy``, differing only by the term."""
        return {"base": self.decoder("decoder_lambda0")[0], "entropy": self.decoder("decoder_entropy")[0]}


def _folders(build_dir: str | os.PathLike[str], figures_dir: str | os.PathLike[str]) -> Paths:
    """Pin the runtime, set torch's threads, resolve the run's folders (the figures' made)."""
    pin()
    set_threads()
    paths = Paths.of(build_dir, figures_dir)
    paths.figures.mkdir(parents=True, exist_ok=True)
    return paths
