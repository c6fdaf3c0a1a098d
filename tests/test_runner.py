"""Notebook execution: parameters cells, config checking, committed notebooks."""

import ast
import json
from pathlib import Path

import pytest

from lasa.base.errors import ConfigError
from lasa.pipeline.execute import load_config, notebook_parameters

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
CONFIGS = [ROOT / "configs" / n for n in ("paper.yaml", "quick.yaml", "large.yaml")]
COMMON = {"robot", "quick", "build_dir", "figures_dir", "settings"}


def test_there_are_notebooks():
    assert [p.stem[:2] for p in NOTEBOOKS] == [f"{i:02d}" for i in range(1, 12)]


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda p: p.stem)
def test_the_first_cell_pins_and_the_parameters_cell_of_literals_is_next(notebook):
    """The first cell pins the runtime before anything loads numpy, torch or MuJoCo (a notebook opened
    in Jupyter too); the next code cell is the parameters, literals only."""
    cells = json.loads(notebook.read_text())["cells"]
    assert cells[0]["id"] == "pin-runtime"
    assert "".join(cells[0]["source"]).endswith("import lasa.runtime\n\nlasa.runtime.pin()")
    code = [c for c in cells if c["cell_type"] == "code"]
    assert "parameters" in code[1]["metadata"].get("tags", [])
    tree = ast.parse("".join(code[1]["source"]))
    for node in tree.body:
        assert isinstance(node, ast.Assign), ast.dump(node)
        ast.literal_eval(node.value)  # literals only: derived values belong in the next cell
    assert COMMON <= set(notebook_parameters(notebook))


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda p: p.stem)
def test_committed_without_outputs(notebook):
    cells = json.loads(notebook.read_text())["cells"]
    assert all(
        not c.get("outputs") and not c.get("execution_count") for c in cells if c["cell_type"] == "code"
    )


def settings_class(notebook):
    """The config dataclass that the notebook's ``settings`` comment names (``lasa.x.Y``)."""
    import importlib
    import re

    cells = json.loads(notebook.read_text())["cells"]
    (source,) = ["".join(c["source"]) for c in cells if "parameters" in c["metadata"].get("tags", ())]
    match = re.search(r"^settings = \{\}  # fields of (lasa[\w.]*)\.(\w+) that differ", source, re.M)
    assert match, f"{notebook.name}: the settings comment must name its config class"
    return getattr(importlib.import_module(match.group(1)), match.group(2))


@pytest.mark.parametrize("config", CONFIGS, ids=lambda p: p.stem)
@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda p: p.stem)
def test_shipped_settings_build_the_named_config(config, notebook):
    """Each YAML section's settings map onto the dataclass the notebook names, with no unknown key."""
    from lasa.base.config import from_dict

    cls = settings_class(notebook)
    built = from_dict(cls, load_config(config, notebook).get("settings", {}))
    assert isinstance(built, cls)
    if config.stem == "paper":  # the paper scale is the dataclass defaults, written once; but for
        # `jobs`, the worker processes of notebooks 10 and 11 (how many cores, not what is computed)
        import dataclasses

        if "jobs" in {f.name for f in dataclasses.fields(cls)}:
            built = dataclasses.replace(built, jobs=cls().jobs)
        assert built == cls()


def test_an_unknown_setting_is_an_error():
    from lasa.base.config import from_dict
    from lasa.experiments import sim1

    with pytest.raises(
        ConfigError, match=r"^notebook 04 settings: unknown setting\(s\) \['n_seed'\]; known: .*'users'"
    ):
        from_dict(sim1.Config, {"n_seed": 3}, where="notebook 04")


@pytest.mark.parametrize("config", CONFIGS, ids=lambda p: p.stem)
@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda p: p.stem)
def test_shipped_configs_pass_only_known_parameters(config, notebook):
    params = load_config(config, notebook)
    assert params["quick"] == (config.stem == "quick")


def test_quick_config_never_writes_into_figures():
    for notebook in NOTEBOOKS:
        params = load_config(CONFIGS[1], notebook)
        assert not Path(params["figures_dir"]).resolve().is_relative_to((ROOT / "figures").resolve())
        assert Path(params["build_dir"]).parts[:2] == ("build", "quick")


