"""The docs' pages point at what exists and say what their pictures show.

- every relative link and image of ``docs/*.md`` resolves, from ``docs/``, to a file of the
  repository (an ``#anchor`` is not checked, only its page);
- each screenshot of the web study names, in its caption, the ``--frames`` mode it was taken
  with (the test of ``tests/test_web.py`` that takes it), and calls a mode the default exactly
  when it is the server's default (its command line's ``--frames`` default).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from lasa.live.web.app import FRAMES

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted((ROOT / "docs").glob("*.md"))
CODE = re.compile(r"^```.*?^```|`[^`\n]*`", re.MULTILINE | re.DOTALL)  # fenced blocks, inline code
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(([^)\s]+)\)")  # [text](target), ![alt](target)
EXTERNAL = re.compile(r"^[a-z][a-z+.-]*:", re.IGNORECASE)  # https:, mailto:, ...
CAPTION = re.compile(r"!\[([^\]]*)\]\(([\w.-]*web_study[\w.-]*\.png)\)")
MODE = re.compile(r"`--frames (\w+)`( \(the default\b)?")


def _links(page: Path) -> list[str]:
    """The relative targets of ``page``'s links and images, outside code."""
    text = CODE.sub("", page.read_text())
    return [t for t in LINK.findall(text) if not EXTERNAL.match(t) and not t.startswith("#")]


def test_the_docs_have_pages_with_relative_links():
    assert PAGES and sum(len(_links(p)) for p in PAGES) >= 10  # the check below checks something


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_relative_link_in_the_docs_resolves(page):
    missing = [t for t in _links(page) if not (page.parent / t.split("#", 1)[0]).resolve().exists()]
    assert not missing, f"{page.name}: links to nothing: {missing}"


def test_a_link_resolved_from_the_repositorys_root_is_caught(tmp_path):
    page = tmp_path / "docs" / "page.md"
    page.parent.mkdir()
    (tmp_path / "CHANGELOG.md").write_text("")
    page.write_text("[log](CHANGELOG.md), [log](../CHANGELOG.md), `[code](x.md)`, [web](https://x.org)\n")
    assert _links(page) == ["CHANGELOG.md", "../CHANGELOG.md"]
    assert [(page.parent / t).resolve().exists() for t in _links(page)] == [False, True]


def _server_default(capsys) -> str:
    """The ``--frames`` default the web study's command line states (its ``--help``)."""
    from lasa.live.web.__main__ import main

    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    match = re.search(r"--frames \{[\w,]+\} .*?\[(\w+)\]", text)
    assert match, text
    return match[1]


def _shot_modes() -> dict[str, str]:
    """Screenshot -> the ``frames`` of the ``WebConfig`` of the ``tests/test_web.py`` test taking it."""
    source = (ROOT / "tests" / "test_web.py").read_text()
    out = {}
    for body in re.split(r"^def ", source, flags=re.MULTILINE):
        shots = set(re.findall(r'"(web_study[\w.-]*\.png)"', body))
        modes = set(re.findall(r'WebConfig\((?:[^()]|\([^()]*\))*?frames="(\w+)"', body))
        for shot in shots:
            assert len(modes) == 1, f"the test taking {shot} must set one frames mode, got {modes}"
            out[shot] = next(iter(modes))
    return out


def test_the_web_studys_screenshots_name_their_frames_and_the_default(capsys):
    from lasa.live.web.app import WebConfig

    default = _server_default(capsys)
    assert default == WebConfig.frames and default in FRAMES
    shots = _shot_modes()
    captions = [(page, *m) for page in PAGES for m in CAPTION.findall(page.read_text())]
    assert {image for _, _, image in captions} == set(shots) == {"web_study.png", "web_study_wasm.png"}
    for page, caption, image in captions:
        named = MODE.findall(caption)
        assert len(named) == 1, f"{page.name}: {image}'s caption must name one --frames mode: {caption!r}"
        ((mode, said_default),) = named
        assert mode == shots[image], f"{image} shows --frames {shots[image]}, its caption says {mode}"
        assert bool(said_default) == (mode == default), f"{image}: the default is --frames {default}"
        assert "(the defaults)" not in caption  # the old caption: server frames, called the defaults
