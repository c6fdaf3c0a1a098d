"""The web study: refused requests write nothing; a browser's trial is logged as `teleop run` logs it;
the page draws the robot from server frames or with MuJoCo's WebAssembly build."""

import contextlib
import json
import re
import shutil
import socket
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from starlette.websockets import WebSocketDisconnect

from lasa.base.errors import ArtifactError, ConfigError
from lasa.evidence.sessionlog import read_session
from lasa.live.teleop import replay
from lasa.live.web.app import NPM_PACKAGES, WebConfig, create_app
from lasa.live.web.plan import Progress, plan_of
from lasa.live.web.protocol import MAX_MESSAGE_BYTES
from lasa.live.web.tokens import check_participant, issue_links, study_dir

with warnings.catch_warnings():  # Starlette 1.x suggests httpx2 for its test client; httpx works
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient

ROOT = Path(__file__).resolve().parents[1]
ORIGIN = {"origin": "http://testserver"}


@pytest.fixture()
def study(tmp_path):
    """A study of three participants: the sessions folder and each participant's token."""
    sessions = tmp_path / "sessions"
    with pytest.warns(UserWarning, match="unevenly"):  # three of the square's four orders
        links = pd.read_csv(issue_links(3, sessions, "http://testserver"))
    return sessions, {
        p: link.split("token=", 1)[1] for p, link in zip(links.participant, links.link, strict=True)
    }


def client(sessions, **settings):
    config = dict(
        sessions=str(sessions), build_dir="no-decoders", practice_s=30.0, trial_s=0.4, frames="none"
    )
    return TestClient(create_app(WebConfig(**(config | settings))))


def files(sessions):
    return {p.relative_to(sessions): p.stat().st_mtime_ns for p in sessions.rglob("*")}


@contextlib.contextmanager
def connect(app, token, headers=ORIGIN):
    """A participant's connection: ``/ws`` (no token in the URL), the token in its first message."""
    with app.websocket_connect("/ws", headers=headers) as ws:
        ws.send_json({"type": "hello", "token": token})
        yield ws


def agree(ws):
    """Consent, and skip the optional demographics that follow on a participant's first visit."""
    ws.send_json({"type": "consent"})
    assert ws.receive_json()["kind"] == "demographics"
    ws.send_json({"type": "demographics", "skip": True})


def refused(app, token, headers=ORIGIN):
    """Why a connection with ``token`` is refused: "origin" (403, before it opens), the server's
    reason (a ``refused`` message, then close 1008), or None if it was not refused."""
    try:
        with connect(app, token, headers) as ws:
            msg = ws.receive_json()
            if msg["type"] != "refused":
                return None
            with pytest.raises(WebSocketDisconnect) as closed:
                ws.receive_json()
            assert closed.value.code == 1008
            return msg["reason"]
    except WebSocketDisconnect as exc:
        return "origin" if exc.code == 1008 else None


def test_links_carry_random_tokens_stored_as_hashes(study):
    sessions, tokens = study
    assert len(set(tokens.values())) == 3 and all(len(t) >= 40 for t in tokens.values())
    stored = (study_dir(sessions) / "tokens.json").read_text()
    assert not any(t in stored for t in tokens.values())
    assert (study_dir(sessions) / "links.csv").stat().st_mode & 0o077 == 0
    with pytest.raises(ConfigError, match="holds a study already"):
        issue_links(3, sessions, "http://testserver")


@pytest.mark.parametrize("bad", ["../p00", "p00/../../x", "p0", "P01", "p01 ", "", "p12345"])
def test_participant_ids_are_strict(bad):
    with pytest.raises(ConfigError):
        check_participant(bad)


def test_requests_without_a_valid_token_are_refused_and_write_nothing(study, tmp_path):
    sessions, tokens = study
    other = tmp_path / "other"
    with pytest.warns(UserWarning, match="unevenly"):
        other_token = pd.read_csv(issue_links(1, other, "http://x")).link[0].split("token=")[1]
    before = files(sessions)
    with client(sessions) as app:
        for token in ("", "wrong", other_token, "x" * 128):
            assert refused(app, token) == "invalid", token
        for token in ("x" * 129, "x" * 5000, 12, None):  # longer than a token, or not a string
            assert refused(app, token) == "no_hello", token
        assert app.get("/study").status_code == 200  # the page is everyone's: it holds no secret
        assert refused(app, tokens["p01"], headers={"origin": "http://evil.example"}) == "origin"
        assert refused(app, tokens["p01"], headers={}) == "origin"
    assert files(sessions) == before


def test_a_connection_that_sends_no_token_in_time_is_refused(study, monkeypatch):
    from lasa.live.web import app as web_app

    sessions, _ = study
    monkeypatch.setattr(web_app, "HELLO_S", 0.2)
    with client(sessions) as app, app.websocket_connect("/ws", headers=ORIGIN) as ws:
        assert ws.receive_json() == {"type": "refused", "reason": "no_hello"}
        ws.send_json({"type": "consent"})  # too late: the server has closed
        with pytest.raises(WebSocketDisconnect) as closed:
            ws.receive_json()
        assert closed.value.code == 1008


def test_a_token_is_its_own_participants_only_and_ends_with_the_schedule(study):
    sessions, tokens = study
    progress = Progress(sessions)
    progress.of("p02")["step"] = len(plan_of(sessions, "p02"))
    progress._save()
    before = files(sessions)
    with client(sessions) as app:
        assert refused(app, tokens["p02"]) == "finished"  # schedule done
        # the participant comes from the token alone: a client cannot name another one
        with app.websocket_connect("/ws?participant=p00", headers=ORIGIN) as ws:
            ws.send_json({"type": "hello", "token": tokens["p01"], "participant": "p00"})
            assert ws.receive_json()["kind"] == "consent"
            agree(ws)
            assert ws.receive_json()["kind"] == "practice"
    assert Progress(sessions).of("p01")["consented"] and not Progress(sessions).of("p00")["consented"]
    assert {p for p in set(files(sessions)) - set(before) if p.parts[0] != "study"} == set()


def test_a_newer_page_of_a_link_takes_over_and_its_trial_runs_again(study, caplog):
    """Two pages of one link (a reload, a second tab): the newest wins; the older is closed with
    REPLACED, its running trial ends ``interrupted`` and is logged; the newer resumes that step as a
    new attempt."""
    from lasa.live.web.conversation import REPLACED

    sessions, tokens = study
    progress = Progress(sessions)
    progress.consent("p01")
    progress.of("p01")["step"] = 1  # p01's first trial (R+SA, Entree)
    progress._save()
    caplog.set_level("INFO", logger="lasa.live.web")
    with client(sessions, trial_s=30.0) as app, connect(app, tokens["p01"]) as first:
        assert first.receive_json()["task"] == "Entree"
        drive(first, ticks=3)
        with connect(app, tokens["p01"]) as second:
            with pytest.raises(WebSocketDisconnect) as closed:
                while True:
                    first.receive_json()
            assert closed.value.code == REPLACED
            msg = second.receive_json()
            assert (msg["kind"], msg["task"], msg["label"]) == ("trial", "Entree", "A")
            ticks, _ = drive(second, ticks=2)
    (old,) = sessions.glob("p01_Entree_R+SA_*_a1.csv")
    assert read_session(old)[1]["status"] == "interrupted" and len(list(sessions.glob("p01_*_a2.csv"))) == 1
    text = caplog.text
    assert (
        "p01: a newer page takes over" in text
        and f"newer page of the same link took over (close {REPLACED})" in text
    )
    assert "p01: trial Entree, way A (R+SA), attempt 1 interrupted" in text


@pytest.mark.parametrize(
    "message, code",
    [
        ("x" * (10 * 1024 * 1024), 1009),
        ("x" * (MAX_MESSAGE_BYTES + 1), 1009),
        ("not json", 1008),
        (json.dumps({"type": "input", "axes": ["../etc", 1]}), 1008),
        ('{"type": "input", "axes": [NaN, 0]}', 1008),
        (json.dumps({"type": "open", "path": "/etc/passwd"}), 1008),
    ],
)
def test_an_oversized_or_malformed_message_closes_the_connection_and_writes_nothing(study, message, code):
    sessions, tokens = study
    before = files(sessions)
    with client(sessions) as app:
        with connect(app, tokens["p00"]) as ws:
            assert ws.receive_json()["kind"] == "consent"
            ws.send_text(message)
            with pytest.raises(WebSocketDisconnect) as closed:
                ws.receive_json()
            assert closed.value.code == code
    assert files(sessions) == before


