"""Every setting gives an honest answer (issue 48): what a figure or its claims cannot support is
refused at construction, in one line naming the setting, the value and what is allowed.

One test per finding of the issue, with the setting it reports; then a property test drawing list
settings with a repeated or an out-of-order value, which every config must refuse.
"""

import math
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lasa.base.config import ASSISTANCE, check_list, from_dict
from lasa.base.errors import ConfigError
from lasa.experiments import convergence, entropy_ablation, robustness, sim1, sim2, sim3, sim4
from lasa.experiments.sim4.episodes import CLAIM_MAPS
from lasa.experiments.study import run as study
from lasa.method.context_map import MAP_KINDS
from lasa.method.entropy import LAMBDA_COST, choose_lambda
from lasa.method.step import METHODS
from lasa.pipeline.execute import load_config

ROOT = Path(__file__).resolve().parents[1]


def refused(cls, values: dict, match: str) -> str:
    """The one-line error of ``cls`` built from ``values`` as a notebook builds it (from_dict)."""
    with pytest.raises(ConfigError, match=match) as err:
        from_dict(cls, values, where="notebook")
    message = str(err.value)
    assert "\n" not in message and message.startswith("notebook settings: ")
    return message


# Finding 3: 06 with record_every > horizon measured t = 0 alone; one that does not divide it
# left the last step out of the measure.
def test_sim3_refuses_a_record_every_beyond_or_not_dividing_the_horizon():
    refused(
        sim3.Config,
        {"horizon": 40, "record_every": 50},
        r"record_every must be at most horizon \(40\), got 50$",
    )
    refused(
        sim3.Config, {"horizon": 40, "record_every": 15}, r"record_every must divide horizon \(40\).*got 15$"
    )
    assert sim3.Config(horizon=40, record_every=8).record_every == 8
    # notebook 09 records the last step itself: the bound only, the same check
    assert convergence.Config(horizon=12, record_every=5).record_every == 5
    refused(convergence.Config, {"horizon": 10, "record_every": 20}, "record_every must be at most horizon")


# Finding 4: a subset of methods crashed 04 and 05 after the sweep (KeyError: 'LA+SA+Entropy').
@pytest.mark.parametrize("cls", [sim1.Config, sim2.Config, sim3.Config], ids=["sim1", "sim2", "sim3"])
def test_sims_refuse_methods_their_claims_read_left_out(cls):
    message = refused(cls, {"methods": ["LA", "LA+SA"]}, r"methods must include 'LA\+SA\+Entropy'")
    assert "claims" in message and "['LA', 'LA+SA']" in message
    refused(cls, {"methods": ["LA+SA+Entropy"]}, r"must include 'LA', 'LA\+SA' ")
    assert cls(methods=tuple(reversed(METHODS))).methods == tuple(reversed(METHODS))  # any order


# Finding 5: 07 with one offset (or two equal ones) crashed in linregress; with two, R^2 = 1.
@pytest.mark.parametrize("offsets", [[0.08], [0.08, 0.2], [0.08, 0.08, 0.2]])
def test_sim4_needs_three_distinct_offsets(offsets):
    match = (
        "offsets must not repeat"
        if len(set(offsets)) < len(offsets)
        else r"offsets must hold at least 3 distinct"
    )
    message = refused(sim4.Config, {"offsets": offsets}, match)
    assert str(offsets) in message
    if len(offsets) < 3:
        assert "R^2 = 1" in message


def test_the_quick_run_of_07_fits_three_offsets():
    built = from_dict(
        sim4.Config,
        load_config(ROOT / "configs" / "quick.yaml", ROOT / "notebooks" / "07_new_goals.ipynb")["settings"],
    )
    assert len(set(built.offsets)) >= 3


# Finding 6: 07 without grasp died on KeyError after publishing; 04's video_beta outside betas on
# IndexError.
def test_sim4_refuses_maps_without_those_notebook_07_reads():
    refused(sim4.Config, {"maps": ["straight_line", "straight_line_ee"]}, r"maps must include 'grasp' ")
    refused(sim4.Config, {"maps": ["grasp"]}, r"maps must include 'straight_line' ")
    assert sim4.Config(maps=("straight_line", "grasp")).maps == ("straight_line", "grasp")


def test_sim1_refuses_a_video_beta_outside_its_betas():
    message = refused(
        sim1.Config,
        {"betas": [1, 75, 1000], "video_beta": 30},
        r"^notebook settings: video_beta must be one of betas",
    )
    assert "[1.0, 75.0, 1000.0]" in message and "got 30" in message
    assert sim1.Config(betas=(1, 75, 1000), video_beta=1000).video_beta == 1000
    # the claims' betas are refused at construction too, not after the sweep
    refused(
        sim1.Config, {"betas": [1, 75], "video_beta": 75}, r"betas must include 1000 \(Fig. sim1's claims"
    )


