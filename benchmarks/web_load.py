"""Load test of the web study's server: N simulated participants at 10 Hz on localhost.

A script, not part of the ``lasa`` library, and not a test. It schedules a throw-away study,
starts ``python -m lasa.live.web`` (no frames) in its own process, and for each N of
``--clients`` connects N WebSocket clients that consent, start their practice and send the
stick at 10 Hz for ``--duration`` seconds, then end the practice. Every participant's loop
runs :meth:`lasa.live.teleop.Station.step` on the server, each condition as the schedule
orders it (the LA conditions need the decoders of ``--build-dir``).

**Tick time** is read from the sessions the server logged: tick k's ``time`` column is when
it finished, counted from the session's start, so ``time - k * dt`` is how long after its
scheduled start the tick was done (waiting for a worker thread included). A server keeps up
at N when that time's p99 is at most one period (100 ms). The script prints, for each N, p50
and p99 of it, the server's late ticks, and the largest N with p99 <= 100 ms, and writes them
as JSON to ``--out`` if given.

Usage, from the repository root::

    python benchmarks/web_load.py                          # N = 1, 2, 4, 8, 16; 60 s each
    python benchmarks/web_load.py --duration 5 --clients 1,2,4   # a smoke run
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
DT = 0.1  # the Panda's control period [s]


def free_port() -> int:
    """A free TCP port on localhost."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def listening(port: int) -> bool:
    """Whether something accepts connections on ``port`` of localhost."""
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) == 0


async def participant(url: str, origin: str, duration: float) -> None:
    """One simulated participant: consent, start the practice, a slowly turning stick at 10 Hz, finish."""
    from websockets.asyncio.client import connect

    async with connect(url, origin=origin, max_size=2**20) as ws:  # type: ignore[arg-type]
        assert json.loads(await ws.recv())["kind"] == "consent"
        await ws.send(json.dumps({"type": "consent"}))
        assert json.loads(await ws.recv())["kind"] == "practice"
        await ws.send(json.dumps({"type": "start"}))
        reader = asyncio.create_task(drain(ws))
        start = time.monotonic()
        k = 0
        while time.monotonic() - start < duration:
            angle = 0.3 * k * DT
            await ws.send(json.dumps({"type": "input", "axes": [np.cos(angle), np.sin(angle)]}))
            k += 1
            await asyncio.sleep(max(0.0, start + k * DT - time.monotonic()))
        await ws.send(json.dumps({"type": "finish"}))
        await asyncio.sleep(3 * DT)
        reader.cancel()


async def drain(ws: object) -> None:
    """Read (and drop) the server's messages, as a page would."""
    async for _ in ws:  # type: ignore[attr-defined]
        pass


def tick_times(folder: Path, participants: list[str]) -> tuple[np.ndarray, int]:
    """Every logged tick's time after its scheduled start [s], and the late ticks, of ``participants``."""
    times, late = [], 0
    for pid in participants:
        for csv in (folder / "practice").glob(f"{pid}_*.csv"):
            frame = pd.read_csv(csv)
            times.append(frame.time.to_numpy() - frame.step.to_numpy() * DT)
            late += int(frame.late.sum())
    return (np.concatenate(times) if times else np.zeros(0)), late


async def level(port: int, tokens: dict[str, str], duration: float) -> None:
    """N participants at once (N = len(tokens))."""
    origin = f"http://127.0.0.1:{port}"
    await asyncio.gather(
        *(participant(f"ws://127.0.0.1:{port}/ws?token={t}", origin, duration) for t in tokens.values())
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--clients", default="1,2,4,8,16", help="numbers of participants to try [%(default)s]"
    )
    parser.add_argument("--duration", type=float, default=60.0, help="seconds per number [%(default)s]")
    parser.add_argument("--build-dir", default="build", help="where make figures left the decoders")
    parser.add_argument("--out", help="write the results as JSON here")
    args = parser.parse_args(argv)
    levels = [int(n) for n in args.clients.split(",")]
    sys.path.insert(0, str(ROOT))
    from lasa.live.web.tokens import issue_links

    folder = Path(tempfile.mkdtemp(prefix="web_load_"))
    port = free_port()
    links = pd.read_csv(issue_links(sum(levels), folder, f"http://127.0.0.1:{port}"))
    tokens = dict(zip(links.participant, (lk.split("token=", 1)[1] for lk in links.link), strict=True))
    command = [sys.executable, "-m", "lasa.live.web", "--port", str(port), "--sessions", str(folder)]
    command += ["--build-dir", args.build_dir, "--frames", "none", "--practice-s", str(args.duration + 30)]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    server = subprocess.Popen(command, env=env, stderr=subprocess.DEVNULL)
    results = []
    try:
        deadline = time.monotonic() + 60
        while not listening(port):
            if time.monotonic() > deadline or server.poll() is not None:
                raise SystemExit("the server did not start")
            time.sleep(0.2)
        names = list(tokens)
        for n in levels:
            group, names = names[:n], names[n:]
            asyncio.run(level(port, {p: tokens[p] for p in group}, args.duration))
            times, late = tick_times(folder, group)
            row = {"clients": n, "ticks": int(times.size), "late": late}
            row |= {
                "p50_ms": 1e3 * float(np.percentile(times, 50)),
                "p99_ms": 1e3 * float(np.percentile(times, 99)),
            }
            results.append(row)
            print(f"N={n:3d}: {row['ticks']} ticks, p50 {row['p50_ms']:.1f} ms, ", end="")
            print(f"p99 {row['p99_ms']:.1f} ms, late {late}")
    finally:
        server.terminate()
        server.wait(10)
    ok = [r["clients"] for r in results if r["p99_ms"] <= 1e3 * DT]
    summary = {
        "duration_s": args.duration,
        "levels": results,
        "largest_n_p99_within_period": max(ok, default=0),
    }
    print(f"largest N with p99 <= 100 ms: {summary['largest_n_p99_within_period']}")
    if args.out:
        Path(args.out).write_text(json.dumps(summary, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
