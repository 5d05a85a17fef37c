"""Packings whose true critical time step is measured, not estimated (issue 17 items 3 and 4).

A packing is pre-compressed (every contact overlaps, ``normal="overlap"`` so that the normal
springs carry their force from the first step), in static equilibrium under its normal forces,
in a periodic box (no walls); friction keeps every shear spring elastic.  A tiny random velocity
and spin excite every mode; :func:`is_unstable` runs it and says whether the kinetic energy grew,
:func:`measured_critical_dt` bisects on Δt.  Nothing here reads demflow's estimate.
"""
from __future__ import annotations

import math

import numpy as np

from demflow import Scene, build
from demflow.cases.stability_matrix import DENSITY, KN, PERTURBATION, hexagonal, packing_scene  # noqa: F401

GROWTH = 100.0  # unstable: the kinetic energy ends above GROWTH × its start (a stable run stays within ~2×)


def random_dense(n: int = 64, seed: int = 1, rmin: float = 0.8, rmax: float = 1.2, fraction: float = 0.88,
                 tol: float = 1e-9):
    """Polydisperse discs (radii uniform in [rmin, rmax]) jammed in a square periodic box at area
    fraction ``fraction`` (above jamming, ~0.84): random centres, then the harmonic overlap energy
    Σ ½ δ² minimised by FIRE (Bitzek et al. 2006) until the largest net force is below ``tol`` × the
    mean overlap force.  Returns x, y, r, (L, L)."""
    rng = np.random.default_rng(seed)
    r = rng.uniform(rmin, rmax, n)
    L = math.sqrt(np.pi * np.sum(r * r) / fraction)
    pos = rng.uniform(0.0, L, (n, 2))
    rs = r[:, None] + r[None, :]

    def forces(p):
        d = p[:, None, :] - p[None, :, :]
        d -= L * np.round(d / L)
        dist = np.sqrt((d ** 2).sum(-1))
        np.fill_diagonal(dist, np.inf)
        ov = np.clip(rs - dist, 0.0, None)
        f = (ov / dist)[:, :, None] * d  # repulsion along the centre line, spring constant 1
        return f.sum(1), ov

    v = np.zeros_like(pos)
    dt, alpha, n_pos = 0.05, 0.1, 0
    for _ in range(200_000):
        f, ov = forces(pos)
        mean = ov[ov > 0].mean() if np.any(ov > 0) else 1.0
        if np.abs(f).max() < tol * mean:
            break
        P = (f * v).sum()
        if P > 0:
            v = (1 - alpha) * v + alpha * np.linalg.norm(v) * f / np.linalg.norm(f)
            n_pos += 1
            if n_pos > 5:
                dt, alpha = min(dt * 1.1, 0.2), alpha * 0.99
        else:
            v[:] = 0.0
            dt, alpha, n_pos = dt * 0.5, 0.1, 0
        v += f * dt
        pos = (pos + v * dt) % L
    else:
        raise RuntimeError("random_dense: FIRE did not converge")
    return pos[:, 0], pos[:, 1], r, (L, L)


def scene(packing, dt: float, **kw) -> Scene:
    """The packing with the linear law (kN = KN, kS = ``ks``), perturbed by random velocities and
    spins of scale PERTURBATION, stepped at ``dt``; build checks skipped (allow_supercritical)
    (:func:`demflow.cases.stability_matrix.packing_scene`)."""
    return packing_scene(packing, dt, allow_supercritical=True, **kw)


def kinetic(sim) -> float:
    return float(0.5 * np.sum(sim.mass * (sim.vx ** 2 + sim.vy ** 2) + sim.inertia * sim.om ** 2))


def is_unstable(packing, dt: float, n_steps: int = 3000, **kw) -> bool:
    """True when the kinetic energy grows beyond GROWTH × its start within ``n_steps`` steps (or the run
    stops with BlowUpError or non-finite values)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = build(scene(packing, dt, n_steps=n_steps, **kw))
    return grows(sim, kinetic, n_steps)


def grows(sim, kinetic_energy, n_steps: int, chunk: int = 250) -> bool:
    """True when ``kinetic_energy(sim)`` grows beyond GROWTH × its start within ``n_steps`` steps, or the run
    stops with BlowUpError or non-finite values; checked every ``chunk`` steps, so an unstable run stops as
    soon as it has grown (it soon moves particles far: slow neighbour rebuilds)."""
    from demflow import BlowUpError

    e0 = kinetic_energy(sim)
    for _ in range(0, n_steps, chunk):
        try:
            sim.run(chunk)
        except BlowUpError:
            return True
        e1 = kinetic_energy(sim)
        if not (math.isfinite(e1) and e1 < GROWTH * e0):
            return True
    return False


def measured_critical_dt(packing, lo: float, hi: float, rel: float = 2e-3, **kw) -> float:
    """The largest stable Δt, bisected between a stable ``lo`` and an unstable ``hi`` to ``rel``."""
    return bisect_stable(lambda dt: is_unstable(packing, dt, **kw), lo, hi, rel)


def bisect_stable(unstable, lo: float, hi: float, rel: float) -> float:
    """The largest Δt with ``unstable(Δt)`` false, bisected between a stable ``lo`` and an unstable ``hi``."""
    assert not unstable(lo) and unstable(hi), (lo, hi)
    while hi - lo > rel * lo:
        mid = 0.5 * (lo + hi)
        if unstable(mid):
            hi = mid
        else:
            lo = mid
    return lo
