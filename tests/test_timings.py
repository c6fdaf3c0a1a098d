"""The pipeline's wall times in benchmarks/results.json and the READMEs (lasa.pipeline.timings).

From synthetic timings files: ``figures_s`` is the run's wall span (not the sum of its notebooks),
a partial run is refused, and the READMEs' generated words sit between their markers.
"""

from __future__ import annotations

import datetime
import json
import subprocess
from pathlib import Path

import pytest

from lasa.base.errors import ConfigError
from lasa.pipeline import execute, timings

ROOT = Path(__file__).resolve().parents[1]
T0 = datetime.datetime(2026, 12, 4, 23, 59, 0, tzinfo=datetime.UTC)
HOST = {
    "cpu": "Test CPU",
    "cores": 2,
    "python": "3.11.7",
    "torch": "2.13.0+cpu",
    "numpy": "2.4.6",
    "mujoco": "4.0.0",
}
# (notebook, robot, start [s after T0], end [s after T0]): two chains side by side, then a third
RUNS = [
    ("01_demonstrations", "planar5", 0.0, 100.0),
    ("01_demonstrations", "panda", 10.0, 130.0),
    ("02_decoder_training", "planar5", 100.0, 250.0),
    ("10_eating_task", None, 130.0, 400.0),
]
EXPECTED = [
    "01_demonstrations-planar5",
    "01_demonstrations-panda",
    "02_decoder_training-planar5",
    "10_eating_task",
]


def _write(path: Path, runs: list[tuple[str, str | None, float, float]]) -> Path:
    for notebook, robot, start, end in runs:
        at = [T0 + datetime.timedelta(seconds=s) for s in (start, end)]
        timings.append_run(path, notebook, robot, end - start, *at)
    return path


@pytest.fixture
def results(tmp_path: Path) -> Path:
    """A results.json with other keys, an old paper-scale figures_s and a quick part."""
    path = tmp_path / "results.json"
    run = {
        "date": "2026-01-01",
        "machine": HOST,
        "commit": "old",
        "command": "make figures",
        "source": "by hand",
    }
    old = {"total": 1.0, "per_notebook": {}, "sum_of_notebooks": 0.0, **run}
    data = {
        "machine": {"cpu": "old"},
        "targets": {"figures_total_s": 300.0},
        "figures_s": {**old, "quick": old},
    }
    path.write_text(json.dumps(data, indent=2) + "\n")
    return path


def test_the_total_is_the_wall_span_not_the_sum(tmp_path, results):
    jsonl = _write(tmp_path / "timings.jsonl", RUNS)
    written = timings.record_figures(
        jsonl, results, "paper", EXPECTED, "make figures", host=HOST, commit="abc1234"
    )
    data = json.loads(results.read_text())
    figures = data["figures_s"]
    assert figures["total"] == 400.0  # first start (0 s) to last end (400 s)
    assert figures["sum_of_notebooks"] == 100 + 120 + 150 + 270
    assert figures["per_notebook"] == {
        "01_demonstrations-planar5": 100.0,
        "01_demonstrations-panda": 120.0,
        "02_decoder_training-planar5": 150.0,
        "10_eating_task": 270.0,
    }
    assert figures["machine"] == HOST
    assert figures["date"] == "2026-12-04"  # the first start's date (UTC), not today's
    assert figures["commit"] == "abc1234" and figures["command"] == "make figures"
    assert str(jsonl) in figures["source"] and "23:59:00 to 00:05:40 UTC" in figures["source"]
    assert written == {k: v for k, v in figures.items() if k != "quick"}
    # the quick part and every other key are kept
    assert figures["quick"]["total"] == 1.0 and data["machine"] == {"cpu": "old"}


def test_a_quick_run_writes_the_quick_part_alone(tmp_path, results):
    jsonl = _write(tmp_path / "timings.jsonl", RUNS[:1])
    timings.record_figures(
        jsonl, results, "quick", EXPECTED[:1], "make figures QUICK=1", host=HOST, commit="x"
    )
    figures = json.loads(results.read_text())["figures_s"]
    assert figures["total"] == 1.0  # the paper-scale part untouched
    assert figures["quick"]["total"] == 100.0 and figures["quick"]["command"] == "make figures QUICK=1"


