"""Figs. sim1-sim3 (lasa.experiments.sim1-3): columns, determinism, pairing, and the claims' rules."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.experiments import sim1, sim2, sim3

ONE = {"assistance": ("point",)}  # the headline member only: the bare sweep
SMALL = sim1.Config(betas=(1.0, 75.0, 1000.0), users=3, horizon=20, seed=0, **ONE)


def test_sim1_frame_columns_and_size(model, task):
    frame, traj = sim1.run(both(model), task, task.robot.control, SMALL)
    assert set(sim1.COLUMNS) <= set(frame.columns)
    assert len(frame) == 3 * 3 * 3 == traj.states.shape[1]
    assert set(frame.method) == {"LA", "LA+SA", "LA+SA+Entropy"}
    assert frame.final_error.ge(0).all() and frame.time.between(0, SMALL.horizon).all()
    # paired design: a seed has the same cup and preference under every condition
    assert frame.groupby("seed")[["goal", "theta"]].nunique().eq(1).all().all()


def test_same_seed_gives_identical_csv(model, task, tmp_path):
    a, _ = sim1.run(both(model), task, task.robot.control, SMALL)
    b, _ = sim1.run(both(model), task, task.robot.control, SMALL)
    a.to_csv(tmp_path / "a.csv", index=False)
    b.to_csv(tmp_path / "b.csv", index=False)
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"betas": (-1.0,)}, "beta"),
        ({"methods": ("LA", "SA")}, "unknown method"),
        ({"users": 0}, "users"),
        ({"users": 200}, "must not exceed cap"),
        ({"tolerance": 0.0}, "tolerance"),
    ],
)
def test_bad_sweep_is_a_clear_error(kw, match):
    with pytest.raises(ConfigError, match=match):
        sim1.Config(**kw)


def synthetic(err_la, err_sa, t_la, t_sa):
    rows = []
    for beta, el, es, tl, ts in zip((10.0, 75.0, 1000.0), err_la, err_sa, t_la, t_sa, strict=True):
        rows += [
            dict(robot="planar5", method="LA", beta=beta, final_error=el, time=tl),
            dict(robot="planar5", method="LA+SA", beta=beta, final_error=es, time=ts),
        ]
    return pd.DataFrame(rows)


def test_claim_rules_reproduced_case():
    claims = sim1._sa_claims(synthetic([0.3, 0.2, 0.1], [0.2, 0.1, 0.08], [100, 145, 130], [90, 100, 100]))
    assert [c.reproduced for c in claims] == ["yes", "yes", "yes"]
    assert "1.45" in claims[1].measured and "1.30" in claims[1].measured


def test_claim_rules_failed_case():
    claims = sim1._sa_claims(synthetic([0.1, 0.1, 0.1], [0.2, 0.2, 0.2], [100, 90, 90], [100, 100, 100]))
    assert [c.reproduced for c in claims] == ["no", "no", "no"]


def test_claim_rules_partial_case():
    claims = sim1._sa_claims(synthetic([0.3, 0.2, 0.1], [0.2, 0.1, 0.2], [100, 200, 110], [90, 100, 100]))
    assert claims[0].reproduced == "partly"  # lower at 2 of 3 betas
    # the effect: LA slower at both betas (ratios 2.0 and 1.1), however far from the paper's sizes
    assert claims[1].reproduced == "yes" and claims[1].values["ratio_75"] == pytest.approx(2.0)
    slow_at_one = sim1._sa_claims(synthetic([0.3, 0.2, 0.1], [0.2, 0.1, 0.2], [100, 200, 90], [90, 100, 100]))
    assert slow_at_one[1].reproduced == "partly"  # LA slower at beta = 75 only


def test_claims_need_the_papers_betas():
    frame = synthetic([0.3, 0.2, 0.1], [0.2, 0.1, 0.08], [1, 1, 1], [1, 1, 1])
    with pytest.raises(ConfigError, match="beta = 75"):
        sim1._sa_claims(frame[frame.beta != 75.0])


def test_same_seed_gives_identical_csv_on_the_panda(panda_model, panda_task, tmp_path):
    ctl = panda_task.robot.control
    a, traj = sim1.run(both(panda_model), panda_task, ctl, SMALL)
    b, _ = sim1.run(both(panda_model), panda_task, ctl, SMALL)
    a.to_csv(tmp_path / "a.csv", index=False)
    b.to_csv(tmp_path / "b.csv", index=False)
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert set(a.robot) == {"panda"}
    robot = panda_task.robot
    assert np.all(traj.states >= robot.lower) and np.all(traj.states <= robot.upper)


def test_a_panda_decoder_is_refused_for_the_planar_task(panda_model, task):
    with pytest.raises(ConfigError, match="trained for 'panda'"):
        sim1.run(both(panda_model), task, task.robot.control, SMALL)


def both(model):
    """Both decoders; the tests reuse one model for each, which exercises the plumbing."""
    return {"base": model, "entropy": model}


def test_sim1_with_three_methods_runs_one_rollout_per_decoder(model, task, monkeypatch):
    from lasa.experiments import sweep

    calls = []
    real = sweep.rollout

    def counted(decoder, task_, users, alpha, *args, **kwargs):
        calls.append((id(decoder), len(alpha), sorted(set(np.round(alpha, 6)))))
        return real(decoder, task_, users, alpha, *args, **kwargs)

    monkeypatch.setattr(sweep, "rollout", counted)
    decoders = both(model)
    frame, traj = sim1.run(
        decoders, task, task.robot.control, sim1.Config(betas=(75.0, 1000.0), users=2, horizon=10, **ONE)
    )
    assert set(frame.method) == {"LA", "LA+SA", "LA+SA+Entropy"}
    # two decoders, two batched rollouts: LA and LA+SA share the lambda = 0 decoder's, the entropy
    # method has its own; every (method, beta, user) episode rides in one of them
    alpha = task.robot.control.alpha
    assert len(calls) == 2
    assert [c[2] for c in calls] == [[0.0, round(alpha, 6)], [round(alpha, 6)]]
    assert sum(c[1] for c in calls) == len(frame) == 3 * 2 * 2
    # the entropy rows used the same model here, with LA+SA's alpha: identical episodes
    a = frame[frame.method == "LA+SA"].final_error.to_numpy()
    b = frame[frame.method == "LA+SA+Entropy"].final_error.to_numpy()
    np.testing.assert_allclose(a, b)


def test_a_missing_decoder_is_a_clear_error(model, task):
    with pytest.raises(ConfigError, match="need the 'entropy' decoder"):
        sim1.run(model, task, task.robot.control, sim1.Config(betas=(75.0, 1000.0), users=1, horizon=5))


def test_sim2_frame(model, task):
    cfg = sim2.Config(change_steps=(0, 5), users=2, settle=10, **ONE)
    frame, traj = sim2.run(both(model), task, task.robot.control, cfg)
    assert set(sim2.COLUMNS) <= set(frame.columns)
    assert len(frame) == 3 * 2 * 2 and traj.states.shape[0] == cfg.horizon + 1 == 16
    assert frame.confidence.between(0, 1).all()


def test_sim2s_wrong_goal_is_the_next_cup_for_any_number_of_cups(model, task):
    assert [sim2.wrong_goal(g, 2) for g in range(2)] == [1, 0]
    assert [sim2.wrong_goal(g, 3) for g in range(3)] == [1, 2, 0]
    with pytest.raises(ConfigError, match="goal must be in"):
        sim2.wrong_goal(2, 2)
    cfg = sim2.Config(change_steps=(0, 5), users=2, settle=10, **ONE)
    frame, traj = sim2.run(both(model), task, task.robot.control, cfg)
    first = frame[frame.change_step == 5].index  # these users aim at the wrong cup first
    wrong = task.target(
        [sim2.wrong_goal(int(g), task.n_goals) for g in frame.goal[first]], frame.theta[first]
    )
    right = task.target(frame.goal[first].to_numpy(), frame.theta[first].to_numpy())
    moved = traj.states[4, first] - traj.states[0, first]  # the first 4 steps go towards the wrong cup
    toward = np.einsum("un,un->u", moved, wrong - traj.states[0, first])
    assert (toward > np.einsum("un,un->u", moved, right - traj.states[0, first])).mean() > 0.5


def test_sim3_frame(model, task):
    cfg = sim3.Config(users=2, horizon=10, record_every=5, **ONE)
    frame, _ = sim3.run(both(model), task, task.robot.control, cfg)
    assert list(frame.columns) == list(sim3.COLUMNS)
    assert set(frame.learner) == {"fast", "slow"} and set(frame.t) == {0, 5, 10}
    assert len(frame) == 3 * 2 * 2 * 3
    # everyone starts at home: the error at t = 0 is the distance from home to some s*(g, theta),
    # over the goal distance; here bounded by every goal's curve on a fine theta grid
    grid = np.linspace(0.0, 1.0, 401)
    reach = np.linalg.norm(task.start - task.target(np.repeat([0, 1], len(grid)), np.tile(grid, 2)), axis=-1)
    low, high = reach.min() / task.goal_distance, reach.max() / task.goal_distance
    start = frame[frame.t == 0]
    assert start.error.between(low - 1e-9, high + 1e-9).all() and start.error.nunique() > 1


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"change_steps": (5, -1)}, r"^change_steps\[1\] must be an integer >= 0, got -1$"),
        ({"change_steps": (1.5,)}, r"^change_steps\[0\] must be an integer >= 0, got 1.5$"),
        ({"beta": -1.0}, "beta"),
    ],
)
def test_bad_sim2_config(kw, match):
    with pytest.raises(ConfigError, match=match):
        sim2.Config(**kw)


def test_sims_1_to_3_share_one_sweep_config_and_a_bad_setting_names_its_notebook():
    from lasa.base.config import from_dict
    from lasa.experiments.sweep import SweepConfig

    shared = {f.name for f in dataclasses.fields(SweepConfig)}
    for sim in (sim1, sim2, sim3):
        assert issubclass(sim.Config, SweepConfig)
        own = {f.name for f in dataclasses.fields(sim.Config)} - shared
        assert own and not own & shared  # each adds only its own sweep
    with pytest.raises(ConfigError) as err:
        from_dict(sim1.Config, {"betas": "x"}, where="notebook 04_fixed_expertise")
    assert str(err.value) == (
        "notebook 04_fixed_expertise settings: betas must be a list, each a number in (0, inf), got 'x': "
        "the figures' beta axis is logarithmic and Eq. S1's Boltzmann user needs 0 < beta < inf"
    )
    with pytest.raises(ConfigError, match=r"^betas\[1\] must be a number in \(0, inf\), got 'x': the "):
        sim1.Config(betas=(1.0, "x"))
    with pytest.raises(ConfigError, match=r"^notebook 06 settings: users must be an integer >= 1, got 0$"):
        from_dict(sim3.Config, {"users": 0}, where="notebook 06")


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"fast_slope": -1.0}, "fast_slope"),
        ({"slow_slope": 0.0}, "slow_slope"),
        ({"record_every": 0}, "record_every"),
    ],
)
def test_bad_sim3_config(kw, match):
    with pytest.raises(ConfigError, match=match):
        sim3.Config(**kw)


def sim2_frame(rates):
    """Synthetic sim2 rows: rates[method] = (success at N=0, success at N=100)."""
    rows = []
    for method, (lo, hi) in rates.items():
        for n, rate in ((0, lo), (100, hi)):
            for i in range(10):
                ok = i < round(10 * rate)
                rows.append(
                    dict(
                        robot="planar5",
                        method=method,
                        change_step=n,
                        seed=i,
                        final_error=0.01 if ok else 0.8,
                        confidence=1.0 if ok else 0.0,
                        success=ok,
                    )
                )
    return pd.DataFrame(rows)


def test_sim2_claim_rules():
    trapped = sim2.claims(sim2_frame({"LA+SA": (1.0, 0.2), "LA+SA+Entropy": (1.0, 0.9)}))
    assert [c.reproduced for c in trapped] == ["yes", "yes"]
    mild = sim2.claims(sim2_frame({"LA+SA": (1.0, 0.7), "LA+SA+Entropy": (1.0, 0.8)}))
    # sa_trapped judges the paper's two parts: the error grows and the confidence falls with N
    assert [c.reproduced for c in mild] == ["yes", "partly"]
    none = sim2.claims(sim2_frame({"LA+SA": (1.0, 1.0), "LA+SA+Entropy": (1.0, 0.9)}))
    assert [c.reproduced for c in none] == ["no", "no"]


def test_sim3_claim_rule():
    rows = []
    for learner, (sa, en) in {"fast": (0.2, 0.1), "slow": (0.3, 0.4)}.items():
        for method, err in (("LA", 0.5), ("LA+SA", sa), ("LA+SA+Entropy", en)):
            rows += [
                dict(robot="panda", method=method, learner=learner, slope=1.0, seed=0, t=t, error=err)
                for t in (0, 5)
            ]
    claim = sim3.claims(pd.DataFrame(rows))[0]
    assert claim.reproduced == "partly" and claim.robot == "panda"


def test_sim1_entropy_claim_rule():
    rows = []
    for beta, (la, sa, en) in {75.0: (0.3, 0.2, 0.25), 1000.0: (0.1, 0.05, 0.2)}.items():
        for method, err in (("LA", la), ("LA+SA", sa), ("LA+SA+Entropy", en)):
            rows.append(dict(robot="planar5", method=method, beta=beta, final_error=err, time=1.0))
    entropy = sim1.claims(pd.DataFrame(rows))[-1]
    assert entropy.id == "sim1.entropy_sa" and entropy.reproduced == "no"  # entropy below LA at 1 of 2


def test_sim1_claims_have_stable_ids():
    claims = sim1.claims(
        pd.DataFrame(
            [
                dict(robot="planar5", method=m, beta=b, final_error=e, time=t)
                for b in (75.0, 1000.0)
                for m, e, t in (("LA", 0.2, 100), ("LA+SA", 0.1, 80), ("LA+SA+Entropy", 0.15, 90))
            ]
        )
    )
    assert [c.id for c in claims] == [
        "sim1.final_error",
        "sim1.time_ratio",
        "sim1.gap_narrows",
        "sim1.entropy_sa",
    ]


def test_members_and_draws_share_la_and_keep_the_headline_bitwise(model, task):
    """LA runs once (assistance 'none'); the headline member's rows equal a run of it alone."""
    ctl = task.robot.control
    cfg = sim1.Config(betas=(75.0, 1000.0), users=4, horizon=15, assistance=("point", "hindsight"))
    frame, _ = sim1.run(both(model), task, ctl, cfg)
    la = frame[frame.method == "LA"]
    assert set(la.assistance) == {"none"} and len(la) == 2 * 4
    assert set(frame[frame.method != "LA"].assistance) == {"point", "hindsight"}
    assert len(frame) == (1 + 2 * 2) * 2 * 4
    assert (frame.look == 0).all()
    alone, _ = sim1.run(both(model), task, ctl, dataclasses.replace(cfg, assistance=("point",)))
    head = frame[frame.assistance.isin(["none", "point"])].reset_index(drop=True)
    pd.testing.assert_frame_equal(head, alone.reset_index(drop=True))
    # the headline member is always run, first, even if the config leaves it out
    other, _ = sim1.run(both(model), task, ctl, dataclasses.replace(cfg, assistance=("hindsight",)))
    assert list(dict.fromkeys(other.assistance)) == ["none", "point", "hindsight"]


