"""The benchmark script (benchmarks/bench.py), run once at a toy size so that it cannot rot.

No timing is asserted: only that every part runs and reports what it should.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from lasa.base.errors import ConfigError
from lasa.pipeline.execute import parse_params

ROOT = Path(__file__).resolve().parents[1]


def _load_bench() -> ModuleType:
    """Import ``benchmarks/bench.py`` (a script, not part of the package) as a module."""
    spec = importlib.util.spec_from_file_location("lasa_benchmarks_bench", ROOT / "benchmarks" / "bench.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve the module's annotations through it
    spec.loader.exec_module(module)
    return module


bench = _load_bench()
TINY = bench.BenchConfig.tiny()


@pytest.fixture(scope="module")
def tiny_results(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    # a small eating decoder where `make figures` would leave the real one (the live LA+SA step loads it)
    from lasa.method.decoder import save_checkpoint
    from lasa.method.train import TrainConfig, train_decoder
    from lasa.people.demos import DemoConfig, collect_eating_demonstrations
    from lasa.world.eating import make_eating_task

    task = make_eating_task()
    demos = collect_eating_demonstrations(
        task, task.robot.control, DemoConfig(n_theta=2, n_starts=1, n_adjust=0, n_perturb=1)
    )
    config = TrainConfig(steps=30, hidden=16, depth=2, z_dim=2, batch_size=128)
    model, _ = train_decoder(demos, task.robot.control, config, progress=False)
    save_checkpoint(model, out / "decoders" / "models" / "eating_decoder_panda.pt")
    # --build is absolute: the script runs the pipeline from the repository root, whatever the cwd
    argv = ["--out", str(out), "--tiny", "--skip-pipeline", "--build", str(out / "build")]
    assert bench.main([*argv, "--decoder-build", str(out / "decoders")]) == 0
    return out


def test_results_hold_every_key(tiny_results):
    results = json.loads((tiny_results / "results.json").read_text())
    assert set(results["step_latency_us"]) == {"p50", "p99", "mean", "n"}
    assert results["step_latency_us"]["n"] == TINY.latency_steps
    deadline = results["step_deadline"]
    assert set(deadline) == {"dt_s", "rate_hz", "deadline_us", "p99_fraction"}
    assert deadline["deadline_us"] == pytest.approx(deadline["dt_s"] * 1e6)
    p99 = results["step_latency_us"]["p99"]
    assert deadline["p99_fraction"] == pytest.approx(p99 / deadline["deadline_us"])
    assert results["targets"]["step_latency_p99_us"] == deadline["deadline_us"]
    assert set(results["targets"]) == set(bench.TARGETS) | {"step_latency_p99_us"}
    assert results["mj_step_us"]["mean"] > 0 and results["step_over_mj_step"] > 0
    # the step live teleoperation runs, for both interfaces (Retargeting includes its mink solve)
    assert set(results["station_step_us"]) == {"R+SA", "LA+SA"}
    for row in results["station_step_us"].values():
        assert set(row) == {"p50", "p99", "mean", "n"} and 0 < row["p50"] <= row["p99"]
    # the live station over franky against franky-sim, LA+SA with the small decoder, every tick sent
    live = results["franky_station"]
    assert live["condition"] == "LA+SA" and live["ticks_planned"] == round(TINY.franky_seconds / 0.1)
    assert 1 <= live["ticks"] <= live["ticks_planned"] and live["sent"] == live["ticks"]
    assert 0 < live["p50_ms"] <= live["p99_ms"] and live["missed_ticks"] >= 0
    assert set(results["sweep"]) == {str(b) for b in TINY.batches}
    for row in results["sweep"].values():
        assert set(row) == {"batched", "loop", "floor"} and all(v > 0 for v in row.values())
    assert set(results["render_fps"]) == {"planar5", "panda"}
    study = results["study_step"]
    assert study["rows"] == TINY.study_rows and study["every_row_ms"] > 0 and study["only_blended_ms"] > 0
    assert study["speedup"] == pytest.approx(study["every_row_ms"] / study["only_blended_ms"])
    grid = results["dask_grid"]
    assert grid["cells"] == TINY.grid_cells[0] and grid["local_s"] > 0
    assert set(grid["workers"]) == {"1", "2"} and grid["speedup_2_over_1"] > 0
    assert grid["identical"] is True  # the same rows here and on 1 or 2 Dask workers
    overhead = results["dask_overhead_1_worker"]
    assert overhead["cells"] == list(TINY.grid_cells) and overhead["identical"] is True
    assert overhead["seconds"]["in_process"][0] == grid["local_s"]
    assert overhead["seconds"]["dask_1_worker"][0] == grid["workers"]["1"]
    large = overhead["grid_seconds_in_process"]
    assert overhead["overhead_fraction"] == pytest.approx(overhead["grid_seconds_dask"] / large - 1)
    assert np.isfinite(overhead["fixed_s"])
    assert "speedup_2_over_1" not in results["targets"]  # reported only
    vs = results["decoder_vs_gemm"]
    assert vs["users"] == TINY.gemm_users and vs["rows"] == vs["users"] * vs["candidates"]
    for key in ("decode_numpy", "decode_torch", "gemm_bound", "fraction", "decode_torch_fraction"):
        assert np.isfinite(vs[key]) and vs[key] > 0, key
    assert results["decoder_vs_gemm_fraction"] == vs["fraction"]
    assert vs["fraction"] == pytest.approx(vs["decode_numpy"] / vs["gemm_bound"])
    assert vs["best_chunk"] in {*TINY.gemm_chunks, vs["rows"]} and vs["best_output_layout"] in {
        "W U^T",
        "U W^T",
    }
    assert str(vs["best_chunk"]) in vs["gemm_by_chunk"] and vs["threads"] == 1
    assert set(vs["by_users"]) == {str(b) for b in TINY.batches}
    for row in vs["by_users"].values():
        assert all(np.isfinite(row[k]) and row[k] > 0 for k in ("decode_numpy", "gemm_bound", "fraction"))
    for key in (
        "decoder_vs_gemm_fraction",
        "dask_overhead_1_worker",
        "figures_total_s",
        "figures_quick_total_s",
    ):
        assert results["targets"][key] > 0, key
    figures = results["figures_s"]
    assert set(figures["per_notebook"]) == {"01_demonstrations-planar5"} and figures["total"] > 0
    assert {"date", "machine", "commit", "command", "source"} <= set(figures)  # the run that measured it
    assert {"cpu", "cores"} <= set(figures["machine"])
    assert isinstance(results["training_s"], dict)
    assert results["machine"]["cores"] >= 1
    assert set(results["threads"]) == {"step", "sweep", "omp_num_threads"}
    assert results["config"]["batches"] == list(TINY.batches)
    assert results["bench_s"] > 0
    assert (tiny_results / "scaling.png").stat().st_size > 10_000


def test_parts_on_another_robot(model, task):
    """The step and sweep parts take any decoder and task: here the planar5 fixtures."""
    control = task.robot.control
    latency, times = bench.step_latency(model, task, control, 20)
    assert latency["n"] == 20 and times.shape == (20,) and np.all(times > 0)
    assert bench.step_deadline(control, latency)["rate_hz"] == pytest.approx(1 / control.dt)
    sweep = bench.sweep_throughput(model, task, control, TINY)
    assert set(sweep) == {str(b) for b in TINY.batches}
    vs = bench.decoder_vs_gemm(model, control, TINY)
    assert vs["fraction"] > 0 and set(vs["by_users"]) == {str(b) for b in TINY.batches}
    with pytest.raises(ConfigError, match="n_steps"):
        bench.step_latency(model, task, control, 5)


def test_gemm_only_computes_the_decoders_products(model):
    """The bound's work is the decoder's affine layers without activations, in either output layout."""
    import torch

    layers = [m for m in model.decoder if isinstance(m, torch.nn.Linear)]
    x = torch.rand(50, layers[0].in_features)
    with torch.no_grad():
        expected = x
        for layer in layers:
            expected = layer(expected)
    for chunk in (7, 50, 64):
        plain = bench.gemm_only(model, 50, chunk, False, x)().clone()
        transposed = bench.gemm_only(model, 50, chunk, True, x)().clone()
        torch.testing.assert_close(plain, expected, rtol=1e-5, atol=1e-5)
        torch.testing.assert_close(transposed.t(), expected, rtol=1e-5, atol=1e-5)


def test_read_timings(tmp_path):
    path = tmp_path / "t.jsonl"
    path.write_text(
        '{"notebook": "01_demonstrations", "robot": "panda", "seconds": 1.5}\n\n'
        '{"notebook": "x", "robot": null, "seconds": 2}\n'
    )
    assert bench.read_timings(path) == {"01_demonstrations-panda": 1.5, "x": 2.0}


def test_training_times_of_no_checkpoints(tmp_path):
    assert bench.training_times(tmp_path) == {}


def test_training_times_read_what_the_checkpoints_record(model, tmp_path):
    from lasa.method.decoder import save_checkpoint

    save_checkpoint(
        model,
        tmp_path / f"decoder_{model.robot}.pt",
        train={"steps": 7},
        train_seconds=1.5,
        val_error=0.25,
        entropy_lambda=0.0,
    )
    save_checkpoint(model, tmp_path / f"decoder_{model.robot}_entropy.pt", train={"steps": 3}, init="base")
    save_checkpoint(model, tmp_path / f"eating_decoder_{model.robot}.pt")  # not a cup decoder: left out
    times = bench.training_times(tmp_path)
    assert times == {
        f"decoder_{model.robot}": {
            "seconds": 1.5,
            "steps": 7,
            "val_error": 0.25,
            "entropy_lambda": 0.0,
            "warm_start": None,
        },
        f"decoder_{model.robot}_entropy": {
            "seconds": None,
            "steps": 3,
            "val_error": None,
            "entropy_lambda": None,
            "warm_start": "base",
        },
    }


def test_parse_params():
    assert parse_params(["build_dir=build/x", "n=3", "betas=[1, 2]"]) == {
        "build_dir": "build/x",
        "n": 3,
        "betas": [1, 2],
    }
    with pytest.raises(ConfigError, match="NAME=VALUE"):
        parse_params(["oops"])


def test_only_remeasures_one_part_and_keeps_the_rest(tmp_path):
    """``--only decoder_vs_gemm`` replaces that part's keys, records when, and keeps every other key."""
    path = tmp_path / "results.json"
    path.write_text(
        json.dumps({"machine": {"date": "old"}, "sweep": {"1": 1.0}, "decoder_vs_gemm_fraction": -1})
    )
    assert bench.main(["--out", str(tmp_path), "--tiny", "--only", "decoder_vs_gemm"]) == 0
    results = json.loads(path.read_text())
    assert results["machine"] == {"date": "old"} and results["sweep"] == {"1": 1.0}
    assert results["decoder_vs_gemm_fraction"] == results["decoder_vs_gemm"]["fraction"] > 0
    assert results["remeasured"]["decoder_vs_gemm"]["machine"]["date"]


