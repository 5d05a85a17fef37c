"""Side-by-side speed of demflow, LIGGGHTS and YADE on the same dense frictional 2D packing.

    python benchmarks/bench_engines.py [--sizes 10000 100000] [--steps S [S ...]] [--rounds R]

The packing is bench_dem's (``make_scene``: polydisperse discs in a box of four walls,
kn = ks = 1e6, friction 0.5, its Gaussian agitation velocities), made engine-expressible:
the normal force is kN x overlap (``ContactModel(normal="overlap")``, what YADE and
LIGGGHTS compute), no global damping and no dashpots (LIGGGHTS has no global damping; the
shared linear law then matches exactly, see shared/ENGINES.md).  Because the overlap law
turns bench_dem's residual overlaps into forces, the packing is first relaxed in demflow
(``--relax`` steps with mass-proportional damping ``--alpha``); the relaxed positions with
bench_dem's agitation velocities are the benchmark's initial state: dense (~3.6 contacts
per disc), stressed, agitated, the same in every engine.

Each engine runs that scene recording nothing (``Outputs(every=0)``; demflow with 1 and with 2
threads, YADE ``-j1``, LIGGGHTS one process, no MPI) and is timed over steps S..2S:
    rate = N x S / (time of steps S..2S)      [particle-steps per second]
(demflow: wall time of steps S..2S of one simulation, in process, JIT warm; LIGGGHTS: the same
interval in its process, its deck's ``run 2S`` run as ``run S`` and ``run S pre no`` and the second
run's "Loop time" taken: no start-up, deck reading or setup in it, and no drift of the host between
two processes, which made t(2S) - t(S) scatter by up to 48 %).  YADE: runs of S and of 2S steps,
t(2S) - t(S) of their wall times, also of their CPU times (getrusage of the children).  ``--rounds`` rounds are run,
the engine order rotating each round; the best round is reported, all are kept.

Physical equivalence: a separate, untimed run of S steps per engine records the snapshots
at steps 0 and S; reported per engine are the contacts per disc, the normal force on each
wall summed from its contacts (equal to round-off at step 0: same geometry, same law), and
at step S the kinetic energy, the wall forces and the contacts per disc (a chaotic dense
packing: agreement within a few per cent, not to round-off).

Results: benchmarks/results/<tag>.json and .md (tag default ``engines_speed``).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import re
import resource
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

from bench_dem import contacts_per_disc, make_scene  # noqa: E402
from demflow import ContactModel, Discs, GlobalDamping, Outputs, build  # noqa: E402
from demflow.atomic import write_text_atomic  # noqa: E402
from demflow.engines import LiggghtsEngine, YadeEngine  # noqa: E402
from demflow.jit import set_threads  # noqa: E402

ENGINE_ORDER = ("demflow-1", "demflow-2", "liggghts", "yade")


def engine_scene(n, relax=2000, alpha=30.0, threads=2):
    """bench_dem's packing of n discs, relaxed under the overlap law, undamped, with
    bench_dem's agitation velocities; returns (scene, info)."""
    t0 = time.perf_counter()
    sc = make_scene(n)
    v = np.asarray(sc.discs.velocity, dtype=float)
    prep = dataclasses.replace(sc, damping=GlobalDamping(alpha=alpha), contact_model=ContactModel(normal="overlap"),
                               discs=dataclasses.replace(sc.discs, velocity=None), outputs=Outputs(every=0))
    sim = build(prep)
    if relax > 0:
        set_threads(threads)
        sim.run(relax, threads=threads)
    ke_left = float(0.5 * np.sum(sim.mass * (sim.vx ** 2 + sim.vy ** 2)))
    discs = Discs(sim.x.copy(), sim.y.copy(), np.asarray(sc.discs.radius, dtype=float), "grain", velocity=v)
    scene = dataclasses.replace(sc, name=f"engines{n}", discs=discs, damping=GlobalDamping(),
                                contact_model=ContactModel(normal="overlap"), outputs=Outputs(every=0))
    info = dict(prep_s=time.perf_counter() - t0, relax_steps=relax, relax_alpha=alpha,
                relax_kinetic_left=ke_left, agitation_kinetic=float(0.5 * np.sum(sim.mass * (v ** 2).sum(1))))
    return scene, info


