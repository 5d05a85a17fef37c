"""Dask sweep vs serial (issue 17 item 6): 8 seeds of the dry simple shear (thesis-simple-shear,
variants loose-dry and dense-dry, no ensemble table), serial in one process and on a local cluster of
2 worker processes; the tables must be identical, and the wall-time ratio is the figure.

    python benchmarks/bench_sweep.py [--rounds 2] [--workers 2]

Run it on a quiet machine (nothing else running): results in benchmarks/results/sweep.{json,md}.
Both modes start warm (the Numba cache is filled by a first serial run before timing).
"""
from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASE = "thesis-simple-shear"
SETS = {"seed": list(range(1, 9)), "variants": ["loose-dry,dense-dry"], "ensemble": [""]}


def main():
    from demflow.sweep import case_sweep

    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    case_sweep(CASE, dict(SETS, seed=[1]), scheduler="serial")  # warm the Numba cache
    times = {"serial": [], "dask": []}
    tables = {}
    for _ in range(a.rounds):
        for mode in ("serial", "dask"):
            t0 = time.perf_counter()
            tables[mode] = case_sweep(CASE, SETS, scheduler="serial" if mode == "serial" else "local",
                                      workers=a.workers)
            times[mode].append(time.perf_counter() - t0)
    cols = [c for c in tables["serial"].columns if c != "wall_s"]
    same = bool(tables["serial"][cols].equals(tables["dask"][cols]))
    best = {k: min(v) for k, v in times.items()}
    out = dict(case=CASE, runs=8, workers=a.workers, rounds=a.rounds, times_s=times, best_s=best,
               ratio=best["dask"] / best["serial"], identical_tables=same, machine=platform.machine(),
               cores=__import__("os").cpu_count(), date=time.strftime("%Y-%m-%d %H:%M"))
    res = ROOT / "benchmarks" / "results"
    (res / "sweep.json").write_text(json.dumps(out, indent=1))
    md = (f"# Dask sweep vs serial ({out['date']})\n\n8 seeds of `{CASE}` (dry variants), {a.workers} local "
          f"worker processes, {a.rounds} rounds, best of each: serial {best['serial']:.1f} s "
          f"(rounds {', '.join(f'{t:.1f}' for t in times['serial'])}), Dask {best['dask']:.1f} s (rounds "
          f"{', '.join(f'{t:.1f}' for t in times['dask'])}); ratio {out['ratio']:.2f}; identical tables: {same}.\n")
    (res / "sweep.md").write_text(md)
    print(md)


if __name__ == "__main__":
    main()
