"""Side-by-side speed of demflow, LIGGGHTS and YADE on the same dense 3D Hertz sphere packing.

    python benchmarks/bench_engines3d.py [--sizes 10000 100000] [--steps S] [--rounds R]

The packing is benchmarks/packing3d.py's ``dense_fcc(n)``: an FCC lattice of glass-like spheres
(R = 1 mm ± 0.2 %), periodic along x and y, on a floor plane, Hertz-Mindlin μ = 0.5, e = 0.9, gravity;
about 3 touching contacts per sphere from the start (a dense, stressed, nearly static packing).
The timing protocol is bench_engines.py's (its ``ExternalRunner`` is used): each engine's time of
steps S..2S of the scene, recording nothing:
    rate = N x S / (time of steps S..2S)      [sphere-steps per second]
demflow: one thread, steps S..2S of one simulation timed in process (JIT warm); engine ``demflow-1`` runs the scene
as written (demflow's own conventions), ``demflow-1-matched`` the LIGGGHTS deck's scene (the model LIGGGHTS runs).  LIGGGHTS: one
process, no MPI, the benchmark deck (``Liggghts3DEngine(benchmark=True)``: atoms from a data file,
the floor a primitive wall, no dumps; the scene in LIGGGHTS's conventions, :func:`liggghts_scene`: shear spring
'total', history projected without rescaling),
its ``run 2S`` run as ``run S`` and ``run S pre no`` (the single run's trajectory) and the second run's
"Loop time" taken (in process, as demflow's).
YADE ``-j1``, the benchmark deck (``Yade3DEngine(benchmark=True)``: no PyRunner during the steps),
t(2S) - t(S) of two subprocesses (wall, and CPU from getrusage of the children).  ``--rounds`` rounds, the engine order rotating each round; the best round is reported
with the spread (best - worst)/best, all rounds kept, and the load average before and after each.

Equivalence: after every timed run each engine reports the touching sphere-sphere contacts
(centres closer than r_i + r_j) and the kinetic energy at its last step (S and 2S); YADE and demflow
also the floor contacts.  Same packing, same law: the counts agree to a few per mille.

Results: benchmarks/results/<tag>.json and .md (tag default ``engines3d_speed``).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numba  # noqa: E402

from bench_engines import (ExternalRunner, acceptance_lines, cpu_text, liggghts_timing_text,  # noqa: E402
                           per_round_ratios)
from packing3d import dense_fcc  # noqa: E402
from demflow import build  # noqa: E402
from demflow.atomic import write_text_atomic  # noqa: E402
from demflow.engines.liggghts3d import Liggghts3DEngine, read_benchmark_output  # noqa: E402
from demflow.engines.yade3d import Yade3DEngine  # noqa: E402
from demflow.jit import set_threads  # noqa: E402

MATCHED = "demflow-1-matched"  # demflow, one thread, the scene in LIGGGHTS's conventions (liggghts_scene)
ENGINE_ORDER = ("demflow-1", MATCHED, "liggghts", "yade")
ALL_ENGINES = ("demflow-1", "demflow-2", MATCHED, "liggghts", "yade")


def liggghts_scene(scene):
    """The scene in LIGGGHTS's conventions: the Mindlin spring on the total tangential displacement, and the
    history projected onto the tangent plane after the increment without rescaling (``history_rotation='project'``,
    LIGGGHTS 3.8.0's rule; demflow's default rescales it: capabilities feature 'history-rotation').  The LIGGGHTS
    deck is this scene's; demflow runs it as engine ``demflow-1-matched`` (the same model as the LIGGGHTS run)."""
    return dataclasses.replace(scene, laws={k: dataclasses.replace(v, shear_spring="total", history_rotation="project")
                                            for k, v in scene.laws.items()})


def demflow_summary(sim):
    p, n = sim.pairs, sim.n
    touching = p.ovl > 0
    sp = sim.spheres
    return dict(steps=int(sim.step), sphere_contacts=int((touching & (p.j < n)).sum()),
                plane_contacts=int((touching & (p.j >= n)).sum()),
                kinetic=float(0.5 * np.sum(sp.mass * (sp.vel ** 2).sum(1))))


