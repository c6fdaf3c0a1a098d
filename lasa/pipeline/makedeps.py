"""Which of lasa's files each notebook runs (the Make prerequisites of the figure targets), read from the
source with the standard library only (Make runs it with the system Python): the lasa modules a notebook
imports, transitively (not under ``if TYPE_CHECKING:``), the MJCF assets, :data:`ALWAYS`."""

from __future__ import annotations

import ast
import functools
import itertools
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ALWAYS = ("lasa/__init__.py", "pyproject.toml")


def module_file(name: str, root: Path = ROOT) -> Path | None:
    """The source file of lasa module ``name`` (a package's ``__init__.py``), or None."""
    if name != "lasa" and not name.startswith("lasa."):
        return None
    base = root.joinpath(*name.split("."))
    return next((path for path in (base.with_suffix(".py"), base / "__init__.py") if path.is_file()), None)


@functools.cache
def _exports(root: Path) -> dict[str, str]:
    """``lasa._EXPORTS``: name -> defining module, read from the package's ``if TYPE_CHECKING:`` imports."""
    tree = ast.parse((root / "lasa" / "__init__.py").read_text())
    typed = [n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "TYPE_CHECKING"]
    return {
        a.name: str(n.module) for b in typed for n in b.body if isinstance(n, ast.ImportFrom) for a in n.names
    }


def _run_nodes(node: ast.AST) -> list[ast.AST]:
    """``node`` and every node under it except those under ``if TYPE_CHECKING:`` (imports for typing only),
    depth first in source order (a stack: the recursion copied each subtree's list once per level)."""
    found, stack = [], [node]
    while stack:
        node = stack.pop()
        found.append(node)
        typing_only = isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
        children = node.orelse if typing_only else ast.iter_child_nodes(node)  # type: ignore[attr-defined]
        stack.extend(reversed(list(children)))
    return found


def imports_of(source: str, root: Path = ROOT) -> set[str]:
    """The lasa modules a piece of Python source imports (each name resolved to its module)."""
    found: set[str] = set()
    for node in _run_nodes(ast.parse(source)):
        if isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            modules = [node.module, *(f"{node.module}.{alias.name}" for alias in node.names)]
            if node.module == "lasa":
                found.update(_exports(root)[a.name] for a in node.names if a.name in _exports(root))
        else:
            continue
        for name in modules:  # the module and each package above it
            found.update(itertools.accumulate(name.split("."), lambda a, b: f"{a}.{b}"))
    return {m for m in found if module_file(m, root) is not None}


def closure(modules: set[str], root: Path = ROOT, read: dict[Path, set[str]] | None = None) -> set[str]:
    """Every lasa module reached from ``modules`` by imports (them included). ``read`` keeps each file's
    imports for the next call (:func:`main`'s notebooks share one: a module is parsed once, not once per
    notebook); pass one only while the files stay as they are."""
    read = {} if read is None else read
    seen = set()
    todo = set(modules)
    while todo:
        seen |= todo
        files = [f for f in (module_file(name, root) for name in todo) if f is not None]
        for f in files:
            if f not in read:
                read[f] = imports_of(f.read_text(), root)
        todo = {m for f in files for m in read[f]} - seen
    return seen


def notebook_sources(
    notebook: str | Path, root: Path = ROOT, read: dict[Path, set[str]] | None = None
) -> list[str]:
    """The repository files a notebook's run depends on, sorted, relative to ``root`` (``read``: as
    :func:`closure`'s)."""
    cells = json.loads(Path(notebook).read_text())["cells"]
    code = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    # IPython magics and shell escapes are not Python: leave them out of the parse
    lines = [line for line in code.splitlines() if not line.lstrip().startswith(("%", "!"))]
    modules = closure(imports_of("\n".join(lines), root) | {"lasa"}, root, read)
    files = {str(module_file(m, root).relative_to(root)) for m in modules}  # type: ignore[union-attr]
    if "lasa.world.robot" in modules:
        files |= {str(p.relative_to(root)) for p in (root / "lasa" / "world" / "assets").rglob("*.xml")}
    return sorted(files | set(ALWAYS))


def main(argv: list[str] | None = None) -> int:
    """Print ``NB_SRC_<stem> := <files>`` for each notebook named on the command line."""
    read: dict[Path, set[str]] = {}  # each module's imports, parsed once for all the notebooks
    for notebook in argv if argv is not None else sys.argv[1:]:
        print(f"NB_SRC_{Path(notebook).stem} := {' '.join(notebook_sources(notebook, read=read))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
