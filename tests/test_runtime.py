"""lasa.runtime: the renderer and the numerical kernels pinned by one explicit call, recorded."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

from lasa.runtime import PINNED, RENDERER

ROOT = Path(__file__).resolve().parents[1]
NAMES = sorted({**PINNED, **RENDERER})
PROBE = (
    "import lasa.runtime; lasa.runtime.pin(); import numpy, torch, json, os;"
    "from numpy._core._multiarray_umath import __cpu_features__ as f;"
    "print(json.dumps({'torch': torch.backends.cpu.get_cpu_capability(), 'x86_v4': f['X86_V4'],"
    f"'env': {{k: os.environ.get(k) for k in {NAMES!r}}}}}))"
)


def _run(args: list[str], **env: str) -> subprocess.CompletedProcess:
    clean = {k: v for k, v in os.environ.items() if k not in NAMES}
    return subprocess.run(
        [sys.executable, *args], env={**clean, **env}, capture_output=True, text=True, check=True, cwd=ROOT
    )


def _probe(**env: str) -> dict:
    return json.loads(_run(["-c", PROBE], **env).stdout)


def test_pin_sets_the_renderer_and_every_kernel_before_torch_and_numpy_load():
    seen = _probe()
    assert seen["env"] == {**PINNED, **RENDERER}
    assert seen["torch"] == "AVX2"  # torch's dispatch reads the variable pin() set
    assert seen["x86_v4"] is False  # numpy's AVX-512 loops are off


def test_a_value_set_by_the_user_is_kept():
    seen = _probe(ATEN_CPU_CAPABILITY="default", MUJOCO_GL="disable")
    assert seen["env"]["ATEN_CPU_CAPABILITY"] == "default" and seen["torch"] == "DEFAULT"
    assert seen["env"]["MUJOCO_GL"] == "disable"
    assert seen["env"]["MKL_CBWR"] == PINNED["MKL_CBWR"]


def test_make_exports_the_same_values():
    text = (ROOT / "Makefile").read_text()
    exported = dict(re.findall(r"^export (\w+) \?= (.+)$", text, flags=re.M))
    assert {k: exported[k] for k in {**PINNED, **RENDERER}} == {**PINNED, **RENDERER}


def test_the_record_says_whether_the_run_was_pinned(tmp_path):
    out = tmp_path / "kernels.json"
    for env, pinned in (({}, True), ({"MKL_CBWR": "AUTO"}, False)):
        _run(["-m", "lasa.runtime", "--out", str(out)], MUJOCO_GL="disable", **env)
        record = json.loads(out.read_text())
        assert record["pinned"] is pinned and record["torch_cpu_capability"] == "AVX2"
        assert set(record["environment"]) == set(PINNED)  # figures/kernels.json keeps its keys


def test_a_pin_too_late_to_take_effect_is_warned_about():
    late = "came after the import of what reads"
    warned = _run(["-c", "import numpy, lasa.runtime; lasa.runtime.pin()"]).stderr
    assert late in warned and "NPY_DISABLE_CPU_FEATURES (numpy)" in warned and "(torch)" not in warned
    assert late not in _run(["-c", "import lasa.runtime; lasa.runtime.pin(); import numpy"]).stderr
    # already set (make's exports): nothing to set, so nothing is late
    code = "import numpy, lasa.runtime; lasa.runtime.pin()"
    assert late not in _run(["-c", code], **PINNED, **RENDERER).stderr
