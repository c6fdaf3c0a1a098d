r"""Training the latent-action model on demonstrations: the reconstruction error of Sec. III-A,
:math:`\|\phi(z, s, b) - a\|^2`, :math:`z = \psi(s, a, b)`, in units of sigma_h, with Gaussian noise
on z (clipped to [-1, 1]) to spread actions over the stick's range and smooth the decoder in z; and
the optional sector loss, whose 2-D latent's ring keeps departures and manipulation apart.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from typing import Annotated

import annotated_types as at
import numpy as np
import pandas as pd
import torch
from tqdm.auto import tqdm

from lasa.base.config import (
    AtLeastTwo,
    ControlConfig,
    NonNegative,
    Number,
    Positive,
    PositiveInt,
    Seed,
    check_range,
    validate,
)
from lasa.base.errors import ConfigError
from lasa.method.dataset import REACH, Demonstrations
from lasa.method.decoder import DecoderConfig, LatentActionModel
from lasa.method.entropy import EntropyRegularizer

ExtraLoss = Callable[[LatentActionModel, torch.Tensor, torch.Tensor], torch.Tensor]


@dataclasses.dataclass(frozen=True)
class TrainConfig:
    """Optimisation of the conditional autoencoder."""

    steps: PositiveInt = 2000  # optimiser steps; held-out error lowest at 1200 (planar5), 600 (Panda) [-]
    batch_size: PositiveInt = 512  # tuples per step [-]
    lr: Positive = 2e-3  # Adam learning rate, cosine-decayed to 5% [-]
    weight_decay: NonNegative = 0.0  # AdamW weight decay [-]
    z_noise: NonNegative = 0.05  # std of the noise added to z while training [-]
    hidden: PositiveInt = 128  # width of the hidden layers [-]
    depth: PositiveInt = 3  # hidden layers in encoder and decoder [-]
    z_dim: PositiveInt = 1  # latent dimension d [-]
    holdout: Annotated[Number, at.Ge(0.0), at.Le(0.5)] = 0.1  # demonstrations held out [-]
    log_every: PositiveInt = 100  # steps between logged losses [-]
    entropy_lambda: NonNegative = 0.0  # lambda of the entropy term (Eq. T6); 0 trains plain LA [-]
    entropy_n_z: AtLeastTwo = 11  # joystick inputs the entropy term's sum over z runs over [-]
    entropy_horizon: PositiveInt = 10  # steps over which the entropy term reads an input's evidence [-]
    entropy_contexts: PositiveInt = 64  # contexts per batch the entropy term is evaluated on [-]
    # the latent's sectors (:func:`sector_loss`; 2-D latents): departures from a confident goal
    # in a share of the ring, manipulation outside it; 0 trains without
    sector_weight: NonNegative = 0.0  # weight of the sector loss [1/rad] [-]
    sector_share: Annotated[Number, at.Gt(0.0), at.Lt(1.0)] = 0.375  # departure sector's share [-]
    seed: Seed = 0  # seed of initialisation, batches and noise [-]

    def __post_init__(self) -> None:
        validate(self)
        if self.sector_weight > 0 and self.z_dim != 2:
            raise ConfigError(f"sector_weight > 0 needs z_dim = 2 (a 2-axis stick), got z_dim={self.z_dim}")


def _split(demos: Demonstrations, holdout: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Train / validation masks that keep whole demonstrations together."""
    ids = np.unique(demos.demo)
    n_val = int(round(holdout * len(ids)))
    val = np.isin(demos.demo, rng.choice(ids, size=n_val, replace=False) if n_val else np.array([], int))
    return ~val, val & ~demos.perturbed


def reconstruction_error(
    model: LatentActionModel, states: np.ndarray, actions: np.ndarray, beliefs: np.ndarray
) -> float:
    """Mean squared reconstruction error ||phi(psi(s, a, b), s, b) - a||^2 [(rad/s)^2]."""
    with torch.inference_mode():
        s, a, b = (torch.as_tensor(x, dtype=torch.float32) for x in (states, actions, beliefs))
        _, a_hat = model(s, a, b)
        return float(((a_hat - a) ** 2).sum(-1).mean())


def _with_entropy(
    config: TrainConfig, control: ControlConfig, goal_sets: np.ndarray | None, extra_loss: ExtraLoss | None
) -> ExtraLoss | None:
    """``extra_loss`` plus the entropy term of Eq. T6 when ``config.entropy_lambda > 0``."""
    if config.entropy_lambda <= 0:
        return extra_loss
    if goal_sets is None:
        raise ConfigError("entropy_lambda > 0 needs goal_sets (belief_targets(task, control.likelihood))")
    c = config
    term = EntropyRegularizer(
        c.entropy_lambda, goal_sets, control, c.entropy_n_z, c.entropy_horizon, c.entropy_contexts, c.seed
    )
    return term if extra_loss is None else lambda model, s, b: term(model, s, b) + extra_loss(model, s, b)


