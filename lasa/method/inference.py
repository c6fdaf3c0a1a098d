"""The decoder's inference forward phi(z, s, b) on numpy arrays, for throughput: weights refolded
once per model (rebuilt when one changes), a chunked forward into reused per-thread buffers.
"""

from __future__ import annotations

import math
import threading
import weakref
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from torch import nn

from lasa.base.errors import ConfigError

if TYPE_CHECKING:
    from lasa.method.decoder import LatentActionModel


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
        if view is None:
            rows = math.prod(shape)
            if rows > _KEEP_ROWS:  # a chunk this large (trailing axes > _CHUNK_ROWS) is not kept
                a, b = torch.empty(rows, width), torch.empty(rows, width)
                a_nd = a.view(*shape, width)
                return (a_nd.numpy(), a_nd, a, b, a.t(), b.t())
            if len(self.views) >= 64:
                self.views = {}
            if rows > self.rows:
                self.rows = rows
                self.a = torch.empty(rows, width)
                self.b = torch.empty(rows, width)
                self.views = {}
            a, b = self.a[:rows], self.b[:rows]
            a_nd = a.view(*shape, width)
            view = (a_nd.numpy(), a_nd, a, b, a.t(), b.t())
            self.views[shape] = view
        return view


class _InferencePlan:
    """The decoder's weights refolded for ``LatentActionModel.decode_numpy`` (read-only)."""

    def __init__(self, model: LatentActionModel) -> None:
        cfg = model.config
        d, n = cfg.z_dim, cfg.n_joints
        layers = [m for m in model.decoder if isinstance(m, nn.Linear)]
        with torch.no_grad():
            w1, c1 = layers[0].weight.detach().double(), layers[0].bias.detach().double()
            mean, std = model.state_mean.detach().double(), model.state_std.detach().double()
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
        self.d, self.n, self.g = d, n, cfg.n_goals
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
        s = np.asarray(s, dtype=np.float64)
        b = np.asarray(b, dtype=np.float64)
        if z.shape[-1:] != (self.d,) or s.shape[-1:] != (self.n,) or b.shape[-1:] != (self.g,):
            raise ConfigError(
                f"decode_numpy needs z (..., {self.d}), s (..., {self.n}) and b (..., {self.g}); "
                f"got {z.shape}, {s.shape} and {b.shape}"
            )
        shape = np.broadcast_shapes(z.shape[:-1], s.shape[:-1], b.shape[:-1])
        lead = shape or (1,)
        t_z, t_c = self._first_terms(z, s, b)
        rows_total = math.prod(lead)
        if rows_total == 0:
            return np.zeros(shape + (self.n,))
        # each term rounded to float32 once, then added in float32: a row's first layer is
        # the same whichever chunk, batch or branch of _forward computes it
        v = self._forward(t_z.astype(np.float32), t_c.astype(np.float32), lead, rows_total)
        return self._squash(v, shape)

    def _first_terms(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The first layer's z term (with its bias) and context term, float64, each unexpanded."""
        z_lead, s_lead, b_lead = z.shape[:-1], s.shape[:-1], b.shape[:-1]
        width = self.width
        if self.d == 1:
            t_z = z * self.w_z[0] + self.c1
        else:
            t_z = (z.reshape(-1, self.d) @ self.w_z + self.c1).reshape(z_lead + (width,))
        if s_lead == b_lead:
            sb = np.concatenate((s, b), axis=-1)
            t_c = (sb.reshape(-1, sb.shape[-1]) @ self.w_sb).reshape(s_lead + (width,))
        else:
            ns = s.shape[-1]
            t_c = s @ self.w_sb[:ns] + b @ self.w_sb[ns:]
        return t_z, t_c

    def _forward(
        self, t_z32: np.ndarray, t_c32: np.ndarray, lead: tuple[int, ...], rows_total: int
    ) -> np.ndarray:
        """The MLP from the first layer's float32 terms, in chunks along the first broadcast axis;
        the output layer transposed (n x rows), copied to float64 (a reused buffer)."""
        width, buffers = self.width, self.buffers
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
            tz32, tc32 = torch.from_numpy(t_z32), torch.from_numpy(t_c32)
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
        last_is_b = len(self.hidden) % 2 == 1
        torch.addmm(self.c_o, self.w_o, b_t if last_is_b else a_t, out=out)

    def _squash(self, v: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
        """The radial squash sigma_h tanh(|v|) v / |v| in float64, rows back to ``shape + (n,)``."""
        norm = np.sqrt(np.einsum("ij,ij->j", v, v))
        np.maximum(norm, 1e-8, out=norm)
        factor = np.tanh(norm)
        factor /= norm
        if self.scale != 1.0:
            factor *= self.scale
        return np.multiply(v.T, factor[:, None], order="C").reshape(shape + (self.n,))


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