def test_the_machine_is_read_here_by_default(tmp_path, results):
    jsonl = _write(tmp_path / "timings.jsonl", RUNS[:1])
    written = timings.record_figures(jsonl, results, "paper", EXPECTED[:1], "make figures")
    assert written is not None
    host = written["machine"]
    assert host["cores"] >= 1 and host["numpy"] and host["torch"] and host["python"]
    assert set(host) == set(HOST) and {"date", "commit", "command", "source"} <= set(written)


@pytest.mark.parametrize(
    "runs, why",
    [
        (RUNS[:3], "3 of 4 notebooks ran"),  # Make skipped an up-to-date notebook
        ([*RUNS, RUNS[0]], "more than once"),
        ([*RUNS, ("99_other", None, 0.0, 1.0)], "outside the expected set"),
    ],
)
def test_a_partial_run_leaves_results_untouched(tmp_path, results, capsys, runs, why):
    jsonl = _write(tmp_path / "timings.jsonl", runs)
    before = results.read_text()
    assert (
        timings.record_figures(jsonl, results, "paper", EXPECTED, "make figures", host=HOST, commit="x")
        is None
    )
    assert results.read_text() == before
    out = capsys.readouterr().out
    assert "left as it was" in out and why in out


def test_no_timings_file_leaves_results_untouched(tmp_path, results, capsys):
    before = results.read_text()
    assert timings.record_figures(tmp_path / "none.jsonl", results, "paper", EXPECTED, "make figures") is None
    assert results.read_text() == before and "no notebook ran" in capsys.readouterr().out


def test_lines_of_an_older_runner_are_not_a_whole_run(tmp_path, results):
    """Lines without start and end cannot give a wall span: refused, and read as seconds only."""
    jsonl = tmp_path / "timings.jsonl"
    jsonl.write_text('{"notebook": "10_eating_task", "robot": null, "seconds": 2}\n')
    before = results.read_text()
    assert timings.record_figures(jsonl, results, "paper", ["10_eating_task"], "make figures") is None
    assert results.read_text() == before
    assert timings.read_timings(jsonl) == {"10_eating_task": 2.0}
    with pytest.raises(ConfigError, match="start and end"):
        timings.summarize(timings.read_runs(jsonl), "make figures", str(jsonl))


def test_a_malformed_line_names_its_file_and_line(tmp_path):
    jsonl = tmp_path / "timings.jsonl"
    jsonl.write_text('{"notebook": "a", "robot": null, "seconds": 1}\nnot json\n')
    with pytest.raises(ConfigError, match="line 2"):
        timings.read_runs(jsonl)


def test_the_runner_records_start_and_end(tmp_path, monkeypatch):
    """``execute.main --timings`` appends one line with the run's seconds, start and end (UTC)."""
    monkeypatch.setattr(execute, "run_notebook", lambda *args, **kwargs: tmp_path / "x.ipynb")
    jsonl = tmp_path / "t" / "timings.jsonl"
    args = ["notebooks/04_fixed_expertise.ipynb", "--config", "c.yaml", "--out", str(tmp_path)]
    assert execute.main([*args, "--robot", "panda", "--timings", str(jsonl)]) == 0
    (run,) = timings.read_runs(jsonl)
    assert run.name == "04_fixed_expertise-panda" and run.start is not None and run.end is not None
    assert run.start <= run.end and run.start.utcoffset() == datetime.timedelta(0)
    assert abs((run.end - run.start).total_seconds() - run.seconds) < 0.1


def _readmes(tmp_path: Path) -> tuple[Path, Path]:
    readme = tmp_path / "README.md"
    begin, end = timings.README_MARKERS
    readme.write_text(f"# x\n\nNeeds time: {begin}old words{end}; `make test` 8 min.\n\nmore\n")
    bench = tmp_path / "bench.md"
    begin, end = timings.BENCH_MARKERS
    bench.write_text(f"table:\n\n{begin}\n| old |\n{end}\n\nafter\n")
    return readme, bench


