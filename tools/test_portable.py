"""Run every notebook under nbval as other CPUs would: ``make test-portable``.

A compared notebook output must come out the same on a student's laptop, on CI and on the machine
that stored it. Different CPUs run different kernels (OpenBLAS picks its kernels by CPU model, numpy
dispatches SIMD loops by CPU feature, torch picks an ATen capability, numba compiles for the host),
and each rounds sums differently. This script re-runs the notebooks on *this* machine with each of
those choices forced to another one, so an output that rests on rounding noise fails here rather
than on somebody else's machine. Each variant is a full ``pytest notebooks`` run (about 5 minutes
on 2 cores); the script exits 1 if any variant fails and prints a one-line summary per variant.

    python tools/test_portable.py                      # every variant
    python tools/test_portable.py sandybridge-1thread  # one of them
    python tools/test_portable.py --list
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# numpy >= 2.4 names its dispatch targets by x86-64 level; naming one the CPU lacks is harmless.
_NO_AVX512 = "X86_V4 AVX512_ICL AVX512_SPR"
VARIANTS = {
    # an AVX2 machine without AVX-512 (most laptops and AMD EPYC/Zen 2-3), torch on 2 threads
    "haswell-2threads": {
        "OPENBLAS_CORETYPE": "Haswell",
        "NPY_DISABLE_CPU_FEATURES": _NO_AVX512,
        "ATEN_CPU_CAPABILITY": "avx2",
        "OMP_NUM_THREADS": "2",
    },
    # an old machine: AVX but no AVX2/FMA in OpenBLAS, baseline numpy loops, torch's default
    # (non-vectorised) kernels, numba generating generic x86-64 code, torch on 1 thread
    "sandybridge-1thread": {
        "OPENBLAS_CORETYPE": "Sandybridge",
        "NPY_DISABLE_CPU_FEATURES": "X86_V3 " + _NO_AVX512,
        "ATEN_CPU_CAPABILITY": "default",
        "NUMBA_CPU_NAME": "generic",
        "OMP_NUM_THREADS": "1",
    },
    # SSE3-only OpenBLAS kernels with everything else generic, torch on 2 threads
    "generic-2threads": {
        "OPENBLAS_CORETYPE": "Prescott",
        "NPY_DISABLE_CPU_FEATURES": "X86_V3 " + _NO_AVX512,
        "ATEN_CPU_CAPABILITY": "default",
        "NUMBA_CPU_NAME": "generic",
        "OMP_NUM_THREADS": "2",
    },
}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("variants", nargs="*", help=f"variants to run (default: all of {', '.join(VARIANTS)})")
    ap.add_argument("--list", action="store_true", help="print the variants and their environments")
    ap.add_argument("--pytest-args", default="", help="extra pytest arguments, e.g. '-k 04'")
    args = ap.parse_args(argv)
    if args.list:
        for name, env in VARIANTS.items():
            print(f"{name}: " + " ".join(f"{k}={v!r}" for k, v in env.items()))
        return 0
    unknown = [v for v in args.variants if v not in VARIANTS]
    if unknown:
        ap.error(f"unknown variant(s) {', '.join(unknown)}; expected one of {', '.join(VARIANTS)}")
    summary = []
    for name in args.variants or list(VARIANTS):
        env = {**os.environ, **VARIANTS[name]}
        cmd = [sys.executable, "-m", "pytest", "notebooks", "-n", "2", "--dist", "loadfile", "-q",
               "-p", "no:cacheprovider", *args.pytest_args.split()]
        print(f"== {name}: " + " ".join(f"{k}={v}" for k, v in VARIANTS[name].items()), flush=True)
        t0 = time.perf_counter()
        rc = subprocess.call(cmd, cwd=ROOT, env=env)
        summary.append((name, rc, time.perf_counter() - t0))
    print("\nvariant                 result   minutes")
    for name, rc, sec in summary:
        print(f"{name:<24}{'passed' if rc == 0 else 'FAILED':<9}{sec / 60:>7.1f}")
    return 0 if all(rc == 0 for _, rc, _ in summary) else 1


if __name__ == "__main__":
    sys.exit(main())
