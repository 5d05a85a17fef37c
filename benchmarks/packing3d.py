"""A dense 3D Hertz sphere packing for speed benchmarks (periodic x/y, floor, gravity).

``dense_fcc(n)``: an FCC lattice of nearest-neighbour distance 2R (R = 1 mm) in a box periodic
along x and y, radii uniform in [0.998R, 1.002R] (seeded), so about half the lattice neighbours
overlap (~6 contacts per sphere: a dense, stressed, nearly static packing), resting on a floor,
glass-like Hertz-Mindlin (E = 70 GPa, ν = 0.3, μ = 0.5, e = 0.9), gravity -9.81 m/s².
"""
from __future__ import annotations

import math

import numpy as np

import demflow as df

R = 1e-3


def fcc_sites(n: int):
    """About n FCC sites with nearest-neighbour distance 2R: (positions, lx, ly)."""
    a = 2 * R * math.sqrt(2.0)  # cubic cell edge
    nx = max(2, int(round((n / 4.0 / 2.0) ** (1 / 3))))  # cells along x and y; z twice as many
    nz = max(1, int(math.ceil(n / (4.0 * nx * nx))))
    base = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    g = np.stack(np.meshgrid(np.arange(nx), np.arange(nx), np.arange(nz), indexing="ij"), -1).reshape(-1, 3)
    pts = (g[:, None, :] + base[None, :, :]).reshape(-1, 3) * a
    pts = pts[np.lexsort((pts[:, 0], pts[:, 1], pts[:, 2]))][:n]
    return pts + np.array([0.0, 0.0, 1.05 * R]), nx * a, nx * a


def dense_fcc(n: int, seed: int = 1, name: str = "bench3d") -> df.Scene3D:
    pos, lx, ly = fcc_sites(n)
    r = np.random.default_rng(seed).uniform(0.998 * R, 1.002 * R, len(pos))
    mats = {"glass": df.Material(density=2500.0, young=7e10, poisson=0.3),
            "floor": df.Material(density=0.0, young=7e10, poisson=0.3)}
    law = df.HertzMindlinLaw(friction=0.5, restitution=0.9)
    return df.Scene3D(name=name, spheres=df.Spheres(x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], radius=r, material="glass"),
                      materials=mats, laws={("glass", "glass"): law, ("glass", "floor"): law},
                      planes=[df.Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "floor")],
                      gravity=(0.0, 0.0, -9.81), box=df.Box(periodic_x=(0.0, lx), periodic_y=(0.0, ly)),
                      outputs=df.Outputs3D(every=0))
