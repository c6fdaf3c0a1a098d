"""A failed notebook leaves the figures folder as it was (execution's write journal, lasa.base.journal)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import nbformat
import pandas as pd
import pytest

from lasa.base import journal
from lasa.base.errors import NotebookError
from lasa.base.io import update_csv
from lasa.pipeline.execute import run_notebook

# One robot's run of a toy figure, as a figure notebook publishes it: its rows merged into toy.csv,
# the PNG redrawn, its claim's rows in claims.csv and claim_values.csv (and claims.md), and a
# plain CSV of its own (a new file for each scale).
WRITE = """
import types

import matplotlib.pyplot as plt
import pandas as pd

from lasa.base.io import write_csv
from lasa.base.paths import Paths
from lasa.evidence.claims import Claim
from lasa.evidence.publish import publish


def plot(table):
    fig, ax = plt.subplots(figsize=(1, 1))
    ax.plot(table.x, table.y)
    return fig


TOY = types.SimpleNamespace(NAME="toy", COLUMNS=("robot", "x", "y"), plot=plot)


def write(figures_dir, robot, scale):
    paths = Paths.of("build", figures_dir)
    frame = pd.DataFrame({"robot": robot, "x": [0.0, 1.0], "y": [scale, 2 * scale]})
    claim = Claim(
        id="toy.grows", claim="y grows", figure="toy", paper="p", measured=f"{scale:g}",
        reproduced="yes", note="n", robot=robot, value=scale, ci_low=scale - 1, ci_high=scale + 1,
        n_users=3, values={"y": scale}, intervals={"y": (scale - 1, scale + 1)}, level=0.95,
    )
    publish(TOY, frame, paths, claims=[claim])
    write_csv(paths.figure(f"toy_{robot}_{scale:g}.csv"), frame)
"""


def writer():
    """The ``write`` function of :data:`WRITE`, for this process."""
    namespace: dict = {}
    exec(WRITE, namespace)
    return namespace["write"]


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.fixture
def figures(tmp_path):
    """A figures folder holding both robots' toy runs (scale 1)."""
    folder = tmp_path / "figures"
    write = writer()
    write(folder, "panda", 1.0)
    write(folder, "planar5", 1.0)
    return folder


def toy_notebook(tmp_path: Path, fail: bool) -> tuple[Path, Path]:
    """A notebook that publishes planar5's toy run at scale 2, then raises if ``fail``; and a config."""
    nb = nbformat.v4.new_notebook()
    params = nbformat.v4.new_code_cell('figures_dir = "figures"\nrobot = "planar5"')
    params.metadata["tags"] = ["parameters"]
    cells = [params, nbformat.v4.new_code_cell(WRITE + "\nwrite(figures_dir, robot, 2.0)")]
    if fail:
        cells.append(nbformat.v4.new_code_cell('raise RuntimeError("the sweep broke")'))
    nb.cells = cells
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    path = tmp_path / ("fails.ipynb" if fail else "works.ipynb")
    nbformat.write(nb, path)
    config = tmp_path / "config.yaml"
    config.write_text("common: {}\n")
    return path, config


def test_a_failed_notebook_leaves_the_figures_as_they_were(figures, tmp_path):
    before = snapshot(figures)
    notebook, config = toy_notebook(tmp_path, fail=True)
    out = tmp_path / "out"
    with pytest.raises(NotebookError, match=r"the sweep broke .* 6 file\(s\) it wrote in .* were restored"):
        run_notebook(notebook, config, out, {"figures_dir": str(figures), "robot": "planar5"}, progress=False)
    assert snapshot(figures) == before  # toy_planar5_2.csv gone, the others' old bytes back
    assert sorted(p.name for p in out.iterdir()) == ["fails-planar5.failed.ipynb"]  # no journal left
    assert journal.ENV not in os.environ