def test_a_flood_of_messages_is_cut_off(study):
    sessions, tokens = study
    with client(sessions) as app:
        with connect(app, tokens["p00"]) as ws:
            ws.receive_json()
            for _ in range(200):
                ws.send_json({"type": "input", "axes": [0, 0]})
            with pytest.raises(WebSocketDisconnect) as closed:
                ws.receive_json()
            assert closed.value.code == 1008


def test_a_hand_edited_token_file_cannot_put_a_path_into_a_session(study):
    sessions, tokens = study
    path = study_dir(sessions) / "tokens.json"
    hashes = json.loads(path.read_text())
    path.write_text(json.dumps({"../../evil": hashes["p00"]}))
    before = files(sessions)
    with client(sessions) as app:
        assert refused(app, tokens["p00"]) == "invalid"
    assert files(sessions) == before and not (sessions.parent / "evil").exists()


def drive(ws, ticks=None, axes=(0.6, 0.4)):
    """Start the step shown, send input, read ticks; return them and the next message (None if cut)."""
    ws.send_json({"type": "start"})
    seen = []
    while True:
        ws.send_json({"type": "input", "axes": list(axes), "mode": False, "stop": False})
        msg = ws.receive_json()
        if msg["type"] != "tick":
            return seen, msg
        seen.append(msg)
        if ticks is not None and len(seen) >= ticks:
            return seen, None


def test_a_browser_drives_a_trial_logged_as_teleop_logs_it(study):
    from lasa.evidence.sessions import load_sessions
    from lasa.world.eating import make_eating_task

    sessions, tokens = study
    with client(sessions, show_belief=True) as app:
        with connect(app, tokens["p00"]) as ws:
            ws.receive_json()
            agree(ws)
            assert ws.receive_json() | {"limit_s": 0} == {
                "type": "phase", "kind": "practice", "label": "A", "task": "Dessert",
                "index": 1, "total": 16, "limit_s": 0,
            }  # fmt: skip
            ticks, _ = drive(ws, ticks=3)
            ws.send_json({"type": "finish"})
            while (msg := ws.receive_json())["type"] == "tick":
                pass
            assert msg["kind"] == "trial" and msg["task"] == "Entree"
            ticks, nxt = drive(ws)
            assert nxt["kind"] == "trial" and nxt["task"] == "Dessert"
    assert len(ticks) == 4 and ticks[-1]["step"] == 4 and len(ticks[-1]["belief"]) == 4
    assert {"q", "belief", "goals", "instruction", "late"} <= set(ticks[-1])
    assert ticks[-1]["goals"] == ["rice", "tofu, marshmallows", "icing", "plate"]  # as the labels name them
    assert abs(sum(ticks[-1]["belief"]) - 1) < 1e-9 and ticks[-1]["q"] != ticks[0]["q"]
    (practice,) = (sessions / "practice").glob("*.csv")
    (entree,) = sessions.glob("p00_Entree_R_*_a2.csv")
    for suffix in (".csv", ".json", ".xml"):
        assert entree.with_suffix(suffix).is_file()
    frame, meta = read_session(entree)
    assert meta["status"] == "complete" and meta["steps"] == len(frame) == 4
    assert meta["interface"] == "web" and meta["participant"] == "p00" and "deadline_misses" in meta
    assert read_session(practice)[1]["status"] == "complete"
    result = replay(entree)
    assert result["exact"] and result["steps"] == 4
    episodes = load_sessions(sessions, make_eating_task())
    assert list(episodes.participant) == ["p00"] and list(episodes.task) == ["Entree"]
    assert list(episodes.order) == [0] and meta["disconnected_ticks"] == 0  # input before every tick


def test_a_disconnect_leaves_the_session_interrupted_and_the_link_resumes_anew(study):
    sessions, tokens = study
    progress = Progress(sessions)
    progress.consent("p01")
    progress.of("p01")["step"] = 1  # p01's first trial (R+SA, Entree)
    progress._save()
    with client(sessions, trial_s=30.0) as app:
        with connect(app, tokens["p01"]) as ws:
            assert ws.receive_json()["task"] == "Entree"
            drive(ws, ticks=3)
        deadline = time.monotonic() + 10
        while not list(sessions.glob("p01_*.csv")) and time.monotonic() < deadline:
            time.sleep(0.05)  # the server notices at its next tick
        (first,) = sessions.glob("p01_*.csv")
        frame, meta = read_session(first)
        assert meta["status"] == "interrupted" and len(frame) >= 3 and meta["steps"] == len(frame)
        kept = first.read_bytes()
        with connect(app, tokens["p01"]) as ws:
            msg = ws.receive_json()
            assert (msg["kind"], msg["task"], msg["label"]) == ("trial", "Entree", "A")  # R+SA, first for p01
            drive(ws, ticks=2)
    assert first.read_bytes() == kept and len(list(sessions.glob("p01_Entree_R+SA_*.csv"))) == 2


def test_a_server_shutdown_mid_step_logs_that_step_before_closing_interrupted(tmp_path, monkeypatch):
    """Cancelling the loop (the server stopping) while a step runs: the step's row goes in, then the
    log closes ``interrupted`` with every row it ran, and no step writes to a closed log."""
    import asyncio

    from lasa.live.station import SessionConfig
    from lasa.live.web import conversation
    from lasa.live.web.protocol import Inputs

    trial = conversation.open_trial(SessionConfig(task="Entree", condition="R"), tmp_path, 1, 30.0)
    in_step, real_tick, errors = threading.Event(), conversation.tick, []

    def slow_tick(trial, sample):
        if trial.steps == 3:
            in_step.set()
            time.sleep(0.3)  # the cancel lands while this step runs
        try:
            return real_tick(trial, sample)
        except Exception as exc:  # a write to a closed log would land here
            errors.append(exc)
            raise

    monkeypatch.setattr(conversation, "tick", slow_tick)

    async def main():
        async def send(message):
            pass

        task = asyncio.create_task(conversation.run_trial(trial, Inputs(), send, lambda: True, lambda: False))
        while not in_step.is_set():
            await asyncio.sleep(0.01)
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task

    asyncio.run(main())
    frame, meta = read_session(trial.writer.csv)
    assert errors == [] and meta["status"] == "interrupted"
    assert trial.steps == 4 and meta["steps"] == len(frame) == 4 and frame.step.tolist() == [0, 1, 2, 3]


def test_the_survey_is_stored_as_the_terminal_survey_stores_it(study):
    from lasa.evidence.sessions import read_likert

    sessions, tokens = study
    progress = Progress(sessions)
    progress.consent("p00")
    progress.of("p00")["step"] = 3
    progress._save()
    with client(sessions) as app:
        with connect(app, tokens["p00"]) as ws:
            msg = ws.receive_json()
            assert msg["kind"] == "survey" and len(msg["questions"]) == 5
            ws.send_json({"type": "survey", "answers": [9, 1, 1, 1, 1]})
            assert ws.receive_json()["type"] == "error"
            ws.send_json({"type": "survey", "answers": [7, 6, 5, 4, 3], "tlx": [50, 40, 30, 20, 10, 0]})
            assert ws.receive_json()["label"] == "B"  # R+SA, p00's second condition
    likert = read_likert(sessions)
    assert list(likert.answer) == [7, 6, 5, 4, 3] and set(likert.condition) == {"R"}


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def served(config):
    """The real server (uvicorn) on a free port, in a thread; yields the port."""
    import uvicorn

    port = _free_port()
    server = uvicorn.Server(
        uvicorn.Config(create_app(config), host="127.0.0.1", port=port, log_level="warning")
    )
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        while not server.started:
            time.sleep(0.05)
        yield port
    finally:
        server.should_exit = True
        thread.join(10)


@contextlib.contextmanager
def chromium(*extra):
    """Headless Chromium; WebGL through its software renderer (SwiftShader), as on a machine without a GPU;
    ``extra``: more command-line switches."""
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    binary, driver = shutil.which("chromium"), shutil.which("chromedriver")
    assert binary and driver, "Chromium or its driver is missing: run `make setup`"
    options = Options()
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader"):
        options.add_argument(arg)
    options.add_argument("--window-size=1100,800")
    for arg in extra:
        options.add_argument(arg)
    options.binary_location = binary
    browser = webdriver.Chrome(options=options, service=Service(driver))
    try:
        yield browser
    finally:
        browser.quit()


