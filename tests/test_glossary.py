"""The guide's glossary ("Names", its table of words) against the code: every name it lists exists
and says, in its own documentation, the word it stands for; and the words it retires are gone."""

from __future__ import annotations

import ast
import importlib
import inspect
import re
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide.md"
HEADING = "### One word, one concept"


def _rows() -> list[tuple[str, str, list[str]]]:
    """(word, meaning, dotted names) of each row of the glossary's table."""
    text = GUIDE.read_text()
    assert HEADING in text, f"docs/guide.md has no {HEADING!r} section"
    section = text.split(HEADING, 1)[1].split("\n#", 1)[0]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 3 or not line.startswith("| **"):
            continue
        word = cells[0].strip("*")
        rows.append((word, cells[1], re.findall(r"`(lasa(?:\.\w+)+)`", cells[2])))
    return rows


def _resolve(dotted: str) -> tuple[object, types.ModuleType, str | None]:
    """The object a dotted name names, its module, and its attribute name (None: the module)."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            module = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        obj: object = module
        for name in parts[cut:]:
            obj = getattr(obj, name)
        return obj, module, parts[-1] if cut < len(parts) else None
    raise ModuleNotFoundError(dotted)


def _says(obj: object, module: types.ModuleType, name: str | None) -> str:
    """What the code says of a name: its docstring, or for a value its definition and comments."""
    if name is None or inspect.isclass(obj) or inspect.isroutine(obj):
        return inspect.getdoc(obj) or ""
    lines = inspect.getsource(module).splitlines()
    at = next(i for i, line in enumerate(lines) if re.match(rf"\s*{name}\s*[:=]", line))
    return "\n".join(lines[max(at - 3, 0) : at + 2])


def test_the_glossary_lists_words() -> None:
    words = [word for word, _, _ in _rows()]
    assert len(words) == len(set(words)) >= 10, words
    for required in ("member", "reading", "user", "participant model", "decoder variant"):
        assert required in words


@pytest.mark.parametrize(("word", "meaning", "names"), _rows(), ids=lambda v: v if isinstance(v, str) else "")
def test_each_name_exists_with_that_meaning(word: str, meaning: str, names: list[str]) -> None:
    assert names, f"the row of {word!r} names no code"
    stem = word.split()[-1].rstrip("s")[:6].lower()
    for dotted in names:
        obj, module, name = _resolve(dotted)
        assert stem in _says(obj, module, name).lower(), f"{dotted} does not say {word!r}"


def _identifiers() -> dict[str, set[str]]:
    """Every identifier defined or used in lasa's code (names, attributes, arguments), by file."""
    found: dict[str, set[str]] = {}
    for path in sorted((ROOT / "lasa").rglob("*.py")):
        names = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Name):
                names.add(node.id)
            elif isinstance(node, ast.Attribute):
                names.add(node.attr)
            elif isinstance(node, ast.arg):
                names.add(node.arg)
            elif isinstance(node, ast.FunctionDef | ast.ClassDef):
                names.add(node.name)
        found[str(path.relative_to(ROOT))] = names
    return found


# "reading" is a claim's labelled alternative only: the modules that name, judge or plan claims
CLAIM_MODULES = {
    "lasa/evidence/claims.py",
    "lasa/evidence/findings.py",
    "lasa/evidence/values.py",
    "lasa/evidence/verdicts.py",
    "lasa/experiments/sim4/analysis.py",
    "lasa/experiments/study/claims.py",
    "lasa/experiments/study/preregister.py",
}


def test_reading_names_claim_readings_only() -> None:
    found = _identifiers()
    assert any("reading" in name for path in CLAIM_MODULES for name in found[path])  # the check sees them
    bad = sorted(
        f"{path}: {name}"
        for path, names in found.items()
        if path not in CLAIM_MODULES
        for name in names
        if "reading" in name.lower() and name != "threading"
    )
    assert not bad, f"'reading' names a claim's alternative only (the glossary); found {bad}"


@pytest.mark.parametrize("retired", ["stream", "arms"])  # a robot arm keeps "arm"
def test_retired_names_are_gone(retired: str) -> None:
    bad = sorted(path for path, names in _identifiers().items() if retired in names)
    assert not bad, f"{retired!r} is retired (the glossary): {bad}"