def _initial_model(
    demos: Demonstrations, control: ControlConfig, config: TrainConfig, init: LatentActionModel | None
) -> LatentActionModel:
    """A fresh model with the demonstrations' state normalisation, or a trainable copy of ``init``
    (ConfigError if its architecture differs)."""
    clean_states = demos.states[~demos.perturbed]
    model = LatentActionModel(
        DecoderConfig(
            robot=demos.robot,
            n_joints=demos.states.shape[1],
            n_goals=demos.beliefs.shape[1],
            z_dim=config.z_dim,
            hidden=config.hidden,
            depth=config.depth,
            action_scale=control.action_scale,
            state_mean=tuple(float(x) for x in clean_states.mean(axis=0)),
            state_std=tuple(float(x) for x in np.maximum(clean_states.std(axis=0), 1e-3)),
        )
    )
    if init is not None:
        mine, theirs = model.config, init.config
        for name in ("robot", "n_joints", "n_goals", "z_dim", "hidden", "depth", "action_scale"):
            if getattr(mine, name) != getattr(theirs, name):
                raise ConfigError(
                    f"cannot warm-start: init has {name}={getattr(theirs, name)!r}, "
                    f"these demonstrations and config give {getattr(mine, name)!r}"
                )
        model = LatentActionModel(theirs)
        model.load_state_dict(init.state_dict())
    return model


def train_decoder(
    demos: Demonstrations,
    control: ControlConfig,
    config: TrainConfig = TrainConfig(),
    *,
    goal_sets: np.ndarray | None = None,
    extra_loss: ExtraLoss | None = None,
    init: LatentActionModel | None = None,
    progress: bool = True,
) -> tuple[LatentActionModel, pd.DataFrame]:
    """Train phi(z, s, b) on ``demos`` with the bound sigma_h = ``control.action_scale``.

    ``goal_sets`` (G, K, n), the belief's, are needed for Eq. T6's term (``entropy_lambda > 0``);
    ``extra_loss(model, states, beliefs)`` is added on each batch; ``init`` warm-starts from a copy.
    Returns the model (eval mode) and the log: ``step``, ``train_loss``, ``val_error``, ``seconds``.
    """
    extra_loss = _with_entropy(config, control, goal_sets, extra_loss)
    gen = torch.Generator().manual_seed(config.seed)
    torch.manual_seed(config.seed)  # nn.Linear initialisation draws from the global generator
    train_mask, val_mask = _split(demos, config.holdout, np.random.default_rng(config.seed))
    if train_mask.sum() < config.batch_size:
        raise ConfigError(
            f"only {train_mask.sum()} training tuples for batch_size={config.batch_size}; "
            "collect more demonstrations or lower batch_size"
        )
    model = _initial_model(demos, control, config, init)
    arrays = (demos.states, demos.actions, demos.beliefs)
    s, a, b = (torch.as_tensor(x[train_mask], dtype=torch.float32) for x in arrays)
    roles = torch.as_tensor(sector_roles(demos)[train_mask]) if config.sector_weight > 0 else None
    data = (s, a, b, roles)
    val = tuple(x[val_mask] for x in arrays)

    # fused: one kernel per parameter for the whole update, about 3x faster on CPU
    optim = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=config.weight_decay, fused=True)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(optim, config.steps, eta_min=0.05 * config.lr)
    log: list[dict[str, float]] = []
    start = time.perf_counter()
    bar = tqdm(range(1, config.steps + 1), desc=f"train {demos.robot}", disable=not progress)
    running = 0.0
    for step in bar:
        loss = _batch_loss(model, data, gen, config, control.action_scale, extra_loss)
        optim.zero_grad(set_to_none=True)
        loss.backward()
        optim.step()
        sched.step()
        running += loss.item()
        if step % config.log_every == 0 or step == config.steps:
            n = config.log_every if step % config.log_every == 0 else step % config.log_every
            model.eval()  # the log's row: the mean loss since the last row, the held-out error
            val_err = reconstruction_error(model, *val) if len(val[0]) else float("nan")
            model.train()
            seconds = time.perf_counter() - start
            log.append(dict(step=step, train_loss=running / n, val_error=val_err, seconds=seconds))
            bar.set_postfix(loss=f"{running / n:.4f}", val=f"{val_err:.4f}")
            running = 0.0
    model.eval()
    return model, pd.DataFrame(log)


def _batch_loss(
    model: LatentActionModel,
    data: tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor | None],
    gen: torch.Generator,
    config: TrainConfig,
    scale: float,
    extra_loss: ExtraLoss | None,
) -> torch.Tensor:
    """One batch's loss: reconstruction (in sigma_h units), the sector loss (if roles) and any extra
    term; the batch, then the noise on z, drawn from ``gen``."""
    s_all, a_all, b_all, roles = data
    idx = torch.randint(len(s_all), (config.batch_size,), generator=gen)
    s, a, b = s_all[idx], a_all[idx], b_all[idx]
    z = model.encode(s, a, b)
    sector = (
        config.sector_weight * sector_loss(z, roles[idx], config.sector_share) if roles is not None else 0.0
    )
    z = (z + config.z_noise * torch.randn(z.shape, generator=gen)).clamp(-1.0, 1.0)
    loss = (((model.decode(z, s, b) - a) / scale) ** 2).sum(-1).mean() + sector
    if extra_loss is not None:
        loss = loss + extra_loss(model, s, b)
    return loss


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
    r"""The hinge on each tuple's angle outside its sector, averaged over the batch [rad]; z (B, 2),
    roles (B,), ``share`` s in (0, 1). The angle :math:`\vartheta = \operatorname{atan2}(z_2, z_1)` of
    a departure (a reach confident in another goal) stays in :math:`|\vartheta| \le \pi s`, of
    manipulation (a confident stroke, adjustment or hold) outside it (Secs. III, IV-B):

    .. math::  L_\text{sector} = \frac{1}{B}\Big(\sum_{\text{departures}} [\,|\vartheta| - \pi s\,]_+
        + \sum_{\text{manipulation}} [\,\pi s - |\vartheta|\,]_+\Big).
    """
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