def consent_and_start(browser, url):
    """Open ``url``, consent, start the practice and hold the stick right and up."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    browser.get(url)
    wait_for(lambda: browser.find_element(By.ID, "agree").is_displayed())
    browser.find_element(By.ID, "agree").click()
    wait_for(lambda: browser.find_element(By.ID, "demographics-skip").is_displayed())
    browser.find_element(By.ID, "demographics-skip").click()
    wait_for(lambda: browser.find_element(By.ID, "start").is_displayed())
    assert browser.find_element(By.ID, "intro-title").text == "Practice: way A"  # never a code
    stick_check(browser)
    browser.find_element(By.ID, "start").click()
    ActionChains(browser).key_down(Keys.ARROW_RIGHT).key_down(Keys.ARROW_UP).perform()


def stick_check(browser):
    """The check before the first practice: Start is disabled until each arrow key has been held."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    start = browser.find_element(By.ID, "start")
    for n, key in enumerate((Keys.ARROW_LEFT, Keys.ARROW_RIGHT, Keys.ARROW_UP, Keys.ARROW_DOWN)):
        assert not start.is_enabled()
        ActionChains(browser).key_down(key).perform()
        wait_for(lambda n=n: len(browser.find_elements(By.CSS_SELECTOR, "#check .reached")) == n + 1)
        ActionChains(browser).key_up(key).perform()
    wait_for(start.is_enabled)


def belief_shown(browser):
    """The page's belief bars: four, summing to 1, moved by the held stick."""
    from selenium.webdriver.common.by import By

    bars = browser.find_elements(By.CSS_SELECTOR, "#belief .goal")
    assert len(bars) == 4 and re.fullmatch(r"\d+:\d\d left", browser.find_element(By.ID, "left").text)
    assert "Dessert" in browser.find_element(By.ID, "instruction").text
    # one read of all four in the page's own script, between two of its 10 Hz updates: read one at a time,
    # the bars could come from different ticks (the capped belief keeps moving at 0.99), summing to 1.06
    script = (
        "return [...document.querySelectorAll('#belief .goal .value')].map((e) => parseFloat(e.textContent))"
    )
    values = browser.execute_script(script)
    assert abs(sum(values) - 1) < 0.03 and max(values) > 0.3  # the held stick moved the belief


def ticks_seen(browser):
    """The page's latest tick (a hidden data attribute: the page shows no counter)."""
    from selenium.webdriver.common.by import By

    return int(browser.find_element(By.ID, "drive").get_attribute("data-tick") or 0)


def no_counters_shown(browser):
    """The drive view shows the instruction and the time left, no tick, late-tick or stick numbers."""
    from selenium.webdriver.common.by import By

    text = browser.find_element(By.ID, "drive").text
    assert re.search(r"\d+:\d\d left", text) and not re.search(
        r"(?i)\b(?:tick|late|stick)\b|\d\.\d\d", text
    ), text


def labels_shown(browser):
    """The goals' names over the picture (what is at each, as the instructions name it), in the picture
    (its box), rice right of the plate."""
    from selenium.webdriver.common.by import By

    stage = browser.find_element(By.CSS_SELECTOR, ".stage").rect
    spans = {s.text: s.rect for s in browser.find_elements(By.CSS_SELECTOR, "#labels span")}
    assert set(spans) == {"rice", "tofu, marshmallows", "icing", "plate"}, spans
    for rect in spans.values():
        assert stage["x"] < rect["x"] < stage["x"] + stage["width"]
        assert stage["y"] < rect["y"] < stage["y"] + stage["height"]
    assert spans["rice"]["x"] > spans["plate"]["x"]


def end_practice(browser):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    ActionChains(browser).key_up(Keys.ARROW_RIGHT).key_up(Keys.ARROW_UP).perform()
    browser.find_element(By.ID, "ready").click()
    wait_for(lambda: browser.find_element(By.ID, "intro").is_displayed())


def test_a_real_browser_consents_drives_and_sees_the_goals_and_ticks(study, report_artifact, tmp_path):
    """Headless Chromium against the real server (uvicorn), frames from the server, the study's
    defaults: consent, the practice, keys held for a few ticks; the page shows the goals' names
    over a frame, the time left and no counter, and no belief (off by default)."""
    from PIL import Image
    from selenium.webdriver.common.by import By

    sessions, tokens = study
    # the default practice (5 minutes): longer than every wait below, so on a loaded machine it never ends
    # by its limit mid-test; the screenshot shows the defaults
    config = WebConfig(sessions=str(sessions), build_dir="no-decoders", practice_s=300.0, frames="server")
    with served(config) as port, chromium() as browser:
        consent_and_start(browser, f"http://127.0.0.1:{port}/study#token={tokens['p00']}")
        wait_for(lambda: ticks_seen(browser) >= 20, timeout=60)
        wait_for(lambda: browser.execute_script("return document.getElementById('view').naturalWidth") > 0)
        no_counters_shown(browser)
        assert not browser.find_element(By.ID, "belief-panel").is_displayed()
        labels_shown(browser)
        # the committed docs/web_study.png is this screenshot; the test never writes into the tree
        shot = tmp_path / "web_study.png"
        browser.save_screenshot(str(shot))
        report_artifact("the web study's page, driving", shot)
        end_practice(browser)
    assert np.asarray(Image.open(shot).convert("L"), dtype=float).std() > 20
    (practice,) = (sessions / "practice").glob("p00_*.csv")
    frame, meta = read_session(practice)
    assert meta["status"] == "complete" and (frame[["z0", "z1"]].to_numpy() == [1.0, 1.0]).all(axis=1).any()


def npm_installed():
    for folder, marker in NPM_PACKAGES.values():
        path = ROOT / ".venv" / folder / marker
        assert path.is_file(), f"{path} is missing: run make setup"


def test_the_npm_packages_are_served_locally_with_their_types(study):
    """MuJoCo's wasm build and three.js come from the server itself, the .wasm as application/wasm."""
    npm_installed()
    sessions, tokens = study
    with client(sessions, frames="browser") as app:
        for url, kind in [
            ("/npm/mujoco/mujoco.wasm", "application/wasm"),
            ("/npm/mujoco/mujoco.js", "text/javascript"),
            ("/npm/three/three.module.js", "text/javascript"),
            ("/npm/three/three.core.js", "text/javascript"),
            ("/static/view.js", "text/javascript"),
        ]:
            reply = app.get(url)
            assert reply.status_code == 200 and reply.headers["content-type"].startswith(kind), url
        assert app.get("/npm/mujoco/mujoco.wasm").content[:4] == b"\0asm"
        for url in (
            "/npm/mujoco/../../pyproject.toml",
            "/npm/mujoco/%2e%2e/%2e%2e/pyproject.toml",
            "/npm/x.js",
        ):
            assert app.get(url).status_code == 404, url
        csp = app.get("/study").headers["content-security-policy"]
        assert "'wasm-unsafe-eval'" in csp and "connect-src 'self'" in csp and "http" not in csp
    with client(sessions, frames="server") as app:  # the JPEG page evaluates no code and loads no wasm
        assert "eval" not in app.get("/study").headers["content-security-policy"]
        assert app.get("/npm/mujoco/mujoco.js").status_code == 404
    with pytest.raises(ConfigError, match="frames is one of"):
        WebConfig(sessions=str(sessions), frames="gpu")


def test_no_step_runs_before_the_page_has_drawn_the_robot(study):
    """--frames browser: the trial's clock waits for the page's ``ready`` (its picture drawn), even with
    the stick held: 1.5 s of input before it (15 ticks' worth) logs no row; after it, ticks come."""
    sessions, tokens = study
    with client(sessions, frames="browser") as app, connect(app, tokens["p00"]) as ws:
        ws.receive_json()
        agree(ws)
        assert ws.receive_json()["kind"] == "practice"
        ws.send_json({"type": "start"})
        assert ws.receive_json()["type"] == "labels" and ws.receive_json()["type"] == "scene"
        for _ in range(15):
            ws.send_json({"type": "input", "axes": [0.5, 0.5]})
            time.sleep(0.1)
        (part,) = (sessions / "practice").glob("p00_*.csv.part")
        assert len(part.read_text().splitlines()) <= 1  # at most the header: no step (rows flush every 10)
        ws.send_json({"type": "ready"})
        ws.send_json({"type": "input", "axes": [0.5, 0.5]})
        tick = ws.receive_json()
        assert tick["type"] == "tick" and tick["step"] == 1


