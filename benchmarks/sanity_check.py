"""Correctness check for kernel optimisations.

    python benchmarks/sanity_check.py save  FILE   # store the reference result
    python benchmarks/sanity_check.py check FILE   # compare against it (bit-for-bit)

SANITY_SHUFFLE=1 numbers the discs randomly (exercises the spatial renumbering).

Runs 200 polydisperse frictional discs falling in a box under gravity for 3000 steps
on 1 and 2 threads, and checks pairs_cell_search against pairs_brute_force on random
polydisperse sets (radius ratios up to 100:1).
"""
from __future__ import annotations

import os
import sys

import numpy as np

from demflow import Discs, GlobalDamping, LinearLaw, Material, Outputs, Scene, Wall, build
from demflow.contacts.neighbours import pairs_brute_force, pairs_cell_search
from demflow.jit import set_threads


def falling_scene(n=200, seed=1):
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.8, 1.2, n)
    cols = 20
    x = 2.9 * (np.arange(n) % cols) + 2.0 + rng.uniform(-0.2, 0.2, n)
    y = 2.9 * (np.arange(n) // cols) + 2.0 + rng.uniform(-0.2, 0.2, n)
    if os.environ.get("SANITY_SHUFFLE"):  # random numbering of the discs
        p = rng.permutation(n)
        x, y, r = x[p], y[p], r[p]
    W, H = 2.9 * cols + 2.0, 2.9 * (n // cols) + 10.0
    walls = [Wall("floor", (0, 0), (1, 0), 0, W, "wall"), Wall("left", (0, 0), (0, 1), 0, H, "wall"),
             Wall("right", (W, 0), (0, 1), 0, H, "wall"), Wall("top", (0, H), (1, 0), 0, W, "wall")]
    law = LinearLaw(kn=1e5, ks=1e5, cn=5.0, cs=2.0, friction=0.5)
    return Scene(name="sanity", discs=Discs(x, y, r, "grain"),
                 materials={"grain": Material(1.0), "wall": Material(1.0)},
                 laws={("grain", "grain"): law, ("grain", "wall"): law}, walls=walls,
                 damping=GlobalDamping(alpha=0.05), gravity=(0.0, -9.81), dt_fraction=0.1,
                 outputs=Outputs(every=100, snapshots=(1500, 3000), track_pairs=((0, 1), (5, "wall:floor"))))


def run_once(threads):
    set_threads(threads)
    sim = build(falling_scene()).run(3000)
    res = sim.results()
    c = sim.contact_table_arrays()
    out = dict(x=sim.x, y=sim.y, vx=sim.vx, vy=sim.vy, om=sim.om, th=sim.th, finder=sim.finder,
               other=sim.other, hist=sim.hist, wall=res.wall_forces[["fx", "fy", "moment"]].to_numpy(),
               energy=res.energy[["kinetic", "elastic"]].to_numpy(),
               tracked=res.tracked[["fn", "fs"]].to_numpy(),
               parts=res.particles[["x", "y", "vx", "omega"]].to_numpy(),
               cons=res.contacts[["i", "j", "fn", "fs", "px"]].to_numpy(),
               ct_fn=c["fn"], ct_i=c["finder"], rebuilds=np.array([sim.rebuilds]),
               Fx=sim.discs.Fx, Fy=sim.discs.Fy, M=sim.discs.M)
    return out


def neighbour_check():
    rng = np.random.default_rng(7)
    bad = 0
    trials = 100
    for trial in range(trials):
        n = int(rng.integers(1, 600))
        kind = trial % 5
        if kind == 0:
            r = rng.uniform(0.8, 1.2, n)
        elif kind == 1:
            r = np.exp(rng.uniform(0, np.log(100.0), n))  # up to 100:1
        elif kind == 2:
            r = np.where(rng.random(n) < 0.05, 100.0, 1.0)  # few huge discs among small
        elif kind == 3:
            r = np.where(rng.random(n) < 0.02, 100.0, 1.0)  # 100:1, dense small ones
        else:
            r = np.ones(n)  # exact square lattice: distances exactly 2, cell-boundary ties
        L = float(np.sqrt(np.sum(np.pi * r ** 2)) * rng.uniform(0.8, 3.0))
        x, y = rng.uniform(0, L, n), rng.uniform(0, L, n)
        if kind == 4:
            c = int(np.ceil(np.sqrt(n)))
            x, y = 2.0 * (np.arange(n) % c), 2.0 * (np.arange(n) // c)
            L = 2.0 * c
        skin = float(rng.choice([0.0, rng.uniform(0.0, 0.5), 0.2])) * float(np.median(r))
        ax, ay = np.array([0.0, 0.0]), np.array([0.0, 0.0])
        bx, by = np.array([L, 0.0]), np.array([0.0, L])
        for threads in (1, 2):
            set_threads(threads)
            f1, o1 = pairs_cell_search(x, y, r, skin, ax, ay, bx, by)
            f2, o2 = pairs_brute_force(x, y, r, skin, ax, ay, bx, by)
            if not (np.array_equal(f1, f2) and np.array_equal(o1, o2)):
                bad += 1
                print("MISMATCH trial", trial, "n", n, "threads", threads)
    print("neighbour check:", "OK" if bad == 0 else f"{bad} mismatches", f"({trials} sets x 2 thread counts)")
    return bad == 0


def main():
    mode, path = sys.argv[1], sys.argv[2]
    a = run_once(1)
    b = run_once(2)
    same12 = all(np.array_equal(a[k], b[k]) for k in a)
    print("threads 1 vs 2 identical:", same12, "rebuilds", a["rebuilds"][0])
    if mode == "save":
        np.savez(path, **a)
        print("saved", path)
        ok = same12
    else:
        ref = np.load(path)
        ok = same12
        for k in a:
            eq = np.array_equal(ref[k], a[k])
            if not eq:
                ok = False
                d = np.max(np.abs(ref[k].astype(float) - a[k].astype(float))) if ref[k].shape == a[k].shape else "shape"
                print(f"  {k}: DIFFERS from reference (max abs diff {d})")
        print("bit-for-bit vs reference:", ok)
    ok = neighbour_check() and ok
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
