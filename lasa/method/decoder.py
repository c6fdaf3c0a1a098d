r"""The latent-action model: a conditional autoencoder over (state, belief) contexts (Sec. III-A),
:math:`z = \psi(s, a, b) \in [-1, 1]^d`, :math:`a_h = \phi(z, s, b) = \sigma_h \tanh(\|v\|)\, v / \|v\|`,
so :math:`\|\phi\| < \sigma_h` (Eq. T4; why: ``docs/method-notes.md``); its numpy forward, an inference
plan (weights refolded once, chunked into per-thread buffers); checkpoints (``weights_only=True``).
"""

from __future__ import annotations

import dataclasses
import math
import os
import threading
import weakref
from pathlib import Path
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np
import torch
from torch import nn
from typing_extensions import TypeVar

from lasa.base.config import AtLeastTwo, Positive, PositiveInt, validate
from lasa.base.errors import CheckpointError, ConfigError
from lasa.base.io import atomic_path, require_file


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

    @property
    def n_goals(self) -> int:
        """G: the length of the belief phi reads."""

    @property
    def z_dim(self) -> int:
        """d: the joystick axes."""

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        """phi(z, s, b), broadcast over the leading dimensions of z (..., d), s (..., n), b (..., G)."""


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
        self.register_buffer("state_mean", torch.tensor(config.state_mean or [0.0] * n, dtype=torch.float32))
        self.register_buffer("state_std", torch.tensor(config.state_std or [1.0] * n, dtype=torch.float32))
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
        v = self.decoder(torch.cat([z.clamp(-1.0, 1.0), self._context(s, b)], dim=-1))
        norm = v.norm(dim=-1, keepdim=True).clamp_min(1e-8)
        return self.config.action_scale * torch.tanh(norm) * v / norm

    def forward(self, s: torch.Tensor, a: torch.Tensor, b: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Encode then decode: returns (z, reconstructed action)."""
        z = self.encode(s, a, b)
        return z, self.decode(z, s, b)

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        """phi(z, s, b) on numpy arrays (broadcast), float64: :meth:`decode` to float32 rounding by
        :func:`inference_plan` (a subclass's or patched ``decode`` runs itself)."""
        if getattr(self.decode, "__func__", None) is _DECODE:
            return inference_plan(self).decode(z, s, b)
        with torch.inference_mode():  # a subclass's or a patched decode itself: float32, expanded
            zt, st, bt = (torch.as_tensor(x, dtype=torch.float32) for x in (z, s, b))
            shape = torch.broadcast_shapes(zt.shape[:-1], st.shape[:-1], bt.shape[:-1])
            zt, st, bt = (x.expand(*shape, x.shape[-1]) for x in (zt, st, bt))
            return self.decode(zt, st, bt).double().numpy()


_DECODE = LatentActionModel.decode  # the decode that the inference plan implements
_CHUNK_ROWS = 1024  # rows per chunk: two 1024 x 128 float32 buffers stay in a core's L2 cache


def _weight_tensors(model: LatentActionModel) -> list[torch.Tensor]:
    """The decoder's parameters and the state normalisation, without nn.Module's (slow) traversal."""
    params = [layer._parameters.values() for layer in model.decoder._modules.values() if layer is not None]
    return [t for values in params for t in values if t is not None] + [model.state_mean, model.state_std]


_KEEP_ROWS = 4 * _CHUNK_ROWS  # largest chunk whose buffers a thread keeps between calls


class _Buffers(threading.local):
    """One thread's activation buffers and their views, reused across chunks and calls."""

    def __init__(self) -> None:
        self.rows = 0
        self.a = torch.empty(0)
        self.b = torch.empty(0)
        self.views: dict[tuple[int, ...], tuple[Any, ...]] = {}
        self.out = torch.empty(0, 0)
        self.out64 = np.empty((0, 0))

    def output(self, n: int, rows: int) -> tuple[torch.Tensor, np.ndarray]:
        """The (n x rows) output layer's buffer, float32, and one of float64 for its squash (kept
        between calls up to ``_KEEP_ROWS`` x 8 rows)."""
        if rows > 8 * _KEEP_ROWS:
            return torch.empty(n, rows), np.empty((n, rows))
        if self.out.shape[0] != n or self.out.shape[1] < rows:
            self.out = torch.empty(n, max(rows, self.out.shape[1]))
            self.out64 = np.empty(self.out.shape)
        return self.out[:, :rows], self.out64[:, :rows]

    def get(self, shape: tuple[int, ...], width: int) -> tuple[Any, ...]:
        """Views of the two (rows x width) buffers a, b for a chunk of leading shape ``shape``:
        (a as numpy of shape ``shape + (width,)``, a as torch of that shape, a, b, a.T, b.T)."""
        view = self.views.get(shape)
        if view is not None:
            return view
        rows = math.prod(shape)
        if rows > _KEEP_ROWS:  # a chunk this large (trailing axes > _CHUNK_ROWS) is not kept
            a = torch.empty(rows, width)
            b = torch.empty(rows, width)
        else:
            if len(self.views) >= 64 or rows > self.rows:
                self.views = {}
            if rows > self.rows:
                self.rows = rows
                self.a = torch.empty(rows, width)
                self.b = torch.empty(rows, width)
            a = self.a[:rows]
            b = self.b[:rows]
        a_nd = a.view(*shape, width)
        view = (a_nd.numpy(), a_nd, a, b, a.t(), b.t())
        if rows <= _KEEP_ROWS:
            self.views[shape] = view
        return view


class _InferencePlan:
    """The decoder's weights refolded for ``LatentActionModel.decode_numpy`` (read-only)."""

    def __init__(self, model: LatentActionModel) -> None:
        cfg = model.config
        d = cfg.z_dim
        n = cfg.n_joints
        layers = [m for m in model.decoder if isinstance(m, nn.Linear)]
        with torch.no_grad():
            w1 = layers[0].weight.detach().double()
            c1 = layers[0].bias.detach().double()
            mean = model.state_mean.detach().double()
            std = model.state_std.detach().double()
            w_s = w1[:, d : d + n] / std
            # h1 = W_z z + [W_s / std, W_b] [s, b] + (c1 - W_s mean / std), in float64
            self.w_z = w1[:, :d].T.numpy().copy()  # (d, H)
            self.w_sb = torch.cat([w_s, w1[:, d + n :]], dim=1).T.numpy().copy()  # (n + G, H)
            self.c1 = (c1 - w_s @ mean).numpy()  # (H,)
            # float32 views of the hidden weights, as decode's nn.Linear reads them
            self.hidden = [(layer.weight.detach().t(), layer.bias.detach()) for layer in layers[1:-1]]
            self.w_o = layers[-1].weight.detach().contiguous()  # (n, H): V^T = W_o U^T + c_o
            self.c_o = layers[-1].bias.detach()[:, None].contiguous()  # (n, 1)
        self.tensors = _weight_tensors(model)  # held, so that identity checks are exact
        self.versions = [t._version for t in self.tensors]
        self.scale = float(cfg.action_scale)
        self.width = int(w1.shape[0])
        self.d = d
        self.n = n
        self.g = cfg.n_goals
        self.buffers = _Buffers()

    def fits(self, model: LatentActionModel) -> bool:
        """Whether the plan was built from the model's current weights."""
        tensors = _weight_tensors(model)
        return (
            self.scale == model.config.action_scale
            and len(tensors) == len(self.tensors)
            and all(
                t is u and t._version == v
                for t, u, v in zip(tensors, self.tensors, self.versions, strict=True)
            )
        )

    def decode(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        """phi(z, s, b), float64; see :meth:`lasa.method.decoder.LatentActionModel.decode_numpy`."""
        z = np.minimum(np.maximum(np.asarray(z, dtype=np.float64), -1.0), 1.0)  # z clamped to [-1, 1]
        s, b = np.asarray(s, dtype=np.float64), np.asarray(b, dtype=np.float64)
        if z.shape[-1:] != (self.d,) or s.shape[-1:] != (self.n,) or b.shape[-1:] != (self.g,):
            raise ConfigError(
                f"decode_numpy needs z (..., {self.d}), s (..., {self.n}) and b (..., {self.g}); "
                f"got {z.shape}, {s.shape} and {b.shape}"
            )
        shape = np.broadcast_shapes(z.shape[:-1], s.shape[:-1], b.shape[:-1])
        lead = shape or (1,)
        rows_total = math.prod(lead)
        if rows_total == 0:
            return np.zeros(shape + (self.n,))
        # the first layer's z term (with its bias) and context term, float64, each unexpanded
        if self.d == 1:
            t_z = z * self.w_z[0] + self.c1
        else:
            t_z = (z.reshape(-1, self.d) @ self.w_z + self.c1).reshape(z.shape[:-1] + (self.width,))
        if s.shape[:-1] == b.shape[:-1]:
            sb = np.concatenate((s, b), axis=-1)
            t_c = (sb.reshape(-1, sb.shape[-1]) @ self.w_sb).reshape(s.shape[:-1] + (self.width,))
        else:
            t_c = s @ self.w_sb[: self.n] + b @ self.w_sb[self.n :]
        # each term rounded to float32 once, then added in float32: a row's first layer is
        # the same whichever chunk, batch or branch of _forward computes it
        v = self._forward(t_z.astype(np.float32), t_c.astype(np.float32), lead, rows_total)
        # the radial squash sigma_h tanh(|v|) v / |v| in float64, rows back to shape + (n,)
        norm = np.sqrt(np.einsum("ij,ij->j", v, v))
        np.maximum(norm, 1e-8, out=norm)
        factor = np.tanh(norm)
        factor /= norm
        if self.scale != 1.0:
            factor *= self.scale
        return np.multiply(v.T, factor[:, None], order="C").reshape(shape + (self.n,))

    def _forward(
        self, t_z32: np.ndarray, t_c32: np.ndarray, lead: tuple[int, ...], rows_total: int
    ) -> np.ndarray:
        """The MLP from the first layer's float32 terms, in chunks along the first broadcast axis;
        the output layer transposed (n x rows), copied to float64 (a reused buffer)."""
        width = self.width
        buffers = self.buffers
        inner = math.prod(lead[1:])
        chunks = -(-lead[0] // max(1, _CHUNK_ROWS // max(inner, 1)))
        step = -(-lead[0] // chunks)  # indices of the first axis per chunk, balanced
        out_t, v = buffers.output(self.n, rows_total)  # V transposed, and its float64 copy
        if chunks == 1:  # the first layer's add in numpy: fewer calls for small batches
            first_np, _, h, g, a_t, b_t = buffers.get(lead, width)
            np.add(t_z32, t_c32, out=first_np)
            self._layers(h, g, a_t, b_t, out_t)
        else:
            full = len(lead) + 1
            tz32 = torch.from_numpy(t_z32)
            tc32 = torch.from_numpy(t_c32)
            for start in range(0, lead[0], step):
                stop = min(lead[0], start + step)
                _, first, h, g, a_t, b_t = buffers.get((stop - start, *lead[1:]), width)
                torch.add(
                    _along_first(tz32, start, stop, full), _along_first(tc32, start, stop, full), out=first
                )
                self._layers(h, g, a_t, b_t, out_t[:, start * inner : stop * inner])
        np.copyto(v, out_t.numpy())  # (n, rows), float64
        return v

    def _layers(
        self, h: torch.Tensor, g: torch.Tensor, a_t: torch.Tensor, b_t: torch.Tensor, out: torch.Tensor
    ) -> None:
        """The first layer's tanh on h (buffer a), the hidden layers (h and g in turn), the output
        (from a_t or b_t, as the count of hidden layers is even or odd) into ``out`` (n x rows)."""
        h.tanh_()
        for w, c in self.hidden:
            torch.addmm(c, h, w, out=g)
            g.tanh_()
            h, g = g, h
        torch.addmm(self.c_o, self.w_o, b_t if len(self.hidden) % 2 == 1 else a_t, out=out)


def _along_first(term: torch.Tensor, start: int, stop: int, full: int) -> torch.Tensor:
    """Indices ``start:stop`` of the first broadcast axis of a first-layer term (itself if broadcast)."""
    if term.dim() == full and term.shape[0] != 1:
        return term[start:stop]
    return term


_PLANS: weakref.WeakKeyDictionary[LatentActionModel, _InferencePlan] = weakref.WeakKeyDictionary()


def inference_plan(model: LatentActionModel) -> _InferencePlan:
    """The model's cached inference plan (``plan.decode`` is ``model.decode_numpy``), rebuilt when
    its weights have changed."""
    plan = _PLANS.get(model)
    if plan is None or not plan.fits(model):
        plan = _InferencePlan(model)
        _PLANS[model] = plan
    return plan


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
    for wanted, got, differs, use in (
        (robot, model.robot, f"was trained for robot {model.robot!r}, not {robot!r}", repr(robot)),
        (n_goals, model.n_goals, f"reads a belief over {model.n_goals} goals, not {n_goals}", "that task"),
    ):
        if wanted is not None and got != wanted:
            raise CheckpointError(
                f"{path} {differs}. Use the checkpoint for {use} or re-make it with: {make_hint}"
            )
    model.eval()
    return model, dict(payload.get("extra", {}))
