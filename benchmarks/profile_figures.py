"""Where ``make figures`` spends its time, per notebook, from one py-spy recording of the whole run.

Record (py-spy is pinned in ``environment.lock``), then read::

    .venv/bin/py-spy record --subprocesses --rate 20 --format raw -o build/figures.raw -- make figures
    .venv/bin/python benchmarks/profile_figures.py build/figures.raw --top 8

py-spy's raw format is one line per distinct stack, ``frame;frame;... count``, and with
``--subprocesses`` each stack starts with its processes' command lines: a notebook's kernel hangs
below the ``lasa.pipeline.execute`` process that names the notebook and the robot. Per notebook this
prints its samples' share of the run, and the functions with the largest share of its samples:
*inclusive* (the function or anything it calls; ``lasa`` functions only, the places to act on) and
*self* (where the CPU is, any library's).
"""

from __future__ import annotations

import argparse
import collections
import re
import sys
from pathlib import Path

Profiles = dict[str, tuple[collections.Counter[str], collections.Counter[str], int]]
RUNNER = re.compile(r"lasa\.pipeline\.runner notebooks/(\w+)\.ipynb.*?(?:--robot (\w+))?\"")


def _frame(text: str) -> str:
    """``name (file)``, the file shortened to the package's path (``lasa/method/step.py``)."""
    name, _, where = text.rpartition(" (")
    path = where.split(":")[0].rstrip(")")
    for marker in ("site-packages/", "/lasa/"):
        if marker in path:
            path = ("lasa/" if marker == "/lasa/" else "") + path.split(marker, 1)[1]
    return f"{name} ({path})"


def read(path: Path) -> Profiles:
    """Per notebook (``stem-robot``): inclusive and self sample counts per frame, and its total."""
    out: Profiles = {}
    for line in path.read_text(errors="replace").splitlines():
        stack, _, count = line.rpartition(" ")
        match = RUNNER.search(stack)
        if not count.isdigit() or match is None or "ipykernel" not in stack:
            continue
        name = match.group(1) + (f"-{match.group(2)}" if match.group(2) else "")
        frames = [_frame(f) for f in stack.split(";") if not f.startswith("process ")]
        if not frames:
            continue
        inclusive, own, total = out.get(name, (collections.Counter(), collections.Counter(), 0))
        own[frames[-1]] += int(count)
        for frame in set(frames):
            inclusive[frame] += int(count)
        out[name] = (inclusive, own, total + int(count))
    return out


def report(
    profiles: dict[str, tuple[collections.Counter[str], collections.Counter[str], int]], top: int
) -> str:
    """Markdown: per notebook, its share of the run and its top inclusive and self entries."""
    run = sum(total for _, _, total in profiles.values()) or 1
    lines = []
    for name, (inclusive, own, total) in sorted(profiles.items(), key=lambda kv: -kv[1][2]):
        lasa = [(f, n) for f, n in inclusive.most_common() if "(lasa/" in f and not f.startswith("<module>")]
        lines += [f"### {name}: {100 * total / run:.1f}% of the run's samples", ""]
        lines += [f"- inclusive {100 * n / total:4.1f}% {f}" for f, n in lasa[:top]]
        lines += [f"- self {100 * n / total:4.1f}% {f}" for f, n in own.most_common(top)]
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("raw", type=Path, help="py-spy's --format raw output of a make figures run")
    parser.add_argument("--top", type=int, default=8, help="entries per list [%(default)s]")
    args = parser.parse_args(argv)
    profiles = read(args.raw)
    if not profiles:
        print(
            f"error: no notebook kernel's stack in {args.raw} (recorded with --subprocesses?)",
            file=sys.stderr,
        )
        return 2
    print(report(profiles, args.top))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
