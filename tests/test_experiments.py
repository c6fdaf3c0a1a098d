"""Fig. sim1 sweep: columns, determinism, pairing, and the claims' decision rules."""

import numpy as np
import pandas as pd
import pytest

from lasa.errors import ConfigError
from lasa.experiments import SIM1_COLUMNS, Sim1Config, run_fixed_expertise, sim1_claims

SMALL = Sim1Config(betas=(1.0, 75.0, 1000.0), n_seeds=3, horizon=20, seed=0)


def test_sim1_frame_columns_and_size(model, task):
    frame, traj = run_fixed_expertise(model, task, task.robot.control, SMALL)
    assert set(SIM1_COLUMNS) <= set(frame.columns)
    assert len(frame) == 2 * 3 * 3 == traj.states.shape[1]
    assert set(frame.method) == {"LA", "LA+SA"}
    assert frame.final_error.ge(0).all() and frame.time.between(0, SMALL.horizon).all()
    # paired design: a seed has the same cup and preference under every condition
    assert frame.groupby("seed")[["goal", "theta"]].nunique().eq(1).all().all()


def test_same_seed_gives_identical_csv(model, task, tmp_path):
    a, _ = run_fixed_expertise(model, task, task.robot.control, SMALL)
    b, _ = run_fixed_expertise(model, task, task.robot.control, SMALL)
    a.to_csv(tmp_path / "a.csv", index=False)
    b.to_csv(tmp_path / "b.csv", index=False)
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"betas": (-1.0,)}, "beta"),
        ({"methods": ("LA", "SA")}, "unknown method"),
        ({"n_seeds": 0}, "n_seeds"),
        ({"tolerance": 0.0}, "tolerance"),
    ],
)
def test_bad_sweep_is_a_clear_error(kw, match):
    with pytest.raises(ConfigError, match=match):
        Sim1Config(**kw)


def synthetic(err_la, err_sa, t_la, t_sa):
    rows = []
    for beta, el, es, tl, ts in zip((10.0, 75.0, 1000.0), err_la, err_sa, t_la, t_sa, strict=True):
        rows += [
            dict(robot="planar5", method="LA", beta=beta, final_error=el, time=tl),
            dict(robot="planar5", method="LA+SA", beta=beta, final_error=es, time=ts),
        ]
    return pd.DataFrame(rows)


def test_claim_rules_reproduced_case():
    claims = sim1_claims(synthetic([0.3, 0.2, 0.1], [0.2, 0.1, 0.08], [100, 145, 130], [90, 100, 100]))
    assert [c.reproduced for c in claims] == ["yes", "yes", "yes"]
    assert "1.45" in claims[1].measured and "1.30" in claims[1].measured


def test_claim_rules_failed_case():
    claims = sim1_claims(synthetic([0.1, 0.1, 0.1], [0.2, 0.2, 0.2], [100, 90, 90], [100, 100, 100]))
    assert [c.reproduced for c in claims] == ["no", "no", "no"]


def test_claim_rules_partial_case():
    claims = sim1_claims(synthetic([0.3, 0.2, 0.1], [0.2, 0.1, 0.2], [100, 200, 110], [90, 100, 100]))
    assert claims[0].reproduced == "partly"  # lower at 2 of 3 betas
    assert claims[1].reproduced == "partly"  # both ratios > 1 but far from the paper's


def test_claims_need_the_papers_betas():
    frame = synthetic([0.3, 0.2, 0.1], [0.2, 0.1, 0.08], [1, 1, 1], [1, 1, 1])
    with pytest.raises(ConfigError, match="beta = 75"):
        sim1_claims(frame[frame.beta != 75.0])


def test_same_seed_gives_identical_csv_on_the_panda(panda_model, panda_task, tmp_path):
    ctl = panda_task.robot.control
    a, traj = run_fixed_expertise(panda_model, panda_task, ctl, SMALL)
    b, _ = run_fixed_expertise(panda_model, panda_task, ctl, SMALL)
    a.to_csv(tmp_path / "a.csv", index=False)
    b.to_csv(tmp_path / "b.csv", index=False)
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert set(a.robot) == {"panda"}
    robot = panda_task.robot
    assert np.all(traj.states >= robot.lower) and np.all(traj.states <= robot.upper)


def test_a_panda_decoder_is_refused_for_the_planar_task(panda_model, task):
    with pytest.raises(ConfigError, match="trained for 'panda'"):
        run_fixed_expertise(panda_model, task, task.robot.control, SMALL)
