r"""The entropy regulariser of Eqs. T5-T6: at every context some z moves towards *each* goal (Sec.
IV-A), :math:`p_{(s,b)}(g) \propto \sum_{z} \eta(g, s, b, z)`, :math:`\mathcal{L} = \|e_a\|^2 + \lambda
\sum_{g} p_{(s,b)}(g) \log p_{(s,b)}(g)`, eta the goal posterior of the decoded action held H steps.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import torch

from lasa.base.config import AtLeastTwo, ControlConfig, Positive, PositiveInt, Seed, validate
from lasa.base.errors import ConfigError
from lasa.method.belief import log_likelihood_torch, nearest_distance
from lasa.method.decoder import LatentActionModel
from lasa.method.step import latent_grid


def goal_scores(
    model: LatentActionModel,
    states: torch.Tensor,
    beliefs: torch.Tensor,
    z_grid: torch.Tensor,
    goal_sets: torch.Tensor,
    control: ControlConfig,
    horizon: int = 10,
) -> torch.Tensor:
    """eta(g, s, b, z) for every context (s (B, n), b (B, G)) and input (K, d), (B, K, G), rows
    summing to one; ``goal_sets`` and ``control`` are the belief's, ``horizon`` H."""
    n_ctx, n_z = states.shape[0], z_grid.shape[0]
    s, b, z = (x.expand(n_ctx, n_z, -1) for x in (states[:, None, :], beliefs[:, None, :], z_grid[None]))
    actions = model.decode(z, s, b)
    step = control.likelihood_step
    max_step = None if step is None else horizon * step
    # the state unexpanded, the distance through each goal's nearest segment only
    dt, beta = horizon * control.dt, control.belief_beta
    loglik = log_likelihood_torch(
        states[:, None, :], actions, goal_sets, dt, beta, max_step, nearest_distance
    )
    return torch.softmax(loglik, dim=-1)


def goal_distribution(scores: torch.Tensor) -> torch.Tensor:
    """p_(s,b)(g) ∝ sum_z eta (Eq. T5), shape (B, G), from scores of shape (B, K, G)."""
    total = scores.sum(dim=1)
    return total / total.sum(dim=-1, keepdim=True)


def entropy(p: torch.Tensor) -> torch.Tensor:
    """Shannon entropy -sum_g p log p along the last axis [nats]."""
    return -(p * torch.log(p.clamp_min(1e-12))).sum(dim=-1)


@dataclasses.dataclass
class EntropyRegularizer:
    """The extra loss lambda * mean over contexts of sum_g p log p (Eq. T6), on ``contexts`` contexts
    of each batch drawn with ``seed``, z over ``n_z`` inputs per axis, evidence over ``horizon`` steps."""

    entropy_lambda: Positive
    goal_sets: np.ndarray
    control: ControlConfig
    n_z: AtLeastTwo = 11
    horizon: PositiveInt = 10
    contexts: PositiveInt = 64
    seed: Seed = 0

    def __post_init__(self) -> None:
        validate(self)
        self._goal_sets = torch.as_tensor(np.asarray(self.goal_sets), dtype=torch.float32)
        self._gen = torch.Generator().manual_seed(self.seed)

    def __call__(self, model: LatentActionModel, states: torch.Tensor, beliefs: torch.Tensor) -> torch.Tensor:
        grid = torch.as_tensor(latent_grid(self.n_z, model.z_dim), dtype=torch.float32)
        pick = torch.randperm(states.shape[0], generator=self._gen)[: self.contexts]
        scores = goal_scores(
            model, states[pick], beliefs[pick], grid, self._goal_sets, self.control, self.horizon
        )
        return -self.entropy_lambda * entropy(goal_distribution(scores)).mean()


def context_entropy(
    model: LatentActionModel,
    states: np.ndarray,
    beliefs: np.ndarray,
    goal_sets: np.ndarray,
    control: ControlConfig,
    n_z: int = 11,
    horizon: int = 10,
) -> np.ndarray:
    """Entropy of p_(s,b) [nats] at each context, shape (B,), without gradients."""
    grid = torch.as_tensor(latent_grid(n_z, model.config.z_dim), dtype=torch.float32)
    s, b, sets = (torch.as_tensor(x, dtype=torch.float32) for x in (states, beliefs, goal_sets))
    with torch.no_grad():
        scores = goal_scores(model, s, b, grid, sets, control, horizon)
        return entropy(goal_distribution(scores)).double().numpy()


def context_grid(
    start: np.ndarray, goal: np.ndarray, goal_index: int, n_goals: int, n_pos: int = 9, n_belief: int = 9
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Contexts along the line from ``start`` to ``goal`` (``n_pos``) and across confidences in it from
    uniform to 0.999 (``n_belief``), progress-major: progress, confidence, states, beliefs."""
    progress = np.linspace(0.0, 1.0, n_pos)
    conf = np.linspace(1.0 / n_goals, 0.999, n_belief)
    pp, cc = np.meshgrid(progress, conf, indexing="ij")
    states = start + pp.reshape(-1, 1) * (goal - start)
    beliefs = np.repeat((1.0 - cc.reshape(-1, 1)) / (n_goals - 1), n_goals, axis=1)
    beliefs[:, goal_index] = cc.reshape(-1)
    return pp.reshape(-1), cc.reshape(-1), states, beliefs


# the rule's bound on a chosen lambda's reconstruction error, as a factor of the control's [-]
LAMBDA_COST = 1.5


def choose_lambda(sweep: pd.DataFrame, n_goals: int, spread: float = 0.8, cost: float = LAMBDA_COST) -> float:
    """The lambda the pipeline trains with, by a rule fixed before looking at results: the smallest
    lambda > 0 whose ``entropy_confident`` reaches ``spread`` of log G with ``recon_error`` within
    ``cost`` times lambda = 0's; else, within that bound, the highest entropy; else 0."""
    if 0.0 not in set(sweep["lambda"]):
        raise ConfigError("the lambda sweep must include 0 (the reference)")
    ref = float(sweep.loc[sweep["lambda"] == 0.0, "recon_error"].iloc[0])
    cand = sweep[(sweep["lambda"] > 0) & (sweep["recon_error"] <= cost * ref)].sort_values("lambda")
    if cand.empty:
        return 0.0
    good = cand[cand["entropy_confident"] >= spread * np.log(n_goals)]
    if not good.empty:
        return float(good["lambda"].iloc[0])
    return float(cand.loc[cand["entropy_confident"].idxmax(), "lambda"])
