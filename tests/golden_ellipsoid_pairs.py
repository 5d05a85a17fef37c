"""Unit golden of the Lin & Ng pair geometry (:func:`demflow.shapes.ellipsoid.ellipsoid_pair`): every output, to the
bit, on 3000 configurations — cold and warm starts, apart, touching and deep pairs, elongated, flat and equal axes,
coincident centres (the eigen/bisection fallback).

Written by ``python tests/golden_ellipsoid_pairs.py`` at the commit named in the file (2026-11-26, before the pair
geometry was computed for several pairs at once, lane by lane): a refactoring guard, as tests/golden3d_scenes.py.
"""
from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np

from demflow.shapes.ellipsoid import ellipsoid_pair, quat_rotation

GOLDEN = Path(__file__).parent / "golden" / "ellipsoid_pairs.npz"
N = 3000


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
            quat_rotation(q / np.linalg.norm(q), R[k])
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
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


if __name__ == "__main__":
    commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    conf = configurations()
    out = outputs(*conf)
    np.savez(GOLDEN, commit=commit, **out)
    c = out["cold"]
    print("written", GOLDEN, "at", commit, "| overlapping", int((c[:, 0] > 0).sum()), "of", len(c),
          "| fallbacks (cold, warm)", int((c[:, 10] > 60).sum()), int((out["warm"][:, 10] > 60).sum()),
          "| factorisations per warm pair", float(np.mean(out["warm"][:, 10])))
