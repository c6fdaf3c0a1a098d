"""The docs' code runs as written, file by file, from a folder of the reader's own; the repository stays.

``docs/extending.md`` is four recipes (a robot, an assistance member, a claim, a decoder). Each
block of the page is a file, labelled on its first line (``# my_member.py``, ``<!-- toy3.xml -->``),
and the page's table names, per recipe, the files it writes, the files of another recipe it
imports (the robot's), and the commands that run it. For each recipe, the test writes exactly
those files into a fresh temporary folder outside the repository and checks, there:

- that importing the recipe's modules (the files another file imports, or with a ``__main__``
  guard) does no work: it writes no file;
- that its commands succeed, in order, without a warning on stderr (numpy imported before lasa,
  say), as ``python <script>`` with that folder as the working directory and the repository (for
  ``lasa``) as the only ``PYTHONPATH``: the folder is on ``sys.path`` only as the script's own
  folder, as for a reader. The folder holds the recipe's files and no other, so a name borrowed
  from another recipe's block fails;
- that they write only into ``build/`` and ``figures/`` of that folder, and ``git status
  --porcelain`` of the repository is what it was;
- that every checkpoint recording a decoder class names an importable one: a fresh process with
  the folder on ``sys.path`` imports ``module.Class`` (``module`` a file of the recipe, never
  ``__main__``) and ``lasa.load_checkpoint`` restores it.

No other page has a ```python block that runs: elsewhere, a block's first line is ``# not run:
<why>`` (a fragment, or a command for a machine the tests do not have).
``test_every_page_with_python_is_run`` holds the pages to that.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = "docs/extending.md"
PAGES = (PAGE,)  # the pages with Python blocks that run (test_every_page_with_python_is_run)
SKIP = "# not run:"
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.MULTILINE | re.DOTALL)
LABEL = re.compile(r"#\s*([\w-]+\.py)\b.*|<!--\s*([\w.-]+)\s*-->")  # a block's first line naming its file
HEADING = re.compile(r"^## (.+)$", re.MULTILINE)
FILE = re.compile(r"`([\w-]+\.(?:py|xml))`")
COMMAND = re.compile(r"`python ([\w-]+\.py)`")
IMPORT = re.compile(r"^\s*(?:from|import)\s+([\w.]+)", re.MULTILINE)
OUTPUTS = ("build", "figures")  # where a recipe may write, in its folder


@dataclasses.dataclass(frozen=True)
class Recipe:
    """One row of the page's table: the files a recipe writes, those it imports, what it runs."""

    name: str  # "a robot"
    own: tuple[str, ...]
    imports: tuple[str, ...]
    runs: tuple[str, ...]

    @property
    def files(self) -> tuple[str, ...]:
        return self.imports + self.own


def blocks(page: str) -> list[tuple[str, int, str]]:
    """The fenced blocks of ``page``: (language, line of the fence, code), in order."""
    text = (ROOT / page).read_text()
    return [(m[1], text.count("\n", 0, m.start()) + 1, m[2]) for m in FENCE.finditer(text)]


def runnable_python(page: str) -> list[int]:
    """The lines of the ```python blocks of ``page`` not marked ``# not run:``."""
    return [line for lang, line, code in blocks(page) if lang == "python" and not code.startswith(SKIP)]


def label(code: str) -> str | None:
    """The file a block is, from its first line."""
    m = LABEL.fullmatch(code.split("\n", 1)[0].strip())
    return (m[1] or m[2]) if m else None


def files_by_section(page: str) -> dict[str, dict[str, str]]:
    """Per ``## `` section of ``page`` (its title, lower-cased), its labelled blocks: file -> text."""
    text = (ROOT / page).read_text()
    heads = list(HEADING.finditer(text))
    sections: dict[str, dict[str, str]] = {}
    for head, after in zip(heads, [*heads[1:], None], strict=True):
        body = text[head.end() : after.start() if after else len(text)]
        named = ((label(m[2]), m[2]) for m in FENCE.finditer(body))
        sections[head[1].strip().lower()] = {name: code for name, code in named if name}
    return sections


def recipes(page: str = PAGE) -> list[Recipe]:
    """The rows of the page's table of recipes."""
    text = (ROOT / page).read_text()
    table = text[text.index("| extension |") :].split("\n\n", 1)[0].splitlines()[2:]
    rows = []
    for line in table:
        name, own, imports, runs, _ = (cell.strip() for cell in line.strip("|").split("|"))
        files = tuple(FILE.findall(own)), tuple(FILE.findall(imports))
        rows.append(Recipe(name, *files, tuple(COMMAND.findall(runs))))
    return rows


def recipe_files(recipe: Recipe) -> dict[str, str]:
    """The text of each file of ``recipe``: its own from its section, the imported ones from theirs."""
    sections = files_by_section(PAGE)
    texts = dict(sections[recipe.name])
    for name in recipe.imports:
        (owner,) = [r for r in recipes() if name in r.own]
        texts[name] = sections[owner.name][name]
    return {name: texts[name] for name in recipe.files}


def modules(files: dict[str, str]) -> list[str]:
    """The recipe's Python modules: files another of its files imports, or with a ``__main__`` guard."""
    stems = {name.removesuffix(".py") for name in files if name.endswith(".py")}
    imported = {m.split(".")[0] for text in files.values() for m in IMPORT.findall(text)} & stems
    guarded = {s for s in stems if 'if __name__ == "__main__":' in files[f"{s}.py"]}
    return sorted(imported | guarded)


