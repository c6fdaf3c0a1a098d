"""The numerical kernels pinned to one instruction set, so that any x86 CPU computes the same bytes.

torch, oneDNN, MKL, numpy and OpenBLAS each pick their kernels at run time by what the CPU offers:
on a CPU with AVX-512 a matrix product or an ``exp`` runs another code path than on one without,
and sums its terms in another order. The results differ in the last bits; training amplifies that
into other decoder weights, and chaotic episodes into other finishes (measured: an AMD run against
Intel figures moved 37 of 47 files and 3 verdicts). Pinned to AVX2, which every x86-64 CPU of the
last decade has, each library runs the same code path everywhere.

The settings are environment variables, read once when each library loads or first dispatches, so
:func:`pin_kernels` must run before torch and numpy are imported: ``lasa`` calls it on import, as it
sets ``MUJOCO_GL``, and ``make`` exports the same values. A variable already set is kept (set
``ATEN_CPU_CAPABILITY=avx512`` yourself for speed when sameness across CPUs does not matter);
:func:`kernel_settings` reports what is in effect; ``make figures`` writes it to
``figures/kernels.json`` (:mod:`lasa.pipeline.kernels`), which ``make verify`` prints for both runs.
"""

from __future__ import annotations

import os
import sys
import warnings

__all__ = ["PINNED", "pin_kernels", "kernel_settings"]

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


def pin_kernels() -> dict[str, str]:
    """Set each of :data:`PINNED` in ``os.environ`` unless it is already set.

    Returns:
        The values in effect afterwards, by variable.
    """
    unset = [name for name in PINNED if name not in os.environ]
    for name in unset:
        os.environ[name] = PINNED[name]
    if "NPY_DISABLE_CPU_FEATURES" in unset and "numpy" in sys.modules:
        warnings.warn(
            "numpy was imported before lasa, so its loops run on this CPU's own SIMD in this process: "
            "results may differ in the last bits from another CPU's. Import lasa first.",
            stacklevel=2,
        )
    return {name: os.environ[name] for name in PINNED}


def kernel_settings() -> dict[str, object]:
    """What the numerical kernels run with: the variables of :data:`PINNED` as set, whether each
    holds its pinned value, and torch's CPU capability as torch reports it (imported here)."""
    import torch  # noqa: PLC0415 (reading the capability needs torch; pinning must not import it)

    env = {name: os.environ.get(name) for name in PINNED}
    return {
        "environment": env,
        "pinned": all(env[name] == value for name, value in PINNED.items()),
        "torch_cpu_capability": torch.backends.cpu.get_cpu_capability(),
    }
