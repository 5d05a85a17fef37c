"""How fast could the ellipsoid bed be if its Lin & Ng potential points cost nothing?  (Issue 16's speed
acceptance: the ellipsoid bed per particle-step ≥ the 12-sphere clump bed.)

    python benchmarks/bench_ellipsoid_bound.py [--settle 200000] [--steps 2000] [--rounds 7] [--reps 2000]

The beds are those of ``bench_ellipsoid_vs_clumps.py`` (the miyata-uniaxial-3d insertion stage, 80 particles,
settled ``--settle`` steps; one thread).  In each round: ``--steps`` steps of the ellipsoid bed and of the K = 12
clump bed, then the two potential points of every touching ellipsoid pair solved ``--reps`` times in a compiled
loop exactly as the pair pass solves them (:func:`demflow.shapes.ellipsoid.potential_point`, warm-started from the
multipliers of the step before, on the state one step on: the pass's own work), and the same loop with only the
potential problems (H, g) set up.  The difference of the two loops is the potential points' cost per step; the
ellipsoid step less that cost is what the bed would take with a free solve, and its ratio to the clump step is an
upper bound of what any faster solve of the same equations could give.  Best round of each, spread = (worst -
best)/best.  Results: benchmarks/results/<tag>.{json,md}.  Run it on a quiet machine.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numba  # noqa: E402
import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

from bench_ellipsoid_vs_clumps import bed  # noqa: E402
from demflow.atomic import write_text_atomic  # noqa: E402
from demflow.shapes.ellipsoid import _potential_problem, potential_point  # noqa: E402


@njit
def _solves(idx, pos, rot, axes, shift, pi, pj, lam, reps, points):
    """Set up both potential problems of every pair in ``idx`` (and, when ``points``, solve both potential
    points warm-started from ``lam``) ``reps`` times.  Returns (a sum that keeps the work live, factorisations of
    the last repetition)."""
    work = np.zeros((6, 3))
    M = np.zeros((3, 3))
    H = np.zeros((3, 3))
    g = np.zeros(3)
    cj = np.zeros(3)
    acc = 0.0
    fact = 0
    for _ in range(reps):
        fact = 0
        for t in range(idx.size):
            k = idx[t]
            i = pi[k]
            j = pj[k]
            for a in range(3):
                cj[a] = pos[j, a] + shift[k, a]
            for side in range(2):  # the point of i's surface, then j's (as ellipsoid_pair)
                if side == 0:
                    _potential_problem(pos[i], rot[i], axes[i], cj, rot[j], axes[j], H, g, M)
                else:
                    _potential_problem(cj, rot[j], axes[j], pos[i], rot[i], axes[i], H, g, M)
                if points:
                    lam_k, it = potential_point(H, g, lam[k, side], True, work[side * 4], work[1], work[2], work[5])
                    acc += lam_k
                    fact += it
                else:
                    acc += H[0, 0] + g[1]
    return acc, fact


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--settle", type=int, default=200000, help="untimed settling steps of each bed")
    ap.add_argument("--steps", type=int, default=2000, help="steps per timed round")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--reps", type=int, default=2000, help="repetitions of the solves per round")
    ap.add_argument("--tag", default="ellipsoid_bound")
    ap.add_argument("--notes", default="")
    a = ap.parse_args(argv)
    numba.set_num_threads(1)
    t0 = time.perf_counter()
    ell = bed("ellipsoids", 8, a.settle)
    clumps = bed("clumps", 12, a.settle)
    ell.run(10)
    clumps.run(10)
    sp, pr = ell.spheres, ell.pairs
    n = sp.pos.shape[0]
    c0 = pr.hist.shape[1] - 3  # the warm-start columns (demflow.contacts.ellipsoids)
    lam = np.ascontiguousarray(pr.hist[:, c0 + 1:c0 + 3])
    ell.run(1)  # one step on: the solves the pass did in it start from lam
    if ell.pairs is not pr:
        raise SystemExit("the pair list was rebuilt in the probe step; run again with another --settle")
    idx = np.array([k for k in range(pr.i.size) if pr.j[k] < n and pr.ovl[k] > 0.0], np.int64)
    args = (idx, sp.pos.copy(), ell.ell.rot.copy(), ell.ell.axes, pr.shift, pr.i, pr.j, lam)
    _, fact = _solves(*args, 1, True)
    _solves(*args, 1, False)
    times = {"ellipsoid step": [], "K = 12 clump step": [], "both potential points set up and solved": [],
             "both potential problems set up": []}
    loads = []
    for r in range(a.rounds):
        loads.append(os.getloadavg())
        t = time.perf_counter()
        ell.run(a.steps)
        times["ellipsoid step"].append((time.perf_counter() - t) / a.steps)
        t = time.perf_counter()
        clumps.run(a.steps)
        times["K = 12 clump step"].append((time.perf_counter() - t) / a.steps)
        t = time.perf_counter()
        _solves(*args, a.reps, True)
        times["both potential points set up and solved"].append((time.perf_counter() - t) / a.reps)
        t = time.perf_counter()
        _solves(*args, a.reps, False)
        times["both potential problems set up"].append((time.perf_counter() - t) / a.reps)
    best = {k: min(v) for k, v in times.items()}
    spread = {k: (max(v) - min(v)) / min(v) for k, v in times.items()}
    points = best["both potential points set up and solved"] - best["both potential problems set up"]
    without = best["ellipsoid step"] - points
    ratio_now = best["K = 12 clump step"] / best["ellipsoid step"]
    bound = best["K = 12 clump step"] / without
    meta = dict(date=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()), machine=platform.processor()
                or platform.machine(), cores=os.cpu_count(), python=platform.python_version(), numba=numba.__version__,
                threads=1, args=vars(a), loadavg_per_round=loads, total_s=time.perf_counter() - t0,
                command="python benchmarks/bench_ellipsoid_bound.py " + " ".join(sys.argv[1:] if argv is None else argv))
    res = dict(meta=meta, touching_pairs=int(idx.size), factorisations_per_point=fact / (2 * idx.size),
               best_s=best, spread=spread, rounds_s=times, potential_points_s=points, step_without_points_s=without,
               ratio_now=ratio_now, ratio_bound=bound)
    out = Path(__file__).resolve().parent / "results"
    write_text_atomic(out / f"{a.tag}.json", json.dumps(res, indent=1))
    lines = [f"# Ellipsoid bed with free potential points: an upper bound (one thread, {meta['date']})", "",
             f"Command: `{meta['command']}`. Notes: {a.notes or '—'}", "",
             f"Beds of bench_ellipsoid_vs_clumps.py settled {a.settle} steps; {a.rounds} rounds (steps of each bed, "
             f"then the compiled solve loops over the {idx.size} touching ellipsoid pairs, {a.reps} repetitions); "
             f"best round, spread = (worst - best)/best. Factorisations per potential point, warm-started from the "
             f"step before as in the pass: {fact / (2 * idx.size):.2f}.", "",
             "| what | best per step [µs] | spread |", "|---|---|---|"]
    for k in times:
        lines.append(f"| {k} | {best[k] * 1e6:.1f} | {spread[k]:.0%} |")
    lines += ["",
              f"The two potential points cost {points * 1e6:.1f} µs per step ({points / idx.size * 1e9:.0f} ns per "
              f"touching pair); without them the ellipsoid step would take {without * 1e6:.1f} µs against the "
              f"clump bed's {best['K = 12 clump step'] * 1e6:.1f} µs.", "",
              f"Ellipsoids / K = 12 clumps per particle-step: now {ratio_now:.2f}×; with free potential points at most "
              f"{bound:.2f}× (issue 16 asks ≥ 1×).", "",
              f"Load average before each round: {[tuple(round(x, 2) for x in l) for l in loads]}."]
    write_text_atomic(out / f"{a.tag}.md", "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