# ------------------------------------------------------------------ timing
def _time_subprocess(cmd, cwd, timeout):
    env = dict(os.environ, OMP_NUM_THREADS="1")
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with open(Path(cwd) / "engine.log", "w") as fh:
        proc = subprocess.run(cmd, cwd=cwd, stdout=fh, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                              env=env, timeout=timeout)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    if proc.returncode != 0:
        tail = (Path(cwd) / "engine.log").read_text(errors="replace")[-1500:]
        raise RuntimeError(f"{cmd[0]} exited with {proc.returncode} in {cwd}:\n{tail}")
    return wall, cpu


def _completed(engine, d):
    if engine == "liggghts":
        log = d / "log.liggghts"
        return log.exists() and "DEMFLOW-COMPLETE" in log.read_text(errors="replace")
    f = d / "yade_out.json"
    return f.exists() and json.loads(f.read_text()).get("complete", False)


def _liggghts_neighbor_builds(d):
    for line in (d / "log.liggghts").read_text(errors="replace").splitlines():
        if line.startswith("Neighbor list builds"):
            return int(line.split("=")[1])
    return None


LOOP_TIME = re.compile(r"^Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps")


def liggghts_loop_times(text):
    """[(seconds, steps), ...]: the "Loop time" line LIGGGHTS prints after each ``run`` (the wall time of that
    run's time-step loop, its setup excluded), in order."""
    out = []
    for line in text.splitlines():
        m = LOOP_TIME.match(line)
        if m:
            out.append((float(m.group(1)), int(m.group(3))))
    return out


def split_run(deck, S):
    """Rewrite the deck's one ``run 2S`` as ``run S`` and ``run S pre no``, so that LIGGGHTS times steps S..2S in its
    own process (the second run's loop time): demflow's quantity, without two processes' start-up, reading and
    setup.  ``pre no`` skips the second run's setup, so the run continues as the single ``run 2S`` does; with the
    setup (forces recomputed, neighbours rebuilt, atoms re-sorted) the kinetic energy of the 3D benchmark packing
    differed from the single run's by 4e-3 one step after the split and 2.4e-4 forty steps after
    (tests/test_bench_timing.py)."""
    lines = Path(deck).read_text().splitlines()
    at = [k for k, line in enumerate(lines) if line.strip() == f"run {2 * S}"]
    if len(at) != 1:
        raise RuntimeError(f"{deck}: expected one 'run {2 * S}' line, found {len(at)}")
    lines[at[0]:at[0] + 1] = [f"run {S}", f"run {S} pre no"]
    write_text_atomic(deck, "\n".join(lines) + "\n")


class ExternalRunner:
    """Decks written once; each call times one subprocess run.  YADE: decks of S and 2S steps (rate from
    t(2S) - t(S)).  LIGGGHTS (``in_process``, the default): one deck of 2S steps run as ``run S`` and ``run S pre no``,
    the rate from the second run's loop time (:func:`split_run`); ``in_process=False``: S and 2S decks as YADE's."""

    def __init__(self, engine, scene, S, root, timeout, E=None, in_process=True):
        """``E``: the engine object writing the decks (default the 2D LIGGGHTS or YADE engine)."""
        self.engine, self.timeout, self.S = engine, timeout, S
        self.in_process = in_process and engine == "liggghts"
        self.E = E or (LiggghtsEngine() if engine == "liggghts" else YadeEngine())
        self.E.path()
        self.dirs = {}
        for k in ((2,) if self.in_process else (1, 2)):
            sc = dataclasses.replace(scene, n_steps=k * S)
            d = Path(root) / f"{engine}_{k}S"
            d.mkdir(parents=True, exist_ok=True)
            self.E.write_deck(sc, build(sc), d)
            if self.in_process:
                split_run(d / "deck.in", S)
            self.dirs[k] = d

    def run(self, k):
        d = self.dirs[k]
        for f in ("yade_out.json", "log.liggghts"):
            (d / f).unlink(missing_ok=True)
        wall, cpu = _time_subprocess(self.E.command(d), d, self.timeout)
        if not _completed(self.engine, d):
            raise RuntimeError(f"{self.engine} did not complete in {d}")
        extra = {}
        if self.engine == "liggghts":
            extra["neighbor_builds"] = _liggghts_neighbor_builds(d)
            if self.in_process:
                loops = liggghts_loop_times((d / "log.liggghts").read_text(errors="replace"))
                if [s for _, s in loops] != [self.S, self.S]:
                    raise RuntimeError(f"{d / 'log.liggghts'}: expected two runs of {self.S} steps, found {loops}")
                extra["loop_S"], extra["loop_2S"] = loops[0][0], loops[1][0]
        return wall, cpu, extra

    def measure(self):
        """One timing of steps S..2S: dict(dt_wall, dt_cpu, ...) (LIGGGHTS in process: its loop time; the CPU time
        of that loop alone is not known, dt_cpu NaN; else t(2S) - t(S) of two subprocesses, wall and CPU)."""
        if self.in_process:
            w, c, x = self.run(2)
            return dict(t_process=w, cpu_process=c, loop_S=x["loop_S"], dt_wall=x["loop_2S"], dt_cpu=float("nan"),
                        neighbor_builds_2S=x["neighbor_builds"])
        w1, c1, x1 = self.run(1)
        w2, c2, x2 = self.run(2)
        m = dict(t_S=w1, t_2S=w2, cpu_S=c1, cpu_2S=c2, dt_wall=w2 - w1, dt_cpu=c2 - c1)
        if "neighbor_builds" in x1:
            m["neighbor_builds_S"], m["neighbor_builds_2S"] = x1["neighbor_builds"], x2["neighbor_builds"]
        return m


