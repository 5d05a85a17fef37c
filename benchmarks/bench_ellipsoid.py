"""Cost of an ellipsoid contact against a sphere contact, per pair and per particle-step (issue 16 item 4).

    python benchmarks/bench_ellipsoid.py [--n 10000] [--steps 40] [--rounds 3]

Scene: benchmarks/packing3d.py's dense FCC Hertz packing (periodic x/y, floor, gravity; ~3 touching
contacts per particle), run three ways on one thread:

- ``spheres``: the sphere cycle (demflow.stepping3d.run_steps3);
- ``ellipsoids a=b=c``: the same spheres as ellipsoids with equal axes (random orientations): the
  same contacts through the ellipsoid cycle (Lin & Ng solves, curvature, body_step);
- ``ellipsoids 1.003:1:0.997``: near-spherical ellipsoids (semi-axes R·(1.003, 1, 0.997), random
  orientations) in the same lattice: about the same contact count, aspherical rotation.

Per pair: one force pass (sphere_forces / ellipsoid_forces) over the listed pairs of the built
packing, timed over ``--passes`` passes; reported per touching pair and per listed pair.  Also the
geometry alone: the Lin & Ng solve (two potential points, cold and warm-started) of a touching pair
against the sphere pair's distance/normal, in a compiled loop over the touching pairs.  Per
particle-step: ``--rounds`` rounds of ``--steps`` steps; the best round with the spread.  Say with
``--notes`` whether anything else ran (the spread shows how much it mattered); results go to
benchmarks/results/ellipsoid_cost.{json,md}.
"""
from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numba  # noqa: E402

import demflow as df  # noqa: E402
from demflow.contacts.spheres import pack_rows, sphere_forces  # noqa: E402
from demflow.ellipsoids3d import contact_pass  # noqa: E402
from demflow.jit import njit  # noqa: E402
from demflow.shapes.ellipsoid import ellipsoid_pair  # noqa: E402
from demflow.stepping3d import MAX_OVERLAP_RATIO  # noqa: E402
from packing3d import dense_fcc  # noqa: E402


def ellipsoid_scene(sphere_scene, stretch: float, seed: int = 2):
    s = sphere_scene.spheres
    n = len(s.x)
    r = np.asarray(s.radius)
    axes = r[:, None] * np.array([1.0 + stretch, 1.0, 1.0 - stretch])
    q = np.random.default_rng(seed).normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    sc = df.Scene3D(**{k: getattr(sphere_scene, k) for k in ("materials", "laws", "planes", "gravity", "box")},
                    name=f"{sphere_scene.name}-ell{int(round(1e3 * stretch))}", spheres=None,
                    ellipsoids=df.Ellipsoids(axes=axes, x=s.x, y=s.y, z=s.z, material=s.material, orientation=q),
                    dt=None)
    return sc


@njit
def _sphere_geometry(pos, r, i, j, reps):
    acc = 0.0
    for _ in range(reps):
        for k in range(i.shape[0]):
            a = i[k]
            b = j[k]
            dx = pos[b, 0] - pos[a, 0]
            dy = pos[b, 1] - pos[a, 1]
            dz = pos[b, 2] - pos[a, 2]
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            acc += (r[a] + r[b] - d) + dx / d + r[a] * r[b] / (r[a] + r[b])
    return acc


@njit
def _ellipsoid_geometry(pos, rot, axes, i, j, lam, warm, reps):
    work = np.zeros((6, 3))
    M = np.zeros((3, 3))
    H = np.zeros((3, 3))
    acc = 0.0
    iters = 0
    for _ in range(reps):
        for k in range(i.shape[0]):
            a = i[k]
            b = j[k]
            res = ellipsoid_pair(pos[a], rot[a], axes[a], pos[b], rot[b], axes[b], lam[k, 0], lam[k, 1], warm, work,
                                 M, H)
            acc += res[0] + res[1] + res[7]
            iters += res[10]
    return acc, iters


