r"""The latent-action model: a conditional autoencoder over (state, belief) contexts.

The encoder maps a demonstrated action in its context to a latent action,
:math:`z = \psi(s, a, b) \in [-1, 1]^d`, and the decoder maps it back,
:math:`a_h = \phi(z, s, b)` (Sec. III-A). Conditioning both on the belief b is what
lets the meaning of z change with the robot's confidence.

Two bounds make the model fit the control loop:

- z is squashed by ``tanh`` into [-1, 1]^d, so a joystick axis maps onto it directly;
- the decoder's output is squashed radially, :math:`\phi = \sigma_h \tanh(\|v\|)\, v / \|v\|`,
  so :math:`\|\phi\| < \sigma_h`, the bound that Eq. T4 assumes.

A checkpoint holds the state dict and the plain-dict config the model was built with;
:func:`load_checkpoint` loads it with ``torch.load(..., weights_only=True)`` and checks
that it was trained for the robot the caller expects.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np
import torch
from torch import nn

from lasa.config import check_range
from lasa.errors import ArtifactError, ConfigError
from lasa.io import atomic_path, require_file

__all__ = [
    "ActionDecoder",
    "DecoderConfig",
    "LatentActionModel",
    "save_checkpoint",
    "load_checkpoint",
]


@dataclasses.dataclass(frozen=True)
class DecoderConfig:
    """Architecture of the conditional autoencoder."""

    robot: str  # robot the model is trained for, e.g. "planar5"
    n_joints: int  # state and action dimension n
    n_goals: int  # number of goals G (belief dimension)
    z_dim: int = 1  # latent dimension d: 1 for the cup task (left/right on a joystick)
    hidden: int = 128  # width of every hidden layer
    depth: int = 3  # number of hidden layers in the encoder and in the decoder
    action_scale: float = 1.0  # sigma_h: bound on ||phi|| [rad/s]
    state_mean: tuple[float, ...] = ()  # input normalisation of s (from the data) [rad]
    state_std: tuple[float, ...] = ()  # ... and its spread [rad]

    def __post_init__(self) -> None:
        for name in ("n_joints", "n_goals", "z_dim", "hidden", "depth"):
            value = getattr(self, name)
            if int(value) != value or value < 1:
                raise ConfigError(f"{name} must be a positive integer, got {value!r}")
        if self.n_goals < 2:
            raise ConfigError(f"n_goals must be >= 2, got {self.n_goals}")
        check_range("action_scale", self.action_scale, 0.0, low_open=True)
        for name in ("state_mean", "state_std"):
            value = getattr(self, name)
            if value and len(value) != self.n_joints:
                raise ConfigError(f"{name} must have n_joints={self.n_joints} entries")
        if self.state_std and min(self.state_std) <= 0:
            raise ConfigError("state_std entries must be positive")


@runtime_checkable
class ActionDecoder(Protocol):
    """What Algorithm 1 needs of a decoder: phi(z, s, b) on numpy arrays, and its shape.

    :class:`LatentActionModel` is one; an extension that changes what the decoder sees
    (the context map of :mod:`lasa.newgoals`) wraps one, so the rollout never needs to
    know about it.
    """

    @property
    def robot(self) -> str:
        """The robot whose joint space phi acts in."""
        ...

    @property
    def n_goals(self) -> int:
        """G: the length of the belief phi reads."""
        ...

    @property
    def z_dim(self) -> int:
        """d: the joystick axes."""
        ...

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        """phi(z, s, b), broadcast over the leading dimensions of z (..., d), s (..., n), b (..., G)."""
        ...


def _mlp(n_in: int, n_out: int, hidden: int, depth: int) -> nn.Sequential:
    layers: list[nn.Module] = []
    width = n_in
    for _ in range(depth):
        layers += [nn.Linear(width, hidden), nn.Tanh()]
        width = hidden
    layers.append(nn.Linear(width, n_out))
    return nn.Sequential(*layers)


class LatentActionModel(nn.Module):
    """Encoder psi(s, a, b) -> z and decoder phi(z, s, b) -> a_h.

    Inputs are float tensors with any leading batch shape: s and a of size n, b of size
    G, z of size d. The decoder clamps z to [-1, 1]; it does not check finiteness
    (the control loop does, see :func:`lasa.control.sanitize`).
    """

    state_mean: torch.Tensor
    state_std: torch.Tensor

    def __init__(self, config: DecoderConfig) -> None:
        super().__init__()
        self.config = config
        n, g, d = config.n_joints, config.n_goals, config.z_dim
        mean = torch.tensor(config.state_mean or [0.0] * n, dtype=torch.float32)
        std = torch.tensor(config.state_std or [1.0] * n, dtype=torch.float32)
        self.register_buffer("state_mean", mean)
        self.register_buffer("state_std", std)
        self.encoder = _mlp(2 * n + g, d, config.hidden, config.depth)
        self.decoder = _mlp(d + n + g, n, config.hidden, config.depth)

    @property
    def robot(self) -> str:
        """The robot the model was trained for."""
        return self.config.robot

    @property
    def n_goals(self) -> int:
        """G: the length of the belief the model reads."""
        return self.config.n_goals

    @property
    def z_dim(self) -> int:
        """d: the latent (joystick) dimension."""
        return self.config.z_dim

    def _context(self, s: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
        return torch.cat([(s - self.state_mean) / self.state_std, b], dim=-1)

    def encode(self, s: torch.Tensor, a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
        """Latent actions z in (-1, 1)^d for actions a in contexts (s, b)."""
        a_n = a / self.config.action_scale
        return torch.tanh(self.encoder(torch.cat([self._context(s, b), a_n], dim=-1)))

    def decode(self, z: torch.Tensor, s: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
        """phi(z, s, b): joint velocities with norm below sigma_h = action_scale."""
        z = z.clamp(-1.0, 1.0)
        v = self.decoder(torch.cat([z, self._context(s, b)], dim=-1))
        norm = v.norm(dim=-1, keepdim=True).clamp_min(1e-8)
        return self.config.action_scale * torch.tanh(norm) * v / norm

    def forward(self, s: torch.Tensor, a: torch.Tensor, b: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Encode then decode: returns (z, reconstructed action)."""
        z = self.encode(s, a, b)
        return z, self.decode(z, s, b)

    @torch.inference_mode()
    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        """phi(z, s, b) on numpy arrays (broadcast over leading dims), as float64."""
        zt, st, bt = (torch.as_tensor(x, dtype=torch.float32) for x in (z, s, b))
        shape = torch.broadcast_shapes(zt.shape[:-1], st.shape[:-1], bt.shape[:-1])
        zt = zt.expand(*shape, zt.shape[-1])
        st = st.expand(*shape, st.shape[-1])
        bt = bt.expand(*shape, bt.shape[-1])
        return self.decode(zt, st, bt).double().numpy()


