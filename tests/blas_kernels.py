"""OpenBLAS's CPU-specific kernels in the tests: which this CPU can run, and running code under a chosen set.

OpenBLAS picks its kernels for the CPU it finds (SkylakeX on an Intel AVX-512 host, Haswell on an AMD EPYC),
and they round differently in the last bits; ``OPENBLAS_CORETYPE`` pins them for a fresh process."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

NEEDS = {"Haswell": (" avx2", " fma"), "SkylakeX": (" avx512f",)}  # /proc/cpuinfo flags each kernel set uses


def can_run(core: str) -> bool:
    """Whether this CPU runs OpenBLAS's ``core`` kernels."""
    info = Path("/proc/cpuinfo")
    flags = info.read_text() if info.exists() else ""
    return all(f in flags for f in NEEDS[core])


def run_under(core: str, args: list[str], **kw) -> subprocess.CompletedProcess:
    """``python args`` in a fresh process with OpenBLAS's ``core`` kernels pinned."""
    return subprocess.run([sys.executable, *args], capture_output=True, text=True,
                          env={**os.environ, "OPENBLAS_CORETYPE": core}, **kw)


def assert_same_output_under_both_kernel_sets(code: str) -> None:
    """``python -c code`` prints the same under the Haswell and the SkylakeX kernels (skipped where the CPU
    cannot run both)."""
    import pytest

    if not (can_run("Haswell") and can_run("SkylakeX")):
        pytest.skip("needs a CPU that runs both OpenBLAS's Haswell and SkylakeX kernels (AVX2 and AVX-512)")
    got = {}
    for core in ("Haswell", "SkylakeX"):
        done = run_under(core, ["-c", code])
        assert done.returncode == 0, done.stderr[-3000:]
        got[core] = done.stdout
    assert got["Haswell"] == got["SkylakeX"], got
