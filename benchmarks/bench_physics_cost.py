"""What a scene pays for physics it does not declare (issue 17 item 5): the same dense 2D packing
(bench_dem's, 1e4 discs, kn = 1e6) run

- frictionless (ks = 0, friction 0): no shear history is allocated (manifest: 1 history column);
- frictional (ks = kn, friction 0.5): the shear spring and Coulomb limit (2 columns);
- dry (no fluid): the cycle's external-force path is compiled out (has_external_force False);
- dry with a zero external force array forced on: what the saturated coupling path would cost
  each step without any fluid solve (the price a dry scene does not pay).

Each: build, S warm-up steps, then S timed steps, one thread; best of --rounds with the spread, and
the manifest's state bytes.  Results: benchmarks/results/physics_cost.{json,md}.  Run it on a quiet
machine.

    python benchmarks/bench_physics_cost.py [--n 10000] [--steps 2000] [--rounds 3]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_dem import make_scene  # noqa: E402
from demflow import Outputs, build  # noqa: E402
from demflow.manifest import physics_manifest  # noqa: E402


def variants(n):
    sc = dataclasses.replace(make_scene(n), outputs=Outputs(every=0))
    law = next(iter(sc.laws.values()))
    smooth = {k: dataclasses.replace(v, ks=0.0, cs=0.0, friction=0.0) for k, v in sc.laws.items()}
    rough = {k: dataclasses.replace(v, ks=law.kn, friction=0.5) for k, v in sc.laws.items()}
    return {"frictionless": dataclasses.replace(sc, laws=smooth), "frictional": dataclasses.replace(sc, laws=rough),
            "frictional, zero external force on": dataclasses.replace(sc, laws=rough)}


def time_one(scene, steps, force_external):
    sim = build(scene)
    if force_external:
        sim.has_external_force = True
        sim.external_force = np.zeros((sim.n, 3))
    sim.run(steps, threads=1)
    t0 = time.perf_counter()
    sim.run(steps, threads=1)
    return time.perf_counter() - t0, sim


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=10000)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    times, info = {}, {}
    for _ in range(a.rounds):
        for name, sc in variants(a.n).items():
            t, sim = time_one(sc, a.steps, "external" in name)
            times.setdefault(name, []).append(t)
            m = physics_manifest(sim)
            info[name] = dict(history_columns=m["contact_history"]["columns"], state_bytes=m["state_bytes"],
                              external_force=bool(sim.has_external_force))
    rows = {k: dict(best_s=min(v), spread=(max(v) - min(v)) / min(v), rate=a.n * a.steps / min(v), **info[k])
            for k, v in times.items()}
    out = dict(n=a.n, steps=a.steps, rounds=a.rounds, rows=rows, date=time.strftime("%Y-%m-%d %H:%M"))
    res = ROOT / "benchmarks" / "results"
    (res / "physics_cost.json").write_text(json.dumps(out, indent=1))
    lines = [f"# What a scene pays for physics it does not declare ({out['date']})", "",
             f"{a.n} discs, {a.steps} timed steps after {a.steps} warm-up, one thread, best of {a.rounds} "
             "(spread = (worst − best)/best).", "",
             "| variant | history columns | state [MiB] | disc-steps/s | spread |", "|---|---|---|---|---|"]
    for k, r in rows.items():
        lines.append(f"| {k} | {r['history_columns']} | {r['state_bytes'] / 2**20:.2f} | {r['rate']:.3g} | "
                     f"{100 * r['spread']:.0f} % |")
    (res / "physics_cost.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
