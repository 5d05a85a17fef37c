"""Cost of the non-finite state check (issue 19 item 2) on the bench_dem packing.

    python benchmarks/bench_nonfinite_check.py [--sizes 10000 100000] [--steps 300] [--rounds 3]

``stepping.run_steps`` ends with one compiled pass over the dynamic state (``state_is_finite``: disc
positions, rotations, velocities and force sums, wall quantities, contact history) once per call of
the cycle, i.e. per neighbour-list rebuild or chunk, never per step or per pair.  Measured here, in
one process and on one thread, for each size:

- the check alone: one ``state_is_finite`` call from Python on the running state (best of 200; this
  includes Numba's dispatch, which the call inside run_steps does not pay: an upper bound);
- how often it runs: the calls of ``run_steps`` per step during ``steps`` timed steps;
- the step time: the best of ``rounds`` runs of ``steps`` steps (CPU time);
- the share: one check × checks per step ÷ step time.

Results: benchmarks/results/nonfinite_check.{json,md}.  Whole-run A/B against a base commit:
benchmarks/bench_ab.py / bench_ab_steps.py (on this shared machine their noise is several per cent).
"""
from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import numba  # noqa: E402

import bench_dem as b  # noqa: E402
import demflow.simulation as simulation  # noqa: E402
from demflow.atomic import write_text_atomic  # noqa: E402
from demflow.stepping import state_is_finite  # noqa: E402


def measure(n, steps, rounds):
    numba.set_num_threads(1)
    sim = b.build(b.make_scene(n))
    sim.run(20, threads=1)
    args = (sim.discs, sim.walls, sim.pairs.hist)
    best = min(_timed(lambda: state_is_finite(*args)) for _ in range(200))
    calls = [0]
    run_steps = simulation.run_steps

    def counting(*a):
        calls[0] += 1
        return run_steps(*a)

    simulation.run_steps = counting
    try:
        sim.run(steps, threads=1)
    finally:
        simulation.run_steps = run_steps
    times = []
    for _ in range(rounds):
        c0 = time.process_time()
        sim.run(steps, threads=1)
        times.append(time.process_time() - c0)
    step_s = min(times) / steps
    per_step = calls[0] / steps
    return dict(n=n, steps=steps, rounds=rounds, check_us=best * 1e6, checks_per_step=per_step,
                step_ms=step_s * 1e3, share=best * per_step / step_s, cpu_s=times,
                elements=int(sum(a.size for a in (*(getattr(sim.discs, f) for f in ("x", "y", "th", "vx", "vy", "om",
                                                                                      "Fx", "Fy", "M")),
                                                     sim.walls.force, sim.pairs.hist))) + 9 * sim.nw)


def _timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    rows = [measure(n, args.steps, args.rounds) for n in args.sizes]
    out = Path(args.out)
    meta = dict(generated=time.strftime("%Y-%m-%d %H:%M:%S"), python=platform.python_version(),
                machine=platform.machine(), threads=1)
    write_text_atomic(out / "nonfinite_check.json", json.dumps(dict(meta, rows=rows), indent=1))
    md = [f"# Non-finite state check: cost on the bench_dem packing ({meta['generated']}, one thread)", "",
          "| N | values checked | one check [µs] | checks per step | step [ms] | share of the run time |",
          "|---|---|---|---|---|---|"]
    for r in rows:
        md.append(f"| {r['n']:,} | {r['elements']:,} | {r['check_us']:.0f} | {r['checks_per_step']:.4f} | "
                  f"{r['step_ms']:.2f} | {r['share']:.1e} |")
    md += ["", f"One check: `state_is_finite` called from Python (with Numba's dispatch, an upper bound on the "
           f"pass run_steps makes). Checks per step: calls of run_steps per step over {args.steps} steps "
           f"(one per neighbour-list rebuild or chunk). Step: best of {args.rounds} runs of {args.steps} steps, "
           "CPU time. Share = one check × checks per step ÷ step time."]
    write_text_atomic(out / "nonfinite_check.md", "\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
