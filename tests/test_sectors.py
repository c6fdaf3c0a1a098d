"""The latent's sectors (lasa.method.train): roles of tuples and the hinge, against hand-computed cases."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from lasa.base.errors import ConfigError
from lasa.method.dataset import ADJUST, HOLD, REACH, STROKE, Demonstrations
from lasa.method.train import DEPARTURE, FREE, MANIPULATION, TrainConfig, sector_loss, sector_roles


def _demos(phase: list[int], goal: list[int], beliefs: list[list[float]]) -> Demonstrations:
    n = len(phase)
    return Demonstrations(
        robot="panda",
        states=np.zeros((n, 7)),
        actions=np.zeros((n, 7)),
        beliefs=np.asarray(beliefs, dtype=float),
        demo=np.zeros(n, dtype=int),
        goal=np.asarray(goal),
        theta=np.zeros(n),
        phase=np.asarray(phase),
        perturbed=np.zeros(n, dtype=bool),
    )


def test_roles_by_hand() -> None:
    demos = _demos(
        [REACH, REACH, REACH, STROKE, ADJUST, HOLD, STROKE],
        [1, 1, 0, 0, 0, 0, 0],
        [
            [0.97, 0.03],  # a reach to 1 while confident in 0: leaving 0
            [0.5, 0.5],  # a reach from an uncertain belief: free (choosing, not leaving)
            [0.97, 0.03],  # a reach to the goal believed in: free
            [0.95, 0.05],  # a stroke, confident: manipulation
            [0.9, 0.1],  # an adjustment at exactly the threshold: manipulation
            [0.05, 0.95],  # a hold, confident in the other goal: manipulation
            [0.6, 0.4],  # a stroke, unsure: free
        ],
    )
    roles = sector_roles(demos)
    assert list(roles) == [DEPARTURE, FREE, FREE, MANIPULATION, MANIPULATION, MANIPULATION, FREE]
    with pytest.raises(ConfigError, match="confident"):
        sector_roles(demos, confident=0.0)


def test_the_hinge_by_hand() -> None:
    share = 0.25  # the departure sector is |angle| <= pi / 4
    z = torch.tensor([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0], [-1.0, 0.0], [0.0, -1.0]])
    roles = torch.tensor([DEPARTURE, DEPARTURE, MANIPULATION, MANIPULATION, FREE])
    # departure at 0: inside (0); departure at pi/2: pi/4 outside; manipulation at 0: pi/4 inside the
    # departure sector; manipulation at pi: outside it (0); free: 0
    expected = (0.0 + np.pi / 4 + np.pi / 4 + 0.0 + 0.0) / 5
    assert float(sector_loss(z, roles, share)) == pytest.approx(expected, rel=1e-6)
    with pytest.raises(ConfigError, match="2-D latent"):
        sector_loss(torch.zeros(3, 1), torch.zeros(3, dtype=torch.long), share)
    with pytest.raises(ConfigError, match="share"):
        sector_loss(z, roles, 1.0)


def test_the_loss_needs_a_two_axis_stick() -> None:
    with pytest.raises(ConfigError, match="z_dim = 2"):
        TrainConfig(z_dim=1, sector_weight=1.0)
    with pytest.raises(ConfigError, match="sector_share"):
        TrainConfig(z_dim=2, sector_weight=1.0, sector_share=1.0)
    assert TrainConfig(z_dim=2, sector_weight=1.0).sector_share == 0.375
