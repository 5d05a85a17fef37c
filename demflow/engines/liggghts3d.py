"""LIGGGHTS-PUBLIC (Debian package ``liggghts``, 3.8.0) on 3D sphere scenes: deck writer, runner, reader.

How a :class:`~demflow.scene3d.Scene3D` with the Hertz-Mindlin law is expressed (the capabilities
table, :data:`demflow.engines.capabilities.FEATURES_3D`, row by row; the writer refuses through it):

- ``atom_style granular``, ``dimension 3``; a type per material (spheres first, then plane-only
  materials); ``youngsModulus``/``poissonsRatio`` per type (a rigid plane gets E = 1e300: its
  compliance 1e-300 vanishes against the sphere's), ``coefficientFriction`` per type pair;
- ``pair_style gran model hertz tangential history limitForce on`` — LIGGGHTS's Yeff, Geff, Hertz
  force, Mindlin k_t = 8G*√(R*δ) and *total* tangential displacement (demflow
  ``shear_spring='total'``), Coulomb on the total normal force; the dashpots γ = −2√(5/6)β√(S m*)
  with β from ``coefficientRestitution``: the deck solves e' per type pair so that its β gives
  demflow's ζ_n (any convention); the tangential dashpot has the same β (ζ_t = ζ_n) or is off
  (``tangential_damping off``: ζ_t = 0), other ζ_t are refused;
- each plane is a one-triangle STL mesh (``fix mesh/surface/stress``, force on the plane), all in one
  ``fix wall/gran``, moved by ``fix move/mesh linear/variable`` with velocities switched by step
  inside one ``run`` (reff = R for walls: no compensation).  LIGGGHTS's contact at step n sees the
  velocity that moved the mesh there, demflow's the velocity of the step ahead: the components in
  the plane switch one step early (exact: a plane's own tangential displacement changes no contact),
  the normal component on demflow's step (exact position; at a switch the contact sees the new
  normal velocity one step late: capabilities feature 'plane-velocity-timing');
- periodic x and/or y: ``boundary p p f``; positions are unwrapped with the image flags;
- LIGGGHTS starts from v(0): the deck gives v(−Δt/2) + gΔt/2, exact when no contact acts at t = 0;
  the reader turns the on-step v_n, ω_n back into v_{n−1/2} = v_n − (Δt/2m) f_n,
  ω_{n−1/2} = ω_n − Δt t_n /(2·0.4 m r²) — the operations of ``fix nve/sphere``.
- above ``READ_DATA_ABOVE`` (1000) spheres the atoms, their densities and velocities come from a data
  file (``spheres.data``, ``read_data``: O(N); one ``create_atoms single`` + ``set atom`` per sphere is
  O(N²)); smaller scenes keep the per-atom commands (the stored conformance decks are unchanged).

``benchmark=True`` (speed runs, ``benchmarks/bench_engines3d.py``): nothing is dumped or printed during
the run; static planes with an axis normal are primitive walls (``fix wall/gran ... primitive type T
zplane z``, reff = R as for the mesh), which also works in a periodic box; after the run the thermo line
gives the kinetic energy and the touching sphere-sphere contacts (``compute contact/atom``), read by
:func:`read_benchmark_output`.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..scene import check_identifier
from .base import EngineOutputError, EngineUnsupported, atomic_json
from .base3d import BenchmarkSummary, recorded_steps, scene3d_numbers, touching_at_start, trajectory_from_arrays
from .capabilities import FEATURES_3D, refuse_inexpressible
from .liggghts import READ_DATA_ABOVE, LiggghtsEngine, _bad_output, _read_local, _read_rows  # the checked parsers

RIGID_MODULUS = 1e300  # a rigid plane's Young's modulus in LIGGGHTS (compliance (1 − ν²)/E ≈ 1e-300)
ZETA_MAX = math.sqrt(5.0 / 6.0)  # LIGGGHTS's ζ = √(5/6)|β| < √(5/6) for any 0 < e ≤ 1


def _f(x) -> str:
    x = float(x)
    if not math.isfinite(x):
        raise EngineUnsupported(f"non-finite number {x} cannot go into a LIGGGHTS deck")
    return repr(x)


def restitution_for_zeta(zeta: float) -> float:
    """The coefficientRestitution e' whose LIGGGHTS dashpot has damping ratio ζ:
    √(5/6)|ln e'|/√(ln²e' + π²) = ζ  ⇒  ln e' = −πb/√(1 − b²), b = ζ/√(5/6)."""
    if zeta == 0.0:
        return 1.0
    b = zeta / ZETA_MAX
    if not 0.0 < b < 1.0:
        raise EngineUnsupported(
            f"LIGGGHTS's Hertz dashpot reaches damping ratios below √(5/6) = {ZETA_MAX:.6f} only; the scene asks "
            f"ζ = {zeta} (capabilities feature 'damping-3d'); use a larger restitution")
    return math.exp(-math.pi * b / math.sqrt(1.0 - b * b))


