"""The study's participant-model dimension and its time figure, on a tiny simulated cohort."""

import matplotlib
import pandas as pd
import pytest
from stand_ins import LinearDecoder

from lasa.base.errors import ConfigError
from lasa.evidence.hypotheses import headline_model
from lasa.experiments.study import analysis, claims, plots
from lasa.experiments.study import run as study
from lasa.people import participants
from lasa.people.design import StudyConfig
from lasa.world.eating import make_eating_task

matplotlib.use("Agg")


@pytest.fixture
def twin(monkeypatch):
    """A second participant model, ``twin``: participants.simulate, its calls recorded."""
    calls = []

    def simulate(*args, **kwargs):
        calls.append(kwargs["interfaces"])
        return participants.simulate(*args, **kwargs)

    monkeypatch.setitem(study.PARTICIPANT_MODELS, "twin", simulate)
    return calls


def test_the_registry_and_the_config_validate_participant_models(twin):
    assert study.PARTICIPANT_MODELS["one_step"] is participants.simulate
    default = study.Config().participant_models
    assert default[-1] == "one_step" and set(default) <= {"planning", "one_step"}
    assert ("planning" in default) == ("planning" in study.PARTICIPANT_MODELS)
    assert study.Config(participant_models=["twin", "one_step"]).participant_models == ("twin", "one_step")
    with pytest.raises(ConfigError, match="participant model 'psychic'"):
        study.Config(participant_models=("one_step", "psychic"))
    with pytest.raises(ConfigError, match="must not repeat"):
        study.Config(participant_models=("one_step", "one_step"))
    with pytest.raises(ConfigError, match="must name at least one"):
        study.Config(participant_models=())


def test_run_simulates_each_model_and_labels_its_rows(twin):
    task = make_eating_task()
    config = study.Config(
        participants=2,
        session=StudyConfig(horizon=20, assistance=("hindsight",)),
        participant_models=("one_step", "twin"),
    )
    decoders = {"head": LinearDecoder(0), "other": LinearDecoder(1)}
    episodes, frames = study.run(task, decoders, task.robot.control, config, progress=False)
    assert twin == [("R", "LA"), ("LA",)]  # the headline decoder: every condition; the other: LA only
    assert list(episodes) == ["one_step", "twin"] and list(episodes["twin"]) == ["head", "other"]
    time = frames["time"]
    assert list(dict.fromkeys(time.model)) == ["one_step", "twin"]
    assert set(plots.ROW_KEYS) <= set(time.columns) and "model" in plots.ROW_KEYS
    for spec in (plots.GOAL_ERROR, plots.TIME, plots.ALIGNMENT):
        assert set(spec.COLUMNS) <= set(frames[spec.NAME.removeprefix("study_")].columns)
    per_model = 2 * (4 + 2) * 2  # participants x (4 arms of the headline + LA, LA+SA of the other) x tasks
    assert len(time) == 2 * per_model
    one, two = (
        time[time.model == m].drop(columns="model").reset_index(drop=True) for m in ("one_step", "twin")
    )
    pd.testing.assert_frame_equal(one, two)  # the same simulate, seed and cohort: the same episodes
    rows, analyses = claims.claims(frames, config.session.assistance, 2, ("head", "other"), horizon=2.0)
    ids = {c.id for c in rows}
    assert {"study.h3", "study.h3@twin", "study.h2@other+twin", "study.h1@mean_distance+twin"} <= ids
    # 20 steps of 0.1 s: nobody finishes, so H3 is not testable under each model
    assert {c.reproduced for c in rows if c.id.startswith("study.h3")} == {"not testable"}
    done = analysis.completion(time)
    assert set(done.model) == {"one_step", "twin"} and (done.finished == 0).all()


def test_a_model_limited_to_the_first_readings_runs_and_is_judged_on_those_only(twin):
    task = make_eating_task()
    config = study.Config(
        participants=2,
        session=StudyConfig(horizon=20, assistance=("hindsight",)),
        participant_models=("one_step", "twin"),
        variants_per_model={"twin": 1},
    )
    decoders = {"head": LinearDecoder(0), "other": LinearDecoder(1)}
    episodes, frames = study.run(task, decoders, task.robot.control, config, progress=False)
    assert twin == [("R", "LA")] and list(episodes["twin"]) == ["head"]
    time = frames["time"]
    assert set(time[time.model == "twin"].decoder) == {"head", "none"}
    rows, _ = claims.claims(frames, config.session.assistance, 2, ("head", "other"), horizon=2.0)
    ids = {c.id for c in rows}
    assert {"study.h3@twin", "study.h2@other"} <= ids and not any("other+twin" in i for i in ids)
    with pytest.raises(ConfigError, match="variants_per_model"):
        study.Config(variants_per_model={"psychic": 1})


def test_plot_time_hatches_censored_bars_and_says_how_many_finished():
    rows = []
    for p in range(4):
        for cond in ("R", "R+SA", "LA", "LA+SA"):
            asst = "hindsight" if "+" in cond else "none"
            for task in ("Entree", "Dessert"):
                done = cond.startswith("R") or (cond == "LA+SA" and p < 2)  # LA 0%, LA+SA 50%
                t = 30.0 if done else 150.0
                rows.append(
                    {
                        "participant": p,
                        "condition": cond,
                        "assistance": asst,
                        "decoder": "none",
                        "task": task,
                        "total_time": t,
                        "idle_time": t / 3,
                        "completed": done,
                    }
                )
    fig = plots.plot_time(pd.DataFrame(rows))
    for ax in fig.axes:
        labels = sorted(t.get_text() for t in ax.texts)
        assert labels == ["0% done", "100% done", "100% done", "50% done"]
        hatched = [p for p in ax.patches if p.get_hatch()]
        assert len(hatched) == 2 and all(p.get_height() > 30 for p in hatched)  # LA and LA+SA only
    legend = " ".join(t.get_text() for leg in fig.legends for t in leg.get_texts())
    assert "censored at the 150 s horizon" in legend


def test_headline_model_is_the_first_whose_retargeting_episodes_finish() -> None:
    def rows(model: str, finished: dict[str, list[bool]]) -> list[dict[str, object]]:
        return [
            {
                "model": model,
                "condition": c,
                "assistance": "none" if c in ("R", "LA") else "hindsight",
                "completed": f,
            }
            for c, flags in finished.items()
            for f in flags
        ]

    ok = {"R": [True] * 20, "R+SA": [True] * 19 + [False], "LA": [False] * 20}  # LA plays no part
    short = {"R": [True] * 18 + [False] * 2, "R+SA": [True] * 20}  # R: 90%
    time = pd.DataFrame(rows("planning", short) + rows("one_step", ok))
    assert headline_model(time, ("planning", "one_step")) == "one_step"
    time = pd.DataFrame(rows("planning", ok) + rows("one_step", ok))
    assert headline_model(time, ("planning", "one_step")) == "planning"
    time = pd.DataFrame(rows("planning", short) + rows("one_step", short))
    assert headline_model(time, ("planning", "one_step")) == "planning"  # none qualifies: the first
    with pytest.raises(ConfigError, match="at least one"):
        headline_model(time, ())
