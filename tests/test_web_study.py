"""The lab's own web study: the consent file, the demographics, the questionnaires (Likert, NASA-TLX,
comment), the device log, the thank-you page, withdraw and export, and the page's checks (WebGL)."""

import json
import zipfile

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence.questionnaire import DEMOGRAPHICS, LIKERT, PREFER_NOT, TLX, TLX_SUBSCALES
from lasa.live.web.conversation import MESSAGES
from lasa.live.web.plan import Progress, plan_of
from lasa.live.web.tokens import issue_links, study_dir
from tests.test_web import agree, chromium, client, connect, drive, refused, served, wait_for


@pytest.fixture()
def study(tmp_path):
    """A study of three participants (as tests/test_web.py's): the sessions folder and the tokens."""
    sessions = tmp_path / "sessions"
    with pytest.warns(UserWarning, match="unevenly"):
        links = pd.read_csv(issue_links(3, sessions, "http://testserver"))
    return sessions, {
        p: link.split("token=", 1)[1] for p, link in zip(links.participant, links.link, strict=True)
    }


def at_step(sessions, participant, step):
    """``participant`` consented, at step ``step`` of their plan."""
    progress = Progress(sessions)
    progress.consent(participant)
    progress.of(participant)["step"] = step
    progress._save()


def test_the_consent_is_the_files_markdown_with_the_durations_and_no_raw_html(study, tmp_path):
    from lasa.live.web.consent import read_consent

    sessions, tokens = study
    text = tmp_path / "consent.md"
    text.write_text(
        "# Our study\n\nPractice {practice}, trials {trial}, {conditions} ways, at most {total}.\n\n"
        '<script>alert(1)</script> <img src=x onerror="alert(2)"> [link](javascript:alert(3))\n'
    )
    with client(sessions, consent=str(text), practice_s=60.0, trial_s=45.0) as app:
        with connect(app, tokens["p00"]) as ws:
            html = ws.receive_json()["html"]
    assert "<h1>Our study</h1>" in html
    # 4 x (60 + 2 x 45 + 120) s = 18 minutes
    assert "Practice 60 seconds, trials 45 seconds, four ways, at most 18 minutes." in html
    assert (
        "<script" not in html and "<img" not in html and "javascript:" not in html.replace("(javascript:", "")
    )
    assert "&lt;script&gt;" in html and 'href="javascript' not in html
    text.write_text("Come for {hours} hours.")
    with pytest.raises(ConfigError, match="hours"):
        read_consent(text)
    with pytest.raises(ConfigError, match="cannot be read"):
        read_consent(tmp_path / "missing.md")


def test_the_example_consent_has_the_boards_fields_and_says_what_is_recorded(study, tmp_path, capsys):
    from lasa.live.web.__main__ import main
    from lasa.live.web.consent import EXAMPLE

    out = tmp_path / "consent.md"
    assert main(["consent-template", "--out", str(out)]) == 0
    text = out.read_text()
    assert text == EXAMPLE.read_text()
    for field in ("Study title", "Investigators", "Contact", "Purpose", "What you will do", "Risks",
                  "Benefits",
                  "Compensation", "voluntary", "withdraw", "participant id", "What is recorded",
                  "What is not recorded", "IP address", "Where it is stored", "how long", "Who sees it",
                  "anonymised", "{practice}", "{trial}", "{total}", "{conditions}"):  # fmt: skip
        assert field in text, field
    assert "simulated person" not in text and "Nobody else is in the scene" in text
    assert "kind and name of the input device" in text
    assert main(["consent-template", "--out", str(out)]) == 2  # never replaced
    assert "exists already" in capsys.readouterr().err
    sessions, tokens = study
    with client(sessions) as app, connect(app, tokens["p00"]) as ws:  # no --consent: the example
        html = ws.receive_json()["html"]
    assert "example consent text" in html and "up to 30 seconds" in html and "{" not in html