def _frame(n):
    """Two unit vectors t1, t2 with t1 × t2 = n (exact for the axis normals)."""
    n = np.asarray(n, dtype=float)
    k = int(np.argmin(np.abs(n)))
    a = np.zeros(3)
    a[k] = 1.0
    if np.count_nonzero(n) == 1:  # an axis normal: the other two axes, cyclic
        i = int(np.flatnonzero(n)[0])
        s = float(np.sign(n[i]))
        t1 = np.zeros(3)
        t2 = np.zeros(3)
        t1[(i + 1) % 3] = 1.0
        t2[(i + 2) % 3] = s
        return t1, t2
    t1 = np.cross(a, n)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1)


def _stl(path: Path, point, normal, half: float):
    """One triangle in the plane whose interior covers the square of half-side ``half`` about ``point``."""
    t1, t2 = _frame(normal)
    p = np.asarray(point, dtype=float)
    verts = [p + half * (-t1 - t2), p + half * (3 * t1 - t2), p + half * (-t1 + 3 * t2)]
    lines = ["solid plane", f"facet normal {' '.join(_f(c) for c in normal)}", "outer loop"]
    lines += [f"vertex {' '.join(_f(c) for c in v)}" for v in verts]
    lines += ["endloop", "endfacet", "endsolid plane"]
    path.write_text("\n".join(lines) + "\n")
    return np.array(verts)


def _write_data3d(path: Path, S, tid, nt, lo, hi, half_g):
    """LAMMPS data file (atom_style granular, 3D): id type diameter density x y z; velocities
    vx vy vz ωx ωy ωz (v(−Δt/2) + half_g·g, as the per-atom deck gives them).  Numbers only (:func:`_f`)."""
    D = S["spheres"]
    g = S["gravity"]
    n = int(S["n_spheres"])
    out = ["demflow spheres (LIGGGHTS data file, atom_style granular)", "",
           f"{n} atoms", f"{int(nt)} atom types", "",
           f"{_f(lo[0])} {_f(hi[0])} xlo xhi", f"{_f(lo[1])} {_f(hi[1])} ylo yhi", f"{_f(lo[2])} {_f(hi[2])} zlo zhi",
           "", "Atoms", ""]
    for i in range(n):
        r = D["r"][i]
        rho = D["mass"][i] / (4.0 * math.pi / 3.0 * r ** 3)
        out.append(f"{i + 1} {tid[D['material'][i]]} {_f(2 * r)} {_f(rho)} {_f(D['x'][i])} {_f(D['y'][i])} "
                   f"{_f(D['z'][i])}")
    out += ["", "Velocities", ""]
    for i in range(n):
        v = [D[c][i] + half_g * g[a] for a, c in enumerate(("vx", "vy", "vz"))]
        out.append(f"{i + 1} {_f(v[0])} {_f(v[1])} {_f(v[2])} {_f(D['wx'][i])} {_f(D['wy'][i])} {_f(D['wz'][i])}")
    path.write_text("\n".join(out) + "\n")


def _primitive(pl):
    """('xplane'|'yplane'|'zplane', offset) of a static plane with an axis normal, else None."""
    nrm = [float(c) for c in pl["normal"]]
    if any(c != 0.0 for ph in pl["phases"] for c in ph["v"]) or sorted(abs(c) for c in nrm) != [0.0, 0.0, 1.0]:
        return None
    a = [abs(c) for c in nrm].index(1.0)
    return "xyz"[a] + "plane", float(pl["point"][a])


