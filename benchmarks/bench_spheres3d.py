"""demflow's 3D Hertz sphere cycle: cost per particle-step from 1e4 to 1e6 spheres, and memory per sphere.

    python benchmarks/bench_spheres3d.py [--sizes 10000 100000 1000000] [--steps S] [--rounds R]

The scene is benchmarks/packing3d.py's dense FCC packing (periodic x/y, floor, gravity, Hertz-Mindlin,
~6 listed pairs and ~3 touching contacts per sphere).  For each size: build, run a few steps (JIT
warm), then ``--rounds`` rounds of S steps on one thread; the best round's particle-steps per second
is reported with the spread.  Memory per sphere: the bytes of every state array (spheres, pairs with
their history, planes, damping) divided by N, and the process's peak RSS growth while building.
Run it on a quiet machine (no other job): the results go to benchmarks/results/spheres3d_scaling.{json,md}.
"""
from __future__ import annotations

import argparse
import json
import platform
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numba  # noqa: E402

from packing3d import dense_fcc  # noqa: E402
from demflow import build  # noqa: E402


def state_bytes(sim) -> int:
    total = 0
    for struct in (sim.spheres, sim.pairs, sim.planes, sim.damping, sim.tris):
        for v in struct:
            if isinstance(v, np.ndarray):
                total += v.nbytes
    return total


def measure(n: int, steps: int, rounds: int) -> dict:
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    sim = build(dense_fcc(n))
    sim.run(5)
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    rates = []
    for _ in range(rounds):
        t = time.perf_counter()
        sim.run(steps)
        rates.append(n * steps / (time.perf_counter() - t))
    touching = int((sim.pairs.ovl > 0).sum())
    return {"n": n, "steps": steps, "rates": rates, "best": max(rates), "spread": (max(rates) - min(rates)) / max(rates),
            "pairs_per_sphere": len(sim.pairs.i) / n, "contacts_per_sphere": touching / n,
            "state_bytes_per_sphere": state_bytes(sim) / n, "rss_growth_kib_per_sphere": (rss1 - rss0) / n,
            "rebuilds": sim.n_rebuilds}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000, 1000000])
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--tag", default="spheres3d_scaling")
    a = ap.parse_args()
    numba.set_num_threads(1)
    rows = [measure(n, a.steps, a.rounds) for n in a.sizes]
    out = Path(__file__).resolve().parent / "results"
    meta = {"date": time.strftime("%Y-%m-%d %H:%M"), "machine": platform.processor() or platform.machine(),
            "python": platform.python_version(), "numba": numba.__version__, "threads": 1}
    (out / f"{a.tag}.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    lines = [f"# 3D Hertz sphere cycle, one thread ({meta['date']})", "",
             "Dense FCC packing (benchmarks/packing3d.py), periodic x/y, floor; best of "
             f"{a.rounds} rounds of {a.steps} steps, spread = (best - worst)/best.", "",
             "| spheres | particle-steps/s | spread | ns per particle-step | pairs/sphere | contacts/sphere | "
             "state bytes/sphere | RSS growth KiB/sphere |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']} | {r['best']:.3g} | {r['spread']:.0%} | {1e9 / r['best']:.0f} | "
                     f"{r['pairs_per_sphere']:.2f} | {r['contacts_per_sphere']:.2f} | {r['state_bytes_per_sphere']:.0f} | "
                     f"{r['rss_growth_kib_per_sphere']:.2f} |")
    (out / f"{a.tag}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