def test_interleaved_warms_each_call_before_its_timing():
    """With ``warm_each``, every timing is preceded by an untimed call of the same callable."""
    order: list[str] = []
    calls = {"a": lambda: order.append("a"), "b": lambda: order.append("b")}
    bench._interleaved(calls, 2, budget_s=0.0, clock=lambda: 0.0, warm_each=True)
    # warm-up (two calls each), then per round: a warm call and one timed call of each
    assert order == ["a", "a", "b", "b"] + ["a", "a", "b", "b"] * 2


def test_fit_overhead_splits_a_fixed_and_a_per_cell_cost():
    """In-process 1 + 2 s per cell; Dask 3 + 2.2 s per cell: fixed 2 s, per cell +10%."""
    fit = bench.fit_overhead((10, 40), (21.0, 81.0), (25.0, 91.0))
    assert fit["fixed_s"] == pytest.approx(2.0)
    assert fit["per_cell_fraction"] == pytest.approx(0.1)
    assert fit["overhead_fraction"] == pytest.approx(91 / 81 - 1)
    assert fit["grid_seconds_in_process"] == 81.0 and fit["cells"] == [10, 40]
    with pytest.raises(ConfigError, match="small < large"):
        bench.fit_overhead((40, 40), (1.0, 1.0), (1.0, 1.0))


