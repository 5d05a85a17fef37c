"""A 3D packing whose true critical time step is measured, not estimated (issue 17 item 3, 3D).

Face-centred cubic: hexagonal (111) layers stacked ABC between two planes, periodic along x and y,
every contact pre-compressed to the same overlap δ = ``overlap`` × R (the planes to the overlap whose
Hertz force equals the vertical pull of the three contacts a boundary layer lacks), so every sphere is
in equilibrium by symmetry.  Tiny random velocities and spins excite every mode; :func:`is_unstable`
says whether the kinetic energy grew, :func:`measured_critical_dt` bisects on Δt.  Nothing here reads
demflow's estimate.
"""
from __future__ import annotations

import math
import warnings

import numpy as np

from critical_dt import GROWTH, bisect_stable, grows  # noqa: F401
from demflow import Box, HertzMindlinLaw, Material, Outputs3D, Plane, Scene3D, Spheres, build

R = 0.01
E, NU, RHO = 7e10, 0.2, 2650.0
PERTURBATION = 1e-6  # [length/time]: displacements far below the pre-compression


def fcc(nx: int = 6, ny: int = 6, layers: int = 3, overlap: float = 0.01, friction: float = 0.5,
        restitution: float = 1.0, dt: float | None = None, seed: int = 3, **kw) -> Scene3D:
    d = 2.0 * R - overlap * R  # centre distance of touching spheres
    h = d * math.sqrt(2.0 / 3.0)  # layer spacing
    lx, ly = nx * d, ny * d * math.sqrt(3.0) / 2.0
    shifts = [(0.0, 0.0), (0.5 * d, d / (2.0 * math.sqrt(3.0))), (d, d / math.sqrt(3.0))]
    pos = []
    for k in range(layers):
        sx, sy = shifts[k % 3]
        for j in range(ny):
            for i in range(nx):
                x = (i + 0.5 * (j % 2)) * d + sx
                y = j * d * math.sqrt(3.0) / 2.0 + sy
                pos.append((x % lx, y % ly, k * h))
    pos = np.array(pos)
    # the plane overlap: 4/3 E* √R δp^1.5 = 3 (h/d) 4/3 E* √(R/2) δ^1.5  →  δp = δ (3 h/d /√2)^(2/3)
    dp = overlap * R * (3.0 * (h / d) / math.sqrt(2.0)) ** (2.0 / 3.0)
    rng = np.random.default_rng(seed)
    n = len(pos)
    law = HertzMindlinLaw(friction=friction, restitution=restitution)
    return Scene3D(
        name="fcc", spheres=Spheres(x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], radius=np.full(n, R), material="rock",
                                    velocity=PERTURBATION * rng.normal(size=(n, 3)),
                                    angular_velocity=PERTURBATION / R * rng.normal(size=(n, 3))),
        materials={"rock": Material(density=RHO, young=E, poisson=NU)},
        laws={("rock", "rock"): law},
        planes=[Plane("floor", (0.0, 0.0, -(R - dp)), (0.0, 0.0, 1.0), "rock"),
                Plane("lid", (0.0, 0.0, (layers - 1) * h + (R - dp)), (0.0, 0.0, -1.0), "rock")],
        box=Box(periodic_x=(0.0, lx), periodic_y=(0.0, ly)), dt=dt, outputs=Outputs3D(every=0),
        max_overlap=overlap, **kw)


def kinetic(sim) -> float:
    s = sim.spheres
    return float(0.5 * np.sum(s.mass * np.sum(s.vel ** 2, 1)) + 0.5 * np.sum(0.4 * s.mass * s.r ** 2
                                                                           * np.sum(s.angvel ** 2, 1)))


def is_unstable(dt: float, n_steps: int = 3000, **kw) -> bool:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = build(fcc(dt=dt, allow_supercritical=True, **kw))
    return grows(sim, kinetic, n_steps)


def measured_critical_dt(lo: float, hi: float, rel: float = 5e-3, **kw) -> float:
    return bisect_stable(lambda dt: is_unstable(dt, **kw), lo, hi, rel)