def time_demflow(scene, S, threads):
    """Build, run S steps, then time S more: the same quantity as t(2S) - t(S)."""
    set_threads(threads)
    t0 = time.perf_counter()
    sim = build(scene)
    sim.run(S, threads=threads)
    t_S = time.perf_counter() - t0
    reb0 = sim.rebuilds
    c0, t1 = time.process_time(), time.perf_counter()
    sim.run(S, threads=threads)
    wall, cpu = time.perf_counter() - t1, time.process_time() - c0
    return wall, cpu, dict(t_S=t_S, rebuilds=sim.rebuilds - reb0, contacts_per_disc_2S=contacts_per_disc(sim),
                           x_checksum=float(np.sum(sim.x * np.arange(1, sim.n + 1)) % 1e6))


def summarise(meas, n, S):
    """Per engine: the best round's rate, the best CPU rate, the median, the spread (best − worst)/best,
    and for the external engines the rate from the shortest t(S) and the shortest t(2S) over the rounds
    (``rate_min_times``: each the least disturbed run; a slow t(S) alone would inflate a round's rate)."""
    best = {}
    for e, ms in meas.items():
        b = max(ms, key=lambda m: m["rate_wall"])
        worst = min(m["rate_wall"] for m in ms)
        best[e] = dict(rate_wall=b["rate_wall"], rate_cpu=max(m["rate_cpu"] for m in ms),
                       rate_wall_median=float(np.median([m["rate_wall"] for m in ms])),
                       spread=(b["rate_wall"] - worst) / b["rate_wall"], rounds=ms)
        if all("t_2S" in m for m in ms):
            d = min(m["t_2S"] for m in ms) - min(m["t_S"] for m in ms)
            best[e]["rate_min_times"] = n * S / d if d > 0 else float("nan")
        else:
            best[e]["rate_min_times"] = b["rate_wall"]  # demflow times steps S..2S directly
    return best


