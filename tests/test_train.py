"""Training: the loss falls, the model is deterministic, bad settings fail clearly."""

import dataclasses

import pytest
import torch

from lasa.base.errors import ConfigError
from lasa.method.train import TrainConfig, reconstruction_error, train_decoder
from tests.conftest import SMALL_TRAIN


def test_training_reduces_reconstruction_error(demos, task):
    clean = demos.clean()
    data = (clean.states, clean.actions, clean.beliefs)
    untrained, _ = train_decoder(
        demos, task.robot.control, dataclasses.replace(SMALL_TRAIN, steps=1), progress=False
    )
    trained, history = train_decoder(demos, task.robot.control, SMALL_TRAIN, progress=False)
    assert reconstruction_error(trained, *data) < 0.2 * reconstruction_error(untrained, *data)
    assert list(history.columns) == ["step", "train_loss", "val_error", "seconds"]


def test_same_seed_same_weights(demos, task):
    cfg = dataclasses.replace(SMALL_TRAIN, steps=20)
    a, _ = train_decoder(demos, task.robot.control, cfg, progress=False)
    b, _ = train_decoder(demos, task.robot.control, cfg, progress=False)
    for key, value in a.state_dict().items():
        assert torch.equal(value, b.state_dict()[key])


def test_extra_loss_is_added_and_reaches_the_decoder(demos, task):
    calls = []

    def extra(model, s, b):
        calls.append(len(s))
        z = torch.zeros(len(s), 1)
        return model.decode(z, s, b).pow(2).sum(-1).mean()

    cfg = dataclasses.replace(SMALL_TRAIN, steps=5)
    train_decoder(demos, task.robot.control, cfg, extra_loss=extra, progress=False)
    assert calls == [cfg.batch_size] * 5


def test_model_carries_robot_and_bound(model, task):
    assert model.config.robot == "planar5"
    assert model.config.action_scale == task.robot.control.action_scale


@pytest.mark.parametrize("field,value", [("steps", 0), ("lr", 0.0), ("holdout", 0.9), ("z_noise", -1)])
def test_bad_config_is_a_clear_error(field, value):
    with pytest.raises(ConfigError, match=field):
        TrainConfig(**{field: value})


def test_too_little_data_is_a_clear_error(demos, task):
    with pytest.raises(ConfigError, match="batch_size"):
        train_decoder(
            demos, task.robot.control, dataclasses.replace(SMALL_TRAIN, batch_size=10**6), progress=False
        )
