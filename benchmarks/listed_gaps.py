"""How far apart the listed pairs of the speed benchmarks' packings are: what a pass over only the pairs that can
touch (a sub-list of the pairs within a fraction of the skin, taken while the displacements allow) could leave out.

    python benchmarks/listed_gaps.py [--n2 10000] [--n3 10000] [--steps 200]

Builds bench_engines.py's 2D disc packing and packing3d.py's dense FCC sphere packing, runs ``--steps`` steps (one
thread), and counts the listed particle pairs, those touching and those whose gap is within 1/4, 1/2, 3/4 and 1
of the skin.  Pairs listed beyond a quarter of the skin are the most such a sub-list could leave out.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import demflow as df  # noqa: E402
from demflow.jit import set_threads  # noqa: E402

FRACTIONS = (0.25, 0.5, 0.75, 1.0)


def _row(name, gap, skin):
    m = gap.size
    cells = [f"{int((gap <= q * skin).sum()):,} ({(gap <= q * skin).mean():.1%})" for q in FRACTIONS]
    return f"| {name} | {m:,} | {int((gap < 0).sum()):,} ({(gap < 0).mean():.1%}) | " + " | ".join(cells) + " |"


def gaps_2d(n, steps):
    from bench_engines import engine_scene
    scene, _ = engine_scene(n, threads=1)
    sim = df.build(scene)
    sim.run(steps, threads=1)
    p = sim.pairs
    disc = p.other < sim.n
    f, o = p.finder[disc], p.other[disc]
    sx = p.sx[disc] if p.sx.size else 0.0
    sy = p.sy[disc] if p.sy.size else 0.0
    gap = np.hypot(sim.x[o] + sx - sim.x[f], sim.y[o] + sy - sim.y[f]) - (sim.r[f] + sim.r[o])
    return gap, sim.skin


def gaps_3d(n, steps):
    from packing3d import dense_fcc
    sim = df.build(dense_fcc(n))
    sim.run(steps)
    p = sim.pairs
    sph = p.j < sim.n
    i, j = p.i[sph], p.j[sph]
    pos = sim.spheres.pos
    d = pos[j] + p.shift[sph] - pos[i]
    gap = np.sqrt((d * d).sum(1)) - (sim.spheres.r[i] + sim.spheres.r[j])
    return gap, sim.skin


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n2", type=int, default=10000)
    ap.add_argument("--n3", type=int, default=10000)
    ap.add_argument("--steps", type=int, default=200)
    a = ap.parse_args(argv)
    set_threads(1)
    print("| packing | listed pairs | touching | gap <= skin/4 | <= skin/2 | <= 3 skin/4 | <= skin |")
    print("|---|---|---|---|---|---|---|")
    g, s = gaps_2d(a.n2, a.steps)
    print(_row(f"2D discs, {a.n2:,} (bench_engines.py), after {a.steps} steps", g, s))
    g, s = gaps_3d(a.n3, a.steps)
    print(_row(f"3D FCC spheres, {a.n3:,} (packing3d.py), after {a.steps} steps", g, s))


if __name__ == "__main__":
    main()
