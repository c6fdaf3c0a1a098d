"""Performance benchmarks: ``make bench`` -> ``benchmarks/results.json`` and ``scaling.png``.

What is measured, on the machine it runs on (never asserted in tests):

- ``step_latency_us``: one user's full LA+SA step on the Panda, from joystick input to
  commanded state (decode, assistance, blend, belief update, safe step), with
  :class:`lasa.realtime.Controller`; median and 99th percentile over 10,000 steps.
  ``mj_step_us`` is one ``mujoco.mj_step`` of the Panda scene in the same run.
- ``sweep``: simulated user-steps per second of the batched rollout
  (:func:`lasa.rollout.rollout`) for 1 to 4096 users, against a per-user, per-step
  loop over the same decoder and the same step functions (``loop``: the rollout run
  for one user at a time), and against the
  bare batched decoder forward pass at the same size (``floor``).
- ``training_s``: the time to train each decoder of ``configs/paper.yaml`` and its
  final error, read from the checkpoints of a fresh paper-scale pipeline run.
- ``figures_s``: wall time of ``make figures`` (fresh, into ``build/bench``) per
  notebook and in total, and the same for ``make figures QUICK=1``.
- ``render_fps``: frames per second of the off-screen video renderer.

Usage: ``python -m lasa.bench --out benchmarks`` (``--tiny`` runs every part at a toy
size in seconds, as ``make test`` does; ``--skip-pipeline`` leaves out the two
``make figures`` runs).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402
import torch  # noqa: E402

from lasa.config import ControlConfig  # noqa: E402
from lasa.decoder import DecoderConfig, LatentActionModel, load_checkpoint  # noqa: E402
from lasa.errors import ConfigError  # noqa: E402
from lasa.io import write_text  # noqa: E402
from lasa.realtime import Controller  # noqa: E402
from lasa.robot import Robot, load_robot  # noqa: E402
from lasa.rollout import rollout  # noqa: E402
from lasa.task import CupTask, make_cup_task  # noqa: E402
from lasa.users import UserPopulation, latent_grid  # noqa: E402
from lasa.video import render_states  # noqa: E402

__all__ = [
    "BenchConfig",
    "step_latency",
    "mj_step_time",
    "sweep_throughput",
    "render_fps",
    "training_times",
    "read_timings",
    "run_pipeline",
    "machine",
    "plot_scaling",
    "main",
]

TARGETS = {
    "step_latency_p99_us": 100.0,
    "sweep_speedup_at_1024": 100.0,
    "sweep_floor_fraction_at_1024": 0.5,
    "figures_total_s": 300.0,
    "figures_quick_total_s": 90.0,
}


@dataclasses.dataclass(frozen=True)
class BenchConfig:
    """Sizes of the benchmarks (the defaults are ``make bench``'s; ``tiny()`` is for tests)."""

    latency_steps: int = 10_000  # control steps timed [-]
    mj_steps: int = 10_000  # mj_step calls timed [-]
    batches: tuple[int, ...] = (1, 4, 16, 64, 256, 1024, 4096)  # users per batched rollout [-]
    sweep_steps: int = 20  # control steps per throughput measurement [-]
    loop_user_steps: int = 200  # user-steps timed in the per-user loop [-]
    render_frames: int = 40  # frames rendered per robot [-]
    hidden: int = 128  # decoder width, as in configs/paper.yaml [-]
    depth: int = 3  # decoder depth, as in configs/paper.yaml [-]
    seed: int = 0  # seed of inputs, users and weights [-]

    @classmethod
    def tiny(cls) -> BenchConfig:
        """Every benchmark at a toy size: seconds, for ``make test``."""
        return cls(
            latency_steps=200,
            mj_steps=100,
            batches=(1, 8),
            sweep_steps=3,
            loop_user_steps=6,
            render_frames=2,
            hidden=16,
            depth=2,
        )


def _percentiles(seconds: np.ndarray) -> dict[str, float]:
    us = np.asarray(seconds) * 1e6
    return {
        "p50": float(np.percentile(us, 50)),
        "p99": float(np.percentile(us, 99)),
        "mean": float(us.mean()),
        "n": int(us.size),
    }


def _decoder(task: CupTask, control: ControlConfig, config: BenchConfig) -> LatentActionModel:
    """A decoder of the paper's size; speed does not depend on its weights."""
    torch.manual_seed(config.seed)
    return LatentActionModel(
        DecoderConfig(
            robot=task.robot.name,
            n_joints=task.robot.n_joints,
            n_goals=task.n_goals,
            z_dim=1,
            hidden=config.hidden,
            depth=config.depth,
            action_scale=control.action_scale,
        )
    ).eval()


def step_latency(
    model: LatentActionModel, task: CupTask, control: ControlConfig, n_steps: int, seed: int = 0
) -> tuple[dict[str, float], np.ndarray]:
    """Latency of one LA+SA control step for one user (``Controller.step``).

    The joystick input is a random walk in [-1, 1]; the episode restarts from home every
    200 steps so the arm stays in the task's region. The first 10% are warm-up.

    Returns:
        ``{p50, p99, mean, n}`` in microseconds, and every timed step [s].
    """
    if n_steps < 10:
        raise ConfigError(f"n_steps must be >= 10, got {n_steps}")
    ctl = Controller(model, task, control, control.alpha)
    rng = np.random.default_rng(seed)
    warm = n_steps // 10
    total = n_steps + warm
    z = np.clip(np.cumsum(rng.normal(0, 0.2, total)), -1, 1)
    times = np.empty(total)
    clock = time.perf_counter
    for i in range(total):
        if i % 200 == 0:
            ctl.reset()
        t0 = clock()
        ctl.step(z[i])
        times[i] = clock() - t0
    return _percentiles(times[warm:]), times[warm:]


def mj_step_time(robot: Robot, n_steps: int) -> dict[str, float]:
    """One ``mujoco.mj_step`` of the robot's scene, in microseconds."""
    data = mujoco.MjData(robot.model)
    data.qpos[robot.qpos_adr] = robot.home
    mujoco.mj_forward(robot.model, data)
    times = np.empty(n_steps)
    clock = time.perf_counter
    for i in range(n_steps):
        t0 = clock()
        mujoco.mj_step(robot.model, data)
        times[i] = clock() - t0
    return _percentiles(times)


def _users(task: CupTask, n_users: int, rng: np.random.Generator) -> UserPopulation:
    goal = rng.integers(0, task.n_goals, n_users)
    theta = rng.uniform(0, 1, n_users)
    return UserPopulation(
        goal=goal,
        theta=theta,
        target=task.target(goal, theta),
        beta0=np.full(n_users, 1000.0),
        slope=np.zeros(n_users),
        seed=np.arange(n_users),
    )


def _loop(
    model: LatentActionModel,
    task: CupTask,
    control: ControlConfig,
    users: UserPopulation,
    noise: np.ndarray,
    steps: int,
) -> float:
    """The baseline: the same rollout, one user at a time (so one step at a time) [user-steps/s]."""
    start = time.perf_counter()
    for u in range(len(users)):
        rollout(model, task, users.subset(np.array([u])), control.alpha, control, steps, noise)
    return len(users) * steps / (time.perf_counter() - start)


def _floor(model: LatentActionModel, n_users: int, n_cand: int, steps: int) -> float:
    """The bare batched decoder forward pass at the rollout's size [user-steps/s]."""
    n, g, d = model.config.n_joints, model.config.n_goals, model.config.z_dim
    z = torch.zeros(n_users, n_cand, d)
    s = torch.zeros(n_users, n_cand, n)
    b = torch.full((n_users, n_cand, g), 1.0 / g)
    with torch.inference_mode():
        model.decode(z, s, b)  # warm-up
        start = time.perf_counter()
        for _ in range(steps):
            model.decode(z, s, b)
    return n_users * steps / (time.perf_counter() - start)


def sweep_throughput(
    model: LatentActionModel, task: CupTask, control: ControlConfig, config: BenchConfig
) -> dict[str, dict[str, float]]:
    """User-steps per second: batched rollout, per-user loop and decoder floor, per batch size."""
    rng = np.random.default_rng(config.seed)
    n_cand = len(latent_grid(control.n_z, model.config.z_dim))
    out: dict[str, dict[str, float]] = {}
    for n_users in config.batches:
        users = _users(task, n_users, rng)
        noise = rng.random((n_users, config.sweep_steps, n_cand))
        rollout(model, task, users, control.alpha, control, 1, noise)  # warm-up
        start = time.perf_counter()
        rollout(model, task, users, control.alpha, control, config.sweep_steps, noise)
        batched = n_users * config.sweep_steps / (time.perf_counter() - start)
        loop_users = max(1, min(n_users, config.loop_user_steps // config.sweep_steps))
        loop = _loop(model, task, control, users.subset(np.arange(loop_users)), noise, config.sweep_steps)
        floor = _floor(model, n_users, n_cand, config.sweep_steps)
        out[str(n_users)] = {"batched": batched, "loop": loop, "floor": floor}
    return out


def render_fps(robot: Robot, n_frames: int) -> float:
    """Frames per second of :func:`lasa.video.render_states` at 320x240 (OSMesa)."""
    states = np.tile(robot.home, (n_frames, 1))
    render_states(robot, states[:1])  # the GL context's first frame is dearer
    start = time.perf_counter()
    render_states(robot, states)
    return n_frames / (time.perf_counter() - start)


def training_times(models_dir: str | os.PathLike[str]) -> dict[str, dict[str, Any]]:
    """Training time and final error of every decoder checkpoint in ``models_dir``."""
    out = {}
    for path in sorted(Path(models_dir).glob("decoder_*.pt")):
        robot = path.stem.split("_")[1]
        _, extra = load_checkpoint(path, robot=robot)
        out[path.stem] = {
            "seconds": extra.get("train_seconds"),
            "steps": extra.get("train", {}).get("steps"),
            "val_error": extra.get("val_error"),
            "entropy_lambda": extra.get("entropy_lambda"),
            "warm_start": extra.get("init"),
        }
    return out


def read_timings(path: str | os.PathLike[str]) -> dict[str, float]:
    """``{"<notebook>-<robot>": seconds}`` from a runner ``--timings`` file (JSON lines)."""
    out = {}
    for line in Path(path).read_text().splitlines():
        if line.strip():
            rec = json.loads(line)
            key = rec["notebook"] + (f"-{rec['robot']}" if rec.get("robot") else "")
            out[key] = float(rec["seconds"])
    return out


def run_pipeline(command: list[str], out_dir: Path) -> dict[str, Any]:
    """Run one pipeline command from scratch into ``out_dir``; its wall time per notebook and total."""
    if out_dir.exists():
        shutil.rmtree(out_dir)
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True)
    total = time.perf_counter() - start
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}")
    per = read_timings(out_dir / "timings.jsonl")
    return {"total": total, "per_notebook": per, "sum_of_notebooks": float(sum(per.values()))}


def machine() -> dict[str, Any]:
    """What the numbers were measured on."""
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "torch": torch.__version__,
        "torch_threads": torch.get_num_threads(),
        "numpy": np.__version__,
        "mujoco": mujoco.__version__,
        "date": datetime.date.today().isoformat(),
    }


