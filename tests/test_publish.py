"""publish: a robot's rows merged, the figure drawn from the file, claims replaced; order-free."""

from __future__ import annotations

import types
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from lasa.base.errors import ConfigError  # noqa: E402
from lasa.base.paths import Paths  # noqa: E402
from lasa.evidence.claims import Claim  # noqa: E402
from lasa.evidence.publish import publish  # noqa: E402


def fake_module(seen: list[pd.DataFrame]) -> types.SimpleNamespace:
    def plot(table: pd.DataFrame) -> plt.Figure:
        seen.append(table.copy())
        fig, ax = plt.subplots(figsize=(2, 2))
        for name, part in table.groupby("robot"):
            ax.plot(part.x, part.y, label=name)
        return fig

    return types.SimpleNamespace(NAME="toy", COLUMNS=("robot", "x", "y"), plot=plot, DPI=50)


def rows(robot: str, seed: int) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    return pd.DataFrame({"robot": robot, "x": np.arange(5.0), "y": rng.random(5) / 3, "extra": 1})


def claim(robot: str) -> Claim:
    return Claim(
        id="toy.a", claim="c", figure="toy", paper="p", measured="m", reproduced="yes", note="n", robot=robot
    )


@pytest.mark.parametrize("order", [("planar5", "panda"), ("panda", "planar5")])
def test_the_files_do_not_depend_on_which_robot_publishes_last(tmp_path, order):
    results = {}
    for run, robots in (("a", order), ("b", order[::-1])):
        paths = Paths(tmp_path / run / "build", tmp_path / run / "figures")
        seen: list[pd.DataFrame] = []
        module = fake_module(seen)
        for robot in robots:
            publish(module, rows(robot, 0 if robot == "panda" else 1), paths, [claim(robot)])
        results[run] = (paths.figures, seen[-1])
    (fa, ta), (fb, tb) = results["a"], results["b"]
    for name in ("toy.csv", "toy.png", "claims.csv", "claims.md"):
        assert (fa / name).read_bytes() == (fb / name).read_bytes(), name
    pd.testing.assert_frame_equal(ta, tb)  # the figure was drawn from the same numbers
    assert list(pd.read_csv(fa / "toy.csv").columns) == ["robot", "x", "y"]  # only COLUMNS are kept


def test_rows_without_a_column_are_refused(tmp_path):
    module = fake_module([])
    with pytest.raises(ConfigError, match="lack column"):
        publish(module, rows("panda", 0).drop(columns="y"), Paths(Path(tmp_path), Path(tmp_path)))
