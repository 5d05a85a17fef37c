"""Scene of the 3D golden (bit-identity) test: a small run that touches every part of the 3D cycle.

Written by ``python tests/golden3d_scenes.py`` at the commit named in the file's ``commit`` entry,
before any optimisation of the 3D kernels.  A refactoring guard, not validation: it says "the code
computes exactly what it computed then", to the bit.  Regenerate it only for a change of physics
that is meant to change results, and say so in the commit.

bed3d.npz was re-recorded once without a change of physics (2026-11-26, at the commit that added
demflow.libm): the file of 97ffa77 held sphere masses from numpy's ``r ** 3``, which numpy computes with SVML on
the AVX-512 host that wrote it and with libm elsewhere, so the test failed on an AVX2-only host at every commit.
The code at that commit gives, on the AVX2-only host, the same bits as the code before it (36d6a24) gave there, and
no longer uses numpy's CPU-specific functions (tests/test_libm.py).
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

import demflow as df

GOLDEN = Path(__file__).parent / "golden"
STATE = ("pos", "vel", "angvel", "quat", "img")


def settling_bed():
    """100 polydisperse frictional Hertz spheres falling in a box periodic along x and y onto a floor
    and a tilted triangle-mesh ramp, a servo plate coming down from above, local damping; the
    orientations are integrated."""
    rng = np.random.default_rng(7)
    L = 0.03
    pos, rad = [], []
    while len(pos) < 100:
        r = rng.uniform(0.0015, 0.0025)
        p = np.array([rng.uniform(0, L), rng.uniform(0, L), rng.uniform(0.011, 0.020)])
        ok = True
        for q, s in zip(pos, rad):
            d = p - q
            d[:2] -= L * np.round(d[:2] / L)
            if np.linalg.norm(d) < r + s + 1e-4:
                ok = False
                break
        if ok:
            pos.append(p)
            rad.append(r)
    pos = np.array(pos)
    vel = rng.normal(0, 0.05, (100, 3)) - np.array([0.0, 0.0, 0.3])
    mats = {"grain": df.Material(density=2600.0, young=5e7, poisson=0.3),
            "steel": df.Material(density=7800.0, young=2e8, poisson=0.3)}
    law = df.HertzMindlinLaw(friction=0.4, restitution=0.7)
    return df.Scene3D(
        name="golden3d-bed",
        spheres=df.Spheres(x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], radius=rad, material="grain", velocity=vel),
        materials=mats, laws={("grain", "grain"): law, ("grain", "steel"): law},
        planes=[df.Plane("floor", (0, 0, 0), (0, 0, 1), "steel"),
                df.Plane("plate", (0, 0, 0.0226), (0, 0, -1), "steel",
                         servo=df.PlateServo(force=0.05, gain=0.5, v_max=0.5, start=100))],
        # the ramp spans the period; the golden was written before meshes were seen through periodic images, and
        # its two triangles are too wide to be (TriangleMesh.periodic_images): it keeps the contacts it was written with
        meshes=[df.TriangleMesh("ramp", [(0.0, 0.0, 0.002), (0.03, 0.0, 0.008), (0.03, 0.015, 0.008),
                                         (0.0, 0.015, 0.002)], [(0, 1, 2), (0, 2, 3)], "steel", periodic_images=False)],
        gravity=(0.0, 0.0, -9.81), local_damping=0.1, box=df.Box(periodic_x=(0.0, L), periodic_y=(0.0, L)),
        dt_fraction=0.2, outputs=df.Outputs3D(every=10, track_spheres=(0, 5), orientation=True),
        # 0.2 × the Rayleigh step is above the safe estimate of a dense packing of these spheres (a loose settling
        # bed is far from it); the golden is a refactoring guard at the step it was written with
        allow_unsafe_dt=True)


def ellipsoid_bed():
    """40 frictional Hertz ellipsoids (semi-axes 1.3 : 1 : 0.7, random orientations) falling in a box periodic
    along x and y onto a floor and a tilted triangle-mesh ramp (ellipsoid-plane, -triangle and -ellipsoid
    contacts, the aspherical body step), local damping.  Added (session 13) before the ellipsoid geometry's
    helpers were inlined, and written by the code before that change."""
    rng = np.random.default_rng(11)
    L = 0.03
    pos = []
    while len(pos) < 40:
        p = np.array([rng.uniform(0, L), rng.uniform(0, L), rng.uniform(0.0095, 0.019)])
        ok = True
        for q in pos:
            d = p - q
            d[:2] -= L * np.round(d[:2] / L)
            if np.linalg.norm(d) < 2 * 0.0026 + 1e-4:
                ok = False
                break
        if ok:
            pos.append(p)
    pos = np.array(pos)
    axes = rng.uniform(0.0017, 0.0020, 40)[:, None] * np.array([1.3, 1.0, 0.7])
    q = rng.normal(size=(40, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    vel = rng.normal(0, 0.02, (40, 3)) - np.array([0.0, 0.0, 0.4])
    mats = {"grain": df.Material(density=2600.0, young=5e9, poisson=0.3),
            "steel": df.Material(density=7800.0, young=2e10, poisson=0.3)}
    law = df.HertzMindlinLaw(friction=0.4, restitution=0.7)
    return df.Scene3D(
        name="golden3d-ellipsoids", spheres=None,
        ellipsoids=df.Ellipsoids(axes=axes, x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], material="grain", orientation=q,
                                 velocity=vel),
        materials=mats, laws={("grain", "grain"): law, ("grain", "steel"): law},
        planes=[df.Plane("floor", (0, 0, 0), (0, 0, 1), "steel")],
        # the ramp stays a particle's reach away from the periodic boundaries (written before meshes were seen
        # through periodic images: then a mesh crossing x = 0 launched an ellipsoid wrapped from its low end to its
        # high end); no particle reaches an image of it, so its bits do not depend on them
        meshes=[df.TriangleMesh("ramp", [(0.006, 0.006, 0.002), (0.024, 0.006, 0.006), (0.024, 0.024, 0.006),
                                         (0.006, 0.024, 0.002)], [(0, 1, 2), (0, 2, 3)], "steel")],
        gravity=(0.0, 0.0, -9.81), local_damping=0.1, box=df.Box(periodic_x=(0.0, L), periodic_y=(0.0, L)),
        dt=2.5e-7, outputs=df.Outputs3D(every=100, track_spheres=(0, 5), orientation=True))


SCENES = {"bed3d": settling_bed, "ell3d": ellipsoid_bed}
STEPS = {"bed3d": 2500, "ell3d": 160000}  # the ellipsoids fall for 0.02 s before their first contact


def run(name: str, steps: int | None = None):
    sim = df.build(SCENES[name]())
    sim.run(STEPS[name] if steps is None else steps)
    out = {k: getattr(sim.spheres, k) for k in STATE}
    out.update({"pair_i": sim.pairs.i, "pair_j": sim.pairs.j, "hist": sim.pairs.hist, "fn": sim.pairs.fn,
                "plane_point": sim.planes.point, "plane_force": sim.planes.force, "tri_v": sim.tris.v})
    for k, v in sim.records().items():
        out[f"records/{k}"] = v
    return sim, out


if __name__ == "__main__":
    commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    for name in (sys.argv[1:] or SCENES):
        _, out = run(name)
        np.savez(GOLDEN / f"{name}.npz", commit=commit, **out)
        print(name, {k: np.asarray(v).shape for k, v in out.items()})
