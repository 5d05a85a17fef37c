"""The one set of JIT flags every demflow kernel is compiled with.

All kernels are compiled by :func:`njit` (serial) or :func:`njit_parallel`
(``prange`` loops).  ``cache=True`` keeps compiled code between processes;
``fastmath`` stays off so results are bit-reproducible across runs (determinism:
same scene, same seed, same results).
"""
from __future__ import annotations

import os

import numba

JIT_FLAGS = dict(cache=True, nogil=True, fastmath=False, error_model="numpy")

njit = numba.njit(**JIT_FLAGS)


def njit_parallel(func):
    """Compile ``func`` with ``parallel=True`` (its ``prange`` loops run on threads)."""
    return numba.njit(parallel=True, **JIT_FLAGS)(func)


def set_threads(n: int | None) -> int:
    """Set the number of threads parallel kernels use; ``None`` keeps the default.

    Returns the number now in force.  The default is ``DEMFLOW_THREADS`` or all cores.
    """
    if n is None:
        env = os.environ.get("DEMFLOW_THREADS")
        if env:
            n = int(env)
    if n is not None:
        if n < 1 or n > numba.config.NUMBA_NUM_THREADS:
            raise ValueError(
                f"threads={n} is outside 1..{numba.config.NUMBA_NUM_THREADS}; "
                "give a number of threads this machine has"
            )
        numba.set_num_threads(n)
    return numba.get_num_threads()
