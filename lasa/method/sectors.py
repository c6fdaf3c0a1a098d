r"""A 2-D latent whose ring keeps departures and manipulation apart (an optional training loss).

The paper asks two things of latent actions at a context where the robot is confident in a
goal (Sec. III, IV-B): most inputs convey *how* to act at that goal (stay), and some input
leads to *each other goal* (leave). A plain autoencoder has no reason to give both: the
encoder places each demonstrated action where reconstruction is easiest, and departures
from a confident goal, a small share of the data, may get no part of the stick at all.

This loss gives them one. With a 2-axis stick, the angle of z on the ring,
:math:`\vartheta = \operatorname{atan2}(z_2, z_1)`, is split into a *departure sector*
:math:`|\vartheta| \le \pi s` (a share s of the ring, centred on +z1) and the rest. A tuple is

- a **departure** when it is a reach (:data:`lasa.method.dataset.REACH`) whose belief is
  confident (its largest entry at least ``confident``) in another goal than the one reached:
  the robot is confident in the goal being left;
- **manipulation** when it is a stroke, an adjustment or a hold and its belief is confident
  (its largest entry at least ``confident``);
- free otherwise (reaches from home with an uncertain belief choose among goals with the
  whole ring, as before).

The loss is a hinge on the angle outside a tuple's sector, averaged over the batch,

.. math::  L_\text{sector} = \frac{1}{B}\Big(\sum_{\text{departures}} [\,|\vartheta| - \pi s\,]_+
    + \sum_{\text{manipulation}} [\,\pi s - |\vartheta|\,]_+\Big),

added to the reconstruction loss with weight ``sector_weight``
(:class:`lasa.method.train.TrainConfig`). The encoder then puts departures in the sector and
manipulation outside it; the decoder, trained on those codes, decodes the sector's inputs as
departures at a confident context. It touches the encoder's codes only, never the decoder's
reconstruction target.
"""

from __future__ import annotations

import numpy as np
import torch

from lasa.base.errors import ConfigError
from lasa.method.dataset import REACH, Demonstrations

__all__ = ["sector_roles", "sector_loss", "DEPARTURE", "MANIPULATION", "FREE"]

FREE, DEPARTURE, MANIPULATION = 0, 1, 2  # a tuple's role on the ring


def sector_roles(demos: Demonstrations, confident: float = 0.9) -> np.ndarray:
    """Each tuple's role on the ring: :data:`DEPARTURE`, :data:`MANIPULATION` or :data:`FREE`, (N,).

    Args:
        demos: The dataset (its phases, goals and beliefs).
        confident: The belief's largest entry from which a tuple is a departure or manipulation.
    """
    if not 0.0 < confident <= 1.0:
        raise ConfigError(f"confident must be in (0, 1], got {confident}")
    believed = demos.beliefs.argmax(axis=1)
    reach = demos.phase == REACH
    roles = np.full(len(demos), FREE, dtype=np.int64)
    sure = demos.beliefs.max(axis=1) >= confident
    roles[reach & sure & (believed != demos.goal)] = DEPARTURE
    roles[~reach & sure] = MANIPULATION
    return roles


def sector_loss(z: torch.Tensor, roles: torch.Tensor, share: float) -> torch.Tensor:
    """The hinge on each tuple's angle outside its sector, averaged over the batch (module docstring).

    Args:
        z: The encoder's codes, (B, 2).
        roles: Each tuple's role, (B,) (:func:`sector_roles`).
        share: s, the departure sector's share of the ring, in (0, 1).

    Returns:
        The loss, a scalar tensor [rad].
    """
    if z.shape[-1] != 2:
        raise ConfigError(f"the sector loss needs a 2-D latent (a 2-axis stick), got z_dim={z.shape[-1]}")
    if not 0.0 < share < 1.0:
        raise ConfigError(f"the departure sector's share must be in (0, 1), got {share}")
    angle = torch.atan2(z[:, 1], z[:, 0]).abs()
    half = torch.pi * share
    outside = torch.where(
        roles == DEPARTURE,
        torch.relu(angle - half),
        torch.where(roles == MANIPULATION, torch.relu(half - angle), torch.zeros_like(angle)),
    )
    return outside.mean()