def save_checkpoint(model: LatentActionModel, path: str | os.PathLike[str], **extra: Any) -> Path:
    """Atomically save the model's state dict, its config and ``extra`` metadata.

    ``extra`` values must be plain Python data (numbers, strings, lists, dicts) so the
    checkpoint loads with ``weights_only=True``; the training config goes here.
    """
    payload = {
        "state_dict": model.state_dict(),
        "config": dataclasses.asdict(model.config),
        "extra": extra,
    }
    with atomic_path(path) as tmp:
        torch.save(payload, tmp)
    return Path(path)


def load_checkpoint(
    path: str | os.PathLike[str],
    robot: str | None = None,
    make_hint: str = "make figures (notebook 02_decoder_training)",
) -> tuple[LatentActionModel, dict[str, Any]]:
    """Load a model saved by :func:`save_checkpoint`.

    Args:
        path: Checkpoint file.
        robot: If given, the robot the caller expects; a mismatch is an error.
        make_hint: Command that makes the checkpoint, for the error message.

    Returns:
        The model in eval mode, and the checkpoint's ``extra`` metadata.

    Raises:
        ArtifactError: if the file is missing, corrupt, or for another robot.
    """
    path = require_file(path, make_hint)
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
        values: dict[str, Any] = {
            k: tuple(v) if isinstance(v, list) else v for k, v in payload["config"].items()
        }
        config = DecoderConfig(**values)
        model = LatentActionModel(config)
        model.load_state_dict(payload["state_dict"])
    except Exception as exc:
        # Name the failure, not torch's message: for a file it cannot unpickle safely, torch
        # suggests loading with weights_only=False, which would run arbitrary code from the file.
        raise ArtifactError(
            f"{path} is not a valid lasa checkpoint (loading it raised {type(exc).__name__}). "
            f"Delete it and re-make it with: {make_hint}"
        ) from None
    if robot is not None and config.robot != robot:
        raise ArtifactError(
            f"{path} was trained for robot {config.robot!r}, not {robot!r}. "
            f"Use the checkpoint for {robot!r} or re-make it with: {make_hint}"
        )
    model.eval()
    return model, dict(payload.get("extra", {}))
