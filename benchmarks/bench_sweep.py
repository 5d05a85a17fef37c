"""Dask sweep vs serial (issue 17 item 6): 8 seeds of the dry simple shear (thesis-simple-shear,
variants loose-dry and dense-dry, no ensemble table), serial and on a local cluster of 2 worker processes;
the tables must be identical, and the wall-time ratio is the figure.

Each mode runs in a fresh Python process, timed from outside, as a user's ``demflow sweep`` would run:
its imports, the loading of the cached Numba kernels, the cluster's start and close all count.  Three modes:
serial with Numba's default threads (its parallel kernels already use every core: what a user's serial run
does), serial with one thread (the work the two workers split), and Dask.  Each run's own wall time
(the table's ``wall_s``) is kept too, so the overhead splits into "runs slower on a worker", "the last run
alone at the end" and "fixed costs".

    python benchmarks/bench_sweep.py [--rounds 3] [--workers 2] [--gamma-max 0.105,0.315]

The sweep is timed at two run lengths: the case's own shear (gamma_max = 0.105, about 3 s a run) and a
three times longer shear (0.315), to show how the fixed costs weigh against the length of the runs.

Run it on a quiet machine (nothing else running): results in benchmarks/results/sweep.{json,md}.
The Numba cache is filled by a first serial run before timing; modes rotate between rounds.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
CASE = "thesis-simple-shear"
SETS = {"seed": list(range(1, 9)), "variants": ["loose-dry,dense-dry"], "ensemble": [""]}
MODES = {"serial": ("serial", None), "serial, 1 thread": ("serial", "1"), "dask": ("local", None)}

CHILD = """
import sys, warnings
warnings.simplefilter("ignore")
if __name__ == "__main__":
    from demflow.sweep import case_sweep
    sets = {sets!r}
    case_sweep({case!r}, sets, scheduler={scheduler!r}, workers={workers}, progress=False).to_parquet({out!r})
"""


def run_mode(mode: str, workers: int, out: Path, sets=SETS) -> float:
    scheduler, threads = MODES[mode]
    env = dict(os.environ)
    if threads:
        env["NUMBA_NUM_THREADS"] = threads
    code = CHILD.format(sets=sets, case=CASE, scheduler=scheduler, workers=workers, out=str(out))
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=ROOT, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--gamma-max", default="0.105,0.315")
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench-sweep-"))
    run_mode("serial", a.workers, tmp / "warm.parquet", dict(SETS, seed=[1]))  # fill the Numba cache
    results = [measure(a, tmp, dict(SETS, gamma_max=[float(g)])) for g in a.gamma_max.split(",")]
    res = ROOT / "benchmarks" / "results"
    (res / "sweep.json").write_text(json.dumps(results, indent=1))
    md = (f"# Dask sweep vs serial ({results[0]['date']})\n\n8 seeds of `{CASE}` (dry variants), each mode a "
          f"fresh process timed from outside (imports, kernel loading, cluster start and close included); "
          f"{a.workers} local worker processes (one kernel thread each), {a.rounds} rounds, modes rotating, best "
          f"of each (spread = (max - min)/min).\n" + "".join(r["md"] for r in results))
    (res / "sweep.md").write_text(md)
    print(md)


def measure(a, tmp: Path, sets: dict) -> dict:
    """Best-of-rounds wall times of the three modes on ``sets``, with the Dask time's split."""
    times = {m: [] for m in MODES}
    run_sum = {m: [] for m in MODES}
    tables = {}
    order = list(MODES)
    for r in range(a.rounds):
        for mode in order[r % len(order):] + order[:r % len(order)]:
            times[mode].append(run_mode(mode, a.workers, tmp / "t.parquet", sets))
            tables[mode] = pd.read_parquet(tmp / "t.parquet")
            run_sum[mode].append(float(tables[mode].groupby("seed").wall_s.first().sum()))
    cols = [c for c in tables["serial"].columns if c != "wall_s"]
    same = all(tables["serial"][cols].equals(tables[m][cols]) for m in MODES)
    best = {k: min(v) for k, v in times.items()}
    ib = {k: times[k].index(best[k]) for k in times}
    dask_runs = run_sum["dask"][ib["dask"]]
    out = dict(case=CASE, gamma_max=sets["gamma_max"][0], runs=8, workers=a.workers, rounds=a.rounds,
               times_s=times, best_s=best,
               sum_of_run_walls_s=run_sum, ratio=best["dask"] / best["serial"],
               ratio_1thread=best["dask"] / best["serial, 1 thread"],
               ideal_s=dask_runs / a.workers, identical_tables=same, machine=platform.machine(),
               cores=os.cpu_count(), date=time.strftime("%Y-%m-%d %H:%M"))
    spread = {k: (max(v) - min(v)) / min(v) for k, v in times.items()}
    out["md"] = (f"\n## gamma_max = {sets['gamma_max'][0]} (runs of {run_sum['serial'][ib['serial']] / 8:.1f} s "
                 f"on average, serial)\n\n"
          + "".join(f"- {k}: {best[k]:.1f} s (rounds {', '.join(f'{t:.1f}' for t in times[k])}; spread "
                    f"{spread[k]:.0%}); the runs' own wall times sum to "
                    f"{run_sum[k][ib[k]]:.1f} s in the best round\n" for k in times)
          + f"\nDask / serial (default kernel threads): {out['ratio']:.2f}; Dask / serial (1 thread): "
          f"{out['ratio_1thread']:.2f}; identical tables: {same}.  The runs' wall times on the workers summed "
          f"to {dask_runs:.1f} s: split evenly over {a.workers} workers that is {out['ideal_s']:.1f} s; "
          f"the rest of the Dask time ({best['dask'] - out['ideal_s']:.1f} s) is start-up, the last run "
          f"running alone, and closing.\n")
    return out


if __name__ == "__main__":
    main()
