"""Scenes for the 3D law variants the golden bed (golden3d_scenes.py) does not run: Mindlin-Deresiewicz (8-column
history, incremental spring; and with the Coulomb cap on the elastic force), the total shear spring (LIGGGHTS's
mode) and the linear law in 3D.  Each is benchmarks/packing3d.py's dense FCC packing of 500 spheres with that law,
run STEPS steps.  tests/golden/laws3d.npz was written by the code of 91c46a5 (before the 3D laws returned their
history row and the pair passes took unsigned indices, session 34) with /tmp's copy of that commit's package:
the expected bits come from the code before the change, not from the code under test."""
from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

STEPS = 400


def scene(name: str):
    import demflow as df
    from packing3d import dense_fcc

    sc = dense_fcc(500)
    if name == "linear":
        return dataclasses.replace(sc, laws={k: df.LinearLaw(kn=1e6, ks=5e5, friction=0.5) for k in sc.laws})
    kw = {"md": dict(tangential="mindlin-deresiewicz", shear_spring="incremental"),
          "md-elastic-cap": dict(tangential="mindlin-deresiewicz", friction_cap="elastic"),
          "total": dict(shear_spring="total")}[name]
    return dataclasses.replace(sc, laws={k: dataclasses.replace(law, **kw) for k, law in sc.laws.items()})


VARIANTS = ("md", "md-elastic-cap", "total", "linear")


def state(sim) -> dict:
    sp, p = sim.spheres, sim.pairs
    return {"pos": sp.pos, "vel": sp.vel, "angvel": sp.angvel, "hist": p.hist, "fn": p.fn, "ft": p.ft, "ovl": p.ovl}