def test_demographics_are_optional_stored_tidy_and_asked_once_before_the_first_practice(study):
    sessions, tokens = study
    with client(sessions) as app:
        with connect(app, tokens["p00"]) as ws:
            ws.receive_json()
            ws.send_json({"type": "consent"})
            form = ws.receive_json()
            assert form["kind"] == "demographics"
            assert [i["item"] for i in form["items"]] == list(DEMOGRAPHICS)
            assert all(PREFER_NOT in i["answers"] for i in form["items"])
            ws.send_json({"type": "demographics", "answers": {"age": "200"}})
            assert ws.receive_json() == {"type": "error", "message": MESSAGES["answers"]}
            ws.send_json({"type": "demographics", "answers": {"age": "25-34", "gender": PREFER_NOT}})
            assert ws.receive_json()["kind"] == "practice"
        with connect(app, tokens["p00"]) as ws:  # back again: straight to the practice
            assert ws.receive_json()["kind"] == "practice"
        with connect(app, tokens["p01"]) as ws:  # a whole form skipped: nothing stored
            ws.receive_json()
            agree(ws)
            assert ws.receive_json()["kind"] == "practice"
    table = pd.read_csv(sessions / "demographics.csv", dtype=str)
    assert table.to_dict("records") == [
        {"participant": "p00", "item": "age", "answer": "25-34"},
        {"participant": "p00", "item": "gender", "answer": PREFER_NOT},
    ]
    assert Progress(sessions).of("p01")["demographics"]


def test_the_questionnaire_stores_likert_tlx_and_comment_and_a_repeat_passes(study):
    """The whole form checked before any part is stored; a repeat after a crash (the step not counted)
    goes on, the first answers kept."""
    from lasa.evidence.sessions import read_tlx

    sessions, tokens = study
    at_step(sessions, "p00", 3)  # p00's first survey (R)
    tlx = [50, 40, 30, 20, 10, 0]
    comment = 'It drifted; "left" felt slow,\nthen fine.'
    with client(sessions) as app:
        with connect(app, tokens["p00"]) as ws:
            msg = ws.receive_json()
            assert [q["text"] for q in msg["questions"]] == list(LIKERT.values())
            assert "I would use this way of controlling the robot again." in json.dumps(msg)
            assert "condition" not in json.dumps(msg)
            assert [t["name"] for t in msg["tlx"]] == list(TLX_SUBSCALES) and msg["tlx_step"] == 5
            perf = msg["tlx"][3]
            assert (perf["name"], perf["low"], perf["high"]) == ("performance", "perfect", "failure")
            for bad in (
                [7, 6, 5, 4, 3],
                [7, 6, 5, 4, 3, 101],
                [7, 6, 5, 4, 3, 1],
            ):  # no TLX, out of 0..100, steps
                ws.send_json({"type": "survey", "answers": [7, 6, 5, 4, 3], "tlx": bad[5:] * 6})
                error = ws.receive_json()
                assert error == {"type": "error", "message": MESSAGES["answers"]}
            ws.send_json({"type": "survey", "answers": [7, 6, 5, 4, 9], "tlx": tlx})
            assert ws.receive_json()["message"] == MESSAGES["answers"]
            assert not any((sessions / n).exists() for n in ("likert.csv", "tlx.csv", "comments.csv"))
            ws.send_json({"type": "survey", "answers": [7, 6, 5, 4, 3], "tlx": tlx, "comment": comment})
            assert ws.receive_json()["label"] == "B"
    # a server that crashed after the write, before the progress step: the same answers again pass
    at_step(sessions, "p00", 3)
    with client(sessions) as app, connect(app, tokens["p00"]) as ws:
        ws.receive_json()
        ws.send_json({"type": "survey", "answers": [7, 6, 5, 4, 3], "tlx": tlx, "comment": comment})
        assert ws.receive_json()["label"] == "B"
    at_step(sessions, "p00", 3)
    with client(sessions) as app, connect(app, tokens["p00"]) as ws:  # other answers: the first are kept
        ws.receive_json()
        ws.send_json({"type": "survey", "answers": [1, 1, 1, 1, 1], "tlx": [100] * 6})
        assert ws.receive_json()["label"] == "B"
    likert = pd.read_csv(sessions / "likert.csv")
    assert list(likert.columns) == ["participant", "condition", "scale", "answer"]
    assert list(likert.scale) == list(LIKERT) and list(likert.answer) == [7, 6, 5, 4, 3]
    stored = pd.read_csv(sessions / "tlx.csv")
    assert list(stored.columns) == ["participant", "condition", "subscale", "value"]
    assert list(stored.value) == tlx and set(stored.condition) == {"R"}
    assert pd.read_csv(sessions / "comments.csv").comment.tolist() == [comment]
    raw = read_tlx(sessions)
    assert raw[raw.subscale == "raw"].value.tolist() == [25.0]  # (50 + 40 + 30 + 20 + 10 + 0) / 6


