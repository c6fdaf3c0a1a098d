"""The pre-registration names the hypotheses, measures and exclusions the analysis applies."""

import inspect
import subprocess
import sys
from pathlib import Path

import pytest

from lasa.evidence import sessions
from lasa.evidence.rules import COMPLETION_BAR, rule
from lasa.experiments.study import preregister
from lasa.world import measures

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ROOT / "figures"


@pytest.fixture(scope="module")
def reading_and_table():
    frames = preregister.cohort(FIGURES)
    reading = preregister.headline_reading(FIGURES, frames)
    return reading, preregister.power_table(frames, reading, draws=2, sizes=(6, 10))


@pytest.fixture(scope="module")
def text(reading_and_table):
    reading, table = reading_and_table
    return preregister.document(table, reading, practice_s=240.0, trial_s=150.0)


def test_every_hypothesis_is_stated_with_the_rule_that_judges_it(text):
    assert set(preregister.HYPOTHESES) == {"study.h1", "study.h2", "study.h3"}
    for claim, hypothesis in preregister.HYPOTHESES.items():
        assert hypothesis in text and rule(claim).text in text
    assert f"at least {100 * COMPLETION_BAR:.0f}% of its episodes" in text


def test_every_measure_is_defined_by_the_function_the_analysis_calls(text):
    source = inspect.getsource(measures.measures)
    for name, function in preregister.MEASURES.items():
        assert f"{function.__name__}(" in source  # the tidy tables come from this function
        line = preregister.definition(function)
        assert line.startswith(f"{name}:") and line in text
        assert inspect.getdoc(function).startswith(line.removesuffix(".")), name


def test_the_exclusions_are_the_analysis_own(text, tmp_path):
    for reason in sessions.LEFT_OUT.values():
        assert f"- {reason}" in text
    assert sessions.DROPPED in text
    (tmp_path / "p00_Entree_R_x_a1.json").write_text("{ not json")  # a damaged sidecar
    _, left_out = sessions.scan_sessions(tmp_path)
    assert list(left_out.session) == ["p00_Entree_R_x_a1"]
    assert left_out.reason[0].startswith(sessions.LEFT_OUT["damaged"])


def test_the_sample_size_and_design_come_from_the_power_and_the_settings(reading_and_table, text):
    (assistance, decoder, model), table = reading_and_table
    assert f"`{assistance}`" in text and f"`{decoder}`" in text and f"`{model}`" in text
    for claim, rows in table.groupby("claim"):
        row = rows.sort_values("n")
        assert f"| {claim.upper()} | " + " | ".join(f"{p:.2f}" for p in row.power) + " |" in text
    assert "up to 240 s" in text and "each at most 150 s" in text and "[to fill in]" in text


def test_the_command_writes_the_document(tmp_path):
    out = tmp_path / "prereg.md"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "lasa.experiments.study.preregister",
            "--draws",
            "2",
            "--sizes",
            "6",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert out.read_text().startswith("# Pre-registration") and "## 7. Sample size" in out.read_text()


def test_peoples_sessions_are_judged_by_the_claims_own_tests():
    """hypotheses.people_claims, which notebook 11 applies to people's sessions, is analyse + judge
    over the participants who did every condition: here ten simulated ones, relabelled as people."""
    import pandas as pd

    from lasa.evidence import hypotheses

    frames = {}
    for name in ("goal_error", "time", "alignment"):
        frame = pd.read_csv(FIGURES / f"study_{name}.csv")
        frame = frame[(frame.model == "planning") & frame.decoder.isin(["transfers", "none"])]
        frame = frame[(frame.participant < 10) & frame.assistance.isin(["none", "hindsight"])]
        frames[name] = frame.drop(columns=["model", "decoder"]).assign(
            participant=lambda d: "p" + d.participant.astype(str)
        )
    one_short = {n: f[~((f.participant == "p9") & (f.condition == "LA"))] for n, f in frames.items()}
    table = hypotheses.people_claims(one_short, n_resamples=200)
    kept = {n: f[f.participant != "p9"] for n, f in frames.items()}
    horizon = float(frames["time"].total_time.max())
    direct = hypotheses.judge(hypotheses.analyse(kept, "hindsight", horizon=horizon, n_resamples=200))
    assert list(table.member.unique()) == ["hindsight"] and set(table.participants) == {9}
    for row in table.itertuples():
        assert row.verdict == direct[row.claim][0] and row.measured == direct[row.claim][4]
    assert set(table.claim) >= {"h1", "h2", "h3"} and "likert" not in set(table.claim)  # no answers given
    # the sessions' trial limit (analyse_sessions' `limit`, from their sidecars) is H3's horizon
    limited = hypotheses.people_claims(
        {**one_short, "limit": pd.DataFrame({"limit_s": [60.0]})}, n_resamples=50
    )
    assert "restricted to the 60 s horizon" in limited[limited.claim == "h3"].measured.iloc[0]
    assert hypotheses.people_claims({n: f[f.participant == "p0"] for n, f in frames.items()}).empty
    # with people's Likert answers (lasa.evidence.sessions.likert_tests' table), Fig. dessert's
    # subjective claim gets a row, judged by its rule
    likert = pd.DataFrame({"scale": ["Easy"] * 3, "a": "LA+SA", "b": ["R", "R+SA", "LA"]})
    likert = likert.assign(diff=[1.0, 1.0, -1.0], p_corr=[0.01, 0.2, 0.01])
    judged = hypotheses.people_claims({**one_short, "likert": likert}, n_resamples=200)
    row = judged[judged.claim == "likert"].iloc[0]
    assert (row.verdict, row.value, row.participants) == ("partly", 1 / 3, 9)
    assert row.measured == "LA+SA rated higher with p < .05 in 1 of 3 comparisons (scale x condition)"


def test_the_belief_is_named_with_its_cap(reading_and_table, text):
    """The plan states the study's belief: Javdani et al.'s, capped at the study's cap."""
    from lasa.world.eating import STUDY_BELIEF_CAP, load_eating_robot

    assert load_eating_robot().control.belief_cap == STUDY_BELIEF_CAP
    assert f"no goal keeps more than {STUDY_BELIEF_CAP:g}" in text and "Javdani" in text
    reading, table = reading_and_table
    other = preregister.document(table, reading, practice_s=240.0, trial_s=150.0, belief_cap=0.9)
    assert "no goal keeps more than 0.9," in other
