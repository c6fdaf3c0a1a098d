"""The public API: `from lasa import *` works, and every exported name resolves."""

import subprocess
import sys
from pathlib import Path

import pytest

import lasa

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def fresh() -> list[str]:
    """One fresh process with a bare environment: ``import lasa`` and three lazy exports (whether numpy,
    torch or mujoco loaded, whether ``os.environ`` and ``sys.meta_path`` are as before), then
    ``from lasa import *`` (three of its names): its printed words."""
    code = (
        "import os, sys; env = dict(os.environ); hooks = list(sys.meta_path); import lasa;"
        "light = not {'numpy', 'torch', 'mujoco'} & set(sys.modules); lasa.Paths; lasa.Runner; lasa.publish;"
        "print(light, dict(os.environ) == env, sys.meta_path == hooks);"
        "from lasa import *; print(Runner.__name__, publish.__name__, DemoConfig.__name__)"
    )
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False, env={"PATH": ""}, cwd=ROOT
    )
    assert run.returncode == 0, run.stderr
    return run.stdout.split()


def test_star_import_works_in_a_fresh_interpreter(fresh):
    assert fresh[3:] == ["Runner", "publish", "DemoConfig"]


def test_all_and_the_lazy_table_agree():
    """Each exported name is the object of that name in the module the lazy table names for it."""
    import ast
    import importlib

    assert sorted(lasa.__all__) == sorted(lasa._EXPORTS)
    tree = ast.parse((ROOT / "lasa" / "__init__.py").read_text())
    (block,) = [n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "TYPE_CHECKING"]
    typed = {a.name: n.module for n in block.body if isinstance(n, ast.ImportFrom) for a in n.names}
    assert typed == lasa._EXPORTS  # what type checkers see is what __getattr__ imports
    for name in lasa.__all__:
        home = importlib.import_module(lasa._EXPORTS[name])
        assert getattr(lasa, name) is getattr(home, name), name


def test_import_lasa_changes_no_environment_variable_and_adds_no_import_hook(fresh):
    """In a fresh process with a bare environment: ``import lasa`` and the lazy exports it resolves
    leave ``os.environ`` and ``sys.meta_path`` as they were, and load neither numpy nor mujoco."""
    assert fresh[:3] == ["True", "True", "True"]


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        lasa.nope  # noqa: B018


def test_every_import_of_the_library_is_a_declared_dependency():
    """Each third-party module lasa imports (anywhere, lazily too) belongs to a distribution that
    pyproject.toml lists: an undeclared one works here only because something else pulled it in."""
    import ast
    import re
    import sys
    import tomllib
    from importlib.metadata import packages_distributions, requires
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    declared = {
        re.split(r"[<>=!~;\[ ]", d, maxsplit=1)[0].strip().lower().replace("_", "-")
        for d in tomllib.loads((root / "pyproject.toml").read_text())["project"]["dependencies"]
    }
    owners = packages_distributions()
    used: dict[str, set[str]] = {}
    for path in (root / "lasa").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top == "lasa" or top in sys.stdlib_module_names or top == "__future__":
                    continue
                used.setdefault(top, set()).add(path.name)
    assert used, "no third-party imports found: the scan is broken"
    missing = {}
    for top, files in sorted(used.items()):
        dists = {d.lower().replace("_", "-") for d in owners.get(top, [])}
        if not dists & declared:
            missing[top] = (sorted(dists), sorted(files))
    assert not missing, f"imported but not declared in pyproject.toml: {missing}"
    assert requires("lasa") is not None  # the installed metadata is this pyproject's


def test_the_import_contracts_hold_and_can_fail(tmp_path):
    """`make lint` checks pyproject's import-linter contracts; a contract the code breaks is caught."""
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    tool = shutil.which("lint-imports", path=str(Path(sys.executable).parent))
    assert tool is not None, "import-linter is not installed (make setup)"
    kept = subprocess.run([tool, "--no-cache"], cwd=root, capture_output=True, text=True, check=False)
    assert kept.returncode == 0, kept.stdout[-2000:]
    broken = tmp_path / "broken.toml"
    broken.write_text(
        '[tool.importlinter]\nroot_package = "lasa"\n\n[[tool.importlinter.contracts]]\n'
        'name = "the figures never use the rollout (false: they do)"\ntype = "forbidden"\n'
        'source_modules = ["lasa.experiments"]\nforbidden_modules = ["lasa.people.rollout"]\n'
    )
    run = subprocess.run(
        [tool, "--no-cache", "--config", str(broken)], cwd=root, capture_output=True, text=True, check=False
    )
    assert run.returncode != 0 and "BROKEN" in run.stdout


def test_the_version_is_pyprojects_even_from_the_repository_root():
    """`lasa.__version__` comes from the package metadata; run from the repository root (where a
    stale lasa.egg-info would be found first, which `make setup` removes), it is pyproject's."""
    import subprocess
    import sys
    import tomllib
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    declared = tomllib.loads((root / "pyproject.toml").read_text())["project"]["version"]
    got = subprocess.run(
        [sys.executable, "-c", "import lasa; print(lasa.__version__)"],
        cwd=root,
        capture_output=True,
        text=True,
        check=True,
        env={"MUJOCO_GL": "disable", "PATH": ""},
    ).stdout.strip()
    assert got == declared