def best_of(f, rounds):
    ts = []
    for _ in range(rounds):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return min(ts), (max(ts) - min(ts)) / min(ts), ts


def per_pair(sim, kind: str, passes: int, rounds: int) -> dict:
    p = sim.pairs
    hist0 = p.hist.copy()
    if kind == "spheres":
        def one():
            for _ in range(passes):
                pack_rows(sim.spheres)
                sphere_forces(sim.spheres, p, sim.planes, sim.tris, sim.law_params, sim.dt, False, MAX_OVERLAP_RATIO)
    else:
        def one():
            for _ in range(passes):
                contact_pass(sim)
    one()
    t, spread, ts = best_of(one, rounds)
    p.hist[:] = hist0
    touching = int((p.ovl > 0).sum())
    return {"seconds_per_pass": t / passes, "spread": spread, "listed": int(p.i.size), "touching": touching,
            "ns_per_touching_pair": 1e9 * t / passes / max(touching, 1),
            "ns_per_listed_pair": 1e9 * t / passes / p.i.size}


def geometry(sim_s, sim_e, reps: int, rounds: int) -> dict:
    p = sim_e.pairs
    on = (p.ovl > 0) & (p.j < sim_e.n)
    i = p.i[on].copy()
    j = p.j[on].copy()
    pos = sim_e.spheres.pos.copy()  # periodic images: take pairs without a shift
    ok = np.all(p.shift[on] == 0.0, axis=1)
    i, j = i[ok], j[ok]
    lam = p.hist[on][ok][:, -2:].copy()
    ell = sim_e.ell
    _sphere_geometry(pos, sim_s.spheres.r, i, j, 1)
    _ellipsoid_geometry(pos, ell.rot, ell.axes, i, j, lam, False, 1)
    ts, ss, _ = best_of(lambda: _sphere_geometry(pos, sim_s.spheres.r, i, j, reps), rounds)
    tc, sc, _ = best_of(lambda: _ellipsoid_geometry(pos, ell.rot, ell.axes, i, j, lam, False, reps), rounds)
    tw, sw, _ = best_of(lambda: _ellipsoid_geometry(pos, ell.rot, ell.axes, i, j, lam, True, reps), rounds)
    _, it_c = _ellipsoid_geometry(pos, ell.rot, ell.axes, i, j, lam, False, 1)
    _, it_w = _ellipsoid_geometry(pos, ell.rot, ell.axes, i, j, lam, True, 1)
    m = i.size * reps
    return {"pairs": int(i.size), "sphere_ns": 1e9 * ts / m, "sphere_spread": ss, "cold_ns": 1e9 * tc / m,
            "cold_spread": sc, "warm_ns": 1e9 * tw / m, "warm_spread": sw,
            "factorisations_per_pair_cold": it_c / i.size, "factorisations_per_pair_warm": it_w / i.size}


