"""The one set of JIT flags every demflow kernel is compiled with.

All kernels are compiled by :func:`njit` (serial), :func:`njit_parallel`
(``prange`` loops) or :func:`njit_inline` (helpers inlined into their caller).  ``cache=True`` keeps compiled code between processes;
``fastmath`` stays off so results are bit-reproducible across runs (determinism:
same scene, same seed, same results).
"""
from __future__ import annotations

import os
import warnings

import numba

# Numba vectorises loops of math calls through Intel's SVML when it finds the library (intel-cmplr-lib-rt), and SVML
# rounds differently from libm and per CPU (demflow.libm); demflow/__init__.py asks it off before Numba is imported.
if getattr(numba.config, "USING_SVML", False):
    warnings.warn("Numba was imported before demflow with Intel's SVML in use: results may then differ between CPUs "
                  "in the last bits; set NUMBA_DISABLE_INTEL_SVML=1 before importing numba", RuntimeWarning,
                  stacklevel=2)

JIT_FLAGS = dict(cache=True, nogil=True, fastmath=False, error_model="numpy")

njit = numba.njit(**JIT_FLAGS)

# Per-pair and per-disc helpers that take arrays are inlined at the Numba IR level: a compiled call
# with array arguments updates reference counts (atomic, serialising threads) on every call.
njit_inline = numba.njit(inline="always", **JIT_FLAGS)


# Parallel kernels and namedtuples of arrays (demflow.state): Numba 0.68 silently drops writes made
# as ``struct.field[i] = v`` inside a prange body, and in the pair kernel even writes through
# fields read into local names before the loop were lost (measured; the golden tests catch it).
# So the arrays a prange loop writes are passed to it as plain arguments; structures are read only.
def njit_parallel(func):
    """Compile ``func`` with ``parallel=True`` (its ``prange`` loops run on threads)."""
    return numba.njit(parallel=True, **JIT_FLAGS)(func)


def check_thread_count(name: str, n) -> int:
    """``n`` as a thread count: a whole number >= 1 (ValueError naming ``name`` otherwise)."""
    import numbers

    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
        raise ValueError(f"{name}={n!r} is not a number of threads; give a whole number >= 1 (at most "
                         f"{numba.config.NUMBA_NUM_THREADS} here), or None for the default")
    return int(n)


def set_threads(n: int | None) -> int:
    """Set the number of threads parallel kernels use; ``None`` keeps the default.

    Returns the number now in force.  The default is ``DEMFLOW_THREADS`` or all cores.
    """
    if n is None:
        env = os.environ.get("DEMFLOW_THREADS")
        if env:
            try:
                n = int(env)
            except ValueError:
                raise ValueError(f"DEMFLOW_THREADS={env!r} is not a whole number; set it to a number of threads "
                                 f"in 1..{numba.config.NUMBA_NUM_THREADS}, or unset it") from None
    if n is not None:
        check_thread_count("threads", n)
        if n > numba.config.NUMBA_NUM_THREADS:
            raise ValueError(
                f"threads={n} is outside 1..{numba.config.NUMBA_NUM_THREADS}; "
                "give a number of threads this machine has"
            )
        numba.set_num_threads(n)
    return numba.get_num_threads()
