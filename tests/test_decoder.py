"""The conditional autoencoder: z range, action bound, checkpoints."""

import numpy as np
import pytest
import torch

from lasa.decoder import DecoderConfig, LatentActionModel, load_checkpoint, save_checkpoint
from lasa.errors import ArtifactError, ConfigError


def make_model(**kw) -> LatentActionModel:
    torch.manual_seed(0)
    cfg = dict(robot="planar5", n_joints=5, n_goals=2, hidden=16, depth=2, action_scale=0.5)
    cfg.update(kw)
    return LatentActionModel(DecoderConfig(**cfg))


def test_latent_range_and_action_bound_hold_for_any_input():
    model = make_model()
    gen = torch.Generator().manual_seed(0)
    s = 100 * torch.randn(4096, 5, generator=gen)
    a = 1e4 * torch.randn(4096, 5, generator=gen)
    b = torch.softmax(torch.randn(4096, 2, generator=gen), -1)
    with torch.no_grad():
        z = model.encode(s, a, b)
        assert z.min() >= -1 and z.max() <= 1
        out = model.decode(1e6 * torch.randn(4096, 1, generator=gen), s, b)
    assert out.norm(dim=-1).max() <= 0.5 + 1e-6


def test_decode_clamps_z():
    model = make_model()
    s, b = torch.zeros(1, 5), torch.tensor([[0.5, 0.5]])
    with torch.no_grad():
        assert torch.equal(
            model.decode(torch.tensor([[7.0]]), s, b), model.decode(torch.tensor([[1.0]]), s, b)
        )


def test_decode_numpy_broadcasts():
    model = make_model()
    out = model.decode_numpy(np.linspace(-1, 1, 7)[:, None], np.zeros(5), np.array([0.5, 0.5]))
    assert out.shape == (7, 5) and out.dtype == np.float64


def test_checkpoint_round_trip_carries_config(tmp_path):
    model = make_model()
    path = save_checkpoint(model, tmp_path / "m.pt", train={"steps": 3}, entropy_lambda=0.0)
    loaded, extra = load_checkpoint(path, robot="planar5")
    assert loaded.config == model.config
    assert extra == {"train": {"steps": 3}, "entropy_lambda": 0.0}
    for key, value in model.state_dict().items():
        assert torch.equal(value, loaded.state_dict()[key])


def test_checkpoint_for_another_robot_is_refused(tmp_path):
    path = save_checkpoint(make_model(), tmp_path / "m.pt")
    with pytest.raises(ArtifactError, match="trained for robot 'planar5', not 'panda'"):
        load_checkpoint(path, robot="panda")


def test_missing_and_corrupt_checkpoints_name_the_fix(tmp_path):
    with pytest.raises(ArtifactError, match="make figures"):
        load_checkpoint(tmp_path / "nope.pt")
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(ArtifactError, match="not a valid lasa checkpoint"):
        load_checkpoint(bad)


def test_an_unsafe_checkpoint_is_refused_without_torchs_unsafe_advice(tmp_path):
    """torch advises weights_only=False for a file it cannot load safely; lasa never repeats it."""
    import pathlib

    import torch

    unsafe = tmp_path / "unsafe.pt"
    torch.save({"config": pathlib.Path("x"), "state_dict": {}}, unsafe)  # a pickled object, not data
    with pytest.raises(ArtifactError, match="not a valid lasa checkpoint") as info:
        load_checkpoint(unsafe)
    assert "weights_only" not in str(info.value) and info.value.__cause__ is None


@pytest.mark.parametrize(
    "field,value", [("n_goals", 1), ("hidden", 0), ("action_scale", -1.0), ("z_dim", 1.5)]
)
def test_bad_architecture_is_a_clear_error(field, value):
    with pytest.raises(ConfigError, match=field):
        DecoderConfig(**{"robot": "planar5", "n_joints": 5, "n_goals": 2, field: value})