def test_the_large_grid_grows_to_the_minimum_time():
    config = bench.BenchConfig(grid_cells=(8, 40), grid_min_s=60.0)
    assert bench._large_size(config, 8.0) == 69  # 1 s per cell: 60 s and a 15% margin
    assert bench._large_size(config, 80.0) == 40  # already long enough


def test_only_dask_updates_its_keys_with_the_sizes_given(tmp_path, monkeypatch):
    """``--only dask --grid-cells 3 5`` measures that part alone (stubbed here) and keeps the rest."""
    seen = {}

    def stub(model, task, control, config):
        seen["cells"] = config.grid_cells
        return {"cells": 3}, {"overhead_fraction": 0.05}

    monkeypatch.setattr(bench, "dask_grid", stub)
    (tmp_path / "results.json").write_text(json.dumps({"sweep": {"1": 1.0}}))
    assert bench.main(["--out", str(tmp_path), "--tiny", "--only", "dask", "--grid-cells", "3", "5"]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    assert seen["cells"] == (3, 5) and results["sweep"] == {"1": 1.0}
    assert results["dask_overhead_1_worker"] == {"overhead_fraction": 0.05}
    assert results["remeasured"]["dask"]["config"]["grid_cells"] == [3, 5]
    assert results["targets"]["dask_overhead_1_worker"] == 0.10