def test_the_comment_is_length_limited_and_never_logged(study, caplog):
    from lasa.evidence.questionnaire import COMMENT_CHARS

    sessions, tokens = study
    at_step(sessions, "p00", 3)
    secret = "my-private-remark-" + "x" * COMMENT_CHARS
    with client(sessions) as app, connect(app, tokens["p00"]) as ws:
        ws.receive_json()
        ws.send_json({"type": "survey", "answers": [7, 6, 5, 4, 3], "tlx": [5] * 6, "comment": secret})
        assert ws.receive_json() == {"type": "error", "message": MESSAGES["answers"]}
    assert "my-private-remark" not in caplog.text and "questionnaire refused" in caplog.text
    assert not (sessions / "comments.csv").exists()


def test_the_session_records_the_input_device_cut_to_printable_text(study):
    from lasa.evidence.sessionlog import read_session

    sessions, tokens = study
    name = "Pad\x00/../../etc " + "y" * 300
    with client(sessions, practice_s=0.3) as app, connect(app, tokens["p00"]) as ws:
        ws.receive_json()
        agree(ws)
        ws.receive_json()
        ws.send_json({"type": "start", "device": {"kind": "gamepad", "id": name, "mapping": "standard"}})
        while ws.receive_json()["type"] == "tick":
            pass
        ws.send_json({"type": "start", "device": {"kind": "keyboard", "id": "ignored"}})
        while ws.receive_json()["type"] == "tick":
            pass
    (practice,) = (sessions / "practice").glob("p00_*.json")
    (entree,) = sessions.glob("p00_Entree_*.json")
    device = read_session(practice)[1]["device"]
    assert device == {"kind": "gamepad", "id": ("Pad/../../etc " + "y" * 300)[:100], "mapping": "standard"}
    assert read_session(entree)[1]["device"] == {"kind": "keyboard"}
    assert all("etc" not in p.name for p in sessions.rglob("*"))
    with client(sessions) as app, connect(app, tokens["p01"]) as ws:
        ws.receive_json()
        agree(ws)
        ws.receive_json()
        ws.send_json({"type": "start", "device": {"kind": "joystick"}})  # not a device the page names
        with pytest.raises(Exception):  # noqa: B017 (the connection closes: WebSocketDisconnect)
            ws.receive_json()


def test_the_thank_you_page_gives_the_id_and_the_completion_code_and_link(study):
    sessions, tokens = study
    at_step(sessions, "p02", len(plan_of(sessions, "p02")) - 1)  # p02's last survey
    with client(sessions, completion_code="C0DE42", completion_url="https://example.org/done") as app:
        with connect(app, tokens["p02"]) as ws:
            ws.receive_json()
            ws.send_json({"type": "survey", "answers": [4] * 5, "tlx": [50] * 6})
            thanks = ws.receive_json()
    assert thanks == {
        "type": "phase", "kind": "thanks", "participant": "p02", "code": "C0DE42",
        "url": "https://example.org/done",
    }  # fmt: skip
    with pytest.raises(ConfigError, match="https"):
        client(sessions, completion_url="javascript:alert(1)")


def _take_part_briefly(app, token):
    """Consent, demographics, a short practice and the Entree: logs, a progress entry and answers."""
    with connect(app, token) as ws:
        ws.receive_json()
        ws.send_json({"type": "consent"})
        ws.receive_json()
        ws.send_json({"type": "demographics", "answers": {"handedness": "left-handed"}})
        ws.receive_json()
        drive(ws, ticks=2)
        ws.send_json({"type": "finish"})
        while ws.receive_json()["type"] == "tick":
            pass
        drive(ws)