def git_status() -> str:
    return subprocess.run(
        ["git", "status", "--porcelain", "--untracked-files=all"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout


def python(args: list[str], folder: Path, what: str) -> str:
    """Run ``python *args`` in ``folder`` as a reader would, with the repository's ``lasa``; its stdout."""
    env = {
        **os.environ,
        "PYTHONPATH": str(ROOT),  # lasa from this checkout; nothing of the folder
        "MUJOCO_GL": "disable",  # nothing on the page renders
        "MPLBACKEND": "Agg",
        "OMP_NUM_THREADS": "1",
    }
    env.pop("LASA_ROOT", None)  # the repository's root as a reader has it
    done = subprocess.run(
        [sys.executable, *args], cwd=folder, env=env, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, f"{what} failed:\n{done.stdout[-3000:]}\n{done.stderr[-6000:]}"
    assert "Warning" not in done.stderr, f"{what} warned:\n{done.stderr[-3000:]}"  # e.g. numpy before lasa
    return done.stdout


def written(folder: Path) -> set[str]:
    """The files in ``folder`` (relative paths), bytecode caches left out."""
    paths = (p for p in folder.rglob("*") if p.is_file() and "__pycache__" not in p.parts)
    return {str(p.relative_to(folder)) for p in paths}


def test_the_page_is_its_recipes_files():
    """Every runnable block is a labelled file of exactly one recipe, as the table names them."""
    rows = recipes()
    assert [r.name for r in rows] == ["a robot", "an assistance member", "a claim", "a decoder"]
    sections = files_by_section(PAGE)
    for r in rows:
        assert set(sections[r.name]) == set(r.own), r.name  # the blocks of its section, no more, no fewer
        assert set(r.runs) <= {f for f in r.files if f.endswith(".py")}, r.name
        assert r.runs, r.name
    robot = rows[0]
    assert robot.own == ("toy3.xml", "my_robot.py") and robot.imports == ()
    assert all(set(r.imports) <= set(robot.own) for r in rows)  # only the robot's files are shared
    labelled = [name for r in rows for name in r.own]
    assert len(labelled) == len(set(labelled))
    python_blocks = [code for lang, _, code in blocks(PAGE) if lang == "python"]
    assert len(runnable_python(PAGE)) == len(python_blocks)
    assert sorted(label(code) or "(unlabelled)" for code in python_blocks) == sorted(
        name for name in labelled if name.endswith(".py")
    )


def test_every_page_with_python_is_run():
    """A page of docs/ (or the README) with a ```python block that runs is in PAGES."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    runnable = {str(p.relative_to(ROOT)) for p in pages if runnable_python(str(p.relative_to(ROOT)))}
    assert runnable == set(PAGES)


CHECKPOINT = textwrap.dedent(
    """
    import importlib, json, sys
    import torch
    import lasa
    payload = torch.load(sys.argv[1], map_location="cpu", weights_only=True)
    module, _, name = payload["decoder"].rpartition(".")
    cls = getattr(importlib.import_module(module), name)
    model, extra = lasa.load_checkpoint(sys.argv[1], decoder=cls)
    print(json.dumps({"recorded": payload["decoder"], "file": sys.modules[module].__file__,
                      "loaded": type(model).__module__ + "." + type(model).__qualname__}))
    """
)


@pytest.mark.parametrize("recipe", recipes(), ids=lambda r: r.name.split()[-1])
def test_a_recipe_runs_from_its_own_files_alone_outside_the_repository(recipe, tmp_path):
    folder = tmp_path / recipe.name.split()[-1]
    folder.mkdir()
    assert ROOT not in folder.resolve().parents and (ROOT / ".git").exists()
    files = recipe_files(recipe)
    for name, text in files.items():
        (folder / name).write_text(text)
    assert written(folder) == set(recipe.files)  # the recipe's files, and no other
    before = git_status()

    # importing its modules does no work (training, rollouts): nothing is written
    names = modules(files)
    out = python(["-c", f"import {', '.join(names)}, lasa; print(lasa.__file__)"], folder, f"import {names}")
    assert Path(out.strip()).resolve() == ROOT / "lasa" / "__init__.py"  # this checkout's lasa
    assert written(folder) == set(recipe.files), f"importing {names} wrote files"

    for script in recipe.runs:
        python([script], folder, f"{recipe.name}: python {script}")
    made = written(folder) - set(recipe.files)
    assert made and all(Path(p).parts[0] in OUTPUTS for p in made), sorted(made)
    assert git_status() == before, f"{recipe.name} changed the repository"

    if recipe.name == "a claim":  # what the page says it writes, where it runs
        for name in ("figures/claims.csv", "figures/claims.md", "figures/toy_sa.csv", "figures/toy_sa.png"):
            assert (folder / name).stat().st_size > 0, name
    import torch  # here, not at the top: the page's checks above need none

    recorded = [p for p in sorted(folder.rglob("*.pt")) if "decoder" in torch.load(p, weights_only=True)]
    assert bool(recorded) == (recipe.name == "a decoder"), recorded  # only a decoder of one's own is named
    for path in recorded:  # the class it names loads in another process, from the recipe's own module
        loaded = json.loads(python(["-c", CHECKPOINT, str(path)], folder, f"loading {path.name}"))
        module = loaded["recorded"].rpartition(".")[0]
        assert module != "__main__" and f"{module}.py" in recipe.own, loaded
        assert Path(loaded["file"]).resolve() == folder.resolve() / f"{module}.py"
        assert loaded["loaded"] == loaded["recorded"] == "my_decoder.GoalPointer"