def test_unknown_parameter_is_an_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("common:\n  quick: true\n04_fixed_expertise:\n  n_seed: 3\n")
    with pytest.raises(ConfigError, match=r"unknown parameter\(s\) \['n_seed'\]"):
        load_config(bad, ROOT / "notebooks" / "04_fixed_expertise.ipynb")


def test_malformed_config_is_an_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("- just\n- a list\n")
    with pytest.raises(ConfigError, match="must map section names"):
        load_config(bad, NOTEBOOKS[0])


def _notebook(*source: str) -> dict:
    """A notebook of an empty ``parameters`` cell and one code cell of ``source``'s lines."""
    cells = [(["parameters"], ["settings = {}\n"]), ([], list(source))]
    return {
        "cells": [
            {
                "cell_type": "code",
                "id": f"c{i}",
                "metadata": {"tags": tags},
                "execution_count": None,
                "outputs": [],
                "source": text,
            }
            for i, (tags, text) in enumerate(cells)
        ],
        "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"}},
        "nbformat": 4,
        "nbformat_minor": 5,
    }


def test_the_kernel_listens_on_unix_sockets_in_a_folder_of_its_own(tmp_path):
    """No TCP port to race for between kernels started side by side; the folder goes with the run."""
    from lasa.pipeline.execute import execute

    notebook = tmp_path / "sockets.ipynb"
    lines = (
        "from ipykernel import get_connection_info\n",
        "{k: get_connection_info(unpack=True)[k] for k in ('transport', 'ip')}\n",
    )
    notebook.write_text(json.dumps(_notebook(*lines)))
    execute(notebook, tmp_path / "out.ipynb", {}, tmp_path, progress=False)
    result = json.loads((tmp_path / "out.ipynb").read_text())
    info = ast.literal_eval("".join(result["cells"][-1]["outputs"][0]["data"]["text/plain"]))
    assert info["transport"] == "ipc"
    folder = Path(info["ip"]).parent
    assert folder.name.startswith("lasa-kernel-") and not folder.exists()


def test_a_failed_notebook_ends_with_the_librarys_own_error(tmp_path):
    """The CLI's last line is the cause (a ConfigError raised in a cell) and the partial run's path."""
    import subprocess
    import sys

    nb = _notebook("from lasa.base.config import check_range\n", "check_range('alpha', 2.0, 0.0, 1.0)\n")
    notebook = tmp_path / "broken.ipynb"
    notebook.write_text(json.dumps(nb))
    config = tmp_path / "c.yaml"
    config.write_text("common: {}\n")
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "lasa.pipeline.execute",
            str(notebook),
            "--config",
            str(config),
            "--out",
            str(tmp_path / "out"),
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert run.returncode == 1
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("error: ") and "ConfigError: alpha must be" in last
    partial = tmp_path / "out" / "broken.failed.ipynb"
    assert str(partial) in last and partial.is_file()
    assert not (tmp_path / "out" / "broken.ipynb").exists()  # no half-written result for Make to take


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (None, r"error: .*missing\.yaml does not exist"),
        ("common: [unclosed\n", r"error: .*is not a YAML file \(line "),
    ],
)
def test_a_missing_or_non_yaml_config_is_one_line(tmp_path, capsys, text, message):
    from lasa.pipeline.execute import main

    config = tmp_path / ("missing.yaml" if text is None else "bad.yaml")
    if text is not None:
        config.write_text(text)
    code = main([str(NOTEBOOKS[0]), "--config", str(config), "--out", str(tmp_path), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert __import__("re").match(message, err), err


def test_a_run_reads_the_parameters_cell_once(tmp_path, monkeypatch):
    """run_notebook checks the config and the overrides against one read of the ``parameters`` cell."""
    import papermill as pm

    from lasa.pipeline import execute

    calls = []
    inspect = pm.inspect_notebook
    monkeypatch.setattr(pm, "inspect_notebook", lambda path: calls.append(path) or inspect(path))
    notebook = tmp_path / "once.ipynb"
    notebook.write_text(json.dumps(_notebook("print(settings)\n")))
    config = tmp_path / "c.yaml"
    config.write_text("common: {settings: {a: 1}}\n")
    out = execute.run_notebook(notebook, config, tmp_path / "out", {"settings": {"a": 2}}, progress=False)
    assert len(calls) == 1 and out.is_file()
    assert "{'a': 2}" in "".join(json.loads(out.read_text())["cells"][-1]["outputs"][0]["text"])