def bench_size(n, S, rounds, relax, alpha, timeout, engines):
    """Time ``engines`` on the n-disc scene over ``rounds`` rounds (module docstring); returns (row, scene)."""
    scene, info = engine_scene(n, relax, alpha)
    sim0 = build(scene)
    info.update(n=n, steps_S=S, dt=float(sim0.dt), contacts_per_disc_0=contacts_per_disc(sim0),
                skin_demflow=float(sim0.skin))
    print(f"N={n}: scene ready in {info['prep_s']:.1f} s (relaxed {relax} steps, contacts/disc "
          f"{info['contacts_per_disc_0']:.2f}, dt {sim0.dt:.3e}); S = {S} steps", flush=True)
    root = Path(tempfile.mkdtemp(prefix=f"bench_engines_{n}_"))
    t0 = time.perf_counter()
    runners = {e: ExternalRunner(e, scene, S, root, timeout) for e in ("liggghts", "yade") if e in engines}
    info["deck_write_s"] = time.perf_counter() - t0
    meas = {e: [] for e in engines}
    for rnd in range(rounds):
        order = list(engines[rnd % len(engines):]) + list(engines[:rnd % len(engines)])
        load_before = os.getloadavg()
        for e in order:
            if e.startswith("demflow"):
                nt = int(e.split("-")[1])
                wall, cpu, extra = time_demflow(scene, S, nt)
                m = dict(round=rnd, dt_wall=wall, dt_cpu=cpu, **extra)
            else:
                m = dict(round=rnd, **runners[e].measure())
            m["rate_wall"] = n * S / m["dt_wall"] if m["dt_wall"] > 0 else float("nan")
            m["rate_cpu"] = n * S / m["dt_cpu"] if m["dt_cpu"] > 0 else float("nan")
            m["order"] = order
            m["load_before"] = [round(v, 2) for v in load_before]
            m["load_after"] = [round(v, 2) for v in os.getloadavg()]
            meas[e].append(m)
            print(f"  round {rnd} {e:>10}: {m['rate_wall']:.3e} particle-steps/s (wall), {m['rate_cpu']:.3e} (cpu); "
                  + (f"t(S) {m['t_S']:.2f} s, t(2S) {m['t_2S']:.2f} s" if "t_2S" in m else
                     f"loop times {m['loop_S']:.2f} s, {m['dt_wall']:.2f} s (process {m['t_process']:.2f} s)"
                     if "loop_S" in m else f"steps S..2S in {m['dt_wall']:.2f} s, rebuilds {m['rebuilds']}"), flush=True)
    best = summarise(meas, n, S)
    shutil.rmtree(root, ignore_errors=True)
    return dict(n=n, info=info, engines=best), scene


# ------------------------------------------------------------------ equivalence
def _summary(res, sim, S):
    """Contacts per disc and wall normal forces (from the contacts) at 0 and S; KE at S."""
    out = {}
    c = res.contacts
    names = sim.wall_names
    for st, lab in ((0, "0"), (S, "S")):
        cs = c[c.step == st]
        disc = cs[cs.j >= 0]
        wall = cs[cs.j < 0]
        out[f"contacts_per_disc_{lab}"] = float((2 * len(disc) + len(wall)) / sim.n)
        out[f"wall_fn_{lab}"] = {w: float(wall[wall.wall == w].fn.sum()) for w in names}
    p = res.particles[res.particles.step == S].sort_values("id")
    ids = p.id.to_numpy().astype(int)
    out["kinetic_trans_S"] = float(0.5 * np.sum(sim.mass[ids] * (p.vx.to_numpy() ** 2 + p.vy.to_numpy() ** 2)))
    out["kinetic_rot_S"] = float(0.5 * np.sum(sim.inertia[ids] * p.omega.to_numpy() ** 2))
    return out


def equivalence(scene, S, engines, timeout):
    sc = dataclasses.replace(scene, n_steps=S, outputs=Outputs(every=S, snapshots=(0, S)))
    sim = build(sc)
    out = {}
    t0 = time.perf_counter()
    set_threads(1)
    out["demflow"] = _summary(build(sc).run(S, threads=1).results(), sim, S)
    for e in ("liggghts", "yade"):
        if e in engines:
            E = LiggghtsEngine() if e == "liggghts" else YadeEngine()
            with tempfile.TemporaryDirectory(prefix=f"bench_engines_check_{e}_") as d:
                res, _ = E.run(sc, d, timeout=timeout)
                out[e] = _summary(res, sim, S)
    ref = out["demflow"]
    for e, s in out.items():
        if e == "demflow":
            continue
        rel = lambda a, b: abs(a - b) / max(abs(b), 1e-300)  # noqa: E731
        s["vs_demflow"] = dict(
            contacts_per_disc_0=rel(s["contacts_per_disc_0"], ref["contacts_per_disc_0"]),
            wall_fn_0_max=max(rel(s["wall_fn_0"][w], ref["wall_fn_0"][w]) for w in ref["wall_fn_0"]),
            contacts_per_disc_S=rel(s["contacts_per_disc_S"], ref["contacts_per_disc_S"]),
            wall_fn_S_max=max(rel(s["wall_fn_S"][w], ref["wall_fn_S"][w]) for w in ref["wall_fn_S"]),
            kinetic_trans_S=rel(s["kinetic_trans_S"], ref["kinetic_trans_S"]),
            kinetic_rot_S=rel(s["kinetic_rot_S"], ref["kinetic_rot_S"]))
    out["check_s"] = time.perf_counter() - t0
    return out


