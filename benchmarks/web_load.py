"""Load test of the web study's server: N simulated participants at 10 Hz on localhost.

A script, not part of the ``lasa`` library, and not a test. It schedules a throw-away study
and, for each mode of ``--modes`` (``--frames server``: the server renders JPEG frames;
``--frames browser``: it sends the state only and the page draws the robot), starts
``python -m lasa.live.web`` in its own process and, for each N of ``--clients``, connects N
WebSocket clients that consent, start their practice and send the stick at 10 Hz for
``--duration`` seconds, then end the practice. Every participant's loop runs
:meth:`lasa.live.station.Station.step` on the server, each condition as the schedule orders it
(the LA conditions need the decoders of ``--build-dir``). The simulated clients read and drop
what the server sends (frames included) and draw nothing, so what differs between the modes is
the server's own work per tick: rendering and encoding frames, or not. The script also counts
the frames each client received per second (server mode; the browser draws every tick itself).

**Tick time** is read from the sessions the server logged: tick k's ``time`` column is when
it finished, counted from the session's start, so ``time - k * dt`` is how long after its
scheduled start the tick was done (waiting for a worker thread included). A server keeps up
at N when that time's p99 is at most one period (100 ms). The script prints, for each mode
and N, p50 and p99 of it, the server's late ticks, and the largest N with p99 <= 100 ms.

**In a browser** (unless ``--no-chromium``): headless Chromium opens one participant's page of
a ``--frames browser`` server, as ``tests/test_web.py`` does, starts the practice and reports
the time to load MuJoCo's WebAssembly module and the scene in the page, the frames it drew and
whether its canvas holds a picture (its PNG's size, a blank canvas's being about 2 KB).

Everything goes to ``--out`` as JSON if given.

Usage, from the repository root::

    python benchmarks/web_load.py                          # both modes, N = 1, 2, 4, 8, 12; 10 s each
    python benchmarks/web_load.py --duration 5 --clients 1,2 --modes browser   # a smoke run
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
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


async def participant(url: str, token: str, origin: str, duration: float) -> int:
    """One simulated participant: its token, consent, start the practice, a slowly turning stick at
    10 Hz, finish; returns the frames (binary messages) it received."""
    from websockets.asyncio.client import connect

    async with connect(url, origin=origin, max_size=2**20) as ws:  # type: ignore[arg-type]
        await ws.send(json.dumps({"type": "hello", "token": token}))
        assert json.loads(await ws.recv())["kind"] == "consent"
        await ws.send(json.dumps({"type": "consent"}))
        assert json.loads(await ws.recv())["kind"] == "practice"
        await ws.send(json.dumps({"type": "start"}))
        await ws.send(json.dumps({"type": "ready"}))  # --frames browser: the clock starts (it draws nothing)
        frames = [0]
        reader = asyncio.create_task(drain(ws, frames))
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
        return frames[0]


async def drain(ws: object, frames: list[int]) -> None:
    """Read (and drop) the server's messages, counting the frames (binary messages) in ``frames[0]``."""
    async for message in ws:  # type: ignore[attr-defined]
        frames[0] += isinstance(message, bytes)


def tick_times(folder: Path, participants: list[str]) -> tuple[np.ndarray, int]:
    """Every logged tick's time after its scheduled start [s], and the late ticks, of ``participants``."""
    times, late = [], 0
    for pid in participants:
        for csv in (folder / "practice").glob(f"{pid}_*.csv"):
            frame = pd.read_csv(csv)
            times.append(frame.time.to_numpy() - frame.step.to_numpy() * DT)
            late += int(frame.late.sum())
    return (np.concatenate(times) if times else np.zeros(0)), late


async def level(port: int, tokens: dict[str, str], duration: float) -> list[int]:
    """N participants at once (N = len(tokens)); the frames each received."""
    origin = f"http://127.0.0.1:{port}"
    return await asyncio.gather(
        *(participant(f"ws://127.0.0.1:{port}/ws", t, origin, duration) for t in tokens.values())
    )


