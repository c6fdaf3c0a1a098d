"""The process's renderer and numerical kernels, pinned by one explicit call: :func:`pin`. An AVX-512 kernel
sums in another order than an AVX2 one and training amplifies the last bits (an AMD run moved 37 of 47 Intel
files and 3 verdicts): pinned to AVX2, every x86-64 CPU runs the same code (``figures/kernels.json``)."""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings

PINNED: dict[str, str] = {
    # torch's own vectorised kernels (tanh, exp, reductions): its AVX2 build of each (DispatchStub)
    "ATEN_CPU_CAPABILITY": "avx2",
    # oneDNN (torch's mkldnn backend): its JIT kernels emit AVX2 at most; both names (v2 and v3)
    "ONEDNN_MAX_CPU_ISA": "AVX2",
    "DNNL_MAX_CPU_ISA": "AVX2",
    # MKL (torch's BLAS): conditional numerical reproducibility, the AVX2 branch on every CPU
    "MKL_CBWR": "AVX2",
    "MKL_ENABLE_INSTRUCTIONS": "AVX2",
    # numpy's dispatched loops (exp, log, sin, sort ...): no AVX-512 ones; names a CPU lacks are ignored
    "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512F AVX512_SKX AVX512_CLX AVX512_CNL AVX512_ICL AVX512_SPR",
    # numpy's and scipy's OpenBLAS: the Haswell (AVX2) kernels and blocking, not those of the CPU found
    "OPENBLAS_CORETYPE": "Haswell",
}
RENDERER = {"MUJOCO_GL": "osmesa"}  # software rendering; set egl, glfw or disable yourself to override
_READ_BY = {"MUJOCO_GL": "mujoco", "NPY_DISABLE_CPU_FEATURES": "numpy", "OPENBLAS_CORETYPE": "numpy"}


def pin() -> None:
    """Set each unset variable of :data:`RENDERER` and :data:`PINNED`; warn if its reader came first."""
    unset = {name: value for name, value in {**RENDERER, **PINNED}.items() if name not in os.environ}
    os.environ.update(unset)
    readers = {name: _READ_BY.get(name, "torch") for name in unset}
    if late := [f"{name} ({reader})" for name, reader in readers.items() if reader in sys.modules]:
        warnings.warn(
            f"lasa.runtime.pin() came after the import of what reads {', '.join(late)}: not in effect in "
            "this process (results may differ in the last bits from another CPU's, rendering may need a "
            "display). Call it first, before numpy, torch or mujoco is imported.",
            RuntimeWarning,
            stacklevel=2,
        )


def record() -> dict[str, object]:
    """What the kernels run with: :data:`PINNED` as set, whether all hold, and torch's CPU capability."""
    import torch  # noqa: PLC0415 (reading the capability needs torch; pinning must not import it)

    env = {name: os.environ.get(name) for name in PINNED}
    return {
        "environment": env,
        "pinned": all(env[name] == value for name, value in PINNED.items()),
        "torch_cpu_capability": torch.backends.cpu.get_cpu_capability(),
    }


def main(argv: list[str] | None = None) -> int:
    """``python -m lasa.runtime [--out FILE]``: pin, then write :func:`record` as JSON."""
    parser = argparse.ArgumentParser(description="Record the numerical kernels a run computes with.")
    parser.add_argument("--out", help="write the JSON to this file (else print it)")
    args = parser.parse_args(argv)
    pin()
    text = json.dumps(record(), indent=2, sort_keys=True) + "\n"
    if args.out is None:
        sys.stdout.write(text)
    else:
        from lasa.base.io import write_text  # noqa: PLC0415

        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
