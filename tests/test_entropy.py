"""The entropy term (Eqs. T5-T6): a hand-computed case, gradients, spreading, the lambda rule."""

import dataclasses
from unittest import mock

import numpy as np
import pandas as pd
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from lasa.base.config import ControlConfig
from lasa.base.errors import ConfigError
from lasa.method.belief import belief_targets
from lasa.method.entropy import (
    LAMBDA_COST,
    EntropyRegularizer,
    choose_lambda,
    context_entropy,
    context_grid,
    entropy,
    goal_distribution,
    goal_scores,
)
from lasa.method.train import TrainConfig, train_decoder
from tests.conftest import SMALL_TRAIN

POINT_GOALS = torch.tensor([[[1.0, 0.0]], [[-1.0, 0.0]]])  # two point goals, shape (G=2, K=1, n=2)
CTL = ControlConfig(dt=0.1, belief_beta=0.5, likelihood="goal")  # plain progress model


class Stub:
    """A decoder whose action is +x for z > 0 and -x otherwise, of norm 1."""

    def decode(self, z, s, b):
        return torch.cat([torch.where(z > 0, 1.0, -1.0), torch.zeros_like(z)], dim=-1)


def test_scores_and_distribution_by_hand():
    # From s = 0, holding a = (1, 0) for H = 10 steps of 0.1 s reaches (1, 0): one closer to
    # g1, one farther from g2. With beta_b = 0.5: eta = softmax(+0.5, -0.5) = (0.731, 0.269).
    s, b = torch.zeros(1, 2), torch.tensor([[0.5, 0.5]])
    both = goal_scores(Stub(), s, b, torch.tensor([[-1.0], [1.0]]), POINT_GOALS, CTL, horizon=10)
    e = 1 / (1 + np.exp(-1.0))
    assert_allclose(both[0].numpy(), [[1 - e, e], [e, 1 - e]], atol=1e-6)
    p = goal_distribution(both)
    assert_allclose(p.numpy(), [[0.5, 0.5]], atol=1e-6)  # one input per goal: p uniform
    assert_allclose(entropy(p).numpy(), [np.log(2)], atol=1e-6)
    one = goal_scores(Stub(), s, b, torch.tensor([[1.0], [0.5]]), POINT_GOALS, CTL, horizon=10)
    p1 = goal_distribution(one)
    assert_allclose(p1.numpy(), [[e, 1 - e]], atol=1e-6)  # every input to g1
    assert_allclose(entropy(p1).numpy(), [-(e * np.log(e) + (1 - e) * np.log(1 - e))], atol=1e-6)


def test_p_is_a_distribution(model, task):
    ctl = task.robot.control
    rng = np.random.default_rng(0)
    states = rng.uniform(task.robot.lower, task.robot.upper, size=(32, task.robot.n_joints))
    beliefs = rng.dirichlet([1, 1], size=32)
    scores = goal_scores(
        model,
        torch.tensor(states, dtype=torch.float32),
        torch.tensor(beliefs, dtype=torch.float32),
        torch.linspace(-1, 1, 7)[:, None],
        torch.tensor(belief_targets(task, ctl.likelihood), dtype=torch.float32),
        ctl,
    )
    p = goal_distribution(scores)
    assert torch.all(p >= 0) and torch.allclose(p.sum(-1), torch.ones(32))
    h = context_entropy(model, states, beliefs, belief_targets(task, ctl.likelihood), ctl)
    assert np.all(h >= -1e-9) and np.all(h <= np.log(2) + 1e-9)


def test_gradient_reaches_the_decoder(model, task, demos):
    ctl = task.robot.control
    reg = EntropyRegularizer(1.0, belief_targets(task, ctl.likelihood), ctl, contexts=16)
    s = torch.tensor(demos.states[:64], dtype=torch.float32)
    b = torch.tensor(demos.beliefs[:64], dtype=torch.float32)
    model.zero_grad()
    reg(model, s, b).backward()
    grads = [p.grad for p in model.decoder.parameters()]
    assert all(g is not None for g in grads)
    assert sum(float(g.abs().sum()) for g in grads) > 0
    model.zero_grad()


def test_large_lambda_spreads_p_at_confident_contexts(demos, task):
    ctl = task.robot.control
    goal_sets = belief_targets(task, ctl.likelihood)
    clean = demos.clean()
    conf = clean.beliefs.max(1) > 0.99
    probe = (clean.states[conf], clean.beliefs[conf])
    cfg = dataclasses.replace(SMALL_TRAIN, steps=300)
    plain, _ = train_decoder(demos, ctl, cfg, progress=False)
    spread, _ = train_decoder(
        demos, ctl, dataclasses.replace(cfg, entropy_lambda=3.0), goal_sets=goal_sets, progress=False
    )
    h_plain = context_entropy(plain, *probe, goal_sets, ctl).mean()
    h_spread = context_entropy(spread, *probe, goal_sets, ctl).mean()
    assert h_plain < 0.3  # without the term, confident contexts lead to one goal
    assert h_spread > h_plain + 0.2