def test_the_readmes_are_generated_between_their_markers(tmp_path, results):
    _write(tmp_path / "timings.jsonl", RUNS)
    timings.record_figures(
        tmp_path / "timings.jsonl", results, "paper", EXPECTED, "make figures", host=HOST, commit="abc1234"
    )
    readme, bench = _readmes(tmp_path)
    assert timings.sync_readmes(results, readme, bench) == [readme, bench]
    begin, end = timings.README_MARKERS
    sentence = "on 2 cores `make figures` took 7 min (Test CPU, 2026-12-04, at abc1234"
    assert f"Needs time: {begin}{sentence}" in readme.read_text()
    assert readme.read_text().endswith(f"{end}; `make test` 8 min.\n\nmore\n")
    table = bench.read_text()
    assert "| old |" not in table and table.startswith("table:\n\n") and table.endswith("\n\nafter\n")
    assert (
        "**400 s** (7 min) | 640 s | Test CPU, 2 cores, 2026-12-04, at abc1234: `make figures` | "
        "≤ 300 s | **missed** |" in table
    )
    assert "| `make figures QUICK=1`, fresh | **1 s** (1 s) |" in table
    texts = (readme.read_text(), bench.read_text())
    assert timings.sync_readmes(results, readme, bench) == []  # idempotent
    assert (readme.read_text(), bench.read_text()) == texts


@pytest.mark.parametrize("drop", [0, 1])
def test_a_missing_marker_is_a_clear_error(tmp_path, results, drop):
    readme, _ = _readmes(tmp_path)
    marker = timings.README_MARKERS[drop]
    readme.write_text(readme.read_text().replace(marker, ""))
    before = readme.read_text()
    with pytest.raises(ConfigError, match="must hold the markers"):
        timings.sync_readmes(results, readme, None)
    assert readme.read_text() == before


def test_the_cli_records_and_syncs_and_a_partial_run_exits_cleanly(tmp_path, results):
    jsonl = _write(tmp_path / "timings.jsonl", RUNS[:2])
    readme, bench = _readmes(tmp_path)
    argv = [str(jsonl), "--part", "paper", "--command", "make figures", "--results", str(results)]
    argv += ["--readme", str(readme), "--bench-readme", str(bench), "--expect", *EXPECTED]
    assert timings.main(argv) == 0  # partial: nothing recorded, the READMEs follow results.json
    assert json.loads(results.read_text())["figures_s"]["total"] == 1.0
    assert timings.main([*argv[:-4], *EXPECTED[:2]]) == 0
    assert json.loads(results.read_text())["figures_s"]["total"] == 130.0
    assert "`make figures` took 2 min (" in readme.read_text()


def test_the_committed_results_have_the_writers_shape(tmp_path):
    """benchmarks/results.json's figures_s holds exactly the keys a run writes, at both scales."""
    committed = json.loads((ROOT / "benchmarks" / "results.json").read_text())["figures_s"]
    jsonl = _write(tmp_path / "timings.jsonl", RUNS[:1])
    written = timings.summarize(timings.read_runs(jsonl), "make figures", str(jsonl))
    for part in (committed, committed["quick"]):
        assert set(part) - {"quick"} == set(written)
        assert set(part["machine"]) == set(written["machine"]) and part["date"] and part["machine"]["cpu"]
        assert part["sum_of_notebooks"] == pytest.approx(sum(part["per_notebook"].values()), abs=0.05)


def test_the_committed_readmes_are_in_sync_with_results(tmp_path):
    """README.md and benchmarks/README.md hold what results.json generates (a hand edit fails here)."""
    readme, bench = tmp_path / "README.md", tmp_path / "bench.md"
    readme.write_text((ROOT / "README.md").read_text())
    bench.write_text((ROOT / "benchmarks" / "README.md").read_text())
    assert timings.sync_readmes(ROOT / "benchmarks" / "results.json", readme, bench) == []


def test_the_makefile_expects_every_notebook_it_runs(tmp_path):
    """``RUNS`` (the whole run the Makefile checks timings.jsonl against) is what ``make figures`` runs."""
    make = ["make", "--no-print-directory"]
    expected = subprocess.run([*make, "print-RUNS"], cwd=ROOT, capture_output=True, text=True, check=True)
    # into an empty folder, where no notebook is up to date: every run, as -B would list it, without
    # -B remaking each sub-make's build/make-deps.mk (7 s)
    dry = subprocess.run(
        [*make, "-n", "notebooks", f"OUT={tmp_path / 'o'}"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    ran = set()
    for line in dry.stdout.splitlines():
        if "lasa.pipeline.execute" in line:
            words = line.split()
            stem = Path(next(w for w in words if w.endswith(".ipynb"))).stem
            ran.add(f"{stem}-{words[words.index('--robot') + 1]}" if "--robot" in words else stem)
    assert sorted(expected.stdout.split()) == sorted(ran) and len(ran) == 20
