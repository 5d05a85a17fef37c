"""LIGGGHTS-PUBLIC (Debian package ``liggghts``, 3.8.0): deck writer, runner and reader.

How a demflow scene is expressed (see :mod:`demflow.engines.capabilities`): ``dimension 2``
discs (``set density`` gives the disc mass ρπR² per unit thickness, the integrator the disc
inertia ½mR²), ``hooke/stiffness`` with ``absolute_damping on`` and ``limitForce on``, per
type-pair kn, kt, γn, γt, friction (type 1..K discs by material, walls after them); walls as
two-triangle STL meshes spanning a thick periodic z, moved by ``move/mesh`` with variables
that switch velocity by step inside one ``run``.  Forces on walls come from
``mesh/surface/stress``; contact forces from ``compute pair/gran/local``.

Not expressed, and refused by the deck writer from the capabilities table: global damping
(LIGGGHTS has no implicit eq 2.27 form here), the incremental normal spring and the thesis sliding
rule (LIGGGHTS computes kN × overlap and the C&S rule), cohesion, servo walls, pore fluid.  The
deck contains numbers and fixed names (w0, w1, ...) only.
"""
from __future__ import annotations

import math
import re
import subprocess
from pathlib import Path

import numpy as np

from .base import Engine, EngineOutputError, EngineUnsupported, atomic_json, scene_numbers
from .capabilities import refuse_inexpressible
from .tables import results_from_records


def _f(x) -> str:
    x = float(x)
    if not math.isfinite(x):
        raise EngineUnsupported(f"non-finite number {x} cannot go into a LIGGGHTS deck")
    return repr(x)


def _stl(path: Path, ax, ay, bx, by, zlo, zhi):
    tri = [((ax, ay, zlo), (bx, by, zlo), (bx, by, zhi)), ((ax, ay, zlo), (bx, by, zhi), (ax, ay, zhi))]
    nx, ny = -(by - ay), bx - ax
    L = math.hypot(nx, ny)
    lines = ["solid wall"]
    for t in tri:
        lines.append(f"facet normal {_f(nx / L)} {_f(ny / L)} 0.0\nouter loop")
        lines += [f"vertex {_f(v[0])} {_f(v[1])} {_f(v[2])}" for v in t]
        lines.append("endloop\nendfacet")
    lines.append("endsolid wall")
    path.write_text("\n".join(lines) + "\n")


# Above this many discs the deck reads the discs from a data file (``read_data``): one
# ``create_atoms single`` + ``set atom ID`` per disc costs O(N) each in LIGGGHTS, O(N^2) in all
# (minutes at 1e5 discs).  Smaller scenes keep the per-atom commands, so decks already stored
# as references (the nine-disc case) stay byte-identical.  In 2D ``read_data``'s density gives
# the disc mass ρπR², as ``set density`` does.
READ_DATA_ABOVE = 1000


def _write_data(path: Path, S, tid, nt, lo, hi, zl):
    """LAMMPS data file (atom_style granular): id type diameter density x y z; velocities
    vx vy vz ωx ωy ωz.  Numbers only (validated by :func:`_f`)."""
    D = S["discs"]
    out = ["demflow discs (LIGGGHTS data file, atom_style granular)", "",
           f"{int(S['n_discs'])} atoms", f"{int(nt)} atom types", "",
           f"{_f(lo[0])} {_f(hi[0])} xlo xhi", f"{_f(lo[1])} {_f(hi[1])} ylo yhi", f"{_f(-zl)} {_f(zl)} zlo zhi",
           "", "Atoms", ""]
    for i in range(int(S["n_discs"])):
        r = D["r"][i]
        out.append(f"{i + 1} {tid[D['material'][i]]} {_f(2 * r)} {_f(D['mass'][i] / (math.pi * r ** 2))} "
                   f"{_f(D['x'][i])} {_f(D['y'][i])} 0.0")
    out += ["", "Velocities", ""]
    for i in range(int(S["n_discs"])):
        out.append(f"{i + 1} {_f(D['vx'][i])} {_f(D['vy'][i])} 0.0 0.0 0.0 {_f(D['omega'][i])}")
    path.write_text("\n".join(out) + "\n")