# ------------------------------------------------------------------ report

def acceptance_lines(rows, vs_liggghts: float, vs_yade: float, a: str = "demflow-1", label: str = ""):
    """Markdown lines: per size, demflow (one core; engine ``a``) against LIGGGHTS and YADE, best round against best
    round, each ratio judged against its target ('met' / 'NOT met'); ``label`` after the size (which demflow run)."""
    lines = []
    for row in rows:
        e = row["engines"]
        if a in e and "liggghts" in e:
            rl = e[a]["rate_wall"] / e["liggghts"]["rate_wall"]
            txt = (f"- N = {row['n']:,}{label}: vs LIGGGHTS {rl:.2f}× "
                   f"({'met' if rl >= vs_liggghts else 'NOT met'})")
            if "yade" in e:
                ry = e[a]["rate_wall"] / e["yade"]["rate_wall"]
                txt += f", vs YADE {ry:.1f}× ({'met' if ry >= vs_yade else 'NOT met'})"
            lines.append(txt + ".")
    return lines


def per_round_ratios(rows, a="demflow-1", b="liggghts"):
    """Markdown lines: the ratio rate(a)/rate(b) of the two engines' runs within each round (run back to
    back, so both see nearly the same state of a host whose speed drifts), min / median / max over the
    rounds per size.  A ratio of the best rounds (the tables above) can pair a fast moment of one engine
    with a slow moment of the other; the per-round median cannot."""
    lines = ["", f"Per-round ratio {a} / {b} (both runs of the same round), min / median / max over the rounds:", "",
             "| N | rounds | min | median | max |", "|---|---|---|---|---|"]
    for row in rows:
        e = row["engines"]
        if a not in e or b not in e:
            continue
        ra = {m["round"]: m["rate_wall"] for m in e[a]["rounds"]}
        rb = {m["round"]: m["rate_wall"] for m in e[b]["rounds"]}
        q = np.array([ra[k] / rb[k] for k in sorted(set(ra) & set(rb)) if rb[k] > 0])
        q = q[np.isfinite(q)]
        if q.size:
            lines.append(f"| {row['n']:,} | {q.size} | {q.min():.2f}× | {float(np.median(q)):.2f}× | {q.max():.2f}× |")
    return lines


def cpu_text(rate):
    """A CPU-time rate for the tables: 'n/a' where the engine's CPU time of the interval is not known."""
    return "n/a" if not np.isfinite(rate) else f"{rate:.2e}"


def liggghts_timing_text(rows):
    """How the rows' LIGGGHTS rates were measured (results of before 2026-11-27 hold two processes' times)."""
    ms = [m for row in rows for m in row["engines"].get("liggghts", {}).get("rounds", [])]
    if ms and all("loop_S" in m for m in ms):
        return ("LIGGGHTS one process, its deck's `run 2S` run as `run S` and `run S pre no` (no second setup: the "
                "single run's trajectory), steps S..2S timed in process (the second run's \"Loop time\"; no CPU time "
                "of its own: n/a)")
    return "LIGGGHTS one process, t(2S) − t(S) of two processes"


