"""Dask sweep vs serial (issue 17 item 6): 8 seeds of the dry simple shear (thesis-simple-shear,
variants loose-dry and dense-dry, no ensemble table), serial in one process and on a local cluster of
2 worker processes; the tables must be identical, and the wall-time ratio is the figure.  The serial run is
timed twice: with Numba's default threads (its parallel kernels already use every core: what a user's serial
run does) and with one thread (the work the two workers split), so that the ratio can be read both ways.

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
    import numba

    threads = numba.get_num_threads()
    times = {"serial": [], "serial, 1 thread": [], "dask": []}
    tables = {}
    for _ in range(a.rounds):
        for mode in times:
            numba.set_num_threads(1 if mode == "serial, 1 thread" else threads)
            t0 = time.perf_counter()
            tables[mode] = case_sweep(CASE, SETS, scheduler="local" if mode == "dask" else "serial",
                                      workers=a.workers)
            times[mode].append(time.perf_counter() - t0)
        numba.set_num_threads(threads)
    cols = [c for c in tables["serial"].columns if c != "wall_s"]
    same = all(tables["serial"][cols].equals(tables[m][cols]) for m in times)
    best = {k: min(v) for k, v in times.items()}
    out = dict(case=CASE, runs=8, workers=a.workers, rounds=a.rounds, times_s=times, best_s=best,
               ratio=best["dask"] / best["serial"], ratio_1thread=best["dask"] / best["serial, 1 thread"],
               serial_threads=threads, identical_tables=same, machine=platform.machine(),
               cores=__import__("os").cpu_count(), date=time.strftime("%Y-%m-%d %H:%M"))
    res = ROOT / "benchmarks" / "results"
    (res / "sweep.json").write_text(json.dumps(out, indent=1))
    spread = {k: (max(v) - min(v)) / min(v) for k, v in times.items()}
    md = (f"# Dask sweep vs serial ({out['date']})\n\n8 seeds of `{CASE}` (dry variants), {a.workers} local "
          f"worker processes (one kernel thread each), {a.rounds} rounds, best of each (spread = (max - min)/min):\n\n"
          + "".join(f"- {k}: {best[k]:.1f} s (rounds {', '.join(f'{t:.1f}' for t in times[k])}; spread "
                    f"{spread[k]:.0%})\n" for k in times)
          + f"\nDask / serial ({threads} kernel threads): {out['ratio']:.2f}; Dask / serial (1 thread): "
          f"{out['ratio_1thread']:.2f}; identical tables: {same}.\n")
    (res / "sweep.md").write_text(md)
    print(md)


if __name__ == "__main__":
    main()