def half_step_start(sim) -> np.ndarray:
    """(n, 3): a(0)Δt/2 and α(0)Δt/2 of each disc at the scene's start, from demflow's own forces at t = 0 (contacts
    and gravity).  demflow holds v(−Δt/2) (central differences), LIGGGHTS takes v(0) (velocity Verlet): the deck
    gives v(−Δt/2) + a(0)Δt/2, so both reach the same v(Δt/2) (capabilities feature 'initial-velocity').  Zero where
    nothing acts at t = 0, so such decks are unchanged."""
    n = sim.n
    c = sim.contact_table_arrays()
    i, j, fn, fs = c["finder"], c["other"], c["fn"], c["fs"]
    fx = -fn * c["nx"] - fs * c["ny"]  # on the finder: -Fn ε - Fs τ, τ = (ε_y, -ε_x)
    fy = -fn * c["ny"] + fs * c["nx"]
    F = np.zeros((n, 3))
    np.add.at(F[:, 0], i, fx)
    np.add.at(F[:, 1], i, fy)
    np.add.at(F[:, 2], i, fs * sim.r[i])
    d = j < n
    np.add.at(F[:, 0], j[d], -fx[d])
    np.add.at(F[:, 1], j[d], -fy[d])
    np.add.at(F[:, 2], j[d], fs[d] * sim.r[j[d]])
    out = np.zeros((n, 3))
    out[:, 0] = 0.5 * sim.dt * (F[:, 0] / sim.mass + sim.gx)
    out[:, 1] = 0.5 * sim.dt * (F[:, 1] / sim.mass + sim.gy)
    out[:, 2] = 0.5 * sim.dt * F[:, 2] / sim.inertia
    return out


