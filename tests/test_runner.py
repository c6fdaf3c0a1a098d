"""Notebook execution: parameters cells, config checking, committed notebooks."""

import ast
import json
from pathlib import Path

import pytest

from lasa.errors import ConfigError
from lasa.runner import load_config, notebook_parameters

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
CONFIGS = [ROOT / "configs" / "paper.yaml", ROOT / "configs" / "quick.yaml"]
COMMON = {"robot", "quick", "build_dir", "figures_dir", "seed"}


def test_there_are_notebooks():
    assert [p.stem[:2] for p in NOTEBOOKS] == ["01", "02", "03", "04", "05", "06", "07"]


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda p: p.stem)
def test_parameters_cell_is_first_code_cell_of_literals(notebook):
    cells = json.loads(notebook.read_text())["cells"]
    code = [c for c in cells if c["cell_type"] == "code"]
    assert "parameters" in code[0]["metadata"].get("tags", [])
    tree = ast.parse("".join(code[0]["source"]))
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
