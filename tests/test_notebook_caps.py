"""Notebook 10 in QUICK mode with the study's belief uncapped (``belief_cap: none``).

The main QUICK run (tests/test_notebooks.py) runs it with the study's cap, 0.99. Before the
cap followed every belief threshold, a cap crashed this notebook: the entropy sweep selected
no confident context and its table was all NaN. Here the other end: Algorithm 1's belief, no
cap, through the same notebook, and its outputs say so.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch
import yaml

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "configs" / "quick.yaml"
NOTEBOOK = ROOT / "notebooks" / "10_eating_task.ipynb"


@pytest.fixture(scope="module")
def uncapped(tmp_path_factory):
    out = tmp_path_factory.mktemp("uncapped")
    config = yaml.safe_load(QUICK.read_text())
    settings = config["10_eating_task"]["settings"]
    # the uncapped belief through the notebook's every step, on the one segmentation its sweep needs
    settings.update(
        belief_cap="none", segmentations=["continuous"], search_segmentations=[], sector_segmentations=[]
    )
    settings.update(seed_segmentations=[])
    path = out / "uncapped.yaml"
    path.write_text(yaml.safe_dump(config))
    command = [sys.executable, "-m", "lasa.pipeline.execute", str(NOTEBOOK), "--config", str(path),
               "--out", str(out / "notebooks"), "--param", f"build_dir={out / 'build'}",
               "--param", f"figures_dir={out / 'figures'}"]  # fmt: skip
    result = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 0, f"{result.stdout[-2000:]}\n{result.stderr[-4000:]}"
    return out


def test_notebook_10_runs_uncapped_and_says_so(uncapped):
    from lasa.evidence import latent_property

    models = uncapped / "build" / "models"
    saved = torch.load(models / "eating_decoder_panda.pt", weights_only=True)
    assert saved["extra"]["control"]["belief_cap"] is None
    demos = np.load(uncapped / "build" / "data" / "eating_demos_panda.npz")
    assert demos["beliefs"].max() > 0.999  # without the cap a goal goes past 0.99
    frame = pd.read_csv(uncapped / "figures" / "latent_property.csv")
    assert set(frame.source) == {"eating"}  # the sweep's only cap is this run's own: nothing more trained
    assert latent_property.choose(latent_property.summary(frame)) == saved["extra"]["reading"]
    executed = (uncapped / "notebooks" / "10_eating_task.ipynb").read_text()
    assert "notebook 03's rule on the continuous base picks lambda =" in executed  # the sweep found contexts