def read_benchmark_output(outdir: Path, run: int = -1) -> dict:
    """The benchmark deck's summary from log.liggghts: steps, kinetic energy and touching sphere-sphere
    contacts (compute contact/atom counts each contact once per atom: half its sum) at the end of a run
    command: ``run`` = -1 the last (the deck's one run), 0 the first (a deck the speed benchmark split into
    ``run S`` and ``run S pre no``: the state at step S)."""
    log = Path(outdir) / "log.liggghts"
    text = log.read_text(errors="replace") if log.exists() else ""
    if "DEMFLOW-COMPLETE" not in text:
        raise EngineOutputError(f"LIGGGHTS did not complete (no completion mark in {log}); rerun the engine")
    ends, last, header = [], None, None  # ends: the last thermo line of each run ("Loop time" closes a run)
    for line in text.splitlines():
        w = line.split()
        if w[:2] == ["Step", "Atoms"]:
            header = w
        elif header and len(w) == len(header):
            try:
                last = dict(zip(header, (float(c) for c in w)))
            except ValueError:
                header = None
        else:
            if line.startswith("Loop time"):
                header = None
                if last is not None:
                    ends.append(last)
    if last is not None and (not ends or ends[-1] is not last):
        ends.append(last)
    if not ends:
        raise EngineOutputError(f"no thermo output in {log}")
    if not -len(ends) <= run < len(ends):
        raise EngineOutputError(f"run={run} asked of {log}, which holds {len(ends)} run(s); give run=0 for the first "
                                "or -1 for the last")
    end = ends[run]
    return BenchmarkSummary(steps=int(end["Step"]), kinetic=end["KinEng"], sphere_contacts=0.5 * end["csum"])


