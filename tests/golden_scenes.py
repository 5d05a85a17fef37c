"""Scenes of the golden (bit-identity) tests: small runs that touch every part of today's 2D cycle.

The golden files in ``tests/golden/`` were written by ``python tests/golden_scenes.py`` at the
commit named in each file's ``commit`` entry, before the core refactor of issue 12 began.  They
are refactoring guards, not validation: they say "the code computes exactly what it computed
then", to the bit, so that a restructuring that changes a single floating-point operation fails.
Regenerate them only for a change of physics that is meant to change results, and say so in
the commit.

The saturated scene goes through LAPACK (the BEM's dense LU), whose last bits depend on the kernels
OpenBLAS picks for the CPU (SkylakeX on an Intel AVX-512 host, Haswell on an AMD EPYC: measured
2026-11-25, 9 of 10 fluid-force rows differed at 1e-12 relative).  So it is recorded and checked with
the kernels pinned, ``OPENBLAS_CORETYPE=Haswell`` (any x86-64 CPU with AVX2 runs them):
``python tests/golden_scenes.py`` re-runs itself for it in a process with that setting.
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from demflow import (Discs, GlobalDamping, LinearLaw, Material, Outputs, Phase, Scene, Servo, Wall,
                     build)

GOLDEN = Path(__file__).parent / "golden"
STATE = ("x", "y", "th", "vx", "vy", "om", "finder", "other", "hist", "wall_force",
         "wpx", "wpy", "wex", "wey")
TABLES = ("wall_forces", "tracked", "energy", "particles", "contacts")


def frictional_box():
    """60 polydisperse frictional discs settling in a box; the top wall is a servo, the right wall
    rotates about its lower end, the bottom wall translates: every wall kind of the 2D cycle."""
    rng = np.random.default_rng(12)
    L = 20.0
    H = 12.0  # the servo lid starts at y = H
    xs, ys, rs = [], [], []
    while len(xs) < 60:
        r = rng.uniform(0.6, 1.0)
        x = rng.uniform(r + 0.1, L - r - 0.1)
        y = rng.uniform(r + 0.1, H - r - 0.1)
        if all((x - a) ** 2 + (y - b) ** 2 >= (r + c + 0.05) ** 2 for a, b, c in zip(xs, ys, rs)):
            xs.append(x)
            ys.append(y)
            rs.append(r)
    law = LinearLaw(kn=1e5, ks=0.8e5, cn=50.0, cs=20.0, friction=0.5)
    walls = [Wall("bottom", (0.0, 0.0), (1.0, 0.0), -2.0, L + 2.0, "wall",
                  phases=(Phase(1500), Phase(1000, velocity=(0.5, 0.0)))),
             Wall("right", (L, 0.0), (0.0, 1.0), 0.0, L + 2.0, "wall",
                  phases=(Phase(1500), Phase(1000, omega=0.02, pivot=(L, 0.0)))),
             Wall("top", (L, H), (-1.0, 0.0), -2.0, L + 2.0, "wall",
                  servo=Servo(force=2.0e3, direction=(0.0, -1.0), gain=20.0, v_max=8.0, start=300)),
             Wall("left", (0.0, L), (0.0, -1.0), 0.0, L + 2.0, "wall")]
    return Scene(name="golden-box", discs=Discs(x=xs, y=ys, radius=rs, material="grain"),
                 materials={"grain": Material(density=2.0), "wall": Material()},
                 laws={("grain", "grain"): law, ("grain", "wall"): law}, walls=walls,
                 damping=GlobalDamping(C=0.5, C_rot=0.1), gravity=(0.0, -10.0), dt_fraction=0.1,
                 n_steps=2500, outputs=Outputs(every=25, snapshots=(1500, 2500), track_pairs=((0, "wall:bottom"),)))


def nine_disc_damped():
    """C&S's damped nine-disc run as the case builds it, with rotating side walls (distortion)."""
    from demflow.cases.cs_nine_disc import NineDisc

    case = NineDisc()
    p = case.merged(dict(rest_cycles=600, distort_cycles=1200))
    return case.scenes(p)["distortion-phi30-ks1"]


def saturated_stage():
    """A short saturated run: the falling disc in its channel with the BEM fluid (16 elements)."""
    from demflow.cases.thesis_falling_disc import FallingDisc

    case = FallingDisc()
    p = case.merged(dict(t_end=0.004, elements=16))
    return case.scene(p, stride=4, name="golden-falling-disc")


SCENES = {"box": frictional_box, "nine_disc": nine_disc_damped, "saturated": saturated_stage}


def run(name: str, threads: int = 1):
    """Build and run golden scene ``name``; returns (simulation, results)."""
    sim = build(SCENES[name]())
    sim.run(threads=threads)
    return sim, sim.results()


def state_arrays(sim, res) -> dict:
    """Every array the golden files hold: the final state and every result table's columns."""
    out = {f"state/{k}": np.asarray(getattr(sim, k)) for k in STATE}
    for t in TABLES + ("fluid_forces",):
        df = getattr(res, t)
        for c in df.columns:
            v = df[c].to_numpy()
            out[f"{t}/{c}"] = v.astype(str) if v.dtype == object else v
    return out


def schema(res) -> dict:
    return {t: {c: str(res.__dict__[t][c].dtype) for c in res.__dict__[t].columns} for t in TABLES}


BLAS_SCENES = ("saturated",)  # results that go through LAPACK: run with the kernels pinned
PINNED_BLAS = {"OPENBLAS_CORETYPE": "Haswell"}


def cpu_runs_pinned_blas() -> bool:
    """Whether this CPU runs the pinned kernels (OpenBLAS's Haswell: x86-64 with AVX2 and FMA)."""
    from blas_kernels import can_run

    return can_run(PINNED_BLAS["OPENBLAS_CORETYPE"])


def run_pinned(name: str, out: Path) -> None:
    """Run golden scene ``name`` in a fresh process with :data:`PINNED_BLAS`; its arrays go to ``out``."""
    from blas_kernels import run_under

    code = (f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); import golden_scenes as gs, numpy as np; "
            f"sim, res = gs.run({name!r}); np.savez(sys.argv[1], **gs.state_arrays(sim, res))")
    done = run_under(PINNED_BLAS["OPENBLAS_CORETYPE"], ["-c", code, str(out)], timeout=900)
    if done.returncode != 0:
        raise RuntimeError(f"golden scene {name} with {PINNED_BLAS}: {done.stderr[-3000:]}")


def main():
    import os
    commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent).stdout.strip()
    GOLDEN.mkdir(exist_ok=True)
    only = sys.argv[1:] or list(SCENES)
    for name in only:
        if name in BLAS_SCENES and os.environ.get("OPENBLAS_CORETYPE") != PINNED_BLAS["OPENBLAS_CORETYPE"]:
            done = subprocess.run([sys.executable, __file__, name], env={**os.environ, **PINNED_BLAS})
            if done.returncode:
                return done.returncode
            continue
        sim, res = run(name)
        arrays = state_arrays(sim, res)
        np.savez_compressed(GOLDEN / f"{name}.npz", commit=commit, **arrays)
        if name == "box":
            (GOLDEN / "schema_v1.json").write_text(json.dumps(dict(commit=commit, tables=schema(res)), indent=1))
        print(name, len(arrays), "arrays")


if __name__ == "__main__":
    sys.exit(main())