def test_the_scene_route_needs_the_trials_key_and_serves_only_the_servers_files(study):
    """The page gets its trial's scene with the meshes under names the server chose; nothing else."""
    sessions, tokens = study
    before = files(sessions)
    with client(sessions, frames="browser") as app:
        for key in ({}, {"x-scene-key": ""}, {"x-scene-key": "wrong"}, {"x-scene-key": "x" * 5000}):
            assert app.get("/scene", headers=key).status_code == 404
            assert app.get("/scene/asset0.stl", headers=key).status_code == 404
        assert app.get(f"/scene?token={tokens['p00']}").status_code == 404  # a token is not a key
        assert files(sessions) == before
        with connect(app, tokens["p00"]) as ws:
            ws.receive_json()
            agree(ws)
            assert ws.receive_json()["kind"] == "practice"
            ws.send_json({"type": "start"})
            labelled = ws.receive_json()  # the goals' names and their places on the picture
            names = ["rice", "tofu, marshmallows", "icing", "plate"]
            assert [g["name"] for g in labelled["labels"]] == names
            assert all(0.1 < g["x"] < 0.9 and 0.1 < g["y"] < 0.9 for g in labelled["labels"])
            announced = ws.receive_json()
            assert announced["type"] == "scene" and announced["qpos_adr"] == list(range(7))
            key = {"x-scene-key": announced["key"]}
            assert tokens["p00"] not in json.dumps(announced) and len(announced["q"]) == 7
            ws.send_json({"type": "ready"})  # the page has drawn the robot: the trial's clock starts
            ws.send_json({"type": "input", "axes": [0.5, 0.5]})
            assert ws.receive_json()["type"] == "tick"  # state only: no frame in browser mode
            reply = app.get("/scene", headers=key)
            assert reply.status_code == 200 and reply.headers["cache-control"] == "no-store"
            scene = reply.json()
            (logged,) = (sessions / "practice").glob("p00_*.xml")  # the file SessionWriter wrote
            originals = re.findall(r'file="([^"]+)"', logged.read_text())
            assert scene["assets"] == sorted(f"asset{k}.stl" for k in range(len(originals))) != []
            assert 'file="/' not in scene["xml"] and str(ROOT) not in scene["xml"]
            by_name = dict(re.findall(r'name="([^"]+)"[^>]*file="(asset\d+\.stl)"', scene["xml"]))
            for name, source in zip(
                re.findall(r'<mesh name="([^"]+)"', logged.read_text()), originals, strict=True
            ):
                served = app.get(f"/scene/{by_name[name]}", headers=key)
                assert served.headers["content-type"] == "model/stl"
                assert served.content == Path(source).read_bytes()
            for bad in (
                "asset99.stl",
                "..%2F..%2Fpyproject.toml",
                "%2Fetc%2Fpasswd",
                "scene.xml",
                logged.name,
            ):
                assert app.get(f"/scene/{bad}", headers=key).status_code == 404, bad
            assert app.get("/scene/../pyproject.toml", headers=key).status_code == 404
        assert app.get("/scene", headers=key).status_code == 404  # the trial is over: its key too


def test_a_real_browser_draws_the_robot_with_mujoco_wasm(study, report_artifact, tmp_path):
    """Headless Chromium, --frames browser: the page loads MuJoCo's wasm build and the trial's scene from
    the server, draws the robot from each tick's joint positions (the canvas is not blank), and the
    belief and the time left update."""
    import base64
    import io

    from PIL import Image
    from selenium.webdriver.common.by import By

    npm_installed()
    sessions, tokens = study
    config = WebConfig(
        sessions=str(sessions), build_dir="no-decoders", practice_s=300.0, frames="browser", show_belief=True
    )  # the default practice: longer than every wait below (the wasm build can take a minute when loaded)
    with served(config) as port, chromium() as browser:
        consent_and_start(browser, f"http://127.0.0.1:{port}/study#token={tokens['p00']}")
        wait_for(lambda: browser.execute_script("return window.lasaView.frames") >= 10, timeout=90)
        wait_for(lambda: ticks_seen(browser) >= 20, timeout=60)
        first = ticks_seen(browser)
        wait_for(lambda: ticks_seen(browser) > first)
        belief_shown(browser)
        labels_shown(browser)
        stats = browser.execute_script("return window.lasaView")
        assert stats["geoms"] >= 20 and stats["modelMs"] > 0  # the arm's links, the table, the food
        shown = browser.execute_script(
            "return [...document.querySelectorAll('section:not([hidden])')].map((s) => s.id)"
        )
        assert browser.find_element(By.ID, "canvas").is_displayed(), f"the page shows {shown}, not the drive"
        assert not browser.find_element(By.ID, "view").is_displayed()
        url = browser.execute_script("return document.getElementById('canvas').toDataURL('image/png')")
        canvas = Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))).convert("L")
        shot = tmp_path / "web_study_wasm.png"
        browser.save_screenshot(str(shot))
        report_artifact(
            f"the web study's page drawn in the browser (scene loaded in {stats['modelMs']:.0f} ms)", shot
        )
        end_practice(browser)
    pixels = np.asarray(canvas, dtype=float)
    assert pixels.shape == (360, 480) and pixels.std() > 20  # not blank: the robot and the table
    (practice,) = (sessions / "practice").glob("p00_*.csv")
    assert read_session(practice)[1]["status"] == "complete"


def wait_for(condition, timeout=20.0):
    deadline = time.monotonic() + timeout
    while True:
        try:
            if condition():
                return
        except Exception:
            if time.monotonic() > deadline:
                raise
        if time.monotonic() > deadline:
            raise AssertionError("the page did not get there in time")
        time.sleep(0.1)


@pytest.fixture()
def decoder_build(tmp_path):
    """A build folder with an (untrained) eating decoder of the study's shape: LA+SA runs on it."""
    from lasa.method.decoder import DecoderConfig, LatentActionModel, save_checkpoint
    from lasa.world.eating import make_eating_task

    task = make_eating_task()
    config = DecoderConfig(robot="panda", n_joints=7, n_goals=task.n_goals, z_dim=2, hidden=8, depth=1)
    save_checkpoint(LatentActionModel(config), tmp_path / "build" / "models" / "eating_decoder_panda.pt")
    return tmp_path / "build"


def next_step(browser, section):
    """Wait until ``section`` of the page is shown."""
    from selenium.webdriver.common.by import By

    wait_for(lambda: browser.find_element(By.ID, section).is_displayed(), timeout=60)


