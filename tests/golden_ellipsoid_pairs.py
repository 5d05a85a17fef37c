"""Unit golden of the Lin & Ng pair geometry (:func:`demflow.shapes.ellipsoid.ellipsoid_pair`): every output, to the
bit, on 3000 configurations — cold and warm starts, apart, touching and deep pairs, elongated, flat and equal axes,
coincident centres (the eigen/bisection fallback).

Written by ``python tests/golden_ellipsoid_pairs.py`` at the commit named in the file (2026-11-26, before the pair
geometry was computed for several pairs at once, lane by lane): a refactoring guard, as tests/golden3d_scenes.py.
It was written where OpenBLAS runs its Haswell kernels (an AMD EPYC): the fallback's eigen-decomposition goes
through LAPACK, whose CPU-specific kernels round differently (3 of the 89 fallback solves, and one warm solve
started from them, are other bits under the SkylakeX kernels of an AVX-512 host), so the test compares in a process
with those kernels pinned (tests/blas_kernels.py).  The configurations take no BLAS (:func:`_norm`): the same bits
as the file's under the Haswell kernels, and on every CPU.
"""
from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np

from demflow.shapes.ellipsoid import ellipsoid_pair, quat_rotation

GOLDEN = Path(__file__).parent / "golden" / "ellipsoid_pairs.npz"
N = 3000


def _norm(v) -> float:
    """|v| summed in order in Python: np.linalg.norm goes through the BLAS, whose CPU-specific kernels round
    differently (the configurations were other bits on an AVX-512 host)."""
    return math.sqrt(sum(float(x) * float(x) for x in v))


def configurations(n: int = N, seed: int = 2026):
    """(ci, Ri, ai, cj, Rj, aj, lam_i, lam_j, warm) arrays of n configurations (module docstring)."""
    rng = np.random.default_rng(seed)
    ai = np.empty((n, 3))
    aj = np.empty((n, 3))
    Ri = np.empty((n, 9))
    Rj = np.empty((n, 9))
    ci = np.zeros((n, 3))
    cj = np.empty((n, 3))
    kind = rng.integers(0, 4, n)  # 0: the seed's particle, 1: random axes, 2: equal axes, 3: flat
    for k in range(n):
        for a in (ai, aj):
            if kind[k] == 0:
                a[k] = np.array([0.371, 0.260, 0.182]) * rng.uniform(0.9, 1.1)
            elif kind[k] == 1:
                a[k] = rng.uniform(0.1, 1.0, 3)
            elif kind[k] == 2:
                a[k] = rng.uniform(0.2, 0.6)
            else:
                a[k] = np.array([1.0, 0.8, 0.05]) * rng.uniform(0.3, 1.0)
        for R in (Ri, Rj):
            q = rng.normal(size=4)
            quat_rotation(q / _norm(q), R[k])
        d = rng.normal(size=3)
        d /= _norm(d)
        reach = ai[k].max() + aj[k].max()
        cj[k] = d * reach * rng.uniform(0.05, 1.1)  # from deep inside to apart
    cj[:5] = 0.0  # coincident centres
    ci += rng.normal(size=(n, 3))  # not at the origin
    cj += ci
    return ci, Ri, ai, cj, Rj, aj


def outputs(ci, Ri, ai, cj, Rj, aj, rng_seed: int = 7) -> dict:
    """Cold solves of every configuration, then warm solves after a small move (warm λ from the cold solve)."""
    n = ci.shape[0]
    work = np.zeros((6, 3))
    M = np.zeros((3, 3))
    H = np.zeros((3, 3))
    cold = np.zeros((n, 11))
    warm = np.zeros((n, 11))
    moved = cj + np.random.default_rng(rng_seed).normal(0.0, 1e-4, cj.shape) * ai.max(axis=1)[:, None]
    for k in range(n):
        cold[k] = ellipsoid_pair(ci[k], Ri[k], ai[k], cj[k], Rj[k], aj[k], 0.0, 0.0, False, work, M, H)
        warm[k] = ellipsoid_pair(ci[k], Ri[k], ai[k], moved[k], Rj[k], aj[k], cold[k, 8], cold[k, 9], True, work, M, H)
    return {"cold": cold, "warm": warm, "moved": moved}


def compare() -> str:
    """"same" when every output equals the stored file's (NaN equal to NaN), else what differs."""
    got = outputs(*configurations())
    with np.load(GOLDEN, allow_pickle=False) as want:
        for key in ("cold", "warm", "moved"):
            same = (got[key] == want[key]) | (np.isnan(got[key]) & np.isnan(want[key]))
            if not same.all():
                return f"{key}: {int((~same).sum())} outputs differ, first at {np.argwhere(~same)[0].tolist()}"
    return "same"


if __name__ == "__main__":
    commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    conf = configurations()
    out = outputs(*conf)
    np.savez(GOLDEN, commit=commit, **out)
    c = out["cold"]
    print("written", GOLDEN, "at", commit, "| overlapping", int((c[:, 0] > 0).sum()), "of", len(c),
          "| fallbacks (cold, warm)", int((c[:, 10] > 60).sum()), int((out["warm"][:, 10] > 60).sum()),
          "| factorisations per warm pair", float(np.mean(out["warm"][:, 10])))