class Liggghts3DEngine(LiggghtsEngine):
    """LIGGGHTS on a :class:`~demflow.scene3d.Scene3D` (module docstring); the executable, version and
    command line are the 2D engine's.  ``benchmark=True``: the speed-run deck (module docstring)."""

    def __init__(self, benchmark: bool = False):
        self.benchmark = benchmark

    def write_deck(self, scene, sim, deckdir: Path):
        check_identifier("scene", scene.name)  # before any message or file names it
        refuse_inexpressible(self.name, scene, FEATURES_3D)
        S = scene3d_numbers(scene, sim)
        M = S["materials"]
        sphere_mats = sorted(set(S["spheres"]["material"]), key=list(M).index)
        types = sphere_mats + [m for m in M if m not in sphere_mats]
        nt = len(types)
        tid = {m: k + 1 for k, m in enumerate(types)}
        pairs = {}
        for p in S["sphere_pairs"] + S["plane_pairs"]:
            pairs[(p["a"], p["b"])] = pairs[(p["b"], p["a"])] = p
        tdamp = set()
        for p in pairs.values():
            if p["zt"] == 0.0 and p["zn"] > 0.0:
                tdamp.add("off")
            elif math.isclose(p["zt"], p["zn"], rel_tol=1e-14, abs_tol=0.0):
                tdamp.add("on")
            else:
                raise EngineUnsupported(
                    f"LIGGGHTS's tangential dashpot has the normal one's β (ζ_t = ζ_n) or none (tangential_damping "
                    f"off); pair ({p['a']}, {p['b']}) asks ζ_t = {p['zt']} with ζ_n = {p['zn']} (capabilities feature "
                    "'shear-damping-ratio'); give restitution_tangential=None (e_t = e_n) or 1.0, or run YADE")
        if len(tdamp) > 1:
            raise EngineUnsupported("LIGGGHTS's tangential_damping is one switch for all pairs; the scene mixes pairs "
                                    "with and without a tangential dashpot (capabilities feature 'shear-damping-ratio')")

        def table(key):
            out = []
            for a in types:
                for b in types:
                    p = pairs.get((a, b))
                    if key == "e":
                        out.append(_f(restitution_for_zeta(p["zn"]) if p else 1.0))
                    else:
                        out.append(_f(p["mu"]) if p else "0.0")
            return " ".join(out)

        E = " ".join(_f(RIGID_MODULUS if M[m]["rigid"] else M[m]["young"]) for m in types)
        nu = " ".join(_f(M[m]["poisson"]) for m in types)
        D = S["spheres"]
        n = S["n_spheres"]
        x = np.array([D["x"], D["y"], D["z"]]).T
        r = np.asarray(D["r"])
        dt = S["dt"]
        T = dt * S["n_steps"]
        g = np.asarray(S["gravity"])
        vmax = max([float(np.max(np.abs([D["vx"], D["vy"], D["vz"]])))]
                   + [float(np.max(np.abs(ph["v"]))) for pl in S["planes"] for ph in pl["phases"]] + [0.0])
        travel = vmax * T + 0.5 * float(np.linalg.norm(g)) * T * T + 4.0 * float(r.max())
        lo = x.min(axis=0) - travel
        hi = x.max(axis=0) + travel
        half = float(np.max(hi - lo))
        b = S["box"]
        prim = [_primitive(pl) for pl in S["planes"]] if self.benchmark else [None] * len(S["planes"])
        if self.benchmark and None in prim:
            raise EngineUnsupported("the LIGGGHTS benchmark deck has static axis-aligned planes only (primitive "
                                    "walls); run a scene with other planes with benchmark=False")
        if S["planes"] and (b["periodic_x"] or b["periodic_y"]) and not self.benchmark:
            raise EngineUnsupported("the LIGGGHTS 3D deck has no planes in a periodic box (capabilities feature "
                                    "'walls-3d'); run YADE or make the box open")
        for k, pl in enumerate(S["planes"]):
            if prim[k]:
                continue
            verts = _stl(deckdir / f"w{k}.stl", pl["point"], pl["normal"], half)
            disp = np.zeros(3)
            lo_m, hi_m = verts.min(axis=0), verts.max(axis=0)
            for ph in pl["phases"]:  # the mesh's path: keep the whole of it in the domain
                disp = disp + np.asarray(ph["v"]) * dt * ph["cycles"]
                lo_m = np.minimum(lo_m, verts.min(axis=0) + disp)
                hi_m = np.maximum(hi_m, verts.max(axis=0) + disp)
            lo = np.minimum(lo, lo_m - 4.0 * float(r.max()))
            hi = np.maximum(hi, hi_m + 4.0 * float(r.max()))
        bnd = ["f", "f", "f"]
        for a, key in ((0, "x"), (1, "y")):
            if b[f"periodic_{key}"]:
                bnd[a] = "p"
                lo[a] = b[f"{key}0"]
                hi[a] = b[f"{key}0"] + b[f"l{key}"]
        touching = touching_at_start(sim)
        # LIGGGHTS starts from v(0) = v(-dt/2) + (F(0)/m) dt/2; with no contact at t = 0, F(0) = m g
        half_g = 0.0 if touching else 0.5 * dt
        big = n > READ_DATA_ABOVE
        L = [
            "# demflow deck for LIGGGHTS-PUBLIC 3.8.0: 3D spheres, Hertz-Mindlin, planes with prescribed translation",
            "atom_style granular", "atom_modify map array sort 0 0", "dimension 3", f"boundary {' '.join(bnd)}",
            "newton off", "communicate single vel yes", "units si", "hard_particles yes"]
        if big:  # box, atoms, densities and velocities from a data file: O(N)
            _write_data3d(deckdir / "spheres.data", S, tid, nt, lo, hi, half_g)
            L.append("read_data spheres.data")
        else:  # small scenes keep the per-atom commands (the stored conformance decks hold them)
            L += [f"region box block {_f(lo[0])} {_f(hi[0])} {_f(lo[1])} {_f(hi[1])} {_f(lo[2])} {_f(hi[2])} units box",
                  f"create_box {nt} box"]
        L += [
            f"neighbor {_f(S['skin'])} bin", "neigh_modify delay 0",
            f"fix m1 all property/global youngsModulus peratomtype {E}",
            f"fix m2 all property/global poissonsRatio peratomtype {nu}",
            f"fix m3 all property/global coefficientRestitution peratomtypepair {nt} {table('e')}",
            f"fix m4 all property/global coefficientFriction peratomtypepair {nt} {table('mu')}",
        ]
        opts = "limitForce on" + (" tangential_damping off" if tdamp == {"off"} else "")
        L += [f"pair_style gran model hertz tangential history {opts}", "pair_coeff * *", f"timestep {_f(dt)}"]
        for i in range(0 if big else n):
            L.append(f"create_atoms {tid[D['material'][i]]} single {_f(x[i, 0])} {_f(x[i, 1])} {_f(x[i, 2])} units box")
        for i in range(0 if big else n):
            rho = D["mass"][i] / (4.0 * math.pi / 3.0 * r[i] ** 3)
            v = [D[c][i] + half_g * g[a] for a, c in enumerate(("vx", "vy", "vz"))]
            L.append(f"set atom {i + 1} diameter {_f(2 * r[i])} density {_f(rho)} vx {_f(v[0])} vy {_f(v[1])} "
                     f"vz {_f(v[2])} omegax {_f(D['wx'][i])} omegay {_f(D['wy'][i])} omegaz {_f(D['wz'][i])}")
        meshes = []
        for k, pl in enumerate(S["planes"]):
            if prim[k]:
                L.append(f"fix p{k} all wall/gran model hertz tangential history primitive type {tid[pl['material']]} "
                         f"{prim[k][0]} {_f(prim[k][1])} {opts}")
                continue
            L.append(f"fix w{k} all mesh/surface/stress file w{k}.stl type {tid[pl['material']]}")
            meshes.append(f"w{k}")
        if meshes:
            L.append(f"fix walls all wall/gran model hertz tangential history mesh n_meshes {len(meshes)} "
                     f"meshes {' '.join(meshes)} {opts}")
        for k, pl in enumerate(S["planes"]):
            if not pl["phases"] or prim[k]:
                continue
            s0 = 0
            terms = [[], [], []]
            nrm = pl["normal"]
            for ph in pl["phases"]:
                s1 = s0 + ph["cycles"]
                vn = sum(ph["v"][a] * nrm[a] for a in range(3))
                for a in range(3):
                    # LIGGGHTS's step n moves the mesh by the velocity its contacts see at step n; demflow moves
                    # the plane after its step n-1 force pass by the velocity of step n-1 and uses the velocity
                    # of step n in the step n force pass.  The normal part must put the plane where demflow has
                    # it (steps s0+1..s1: the contact sees a switch one step late); the part in the plane moves
                    # nothing a contact sees, so it follows demflow's velocity (steps s0..s1-1).  Both parts are
                    # exact for an axis-aligned plane (vn·n_a is v_a or 0).
                    for part, shift in ((vn * nrm[a], 1), (ph["v"][a] - vn * nrm[a], 0)):
                        if part:
                            terms[a].append(f"(step>={s0 + shift})*(step<={s1 - 1 + shift})*{_f(part)}")
                s0 = s1
            for a, c in enumerate("xyz"):
                L.append(f"variable w{k}v{c} equal {'+'.join(terms[a]) or '0.0'}")
            L.append(f"fix w{k}mv all move/mesh mesh w{k} linear/variable v_w{k}vx v_w{k}vy v_w{k}vz")
        if np.any(g != 0):
            gn = float(np.linalg.norm(g))
            L.append(f"fix grav all gravity {_f(gn)} vector {_f(g[0] / gn)} {_f(g[1] / gn)} {_f(g[2] / gn)}")
        L.append("fix integr all nve/sphere")
        if self.benchmark:  # nothing recorded during the run; after it, KE and touching contacts
            L += ["compute cn all contact/atom", "compute csum all reduce sum c_cn",
                  "thermo_style custom step atoms ke c_csum", "thermo 0", f"run {int(S['n_steps'])}",
                  'print "DEMFLOW-COMPLETE"']
            S["liggghts"] = dict(types=types, boundary=bnd, lo=lo.tolist(), hi=hi.tolist(), touching_at_start=touching,
                                 tangential_damping=sorted(tdamp), benchmark=True)
            deck = deckdir / "deck.in"
            deck.write_text("\n".join(L) + "\n")
            atomic_json(deckdir / "scene.json", S)
            return [deck, deckdir / "scene.json"] + ([deckdir / "spheres.data"] if big else [])
        every = S["every"]
        cols = []
        for k in range(len(meshes)):
            for c in (1, 2, 3):
                L.append(f"variable w{k}f{c} equal f_w{k}[{c}]")
                cols.append(f"${{w{k}f{c}}}")
        if cols:
            L.append(f"fix rec all print {every} \"$(step) {' '.join(cols)}\" file planes.txt screen no title none")
        fields = "id x y z ix iy iz vx vy vz omegax omegay omegaz fx fy fz tqx tqy tqz mass radius"
        L.append(f"dump ds all custom {every} spheres.txt {fields}")
        L.append('dump_modify ds sort id format "%d %.17g %.17g %.17g %d %d %d' + " %.17g" * 14 + '"')
        L += ["thermo_style custom step atoms ke", "thermo 1000", f"run {int(S['n_steps'])}",
              'print "DEMFLOW-COMPLETE"']
        S["liggghts"] = dict(types=types, boundary=bnd, lo=lo.tolist(), hi=hi.tolist(), touching_at_start=touching,
                             tangential_damping=sorted(tdamp))
        deck = deckdir / "deck.in"
        deck.write_text("\n".join(L) + "\n")
        atomic_json(deckdir / "scene.json", S)
        return ([deck, deckdir / "scene.json"] + [deckdir / f"w{k}.stl" for k in range(len(meshes))]
                + ([deckdir / "spheres.data"] if big else []))

    def read(self, scene, sim, outdir: Path):
        if self.benchmark:
            return read_benchmark_output(outdir)
        import json

        outdir = Path(outdir)
        log = outdir / "log.liggghts"
        if not log.exists() or "DEMFLOW-COMPLETE" not in log.read_text(errors="replace"):
            raise EngineOutputError(f"LIGGGHTS did not complete scene {scene.name!r} (no completion mark in {log}); "
                                    "the output is truncated; rerun the engine")
        try:  # the deck's own record of the scene (written by write_deck beside the deck)
            S = json.loads((outdir / "scene.json").read_text())
            lo, hi = (np.asarray(S["liggghts"][k], dtype=float) for k in ("lo", "hi"))
            touching = S["liggghts"]["touching_at_start"]
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise EngineOutputError(f"LIGGGHTS deck record {outdir / 'scene.json'} is missing or corrupt ({e!r}); "
                                    "rerun the engine") from None
        if lo.shape != (3,) or hi.shape != (3,) or not np.all(np.isfinite(hi - lo)):
            raise EngineOutputError(f"LIGGGHTS deck record {outdir / 'scene.json'}: box bounds lo/hi are not three "
                                    "finite numbers each; rerun the engine")
        steps, p_steps = recorded_steps(sim)
        # the dump is written at step 0 and every ``every`` steps after it; each block lists atoms 1..n
        dumps = _read_local(outdir / "spheres.txt", 21, steps, {0: sim.n}, atoms=sim.n)
        period = hi - lo
        dtf = 0.5 * sim.dt
        rows = []
        for step in steps:
            d = dumps[int(step)]
            d = d[np.argsort(d[:, 0])]
            m, rad = d[:, 19], d[:, 20]
            if not (np.all(m > 0) and np.all(rad > 0)):
                raise _bad_output(outdir / "spheres.txt", None, f"timestep {step}: a mass or radius is not positive")
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # refused below when not finite
                pos = d[:, 1:4] + d[:, 4:7] * period  # image flags are 0 along non-periodic axes
                dtfm = dtf / m
                v = d[:, 7:10] - dtfm[:, None] * d[:, 13:16]  # the dump's velocities are half a step ahead
                dtirot = (dtf / 0.4) / (rad * rad * m)
                w = d[:, 10:13] - dtirot[:, None] * d[:, 16:19]
                row = np.concatenate([pos, v, w], axis=1)
            if not np.all(np.isfinite(row)):
                raise _bad_output(outdir / "spheres.txt", None, f"timestep {step}: a position or velocity derived "
                                  "from the dump is not finite (a value out of range)")
            rows.append(row)
        if sim.n_planes:  # fix print: steps every, 2·every, ... up to n_steps (the forces evaluated before them)
            planes = _read_rows(outdir / "planes.txt", 1 + 3 * sim.n_planes)
            if not np.array_equal(planes[:, 0], p_steps + max(int(sim.scene.outputs.every), 1)):
                raise _bad_output(outdir / "planes.txt", None, f"it holds {planes.shape[0]} rows of steps "
                                  f"{planes[:3, 0].tolist()}..., the deck prints {len(p_steps)}")
            p_rows = planes[:, 1:].reshape(-1, sim.n_planes, 3)
            p_steps = planes[:, 0].astype(np.int64)  # LIGGGHTS's labels, kept as the stored references hold them
        else:
            p_steps, p_rows = np.zeros(0, np.int64), np.zeros((0, 0, 3))
        res = trajectory_from_arrays(sim, "liggghts", steps, rows, p_steps, p_rows)
        res.meta.update(touching_at_start=touching)
        return res


__all__ = ["Liggghts3DEngine", "read_benchmark_output", "restitution_for_zeta"]
