"""The benchmark code, run once at a toy size so that it cannot rot. No timing is asserted."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from lasa.bench import BenchConfig, main, read_timings
from lasa.errors import ConfigError
from lasa.runner import parse_params

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def tiny_results(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    cwd = os.getcwd()
    os.chdir(ROOT)  # the tiny pipeline run uses the repository's notebooks and configs
    try:
        assert main(["--out", str(out), "--tiny", "--skip-pipeline", "--build", str(out / "build")]) == 0
    finally:
        os.chdir(cwd)
    return out


def test_results_hold_every_key(tiny_results):
    results = json.loads((tiny_results / "results.json").read_text())
    assert set(results["step_latency_us"]) >= {"p50", "p99"}
    assert results["step_latency_us"]["n"] == BenchConfig.tiny().latency_steps
    assert results["mj_step_us"]["mean"] > 0
    assert set(results["sweep"]) == {str(b) for b in BenchConfig.tiny().batches}
    for row in results["sweep"].values():
        assert set(row) == {"batched", "loop", "floor"} and all(v > 0 for v in row.values())
    assert set(results["render_fps"]) == {"planar5", "panda"}
    figures = results["figures_s"]
    assert set(figures["per_notebook"]) == {"01_demonstrations-planar5"} and figures["total"] > 0
    assert isinstance(results["training_s"], dict)
    assert results["machine"]["cores"] >= 1
    assert (tiny_results / "scaling.png").stat().st_size > 10_000


def test_read_timings(tmp_path):
    path = tmp_path / "t.jsonl"
    path.write_text(
        '{"notebook": "01_demonstrations", "robot": "panda", "seconds": 1.5}\n\n'
        '{"notebook": "x", "robot": null, "seconds": 2}\n'
    )
    assert read_timings(path) == {"01_demonstrations-panda": 1.5, "x": 2.0}


def test_parse_params():
    assert parse_params(["build_dir=build/x", "n=3", "betas=[1, 2]"]) == {
        "build_dir": "build/x",
        "n": 3,
        "betas": [1, 2],
    }
    with pytest.raises(ConfigError, match="NAME=VALUE"):
        parse_params(["oops"])
