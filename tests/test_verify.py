"""`make verify` (lasa.pipeline.verify): comparing a regenerated figures folder with the committed one."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from lasa.base.errors import ArtifactError
from lasa.pipeline.verify import Tolerance, compare_folders, key_columns, main

ROOT = Path(__file__).resolve().parents[1]
PNG = b"\x89PNG\r\n\x1a\n" + bytes(range(64))


def _folder(root: Path) -> Path:
    """A tiny figures folder: a CSV (label, numeric and text columns), a PNG and a claims table."""
    root.mkdir()
    pd.DataFrame(
        {
            "robot": ["panda", "panda", "planar5"],
            "error": [0.5, 1.25, 3.0],
            "note": ["a b", "c d", "e f"],
        }
    ).to_csv(root / "sim.csv", index=False)
    (root / "sim.png").write_bytes(PNG)
    pd.DataFrame(
        {
            "id": ["sim1.a", "sim1.a", "sim2.b"],
            "claim": ["SA helps", "SA helps", "B holds"],
            "robot": ["panda", "planar5", "panda"],
            "measured": [0.1, 0.2, 0.3],
            "reproduced": ["yes", "partly", "no"],
            "settled": ["yes", "no", "yes"],
            "effect": ["reproduced", "partly", "not reproduced"],
            "number": ["in", "undecided", "out; in"],
        }
    ).to_csv(root / "claims.csv", index=False)
    return root


@pytest.fixture
def folders(tmp_path: Path) -> tuple[Path, Path]:
    return _folder(tmp_path / "committed"), _folder(tmp_path / "new")


def _edit(path: Path, column: str, row: int, value: object) -> None:
    frame = pd.read_csv(path)
    frame[column] = frame[column].astype(object)
    frame.loc[row, column] = value
    frame.to_csv(path, index=False)


def test_identical_folders_pass(folders, capsys):
    assert main([str(f) for f in folders]) == 0
    out = capsys.readouterr().out
    for name in ("sim.csv", "sim.png", "claims.csv"):
        assert f"| {name}" in out
    *kernels, summary = out.strip().splitlines()
    table = kernels[2:]  # the two runs' kernel lines, one table, then the summary line
    assert all(line.startswith("kernels of the ") for line in kernels[:2])
    assert all(line.endswith("|") for line in table)
    assert [line.split("|")[3].strip() for line in table[2:]] == ["identical"] * 4
    assert summary == "OK: 3 files compared, 0 with differences; every verdict identical"


def test_a_value_beyond_tolerance_is_reported_and_does_not_fail(folders, capsys):
    committed, new = folders
    _edit(new / "sim.csv", "error", 1, 1.5)  # 1.25 -> 1.5: abs 0.25, rel 0.2
    _edit(new / "sim.csv", "note", 2, "changed")
    assert main([str(committed), str(new)]) == 0
    lines = capsys.readouterr().out.splitlines()
    error = next(line for line in lines if "| error" in line)
    assert "beyond tolerance" in error and "max abs 0.25, max rel 0.2, 1 rows" in error
    assert any("| note" in line and "1 cells" in line for line in lines)
    assert any("| rows" in line and "1 of 3 rows" in line for line in lines)
    assert lines[-1].startswith("OK:") and "1 with differences" in lines[-1]


def test_tolerance_passes_print_precision_noise(folders):
    committed, new = folders
    _edit(new / "sim.csv", "error", 2, 3.0 + 2e-7)
    assert [r.result for r in compare_folders(committed, new).rows if r.file == "sim.csv"] == ["identical"]
    loose = compare_folders(committed, new, Tolerance(rtol=0.0, atol=0.0))
    assert "beyond tolerance" in [r.result for r in loose.rows]


def test_rows_that_no_longer_line_up_are_reported_as_rows_differ(folders):
    committed, new = folders
    _edit(new / "sim.csv", "robot", 0, "planar5")  # a key column: the rows are other rows
    rows = [r for r in compare_folders(committed, new).rows if r.file == "sim.csv"]
    assert [(r.part, r.result) for r in rows] == [("rows", "rows differ")]
    assert key_columns(pd.read_csv(committed / "sim.csv")) == ["robot"]


def test_a_changed_verdict_fails_and_names_the_claim(folders, capsys):
    committed, new = folders
    _edit(new / "claims.csv", "reproduced", 1, "yes")
    assert main([str(committed), str(new)]) == 1
    out = capsys.readouterr().out
    assert "verdict sim1.a / planar5" in out and "reproduced partly -> yes" in out
    assert "sim1.a / panda" not in out
    assert out.splitlines()[-1].startswith("FAILED:") and "1 verdict(s) differ" in out


def test_a_changed_number_word_alone_fails(folders, capsys):
    committed, new = folders
    _edit(new / "claims.csv", "number", 2, "in; in")
    assert main([str(committed), str(new)]) == 1
    assert "number out; in -> in; in" in capsys.readouterr().out


def test_a_claim_in_one_table_only_fails(folders):
    committed, new = folders
    frame = pd.read_csv(new / "claims.csv")
    frame.iloc[:2].to_csv(new / "claims.csv", index=False)
    report = compare_folders(committed, new)
    assert report.failed and report.verdicts_differ == ["sim2.b / panda: missing from the new table"]


def test_a_changed_byte_in_an_image_differs(folders, capsys):
    committed, new = folders
    (new / "sim.png").write_bytes(PNG[:-1] + b"\x00")
    assert main([str(committed), str(new)]) == 0
    assert any("| sim.png" in line and "differs" in line for line in capsys.readouterr().out.splitlines())


def test_missing_and_extra_files(folders, capsys):
    committed, new = folders
    (new / "sim.png").unlink()
    (new / "extra.mp4").write_bytes(b"x")
    assert main([str(committed), str(new)]) == 0
    out = capsys.readouterr().out
    assert "missing in new" in out and "missing in committed" in out
    (new / "claims.csv").unlink()
    assert main([str(committed), str(new)]) == 1
    assert "claims.csv missing" in capsys.readouterr().out


def test_a_missing_folder_is_a_clear_error(folders, tmp_path, capsys):
    assert main([str(folders[0]), str(tmp_path / "nowhere")]) == 2
    assert "nowhere does not exist" in capsys.readouterr().err
    with pytest.raises(ArtifactError, match="make figures OUT="):
        compare_folders(tmp_path / "nowhere", folders[1])


@pytest.fixture(scope="module")
def tree(tmp_path_factory) -> Path:
    """A copy of the pipeline with `make setup` done (its stamps), as tests/test_makedeps.py does."""
    tree = tmp_path_factory.mktemp("repo")
    for name in ("Makefile", "pyproject.toml", "environment.lock"):
        shutil.copy2(ROOT / name, tree / name)
    for name in ("lasa", "notebooks", "configs"):
        shutil.copytree(ROOT / name, tree / name, ignore=shutil.ignore_patterns("__pycache__"))
    for stamp in (".venv/.lasa-installed", ".venv/mathjax/es5/tex-chtml.js"):
        (tree / stamp).parent.mkdir(parents=True, exist_ok=True)
        (tree / stamp).touch()
    return tree


def _make(tree: Path, *args: str) -> str:
    return subprocess.run(
        ["make", "--no-print-directory", *args], cwd=tree, capture_output=True, text=True, check=True
    ).stdout


def test_make_verify_runs_the_pipeline_into_its_own_folder_then_compares(tree):
    out = _make(tree, "-n", "verify")
    assert "figures OUT=build/verify" in out
    assert ".venv/bin/python -m lasa.pipeline.verify figures build/verify/figures" in out
    runs = [line for line in out.splitlines() if "lasa.pipeline.execute" in line]
    assert runs and all("--param figures_dir=build/verify/figures" in line for line in runs)
    assert "lasa.evidence.claims README.md" not in out  # figures/ and README.md untouched


def test_a_bare_make_prints_the_usage(tree):
    out = _make(tree)
    assert "make figures" in out and "make verify" in out and "make help" in out
    assert not any(line.startswith("#") for line in out.splitlines())


def test_a_value_that_became_non_finite_is_named_with_its_rows(folders, capsys):
    _edit(folders[1] / "sim.csv", "error", 1, float("inf"))
    _edit(folders[1] / "sim.csv", "error", 2, float("nan"))
    assert main([str(f) for f in folders]) == 0  # values are reported, never fatal
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if "non-finite" in x)
    assert "2 rows" in line and "row 1 (panda): 1.25 -> inf" in line and "row 2 (planar5): 3 -> nan" in line
    beyond = next(x for x in out.splitlines() if "| error" in x and "beyond tolerance" in x)
    assert "max abs 0," in beyond and "2 rows" in beyond  # no infinite difference among the finite pairs


def test_two_equal_non_finite_values_are_the_same(folders):
    for folder in folders:
        _edit(folder / "sim.csv", "error", 0, float("-inf"))
    report = compare_folders(*folders)
    assert all(r.result == "identical" for r in report.rows if r.file == "sim.csv")


def test_each_runs_kernels_are_printed_above_the_table(folders, capsys):
    (folders[0] / "kernels.json").write_text(
        '{"environment": {"ATEN_CPU_CAPABILITY": "avx2"}, "pinned": true, "torch_cpu_capability": "AVX2"}'
    )
    main([str(f) for f in folders])
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "kernels of the committed run: pinned, torch AVX2; ATEN_CPU_CAPABILITY=avx2"
    assert out[1] == "kernels of the new run: kernels.json missing (its kernels were not recorded)"


def _page(folder: Path, build: str, outputs: dict[str, str]) -> Path:
    """A notebook page under ``folder/notebooks``: the run's injected parameters, then a code cell
    per ``{id: printed text}``, and an image output."""
    params = f'robot = "panda"\nbuild_dir = "{build}"\nfigures_dir = "{build}/figures"\n'
    injected = {"cell_type": "code", "id": "injected-parameters", "execution_count": 1, "outputs": []}
    cells = [{**injected, "metadata": {"tags": ["injected-parameters"]}, "source": params}]
    for i, (cell_id, text) in enumerate(outputs.items()):
        stream = {"name": "stdout", "output_type": "stream", "text": text}
        cells.append({"cell_type": "code", "execution_count": i + 2, "id": cell_id, "metadata": {}})
        cells[-1].update(outputs=[stream], source="print(...)")
    image = {"data": {"image/png": "iVBORw0KGgo=", "text/plain": "<Figure>"}, "metadata": {}}
    cells[-1]["outputs"].append({**image, "output_type": "display_data"})
    path = folder / "notebooks" / "04_fixed_expertise-panda.ipynb"
    path.parent.mkdir(exist_ok=True)
    path.write_text(json.dumps({"cells": cells, "metadata": {}, "nbformat": 4, "nbformat_minor": 5}))
    return path


SHOWN = {"run": "6 demonstrations -> {}/data/demos_panda.npz\n", "shows": "V rose on 0 of 243 steps.\n"}


def _pages(folders: tuple[Path, Path], new_text: dict[str, str] | None = None) -> None:
    """The same page in both folders, the new one run into ``build/verify`` (its paths differ)."""
    committed, new = folders
    _page(committed, "build", {k: v.format("build") for k, v in SHOWN.items()})
    texts = {k: v.format("build/verify") for k, v in SHOWN.items()}
    _page(new, "build/verify", {**texts, **(new_text or {})})


def test_notebook_pages_with_the_same_outputs_are_identical(folders, capsys):
    _pages(folders)  # the printed paths differ by the run's folder only
    assert main([str(f) for f in folders]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "| notebooks/" in x)
    assert "| outputs " in line and "| identical" in line and "3 code cells" in line


def test_a_notebook_output_that_differs_is_listed_and_does_not_fail(folders, capsys):
    _pages(folders, {"shows": "V rose on 2 of 243 steps.\n", "extra": "new cell\n"})
    assert main([str(f) for f in folders]) == 0  # never fatal: the verdicts decide
    lines = [x for x in capsys.readouterr().out.splitlines() if "| notebooks/" in x]
    shows = next(x for x in lines if "| cell shows" in x)
    assert "outputs differ" in shows
    assert "line 1: 'stdout: V rose on 0 of 243 steps.' -> 'stdout: V rose on 2 of 243 steps.'" in shows
    assert any("| cell extra" in x and "cell only in new" in x for x in lines)
    assert not any("| cell run" in x for x in lines)  # its path differs by the run's folder alone


def test_a_notebook_image_that_differs_is_listed(folders, capsys):
    committed, new = folders
    _pages(folders)
    page = new / "notebooks" / "04_fixed_expertise-panda.ipynb"
    data = json.loads(page.read_text())
    data["cells"][-1]["outputs"][-1]["data"]["image/png"] = "iVBORw0KGgp="
    page.write_text(json.dumps(data))
    assert main([str(committed), str(new)]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "| cell shows" in x)
    assert "outputs differ" in line and "image/png: sha256" in line