def test_context_grid():
    progress, conf, states, beliefs = context_grid(np.zeros(3), np.ones(3), 1, 2, n_pos=3, n_belief=4)
    assert states.shape == (12, 3) and beliefs.shape == (12, 2)
    assert_allclose(beliefs.sum(1), 1.0)
    assert_allclose(states[progress == 1.0], 1.0)
    assert conf.min() == pytest.approx(0.5) and conf.max() == pytest.approx(0.999)


def test_choose_lambda_rule():
    sweep = pd.DataFrame(
        {
            "lambda": [0.0, 0.1, 0.3, 1.0],
            "entropy_confident": [0.01, 0.3, 0.6, 0.69],
            "recon_error": [1, 1.1, 1.2, 2.0],
        }
    )
    assert choose_lambda(sweep, 2) == 0.3  # smallest reaching 0.8 log 2 = 0.55 within 1.5x error
    assert choose_lambda(sweep.assign(entropy_confident=[0.01, 0.1, 0.2, 0.69]), 2) == 0.3  # best within cost
    with pytest.raises(ConfigError, match="include 0"):
        choose_lambda(sweep[sweep["lambda"] > 0], 2)


def test_bad_lambda_is_a_clear_error(task):
    with pytest.raises(ConfigError, match="entropy_lambda"):
        TrainConfig(entropy_lambda=-0.1)
    with pytest.raises(ConfigError, match="entropy_lambda"):
        EntropyRegularizer(0.0, task.curves, task.robot.control)
    with pytest.raises(ConfigError, match="goal_sets"):
        train_decoder(None, task.robot.control, TrainConfig(entropy_lambda=1.0))  # type: ignore[arg-type]


def test_ablation_runs_differ_only_by_the_term(model, demos, task, tmp_path):
    """Every lambda, 0 included, fine-tunes the base decoder with the same steps, schedule and seed."""
    from lasa.base.config import to_dict
    from lasa.experiments import entropy_ablation
    from lasa.method.decoder import load_checkpoint, save_checkpoint

    ctl = task.robot.control
    cfg = entropy_ablation.Config(lambdas=(0.0, 0.3), sweep_steps=20, seed=0)
    sweep = entropy_ablation.run_sweep(model, SMALL_TRAIN, demos, task, ctl, cfg, progress=False)
    c0, c1 = sweep.configs[0.0], sweep.configs[0.3]
    assert c0.steps == c1.steps == 20 and c0.entropy_lambda == 0.0
    assert dataclasses.replace(c0, entropy_lambda=0.3) == c1  # nothing else differs

    def weights(m):
        return [t.clone() for t in m.state_dict().values()]

    def same(a, b):
        return all(torch.equal(x, y) for x, y in zip(weights(a), weights(b), strict=True))

    assert not same(sweep.models[0.0], model)  # the control is fine-tuned too, not the base itself
    assert not same(sweep.models[0.0], sweep.models[0.3])  # the term changes the weights
    again, _ = train_decoder(
        demos, ctl, c0, goal_sets=belief_targets(task, ctl.likelihood), init=model, progress=False
    )
    assert same(again, sweep.models[0.0])  # the control is reproducible: only lambda differs
    assert list(sweep.table["lambda"]) == [0.0, 0.3]
    # this short sweep's 0.3 costs more than the rule's bound: the rule keeps the control
    cost = sweep.table.recon_error.iloc[1] / sweep.table.recon_error.iloc[0]
    assert sweep.chosen == (0.3 if cost <= LAMBDA_COST else 0.0)
    path = save_checkpoint(sweep.models[0.3], tmp_path / "e.pt", train=to_dict(c1), entropy_lambda=0.3)
    loaded, extra = load_checkpoint(path)
    assert same(loaded, sweep.models[0.3]) and extra["train"]["entropy_lambda"] == 0.3


def test_ablation_config_needs_the_control():
    from lasa.experiments import entropy_ablation

    with pytest.raises(ConfigError, match="include 0"):
        entropy_ablation.Config(lambdas=(0.1, 0.3))
    with pytest.raises(ConfigError, match="lambda"):
        entropy_ablation.Config(lambdas=(0.0, -1.0))