def time_demflow(scene, S, threads, checkpoints=()):
    """Build, run S steps, then time S more: the same quantity as t(2S) - t(S).  Each step of ``checkpoints`` (the
    other engines' step counts) is summarised on the way: those below S during the first, untimed S steps (run in
    pieces: the same trajectory), those beyond 2S after the timed run, untimed."""
    set_threads(threads)
    t0 = time.perf_counter()
    sim = build(scene)
    more = {}
    for k in sorted(set(checkpoints)):  # the other engines' step counts below S (YADE's with --yade-steps)
        if 0 < k < S:
            sim.run(k - sim.step)
            more[k] = demflow_summary(sim)
    sim.run(S - sim.step)
    t_S = time.perf_counter() - t0
    at_S = demflow_summary(sim)
    reb0 = sim.n_rebuilds
    c0, t1 = time.process_time(), time.perf_counter()
    sim.run(S)
    wall, cpu = time.perf_counter() - t1, time.process_time() - c0
    out = dict(t_S=t_S, rebuilds=sim.n_rebuilds - reb0, at_S=at_S, at_2S=demflow_summary(sim))
    for k in sorted(set(checkpoints)):
        if k > sim.step:
            sim.run(k - sim.step)
            more[k] = demflow_summary(sim)
    if more:
        out["checkpoints"] = more
    return wall, cpu, out


def liggghts_at_S(d):
    """The benchmark summary at step S of a deck run in two parts (bench_engines.split_run): the end of the
    log's first run."""
    return read_benchmark_output(Path(d), run=0)


def load():
    return [round(x, 2) for x in os.getloadavg()]


def bench_size(n, S, rounds, timeout, engines, liggghts_factor=1, yade_S=None):
    """``yade_S``: YADE's S at this size (default S: the same steps as the others)."""
    t0 = time.perf_counter()
    scene = dense_fcc(n, name=f"engines3d{n}")
    sim0 = build(scene)
    info = dict(n=n, steps_S=S, dt=float(sim0.dt), skin=float(sim0.skin), build_s=time.perf_counter() - t0,
                pairs_per_sphere_0=len(sim0.pairs.i) / n)
    del sim0
    print(f"N={n}: scene built in {info['build_s']:.1f} s (dt {info['dt']:.3e}); S = {S} steps", flush=True)
    root = Path(tempfile.mkdtemp(prefix=f"bench_engines3d_{n}_"))
    t0 = time.perf_counter()
    makers = {"liggghts": (liggghts_scene(scene), Liggghts3DEngine(benchmark=True)),
              "yade": (scene, Yade3DEngine(benchmark=True))}
    steps = {e: S * (liggghts_factor if e == "liggghts" else 1) for e in engines}
    if "yade" in steps and yade_S is not None:
        steps["yade"] = int(yade_S)
    runners = {e: ExternalRunner(e, makers[e][0], steps[e], root, timeout, E=makers[e][1]) for e in makers
               if e in engines}
    info["deck_write_s"] = time.perf_counter() - t0
    meas = {e: [] for e in engines}
    loads = []
    for rnd in range(rounds):
        order = list(engines[rnd % len(engines):]) + list(engines[:rnd % len(engines)])
        before = load()
        for e in order:
            if e.startswith("demflow"):
                wall, cpu, extra = time_demflow(liggghts_scene(scene) if e == MATCHED else scene, steps[e],
                                                int(e.split("-")[1]),
                                                checkpoints=[k * steps[x] for x in engines for k in (1, 2)]
                                                if rnd == 0 else ())
                m = dict(round=rnd, dt_wall=wall, dt_cpu=cpu, **extra)
            else:
                r = runners[e]
                m = dict(round=rnd, **r.measure())
                m["at_S"] = dict(liggghts_at_S(r.dirs[2]) if r.in_process else r.E.read(None, None, r.dirs[1]))
                m["at_2S"] = dict(r.E.read(None, None, r.dirs[2]))
            m["rate_wall"] = n * steps[e] / m["dt_wall"] if m["dt_wall"] > 0 else float("nan")
            m["rate_cpu"] = n * steps[e] / m["dt_cpu"] if m["dt_cpu"] > 0 else float("nan")
            meas[e].append(m)
            print(f"  round {rnd} {e:>10}: {m['rate_wall']:.3e} sphere-steps/s (wall), {m['rate_cpu']:.3e} (cpu); "
                  + (f"t(S) {m['t_S']:.2f} s, t(2S) {m['t_2S']:.2f} s" if "t_2S" in m else
                     f"loop times {m['loop_S']:.2f} s, {m['dt_wall']:.2f} s (process {m['t_process']:.2f} s)"
                     if "loop_S" in m else f"steps S..2S in {m['dt_wall']:.2f} s, rebuilds {m['rebuilds']}")
                  + f"; contacts/sphere at 2S {m['at_2S']['sphere_contacts'] / n:.4f}", flush=True)
        loads.append(dict(round=rnd, order=order, load_before=before, load_after=load()))
        print(f"  round {rnd}: load average before {before}, after {loads[-1]['load_after']}", flush=True)
    best = {}
    for e, ms in meas.items():
        rates = [m["rate_wall"] for m in ms]
        b = ms[int(np.nanargmax(rates))] if np.any(np.isfinite(rates)) else ms[0]
        best[e] = dict(rate_wall=b["rate_wall"], rate_cpu=float(max(m["rate_cpu"] for m in ms)),
                       steps_S=steps[e], rate_wall_median=float(np.nanmedian(rates)),
                       spread=float((np.nanmax(rates) - np.nanmin(rates)) / np.nanmax(rates)),
                       at_S=b["at_S"], at_2S=b["at_2S"], rounds=ms)
    shutil.rmtree(root, ignore_errors=True)
    return dict(n=n, info=info, loads=loads, engines=best)


