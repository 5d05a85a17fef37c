"""Where a step of the 3D dense Hertz benchmark goes, in demflow and in LIGGGHTS (issue 13 item 5: ≥ 1.5×
LIGGGHTS on one core at 1e4 and 1e5 spheres).

    python benchmarks/bench_breakdown3d.py [--sizes 10000 100000] [--steps 600 400] [--rounds 3] [--reps 20 5]

The packing is ``bench_engines3d.py``'s (``packing3d.dense_fcc``; one thread).  demflow: the scene built and
run S steps, then per round ``run(S)`` timed as a whole and its compiled cycle alone (``Simulation3D.dem_s``),
and on the state reached, with nothing moving between repetitions, the pair pass with its packed rows
(``pack_rows`` + ``sphere_forces``, ``--reps`` times), the integrator on a copy of the state, and one
neighbour-list rebuild.  LIGGGHTS: the benchmark deck run as ``run S`` + ``run S pre no``
(``bench_engines.split_run``); the second run's loop time and the breakdown LIGGGHTS prints after it (Pair,
Neigh, Comm, Output, Other).  Best round of each quantity; spread = (worst - best)/best.  Results:
benchmarks/results/<tag>.{json,md}.  Run it on a quiet machine.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numba  # noqa: E402

from bench_engines import ExternalRunner  # noqa: E402
from bench_engines3d import liggghts_scene  # noqa: E402
from demflow import build  # noqa: E402
from demflow.atomic import write_text_atomic  # noqa: E402
from demflow.contacts.spheres import pack_rows, sphere_forces  # noqa: E402
from demflow.engines.liggghts3d import Liggghts3DEngine  # noqa: E402
from demflow.stepping3d import MAX_OVERLAP_RATIO, integrate  # noqa: E402
from packing3d import dense_fcc  # noqa: E402

BREAKDOWN = re.compile(r"^(Pair|Neigh|Comm|Outpt|Output|Modify|Other)\s+time \(%\) = ([0-9.eE+-]+)")


def liggghts_breakdown(log: str) -> dict:
    """{part: seconds} of the breakdown LIGGGHTS prints after its second run (the timed steps S..2S)."""
    part = log.split("Loop time")[2]
    out = {}
    for line in part.splitlines():
        m = BREAKDOWN.match(line.strip())
        if m:
            out[m.group(1)] = float(m.group(2))
    return out


def best_of(f, k):
    best = float("inf")
    for _ in range(k):
        t = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t)
    return best


def demflow_round(sim, S, reps):
    """One round on ``sim`` (already run S steps): per-step seconds of the whole run, its compiled cycle, the pair
    pass, the integrator and the share of a rebuild; the pair list's size."""
    d0, r0 = sim.dem_s, sim.n_rebuilds
    t = time.perf_counter()
    sim.run(S)
    whole = (time.perf_counter() - t) / S
    cycle = (sim.dem_s - d0) / S
    rebuilds = sim.n_rebuilds - r0
    keep = sim._copy_state()

    def forces():
        for _ in range(reps):
            pack_rows(sim.spheres)
            sphere_forces(sim.spheres, sim.pairs, sim.planes, sim.tris, sim.law_params, sim.dt, False,
                          MAX_OVERLAP_RATIO)

    def integ():
        for _ in range(reps):
            integrate(sim.spheres, sim.g, sim.damping, sim.dt, False, False)

    pair = best_of(forces, 3) / reps
    sim._restore_state(keep)
    integ_s = best_of(integ, 3) / reps
    sim._restore_state(keep)
    rebuild = best_of(sim.rebuild, 2)
    sim._restore_state(keep)
    touching = int((sim.pairs.ovl > 0).sum())
    return dict(whole=whole, cycle=cycle, pair=pair, integrate=integ_s, rebuild=rebuild, rebuilds=rebuilds,
                rebuild_per_step=rebuild * rebuilds / S, listed=int(sim.pairs.i.size), touching=touching)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--steps", type=int, nargs="+", default=[600, 400], help="S per size")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--reps", type=int, nargs="+", default=[20, 5], help="pair-pass repetitions per size")
    ap.add_argument("--tag", default="breakdown3d")
    ap.add_argument("--notes", default="")
    ap.add_argument("--conventions", choices=("own", "liggghts"), default="own",
                    help="demflow's scene: as written ('own': incremental spring, rescaled history) or in the LIGGGHTS "
                         "deck's conventions ('liggghts': bench_engines3d.liggghts_scene, the model LIGGGHTS runs)")
    a = ap.parse_args(argv)
    numba.set_num_threads(1)
    t0 = time.perf_counter()
    rows = {}
    for n, S, reps in zip(a.sizes, a.steps, a.reps):
        scene = dense_fcc(n, name=f"breakdown3d{n}")
        if a.conventions == "liggghts":
            scene = liggghts_scene(scene)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            build(scene).run(20)  # compile and warm
        root = Path(tempfile.mkdtemp(prefix=f"breakdown3d_{n}_"))
        lig = ExternalRunner("liggghts", liggghts_scene(scene), S, root, 3600, E=Liggghts3DEngine(benchmark=True))
        dem, ligs = [], []
        for _ in range(a.rounds):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sim = build(scene)  # every round from the state at S
            sim.run(S)
            dem.append(demflow_round(sim, S, reps))
            m = lig.measure()
            parts = liggghts_breakdown((lig.dirs[2] / "log.liggghts").read_text(errors="replace"))
            ligs.append(dict(loop=m["dt_wall"] / S, **{k: v / S for k, v in parts.items()}))
        shutil.rmtree(root, ignore_errors=True)
        best = {k: min(r[k] for r in dem) for k in ("whole", "cycle", "pair", "integrate", "rebuild_per_step")}
        spread = {k: (max(r[k] for r in dem) - best[k]) / best[k] if best[k] else 0.0 for k in best}
        lbest = {k: min(r[k] for r in ligs) for k in ligs[0]}
        lspread = {k: (max(r[k] for r in ligs) - lbest[k]) / lbest[k] if lbest[k] else 0.0 for k in lbest}
        rows[n] = dict(S=S, reps=reps, demflow=dem, liggghts=ligs, demflow_best=best, demflow_spread=spread,
                       liggghts_best=lbest, liggghts_spread=lspread, listed=dem[-1]["listed"],
                       touching=dem[-1]["touching"])
    meta = dict(date=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()), machine=platform.processor()
                or platform.machine(), cores=os.cpu_count(), python=platform.python_version(), numba=numba.__version__,
                threads=1, args=vars(a), total_s=time.perf_counter() - t0,
                command="python benchmarks/bench_breakdown3d.py " + " ".join(sys.argv[1:] if argv is None else argv))
    out = Path(__file__).resolve().parent / "results"
    write_text_atomic(out / f"{a.tag}.json", json.dumps(dict(meta=meta, rows=rows), indent=1))
    lines = [f"# Where the 3D benchmark step goes: demflow and LIGGGHTS, one thread ({meta['date']})", "",
             f"Command: `{meta['command']}`. Notes: {a.notes or '—'}", "",
             f"demflow's conventions: {a.conventions} ('own': the scene as written; 'liggghts': the LIGGGHTS deck's, "
             "total shear spring and history projected without rescaling).", "",
             f"Per step, best of {a.rounds} rounds (spread = (worst - best)/best). demflow's parts are timed on a "
             "fixed state (module docstring); LIGGGHTS's are its own breakdown of the timed run.", ""]
    for n, r in rows.items():
        b, s, lb, ls = r["demflow_best"], r["demflow_spread"], r["liggghts_best"], r["liggghts_spread"]
        lines += [f"## {n} spheres (S = {r['S']}; {r['listed']} listed pairs, {r['touching']} touching)", "",
                  "| part | demflow [ms] | spread | LIGGGHTS [ms] | spread |", "|---|---|---|---|---|",
                  f"| whole step (`run(S)`; LIGGGHTS: loop time) | {b['whole'] * 1e3:.2f} | {s['whole']:.0%} | "
                  f"{lb['loop'] * 1e3:.2f} | {ls['loop']:.0%} |",
                  f"| compiled cycle | {b['cycle'] * 1e3:.2f} | {s['cycle']:.0%} | | |",
                  f"| pair pass (+ packed rows; LIGGGHTS: Pair) | {b['pair'] * 1e3:.2f} | {s['pair']:.0%} | "
                  f"{lb.get('Pair', float('nan')) * 1e3:.2f} | {ls.get('Pair', float('nan')):.0%} |",
                  f"| integrator (LIGGGHTS: Other, its fixes and the rest) | {b['integrate'] * 1e3:.2f} | {s['integrate']:.0%} | "
                  f"{lb.get('Other', float('nan')) * 1e3:.2f} | {ls.get('Other', float('nan')):.0%} |",
                  f"| neighbour lists (rebuilds × cost / S; LIGGGHTS: Neigh) | {b['rebuild_per_step'] * 1e3:.2f} | "
                  f"{s['rebuild_per_step']:.0%} | {lb.get('Neigh', float('nan')) * 1e3:.2f} | "
                  f"{ls.get('Neigh', float('nan')):.0%} |",
                  f"| LIGGGHTS Comm | | | {lb.get('Comm', float('nan')) * 1e3:.2f} | |", "",
                  f"demflow / LIGGGHTS speed: whole step {lb['loop'] / b['whole']:.2f}×, pair pass alone "
                  f"{lb.get('Pair', float('nan')) / b['pair']:.2f}×; for 1.5× the whole step must take "
                  f"{lb['loop'] / 1.5 * 1e3:.2f} ms.", ""]
    write_text_atomic(out / f"{a.tag}.md", "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