# Finding 7: 05 with one change step compared N = 0 with itself.
@pytest.mark.parametrize(
    "steps, match",
    [
        ([0], r"change_steps must hold at least 2 distinct values \(the claims compare the smallest N"),
        ([20, 20], "change_steps must not repeat a value, got \\[20, 20\\]"),
        ([20, 0], r"change_steps must be in ascending order, got \[20, 0\]; sorted: \[0, 20\]"),
    ],
)
def test_sim2_needs_two_distinct_ascending_change_steps(steps, match):
    refused(sim2.Config, {"change_steps": steps}, match)
    refused(robustness.Config, {"change_steps": steps}, match.replace("the claims", "the sim2 claims"))


# Finding 8: beta = 0 and beta = inf were accepted, written to the CSV, dropped by the log axis.
BETA_CONFIGS = [
    (sim1.Config, [0.3, 75, 1000]),
    (robustness.Config, [1, 75, 1000]),
    (convergence.Config, [75, 1000]),
]


@pytest.mark.parametrize("cls, betas", BETA_CONFIGS, ids=["sim1", "robustness", "convergence"])
@pytest.mark.parametrize("bad", [0.0, math.inf])
def test_every_betas_setting_refuses_zero_and_infinity(cls, betas, bad):
    given_ = sorted([bad, *betas])
    k = given_.index(bad)
    message = refused(cls, {"betas": given_}, rf"betas\[{k}\] must be in \(0, inf\), got {bad!r}: ")
    assert message.endswith(
        "the figures' beta axis is logarithmic and Eq. S1's Boltzmann user needs 0 < beta < inf"
    )
    assert cls(betas=tuple(betas)).betas == tuple(float(b) for b in betas)


# Finding 10: duplicated list entries (36 duplicated CSV rows), a "fast" learner slower than the
# "slow" one, an incomplete Latin square, power sizes beyond the cohort, 03's lambda at 8x the cost.
def test_a_duplicated_entry_is_refused():
    message = refused(
        sim1.Config, {"betas": [1, 75, 75, 1000]}, r"^notebook settings: betas must not repeat a value"
    )
    assert message.endswith("got [1, 75, 75, 1000] (75 twice)")
    refused(sim1.Config, {"assistance": ["point", "point"]}, "assistance must not repeat")
    refused(robustness.Config, {"pilots": ["boltzmann", "laggy", "boltzmann"]}, "pilots must not repeat")


def test_the_fast_learner_must_learn_faster_than_the_slow_one():
    refused(
        sim3.Config,
        {"fast_slope": 2.0, "slow_slope": 20.0},
        r"fast_slope must be above slow_slope \(20.0\).*got 2.0$",
    )
    refused(sim3.Config, {"fast_slope": 5.0, "slow_slope": 5.0}, "fast_slope must be above slow_slope")