def serve(folder: Path, port: int, mode: str, args: argparse.Namespace) -> subprocess.Popen[bytes]:
    """``python -m lasa.live.web`` on ``port`` in ``mode``, once it accepts connections."""
    command = [sys.executable, "-m", "lasa.live.web", "--port", str(port), "--sessions", str(folder)]
    command += ["--build-dir", args.build_dir, "--frames", mode, "--practice-s", str(args.duration + 30)]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    server = subprocess.Popen(command, env=env, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while not listening(port):
        if time.monotonic() > deadline or server.poll() is not None:
            server.terminate()
            raise SystemExit(f"the server (--frames {mode}) did not start")
        time.sleep(0.2)
    return server


def in_chromium(port: int, token: str, seconds: float = 60.0) -> dict[str, float]:
    """One participant's page in headless Chromium: load times of the wasm module and the scene, frames
    drawn, and the canvas's PNG size (a few seconds after the first frame)."""
    import shutil

    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    options = Options()
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader"):
        options.add_argument(arg)
    options.binary_location = shutil.which("chromium") or "chromium"
    browser = webdriver.Chrome(options=options, service=Service(shutil.which("chromedriver")))
    try:
        browser.get(f"http://127.0.0.1:{port}/study#token={token}")
        t0 = time.monotonic()
        while time.monotonic() - t0 < seconds:
            if browser.find_element(By.ID, "agree").is_displayed():
                browser.find_element(By.ID, "agree").click()
            if browser.find_element(By.ID, "start").is_displayed():
                browser.find_element(By.ID, "start").click()
                break
            time.sleep(0.1)
        clicked = time.monotonic()
        stats: dict[str, float] = {}
        while time.monotonic() - clicked < seconds:
            stats = browser.execute_script("return window.lasaView || {}")
            if stats.get("frames", 0) >= 20:
                break
            time.sleep(0.2)
        png = browser.execute_script("return document.getElementById('canvas').toDataURL('image/png').length")
        blank = browser.execute_script(
            "const c = document.createElement('canvas'); c.width = 480; c.height = 360; "
            "return c.toDataURL('image/png').length"
        )
        return {
            "module_load_ms": float(stats.get("moduleMs") or float("nan")),
            "scene_load_ms": float(stats.get("modelMs") or float("nan")),
            "frames_drawn": int(stats.get("frames", 0)),
            "geoms_drawn": int(stats.get("geoms", 0)),
            "canvas_png_chars": int(png),
            "blank_png_chars": int(blank),
        }
    finally:
        browser.quit()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--clients", default="1,2,4,8,12", help="numbers of participants to try [%(default)s]"
    )
    parser.add_argument("--duration", type=float, default=10.0, help="seconds per number [%(default)s]")
    parser.add_argument("--modes", default="server,browser", help="--frames modes to compare [%(default)s]")
    parser.add_argument("--no-chromium", action="store_true", help="skip the page in headless Chromium")
    parser.add_argument("--build-dir", default="build", help="where make figures left the decoders")
    parser.add_argument("--out", help="write the results as JSON here")
    parser.add_argument("--results", help="merge `web_participants` into this JSON (benchmarks/results.json)")
    args = parser.parse_args(argv)
    levels = [int(n) for n in args.clients.split(",")]
    modes = args.modes.split(",")
    sys.path.insert(0, str(ROOT))
    from lasa.live.web.tokens import issue_links

    folder = Path(tempfile.mkdtemp(prefix="web_load_"))
    wanted = len(modes) * sum(levels) + 1
    # the server checks at startup that every condition can run (lasa.live.web.__main__.preflight)
    if not (Path(args.build_dir) / "models" / "eating_decoder_panda.pt").is_file():
        raise SystemExit(f"no eating decoder in {args.build_dir}: run make figures first")
    total = 4 * math.ceil((wanted + 4) / 4)  # whole rounds of the Latin square
    links = pd.read_csv(issue_links(total, folder, "http://127.0.0.1"))
    tokens = dict(zip(links.participant, (lk.split("token=", 1)[1] for lk in links.link), strict=True))
    names = list(tokens)
    summary: dict[str, object] = {"duration_s": args.duration, "cpus": os.cpu_count(), "modes": {}}
    for mode in modes:
        port = free_port()
        server = serve(folder, port, mode, args)
        results = []
        try:
            for n in levels:
                group, names = names[:n], names[n:]
                frames = asyncio.run(level(port, {p: tokens[p] for p in group}, args.duration))
                times, late = tick_times(folder, group)
                row = {"clients": n, "ticks": int(times.size), "late": late}
                row["frames_per_s_each"] = float(np.mean(frames)) / args.duration
                row |= {
                    "p50_ms": 1e3 * float(np.percentile(times, 50)),
                    "p99_ms": 1e3 * float(np.percentile(times, 99)),
                }
                results.append(row)
                print(
                    f"--frames {mode:7s} N={n:3d}: {row['ticks']} ticks, p50 {row['p50_ms']:.1f} ms, ", end=""
                )
                print(f"p99 {row['p99_ms']:.1f} ms, late {late}, ", end="")
                print(f"{row['frames_per_s_each']:.1f} frames/s each", flush=True)
            if mode == "browser" and not args.no_chromium:
                page = in_chromium(port, tokens[names.pop()])
                summary["chromium"] = page
                print(f"in Chromium: {page}", flush=True)
        finally:
            server.terminate()
            server.wait(10)
        ok = [r["clients"] for r in results if r["p99_ms"] <= 1e3 * DT]
        summary["modes"][mode] = {"levels": results, "largest_n_p99_within_period": max(ok, default=0)}  # type: ignore[index]
        print(f"--frames {mode}: largest N with p99 <= 100 ms: {max(ok, default=0)}", flush=True)
    if args.out:
        Path(args.out).write_text(json.dumps(summary, indent=2) + "\n")
    if args.results:
        record_participants(Path(args.results), summary)
    return 0


def record_participants(path: Path, summary: dict[str, object]) -> None:
    """Merge ``web_participants`` into the bench's results: per mode the largest N whose p99 tick is
    within the 100 ms period, with that level's p50 and p99; the headline is the best mode's."""
    modes = summary["modes"]
    assert isinstance(modes, dict)
    per_mode = {}
    for mode, found in modes.items():
        best = found["largest_n_p99_within_period"]
        at = next((r for r in found["levels"] if r["clients"] == best), {})
        per_mode[mode] = {"participants": best, "p50_ms": at.get("p50_ms"), "p99_ms": at.get("p99_ms")}
    head = max(per_mode, key=lambda m: per_mode[m]["participants"])
    results = json.loads(path.read_text()) if path.is_file() else {}
    results["web_participants"] = {
        **per_mode[head],
        "mode": head,
        "goal": 8,
        "duration_s": summary["duration_s"],
        "by_mode": per_mode,
        "levels": summary,
    }
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(results, indent=2) + "\n")
    tmp.replace(path)


if __name__ == "__main__":
    raise SystemExit(main())
