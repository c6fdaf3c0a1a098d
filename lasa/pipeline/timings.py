"""The pipeline's wall times, from the run that measured them (``make figures``).
Each notebook run appends a line to ``<build>/timings.jsonl``; :func:`record_figures` turns a whole run's
file into ``figures_s`` of ``benchmarks/results.json``, :func:`sync_readmes` the READMEs' words."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import datetime
import importlib.metadata
import json
import os
import platform
import subprocess
import sys
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

from lasa.base.errors import ArtifactError, ConfigError
from lasa.base.io import locked, require_file, sync_between, write_text

README_MARKERS, BENCH_MARKERS = (
    (f"<!-- figures-{n}:begin (generated from {src} by make figures) -->", f"<!-- figures-{n}:end -->")
    for n, src in (("time", "benchmarks/results.json"), ("table", "results.json"))
)
PARTS = ("paper", "quick")  # figures_s's top level, or its "quick" part
_ROWS = {  # each part's row in benchmarks/README.md's table and its target in results.json
    "paper": ("`make figures`, paper scale, fresh", "figures_total_s"),
    "quick": ("`make figures QUICK=1`, fresh", "figures_quick_total_s"),
}


@dataclasses.dataclass(frozen=True)
class Run:
    """One notebook run: ``<notebook>[-<robot>]``, its wall time [s], its start and end (UTC, or None)."""

    name: str
    seconds: float
    start: datetime.datetime | None = None
    end: datetime.datetime | None = None


def append_run(
    path: str | os.PathLike[str],
    notebook: str,
    robot: str | None,
    seconds: float,
    start: datetime.datetime,
    end: datetime.datetime,
) -> None:
    """Append one run to ``path`` as one short JSON line (parallel appends do not interleave)."""
    record: dict[str, Any] = {"notebook": notebook, "robot": robot, "seconds": round(seconds, 2)}
    for key, when in (("start", start), ("end", end)):
        record[key] = when.astimezone(datetime.UTC).isoformat(timespec="milliseconds")
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as fh:
        fh.write(json.dumps(record) + "\n")


def _when(value: str | None) -> datetime.datetime | None:
    if value is None:
        return None
    when = datetime.datetime.fromisoformat(value)
    return (when if when.tzinfo else when.replace(tzinfo=datetime.UTC)).astimezone(datetime.UTC)


def read_runs(path: str | os.PathLike[str]) -> list[Run]:
    """A ``timings.jsonl``'s runs in finishing order; ArtifactError if missing, ConfigError if malformed."""
    path = require_file(path, "make figures (lasa.pipeline.execute --timings)")
    runs = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
            name = rec["notebook"] + (f"-{rec['robot']}" if rec.get("robot") else "")
            runs.append(Run(name, float(rec["seconds"]), _when(rec.get("start")), _when(rec.get("end"))))
        except (ValueError, KeyError, TypeError) as exc:
            raise ConfigError(f"{path}, line {number}: not a runner's timing record ({exc})") from None
    return runs


def read_timings(path: str | os.PathLike[str]) -> dict[str, float]:
    """``{"<notebook>-<robot>": seconds}`` from a ``--timings`` file (JSON lines)."""
    return {run.name: run.seconds for run in read_runs(path)}


def _incomplete(runs: list[Run], expected: Collection[str]) -> str | None:
    """Why ``runs`` are not each ``expected`` notebook once, dated, and nothing else; or ``None``."""
    names = [run.name for run in runs]
    undated = [r.name for r in runs if r.start is None or r.end is None]
    for found, why in (
        (sorted(set(expected) - set(names)), f"{len(names)} of {len(set(expected))} notebooks ran; not run"),
        (sorted(set(names) - set(expected)), "notebooks outside the expected set ran"),
        (sorted({name for name in names if names.count(name) > 1}), "notebooks recorded more than once"),
        (undated, "runs without start and end times (an older runner)"),
    ):
        if found:
            return f"{why}: {', '.join(found)}"
    return None


def machine() -> dict[str, Any]:
    """CPU model, cores, and the Python, torch, numpy, MuJoCo versions (from installed metadata)."""
    cpu = platform.processor() or ""
    with contextlib.suppress(OSError):
        lines = Path("/proc/cpuinfo").read_text().splitlines()
        cpu = next((line.split(":", 1)[1].strip() for line in lines if line.startswith("model name")), cpu)
    out: dict[str, Any] = {"cpu": cpu, "cores": os.cpu_count(), "python": platform.python_version()}
    for package in ("torch", "numpy", "mujoco"):
        with contextlib.suppress(importlib.metadata.PackageNotFoundError):
            out[package] = None
            out[package] = importlib.metadata.version(package)
    return out


def git_commit(cwd: str | os.PathLike[str] | None = None) -> str:
    """The short hash of ``HEAD`` in ``cwd``, or ``"unknown"`` outside a git checkout."""
    with contextlib.suppress(OSError):
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=cwd
        )
        return head.stdout.strip() or "unknown"
    return "unknown"