def test_withdraw_removes_a_participant_everywhere_and_export_holds_no_secret(study, tmp_path, monkeypatch):
    from lasa.live.answers import record_comment, record_tlx
    from lasa.live.studykit import survey
    from lasa.live.web.__main__ import main

    sessions, tokens = study
    with client(sessions, practice_s=30.0) as app:
        for who in ("p00", "p01"):
            _take_part_briefly(app, tokens[who])
            survey(sessions, who, "R", [4] * 5)
            record_tlx(sessions, who, "R", [20] * 6)
            record_comment(sessions, who, "R", f"comment of {who}")
        monkeypatch.setattr("builtins.input", lambda question: "no")
        assert main(["withdraw", "--participant", "p01", "--sessions", str(sessions)]) == 1  # not confirmed
        assert list(sessions.glob("p01_*"))
        assert main(["withdraw", "--participant", "p01", "--sessions", str(sessions), "--yes"]) == 0
        assert refused(app, tokens["p01"]) == "invalid"  # the running server: the link is dead
        assert refused(app, tokens["p00"]) is None
    mine = [p for p in sessions.rglob("*") if "p01" in p.name]
    assert mine == []
    for name in ("likert.csv", "tlx.csv", "comments.csv", "demographics.csv"):
        table = pd.read_csv(sessions / name, dtype=str)
        assert set(table.participant) == {"p00"}, name
    for name in ("progress.json", "tokens.json"):
        assert "p01" not in json.loads((study_dir(sessions) / name).read_text())
    assert "p01" not in (study_dir(sessions) / "links.csv").read_text()
    withdrawn = pd.read_csv(study_dir(sessions) / "withdrawn.csv")
    assert list(withdrawn.columns) == ["participant", "withdrawn_utc"] and list(withdrawn.participant) == [
        "p01"
    ]
    out = tmp_path / "export.zip"
    assert main(["export", "--sessions", str(sessions), "--out", str(out)]) == 0
    with zipfile.ZipFile(out) as archive:
        names = archive.namelist()
        text = b"".join(archive.read(n) for n in names).decode(errors="replace")
        readme = archive.read("README.md").decode()
    assert {"README.md", "likert.csv", "tlx.csv", "comments.csv", "demographics.csv"} <= set(names)
    assert any(n.startswith("practice/p00_") for n in names) and any(
        n.startswith("p00_Entree") for n in names
    )
    assert not [n for n in names if n.startswith("study") or "p01" in n]
    assert "p01" not in text and "comment of p00" in text
    assert not [t for t in tokens.values() if t in text] and "token=" not in text
    assert all(f"`{n}`" in readme for n in ("likert.csv", "tlx.csv", "comments.csv", "demographics.csv"))


def test_tlx_and_demographics_are_analysed_when_present(tmp_path):
    from lasa.evidence.sessions import demographics_counts, read_demographics, read_tlx, tlx_tests
    from lasa.live.answers import record_demographics, record_tlx

    assert read_tlx(tmp_path) is None and read_demographics(tmp_path) is None
    rng = np.random.default_rng(0)
    for p in ("p00", "p01", "p02"):
        for c in ("R", "R+SA", "LA", "LA+SA"):
            values = (rng.integers(0, 10, 6) * 5 + (0 if c == "LA+SA" else 40)).tolist()
            record_tlx(tmp_path, p, c, values)
    record_demographics(tmp_path, "p00", {"age": "18-24", "handedness": "both"})
    record_demographics(tmp_path, "p01", {"age": "18-24"})
    ratings = read_tlx(tmp_path)
    tests = tlx_tests(ratings)
    assert set(tests.scale) == {*TLX_SUBSCALES, "raw"} and len(tests) == 7 * 3
    assert (tests["diff"] < 0).all()  # LA+SA rated 40 points less demanding on every subscale
    counts = demographics_counts(read_demographics(tmp_path)).set_index(["item", "answer"])["count"]
    assert counts[("age", "18-24")] == 2 and counts[("handedness", "both")] == 1
    assert counts[("gender", PREFER_NOT)] == 0 and len(counts) == sum(len(a) for a in DEMOGRAPHICS.values())
    with pytest.raises(ConfigError, match="answered already"):
        record_demographics(tmp_path, "p00", {"age": "65 or older"})
    assert TLX[3].low == "perfect" and TLX[3].high == "failure"


def test_a_browser_without_webgl_is_stopped_before_consent(study):
    """Chromium with WebGL off (`--frames browser`, the default): the page says so, never the consent."""
    from selenium.webdriver.common.by import By

    from lasa.live.web.app import WebConfig

    sessions, tokens = study
    config = WebConfig(sessions=str(sessions), build_dir="no-decoders")
    with served(config) as port, chromium("--disable-webgl", "--disable-3d-apis") as browser:
        browser.get(f"http://127.0.0.1:{port}/study#token={tokens['p00']}")
        wait_for(lambda: "cannot run the study" in browser.find_element(By.ID, "error-text").text)
        assert not browser.find_element(By.ID, "agree").is_displayed()
        assert browser.title == "A study with a robot arm"
        assert browser.execute_script("return document.getElementById('consent-text').innerHTML") == ""
    assert not Progress(sessions).of("p00")["consented"]


def test_the_page_has_a_neutral_title_and_says_way_never_condition(study):
    import re

    sessions, _ = study
    with client(sessions) as app:
        html = app.get("/study").text
        script = app.get("/static/study.js").text
    assert "<title>A study with a robot arm</title>" in html
    code = re.sub(r"//[^\n]*", "", script)  # what the page can show: not the comments
    assert "condition" not in html.lower() and "condition" not in code.lower()
    assert "way ${msg.label}" in code
