"""Make's per-notebook prerequisites (lasa.pipeline.makedeps): the import closure; what an edit re-runs."""

import json
import os
import re
import shutil
import subprocess
import time
from pathlib import Path

from lasa.pipeline.makedeps import closure, imports_of, notebook_sources

ROOT = Path(__file__).resolve().parents[1]


def _package(root: Path) -> None:
    """A toy ``lasa``: a lazy export, an import inside a function, one for typing only."""
    (root / "lasa" / "a").mkdir(parents=True)
    (root / "lasa" / "__init__.py").write_text("if TYPE_CHECKING:\n    from lasa.a.one import Thing\n")
    (root / "lasa" / "a" / "__init__.py").write_text("")
    (root / "lasa" / "a" / "one.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from lasa.a import three\n"
        "def f():\n    from lasa.a.two import g\n    return g\n"
    )
    (root / "lasa" / "a" / "two.py").write_text("import numpy\ng = 1\n")
    (root / "lasa" / "a" / "three.py").write_text("")


def test_imports_resolve_lazy_exports_submodules_and_skip_typing_only(tmp_path):
    _package(tmp_path)
    assert imports_of("from lasa import Thing", tmp_path) == {"lasa", "lasa.a.one"}
    assert imports_of("from lasa.a import two\nimport os", tmp_path) == {"lasa", "lasa.a", "lasa.a.two"}
    # the function-level import is followed, the TYPE_CHECKING one is not, numpy is not lasa's
    assert closure({"lasa.a.one"}, tmp_path) == {"lasa", "lasa.a", "lasa.a.one", "lasa.a.two"}


def test_a_notebook_depends_on_what_it_runs(tmp_path):
    _package(tmp_path)
    (tmp_path / "pyproject.toml").write_text("")
    nb = tmp_path / "n.ipynb"
    cells = [
        {"cell_type": "markdown", "source": ["from lasa.a import three"]},
        {"cell_type": "code", "source": ["%matplotlib inline\n", "from lasa import Thing\n"]},
    ]
    nb.write_text(json.dumps({"cells": cells}))
    assert notebook_sources(nb, tmp_path) == [
        "lasa/__init__.py",
        "lasa/a/__init__.py",
        "lasa/a/one.py",
        "lasa/a/two.py",
        "pyproject.toml",
    ]


def test_the_real_notebooks_never_reach_live_use():
    read: dict = {}  # each module parsed once for all the notebooks, as make's run of makedeps does
    for nb in sorted((ROOT / "notebooks").glob("[0-9]*.ipynb")):
        files = notebook_sources(nb, read=read)
        assert not [f for f in files if f.startswith("lasa/live/") or f == "lasa/pipeline/book.py"], nb.name
        assert "lasa/base/config.py" in files and "pyproject.toml" in files
    sim1 = notebook_sources(ROOT / "notebooks" / "04_fixed_expertise.ipynb")
    assert notebook_sources(ROOT / "notebooks" / "04_fixed_expertise.ipynb", read=read) == sim1
    assert "lasa/experiments/sim1.py" in sim1 and "lasa/experiments/sim2.py" not in sim1
    assert "lasa/world/assets/panda/panda.xml" in sim1  # it reaches the robots, so their models
    demos = notebook_sources(ROOT / "notebooks" / "01_demonstrations.ipynb")
    assert not [f for f in demos if "figures/" in f]


def _runs(tree: Path) -> list[str]:
    """The notebook runs `make -n notebooks` would do, as 'stem robot'."""
    out = subprocess.run(
        ["make", "-n", "--no-print-directory", "notebooks", "OUT=o"],
        cwd=tree,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    runs = []
    for line in out.splitlines():
        if "lasa.pipeline.execute" in line:
            words = line.split()
            stem = Path(words[words.index("lasa.pipeline.execute") + 1]).stem
            robot = words[words.index("--robot") + 1] if "--robot" in words else "-"
            runs.append(f"{stem} {robot}")
    return sorted(runs)


def test_an_edit_to_live_use_leaves_make_figures_nothing_to_do(tmp_path):
    """On a copy of the pipeline with every notebook up to date (`make -t`), touch files, ask `make -n`."""
    tree = tmp_path / "repo"
    tree.mkdir()
    for name in ("Makefile", "pyproject.toml", "environment.lock"):
        shutil.copy2(ROOT / name, tree / name)
    for name in ("lasa", "notebooks", "configs"):
        shutil.copytree(ROOT / name, tree / name, ignore=shutil.ignore_patterns("__pycache__"))
    pins = dict(re.findall(r"^(MUJOCO_JS|THREE)_VERSION := (\S+)$", (ROOT / "Makefile").read_text(), re.M))
    npm = [f".venv/mujoco-js/.installed-{pins['MUJOCO_JS']}", f".venv/three/.installed-{pins['THREE']}"]
    for stamp in (".venv/.lasa-installed", ".venv/mathjax/es5/tex-chtml.js", *npm, "o/notebooks/.keep"):
        (tree / stamp).parent.mkdir(parents=True, exist_ok=True)
        (tree / stamp).touch()
    # every file as if checked out 1000 s ago and the notebooks made (`make -t`) 900 s ago: the edits
    # below fall between those and now (an edit dated in the future kept make remaking build/make-deps.mk,
    # older than the edit, until the clock caught up: 10 s of each `make -n`)
    checkout = time.time() - 1000
    for path in tree.rglob("*"):
        os.utime(path, (checkout, checkout))
    subprocess.run(["make", "-t", "notebooks", "OUT=o"], cwd=tree, capture_output=True, check=True)
    made = [path for path in tree.rglob("*") if path.stat().st_mtime > checkout]
    assert any(path.suffix == ".ipynb" for path in made)
    for path in made:
        os.utime(path, (checkout + 100, checkout + 100))
    assert _runs(tree) == []

    def touch(*files: str) -> None:
        later = max(p.stat().st_mtime for p in (tree / "o").rglob("*.ipynb")) + 10
        assert later < time.time()  # in the past: make sees the edit once, as in real use
        for f in files:
            os.utime(tree / f, (later, later))

    touch("lasa/live/teleop.py", "lasa/live/devices.py", "lasa/live/studykit.py", "lasa/pipeline/book.py")
    assert _runs(tree) == []
    touch("lasa/experiments/sim1.py")  # one figure's module: that figure and the verdict map, which reads it
    assert _runs(tree) == [
        "04_fixed_expertise panda",
        "04_fixed_expertise planar5",
        "08_claims_robustness panda",
        "08_claims_robustness planar5",
    ]