def test_the_study_warns_of_an_incomplete_square_and_of_power_sizes_beyond_the_cohort():
    with pytest.warns(UserWarning, match=r"^participants = 10 is not a multiple of 4: ") as record:
        study.Config(participants=10, power_sizes=(6, 10))
    assert len(record) == 1 and "\n" not in str(record[0].message)
    with pytest.warns(UserWarning, match=r"^power_sizes \[60\] exceed participants \(40\): ") as record:
        study.Config(participants=40, power_sizes=(10, 40, 60))
    assert len(record) == 1 and "rests on the spread of 40 people" in str(record[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        study.Config(participants=40, power_sizes=(10, 40))  # a full square, sizes within it: silent
    refused(study.Config, {"power_sizes": [10, 6]}, r"power_sizes must be in ascending order")


def _sweep(*rows: tuple[float, float, float]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=["lambda", "entropy_confident", "recon_error"])


def test_the_lambda_rule_keeps_the_control_when_every_lambda_costs_too_much():
    # the lambdas: [0, 1e6], 1e6 at 8x the control's reconstruction error
    table = _sweep((0.0, 0.01, 0.001), (1e6, 0.69, 0.008))
    assert choose_lambda(table, 2) == 0.0
    text = entropy_ablation.findings(table.assign(val_error=[0.002, 0.009]), 0.0, 2)
    assert "The rule keeps the control, λ = 0." in text and "λ = 1e+06, has 8.00× it" in text
    # a lambda just within the bound is still chosen
    assert choose_lambda(_sweep((0.0, 0.01, 0.001), (0.1, 0.69, 0.001 * LAMBDA_COST)), 2) == 0.1


def test_the_paper_scale_sweep_picks_the_same_lambda(task, panda_task):
    """figures/entropy_ablation.csv holds the paper-scale sweeps: 0.1 on both robots, before and after."""
    table = pd.read_csv(ROOT / "figures" / "entropy_ablation.csv")
    sweep = table[table.kind == "sweep"].rename(columns={"entropy": "entropy_confident"})
    for name, t in (("planar5", task), ("panda", panda_task)):
        part = sweep[sweep.robot == name]
        assert len(part) == 5 and choose_lambda(part, t.n_goals) == 0.1


def test_confident_contexts_follow_the_cap_not_a_fixed_threshold():
    beliefs = np.array([[0.985, 0.015], [0.995, 0.005], [0.5, 0.5]])
    demos = type("D", (), {})()
    clean = type("C", (), {"states": np.arange(3.0)[:, None], "beliefs": beliefs, "__len__": lambda s: 3})()
    demos.clean = lambda: clean
    states, _ = entropy_ablation.confident_contexts(demos, None, every=1)
    assert states[:, 0].tolist() == [1.0]  # 0.99 without a cap
    states, _ = entropy_ablation.confident_contexts(demos, 0.99, every=1)
    assert states[:, 0].tolist() == [0.0, 1.0]  # 0.98 under the study's cap


# The property: a list setting with a repeated value, or a numeric grid out of order, is refused
# in one line naming it, whatever else it holds.
def _numbers(low: float, high: float, needed: tuple[float, ...] = (), at_least: int = 1):
    """Valid grids: distinct, ascending, with ``needed``."""
    values = st.lists(st.floats(low, high).map(lambda v: float(f"{v:.4g}")), min_size=at_least, max_size=5)
    return values.map(lambda v: sorted(set(v) | set(needed))).filter(lambda v: len(v) >= at_least)


def _integers(low: int, high: int, needed: tuple[int, ...] = (), at_least: int = 1):
    values = st.lists(st.integers(low, high), min_size=at_least, max_size=5)
    return values.map(lambda v: sorted(set(v) | set(needed))).filter(lambda v: len(v) >= at_least)


def _names(choices: tuple[str, ...], needed: tuple[str, ...] = ()):
    """Valid name lists: distinct, with ``needed``, in any order."""
    subsets = st.lists(st.sampled_from(choices), unique=True, max_size=len(choices))
    return subsets.map(lambda v: list(dict.fromkeys([*needed, *v]))).filter(bool).flatmap(st.permutations)


# (config, setting, valid values, numeric grid)
LISTS = [
    (sim1.Config, "betas", _numbers(0.01, 1e4, sim1.CLAIM_BETAS), True),
    (sim1.Config, "methods", _names(METHODS, METHODS), False),
    (sim1.Config, "assistance", _names(ASSISTANCE), False),
    (sim2.Config, "change_steps", _integers(0, 150, at_least=2), True),
    (sim4.Config, "offsets", _numbers(0.01, 0.3, at_least=3), True),
    (sim4.Config, "maps", _names(MAP_KINDS, CLAIM_MAPS), False),
    (robustness.Config, "alphas", _numbers(0.01, 1.0), True),
    (robustness.Config, "action_scales", _numbers(0.01, 2.0), True),
    (robustness.Config, "betas", _numbers(0.01, 1e4, sim1.CLAIM_BETAS), True),
    (robustness.Config, "change_steps", _integers(0, 150, at_least=2), True),
    (robustness.Config, "pilots", _names(("boltzmann", "laggy", "noisy")), False),
    (convergence.Config, "betas", _numbers(0.01, 1e4), True),
    (convergence.Config, "assistance", _names(ASSISTANCE), False),
    (entropy_ablation.Config, "lambdas", _numbers(0.001, 10.0, (0.0,), at_least=2), True),
    (study.Config, "power_sizes", _integers(2, 40), True),
]


@pytest.mark.parametrize(
    "cls, name, values, grid", LISTS, ids=[f"{c.__module__.rsplit('.', 1)[1]}.{n}" for c, n, _, _ in LISTS]
)
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_a_repeated_or_unsorted_list_setting_is_refused(cls, name, values, grid, data):
    good = data.draw(values, label="valid")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the study's cohort warnings: not what is tested here
        assert list(getattr(from_dict(cls, {name: good}), name)) == good  # valid: built as given
        bad = list(good)
        k = data.draw(st.integers(0, len(bad) - 1), label="repeated")
        bad.insert(data.draw(st.integers(0, len(bad)), label="at"), bad[k])
        if grid and len(good) > 1 and data.draw(st.booleans(), label="unsort instead"):
            bad = list(reversed(good))
        with pytest.raises(
            ConfigError, match=rf"^{name} must (not repeat a value|be in ascending order)"
        ) as err:
            cls(**{name: tuple(bad)})
    assert "\n" not in str(err.value) and str(bad) in str(err.value)


def test_check_list_states_what_it_refuses():
    assert check_list("x", [1, 2, 3], at_least=3, ascending=True) == (1, 2, 3)
    with pytest.raises(ConfigError, match=r"^x must not repeat a value, got \[1, 1.0\] \(1.0 twice\)$"):
        check_list("x", [1, 1.0])
    with pytest.raises(ConfigError, match=r"^x must hold a value, got \[\]$"):
        check_list("x", [])