class LiggghtsEngine(Engine):
    name = "liggghts"
    executable = "liggghts"
    package = "liggghts"

    def version(self) -> str:
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:  # LIGGGHTS writes log.liggghts into its cwd
            out = subprocess.run([self.path(), "-h", "-log", "none"], capture_output=True, text=True, timeout=60,
                                 stdin=subprocess.DEVNULL, cwd=tmp)
        m = re.search(r"LIGGGHTS \(Version ([^)]*)\)", out.stdout)
        return m.group(1) if m else out.stdout.splitlines()[0][:80]

    def write_deck(self, scene, sim, deckdir: Path):
        refuse_inexpressible(self.name, scene)
        S = scene_numbers(scene, sim)
        if S["gravity"] != [0.0, 0.0]:  # (scenes without gravity keep the decks their stored references hold)
            half = half_step_start(sim)
            D = S["discs"]
            for k, key in enumerate(("vx", "vy", "omega")):
                D[key] = [v + h if h != 0.0 else v for v, h in zip(D[key], half[:, k].tolist())]
        disc_mats = sorted(set(S["discs"]["material"]))
        wall_mats = sorted({w["material"] for w in S["walls"]})
        types = disc_mats + [m for m in wall_mats if m not in disc_mats]
        nt = len(types)
        tid = {m: k + 1 for k, m in enumerate(types)}

        def table(key):
            vals = []
            for a in types:
                for b in types:
                    law = S["laws"].get(f"{a}|{b}") or S["laws"].get(f"{b}|{a}")
                    vals.append(_f(law[key]) if law else "0.0")
            return " ".join(vals)

        x, y, r = (np.asarray(S["discs"][k]) for k in ("x", "y", "r"))
        rmax = float(r.max())
        pad = 4.0 * rmax
        xs = [x.min() - pad, x.max() + pad]
        ys = [y.min() - pad, y.max() + pad]
        for w in S["walls"]:
            for h in (w["h1"], w["h2"]):
                xs += [w["px"] + h * w["ex"]]
                ys += [w["py"] + h * w["ey"]]
        lo = (min(xs) - pad, min(ys) - pad)
        hi = (max(xs) + pad, max(ys) + pad)
        px = scene.box.periodic_x
        if px is not None:  # periodic along x: the box is the period, the walls are clipped to it
            lo, hi = (float(px[0]), lo[1]), (float(px[1]), hi[1])
            for w in S["walls"]:
                if w["ey"] != 0.0 or any(ph["vx"] or ph["omega"] for ph in w["phases"]):
                    raise EngineUnsupported(
                        f"wall {w['name']!r} is not horizontal and fixed in x in a box periodic along x; the LIGGGHTS "
                        "deck clips walls to the period, which only a horizontal wall moving along y survives "
                        "(capabilities feature 'periodic-2d'); use horizontal walls or an open box")
        zl = 6.0 * rmax
        dt = S["dt"]
        n = S["n_discs"]
        big = n > READ_DATA_ABOVE
        span = max(hi[0] - lo[0], hi[1] - lo[1])
        if big or zl < 0.25 * span:  # LIGGGHTS's mesh neighbour bins fail an assertion
            # (region_neighbor_list_I.h:165) when the periodic z span is small against the walls' length:
            # 0.25 x the box failed at 1e5 discs, 0.1 x at the 197-disc photoelastic box; 0.5 x works
            # at 197-1e5 discs (the nine-disc decks, 300 against 1200, keep their size)
            zl = max(zl, 0.5 * span)
        L = [
            "# demflow deck for LIGGGHTS-PUBLIC 3.8.0: 2D discs, linear law, walls with prescribed motion",
            "atom_style granular", "atom_modify map array sort 0 0", "dimension 2",
            "boundary p f p" if px is not None else "boundary f f p", "newton off",
            "communicate single vel yes", "units si",
        ]
        if big:  # box, atoms and velocities from a data file: O(N) (create_atoms + set atom is O(N^2))
            _write_data(deckdir / "discs.data", S, tid, nt, lo, hi, zl)
            L.append("read_data discs.data")
        else:  # small scenes keep the original deck text (the stored nine-disc references hold it)
            L += [f"region box block {_f(lo[0])} {_f(hi[0])} {_f(lo[1])} {_f(hi[1])} {_f(-zl)} {_f(zl)} units box",
                  f"create_box {nt} box"]
        L += [
            "neighbor " + _f(0.2 * rmax) + " bin", "neigh_modify delay 0",
            f"fix m1 all property/global kn peratomtypepair {nt} {table('kn')}",
            f"fix m2 all property/global kt peratomtypepair {nt} {table('ks')}",
            f"fix m3 all property/global gamman_abs peratomtypepair {nt} {table('cn')}",
            f"fix m4 all property/global gammat_abs peratomtypepair {nt} {table('cs')}",
            f"fix m5 all property/global coefficientFriction peratomtypepair {nt} {table('mu')}",
            "pair_style gran model hooke/stiffness tangential history absolute_damping on limitForce on",
            "pair_coeff * *", f"timestep {_f(dt)}",
        ]
        for i in range(0 if big else n):
            L.append(f"create_atoms {tid[S['discs']['material'][i]]} single {_f(x[i])} {_f(y[i])} 0.0 units box")
        for i in range(0 if big else n):
            m = S["discs"]["mass"][i]
            L.append(f"set atom {i + 1} diameter {_f(2 * r[i])} density {_f(m / (math.pi * r[i] ** 2))} "
                     f"vx {_f(S['discs']['vx'][i])} vy {_f(S['discs']['vy'][i])} omegaz {_f(S['discs']['omega'][i])}")
        meshes = []
        for k, w in enumerate(S["walls"]):
            ax, ay = w["px"] + w["h1"] * w["ex"], w["py"] + w["h1"] * w["ey"]
            bx, by = w["px"] + w["h2"] * w["ex"], w["py"] + w["h2"] * w["ey"]
            if px is not None:  # a horizontal wall (checked above), clipped to the period
                (ax, bx) = (lo[0], hi[0]) if ax < bx else (hi[0], lo[0])
            _stl(deckdir / f"w{k}.stl", ax, ay, bx, by, -zl, zl)
            L.append(f"fix w{k} all mesh/surface/stress file w{k}.stl type {tid[w['material']]} "
                     f"reference_point {_f(w['px'])} {_f(w['py'])} 0.0")
            meshes.append(f"w{k}")
        if meshes:
            L.append(f"fix walls all wall/gran model hooke/stiffness tangential history mesh n_meshes {len(meshes)} "
                     f"meshes {' '.join(meshes)} absolute_damping on limitForce on")
        # motion: piecewise-constant velocities by step (all inside one run)
        for k, w in enumerate(S["walls"]):
            s0 = 0
            vx_terms, vy_terms, om_terms = [], [], []
            origin = None
            for ph in w["phases"]:
                s1 = s0 + ph["cycles"]
                cond = f"(step>={s0 + 1})*(step<={s1})"
                if ph["vx"]:
                    vx_terms.append(f"{cond}*{_f(ph['vx'])}")
                if ph["vy"]:
                    vy_terms.append(f"{cond}*{_f(ph['vy'])}")
                if ph["omega"]:
                    if ph["pivot"] is not None:
                        piv = ph["pivot"]
                    else:  # about P: where demflow's P is when the phase starts
                        piv = self._p_at(w, s0, dt)
                    if origin is not None and (abs(origin[0] - piv[0]) > 1e-9 or abs(origin[1] - piv[1]) > 1e-9):
                        raise EngineUnsupported(
                            f"wall {w['name']!r} rotates about {piv} after rotating about {origin}; the LIGGGHTS "
                            "deck supports one rotation origin per wall (capabilities feature 'walls'): give "
                            "every rotating phase of a wall the same pivot")
                    origin = piv
                    om_terms.append(f"{cond}*{_f(ph['omega'])}")
                s0 = s1
            if vx_terms or vy_terms:
                L.append(f"variable w{k}vx equal {'+'.join(vx_terms) or '0.0'}")
                L.append(f"variable w{k}vy equal {'+'.join(vy_terms) or '0.0'}")
                L.append(f"variable w{k}vz equal 0.0")
                L.append(f"fix w{k}lin all move/mesh mesh w{k} linear/variable v_w{k}vx v_w{k}vy v_w{k}vz")
            if om_terms:
                L.append(f"variable w{k}om equal {'+'.join(om_terms)}")
                L.append(f"fix w{k}rot all move/mesh mesh w{k} rotate/variable origin {_f(origin[0])} {_f(origin[1])} 0.0 "
                         f"axis 0.0 0.0 1.0 omega v_w{k}om")
        gx, gy = S["gravity"]
        g = math.hypot(gx, gy)
        if g > 0.0:  # (scenes without gravity keep the deck text the stored references hold)
            L.append(f"fix grav all gravity {_f(g)} vector {_f(gx / g)} {_f(gy / g)} 0.0")
        L += ["fix integr all nve/sphere", "fix e2d all enforce2d"]
        every = int(S["every"])
        if every > 0:  # every = 0: no outputs at all (benchmarks)
            cols = []
            for k in range(len(S["walls"])):
                for c in (1, 2, 6):
                    L.append(f"variable w{k}f{c} equal f_w{k}[{c}]")
                    cols.append(f"${{w{k}f{c}}}")
            L.append("variable ke equal ke")
            L.append(f"fix rec all print {every} \"${{ke}} {' '.join(cols)}\" file walls.txt screen no title none")
            L.append("compute pg all pair/gran/local id pos force_normal force_tangential delta")
            L.append("compute wg all wall/gran/local id pos force_normal force_tangential delta")
            f16 = " ".join(["%.17g"] * 16)
            L.append(f"dump dc all local {every} contacts.txt " + " ".join(f"c_pg[{c}]" for c in range(1, 17)))
            L.append(f'dump_modify dc format "{f16}"')
            L.append(f"dump dw all local {every} wallcontacts.txt " + " ".join(f"c_wg[{c}]" for c in range(1, 17)))
            L.append(f'dump_modify dw format "{f16}"')
            L.append(f"dump dp all custom {every} particles.txt id x y vx vy omegaz radius")
            L.append('dump_modify dp sort id format "%d %.17g %.17g %.17g %.17g %.17g %.17g"')
        L.append("thermo_style custom step atoms ke")
        L.append("thermo 1000")
        L.append(f"run {int(S['n_steps'])}")
        L.append("print \"DEMFLOW-COMPLETE\"")
        deck = deckdir / "deck.in"
        deck.write_text("\n".join(L) + "\n")
        atomic_json(deckdir / "scene.json", S)
        return ([deck, deckdir / "scene.json"] + ([deckdir / "discs.data"] if big else [])
                + [deckdir / f"w{k}.stl" for k in range(len(S["walls"]))])

    @staticmethod
    def _p_at(w, step, dt):
        px, py = w["px"], w["py"]
        s0 = 0
        for ph in w["phases"]:
            k = max(0, min(ph["cycles"], step - s0))
            if ph["omega"] and k > 0:
                raise EngineUnsupported(
                    f"wall {w['name']!r}: a rotation about P after another rotation is not expressed in the LIGGGHTS "
                    "deck (P's path is not tracked through a rotation; capabilities feature 'walls'); give the "
                    "later phase an explicit pivot")
            px += ph["vx"] * dt * k
            py += ph["vy"] * dt * k
            s0 += ph["cycles"]
        return [px, py]

    def command(self, deckdir: Path):
        return ["stdbuf", "-o0", "-e0", self.path(), "-in", "deck.in", "-log", "log.liggghts", "-echo", "none"]

    def read(self, scene, sim, outdir: Path):
        """The result tables of a LIGGGHTS run in ``outdir``.  Every file is checked before use (its
        layout, row and column counts, finite numbers, body ids in range, the timesteps the deck
        asked for, in order); anything else raises EngineOutputError naming the file."""
        outdir = Path(outdir)
        log = outdir / "log.liggghts"
        try:
            complete = "DEMFLOW-COMPLETE" in log.read_text(errors="replace")
        except OSError:
            complete = False
        if not complete:
            raise EngineOutputError(f"LIGGGHTS did not complete scene {scene.name!r} (no completion mark in {log}); "
                                    "the output is truncated; rerun the engine")
        every = max(int(scene.outputs.every), 1)
        n, nw = sim.n, sim.nw
        n_steps = int(scene.n_steps)
        walls = _read_rows(outdir / "walls.txt", 1 + 3 * nw)
        if walls.shape[0] != n_steps // every:  # fix print: steps every, 2·every, ... up to n_steps
            raise EngineOutputError(f"LIGGGHTS walls.txt has {walls.shape[0]} rows, expected {n_steps // every} (one "
                                    f"every {every} steps to step {n_steps}); the output is truncated or corrupt; "
                                    "rerun the engine")
        dumps = np.arange(0, n_steps + 1, every)  # dumps: steps 0, every, ... up to n_steps
        pairs = _read_local(outdir / "contacts.txt", 16, dumps, {6: n, 7: n})
        wallc = _read_local(outdir / "wallcontacts.txt", 16, dumps, {6: nw - 1, 8: n}, wall_col=6)
        parts = _read_local(outdir / "particles.txt", 7, dumps, {0: n}, atoms=n)
        steps = every * np.arange(1, walls.shape[0] + 1, dtype=np.int64)
        wall = walls[:, 1:].reshape(-1, nw, 3)
        ppos = _wall_p_history(sim, steps)
        track = np.zeros((len(steps), len(sim.track), 2))
        for q, st in enumerate(steps):
            for t, (a, b) in enumerate(sim.track):
                track[q, t] = _pair_from_dumps(pairs.get(int(st)), wallc.get(int(st)), a, b, n)
        snaps = []
        for st in scene.outputs.snapshots:
            st = int(st)
            if st not in parts:
                continue
            p = parts[st]
            order = np.argsort(p[:, 0])
            p = p[order]
            prt = np.c_[p[:, 1], p[:, 2], np.full(len(p), np.nan), p[:, 3], p[:, 4], p[:, 5], p[:, 6]]
            cons = []
            for row in pairs.get(st, np.zeros((0, 16))):
                i1, i2 = int(row[6]) - 1, int(row[7]) - 1
                r = sim.r
                a, b = (i1, i2) if (r[i1] > r[i2] or (r[i1] == r[i2] and i1 < i2)) else (i2, i1)
                d = row[3:5] - row[0:2] if a == i1 else row[0:2] - row[3:5]  # from the finder a to b
                fn, fs, ex, ey = _decompose(row[9:11], row[12:14], d, a == i1)
                cons.append([a, b, 0.5 * (row[0] + row[3]), 0.5 * (row[1] + row[4]), ex, ey, fn, fs, row[15]])
            for row in wallc.get(st, np.zeros((0, 16))):
                w, a = int(row[6]), int(row[8]) - 1
                fn, fs, ex, ey = _decompose(row[9:11], row[12:14], row[0:2] - row[3:5], True)
                cons.append([a, n + w, row[0], row[1], ex, ey, fn, fs, row[15]])
            pw = _wall_p_history(sim, np.array([st]))[0]
            geo = [[pw[w, 0], pw[w, 1], np.nan, np.nan] for w in range(nw)]
            snaps.append(dict(step=st, particles=prt.tolist(), contacts=cons, walls=geo))
        return results_from_records(sim, engine="liggghts", steps=steps, wall=wall, wallpos=ppos, track=track,
                                    kinetic=walls[:, 0], snapshots=snaps)