def plot_scaling(results: dict[str, Any], latencies: np.ndarray, path: Path) -> None:
    """Throughput against batch size, and the control step's latency histogram."""
    sweep = results["sweep"]
    sizes = np.array([int(k) for k in sweep])
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    for key, style, label in (
        ("floor", "k--", "bare batched decoder forward"),
        ("batched", "o-", "batched rollout (Algorithm 1)"),
        ("loop", "s-", "per-user, per-step loop"),
    ):
        ax1.plot(sizes, [sweep[str(s)][key] for s in sizes], style, label=label)
    ax1.set_xscale("log")
    ax1.set_yscale("log")
    ax1.set_xlabel("simulated users per batch")
    ax1.set_ylabel("user-steps per second")
    ax1.set_title("sweep throughput")
    ax1.legend(frameon=False)
    us = latencies * 1e6
    ax2.hist(us, bins=np.linspace(0, max(150.0, float(np.percentile(us, 99.9))), 80), color="0.6")
    lat = results["step_latency_us"]
    for value, color, label in (
        (lat["p50"], "C0", f"p50 {lat['p50']:.0f} us"),
        (lat["p99"], "C3", f"p99 {lat['p99']:.0f} us"),
        (TARGETS["step_latency_p99_us"], "k", "target p99 100 us"),
        (results["mj_step_us"]["mean"], "C2", f"mj_step {results['mj_step_us']['mean']:.0f} us"),
    ):
        ax2.axvline(value, color=color, ls="--", label=label)
    ax2.set_xlabel("control step latency [us]")
    ax2.set_ylabel("steps")
    ax2.set_title("one user's LA+SA step on the Panda")
    ax2.legend(frameon=False, fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp, dpi=130)
    os.replace(tmp, path)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmarks and write ``results.json`` and ``scaling.png`` into ``--out``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="benchmarks", help="folder of results.json and scaling.png")
    parser.add_argument("--tiny", action="store_true", help="toy sizes, for make test")
    parser.add_argument("--skip-pipeline", action="store_true", help="leave out the make figures runs")
    parser.add_argument("--build", default="build/bench", help="scratch folder of the pipeline runs")
    args = parser.parse_args(argv)
    config = BenchConfig.tiny() if args.tiny else BenchConfig()
    torch.set_num_threads(1)  # one user's step and small batches: a second thread only adds overhead
    out = Path(args.out)
    results: dict[str, Any] = {"machine": machine(), "targets": TARGETS, "config": dataclasses.asdict(config)}

    print("control step latency (Panda, one user)", flush=True)
    arm = load_robot("panda")
    task = make_cup_task(arm)
    control = arm.control
    model = _decoder(task, control, config)
    results["step_latency_us"], latencies = step_latency(
        model, task, control, config.latency_steps, config.seed
    )
    results["mj_step_us"] = mj_step_time(arm, config.mj_steps)
    results["step_over_mj_step"] = results["step_latency_us"]["p50"] / results["mj_step_us"]["p50"]

    print("sweep throughput", flush=True)
    torch.set_num_threads(os.cpu_count() or 1)  # the sweeps use every core, as the notebooks do
    results["sweep"] = sweep_throughput(model, task, control, config)
    torch.set_num_threads(1)

    print("rendering", flush=True)
    results["render_fps"] = {
        name: render_fps(load_robot(name), config.render_frames) for name in ("planar5", "panda")
    }

    build = Path(args.build)
    if not args.skip_pipeline:
        make = os.environ.get("MAKE", "make")
        print("make figures (fresh, paper scale)", flush=True)
        paper = run_pipeline([make, "figures", f"OUT={build / 'paper'}"], build / "paper")
        print("make figures QUICK=1 (fresh)", flush=True)
        quick = run_pipeline([make, "figures", "QUICK=1", f"OUT={build / 'quick'}"], build / "quick")
        results["figures_s"] = {**paper, "quick": quick}
        results["training_s"] = training_times(build / "paper" / "models")
    elif args.tiny:
        # exercise the timing path on one tiny notebook run, so that it cannot rot
        nb_out = build / "tiny"
        command = [
            sys.executable,
            "-m",
            "lasa.runner",
            "notebooks/01_demonstrations.ipynb",
            "--config",
            "configs/quick.yaml",
            "--out",
            str(nb_out / "notebooks"),
            "--robot",
            "planar5",
            "--no-progress",
            "--timings",
            str(nb_out / "timings.jsonl"),
            "--param",
            f"build_dir={nb_out}",
            "--param",
            f"figures_dir={nb_out / 'figures'}",
        ]
        results["figures_s"] = run_pipeline(command, nb_out)
        results["training_s"] = training_times(nb_out / "models")

    write_text(out / "results.json", json.dumps(results, indent=2) + "\n")
    plot_scaling(results, latencies, out / "scaling.png")
    print(json.dumps({k: results[k] for k in ("step_latency_us", "mj_step_us")}, indent=2))
    print(f"-> {out / 'results.json'}, {out / 'scaling.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
