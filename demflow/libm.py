"""Elementwise float64 math that rounds the same on every x86-64 CPU: the C library's functions, element by element.

numpy compiles several of its float64 ufuncs more than once and picks a version for the CPU it runs on
(``numpy._core._multiarray_umath.__cpu_targets_info__`` lists them).  The versions round differently in the last
bit: on an AVX-512 CPU ``power``, ``arcsin``, ``arccosh``, ``arctan2``, ``cbrt`` ... run Intel's SVML and ``exp``,
``log``, ``sin``, ``cos``, ``tanh`` numpy's own AVX-512 code; on an AVX2-only CPU ``tanh`` runs numpy's AVX2 code
and the rest glibc's libm.  So ``r ** 3`` of an array gave a sphere's mass one bit apart on the two kinds of host
(found on 2026-11-26: the 3D golden bed and every stored 3D conformance deck, written on AVX-512 hosts, differed on
an AVX2-only one).  What goes into a simulation's state therefore comes from here, never from those ufuncs.

Each function here calls Python's :mod:`math` (glibc's libm, whose x86-64 build selects its FMA variant on every
CPU with AVX2 and FMA) once per element.  On an AVX2-only CPU numpy's ``power``, ``arcsin``, ``sin``, ``cos``,
``exp``, ``log`` and ``arccosh`` already are libm (measured: the same bits on 2e5 random arguments each), so these
functions give exactly what numpy gave there.  ``tests/test_libm.py`` runs scenes with numpy's CPU-specific code
switched off (``NPY_DISABLE_CPU_FEATURES``) and asks for the same bits.

The cost is a Python call per element (about 0.1 µs): for per-particle set-up work, not for kernels (Numba's
compiled ``math`` calls are libm already).
"""
from __future__ import annotations

import math

import numpy as np


def _map(f, *args) -> np.ndarray:
    """``f`` (a scalar function of libm) applied to each element of the broadcast ``args``, as float64."""
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in args))
    shape = arrays[0].shape
    flat = [a.ravel().tolist() for a in arrays]
    return np.fromiter(map(f, *flat), dtype=np.float64, count=math.prod(shape)).reshape(shape)


def cube(x) -> np.ndarray:
    """x³ = libm ``pow(x, 3)`` per element (not numpy's ``x ** 3``, which is SVML's on AVX-512)."""
    return _map(lambda v: math.pow(v, 3.0), x)


def power(x, y) -> np.ndarray:
    """libm ``pow(x, y)`` per element."""
    return _map(math.pow, x, y)


def sin(x) -> np.ndarray:
    """libm ``sin`` per element."""
    return _map(math.sin, x)


def cos(x) -> np.ndarray:
    """libm ``cos`` per element."""
    return _map(math.cos, x)


def log(x) -> np.ndarray:
    """libm ``log`` per element."""
    return _map(math.log, x)


def arcsin(x) -> np.ndarray:
    """libm ``asin`` per element."""
    return _map(math.asin, x)


def arccosh(x) -> np.ndarray:
    """libm ``acosh`` per element."""
    return _map(math.acosh, x)


def tanh(x) -> np.ndarray:
    """libm ``tanh`` per element."""
    return _map(math.tanh, x)
