"""The docs' code runs as written, from a folder of the reader's own, and leaves the repository alone.

For each page of ``PAGES``, every ```python block runs, in the page's order, as one script (a
later block uses what an earlier one defined, as for a reader who pastes them into one file), in
a subprocess whose working directory is a temporary folder outside the repository, with the
repository importable. Afterwards ``git status --porcelain`` of the repository must be what it
was: the docs write where they run, never into the package's folders.

Conventions of the pages:

- A ```python block runs unless its first line is ``# not run: <why>`` (a fragment, or a
  command for a machine the tests do not have).
- A block in another language whose first line is an XML comment naming a file, such as
  ``<!-- toy3.xml -->``, is that file: the test writes it into the folder before the script runs.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = ("docs/extending.md",)  # the pages with Python blocks (test_every_page_with_python_is_run)
SKIP = "# not run:"
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.MULTILINE | re.DOTALL)
FILE_COMMENT = re.compile(r"<!--\s*([\w.-]+)\s*-->")


def blocks(page: str) -> list[tuple[str, int, str]]:
    """The fenced blocks of ``page``: (language, line of the fence, code), in order."""
    text = (ROOT / page).read_text()
    return [(m[1], text.count("\n", 0, m.start()) + 1, m[2]) for m in FENCE.finditer(text)]


def script_and_files(page: str) -> tuple[str, dict[str, str]]:
    """The page's runnable Python as one script (each block headed by where it comes from), and
    the files its blocks name."""
    parts, files = [], {}
    for language, line, code in blocks(page):
        first = code.split("\n", 1)[0].strip()
        named = FILE_COMMENT.fullmatch(first)
        if language != "python" and named:
            files[named[1]] = code.split("\n", 1)[1]
        elif language == "python" and not first.startswith(SKIP):
            parts.append(f"# ---- {page}, the block at line {line} ----\n{code}")
    return "\n".join(parts), files


def git_status() -> str:
    return subprocess.run(
        ["git", "status", "--porcelain", "--untracked-files=all"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout


def test_the_pages_mark_what_runs():
    """The extending page's blocks all run; its XML block is the scene the robot block reads."""
    script, files = script_and_files("docs/extending.md")
    assert script.count("# ---- docs/extending.md") == sum(
        1 for language, _, _ in blocks("docs/extending.md") if language == "python"
    )
    assert list(files) == ["toy3.xml"]
    assert 'Path("toy3.xml")' in script


def test_every_page_with_python_is_run():
    """A page of docs/ (or the README) with a ```python block that runs is in PAGES."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    runnable = {str(p.relative_to(ROOT)) for p in pages if script_and_files(str(p.relative_to(ROOT)))[0]}
    assert runnable == set(PAGES)


@pytest.mark.parametrize("page", PAGES)
def test_the_python_of_a_page_runs_as_written_outside_the_repository(page, tmp_path):
    script, files = script_and_files(page)
    assert script and (ROOT / ".git").exists()
    assert ROOT not in tmp_path.resolve().parents
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "doc_script.py").write_text(script)
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]),
        "MUJOCO_GL": "disable",  # nothing on the pages renders
        "MPLBACKEND": "Agg",
        "OMP_NUM_THREADS": "1",
    }
    env.pop("LASA_ROOT", None)  # the repository's root as a reader has it
    before = git_status()
    done = subprocess.run(
        [sys.executable, "doc_script.py"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=1200
    )
    assert done.returncode == 0, f"{page}'s code failed:\n{done.stdout[-3000:]}\n{done.stderr[-6000:]}"
    assert git_status() == before, f"{page}'s code changed the repository"
    if page == "docs/extending.md":  # what the page says its code writes, where it runs
        for name in ("figures/claims.csv", "figures/claims.md", "figures/toy_sa.csv", "figures/toy_sa.png"):
            assert (tmp_path / name).stat().st_size > 0, name
        assert (tmp_path / "build" / "models" / "pointer_toy3.pt").is_file()
