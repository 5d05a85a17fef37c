"""Cost of the non-finite state check (issue 19 item 2) on the bench_dem packing.

    python benchmarks/bench_nonfinite_check.py [--sizes 10000 100000] [--steps 300] [--rounds 5]

``Simulation._run`` checks the dynamic state for NaN/inf once per call of the compiled cycle (one
call per neighbour-list rebuild or chunk, never per step or per pair).  Measured here, in one
process and on one thread, for each size:

- the check alone: the time of one ``_nonfinite_state()`` call on the running state (best of 200);
- how often it runs: the cycle calls per step during the timed steps;
- the run with and without it: ``steps`` steps with the check as shipped and with it replaced by a
  no-op, alternating the two ``rounds`` times each from the same state (CPU time; best and median
  of each side), so process-to-process noise cancels.

Results: benchmarks/results/nonfinite_check.{json,md}.
"""
from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import numba  # noqa: E402

import bench_dem as b  # noqa: E402
from demflow.simulation import Simulation  # noqa: E402


def measure(n, steps, rounds):
    numba.set_num_threads(1)
    sim = b.build(b.make_scene(n))
    sim.run(20, threads=1)
    # the check alone
    best = min(_timed(sim._nonfinite_state) for _ in range(200))
    # how many cycle calls (each followed by one check) per step
    calls = [0]
    orig = Simulation._nonfinite_state

    def counting(self):
        calls[0] += 1
        return orig(self)

    Simulation._nonfinite_state = counting
    try:
        sim.run(steps, threads=1)
    finally:
        Simulation._nonfinite_state = orig
    per_step = calls[0] / steps
    # with and without, alternating
    on, off = [], []
    for k in range(rounds):
        for side in ((on, off) if k % 2 == 0 else (off, on)):
            if side is off:
                Simulation._nonfinite_state = lambda self: None
            try:
                c0 = time.process_time()
                sim.run(steps, threads=1)
                side.append(time.process_time() - c0)
            finally:
                Simulation._nonfinite_state = orig
    step_s = min(off) / steps
    return dict(n=n, steps=steps, rounds=rounds, check_us=best * 1e6, checks_per_step=per_step,
                check_share_estimate=best * per_step / step_s, cpu_with_best=min(on), cpu_without_best=min(off),
                cpu_with_median=statistics.median(on), cpu_without_median=statistics.median(off),
                ratio_best=min(on) / min(off), ratio_median=statistics.median(on) / statistics.median(off),
                cpu_with=on, cpu_without=off)


def _atomic_write(path: Path, text: str):
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)


def _timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    rows = [measure(n, args.steps, args.rounds) for n in args.sizes]
    out = Path(args.out)
    meta = dict(generated=time.strftime("%Y-%m-%d %H:%M:%S"), python=platform.python_version(),
                machine=platform.machine(), threads=1)
    _atomic_write(out / "nonfinite_check.json", json.dumps(dict(meta, rows=rows), indent=1))
    md = [f"# Non-finite state check: cost on the bench_dem packing ({meta['generated']}, one thread)", "",
          "| N | one check [µs] | checks per step | check / step time | CPU s with (best, median) | "
          "CPU s without (best, median) | with/without (best; median) |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        md.append(f"| {r['n']:,} | {r['check_us']:.0f} | {r['checks_per_step']:.3f} | {r['check_share_estimate']:.2e} "
                  f"| {r['cpu_with_best']:.2f}, {r['cpu_with_median']:.2f} | {r['cpu_without_best']:.2f}, "
                  f"{r['cpu_without_median']:.2f} | {r['ratio_best']:.3f}; {r['ratio_median']:.3f} |")
    md += ["", f"{args.steps} steps per timed run, {args.rounds} runs per side alternating, from one state in one "
           "process. 'check / step time' is one check's time × checks per step ÷ the best step time without it: "
           "the check's share of a run, measured directly (the with/without ratio also carries the machine's "
           "noise)."]
    _atomic_write(out / "nonfinite_check.md", "\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
