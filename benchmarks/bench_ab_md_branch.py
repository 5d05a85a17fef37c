"""A/B in one process and one package: the 3D cycle with and without the Mindlin-Deresiewicz branch compiled in.

    python benchmarks/bench_ab_md_branch.py [--sizes 10000 100000] [--chunk 300 30] [--rounds 30]

A Hertz-Mindlin scene gets :data:`demflow.laws.hertz_mindlin.HertzParams` when none of its material pairs uses
Mindlin-Deresiewicz, and its pair pass is compiled without that branch; :data:`HertzParamsMD` (the same fields)
compiles it.  Here bench_engines3d.py's scene (packing3d.py's dense FCC Hertz sphere packing, which has no
Mindlin-Deresiewicz pair) is built twice; the second simulation's parameters are given the MD type, values
unchanged, so it runs the cycle as it was compiled before the split (the branch present and never taken).  Both
run in alternating chunks of ``--chunk`` steps, the order swapped every round, one thread, so both see the same
host states and everything else (the package, its other kernels, the arrays' allocator) is the same.

Why not :mod:`bench_ab_inprocess` (a base commit's package imported beside this one): the variant here is a type
of the same package, so nothing but the branch differs between the two runs (a null run of that tool, HEAD against
HEAD at 1e4 spheres, 16 rounds of 300 steps, 2026-12-01 on an AMD EPYC host without AVX-512, gave a per-round
median of 1.030 and a ratio of the minima of 0.969: neither tool resolves a few per cent in one short run).  Reported per size: ns per sphere-step of each (min, 10th percentile,
median), the per-round ratio (min, median, max), the ratio of the minima, and whether both ended with the same
bits (they must).  ``--null`` gives neither simulation the MD type: the same code twice, whose ratio shows what the
host's noise alone gives in a run of that length.  Results: benchmarks/results/<tag>.{json,md}.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE / "benchmarks"))

from bench_ab_inprocess import alternate, per_size, run_info, table_rows, timing_summary, write_results  # noqa: E402

WITH, WITHOUT = "with MD branch", "without"


def measure(n: int, chunk: int, rounds: int, warm: int, null: bool = False) -> dict:
    import numba

    import demflow
    from demflow.laws.hertz_mindlin import HertzParams, HertzParamsMD
    from packing3d import dense_fcc

    numba.set_num_threads(1)
    sims = {WITH: demflow.build(dense_fcc(n)), WITHOUT: demflow.build(dense_fcc(n))}
    if not isinstance(sims[WITH].law_params, HertzParams):
        raise RuntimeError(f"the benchmark scene's parameters are {type(sims[WITH].law_params).__name__}, "
                           "not HertzParams")
    if not null:  # --null: both keep HertzParams (the tool's own noise: the ratio should be 1 within it)
        sims[WITH].law_params = HertzParamsMD(*sims[WITH].law_params)
    ts = alternate(sims, chunk, rounds, warm)
    a, b = sims[WITH], sims[WITHOUT]
    same = all(np.array_equal(u, v) for u, v in ((a.spheres.pos, b.spheres.pos), (a.spheres.vel, b.spheres.vel),
                                                   (a.spheres.angvel, b.spheres.angvel), (a.pairs.hist, b.pairs.hist)))
    row = dict(n=n, chunk=chunk, rounds=rounds, steps=int(b.step), rebuilds=int(b.n_rebuilds), same_bits=bool(same),
               null=bool(null))
    row.update(timing_summary(ts, chunk, n, WITH, WITHOUT))
    return row


def markdown(data: dict) -> str:
    i = data["info"]
    out = [f"# 3D cycle without / with the Mindlin-Deresiewicz branch, one process, one package ({i['date']})", "",
           f"Code {i['head'][:7]}{' + working tree changes' if i['dirty'] else ''}; command `{i['command']}`; "
           f"{i['cores']} cores, {i['cpu']}, numba {i['numba']}, one thread.  {i['notes']}", "",
           "Scene: packing3d.py's dense FCC Hertz sphere packing (no Mindlin-Deresiewicz pair), built twice; one "
           "simulation's parameters given the MD type (the branch compiled in, never taken"
           f"{'; NULL RUN: here neither was, both ran HertzParams' if any(r.get('null') for r in data['rows']) else ''}"
           ").  Chunks alternate, "
           "the order swapped each round.  ns per sphere-step (wall clock), over the rounds.", "",
           "| N | chunk × rounds | with: min | p10 | median | without: min | p10 | median | "
           "without/with per round (min / median / max) | ratio of minima | same bits | rebuilds |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    out += table_rows(data["rows"], WITH, WITHOUT, "rebuilds")
    return "\n".join(out) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--chunk", type=int, nargs="+", default=None,
                    help="steps per timed chunk, one per size (default 3e6/N: 300 at 1e4, 30 at 1e5)")
    ap.add_argument("--rounds", type=int, default=30)
    ap.add_argument("--warm", type=int, default=200, help="untimed steps first (compilation, first rebuilds)")
    ap.add_argument("--null", action="store_true",
                    help="a null run: neither simulation gets the MD type (the ratio measures the tool's noise)")
    ap.add_argument("--notes", default="")
    ap.add_argument("--tag", default="speed3d_md_branch_ab")
    ap.add_argument("--out", default=str(HERE / "benchmarks" / "results"))
    a = ap.parse_args(argv)
    rows = per_size(ap, a, 3e6, lambda n, c: measure(n, c, a.rounds, a.warm, a.null))
    data = dict(info=run_info("bench_ab_md_branch.py", argv, a.notes), rows=rows)
    write_results(a.out, a.tag, data, markdown(data))


if __name__ == "__main__":
    main()