def test_a_notebook_that_succeeds_keeps_its_writes_and_no_journal(figures, tmp_path):
    notebook, config = toy_notebook(tmp_path, fail=False)
    out = tmp_path / "out"
    run_notebook(notebook, config, out, {"figures_dir": str(figures), "robot": "planar5"}, progress=False)
    toy = pd.read_csv(figures / "toy.csv")
    assert toy[toy.robot == "planar5"].y.tolist() == [2.0, 4.0] and toy[toy.robot == "panda"].y.tolist() == [
        1,
        2,
    ]
    claims = pd.read_csv(figures / "claims.csv").set_index("robot")
    assert claims.loc["planar5", "measured"] == 2 and claims.loc["panda", "measured"] == 1
    assert (figures / "toy_planar5_2.csv").exists()
    assert sorted(p.name for p in out.iterdir()) == ["works-planar5.ipynb"]
    assert journal.ENV not in os.environ


def test_restore_keeps_the_rows_a_parallel_run_wrote_meanwhile(figures, tmp_path):
    """planar5's run writes, panda's run (beside it) then rewrites the shared files, planar5's fails.

    The merged tables come back as if planar5's run had never happened: byte for byte the folder
    where only panda's run wrote. The PNG and claims.md, redrawn by panda from planar5's rows too,
    cannot be split by rows: they are left and named.
    """
    write = writer()
    twin = tmp_path / "twin"
    shutil.copytree(figures, twin)
    with journal.recording(tmp_path / "journal", figures):
        write(figures, "planar5", 2.0)  # the run that will fail
    write(figures, "panda", 3.0)  # the notebook beside it, unjournaled, after it
    write(twin, "panda", 3.0)  # what the folder should hold
    result = journal.restore(tmp_path / "journal")
    assert sorted(p.name for p in figures.iterdir()) == sorted(p.name for p in twin.iterdir())
    for name in ("toy.csv", "claims.csv", "claim_values.csv", "toy_planar5_1.csv"):
        assert (figures / name).read_bytes() == (twin / name).read_bytes(), name
    assert pd.read_csv(figures / "claim_values.csv").groupby("robot").value.first().to_dict() == {
        "panda": 3,
        "planar5": 1,
    }
    assert sorted(p.name for p, _ in result.left) == ["claims.md", "toy.png"]
    assert str(result).startswith(f"4 of the 6 file(s) it wrote in {figures} were restored; not: ")
    assert "toy.png (another run rewrote it since)" in str(result)


def test_restored_rows_keep_a_numeric_key_in_numeric_order(tmp_path):
    """A figure keyed by a number (module.KEY): the rows come back sorted as update_csv sorts them."""
    path, twin = tmp_path / "figures" / "beta.csv", tmp_path / "twin" / "beta.csv"

    def rows(betas, y):
        return pd.DataFrame({"beta": betas, "y": [y] * len(betas)})

    for target in (path, twin):
        update_csv(target, rows([1.0, 10.0, 1e-7], 0.5), key="beta")
    with journal.recording(tmp_path / "journal", path.parent):
        update_csv(path, rows([10.0, 1e-7], 0.25), key="beta")  # the failing run
    for target in (path, twin):
        update_csv(target, rows([2.0], 0.75), key="beta")  # another run, meanwhile
    result = journal.restore(tmp_path / "journal")
    assert result.restored == [path] and not result.left
    assert path.read_text() == twin.read_text() == "beta,y\n1e-07,0.5\n1,0.5\n2,0.75\n10,0.5\n"


def test_writes_outside_the_journaled_folder_are_not_journaled(tmp_path):
    from lasa.base.io import write_text

    with journal.recording(tmp_path / "journal", tmp_path / "figures"):
        write_text(tmp_path / "elsewhere.txt", "x")
        write_text(tmp_path / "figures" / "new.txt", "y")
    result = journal.restore(tmp_path / "journal")
    assert (tmp_path / "elsewhere.txt").read_text() == "x" and not (tmp_path / "figures" / "new.txt").exists()
    assert result.restored == [(tmp_path / "figures" / "new.txt").resolve()]
