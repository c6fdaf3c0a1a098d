"""lasa.base.kernels: the numerical kernels pinned to AVX2, before torch and numpy load."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

from lasa.base.kernels import PINNED

ROOT = Path(__file__).resolve().parents[1]
NAMES = sorted(PINNED)
PROBE = (
    "import lasa, numpy, torch, json, os;"
    "from numpy._core._multiarray_umath import __cpu_features__ as f;"
    "print(json.dumps({'torch': torch.backends.cpu.get_cpu_capability(), 'x86_v4': f['X86_V4'],"
    f"'env': {{k: os.environ.get(k) for k in {NAMES!r}}}}}))"
)


def _probe(**env: str) -> dict:
    clean = {k: v for k, v in os.environ.items() if k not in PINNED}
    out = subprocess.run(
        [sys.executable, "-c", PROBE],
        env={**clean, "MUJOCO_GL": "disable", **env},
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    return json.loads(out.stdout)


def test_importing_lasa_pins_every_kernel_before_torch_and_numpy_load():
    seen = _probe()
    assert seen["env"] == PINNED
    assert seen["torch"] == "AVX2"  # torch's dispatch reads the variable lasa set
    assert seen["x86_v4"] is False  # numpy's AVX-512 loops are off


def test_a_value_set_by_the_user_is_kept():
    seen = _probe(ATEN_CPU_CAPABILITY="default")
    assert seen["env"]["ATEN_CPU_CAPABILITY"] == "default" and seen["torch"] == "DEFAULT"
    assert seen["env"]["MKL_CBWR"] == PINNED["MKL_CBWR"]


def test_make_exports_the_same_values():
    text = (ROOT / "Makefile").read_text()
    exported = dict(re.findall(r"^export (\w+) \?= (.+)$", text, flags=re.M))
    assert {k: exported[k] for k in PINNED} == PINNED


def test_the_record_says_whether_the_run_was_pinned(tmp_path):
    out = tmp_path / "kernels.json"
    clean = {k: v for k, v in os.environ.items() if k not in PINNED}
    for env, pinned in (({}, True), ({"MKL_CBWR": "AUTO"}, False)):
        subprocess.run(
            [sys.executable, "-m", "lasa.pipeline.kernels", "--out", str(out)],
            env={**clean, "MUJOCO_GL": "disable", **env},
            check=True,
            cwd=ROOT,
        )
        record = json.loads(out.read_text())
        assert record["pinned"] is pinned and record["torch_cpu_capability"] == "AVX2"


def _stderr(code: str) -> str:
    clean = {k: v for k, v in os.environ.items() if k not in PINNED}
    run = subprocess.run(
        [sys.executable, "-c", code],
        env={**clean, "MUJOCO_GL": "disable"},
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    return run.stderr


def test_numpy_loaded_before_lasa_is_warned_about():
    assert "numpy was imported before lasa" in _stderr("import numpy, lasa")
    assert "numpy was imported before lasa" not in _stderr("import lasa, numpy")
