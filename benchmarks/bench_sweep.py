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
    python benchmarks/bench_sweep.py --case miyata-uniaxial-3d [--modes serial dask]

The sweep is timed at two run lengths: the case's own shear (gamma_max = 0.105, about 3 s a run) and a
three times longer shear (0.315), to show how the fixed costs weigh against the length of the runs.
``--case miyata-uniaxial-3d``: 8 seeds of the uniaxial clump case as its page runs them (one protocol run
each, about 15 s; no engine references, no undamped band), results in sweep_miyata-uniaxial-3d.{json,md}.

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
CASE_SETS = {CASE: SETS,
             "miyata-uniaxial-3d": {"seed": list(range(1, 9)), "band_seeds": [1], "engine_refs": [0],
                                    "undamped_band": [0]}}
MODES = {"serial": ("serial", None), "serial, 1 thread": ("serial", "1"), "dask": ("local", None)}

CHILD = """
import sys, warnings
warnings.simplefilter("ignore")
if __name__ == "__main__":
    from demflow.sweep import case_sweep
    sets = {sets!r}
    case_sweep({case!r}, sets, scheduler={scheduler!r}, workers={workers}, progress=False).to_parquet({out!r})
"""


def run_mode(mode: str, workers: int, out: Path, sets=SETS, case=CASE) -> float:
    scheduler, threads = MODES[mode]
    env = dict(os.environ)
    if threads:
        env["NUMBA_NUM_THREADS"] = threads
    code = CHILD.format(sets=sets, case=case, scheduler=scheduler, workers=workers, out=str(out))
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=ROOT, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--gamma-max", default="0.105,0.315")
    ap.add_argument("--case", default=CASE, choices=list(CASE_SETS))
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=list(MODES))
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench-sweep-"))
    sets0 = CASE_SETS[a.case]
    run_mode("serial", a.workers, tmp / "warm.parquet", dict(sets0, seed=[1]), a.case)  # fill the Numba cache
    if a.case == CASE:
        results = [measure(a, tmp, dict(SETS, gamma_max=[float(g)])) for g in a.gamma_max.split(",")]
        tag = "sweep"
    else:
        results = [measure(a, tmp, sets0)]
        tag = f"sweep_{a.case}"
    res = ROOT / "benchmarks" / "results"
    (res / f"{tag}.json").write_text(json.dumps(results, indent=1))
    md = (f"# Dask sweep vs serial ({results[0]['date']})\n\n8 seeds of `{a.case}`, each mode a "
          f"fresh process timed from outside (imports, kernel loading, cluster start and close included); "
          f"{a.workers} local worker processes (one kernel thread each), {a.rounds} rounds, modes rotating, best "
          f"of each (spread = (max - min)/min).\n" + "".join(r["md"] for r in results))
    (res / f"{tag}.md").write_text(md)
    print(md)


def measure(a, tmp: Path, sets: dict) -> dict:
    """Best-of-rounds wall times of the three modes on ``sets``, with the Dask time's split."""
    modes = list(a.modes)
    times = {m: [] for m in modes}
    run_sum = {m: [] for m in modes}
    tables = {}
    for r in range(a.rounds):
        for mode in modes[r % len(modes):] + modes[:r % len(modes)]:
            times[mode].append(run_mode(mode, a.workers, tmp / "t.parquet", sets, a.case))
            tables[mode] = pd.read_parquet(tmp / "t.parquet")
            run_sum[mode].append(float(tables[mode].groupby("seed").wall_s.first().sum()))
    cols = [c for c in tables["serial"].columns if c != "wall_s"]
    same = all(tables["serial"][cols].equals(tables[m][cols]) for m in modes)
    best = {k: min(v) for k, v in times.items()}
    ib = {k: times[k].index(best[k]) for k in times}
    dask_runs = run_sum["dask"][ib["dask"]]
    out = dict(case=a.case, gamma_max=sets.get("gamma_max", [None])[0], runs=8, workers=a.workers, rounds=a.rounds,
               times_s=times, best_s=best,
               sum_of_run_walls_s=run_sum, ratio=best["dask"] / best["serial"],
               ratio_1thread=(best["dask"] / best["serial, 1 thread"]) if "serial, 1 thread" in best else None,
               ideal_s=dask_runs / a.workers, identical_tables=same, machine=platform.machine(),
               cores=os.cpu_count(), date=time.strftime("%Y-%m-%d %H:%M"))
    spread = {k: (max(v) - min(v)) / min(v) for k, v in times.items()}
    head = f"gamma_max = {sets['gamma_max'][0]}" if "gamma_max" in sets else "the case's defaults"
    out["md"] = (f"\n## {head} (runs of {run_sum['serial'][ib['serial']] / 8:.1f} s "
                 f"on average, serial)\n\n"
          + "".join(f"- {k}: {best[k]:.1f} s (rounds {', '.join(f'{t:.1f}' for t in times[k])}; spread "
                    f"{spread[k]:.0%}); the runs' own wall times sum to "
                    f"{run_sum[k][ib[k]]:.1f} s in the best round\n" for k in times)
          + f"\nDask / serial (default kernel threads): {out['ratio']:.2f}; Dask / serial (1 thread): "
          f"{out['ratio_1thread'] if out['ratio_1thread'] is None else round(out['ratio_1thread'], 2)}; "
          f"identical tables: {same}.  The runs' wall times on the workers summed "
          f"to {dask_runs:.1f} s: split evenly over {a.workers} workers that is {out['ideal_s']:.1f} s; "
          f"the rest of the Dask time ({best['dask'] - out['ideal_s']:.1f} s) is start-up, the last run "
          f"running alone, and closing.\n")
    return out


if __name__ == "__main__":
    main()
