"""Folders resolve against the repository root, whatever the working directory."""

from pathlib import Path

import pytest

from lasa.base.errors import ConfigError
from lasa.base.paths import ARTIFACTS, Paths, repo_root, resolve

ROOT = Path(__file__).resolve().parents[1]


def test_root_is_the_clone_and_relative_paths_resolve_against_it(monkeypatch, tmp_path):
    monkeypatch.delenv("LASA_ROOT", raising=False)
    assert repo_root() == ROOT
    monkeypatch.chdir(tmp_path)  # as Jupyter's kernel in notebooks/: the working directory does not matter
    assert resolve("build") == ROOT / "build"
    assert resolve(tmp_path / "x") == tmp_path / "x"


def test_lasa_root_overrides(monkeypatch, tmp_path):
    monkeypatch.setenv("LASA_ROOT", str(tmp_path))
    assert Paths.of("build", "figures") == Paths(tmp_path / "build", tmp_path / "figures")
    monkeypatch.setenv("LASA_ROOT", str(tmp_path / "missing"))
    with pytest.raises(ConfigError, match="LASA_ROOT"):
        repo_root()


def test_artifacts_and_their_hints():
    paths = Paths(Path("/b"), Path("/f"))
    assert paths.artifact("decoder", "panda") == Path("/b/models/decoder_panda.pt")
    assert paths.artifact("decoder_lambda0", "planar5") == Path("/b/models/decoder_planar5_lambda0.pt")
    assert "03_entropy_ablation" in Paths.make_hint("decoder_entropy", "panda")
    assert paths.claims == Path("/f/claims.csv")
    assert set(ARTIFACTS) >= {"demos", "decoder", "decoder_lambda0", "decoder_entropy", "latent_paths"}
    with pytest.raises(ConfigError, match="unknown artifact"):
        paths.artifact("decoder_typo", "panda")