def _decompose(fnv, ftv, d, on_finder):
    """fn, fs (demflow sign convention) and ε from the normal and tangential force on atom 1.

    d: vector from the finder towards the other body; on_finder: atom 1 is the finder.
    """
    fn = float(np.hypot(*fnv))
    L = float(np.hypot(*d))
    ex, ey = d / L if L > 0 else (np.nan, np.nan)
    tx, ty = ey, -ex
    ft_on_finder = np.asarray(ftv) if on_finder else -np.asarray(ftv)
    fs = -(ft_on_finder[0] * tx + ft_on_finder[1] * ty)
    return fn, fs, ex, ey


def _pair_from_dumps(prow, wrow, a, b, n):
    if b >= n:
        rows = wrow if wrow is not None else np.zeros((0, 16))
        for row in rows:
            if int(row[6]) == b - n and int(row[8]) - 1 == a:
                fn, fs, _, _ = _decompose(row[9:11], row[12:14], row[0:2] - row[3:5], True)
                return fn, fs
        return 0.0, 0.0
    rows = prow if prow is not None else np.zeros((0, 16))
    for row in rows:
        i1, i2 = int(row[6]) - 1, int(row[7]) - 1
        if {i1, i2} == {a, b}:
            d = (row[3:5] - row[0:2]) if i1 == a else (row[0:2] - row[3:5])
            fn, fs, _, _ = _decompose(row[9:11], row[12:14], d, i1 == a)
            return fn, fs
    return 0.0, 0.0


