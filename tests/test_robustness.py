"""The verdict map (lasa.experiments.robustness) and its scale-out (lasa.pipeline.scaleout)."""

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence.decision import WORDS
from lasa.experiments import robustness
from lasa.pipeline.scaleout import run_jobs, scheduler_address

TINY = robustness.Config(
    assistance=("point", "grasp_set"),
    alphas=(0.2, 0.5),
    action_scales=(0.375,),
    pilots=("boltzmann", "noisy"),
    betas=(75.0, 1000.0),
    change_steps=(0, 5),
    horizon=10,
    settle=5,
    users=3,
    n_boot=20,
)


def both(model):
    return {"base": model, "entropy": model}


def test_one_at_a_time_cells_vary_one_setting_from_the_default(task):
    cfg = robustness.Config()
    cells = robustness.cells(cfg, task.robot.control)
    assert len(cells) == 1 + (len(cfg.alphas) - 1) + (len(cfg.action_scales) - 1) + (len(cfg.pilots) - 1)
    for c in cells:
        changed = [
            c.alpha != 0.2,
            c.action_scale != 0.375,
            c.pilot != "boltzmann",
        ]
        assert sum(changed) == (c.setting != "default")
    factorial = robustness.cells(dataclasses.replace(cfg, design="factorial"), task.robot.control)
    assert len(factorial) == 3 * 3 * 3 and {c.setting for c in factorial} == {"all"}


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"alphas": (0.0,)}, "alpha"),
        ({"betas": (1.0, 75.0)}, "betas must include 1000"),
        ({"pilots": ("sleepy",)}, "pilot"),
        ({"design": "latin"}, "design"),
        ({"change_steps": (0,)}, "change_steps"),
        ({"assistance": ("magnet",)}, "assistance"),
    ],
)
def test_bad_grid_is_a_clear_error(kw, match):
    with pytest.raises(ConfigError, match=match):
        robustness.Config(**kw)


def test_the_defaults_must_be_on_a_one_at_a_time_grid(task):
    with pytest.raises(ConfigError, match="defaults on its axes"):
        robustness.cells(dataclasses.replace(TINY, alphas=(0.5,)), task.robot.control)


def test_scaled_decoder_scales_the_action_and_nothing_else(model, task):
    rng = np.random.default_rng(0)
    z, s, b = rng.uniform(-1, 1, (4, 1)), np.tile(task.start, (4, 1)), np.full((4, 2), 0.5)
    base = model.decode_numpy(z, s, b)
    np.testing.assert_allclose(robustness.ScaledDecoder(model, 2.0).decode_numpy(z, s, b), 2 * base)
    np.testing.assert_array_equal(robustness.ScaledDecoder(model, 1.0).decode_numpy(z, s, b), base)
    with pytest.raises(ConfigError, match="factor"):
        robustness.ScaledDecoder(model, 0.0)


@pytest.fixture(scope="module")
def local(model, task):
    return robustness.run(both(model), task, task.robot.control, TINY)


def test_grid_rows_per_cell_and_reading(local, task):
    cells = robustness.cells(TINY, task.robot.control)
    assert list(local.columns) == list(robustness.COLUMNS)
    ids = {"sim1.final_error", "sim1.time_ratio", "sim1.gap_narrows", "sim1.entropy_sa"}
    ids |= {"sim2.sa_trapped", "sim2.entropy_escapes", "sim3.entropy_learners"}
    assert set(local.id) == ids
    # the default cell judges every member, the others the headline member only
    members = len(TINY.assistance)
    assert len(local) == len(ids) * (members + len(cells) - 1)
    assert set(local[local.setting != "default"].assistance) == {"point"}
    assert set(local.reproduced) <= {"reproduced", "partly", "not reproduced", "undecided"}
    assert (local.users == TINY.users).all()
    assert (local.level == robustness.LEVEL).all()  # the claims table's level, not 95%
    # undecided only while unsettled; an unsettled row whose interval excludes the paper's number
    # reads "not reproduced"
    assert (~local[local.reproduced == "undecided"].settled.astype(bool)).all()
    assert (local[local.settled.astype(bool)].reproduced != "undecided").all()
    summary = robustness.summary(local)
    words = ["reproduced", "partly", "not reproduced", "undecided"]
    assert (summary[words].sum(axis=1) == members + len(cells) - 1).all()
    lines = robustness.describe(summary)
    assert len(lines) == len(ids) and all(line.startswith("planar5 sim") for line in lines)
    fig = robustness.plot(local)
    assert len(fig.axes) == 1  # one robot
    fig.clf()