def summarize(
    runs: list[Run],
    command: str,
    source: str,
    host: Mapping[str, Any] | None = None,
    commit: str | None = None,
) -> dict[str, Any]:
    """One part of ``figures_s`` from a whole run's ``runs``; ``total``: first start to last end."""
    if not runs:
        raise ConfigError("no notebook runs to summarize")
    if any(run.start is None or run.end is None for run in runs):
        raise ConfigError("every run needs its start and end (a timings.jsonl of an older runner?)")
    first = min(run.start for run in runs if run.start is not None)
    last = max(run.end for run in runs if run.end is not None)
    per = {run.name: run.seconds for run in runs}
    span = f"{first:%H:%M:%S} to {last:%H:%M:%S} UTC"
    return {
        "total": round((last - first).total_seconds(), 2),
        "per_notebook": per,
        "sum_of_notebooks": round(sum(per.values()), 2),
        "date": first.date().isoformat(),
        "machine": dict(machine() if host is None else host),
        "commit": git_commit() if commit is None else commit,
        "command": command,
        "source": f"{source}: total from the first notebook's start to the last one's end ({span})",
    }


def _read_results(path: Path) -> dict[str, Any]:
    if not path.exists():
        return {}
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ConfigError(f"{path} is not JSON ({exc})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path} must hold a JSON object")
    return data


def record_figures(
    timings: str | os.PathLike[str],
    results: str | os.PathLike[str],
    part: str,
    expected: Collection[str],
    command: str,
    **summary: Any,
) -> dict[str, Any] | None:
    """Write a whole run's times from ``timings`` into ``results``' ``figures_s`` (``part`` "quick": its
    ``quick``); return them, or None (nothing written, why printed) unless each ``expected`` notebook ran."""
    if part not in PARTS:
        raise ConfigError(f"part must be one of {PARTS}, got {part!r}")
    timings, results = Path(timings), Path(results)
    if not timings.is_file():
        print(f"{results} left as it was: no notebook ran in this invocation ({timings} does not exist)")
        return None
    runs = read_runs(timings)
    if (why := _incomplete(runs, expected)) is not None:
        print(f"{results} left as it was: not a whole run ({why}); a whole run needs `make clean` first")
        return None
    written = summarize(runs, command, str(timings), **summary)
    with locked(results.parent):  # a paper and a QUICK run may finish at once
        data = _read_results(results)
        figures = data.get("figures_s") or {}
        quick = {"quick": figures["quick"]} if "quick" in figures else {}
        data["figures_s"] = {**written, **quick} if part == "paper" else {**figures, "quick": written}
        write_text(results, json.dumps(data, indent=2) + "\n")
    print(f"{results}: figures_s{'.quick' if part == 'quick' else ''} = {written['total']:.0f} s ({timings})")
    return written


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min"


def _row(part: str, figures: Mapping[str, Any] | None, targets: Mapping[str, float]) -> str:
    """One row of the pipeline's table: a part's time, its run, its target and whether it is met."""
    label, target = _ROWS[part][0], targets.get(_ROWS[part][1])
    bound = f"≤ {target:,.0f} s" if target is not None else "(none)"
    if not figures:
        return f"| {label} | not measured | | | {bound} | |"
    m, total = figures["machine"], figures["total"]
    verdict = "" if target is None else ("met" if total <= target else "**missed**")
    at = "commit unknown" if figures["commit"] == "unknown" else f"at {figures['commit']}"
    run = f"{m['cpu']}, {m['cores']} cores, {figures['date']}, {at}: `{figures['command']}`"
    wall = f"**{total:,.0f} s** ({_duration(total)}) | {figures['sum_of_notebooks']:,.0f} s"
    return f"| {label} | {wall} | {run} | {bound} | {verdict} |"


def sync_readmes(
    results: str | os.PathLike[str],
    readme: str | os.PathLike[str] | None = "README.md",
    bench_readme: str | os.PathLike[str] | None = "benchmarks/README.md",
) -> list[Path]:
    """Write the READMEs' sentence and table from ``results`` between their markers; the files changed."""
    data = _read_results(Path(results))
    if "total" not in (figures := data.get("figures_s") or {}):
        raise ConfigError(f"{results} has no paper-scale figures_s: `make figures` (paper scale) writes it")
    m, changed = figures["machine"], []
    sentence = (
        f"on {m['cores']} cores `make figures` took {_duration(figures['total'])} "
        f"({m['cpu']}, {figures['date']}, at {figures['commit']}: `figures_s` in benchmarks/results.json)"
    )
    if readme is not None and sync_between(readme, README_MARKERS, sentence, inline=True):
        changed.append(Path(readme))
    head = "| run | wall time | sum of its notebooks | the run that measured it (`figures_s`) | target | |"
    targets = data.get("targets", {})
    rows = [_row("paper", figures, targets), _row("quick", figures.get("quick"), targets)]
    table = "\n".join([head, "| --- | ---: | ---: | --- | --- | --- |", *rows])
    if bench_readme is not None and sync_between(bench_readme, BENCH_MARKERS, table):
        changed.append(Path(bench_readme))
    return changed


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point: record a whole run's times, then sync the READMEs from them."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("timings", help="the run's timings.jsonl (build/timings.jsonl)")
    parser.add_argument("--part", choices=PARTS, required=True, help="paper scale, or QUICK=1")
    parser.add_argument("--expect", nargs="+", required=True, help="the notebooks of a whole run")
    parser.add_argument("--command", required=True, help="the command that ran them, for the record")
    parser.add_argument("--results", default="benchmarks/results.json", help="the file of figures_s")
    parser.add_argument("--readme", default="README.md", help="the README with the figures-time markers")
    parser.add_argument("--bench-readme", default="benchmarks/README.md", help="the figures-table's README")
    args = parser.parse_args(argv)
    try:
        record_figures(args.timings, args.results, args.part, args.expect, args.command)
        changed = sync_readmes(args.results, args.readme, args.bench_readme)
    except (ConfigError, ArtifactError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wall times: {', '.join(map(str, changed)) or 'the READMEs already current'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