def _bad_output(path: Path, line: int | None, what: str):
    where = f"{path.name}" + (f", line {line}" if line is not None else "")
    return EngineOutputError(f"LIGGGHTS output {where}: {what}; the output is truncated or corrupt; rerun the engine "
                             f"(files in {path.parent})")


def _text(path: Path) -> str:
    try:
        return Path(path).read_text()
    except (OSError, ValueError) as e:  # missing, unreadable, or not text (UnicodeDecodeError)
        raise _bad_output(Path(path), None, f"cannot be read ({type(e).__name__}: {e})") from None


def _numbers(path: Path, line: int, text: str, ncol: int) -> list:
    """The ``ncol`` finite numbers of one data line."""
    fields = text.split()
    if len(fields) != ncol:
        raise _bad_output(path, line, f"{len(fields)} values where {ncol} are expected")
    try:
        row = [float(v) for v in fields]
    except ValueError:
        raise _bad_output(path, line, f"not a number in {text[:80]!r}") from None
    if not all(math.isfinite(v) for v in row):
        raise _bad_output(path, line, f"a non-finite value in {text[:80]!r}")
    return row


def _whole(path: Path, line: int, text: str) -> int:
    try:
        k = int(text.strip())
    except ValueError:
        raise _bad_output(path, line, f"{text[:40]!r} is not a whole number") from None
    if k < 0:
        raise _bad_output(path, line, f"{k} is negative")
    return k


