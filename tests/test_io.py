"""Atomic writes: an interrupted write leaves nothing behind; a finished one is complete."""

import os

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ArtifactError
from lasa.base.io import atomic_path, load_npz, save_npz, write_csv


def test_interrupted_write_leaves_no_file(tmp_path):
    target = tmp_path / "out.csv"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("interrupted")
    assert not target.exists()
    assert os.listdir(tmp_path) == []


def test_interrupted_rewrite_keeps_the_old_file(tmp_path):
    target = write_csv(tmp_path / "out.csv", pd.DataFrame({"a": [1]}))
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(target) as tmp:
            tmp.write_text("partial")
            raise KeyboardInterrupt
    assert pd.read_csv(target).a.tolist() == [1]


def test_written_files_have_normal_permissions(tmp_path):
    target = write_csv(tmp_path / "out.csv", pd.DataFrame({"a": [1]}))
    assert target.stat().st_mode & 0o044  # readable by group/others, unlike mkstemp's 0600


def test_npz_round_trip_and_errors(tmp_path):
    path = save_npz(tmp_path / "x.npz", a=np.arange(3))
    assert load_npz(path, "make it")["a"].tolist() == [0, 1, 2]
    with pytest.raises(ArtifactError, match="make it"):
        load_npz(tmp_path / "missing.npz", "make it")


def test_update_csv_replaces_one_robots_rows(tmp_path):
    from lasa.base.io import update_csv

    path = tmp_path / "t.csv"
    update_csv(path, pd.DataFrame({"robot": ["a", "a"], "x": [1, 2]}))
    update_csv(path, pd.DataFrame({"robot": ["b"], "x": [3]}))
    assert update_csv(path, pd.DataFrame({"robot": ["a"], "x": [9]})) == path
    table = pd.read_csv(path)
    assert sorted(zip(table.robot, table.x, strict=True)) == [("a", 9), ("b", 3)]
    assert len(pd.read_csv(path)) == 2
    with pytest.raises(ArtifactError, match="columns"):
        update_csv(path, pd.DataFrame({"robot": ["a"], "y": [1]}))


def test_update_csv_replaces_an_older_version_only_when_every_row_goes(tmp_path):
    from lasa.base.io import update_csv

    path = tmp_path / "t.csv"
    update_csv(path, pd.DataFrame({"robot": ["a", "a"], "x": [1, 2]}))
    # new columns, and every old row is the robot being replaced: the file is the new table
    update_csv(path, pd.DataFrame({"robot": ["a"], "x": [5], "model": ["m"]}))
    table = pd.read_csv(path)
    assert list(table.columns) == ["robot", "x", "model"] and list(table.x) == [5]
    # another robot's rows would be lost: still an error, and the file is untouched
    update_csv(path, pd.DataFrame({"robot": ["b"], "x": [3], "model": ["m"]}))
    with pytest.raises(ArtifactError, match="columns"):
        update_csv(path, pd.DataFrame({"robot": ["a"], "y": [1]}))
    assert len(pd.read_csv(path)) == 2