def per_step(sim, steps: int, rounds: int) -> dict:
    sim.run(3)
    it0 = sim.work[2] if sim.work.size > 2 else 0.0
    t, spread, ts = best_of(lambda: sim.run(steps), rounds)
    n = sim.n
    out = {"n": n, "steps": steps, "best_particle_steps_per_s": n * steps / t, "spread": spread,
           "rounds_s": ts, "contacts_per_particle": float((sim.pairs.ovl > 0).sum()) / n,
           "listed_per_particle": sim.pairs.i.size / n}
    if sim.work.size > 2:
        out["factorisations_per_touching_pair_step"] = float(
            (sim.work[2] - it0) / (rounds * steps) / max((sim.pairs.ovl > 0).sum(), 1))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=10000)
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--passes", type=int, default=20)
    ap.add_argument("--tag", default="ellipsoid_cost")
    ap.add_argument("--notes", default="", help="the machine's state during the run (say whether anything else ran)")
    a = ap.parse_args()
    numba.set_num_threads(1)
    base = dense_fcc(a.n)
    cases = {"spheres": base, "ellipsoids a=b=c": ellipsoid_scene(base, 0.0),
             "ellipsoids 1.003:1:0.997": ellipsoid_scene(base, 0.003)}
    # the same dt for all three (the sphere scene's), so that the motion is comparable
    sims = {}
    for k, sc in cases.items():
        sims[k] = df.build(sc)
    dt = sims["spheres"].dt
    for s in sims.values():
        s.dt = dt
    rows = {}
    for k, s in sims.items():
        rows[k] = {"pair_pass": per_pair(s, "spheres" if k == "spheres" else "ellipsoids", a.passes, a.rounds)}
    for k, s in sims.items():
        rows[k]["cycle"] = per_step(s, a.steps, a.rounds)
    # after the cycle: the pairs carry the last step's multipliers (the warm start)
    geo = {k: geometry(sims["spheres"], sims[k], 20, a.rounds) for k in list(sims)[1:]}
    out = Path(__file__).resolve().parent / "results"
    meta = {"date": time.strftime("%Y-%m-%d %H:%M"), "machine": platform.processor() or platform.machine(),
            "python": platform.python_version(), "numba": numba.__version__, "threads": 1, "n": a.n,
            "steps": a.steps, "rounds": a.rounds, "passes": a.passes,
            "note": a.notes or "machine state not recorded: compare ratios, mind the spread"}
    (out / f"{a.tag}.json").write_text(json.dumps({"meta": meta, "rows": rows, "geometry": geo}, indent=1))
    s0 = rows["spheres"]
    lines = [f"# Ellipsoid vs sphere contact cost, one thread ({meta['date']})", "",
             f"Dense FCC Hertz packing (benchmarks/packing3d.py), {a.n} particles, periodic x/y, floor. Best of "
             f"{a.rounds} rounds; spread = (worst - best)/best. {meta['note']}.", "",
             "## Per pair: one force pass over the listed pairs", "",
             "| particles | touching pairs | ns / touching pair | ns / listed pair | × spheres | spread |",
             "|---|---|---|---|---|---|"]
    for k, r in rows.items():
        pp = r["pair_pass"]
        lines.append(f"| {k} | {pp['touching']} | {pp['ns_per_touching_pair']:.0f} | {pp['ns_per_listed_pair']:.0f} | "
                     f"{pp['seconds_per_pass'] / s0['pair_pass']['seconds_per_pass']:.1f} | {pp['spread']:.0%} |")
    lines += ["", "## Per pair: the geometry alone (touching ellipsoid pairs, compiled loop)", "",
              "| particles | pairs | sphere ns | Lin & Ng cold ns | warm ns | factorisations cold / warm "
              "| warm × sphere |",
              "|---|---|---|---|---|---|---|"]
    for k, g in geo.items():
        lines.append(f"| {k} | {g['pairs']} | {g['sphere_ns']:.1f} | {g['cold_ns']:.0f} | {g['warm_ns']:.0f} | "
                     f"{g['factorisations_per_pair_cold']:.1f} / {g['factorisations_per_pair_warm']:.1f} | "
                     f"{g['warm_ns'] / g['sphere_ns']:.0f} |")
    lines += ["", "## Per particle-step: the whole cycle", "",
              "| particles | particle-steps/s | ns / particle-step | × spheres (time) | spread | contacts/particle |",
              "|---|---|---|---|---|---|"]
    for k, r in rows.items():
        c = r["cycle"]
        lines.append(f"| {k} | {c['best_particle_steps_per_s']:.3g} | {1e9 / c['best_particle_steps_per_s']:.0f} | "
                     f"{s0['cycle']['best_particle_steps_per_s'] / c['best_particle_steps_per_s']:.1f} | "
                     f"{c['spread']:.0%} | {c['contacts_per_particle']:.2f} |")
    (out / f"{a.tag}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