def markdown(rows, info):
    lines = [f"# demflow vs LIGGGHTS vs YADE: particle-steps per second ({info['date']})", "",
             f"Machine: {info['cores']} cores ({info['cpu']}); numba {info['numba']} "
             f"({info['threading_layer']}), {info['yade']}, LIGGGHTS {info['liggghts']}. "
             f"Command: `{info.get('command', '')}`.", "",
             f"Notes: {info.get('notes') or '—'}", "",
             *([f"Analysis (after the run): {info['analysis']}", ""] if info.get("analysis") else []),
             "Same scene in every engine: bench_dem's dense polydisperse packing relaxed under the overlap law "
             "(kN = kS = 1e6, μ = 0.5, no damping, four fixed walls, bench_dem's agitation). "
             "rate = N·S / (time of steps S..2S), best of the rounds (wall clock) ± spread = (best − worst)/best "
             "over the rounds; the best CPU-time rate in brackets. "
             "demflow: steps S..2S timed in process; " + liggghts_timing_text(rows) + "; YADE `-j1`: t(2S) − t(S) "
             "of two processes.", "",
             "| N | S | demflow 1 thr | demflow 2 thr | LIGGGHTS | YADE -j1 | demflow(1)/LIGGGHTS | "
             "demflow(1)/YADE | demflow(2)/LIGGGHTS | demflow(2)/YADE |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        e = row["engines"]
        cell = lambda k: (f"{e[k]['rate_wall']:.3e} ±{100 * e[k].get('spread', float('nan')):.0f}% "  # noqa: E731
                          f"({cpu_text(e[k]['rate_cpu'])})" if k in e else "—")
        ratio = lambda a, b: (f"{e[a]['rate_wall'] / e[b]['rate_wall']:.2f}×" if a in e and b in e else "—")  # noqa: E731
        lines.append(f"| {row['n']:,} | {row['info']['steps_S']} | {cell('demflow-1')} | {cell('demflow-2')} | "
                     f"{cell('liggghts')} | {cell('yade')} | {ratio('demflow-1', 'liggghts')} | "
                     f"{ratio('demflow-1', 'yade')} | {ratio('demflow-2', 'liggghts')} | {ratio('demflow-2', 'yade')} |")
    for key, what in (("rate_wall_median", "Median over the rounds (less sensitive to a host whose speed changes "
                                             "between the S and the 2S run of one round)"),
                      ("rate_min_times", "Rate from the shortest t(S) and the shortest t(2S) over the rounds (engines "
                                         "timed by two processes; a round whose t(S) run alone was disturbed reports too "
                                         "high a rate; engines timed in process: their best round)")):
        lines += ["", what + ", one core:", "",
                  "| N | demflow 1 thr | LIGGGHTS | YADE -j1 | demflow(1)/LIGGGHTS | demflow(1)/YADE |",
                  "|---|---|---|---|---|---|"]
        for row in rows:
            e = row["engines"]
            mt = lambda k: e[k].get(key, float("nan")) if k in e else float("nan")  # noqa: E731
            lines.append(f"| {row['n']:,} | {mt('demflow-1'):.3e} | {mt('liggghts'):.3e} | {mt('yade'):.3e} | "
                         f"{mt('demflow-1') / mt('liggghts'):.2f}× | {mt('demflow-1') / mt('yade'):.2f}× |")
    lines += ["", "Acceptance (issue 18 item 5, one core): demflow ≥ 3× LIGGGHTS at 1e4 and 1e5 discs "
              "(earlier targets: ≥ 15× YADE).", ""]
    lines += acceptance_lines(rows, 3.0, 15.0)
    lines += per_round_ratios(rows)
    lines += ["", "## Rounds (wall-clock rate; load average 1/5/15 min before the round and after each engine)", "",
              "| N | round | order | engine | rate | load before round | load after |", "|---|---|---|---|---|---|---|"]
    for row in rows:
        for name, b in row["engines"].items():
            for m in b["rounds"]:
                lines.append(f"| {row['n']:,} | {m['round']} | {', '.join(m.get('order', []))} | {name} | "
                             f"{m['rate_wall']:.3e} | {m.get('load_before', '')} | {m.get('load_after', '')} |")
    lines += ["", "## Physical equivalence (untimed run of S steps, snapshots at 0 and S)", "",
              "| N | engine | contacts/disc at 0 | Σ wall Fn at 0 | contacts/disc at S | Σ wall Fn at S | KE trans at S | "
              "KE rot at S | max rel. diff. vs demflow (Fn at 0 / Fn at S / KE at S) |",
              "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        eq = row.get("equivalence")
        if not eq:
            continue
        for e in ("demflow", "liggghts", "yade"):
            if e not in eq:
                continue
            s = eq[e]
            v = s.get("vs_demflow")
            dif = (f"{v['wall_fn_0_max']:.1e} / {v['wall_fn_S_max']:.1e} / {v['kinetic_trans_S']:.1e}" if v else "—")
            lines.append(f"| {row['n']:,} | {e} | {s['contacts_per_disc_0']:.3f} | {sum(s['wall_fn_0'].values()):.6e} | "
                         f"{s['contacts_per_disc_S']:.3f} | {sum(s['wall_fn_S'].values()):.4e} | "
                         f"{s['kinetic_trans_S']:.4e} | {s['kinetic_rot_S']:.3e} | {dif} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    p.add_argument("--steps", type=int, nargs="+", default=None,
                   help="S (the runs are S and 2S steps), one per size (the last repeats); default min(1000, 2e7/N): "
                        "1000 at 1e4, 200 at 1e5")
    p.add_argument("--rounds", type=int, default=2, help="timing rounds (best reported)")
    p.add_argument("--relax", type=int, default=2000, help="demflow relaxation steps before the benchmark state")
    p.add_argument("--alpha", type=float, default=30.0, help="mass-proportional damping during the relaxation")
    p.add_argument("--engines", nargs="+", default=list(ENGINE_ORDER), choices=ENGINE_ORDER)
    p.add_argument("--yade-max", type=int, default=None,
                   help="run YADE only at sizes up to this N (at 1e5 discs one YADE round of S = 400 takes ~5 min)")
    p.add_argument("--no-check", action="store_true", help="skip the physical-equivalence runs")
    p.add_argument("--timeout", type=float, default=600.0, help="per engine subprocess [s]")
    p.add_argument("--out", default=str(Path(__file__).resolve().parent / "results"))
    p.add_argument("--tag", default="engines_speed")
    p.add_argument("--render", metavar="JSON", help="rewrite the .md of an existing results file and stop")
    p.add_argument("--notes", default="", help="conditions of the measurement, written into the results")
    a = p.parse_args(argv)
    if a.render:
        data = json.loads(Path(a.render).read_text())
        if a.notes:  # an analysis added after the run, kept apart from the notes taken with it
            data["info"]["analysis"] = a.notes
            write_text_atomic(a.render, json.dumps(data, indent=2))
        for row in data["rows"]:
            row["engines"] = summarise({e: b["rounds"] for e, b in row["engines"].items()}, row["n"],
                                       row["info"]["steps_S"])
        write_text_atomic(Path(a.render).with_suffix(".md"), markdown(data["rows"], data["info"]))
        print(markdown(data["rows"], data["info"]))
        return
    t_all = time.perf_counter()

    print("warming up the JIT ...", flush=True)
    warm, _ = engine_scene(400, relax=50)
    for nt in (1, 2):
        set_threads(nt)
        build(warm).run(50, threads=nt)
        build(dataclasses.replace(warm, outputs=Outputs(every=25, snapshots=(0, 50)))).run(50, threads=nt).results()

    rows = []
    for k, n in enumerate(a.sizes):
        S = a.steps[min(k, len(a.steps) - 1)] if a.steps else max(10, int(round(min(1000.0, 2e7 / n))))
        engines = [e for e in a.engines if not (e == "yade" and a.yade_max is not None and n > a.yade_max)]
        row, scene = bench_size(n, S, a.rounds, a.relax, a.alpha, a.timeout, engines)
        if not a.no_check:
            print(f"  equivalence run ({S} steps, snapshots at 0 and {S}) ...", flush=True)
            row["equivalence"] = equivalence(scene, S, engines, a.timeout)
            for e, s in row["equivalence"].items():
                if isinstance(s, dict):
                    print(f"    {e:>8}: contacts/disc {s['contacts_per_disc_0']:.3f} -> {s['contacts_per_disc_S']:.3f}, "
                          f"sum wall Fn {sum(s['wall_fn_0'].values()):.6e} -> {sum(s['wall_fn_S'].values()):.4e}, "
                          f"KE(S) {s['kinetic_trans_S']:.4e} + {s['kinetic_rot_S']:.3e}"
                          + (f"; rel. diff. vs demflow {s['vs_demflow']}" if "vs_demflow" in s else ""), flush=True)
        rows.append(row)

    def _ver(f):
        try:
            return f()
        except Exception as exc:  # noqa: BLE001
            return f"unknown ({exc})"

    info = dict(date=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()), command="python benchmarks/bench_engines.py "
                + " ".join(sys.argv[1:] if argv is None else argv), notes=a.notes, python=platform.python_version(), numba=numba.__version__,
                numpy=np.__version__, cpu=platform.processor() or platform.machine(), cores=os.cpu_count(),
                threading_layer=numba.threading_layer(), yade=_ver(YadeEngine().version),
                liggghts=_ver(LiggghtsEngine().version), loadavg_after=os.getloadavg(),
                total_s=time.perf_counter() - t_all, args=vars(a))
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