def markdown(rows, info):
    lines = [f"# demflow vs LIGGGHTS vs YADE, 3D dense Hertz spheres: sphere-steps per second ({info['date']})", "",
             f"Machine: {info['cores']} cores ({info['cpu']}), shared; numba {info['numba']}, YADE {info['yade']}, "
             f"LIGGGHTS {info['liggghts']}. Command: `python benchmarks/bench_engines3d.py "
             f"{' '.join(info['argv'])}`.", "",
             "Scene: benchmarks/packing3d.py `dense_fcc(N)` (FCC lattice, R = 1 mm ± 0.2 %, periodic x/y, floor, "
             "Hertz-Mindlin E = 70 GPa, ν = 0.3, μ = 0.5, e = 0.9, gravity). rate = N·S / (time of steps S..2S), "
             "best of the rounds (wall clock), spread = (best − worst)/best over the rounds, CPU-time rate in brackets. "
             "demflow 1 thread, steps S..2S in process, in its own conventions (the scene as written: shear spring "
             "'incremental', history rescaled when the normal turns) and in LIGGGHTS's (`demflow-1-matched`: shear "
             "spring 'total', history projected after the increment without rescaling — the model LIGGGHTS runs); "
             "LIGGGHTS one process (data file, primitive floor wall, "
             "no output during the run, shear spring 'total' = its matching mode), " + liggghts_timing_text(rows)
             + "; YADE `-j1` (no PyRunner), t(2S) − t(S) of two processes.", "",
             "S is the step count of the shorter run (LIGGGHTS's and YADE's S are given after their rates; "
             "each engine's rate is over its own steps S..2S of the same packing).", "",
             "| N | S | demflow 1 thr | demflow 1 thr, LIGGGHTS's conventions | LIGGGHTS | YADE -j1 | demflow/LIGGGHTS "
             "| demflow/LIGGGHTS, both in LIGGGHTS's conventions | demflow/YADE |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        e = row["engines"]
        cell = lambda k: (f"{e[k]['rate_wall']:.3e} ±{e[k]['spread']:.0%} ({cpu_text(e[k]['rate_cpu'])})"  # noqa: E731
                          if k in e else "—")
        ratio = lambda a, b: (f"{e[a]['rate_wall'] / e[b]['rate_wall']:.2f}×" if a in e and b in e else "—")  # noqa: E731
        lig = f" S = {e['liggghts']['steps_S']}" if "liggghts" in e else ""
        yad = f" S = {e['yade']['steps_S']}" if "yade" in e else ""
        lines.append(f"| {row['n']:,} | {row['info']['steps_S']} | {cell('demflow-1')} | {cell(MATCHED)} | "
                     f"{cell('liggghts')}{lig} | {cell('yade')}{yad} | {ratio('demflow-1', 'liggghts')} | "
                     f"{ratio(MATCHED, 'liggghts')} | {ratio('demflow-1', 'yade')} |")
    if any("demflow-2" in r["engines"] for r in rows):
        lines += ["", "demflow 2 threads: " + ", ".join(
            f"N = {r['n']:,}: {r['engines']['demflow-2']['rate_wall']:.3e}" for r in rows if "demflow-2" in r["engines"])]
    lines += ["", "Acceptance (issue 13, one core): demflow ≥ 1.5× LIGGGHTS and ≥ 10× YADE.", ""]
    lines += acceptance_lines(rows, 1.5, 10.0, label=" (demflow in its own conventions)")
    lines += acceptance_lines(rows, 1.5, 10.0, a=MATCHED, label=" (demflow in LIGGGHTS's conventions, the same model)")
    lines += per_round_ratios(rows)
    lines += per_round_ratios(rows, a=MATCHED)
    lines += ["", "## Rounds (wall-clock rate per engine; load average 1/5/15 min before and after each round)", "",
              "| N | round | order | " + " | ".join(ENGINE_ORDER) + " | load before | load after |",
              "|---|---|---|" + "---|" * len(ENGINE_ORDER) + "---|---|"]
    for row in rows:
        for ld in row["loads"]:
            k = ld["round"]
            cells = [f"{row['engines'][e]['rounds'][k]['rate_wall']:.3e}" if e in row["engines"] else "—"
                     for e in ENGINE_ORDER]
            lines.append(f"| {row['n']:,} | {k} | {', '.join(ld['order'])} | " + " | ".join(cells)
                         + f" | {ld['load_before']} | {ld['load_after']} |")
    lines += ["", "## Equivalence (each engine's runs of the best round against demflow at the same step)", "",
              "Touching sphere-sphere contacts per sphere (centres closer than r_i + r_j; demflow and YADE: at the "
              "last force pass, LIGGGHTS: at the positions after the last step) and kinetic energy (demflow and "
              "YADE: of v_{n-1/2}; LIGGGHTS: of its on-step v_n) after the run; demflow's from its round-0 "
              "simulation continued (untimed) to the same step: for LIGGGHTS and `demflow-1-matched` demflow's run "
              "in LIGGGHTS's conventions (when it ran), for the others demflow's own.", "",
              "| N | engine | steps | contacts/sphere | demflow's | rel. diff. | floor contacts | KE [J] | demflow's | "
              "rel. diff. |", "|---|---|---|---|---|---|---|---|---|---|"]
    def refs(d0):
        ref = {}
        for m in d0["rounds"]:
            for key in ("at_S", "at_2S"):
                ref.setdefault(m[key]["steps"], m[key])
            for k, v in m.get("checkpoints", {}).items():
                ref.setdefault(int(k), v)
        return ref

    for row in rows:
        e = row["engines"]
        d0 = e.get("demflow-1") or e.get("demflow-2") or e.get(MATCHED)
        if d0 is None:
            continue
        ref = refs(d0)
        # LIGGGHTS against demflow in LIGGGHTS's conventions when that ran (the same model), else demflow's own
        ref_lig = refs(e[MATCHED]) if MATCHED in e else ref
        for name, b in e.items():
            for key in ("at_S", "at_2S"):
                sm = b[key]
                r = (ref_lig if name in ("liggghts", MATCHED) else ref).get(sm["steps"])
                n = row["n"]
                c = sm["sphere_contacts"] / n
                cr = r["sphere_contacts"] / n if r else float("nan")
                fc = sm.get("plane_contacts")
                lines.append(f"| {n:,} | {name} | {sm['steps']} | {c:.4f} | {cr:.4f} | {abs(c - cr) / cr:.1e} | "
                             f"{'—' if fc is None else fc} | {sm['kinetic']:.5e} | "
                             f"{r['kinetic'] if r else float('nan'):.5e} | "
                             f"{abs(sm['kinetic'] - r['kinetic']) / r['kinetic'] if r else float('nan'):.1e} |")
    if info.get("notes"):
        lines += ["", "Notes: " + info["notes"]]
    return "\n".join(lines) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    p.add_argument("--steps", type=int, nargs="+", default=None,
                   help="S per size (the runs are S and 2S steps); default max(20, 3e6/N): 300 at 1e4, 30 at 1e5")
    p.add_argument("--rounds", type=int, default=3, help="timing rounds (best reported)")
    p.add_argument("--liggghts-factor", type=int, default=1,
                   help="LIGGGHTS runs factor x S and 2 x factor x S steps (default 1: the same steps, the same "
                        "state of the packing, as the other engines)")
    p.add_argument("--yade-steps", type=int, nargs="+", default=None,
                   help="YADE's S per size (default: the others' S).  YADE is 20-25x slower than demflow here, so "
                        "its S..2S steps take long enough to time at a fraction of the others' S: at 1e5 spheres "
                        "and S = 400 a round's YADE runs alone took 17 min (2026-12-02), of which ~3 min a process "
                        "was setup")
    p.add_argument("--engines", nargs="+", default=list(ENGINE_ORDER), choices=ALL_ENGINES)
    p.add_argument("--timeout", type=float, default=900.0, help="per engine subprocess [s]")
    p.add_argument("--yade-max", type=int, default=None,
                   help="run YADE only at sizes up to this N (at 1e5 spheres and S = 400 its S-step runs took "
                        "388-432 s and its 2S-step runs 620-665 s: 2026-12-02, an Intel Xeon host)")
    p.add_argument("--notes", default="", help="free text for the report (e.g. the machine's load)")
    p.add_argument("--out", default=str(Path(__file__).resolve().parent / "results"))
    p.add_argument("--tag", default="engines3d_speed")
    a = p.parse_args(argv)
    t_all = time.perf_counter()
    uptime_start = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()

    print("warming up the JIT ...", flush=True)
    for nt in sorted({int(e.split("-")[1]) for e in a.engines if e.startswith("demflow")}):
        set_threads(nt)
        build(dense_fcc(500)).run(20)

    rows = []
    for k, n in enumerate(a.sizes):
        S = a.steps[min(k, len(a.steps) - 1)] if a.steps else max(20, int(round(3e6 / n)))
        engines = [e for e in a.engines if not (e == "yade" and a.yade_max is not None and n > a.yade_max)]
        yS = a.yade_steps[min(k, len(a.yade_steps) - 1)] if a.yade_steps else None
        rows.append(bench_size(n, S, a.rounds, a.timeout, engines, a.liggghts_factor, yS))

    def _ver(f):
        try:
            return f()
        except Exception as exc:  # noqa: BLE001
            return f"unknown ({exc})"

    info = dict(date=time.strftime("%Y-%m-%d %H:%M:%S %Z"), python=platform.python_version(), numba=numba.__version__,
                numpy=np.__version__, cpu=platform.processor() or platform.machine(), cores=os.cpu_count(),
                yade=_ver(Yade3DEngine().version), liggghts=_ver(Liggghts3DEngine().version),
                uptime_start=uptime_start,
                uptime_end=subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip(),
                total_s=time.perf_counter() - t_all, args=vars(a), argv=list(sys.argv[1:] if argv is None else argv),
                notes=a.notes)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / f"{a.tag}.json", json.dumps(dict(info=info, rows=rows), indent=2))
    md = markdown(rows, info)
    write_text_atomic(out / f"{a.tag}.md", md)
    print()
    print(md)
    print(f"written {out / (a.tag + '.json')} and {out / (a.tag + '.md')} (total {info['total_s']:.0f} s)")


if __name__ == "__main__":
    main()