def test_the_default_cell_from_the_sims_is_the_default_cell_run_again(local, model, task):
    """Notebook 08 judges its default cell on notebooks 04-06's first look instead of running it:
    with the same users and settings, that is the same verdicts and numbers."""
    sims = robustness._sim_configs(TINY, {"pilot": "boltzmann", "pilot_prob": 0.0})
    control = task.robot.control
    frames = [m.run(both(model), task, control, c, assistance=TINY.assistance)[0] for m, c, _ in sims]
    defaults = robustness.default_frames(TINY, *frames)
    reused = robustness.run(both(model), task, control, TINY, defaults=defaults)
    pd.testing.assert_frame_equal(reused, local)
    with pytest.raises(ConfigError, match="the map's cells need 5"):
        robustness.default_frames(dataclasses.replace(TINY, users=5), *frames)
    with pytest.raises(ConfigError, match="lack beta"):
        robustness.default_frames(dataclasses.replace(TINY, betas=(10.0, 75.0, 1000.0)), *frames)


def test_the_grid_is_deterministic(local, model, task):
    again = robustness.run(both(model), task, task.robot.control, TINY)
    pd.testing.assert_frame_equal(local, again)


def test_a_local_dask_cluster_gives_the_same_csv(local, model, task, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        cfg = dataclasses.replace(TINY, scheduler=cluster.scheduler_address)
        remote = robustness.run(both(model), task, task.robot.control, cfg)
    local.to_csv(tmp_path / "local.csv", index=False)
    remote.to_csv(tmp_path / "dask.csv", index=False)
    assert (tmp_path / "local.csv").read_bytes() == (tmp_path / "dask.csv").read_bytes()


def test_run_jobs_keeps_the_order_and_checks_its_arguments(monkeypatch):
    # a function of the standard library: the worker processes need not import this test module
    assert run_jobs(math.factorial, range(6)) == [1, 1, 2, 6, 24, 120]
    assert run_jobs(math.factorial, range(6), n_jobs=2) == [1, 1, 2, 6, 24, 120]
    with pytest.raises(ConfigError, match="n_jobs"):
        run_jobs(math.factorial, range(2), n_jobs=0)
    monkeypatch.setenv("LASA_SCHEDULER", "tcp://10.0.0.1:8786")
    assert scheduler_address() == "tcp://10.0.0.1:8786"
    assert scheduler_address("tcp://a:1") == "tcp://a:1"  # the config wins over the environment
    monkeypatch.setenv("LASA_SCHEDULER", "localhost")
    with pytest.raises(ConfigError, match="LASA_SCHEDULER"):
        scheduler_address()


def test_an_unreachable_scheduler_is_a_clear_error():
    with pytest.raises(ConfigError, match="cannot reach the Dask scheduler"):
        run_jobs(math.factorial, range(2), scheduler="tcp://127.0.0.1:9", timeout="1s")


def _table(effects: list[tuple[str, str, str]], level: float = robustness.LEVEL) -> pd.DataFrame:
    """Rows of the map's table for one robot: (claim id, reading, effect), the retired one-word
    ``reproduced`` set to another word wherever it can differ, as 18 of the 140 cells once did."""
    other = {"reproduced": "not reproduced", "partly": "reproduced", "undecided": "not reproduced"}
    rows = []
    for i, (claim, member, effect) in enumerate(effects):
        rows.append(
            {
                **dict.fromkeys(robustness.COLUMNS, 0),
                "id": claim,
                "robot": "planar5",
                "assistance": member,
                "alpha": 0.2,
                "action_scale": 0.375,
                "measured": 0.1 * i,
                "reproduced": other.get(effect, effect),
                "settled": effect != "undecided",
                "pilot": "boltzmann",
                "setting": "default",
                "users": 60,
                "effect": effect,
                "number": "n/a",
                "level": level,
            }
        )
    return pd.DataFrame(rows, columns=list(robustness.COLUMNS))


EFFECTS = [
    ("sim1.a", "point", "reproduced"),
    ("sim1.a", "grasp_set", "not reproduced"),
    ("sim1.b", "point", "partly"),
    ("sim1.b", "grasp_set", "undecided"),
    ("sim2.c", "point", "not testable"),
    ("sim2.c", "grasp_set", "reproduced"),
]


def test_the_map_colours_every_cell_by_its_effect_word():
    from matplotlib.colors import to_rgba

    table = _table(EFFECTS)
    fig = robustness.plot(table)
    (ax,) = [a for a in fig.axes if a.images]
    (image,) = ax.images
    rows = [t.get_text() for t in ax.get_yticklabels()]
    columns = [t.get_text() for t in ax.get_xticklabels()]
    assert columns == ["default", "grasp_set"]  # point's default cell, then the other member
    cells = image.get_array()
    for claim, member, effect in EFFECTS:
        r, c = rows.index(claim), columns.index("default" if member == "point" else member)
        drawn = image.cmap(image.norm(cells[r, c]))
        assert drawn == pytest.approx(to_rgba(robustness.COLOURS[effect])), (claim, member, effect)
    # the legend names the five effect words, each in its colour
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == list(WORDS)
    for patch, word in zip(legend.get_patches(), WORDS, strict=True):
        assert patch.get_facecolor() == pytest.approx(to_rgba(robustness.COLOURS[word]))
    # the undecided cell, and only it, is hatched and its number marked
    hatched = [p for p in ax.patches if p.get_hatch()]
    assert [(round(p.get_x() + 0.5), round(p.get_y() + 0.5)) for p in hatched] == [
        (columns.index("grasp_set"), rows.index("sim1.b"))
    ]
    assert sorted(t.get_text() for t in ax.texts if t.get_text().endswith("?")) == ["0.3?"]


def _title_level(fig) -> float:
    import re

    match = re.search(r"\(([\d.]+)% intervals", fig.get_suptitle())
    assert match, fig.get_suptitle()
    return float(match[1]) / 100


def test_the_maps_title_states_the_level_its_cells_were_judged_at():
    from lasa.evidence.verdicts import ALPHA, Looks

    looks = len(Looks().sizes)
    assert robustness.LEVEL == pytest.approx(1 - ALPHA / looks)
    assert _title_level(robustness.plot(_table(EFFECTS))) == pytest.approx(robustness.LEVEL)
    # the title reads the table's level: a table judged at another level says so
    assert _title_level(robustness.plot(_table(EFFECTS, level=0.9))) == pytest.approx(0.9)
    with pytest.raises(ConfigError, match="`level` column"):
        robustness.plot(_table(EFFECTS).drop(columns="level"))
    with pytest.raises(ConfigError, match="one interval level"):
        robustness.plot(pd.concat([_table(EFFECTS[:2]), _table(EFFECTS[2:], level=0.9)]))


def test_the_summary_counts_effect_words():
    table = _table([("sim1.a", m, e) for m, e in [("point", "reproduced"), ("grasp_set", "partly")]])
    (row,) = robustness.summary(table).to_dict("records")
    assert (row["reproduced"], row["partly"], row["not reproduced"]) == (1, 1, 0)
    assert row["default"] == "reproduced" and row["moves"] == "grasp_set partly" and not row["stable"]