@pytest.mark.parametrize("seed", range(3))
def test_nearest_distance_is_distance_to_sets(task, seed):
    """The entropy term's distance: distance_to_sets_torch's value to the bit, its gradient to rounding."""
    from lasa.method.belief import distance_to_sets_torch, nearest_distance

    goal_sets = torch.as_tensor(task.preference_sets, dtype=torch.float32)
    rng = np.random.default_rng(seed)
    lo, hi = task.robot.lower, task.robot.upper
    # states of the workspace, and points on the sets' vertices and segments (ties between segments)
    near = goal_sets.reshape(-1, goal_sets.shape[-1]).numpy()
    mid = 0.5 * (near[:-1] + near[1:])
    pts = np.concatenate(
        [rng.uniform(lo, hi, (500, len(lo))), near, mid, near + 1e-4 * rng.normal(size=near.shape)]
    )
    points = torch.tensor(pts, dtype=torch.float32).reshape(-1, 1, len(lo)).requires_grad_()
    weight = torch.as_tensor(rng.normal(size=(len(pts), 1, goal_sets.shape[0])), dtype=torch.float32)
    ref = distance_to_sets_torch(points, goal_sets)
    (ref_grad,) = torch.autograd.grad((ref * weight).sum(), points)
    out = nearest_distance(points, goal_sets)
    (grad,) = torch.autograd.grad((out * weight).sum(), points)
    assert out.shape == ref.shape and torch.equal(out, ref)
    torch.testing.assert_close(grad, ref_grad, rtol=0, atol=1e-6)


def test_runs_spread_over_worker_processes_train_the_same_decoders(model, demos, task):
    """train_all: two worker processes give the decoders one process gives, bit for bit."""
    from lasa.experiments import entropy_ablation

    ctl = task.robot.control
    goal_sets = belief_targets(task, ctl.likelihood)
    runs = [
        entropy_ablation.Run(
            demos, ctl, dataclasses.replace(SMALL_TRAIN, steps=15, entropy_lambda=lam), goal_sets, model
        )
        for lam in (0.0, 0.3, 1.0)
    ]
    here = entropy_ablation.train_all(runs, jobs=1)
    spread = entropy_ablation.train_all(runs, jobs=2)
    for (a, _), (b, _) in zip(here, spread, strict=True):
        sa, sb = a.state_dict(), b.state_dict()
        assert all(torch.equal(sa[k], sb[k]) for k in sa)
    assert not torch.equal(
        here[0][0].state_dict()["decoder.0.weight"], here[1][0].state_dict()["decoder.0.weight"]
    )


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), rows=st.integers(1, 60), block=st.integers(1, 17))
def test_candidates_in_blocks_give_the_reference_distance(seed, rows, block):
    """nearest_distance, whatever the row blocks of its candidate search: the reference's value to the bit.

    Random polylines, and points anywhere, on their vertices and at their segments' midpoints
    (ties between segments).
    """
    from lasa.method import belief

    rng = np.random.default_rng(seed)
    sets = torch.as_tensor(rng.normal(size=(3, 6, 7)), dtype=torch.float32)
    verts = sets.reshape(-1, 7).numpy()
    pick = rng.integers(0, len(verts) - 1, rows)
    kind = rng.integers(0, 3, rows)[:, None]
    mid = 0.5 * (verts[pick] + verts[pick + 1])
    pts = np.where(kind == 0, rng.normal(size=(rows, 7)), np.where(kind == 1, verts[pick], mid))
    points = torch.as_tensor(pts, dtype=torch.float32)
    with mock.patch.object(belief, "_CANDIDATE_ROWS", block):
        out = belief.nearest_distance(points, sets)
    assert torch.equal(out, belief.distance_to_sets_torch(points, sets))


def test_confident_contexts_follow_the_cap_and_an_empty_selection_names_the_setting(demos):
    """Without a cap a context is confident above 0.99; under the study's 0.99 cap above 0.98 (a capped
    belief never exceeds 0.99, so '> 0.99' would select nothing); none selected: a named error."""
    from lasa.base.errors import EmptySelectionError
    from lasa.experiments.entropy_ablation import confident_contexts

    clean = demos.clean()
    top = clean.beliefs.max(axis=1)
    states, beliefs = confident_contexts(demos, None, every=1)
    assert len(states) == int((top > 0.99).sum()) > 0 and (beliefs.max(axis=1) > 0.99).all()
    capped = dataclasses.replace(demos, beliefs=np.minimum(demos.beliefs, 0.985))  # as if capped below 0.99
    _, beliefs = confident_contexts(capped, 0.99, every=1)
    assert len(beliefs) > 0 and (beliefs.max(axis=1) > 0.98).all()
    with pytest.raises(EmptySelectionError, match="belief_cap 0.999 less 0.01.*belief_cap"):
        confident_contexts(capped, 0.999)
