"""A notebook's workspace: the cup task's (notebooks 01-09) and the eating study's (notebooks 10-11)."""

import pytest

from lasa.base.errors import ArtifactError, ConfigError
from lasa.pipeline.workspace import Workspace
from lasa.world.eating import EatingTask
from lasa.world.task import CupTask


def test_the_eating_workspace_loads_the_eating_scene_and_names_its_artifacts(tmp_path):
    ws = Workspace.eating("panda", tmp_path / "build", tmp_path / "figures")
    assert isinstance(ws.task, EatingTask) and ws.robot is ws.task.robot and ws.name == "panda"
    assert ws.control == ws.task.robot.control and (tmp_path / "figures").is_dir()
    path = ws.artifact("eating_segmentation_decoder", segmentation="transfers")
    assert path == tmp_path / "build" / "models" / "eating_decoder_panda_transfers.pt"
    with pytest.raises(ArtifactError, match="10_eating_task"):
        ws.decoder("eating_segmentation_decoder", segmentation="transfers")
    with pytest.raises(ConfigError, match="robot"):
        Workspace.eating("planar5", tmp_path / "build", tmp_path / "figures")


def test_the_cup_workspace_is_unchanged(tmp_path):
    ws = Workspace.open("planar5", tmp_path / "build", tmp_path / "figures")
    assert isinstance(ws.task, CupTask) and ws.name == "planar5"
    assert ws.artifact("decoder") == tmp_path / "build" / "models" / "decoder_planar5.pt"
    with pytest.raises(ArtifactError, match="02_decoder_training"):
        ws.decoder()