def _read_rows(path: Path, ncol: int) -> np.ndarray:
    """A whitespace table of finite numbers, ``ncol`` per line (``fix print`` output)."""
    lines = _text(path).splitlines()
    rows = [_numbers(path, k + 1, ln, ncol) for k, ln in enumerate(lines) if ln.strip()]
    return np.array(rows, dtype=float).reshape(len(rows), ncol)


def dump_blocks(path: Path, ncol: int, atoms: bool = False):
    """The blocks of a LAMMPS-style dump, in file order: (timestep, line number of the block's first row,
    rows (count, ncol)).  Each block is a header (TIMESTEP, NUMBER OF ENTRIES or ATOMS, BOX BOUNDS and its
    three lines, ENTRIES or ATOMS) and its rows of ``ncol`` finite numbers; anything else is refused
    naming the file and the line."""
    lines = _text(path).splitlines()
    head = "ITEM: ATOMS" if atoms else "ITEM: ENTRIES"
    count_head = "ITEM: NUMBER OF ATOMS" if atoms else "ITEM: NUMBER OF ENTRIES"
    k = 0
    while k < len(lines):
        if not lines[k].strip():
            k += 1
            continue
        if lines[k].rstrip() != "ITEM: TIMESTEP":
            raise _bad_output(path, k + 1, f"expected 'ITEM: TIMESTEP', found {lines[k][:60]!r}")
        if k + 8 >= len(lines):
            raise _bad_output(path, k + 1, "a block header is cut short")
        step = _whole(path, k + 2, lines[k + 1])
        if lines[k + 2].rstrip() != count_head or not lines[k + 4].startswith("ITEM: BOX BOUNDS") \
                or not lines[k + 8].startswith(head):
            raise _bad_output(path, k + 1, f"the header of timestep {step} is not {count_head}, BOX BOUNDS, {head}")
        count = _whole(path, k + 4, lines[k + 3])
        first = k + 9
        if first + count > len(lines):
            raise _bad_output(path, k + 4, f"timestep {step} announces {count} rows, the file holds "
                                           f"{len(lines) - first}")
        rows = np.array([_numbers(path, first + q + 1, lines[first + q], ncol) for q in range(count)],
                        dtype=float).reshape(count, ncol)
        yield step, first + 1, rows
        k = first + count


