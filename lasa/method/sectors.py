r"""A 2-D latent whose ring keeps departures and manipulation apart (an optional training loss).

The angle :math:`\vartheta = \operatorname{atan2}(z_2, z_1)` of a departure (a reach confident in
another goal) stays in :math:`|\vartheta| \le \pi s`, of manipulation (a confident stroke,
adjustment or hold) outside it (Secs. III, IV-B); weighted by ``sector_weight``:

.. math::  L_\text{sector} = \frac{1}{B}\Big(\sum_{\text{departures}} [\,|\vartheta| - \pi s\,]_+
    + \sum_{\text{manipulation}} [\,\pi s - |\vartheta|\,]_+\Big).
"""

from __future__ import annotations

import numpy as np
import torch

from lasa.base.config import check_range
from lasa.base.errors import ConfigError
from lasa.method.dataset import REACH, Demonstrations

FREE, DEPARTURE, MANIPULATION = 0, 1, 2  # a tuple's role on the ring


def sector_roles(demos: Demonstrations, confident: float = 0.9) -> np.ndarray:
    """Each tuple's role on the ring, (N,): :data:`DEPARTURE`, :data:`MANIPULATION` (both from a
    top belief of ``confident``) or :data:`FREE`."""
    check_range("confident", confident, 0.0, 1.0, low_open=True)
    believed = demos.beliefs.argmax(axis=1)
    reach = demos.phase == REACH
    roles = np.full(len(demos), FREE, dtype=np.int64)
    sure = demos.beliefs.max(axis=1) >= confident
    roles[reach & sure & (believed != demos.goal)] = DEPARTURE
    roles[~reach & sure] = MANIPULATION
    return roles


def sector_loss(z: torch.Tensor, roles: torch.Tensor, share: float) -> torch.Tensor:
    """The hinge on each tuple's angle outside its sector, averaged over the batch [rad]; z (B, 2),
    roles (B,), ``share`` s in (0, 1)."""
    if z.shape[-1] != 2:
        raise ConfigError(f"the sector loss needs a 2-D latent (a 2-axis stick), got z_dim={z.shape[-1]}")
    check_range("the departure sector's share", share, 0.0, 1.0, low_open=True, high_open=True)
    angle = torch.atan2(z[:, 1], z[:, 0]).abs()
    half = torch.pi * share
    outside = torch.where(
        roles == DEPARTURE,
        torch.relu(angle - half),
        torch.where(roles == MANIPULATION, torch.relu(half - angle), torch.zeros_like(angle)),
    )
    return outside.mean()
