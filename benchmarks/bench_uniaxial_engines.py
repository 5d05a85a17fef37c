"""Speed side by side on the uniaxial clump case (issue 14 item 6): demflow, LIGGGHTS and YADE, one core.

    python benchmarks/bench_uniaxial_engines.py [--steps S] [--rounds R] [--tag TAG]

The work: the first settling stage of miyata-uniaxial-3d (seed 1: 80 clumps of 8 spheres, 191 kg, in the
2 x 2 m periodic box, Hertz-Mindlin E 70 GPa, mu 0.6, e 0.3 body-mass dashpots, gravity) for S steps at
the case's time step, with the protocol's at-rest check every 5000 steps (none of the three beds is at
rest before 160000 steps, so every engine runs exactly S steps).  Each engine times its own loop, so
start-up and deck reading are left out: demflow the ``settle`` call (one Numba thread, JIT warm),
YADE the deck's settle loop (``YadeUniaxial3DEngine(benchmark=True)``, ``-j1``: Cundall damping 0.3 as
demflow), LIGGGHTS the sum of its "Loop time" lines in pass 1 of its deck (``settle_max = S``; no
local damping: LIGGGHTS has none for multisphere bodies).  The beds start alike, not identical:
demflow and YADE from demflow's lattice and orientations, LIGGGHTS from its own random insertion.

    rate = clumps x S / loop time      [clump-steps per second]

``--rounds`` rounds, the engine order rotating; the best round per engine is reported with the spread
(worst - best)/best and the load average before and after each run.  Run it on a quiet machine.
Results: benchmarks/results/<tag>.json and .md (tag default ``uniaxial_engines_speed``).
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

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

ENGINES = ("demflow", "liggghts", "yade")


def params(S: int) -> dict:
    from demflow.cases import get_case

    return get_case("miyata-uniaxial-3d").merged({"settle_max": S, "band_seeds": 1, "engine_refs": 0})


def time_demflow(S: int) -> dict:
    """demflow in a fresh process with one Numba thread (the JIT cache warm from a first short run)."""
    code = f"""
import json, time, warnings
warnings.simplefilter("ignore")
from demflow.jit import set_threads
set_threads(1)
from demflow.build import build
from demflow.cases.miyata_uniaxial3d_protocol import insertion_scene, settle
import sys
sys.path.insert(0, {str(Path(__file__).resolve().parent)!r})
from bench_uniaxial_engines import params
p = params({S})
sim = build(insertion_scene(p))
sim.run(10)  # compile / load the kernels
sim = build(insertion_scene(p))
t0 = time.perf_counter()
steps = settle(sim, p, {S})
wall = time.perf_counter() - t0
print(json.dumps(dict(steps=abs(steps), wall_s=wall, clumps=len(sim.bodies.mass))))
"""
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1",
               PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def time_yade(S: int) -> dict:
    from demflow.build import build
    from demflow.cases.miyata_uniaxial3d_protocol import insertion_scene
    from demflow.engines.yade_uniaxial3d import YadeUniaxial3DEngine

    p = params(S)
    sc = insertion_scene(p)
    with tempfile.TemporaryDirectory() as tmp:
        res, _ = YadeUniaxial3DEngine(p, benchmark=True).run(sc, tmp, timeout=3600, sim=build(sc))
    return dict(steps=int(res["steps"]), wall_s=float(res["wall_s"]), clumps=int(res["clumps"]))


def time_liggghts(S: int) -> dict:
    from bench_engines import liggghts_loop_times
    from demflow.build import build
    from demflow.cases.miyata_uniaxial3d_protocol import insertion_scene
    from demflow.engines.liggghts_uniaxial3d import LiggghtsUniaxial3DEngine

    p = params(S)
    sc = insertion_scene(p)
    eng = LiggghtsUniaxial3DEngine(p)
    with tempfile.TemporaryDirectory() as tmp:
        eng.write_deck(sc, build(sc), Path(tmp))
        subprocess.run(eng.command(Path(tmp)), cwd=tmp, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT,
                       env=dict(os.environ, OMP_NUM_THREADS="1"), check=True, timeout=3600)
        loops = liggghts_loop_times((Path(tmp) / "log1.liggghts").read_text())
        wall, steps = sum(t for t, _ in loops), sum(s for _, s in loops)
    # the deck's first runs (insertion: 1 step; each settle chunk: 5000) are all counted
    return dict(steps=steps, wall_s=wall, clumps=int(p["n_insert"]))


TIMERS = {"demflow": time_demflow, "liggghts": time_liggghts, "yade": time_yade}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--tag", default="uniaxial_engines_speed")
    a = ap.parse_args(argv)
    runs = {e: [] for e in ENGINES}
    for r in range(a.rounds):
        order = ENGINES[r % 3:] + ENGINES[:r % 3]
        for e in order:
            l0 = os.getloadavg()[0]
            t = TIMERS[e](a.steps)
            t.update(rate=t["clumps"] * t["steps"] / t["wall_s"], round=r, load_before=l0, load_after=os.getloadavg()[0])
            runs[e].append(t)
            print(f"round {r} {e}: {t['rate']:.4g} clump-steps/s ({t['steps']} steps in {t['wall_s']:.2f} s, "
                  f"load {l0:.2f} -> {t['load_after']:.2f})", flush=True)
    best = {e: max(v, key=lambda t: t["rate"]) for e, v in runs.items()}
    spread = {e: (max(t["rate"] for t in v) - min(t["rate"] for t in v)) / max(t["rate"] for t in v)
              for e, v in runs.items()}
    info = dict(date=time.strftime("%Y-%m-%d %H:%M:%S"), machine=platform.platform(), cpus=os.cpu_count(),
                steps=a.steps, rounds=a.rounds)
    out = Path(__file__).resolve().parent / "results"
    out.mkdir(exist_ok=True)
    (out / f"{a.tag}.json").write_text(json.dumps(dict(info=info, runs=runs), indent=1))
    lines = [f"# Speed on the uniaxial clump case ({info['date']})", "",
             f"`python benchmarks/bench_uniaxial_engines.py --steps {a.steps} --rounds {a.rounds}` on {info['machine']} "
             f"({info['cpus']} cores), one core per engine; the first settling stage of miyata-uniaxial-3d seed 1 "
             "(80 clumps x 8 spheres), each engine's own loop time.", "",
             "| engine | best clump-steps/s | spread over rounds | demflow / engine | loads (before -> after) |",
             "|---|---|---|---|---|"]
    for e in ENGINES:
        loads = ", ".join(f"{t['load_before']:.2f}->{t['load_after']:.2f}" for t in runs[e])
        ratio = best["demflow"]["rate"] / best[e]["rate"]
        lines.append(f"| {e} | {best[e]['rate']:.4g} | {spread[e]:.0%} | {ratio:.2f} | {loads} |")
    (out / f"{a.tag}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