def _read_local(path: Path, ncol: int, steps, ids: dict, *, atoms: int = 0, wall_col: int | None = None) -> dict:
    """Parse a LAMMPS-style dump (:func:`dump_blocks`) into {timestep: array (rows, ncol)}.

    The dump must hold exactly the timesteps ``steps``, in order; ``ids`` maps a column to the largest id
    it may hold (1-based atom ids, or from 0 in ``wall_col``); with ``atoms`` every block lists atoms
    1..atoms once each."""
    out = {}
    for step, row1, rows in dump_blocks(path, ncol, bool(atoms)):
        if step in out or (out and step < max(out)):
            raise _bad_output(path, row1 - 8, f"timestep {step} is repeated or out of order")
        for col, top in ids.items():
            v = rows[:, col]
            lo = 0 if col == wall_col else 1
            if not (np.all(v == np.round(v)) and np.all(v >= lo) and np.all(v <= top)):
                raise _bad_output(path, row1, f"timestep {step}: column {col + 1} holds an id outside {lo}..{top}")
        if atoms and not np.array_equal(np.sort(rows[:, 0]), np.arange(1, atoms + 1)):
            raise _bad_output(path, row1, f"timestep {step} does not list atoms 1..{atoms} once each")
        out[step] = rows
    if list(out) != [int(s) for s in steps]:
        raise _bad_output(path, None, f"it holds timesteps {_span(list(out))}, the deck wrote {_span(list(steps))}")
    return out


def _span(steps) -> str:
    return f"{steps[:3]}...{steps[-1:]} ({len(steps)})" if len(steps) > 4 else str([int(s) for s in steps])


def _wall_p_history(sim, steps):
    """Each wall's reference point P after each step in ``steps`` (demflow's kinematics)."""
    from ..walls import prescribed_wall_points

    return prescribed_wall_points(sim.walls, sim.loading, sim.dt, steps)