def test_a_laggy_pilot_that_always_lags_never_moves_the_stick(model, task):
    cfg = sim3.Config(users=3, horizon=10, pilot="laggy", pilot_prob=1.0, **ONE)
    _, traj = sim3.run(both(model), task, task.robot.control, cfg)
    assert (traj.z == traj.z[:1]).all()  # every later input repeats the first
    _, boltzmann = sim3.run(both(model), task, task.robot.control, dataclasses.replace(cfg, pilot_prob=0.0))
    assert not (boltzmann.z == boltzmann.z[:1]).all()


@pytest.mark.parametrize("kw,match", [({"pilot": "sleepy"}, "pilot"), ({"pilot_prob": 1.5}, "pilot_prob")])
def test_bad_pilot_is_a_clear_error(kw, match):
    with pytest.raises(ConfigError, match=match):
        sim1.Config(**kw)


def test_a_later_look_adds_new_users_of_its_own_stream(model, task):
    ctl = task.robot.control
    cfg = sim1.Config(
        betas=(75.0, 1000.0), users=3, block=2, cap=5, horizon=10, assistance=("point", "hindsight")
    )
    first, _ = sim1.run(both(model), task, ctl, cfg)
    later, _ = sim1.run(both(model), task, ctl, cfg, look=1, assistance=("point",))
    assert sorted(set(first.seed)) == [0, 1, 2] and sorted(set(later.seed)) == [3, 4]
    assert (later.look == 1).all() and set(later.assistance) == {"none", "point"}
    # a look's users do not depend on the looks after it: the first look is the same with a bigger cap
    again, _ = sim1.run(both(model), task, ctl, dataclasses.replace(cfg, cap=9))
    pd.testing.assert_frame_equal(first, again)