def test_a_real_browser_takes_part_practice_la_sa_dessert_and_survey(tmp_path, decoder_build):
    """The paper's protocol for one condition in headless Chromium, by keys: consent, a practice,
    the LA+SA Entree and Dessert trials, the survey; the Dessert session then replays exactly, and
    the analysis of people's sessions reads it."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    from lasa.evidence.sessions import analyse_sessions, load_sessions
    from lasa.world.eating import make_eating_task

    sessions = tmp_path / "sessions"  # four participants: one of them starts with LA+SA
    links = pd.read_csv(issue_links(4, sessions, "http://testserver"))
    tokens = {p: link.split("token=", 1)[1] for p, link in zip(links.participant, links.link, strict=True)}
    who = next(p for p in sorted(tokens) if plan_of(sessions, p)[0].condition == "LA+SA")
    config = WebConfig(
        sessions=str(sessions), build_dir=str(decoder_build), practice_s=60.0, trial_s=2.0, frames="none"
    )
    with served(config) as port, chromium() as browser:
        consent_and_start(browser, f"http://127.0.0.1:{port}/study#token={tokens[who]}")  # the practice
        wait_for(lambda: ticks_seen(browser) >= 5, timeout=60)
        end_practice(browser)
        # a gamepad the browser cannot read in the standard layout is not used, and the page says so
        fake = "[{connected: true, mapping: '', id: 'Odd pad', axes: [1, 1], buttons: []}]"
        browser.execute_script(f"navigator.getGamepads = () => {fake};")
        wait_for(lambda: browser.find_element(By.ID, "pad-notice").is_displayed())
        browser.execute_script("navigator.getGamepads = () => [];")
        wait_for(lambda: not browser.find_element(By.ID, "pad-notice").is_displayed())
        for _task in ("Entree", "Dessert"):  # each trial ends at its 2 s limit, keys held
            browser.find_element(By.ID, "start").click()
            ActionChains(browser).key_down(Keys.ARROW_LEFT).perform()
            next_step(browser, "drive")
            wait_for(lambda: browser.find_element(By.ID, "instruction").text == "Time is up", timeout=60)
            wait_for(lambda: not browser.find_element(By.ID, "drive").is_displayed(), timeout=60)
            ActionChains(browser).key_up(Keys.ARROW_LEFT).perform()
        next_step(browser, "survey")
        for question in browser.find_elements(By.CSS_SELECTOR, "#survey-form .question"):
            question.find_elements(By.CSS_SELECTOR, "input")[4].click()  # 5 of 7; 20 of 100 on the TLX
        browser.find_element(By.ID, "submit").click()
        wait_for(lambda: browser.find_element(By.ID, "intro").is_displayed(), timeout=30)
    (dessert,) = sessions.glob(f"{who}_Dessert_LA+SA_*.csv")
    frame, meta = read_session(dessert)
    assert meta["status"] == "complete" and meta["condition"] == "LA+SA" and len(frame) >= 10
    assert (frame.z0 < 0).any()  # the held left arrow reached the step
    assert replay(dessert)["exact"]
    beliefs = frame[[c for c in frame.columns if c.startswith("b") and c[1:].isdigit()]].to_numpy()
    assert meta["control"]["belief_cap"] == 0.99 and beliefs.max() <= 0.99 + 1e-12  # the study's belief
    episodes = load_sessions(sessions, make_eating_task())
    with pytest.warns(UserWarning, match="left out participant"):  # one condition of four: no test
        people = analyse_sessions(sessions, make_eating_task())
    assert set(people["goal_error"].participant) == {who} and list(people["limit"].limit_s) == [2.0]
    assert "LA+SA" in set(people["means"].reset_index().condition), people["means"]
    assert {(who, "LA+SA", "Dessert"), (who, "LA+SA", "Entree")} <= set(
        zip(episodes.participant, episodes.condition, episodes.task, strict=True)
    )
    likert = pd.read_csv(sessions / "likert.csv", dtype={"participant": str})
    mine = likert[(likert.participant == who) & (likert.condition == "LA+SA")]
    assert len(mine) > 0 and (mine.answer == 5).all()
    tlx = pd.read_csv(sessions / "tlx.csv", dtype={"participant": str})  # the fifth of 0, 5, ..., 100
    assert len(tlx) == 6 and (tlx.value == 20).all() and set(tlx.participant) == {who}
    assert meta["device"] == {"kind": "keyboard"}


@contextlib.contextmanager
def cli_server(sessions, build_dir, log, *options, port=None):
    """``python -m lasa.live.web`` (uvicorn's own logging into ``log``) on ``port`` (a free one if
    None); yields the port."""
    import os
    import signal
    import subprocess
    import sys

    port = port or _free_port()
    command = [sys.executable, "-m", "lasa.live.web", "--port", str(port), "--sessions", str(sessions)]
    command += ["--build-dir", str(build_dir), "--frames", "none", "--practice-s", "30", *options]
    starts = log.read_text().count("Uvicorn running") if log.exists() else 0  # earlier runs' lines
    with open(log, "ab") as out:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        server = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, env=env)
        try:
            wait_for(lambda: log.read_text().count("Uvicorn running") > starts, timeout=60)
            yield port
        finally:
            server.send_signal(signal.SIGINT)
            server.wait(timeout=30)


@contextlib.asynccontextmanager
async def _at_practice(port: int, token: str):
    """A page of the real server that has sent its token and consented: its practice is shown."""
    from websockets.asyncio.client import connect as ws_connect

    async with ws_connect(f"ws://127.0.0.1:{port}/ws", origin=f"http://127.0.0.1:{port}") as ws:
        await ws.send(json.dumps({"type": "hello", "token": token}))
        assert json.loads(await ws.recv())["kind"] == "consent"
        await ws.send(json.dumps({"type": "consent"}))
        assert json.loads(await ws.recv())["kind"] == "demographics"
        await ws.send(json.dumps({"type": "demographics", "skip": True}))
        assert json.loads(await ws.recv())["kind"] == "practice"
        yield ws


async def _take_part(port: int, token: str, seconds: float = 1.0) -> None:
    """A participant through the real server: the token, consent, the practice driven, ended."""
    import asyncio

    async with _at_practice(port, token) as ws:
        await ws.send(json.dumps({"type": "start"}))
        for _ in range(int(seconds * 10)):
            await ws.send(json.dumps({"type": "input", "axes": [0.5, -0.5]}))
            assert json.loads(await ws.recv())["type"] == "tick"
            await asyncio.sleep(0.1)
        await ws.send(json.dumps({"type": "finish"}))
        while json.loads(await ws.recv())["type"] != "phase":
            pass


async def _taken_over_mid_trial(port: int, token: str) -> tuple[int, dict]:
    """A page drives its trial a few ticks; a second page of the link opens: the first's close code,
    and what the second is told first."""
    from websockets.asyncio.client import connect as ws_connect
    from websockets.exceptions import ConnectionClosed

    url, origin = f"ws://127.0.0.1:{port}/ws", f"http://127.0.0.1:{port}"
    async with ws_connect(url, origin=origin) as first, ws_connect(url, origin=origin) as second:
        await first.send(json.dumps({"type": "hello", "token": token}))
        assert json.loads(await first.recv())["kind"] == "trial"
        await first.send(json.dumps({"type": "start"}))
        for _ in range(3):
            await first.send(json.dumps({"type": "input", "axes": [0.5, 0.5]}))
            assert json.loads(await first.recv())["type"] == "tick"
        await second.send(json.dumps({"type": "hello", "token": token}))
        with contextlib.suppress(ConnectionClosed):
            while True:
                await first.recv()
        return first.close_code, json.loads(await second.recv())


IP = re.compile(r"\b(?:\d{1,3}\.){3}\d{1,3}\b|::1\b|::ffff")


def test_no_token_nor_ip_reaches_the_servers_log_or_any_file_but_the_links(tmp_path, decoder_build):
    """The real server (the CLI, uvicorn's own logging) and a participant who takes part, then opens a
    second page mid-trial; every line it logs (its output and the experimenter's log) and every file
    written, but study/links.csv, is searched for every token and for any IP address. The experimenter's
    log names the join, the takeover, the close and the interrupted trial with their reasons."""
    import asyncio
    import urllib.request

    from lasa.live.web.conversation import REPLACED

    sessions = tmp_path / "sessions"
    links = pd.read_csv(issue_links(4, sessions, "http://127.0.0.1"))
    tokens = {p: link.split("#token=", 1)[1] for p, link in zip(links.participant, links.link, strict=True)}
    who = next(p for p in sorted(tokens) if plan_of(sessions, p)[0].condition.startswith("R"))
    log = tmp_path / "server.log"
    with cli_server(sessions, decoder_build, log, "--trial-s", "30") as port:
        page = urllib.request.urlopen(f"http://127.0.0.1:{port}/study").read().decode()
        assert "study.js" in page
        asyncio.run(_take_part(port, tokens[who]))
        code, resumed = asyncio.run(_taken_over_mid_trial(port, tokens[who]))
        assert code == REPLACED and resumed["kind"] == "trial" and resumed["resume"] is True
    text = log.read_text()
    assert "<ip>:" in text and '"WebSocket /ws" [accepted]' in text  # uvicorn's lines, addresses redacted
    mine = (study_dir(sessions) / "server.log").read_text()  # the experimenter's log (--log's default)
    for line in (
        f"participant {who}: joined at step 1",
        f"participant {who}: a newer page takes over",
        f"participant {who}: connection closed: a newer page of the same link took over (close {REPLACED})",
        f"participant {who}: trial Entree, way A (",
        "interrupted after 3 steps: a newer page",
        "0 session(s) left running",
        "EXAMPLE consent text",  # no --consent: the server says the page shows the example
    ):
        assert line in mine, line
    written = [p for p in sessions.rglob("*") if p.is_file() and p != study_dir(sessions) / "links.csv"]
    assert any(p.suffix == ".csv" and who in p.name for p in written)  # the practice was logged
    for path in [log, *written]:
        assert not IP.search(path.read_text(errors="replace")), path
    for token in tokens.values():
        assert token not in text
        assert not [p for p in written if token in p.read_text(errors="replace")]


def test_participants_see_letters_not_condition_codes_and_no_belief_by_default(study):
    """A blind protocol: the page is told the condition's letter in the participant's own order,
    never its code, and (by default) not the robot's belief; the logs keep the code."""
    sessions, tokens = study
    plan = plan_of(sessions, "p01")
    codes = list(dict.fromkeys(step.condition for step in plan))
    assert [step.label for step in plan] == [c for c in "ABCD" for _ in range(4)]
    seen = []
    with client(sessions, practice_s=90.0, trial_s=45.0) as app, connect(app, tokens["p01"]) as ws:
        seen.append(ws.receive_json())
        agree(ws)
        seen.append(ws.receive_json())
        ticks, _ = drive(ws, ticks=3)
    consent, practice = seen
    assert consent.pop("html") and consent.pop("webgl") is False  # the consent text: test_web_study.py
    assert consent == {
        "type": "phase", "kind": "consent", "practice_s": 90.0, "trial_s": 45.0, "conditions": 4,
        "longest_min": round(4 * (90 + 2 * 45 + 120) / 60),
    }  # fmt: skip
    assert practice["label"] == "A" and "condition" not in practice
    shown = json.dumps(seen + ticks)
    assert not [code for code in codes if f'"{code}"' in shown]  # no code as a value the page gets
    assert ticks and not {"belief", "goals"} & set(ticks[-1])
    (log,) = (sessions / "practice").glob("p01_*.csv")
    assert read_session(log)[1]["condition"] == codes[0]


def test_a_server_missing_a_decoder_exits_at_startup_in_one_line(tmp_path, decoder_build):
    """The CLI checks every step the schedule needs before it listens (lasa.live.web.__main__.preflight)."""
    import os
    import subprocess
    import sys

    sessions = tmp_path / "sessions"
    issue_links(4, sessions, "http://127.0.0.1")
    command = [
        sys.executable,
        "-m",
        "lasa.live.web",
        "--port",
        str(_free_port()),
        "--sessions",
        str(sessions),
    ]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    empty = tmp_path / "empty-build"
    out = subprocess.run(
        [*command, "--build-dir", str(empty), "--frames", "none"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    errors = [line for line in out.stderr.splitlines() if line.startswith("error:")]
    assert out.returncode == 2 and "Uvicorn running" not in out.stderr + out.stdout
    assert len(errors) == 1 and "eating_decoder_panda.pt" in errors[0] and "make figures" in errors[0], (
        out.stderr
    )
    assert "condition cannot run" in errors[0]


def test_a_step_the_server_cannot_run_shows_the_page_no_server_path(study):
    """Without preflight (a decoder deleted mid-study): the page gets a plain message; the log the detail."""
    from lasa.live.web.conversation import UNAVAILABLE

    sessions, tokens = study
    who = next(p for p in sorted(tokens) if plan_of(sessions, p)[0].condition.startswith("LA"))
    with client(sessions, build_dir=str(sessions / "no-decoders")) as app, connect(app, tokens[who]) as ws:
        ws.receive_json()
        agree(ws)
        assert ws.receive_json()["kind"] == "practice"
        ws.send_json({"type": "start"})
        msg = ws.receive_json()
    assert msg == {"type": "error", "message": UNAVAILABLE}
    assert str(sessions) not in msg["message"] and "make" not in msg["message"]


async def _stale_start_and_held_stick(port: int, token: str) -> list[str]:
    """Two Starts for the practice and the stick held to its end; then the Entree's phase: what comes
    before this page's own Start (nothing, if the stale Start was dropped), then its first ticks."""
    import asyncio

    async with _at_practice(port, token) as ws:
        await ws.send(json.dumps({"type": "start"}))
        await ws.send(json.dumps({"type": "start"}))  # a double click: the second is out of step
        for _ in range(5):
            await ws.send(json.dumps({"type": "input", "axes": [1.0, 1.0]}))
            assert json.loads(await ws.recv())["type"] == "tick"
        await ws.send(json.dumps({"type": "input", "axes": [1.0, 1.0]}))  # held as the practice ends
        await ws.send(json.dumps({"type": "finish"}))
        while (msg := json.loads(await ws.recv()))["type"] == "tick":
            pass
        assert msg["kind"] == "trial" and msg["task"] == "Entree"
        early = []
        with contextlib.suppress(TimeoutError):
            early.append(json.loads(await asyncio.wait_for(ws.recv(), 1.0))["type"])
        await ws.send(json.dumps({"type": "start"}))  # no input after it: the stick is at rest
        for _ in range(3):
            assert json.loads(await ws.recv())["type"] == "tick"
        return early


def test_a_step_starts_from_its_own_start_and_a_resting_stick(tmp_path, decoder_build):
    """A stale Start does not start the next trial; the stick held at a step's end is not carried
    into the next; the sidecar records the condition's position in the schedule (order); a trial
    without input is left out of the analysis, by name."""
    import asyncio

    from lasa.evidence.sessions import load_sessions
    from lasa.world.eating import make_eating_task

    sessions = tmp_path / "sessions"
    links = pd.read_csv(issue_links(4, sessions, "http://127.0.0.1"))
    tokens = {p: link.split("#token=", 1)[1] for p, link in zip(links.participant, links.link, strict=True)}
    who = next(p for p in sorted(tokens) if plan_of(sessions, p)[0].condition.startswith("R"))
    with cli_server(sessions, decoder_build, tmp_path / "server.log") as port:
        assert asyncio.run(_stale_start_and_held_stick(port, tokens[who])) == []
    (entree,) = sessions.glob(f"{who}_Entree_*.csv")
    frame, meta = read_session(entree)
    assert (frame[["z0", "z1"]].to_numpy() == 0).all() and len(frame) >= 3
    assert meta["order"] == 0
    second = plan_of(sessions, who)[4]  # the next condition's practice: its order is 1
    assert second.order == 1 and second.label == "B"
    assert meta["disconnected_ticks"] == len(frame) and meta["flagged"]  # the page sent no input
    with (
        pytest.warns(UserWarning, match="ticks without input"),
        pytest.raises(ArtifactError, match="no sound"),
    ):
        load_sessions(sessions, make_eating_task(), include_interrupted=True)


@pytest.mark.parametrize(
    "message",
    [
        '{"type": "input", "axes": [' + "9" * 400 + ", 0]}",  # a float of it overflows
        "[" * 2000 + "]" * 2000,  # nesting deeper than the parser's recursion
        '{"type": "hello", "token": ' + "[" * 1000 + "]" * 1000 + "}",
    ],
)
def test_huge_integers_and_deep_nesting_close_with_a_protocol_error(study, message):
    sessions, tokens = study
    before = files(sessions)
    with client(sessions) as app, connect(app, tokens["p00"]) as ws:
        assert ws.receive_json()["kind"] == "consent"
        ws.send_text(message)
        with pytest.raises(WebSocketDisconnect) as closed:
            ws.receive_json()
        assert closed.value.code in (1008, 1009)
    assert files(sessions) == before


def test_a_stick_beyond_its_range_is_read_and_logged_at_its_end():
    from lasa.live.web.protocol import Inputs, parse

    inputs = Inputs()
    inputs.update(parse(json.dumps({"type": "input", "axes": [1e308, -5.0]})))
    assert inputs.axes == (1.0, -1.0) and list(inputs.take().raw) == [1.0, -1.0]
    inputs.reset()
    assert inputs.axes == (0.0, 0.0) and not inputs.take().connected


def test_a_refused_schedule_leaves_no_folder_and_an_uneven_one_warns(tmp_path):
    for bad in (0, -1, 2.5, 10**6):
        with pytest.raises(ConfigError, match="whole number"):
            issue_links(bad, tmp_path / "sessions", "http://x")
        assert not (tmp_path / "sessions").exists()
    with pytest.warns(UserWarning, match="multiple of 4"):
        issue_links(3, tmp_path / "three", "http://x")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        issue_links(8, tmp_path / "eight", "http://x")  # two full rounds of the square: no warning


DEAD_CLIENT = """
import asyncio, json, sys
from websockets.asyncio.client import connect

async def main(port, token):
    url, origin = f"ws://127.0.0.1:{port}/ws", f"http://127.0.0.1:{port}"
    async with connect(url, origin=origin, ping_interval=None) as ws:
        await ws.send(json.dumps({"type": "hello", "token": token}))
        await ws.recv()
        print("connected", flush=True)
        await asyncio.sleep(600)

asyncio.run(main(int(sys.argv[1]), sys.argv[2]))
"""


async def _first_reply(port: int, token: str) -> dict:
    from websockets.asyncio.client import connect as ws_connect

    async with ws_connect(f"ws://127.0.0.1:{port}/ws", origin=f"http://127.0.0.1:{port}") as ws:
        await ws.send(json.dumps({"type": "hello", "token": token}))
        return json.loads(await ws.recv())


def test_a_connection_that_dies_silently_never_holds_its_link(tmp_path, decoder_build):
    """A page that stops answering (its process frozen, as a laptop asleep: the TCP connection stays
    open) does not hold its link: a new page of it takes over at once (and uvicorn's pings would drop
    the dead one within 10 s)."""
    import asyncio
    import os
    import signal
    import subprocess
    import sys

    from lasa.live.web.app import PING_S, PING_TIMEOUT_S

    sessions = tmp_path / "sessions"
    links = pd.read_csv(issue_links(4, sessions, "http://127.0.0.1"))
    token = links.link[0].split("#token=", 1)[1]
    with cli_server(sessions, decoder_build, tmp_path / "server.log") as port:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        dead = subprocess.Popen(
            [sys.executable, "-c", DEAD_CLIENT, str(port), token], stdout=subprocess.PIPE, text=True, env=env
        )
        try:
            assert dead.stdout.readline().strip() == "connected"
            os.kill(dead.pid, signal.SIGSTOP)
            frozen = time.monotonic()
            reply = asyncio.run(_first_reply(port, token))
            freed = time.monotonic() - frozen
        finally:
            dead.kill()
            dead.wait()
    assert reply["kind"] == "consent" and freed <= 5.0 and PING_S + PING_TIMEOUT_S <= 10.0, freed


def test_a_real_browser_says_what_happened_and_recovers_from_a_restart(tmp_path, decoder_build):
    """Headless Chromium against the CLI server: a finished link, the same link in a second window
    (which takes over: the first says the study continues there and stops), and a server restart
    each get their own message; after the restart the page reconnects by itself and goes on where
    it was."""
    from selenium.webdriver.common.by import By

    sessions = tmp_path / "sessions"
    links = pd.read_csv(issue_links(4, sessions, "http://127.0.0.1"))
    tokens = {p: link.split("#token=", 1)[1] for p, link in zip(links.participant, links.link, strict=True)}
    progress = Progress(sessions)
    progress.of("p03")["step"] = len(plan_of(sessions, "p03"))  # p03 has done the study
    progress._save()
    log, port = tmp_path / "server.log", _free_port()
    text = lambda browser, id_: browser.find_element(By.ID, id_).text  # noqa: E731
    with chromium() as browser:
        with cli_server(sessions, decoder_build, log, port=port):
            browser.get(f"http://127.0.0.1:{port}/study#token={tokens['p03']}")
            wait_for(lambda: "finished the study" in text(browser, "error-text"))
            browser.get("about:blank")  # a new fragment alone would not load the page again
            browser.get(f"http://127.0.0.1:{port}/study#token={tokens['p00']}")
            wait_for(lambda: browser.find_element(By.ID, "agree").is_displayed())
            first = browser.current_window_handle
            browser.switch_to.new_window("window")  # the same link in a second window: it takes over
            browser.get(f"http://127.0.0.1:{port}/study#token={tokens['p00']}")
            wait_for(lambda: browser.find_element(By.ID, "agree").is_displayed())
            browser.close()
            browser.switch_to.window(first)
            wait_for(lambda: "continues in another window" in text(browser, "error-text"))
            assert "token" not in browser.current_url.split("#")[0]
            time.sleep(1.2)  # it stopped: no retry (the first comes after 1 s) takes the link back
            assert "continues in another window" in text(browser, "error-text")
            browser.refresh()  # this window again: it takes over
            wait_for(lambda: browser.find_element(By.ID, "agree").is_displayed())
        # the server is gone (SIGINT: uvicorn closes its WebSockets with 1012, "service restart")
        wait_for(lambda: "restarting" in text(browser, "notice"))
        time.sleep(3.5)  # retries at 1 s and 2 s find no server: the notice still says why
        assert "restarting" in text(browser, "notice")
        assert browser.find_element(By.ID, "agree").is_displayed()  # the page is kept as it was
        with cli_server(sessions, decoder_build, log, port=port):
            wait_for(lambda: not browser.find_element(By.ID, "notice").is_displayed(), timeout=30)
            browser.find_element(By.ID, "agree").click()
            wait_for(lambda: browser.find_element(By.ID, "demographics-skip").is_displayed())
    assert Progress(sessions).of("p00")["consented"]


def test_a_connections_queue_is_bounded_and_out_of_step_messages_are_counted():
    import asyncio

    from lasa.live.web.conversation import QUEUE_MAX, Conversation

    async def main():
        conv = Conversation(ws=None, study=None, participant="p00")  # type: ignore[arg-type]
        for _ in range(3 * QUEUE_MAX):
            conv._put({"type": "survey", "answers": [1] * 5})  # 4 KB each in a flood: never all kept
        assert conv._queue.qsize() == QUEUE_MAX and conv.dropped == 2 * QUEUE_MAX
        conv._clear()  # a new step: nothing queued before it (its stick: the resting-stick test)
        assert conv._queue.empty() and conv.dropped == 3 * QUEUE_MAX

    asyncio.run(main())


CODE_OR_PATH = re.compile(r"\b(?:R|LA)(?:\+SA)?\b|/|--|\.csv|\.pt\b")


def test_every_error_a_participant_can_get_is_plain_and_a_repeat_survey_goes_on(study, monkeypatch, caplog):
    """Each error path forced: a step the server cannot run, answers out of range, answers that cannot
    be saved, a refused message; none tells the page a condition's code, a path or an option (the log
    has the detail). Answers stored before a crash (the step not yet counted) are recognised: go on."""
    from lasa.live.web import conversation
    from lasa.live.web.conversation import MESSAGES, REPLACED

    sessions, tokens = study
    caplog.set_level("INFO", logger="lasa.live.web")
    progress = Progress(sessions)
    for who in ("p00", "p01"):
        progress.consent(who)
        progress.of(who)["step"] = 3  # the survey after the first condition
    progress._save()
    said = []
    who_la = next(p for p in sorted(tokens) if plan_of(sessions, p)[0].condition.startswith("LA"))
    with client(sessions, build_dir=str(sessions / "no-decoders")) as app:
        with connect(app, tokens[who_la]) as ws:  # the LA decoder is missing
            ws.receive_json()
            agree(ws)
            assert ws.receive_json()["kind"] == "practice"
            ws.send_json({"type": "start"})
            said.append(ws.receive_json())
        with connect(app, tokens["p00"]) as ws:
            assert ws.receive_json()["kind"] == "survey"
            ws.send_json({"type": "survey", "answers": [9, 1, 1, 1, 1]})
            said.append(ws.receive_json())
            real = conversation.survey
            monkeypatch.setattr(
                conversation,
                "survey",
                lambda *a: (_ for _ in ()).throw(OSError(f"{sessions}/likert.csv: disk full")),
            )
            ws.send_json({"type": "survey", "answers": [4, 4, 4, 4, 4], "tlx": [50] * 6})
            said.append(ws.receive_json())
            monkeypatch.setattr(conversation, "survey", real)
            ws.send_json({"type": "input", "axes": "--overwrite /etc/passwd"})
            with pytest.raises(WebSocketDisconnect) as closed:
                ws.receive_json()
            said.append({"close": closed.value.code, "reason": closed.value.reason})
        from lasa.live.studykit import survey

        survey(sessions, "p01", plan_of(sessions, "p01")[3].condition, [5] * 5)  # stored; the crash came next
        with connect(app, tokens["p01"]) as ws:
            assert ws.receive_json()["kind"] == "survey"
            ws.send_json({"type": "survey", "answers": [2] * 5, "tlx": [50] * 6})  # a repeat: passed through
            after = ws.receive_json()
            assert after["kind"] == "practice" and after["label"] == "B"
    assert [m.get("message") for m in said[:3]] == [
        MESSAGES["unavailable"],
        MESSAGES["answers"],
        MESSAGES["not_saved"],
    ]
    assert said[3]["close"] == 1008 and REPLACED != 1008
    for message in said:
        text = " ".join(str(v) for v in message.values())
        assert not CODE_OR_PATH.search(text), text
    assert "disk full" in caplog.text and "no-decoders" in caplog.text  # the detail: the experimenter's
    assert "input carries two numeric axes" in caplog.text
    likert = pd.read_csv(sessions / "likert.csv", dtype={"participant": str})
    assert list(likert[likert.participant == "p01"].answer) == [5] * 5  # the first answers kept


def _ticked(folder, participant, inputs, ticks=5, limit_s=30.0):
    """A web trial of ``ticks`` steps on ``inputs`` (run_trial's own loop), closed as it closes."""
    import asyncio

    from lasa.live.station import SessionConfig
    from lasa.live.web import conversation

    config = SessionConfig(task="Entree", condition="R", participant=participant)
    trial = conversation.open_trial(config, folder, 1, limit_s)
    trial.max_steps, trial.realtime = ticks, False

    async def send(message):
        pass

    asyncio.run(conversation.run_trial(trial, inputs, send, lambda: True, lambda: False))
    return trial.writer.csv


def test_a_trial_without_input_is_flagged_and_left_out_by_name(tmp_path):
    """The sidecar counts the ticks without input; past DISCONNECTED_SHARE the trial is flagged and the
    analysis leaves it out, named in its warning; its limit is the sidecar's."""
    from lasa.evidence.sessions import DISCONNECTED_SHARE, LEFT_OUT, scan_sessions, session_limit
    from lasa.live.web.protocol import Inputs

    class Held(Inputs):
        def take(self):  # a page that sends input before every tick
            self.update({"axes": [0.2, 0.0]})
            return super().take()

    silent = _ticked(tmp_path, "p00", Inputs(), limit_s=42.0)  # a frozen page: no input at all
    driven = _ticked(tmp_path, "p01", Held())
    _, meta = read_session(silent)
    assert meta["disconnected_ticks"] == 5 and meta["flagged"] == "5 of 5 ticks without input (more than 5%)"
    assert meta["limit_s"] == 42.0 == session_limit(meta) and meta["status"] == "complete"
    assert read_session(driven)[1]["disconnected_ticks"] == 0 and read_session(driven)[1]["flagged"] is None
    assert session_limit({}) == 150.0 and DISCONNECTED_SHARE == 0.05
    logs, left_out = scan_sessions(tmp_path)
    assert [m["participant"] for _, m in logs] == ["p01"]
    assert list(left_out.session) == [silent.stem] and left_out.reason[0].startswith(LEFT_OUT["disconnected"])


def test_sessions_a_killed_server_left_running_are_closed_at_startup(tmp_path):
    """A trial and a practice whose server was killed: sidecar ``running``, rows in ``.csv.part`` (one torn
    last line). The repair closes both ``interrupted``, the rows kept; a closed session is untouched."""
    from lasa.live.station import SessionConfig
    from lasa.live.web import conversation
    from lasa.live.web.app import repair_sessions

    sessions = tmp_path / "sessions"
    kept = _ticked(sessions, "p02", conversation.Inputs(), ticks=2)
    before = kept.with_suffix(".json").read_bytes()
    for folder, who in ((sessions, "p00"), (sessions / "practice", "p01")):
        trial = conversation.open_trial(
            SessionConfig(task="Entree", condition="R", participant=who), folder, 1, 30
        )
        for _ in range(12):
            trial.step(conversation.Inputs().take())
        trial.writer.flush()
        with open(trial.writer.part, "a") as torn:
            torn.write("12,1.2,0.0,0.5")  # the process died mid-row
    assert repair_sessions(sessions) == [
        p.name.removesuffix(".json") for p in sorted(sessions.glob("p00_*.json"))
    ] + [p.name.removesuffix(".json") for p in (sessions / "practice").glob("*.json")]
    for part in (sessions.glob("p00_*.csv"), (sessions / "practice").glob("*.csv")):
        (csv,) = part
        frame, meta = read_session(csv)
        assert meta["status"] == "interrupted" and meta["reason"] == "the server stopped"
        assert meta["steps"] == len(frame) == 12 and not csv.with_suffix(".csv.part").exists()
    assert kept.with_suffix(".json").read_bytes() == before and repair_sessions(sessions) == []


class Proxy:
    """A TCP proxy on a free port of this machine to ``target``: :meth:`cut` drops every connection and stops
    listening (a network gone), :meth:`restore` listens again on the same port."""

    def __init__(self, target: int) -> None:
        self.target, self.port, self._open = target, _free_port(), []
        self.restore()

    def restore(self) -> None:
        self._listener = socket.create_server(("127.0.0.1", self.port))
        threading.Thread(target=self._accept, args=(self._listener,), daemon=True).start()

    def _accept(self, listener) -> None:
        while True:
            try:
                client, _ = listener.accept()
            except OSError:
                return
            upstream = socket.create_connection(("127.0.0.1", self.target))
            self._open += [client, upstream]
            for a, b in ((client, upstream), (upstream, client)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    @staticmethod
    def _pipe(a, b) -> None:
        with contextlib.suppress(OSError):
            while data := a.recv(65536):
                b.sendall(data)
        for end in (a, b):
            with contextlib.suppress(OSError):
                end.shutdown(socket.SHUT_RDWR)

    def cut(self) -> None:
        for end in [self._listener, *self._open]:
            with contextlib.suppress(OSError):
                end.shutdown(socket.SHUT_RDWR)
            end.close()
        self._open = []


def test_a_real_browser_drives_on_after_a_reload_a_network_drop_and_a_frozen_tab(study):
    """Headless Chromium mid-trial, through a TCP proxy: the page reloaded, then its network cut and
    restored: after each the page drives again by itself (no click), the left trial ``interrupted``, a
    new attempt running. Then the tab frozen for 3 s: that trial's sidecar counts its ticks without
    input and flags it (Chromium closes a frozen page's connection when it wakes: it reconnects too)."""
    from selenium.webdriver.common.by import By

    sessions, tokens = study
    progress = Progress(sessions)
    progress.consent("p01")
    progress.of("p01")["step"] = 1  # p01's first trial (R+SA, Entree)
    progress._save()
    config = WebConfig(sessions=str(sessions), build_dir="no-decoders", trial_s=600.0, frames="none")
    shown = lambda browser, id_: browser.find_element(By.ID, id_).is_displayed()  # noqa: E731

    def attempt(n):
        (sidecar,) = sessions.glob(f"p01_Entree_R+SA_*_a{n}.json")
        return read_session(sidecar, allow_damaged=True)[1] if sidecar.with_suffix(".csv").exists() else {}

    def driving(browser, n):
        """The page drives attempt n by itself (no click): its ticks count up, nothing is noticed."""
        wait_for(lambda: list(sessions.glob(f"p01_*_a{n}.csv.part")), timeout=30)  # the new page's Start
        wait_for(lambda: shown(browser, "drive") and ticks_seen(browser) >= 5, timeout=30)
        assert not shown(browser, "notice")

    with served(config) as port, chromium() as browser:
        proxy = Proxy(port)
        try:
            browser.get(f"http://127.0.0.1:{proxy.port}/study#token={tokens['p01']}")
            wait_for(lambda: shown(browser, "start"))
            browser.find_element(By.ID, "start").click()
            driving(browser, 1)
            browser.refresh()
            driving(browser, 2)
            wait_for(lambda: attempt(1).get("status") == "interrupted")
            proxy.cut()
            wait_for(lambda: shown(browser, "notice"))
            time.sleep(1.0)
            proxy.restore()
            driving(browser, 3)
            wait_for(lambda: attempt(2).get("status") == "interrupted")
            browser.execute_cdp_cmd("Page.setWebLifecycleState", {"state": "frozen"})
            time.sleep(3.0)
            browser.execute_cdp_cmd("Page.setWebLifecycleState", {"state": "active"})
            first = ticks_seen(browser)
            wait_for(lambda: ticks_seen(browser) > first + 5)  # the page runs again, as does the trial
        finally:
            proxy.cut()  # the page's trial ends: interrupted, its sidecar written
    wait_for(lambda: attempt(3).get("status") == "interrupted")
    frozen = attempt(3)
    assert 20 <= frozen["disconnected_ticks"] <= 40, frozen["disconnected_ticks"]  # ~3 s at 10 Hz
    assert frozen["flagged"].endswith("ticks without input (more than 5%)")
    for n in (1, 2):
        assert attempt(n)["disconnected_ticks"] <= 3 and attempt(n)["flagged"] is None
