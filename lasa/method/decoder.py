r"""The latent-action model: a conditional autoencoder over (state, belief) contexts (Sec. III-A).

:math:`z = \psi(s, a, b) \in [-1, 1]^d`, :math:`a_h = \phi(z, s, b) = \sigma_h \tanh(\|v\|)\, v /
\|v\|`, so :math:`\|\phi\| < \sigma_h` (Eq. T4). Checkpoints (state dict and config) load with
``weights_only=True``. Why the bounds: ``docs/method-notes.md``.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np
import torch
from torch import nn
from typing_extensions import TypeVar

from lasa.base.config import AtLeastTwo, Positive, PositiveInt, validate
from lasa.base.errors import CheckpointError, ConfigError
from lasa.base.io import atomic_path, require_file
from lasa.method.inference import inference_plan


@dataclasses.dataclass(frozen=True)
class DecoderConfig:
    """Architecture of the conditional autoencoder."""

    robot: str  # robot the model is trained for, e.g. "planar5"
    n_joints: PositiveInt  # state and action dimension n
    n_goals: AtLeastTwo  # number of goals G (belief dimension)
    z_dim: PositiveInt = 1  # latent dimension d: 1 for the cup task (left/right on a joystick)
    hidden: PositiveInt = 128  # width of every hidden layer
    depth: PositiveInt = 3  # number of hidden layers in the encoder and in the decoder
    action_scale: Positive = 1.0  # sigma_h: bound on ||phi|| [rad/s]
    state_mean: tuple[float, ...] = ()  # input normalisation of s (from the data) [rad]
    state_std: tuple[Positive, ...] = ()  # ... and its spread [rad]

    def __post_init__(self) -> None:
        validate(self)
        for name in ("state_mean", "state_std"):
            value = getattr(self, name)
            if value and len(value) != self.n_joints:
                raise ConfigError(f"{name} must have n_joints={self.n_joints} entries")


@runtime_checkable
class ActionDecoder(Protocol):
    """What Algorithm 1 needs of a decoder (e.g. :class:`LatentActionModel`): phi(z, s, b) on numpy."""

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
    widths = [n_in] + [hidden] * depth
    layers = [m for w in widths[:-1] for m in (nn.Linear(w, hidden), nn.Tanh())]
    return nn.Sequential(*layers, nn.Linear(widths[-1], n_out))


class LatentActionModel(nn.Module):
    """Encoder psi(s, a, b) -> z and decoder phi(z, s, b) -> a_h (z clamped to [-1, 1]), batched."""

    config_class: ClassVar[type[DecoderConfig]] = DecoderConfig  # what a checkpoint's config builds
    state_mean: torch.Tensor
    state_std: torch.Tensor

    def __init__(self, config: DecoderConfig) -> None:
        super().__init__()
        self.config = config
        self.robot: str = config.robot  # the robot the model was trained for
        self.n_goals: int = config.n_goals  # G, the length of the belief it reads
        self.z_dim: int = config.z_dim  # d, the latent (joystick) dimension
        n, g, d = config.n_joints, config.n_goals, config.z_dim
        mean = torch.tensor(config.state_mean or [0.0] * n, dtype=torch.float32)
        std = torch.tensor(config.state_std or [1.0] * n, dtype=torch.float32)
        self.register_buffer("state_mean", mean)
        self.register_buffer("state_std", std)
        self.encoder = _mlp(2 * n + g, d, config.hidden, config.depth)
        self.decoder = _mlp(d + n + g, n, config.hidden, config.depth)

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

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        """phi(z, s, b) on numpy arrays (broadcast), float64: :meth:`decode` to float32 rounding by
        :mod:`lasa.method.inference` (a subclass's or patched ``decode`` runs itself)."""
        if getattr(self.decode, "__func__", None) is not _DECODE:
            return self._decode_numpy_reference(z, s, b)  # a subclass's or a patched decode
        return inference_plan(self).decode(z, s, b)

    @torch.inference_mode()
    def _decode_numpy_reference(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        """decode_numpy through :meth:`decode` itself: float32 inputs expanded to the batch."""
        zt, st, bt = (torch.as_tensor(x, dtype=torch.float32) for x in (z, s, b))
        shape = torch.broadcast_shapes(zt.shape[:-1], st.shape[:-1], bt.shape[:-1])
        zt, st, bt = (x.expand(*shape, x.shape[-1]) for x in (zt, st, bt))
        return self.decode(zt, st, bt).double().numpy()


_DECODE = LatentActionModel.decode  # the decode that the inference plan implements

M = TypeVar("M", bound=nn.Module, default=LatentActionModel)  # a decoder class


def _class_name(cls: type) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


def save_checkpoint(model: nn.Module, path: str | os.PathLike[str], **extra: Any) -> Path:
    """Atomically save the model's state dict, its dataclass ``config`` and plain-data ``extra``;
    another class than :class:`LatentActionModel` is recorded as ``module.Class`` (not ``__main__``)."""
    config = getattr(model, "config", None)
    if not dataclasses.is_dataclass(config) or isinstance(config, type):
        raise ConfigError(
            f"{type(model).__name__} has no dataclass `config`: a checkpoint saves the config "
            "the decoder is built from"
        )
    payload: dict[str, Any] = dict(
        state_dict=model.state_dict(), config=dataclasses.asdict(config), extra=extra
    )
    if type(model) is not LatentActionModel:
        cls = type(model)
        if cls.__module__ == "__main__":
            raise ConfigError(
                f"{cls.__qualname__} is defined in __main__ (the script or notebook being run): its "
                f"checkpoint would name the class __main__.{cls.__qualname__}, which no other process "
                f"can import to load it. Define {cls.__qualname__} in a module of its own (e.g. "
                "my_decoder.py) and import it from the script (docs/extending.md, 'A decoder')"
            )
        payload["decoder"] = _class_name(cls)
    with atomic_path(path) as tmp:
        torch.save(payload, tmp)
    return Path(path)


def load_checkpoint(
    path: str | os.PathLike[str],
    robot: str | None = None,
    make_hint: str = "make figures (notebook 02_decoder_training)",
    *,
    decoder: type[M] = LatentActionModel,  # type: ignore[assignment]  # M's default (PEP 696)
    n_goals: int | None = None,
) -> tuple[M, dict[str, Any]]:
    """A model saved by :func:`save_checkpoint` (eval mode) and its ``extra``, built as
    ``decoder(decoder.config_class(**config))`` and checked against ``robot`` and ``n_goals`` if given:
    ArtifactError if the file is missing, CheckpointError if it is corrupt or of another decoder class,
    robot or number of goals, ConfigError if ``decoder`` has no ``config_class`` or is no ActionDecoder."""
    config_class = getattr(decoder, "config_class", None)
    if not isinstance(config_class, type) or not dataclasses.is_dataclass(config_class):
        raise ConfigError(
            f"decoder class {decoder.__name__} needs a `config_class` attribute: the dataclass its "
            "constructor takes"
        )
    path = require_file(path, make_hint)
    try:  # one error for whatever fails, without torch's advice to load the file unsafely
        payload = torch.load(path, map_location="cpu", weights_only=True)
        saved_as = str(payload.get("decoder", _class_name(LatentActionModel)))
        values = {k: tuple(v) if isinstance(v, list) else v for k, v in payload["config"].items()}
        if saved_as == _class_name(decoder):
            model = decoder(config_class(**values))
            model.load_state_dict(payload["state_dict"])
    except Exception as exc:
        raise CheckpointError(
            f"{path} is not a valid lasa checkpoint (loading it raised {type(exc).__name__}). "
            f"Delete it and re-make it with: {make_hint}"
        ) from None
    if saved_as != _class_name(decoder):
        raise CheckpointError(
            f"{path} holds a {saved_as} decoder, not a {_class_name(decoder)}: load it with "
            f"load_checkpoint(..., decoder={saved_as.rsplit('.', 1)[-1]})"
        )
    if not isinstance(model, ActionDecoder):
        raise ConfigError(
            f"decoder class {decoder.__name__} does not follow lasa.method.decoder.ActionDecoder"
        )
    if robot is not None and model.robot != robot:
        raise CheckpointError(
            f"{path} was trained for robot {model.robot!r}, not {robot!r}. "
            f"Use the checkpoint for {robot!r} or re-make it with: {make_hint}"
        )
    if n_goals is not None and model.n_goals != n_goals:
        raise CheckpointError(
            f"{path} reads a belief over {model.n_goals} goals, not {n_goals}. "
            f"Use the checkpoint for that task or re-make it with: {make_hint}"
        )
    model.eval()
    return model, dict(payload.get("extra", {}))