def test_judge_runs_looks_until_settled_or_the_cap(model, task):
    from lasa.experiments.sweep import judge

    cfg = sim1.Config(
        betas=(75.0, 1000.0),
        users=2,
        block=2,
        cap=4,
        horizon=10,
        n_boot=20,
        assistance=("point", "hindsight"),
    )
    frame, outcome, traj = judge(sim1, both(model), task, task.robot.control, cfg)
    heads = [c for c in outcome.claims if "@" not in c.id]
    others = [c for c in outcome.claims if "@" in c.id]
    assert [c.id for c in heads] == [
        "sim1.final_error",
        "sim1.time_ratio",
        "sim1.gap_narrows",
        "sim1.entropy_sa",
    ]
    assert {c.id.split("@")[1] for c in others} == {"hindsight"} and all(c.n_users == 2 for c in others)
    n = heads[0].n_users
    # 2 users can settle nothing (verdicts.MIN_USERS): the looks run to the cap, every verdict open
    assert n == 4 and all(c.n_users == n for c in heads)
    assert not any(c.settled for c in outcome.claims)
    assert frame.seed.nunique() == n and traj.states.shape[1] == (frame.look == 0).sum()
    assert set(frame[frame.look > 0].assistance) <= {"none", "point"}


@pytest.mark.parametrize("name", ["sim1", "sim2", "sim3"])
def test_the_vectorized_bootstrap_gives_the_resampled_frames_numbers(model, task, name):
    """boot_values (group means from resample counts) = claims() on each resampled frame."""
    from lasa.evidence.verdicts import assess, member_frame

    module = {"sim1": sim1, "sim2": sim2, "sim3": sim3}[name]
    small = {
        "sim1": sim1.Config(betas=(1.0, 75.0, 1000.0), users=6, horizon=25, **ONE),
        "sim2": sim2.Config(change_steps=(0, 5), users=6, settle=20, **ONE),
        "sim3": sim3.Config(users=6, horizon=25, **ONE),
    }[name]
    frame, _ = module.run(both(model), task, task.robot.control, small)
    frame = member_frame(sim3.episode_means(frame) if name == "sim3" else frame, "point")
    slow = assess(module.claims, frame, n_boot=60, seed=3)
    fast = assess(module.claims, frame, n_boot=60, seed=3, fast=module.boot_values)
    for a, b in zip(slow, fast, strict=True):
        assert (a.id, a.reproduced, a.settled) == (b.id, b.reproduced, b.settled)
        np.testing.assert_allclose([a.ci_low, a.ci_high], [b.ci_low, b.ci_high], rtol=1e-9, atol=1e-12)
        assert a.note == b.note  # every number's interval, as printed


def test_sim2_after_the_change_measures_the_wrong_cup(model, task):
    cfg = sim2.Config(change_steps=(0, 5), users=2, settle=10, **ONE)
    frame, traj = sim2.run(both(model), task, task.robot.control, cfg)
    after = sim2.after_the_change(frame, traj, task, cfg.success)
    goal, theta = after.goal.to_numpy(), after.theta.to_numpy()
    wrong = task.target(sim2.wrong_goal(goal, task.n_goals), theta)
    apart = np.linalg.norm(task.target(goal, theta) - wrong, axis=-1) / task.goal_distance
    # the triangle through the end state, the user's grasp and the wrong cup's grasp
    assert (np.abs(after.wrong_error - after.final_error) <= apart + 1e-9).all()
    assert (apart <= after.wrong_error + after.final_error + 1e-9).all()
    assert (after.steps_left == cfg.horizon - after.change_step).all()
