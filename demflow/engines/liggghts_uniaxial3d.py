"""miyata-uniaxial-3d in LIGGGHTS-PUBLIC 3.8.0 (Debian ``liggghts``): the whole protocol as a
multisphere simulation, read into a :class:`~demflow.engines.uniaxial3d.UniaxialRun`.

Every number comes from :func:`demflow.engines.uniaxial3d.protocol_numbers` and reaches the decks
only as a validated finite number (:func:`demflow.engines.liggghts3d._f`); the decks hold fixed
identifiers only.

How the protocol is expressed:

- Bodies: ``fix particletemplate/multisphere`` with demflow's template (member centres in the
  principal frame, about the centre of mass) and ``mass M inertia_tensor I1 0 0 I2 0 I3
  use_density``: LIGGGHTS takes demflow's mass and principal moments as given (no Monte Carlo
  integration; the template's centre of mass is the origin of the member coordinates), read back
  from LIGGGHTS (``compute multisphere property masstotal/inertia``) into ``clump_mass`` and
  ``clump_inertia``.  Inserted by ``fix insert/pack`` (``orientation random``, ``all_in yes`` in a
  region covering the periodic box, so no two bounding spheres overlap across the period), seeds
  derived from ``params["seed"]`` (three primes > 10000 per pass, distinct for every seed 0..2999).  ``fix multisphere`` integrates them.
- Contact: ``pair_style gran model hertz tangential history limitForce on`` and the same law on the
  floor and plate meshes (one ``fix wall/gran``, ``limitForce on`` after the mesh list); E, ν per
  type (particles 1, walls 2), μ per pair, ``coefficientRestitution`` per pair solved so that
  LIGGGHTS's dashpot (on the *body* masses of the multisphere fix) has demflow's ζ_n
  (:func:`demflow.engines.liggghts3d.restitution_for_zeta`); ζ_t = ζ_n (LIGGGHTS's tangential
  dashpot shares β).  LIGGGHTS's tangential force is k_t × the total stored displacement, demflow's
  ``shear_spring`` is incremental: a model difference, not compensated.
- **No local (Cundall) damping.**  demflow and YADE run with local damping 0.3; LIGGGHTS 3.8 has no
  non-viscous damping for multisphere bodies (``fix multisphere`` has no damping keyword and its
  sources none; ``fix viscous`` is viscous and acts on member spheres).  This engine runs with
  the contact dashpots only: a difference between the engines (settling takes longer, the loading
  curve is the dashpots' only).
- Neighbour lists: ``neighbor`` skin = demflow's neighbour margin (``protocol_numbers``'s ``skin``),
  checked every step (``neigh_modify delay 0``).
- Box periodic in x and y (``boundary p p f``), the floor a two-triangle square mesh at z = 0
  covering the period, the plate the same square with normal −z, moved by ``fix move/mesh
  linear/variable`` (static while settling, then lowered to its start height at up to
  ``POSITION_SPEED`` with the exact travel, then at ``plate_speed``).
- **The trim is two LIGGGHTS invocations.**  ``delete_atoms`` on multisphere bodies in a periodic box
  leaves orphan frozen member spheres (LIGGGHTS 3.8 defect, /work/shared/ENGINES.md), so nothing is
  deleted: pass 1 (``deck1.in``) inserts ``n_insert`` bodies, settles them and writes the bodies'
  centres of mass; Python counts those at or below ``trim``; pass 2 (``deck2.in``, a fresh LIGGGHTS
  run, another insertion) inserts that many bodies, settles them (``settle_steps[0]``), settles
  again (``settle_steps[1]``), records the floor force and loads.  The pass-2 bed is therefore a
  fresh random bed of the kept count, not pass 1's bed minus its top.
- Settling: runs of ``settle_check_every`` steps until the bodies' kinetic energy (``compute
  ke/multisphere`` + ``erotate/multisphere``) < ``settle_ke_fraction`` × weight × 1 m, at most
  ``settle_max`` steps (a negative count if not at rest; the reader then refuses the run; a pass 1
  not at rest stops the engine before pass 2).
- Loading: the plate starts ``plate_gap`` above the highest member-sphere point; runs of
  ``record_every`` steps (``run N pre no post no``) until the plate stress reaches ``stress_max`` or
  the plate is below ``plate_z_min``; ``fix print`` records the mesh forces (``fix mesh/surface/stress``),
  ``compute wall/gran/local id force_normal ms_id`` (dumped every record) gives each member-sphere
  wall contact with its mesh and its body (``ms_id``); a particle's force on a wall is the sum of its
  members' normal forces, contacts are counted per body.  The plate height is computed from the
  steps it moved (z₀ − v Δt (step − s₀)) and checked against the mesh LIGGGHTS has when loading
  stops (``dump mesh/stl``, to 1e-5 m).
- Body membership (``mol``/``id_multisphere`` per atom, and ``ms_id`` in the wall contacts) is
  checked by the reader: after settling, the member spheres of each body (``atoms2.txt``) sit at the
  template's pairwise distances, and every wall contact's body is its atom's body.
"""
from __future__ import annotations

import json
import math
import os
import re
import subprocess
import time
from pathlib import Path

import numpy as np
import pandas as pd

from .base import (EngineFailed, EngineOutputError, EngineRun, EngineTimeout, EngineUnsupported, atomic_json,
                   sha256)
from .liggghts import LiggghtsEngine, _bad_output, _numbers, _read_rows, _text, dump_blocks
from .liggghts3d import _f, restitution_for_zeta
from ..shapes.clump import bounding_radius
from .uniaxial3d import CURVE_COLUMNS, SNAPSHOT_COLUMNS, per_particle_contacts, protocol_numbers, read_uniaxial_output

POSITION_SPEED = 50.0  # [m/s] the plate's speed when it is brought down to its start height (touches nothing)
PACKING = 0.2  # bounding-sphere volume fraction of the insertion region
BASE_MARKS = ("DEMFLOW-PASS1-COMPLETE", "DEMFLOW-COMPLETE")


def _i(x) -> str:
    k = int(x)
    if k != x or k < 0:
        raise EngineUnsupported(f"{x!r} is not a non-negative whole number for a LIGGGHTS deck")
    return str(k)


def _next_prime(n: int) -> int:
    n = max(int(n), 2)
    while any(n % d == 0 for d in range(2, int(math.isqrt(n)) + 1)):
        n += 1
    return n


def _seeds(seed, k: int) -> list[int]:
    """Three distinct primes > 10000 for the LIGGGHTS random generators of pass ``k`` (1 or 2), one set per
    ``params['seed']`` (0 ≤ seed < 3000: LIGGGHTS's seeds are 32-bit ints)."""
    s = int(seed)
    if s != seed or not 0 <= s < 3000:
        raise EngineUnsupported(f"seed {seed!r} must be a whole number in 0..2999 for the LIGGGHTS deck")
    return [_next_prime(100_000 * (1 + 6 * s + 3 * (k - 1) + j)) for j in range(3)]


def _square_stl(path: Path, L: float, z: float, normal_up: bool):
    """Two triangles covering [0, L]² at height z, facet normal +z or −z."""
    a, b, c, d = (0.0, 0.0), (L, 0.0), (L, L), (0.0, L)
    tris = [(a, b, c), (a, c, d)] if normal_up else [(a, c, b), (a, d, c)]
    nz = "1.0" if normal_up else "-1.0"
    out = ["solid plane"]
    for t in tris:
        out += [f"facet normal 0.0 0.0 {nz}", "outer loop"]
        out += [f"vertex {_f(p[0])} {_f(p[1])} {_f(z)}" for p in t]
        out += ["endloop", "endfacet"]
    out.append("endsolid plane")
    path.write_text("\n".join(out) + "\n")


class LiggghtsUniaxial3DEngine(LiggghtsEngine):
    """The miyata-uniaxial-3d protocol in LIGGGHTS (module docstring), case parameters ``params``
    (:attr:`demflow.cases.miyata_uniaxial3d.MiyataUniaxial3D.params`)."""

    def __init__(self, params: dict):
        self.params = dict(params)

    # ---------------------------------------------------------------- numbers and decks
    def _numbers(self, scene, sim) -> dict:
        N = protocol_numbers(scene, sim, self.params)
        P = N["protocol"]
        T = N["template"]
        pairs = N["sphere_pairs"] + N["plane_pairs"]
        for p in pairs:
            if not math.isclose(p["zt"], p["zn"], rel_tol=1e-12, abs_tol=0.0):
                raise EngineUnsupported("LIGGGHTS's tangential dashpot shares the normal one's β: ζ_t must equal ζ_n "
                                        f"(pair {p['a']}/{p['b']}: {p['zt']} vs {p['zn']})")
        M = N["materials"]
        pm, wm = N["particle_material"], N["plane_material"]
        if M[wm].get("rigid") or M[pm].get("rigid"):
            raise EngineUnsupported("the uniaxial LIGGGHTS deck takes elastic particles and walls (a material is rigid)")
        g = np.asarray(N["gravity"], float)
        if g[0] != 0.0 or g[1] != 0.0 or g[2] >= 0.0:
            raise EngineUnsupported(f"the uniaxial deck takes gravity along −z, not {g.tolist()}")
        c = np.asarray(T["centres"], float)
        r = np.asarray(T["radii"], float)
        if c.shape != (len(r), 3) or np.any(r <= 0):
            raise EngineUnsupported("the clump template needs K centres (K × 3) and K positive radii")
        for k in ("record_every", "settle_max", "settle_check_every", "n_insert"):
            if int(P[k]) <= 0:
                raise EngineUnsupported(f"protocol {k}={P[k]} must be a positive whole number")
        if P["record_every"] > P["settle_check_every"] or P["settle_check_every"] % P["record_every"]:
            raise EngineUnsupported("record_every must divide the settle check interval (the decks keep runs aligned "
                                    "to the record steps)")
        N["rb"] = bounding_radius(c, r)  # bounding sphere about the centre of mass
        N["pair_e"] = {f"{p['a']}|{p['b']}": restitution_for_zeta(p["zn"]) for p in pairs}
        return N

    def _deck(self, N: dict, n: int, pas: int) -> str:
        P = N["protocol"]
        T = N["template"]
        M = N["materials"]
        pm, wm = N["particle_material"], N["plane_material"]
        pp = N["sphere_pairs"][0]
        wp = N["plane_pairs"][0]
        L = P["box"]
        dt = N["dt"]
        gz = -float(N["gravity"][2])
        rb = N["rb"]
        R = int(P["record_every"])
        chk = int(P["settle_check_every"])
        nchk = max(1, -(-int(P["settle_max"]) // chk))
        z_ins0 = 0.05 + rb
        H = n * (4.0 / 3.0 * math.pi * rb ** 3) / (PACKING * L * L) + 2.0 * rb
        z_ins1 = z_ins0 + H
        z_plate0 = z_ins1 + 2.0 * rb  # the plate waits here while the bed settles (pass 2)
        z_top = z_plate0 + 4.0 * rb
        s1, s2, s3 = _seeds(self.params["seed"], pas)
        W = n * T["mass"] * gz
        thr = P["settle_ke_fraction"] * W * 1.0
        e_pp = N["pair_e"][f"{pp['a']}|{pp['b']}"]
        e_pw = N["pair_e"][f"{wp['a']}|{wp['b']}"]
        I = T["moments"]
        rho = float(M[pm]["density"])
        meshes = "n_meshes 2 meshes floor plate" if pas == 2 else "n_meshes 1 meshes floor"
        D = [
            f"# demflow deck for LIGGGHTS-PUBLIC 3.8.0: miyata-uniaxial-3d, pass {pas} of 2 ({n} clumps)",
            "atom_style granular", "atom_modify map array sort 0 0", "dimension 3", "boundary p p f", "newton off",
            "communicate single vel yes", "units si", "hard_particles yes", "processors 1 1 1",
            f"region box block 0.0 {_f(L)} 0.0 {_f(L)} {_f(-2.0 * rb)} {_f(z_top)} units box", "create_box 2 box",
            f"neighbor {_f(N['skin'])} bin", "neigh_modify delay 0",  # demflow's neighbour margin
            f"fix m1 all property/global youngsModulus peratomtype {_f(M[pm]['young'])} {_f(M[wm]['young'])}",
            f"fix m2 all property/global poissonsRatio peratomtype {_f(M[pm]['poisson'])} {_f(M[wm]['poisson'])}",
            f"fix m3 all property/global coefficientRestitution peratomtypepair 2 {_f(e_pp)} {_f(e_pw)} {_f(e_pw)} "
            f"{_f(e_pw)}",
            f"fix m4 all property/global coefficientFriction peratomtypepair 2 {_f(pp['mu'])} {_f(wp['mu'])} "
            f"{_f(wp['mu'])} {_f(wp['mu'])}",
            "pair_style gran model hertz tangential history limitForce on", "pair_coeff * *", f"timestep {_f(dt)}",
            f"fix grav all gravity {_f(gz)} vector 0.0 0.0 -1.0",
            "fix floor all mesh/surface/stress file floor.stl type 2",
        ]
        if pas == 2:
            D.append(f"fix plate all mesh/surface/stress file plate.stl type 2 move 0.0 0.0 {_f(z_plate0)}")
        D += [
            f"fix walls all wall/gran model hertz tangential history mesh {meshes} limitForce on",
            f"fix pts all particletemplate/multisphere {s1} atom_type 1 density constant {_f(rho)} "
            f"nspheres {_i(len(T['radii']))} ntry 1000000 spheres file template.txt scale 1.0 type 1 "
            f"mass {_f(T['mass'])} inertia_tensor {_f(I[0])} 0.0 0.0 {_f(I[1])} 0.0 {_f(I[2])} use_density",
            f"fix pdd all particledistribution/discrete {s2} 1 pts 1.0",
            f"region ins block 0.0 {_f(L)} 0.0 {_f(L)} {_f(z_ins0 - rb)} {_f(z_ins1 + rb)} units box",
            f"fix ins all insert/pack seed {s3} distributiontemplate pdd insert_every once overlapcheck yes "
            f"all_in yes orientation random maxattempt 1000 particles_in_region {_i(n)} region ins ntry_mc 100000",
            "fix ms all multisphere",
            "compute ke all ke/multisphere", "compute rke all erotate/multisphere",
            "compute rad all property/atom radius", "variable top atom z+c_rad", "compute zmax all reduce max v_top",
            "thermo_style custom step atoms c_ke c_rke c_zmax", f"thermo {_i(chk)}", "thermo_modify lost error norm no",
            "variable kt equal c_ke+c_rke",
            "variable ffz equal f_floor[3]",
            "compute bx all multisphere property xcm", "compute bm all multisphere property masstotal",
            "compute bi all multisphere property inertia",
        ]
        if pas == 2:  # LIGGGHTS wants it before the first run
            D.append("compute wc all wall/gran/local pos id force_normal ms_id")

        def settle(tag):
            return [f"variable k{tag} loop {_i(nchk)}", f"label L{tag}", f"run {_i(chk)}",
                    f'print "DEMFLOW-SETTLE-{tag} ${{k{tag}}} ${{kt}} {_f(thr)}"',
                    f'if "${{kt}} < {_f(thr)}" then "jump SELF E{tag}"', f"next k{tag}", f"jump SELF L{tag}",
                    f"label E{tag}"]

        D += settle("a")
        D.append('print "DEMFLOW-INSERTED $(atoms)"')
        if pas == 1:
            D += ["dump db all local 1 bodies1.txt c_bx[1] c_bx[2] c_bx[3]",
                  'dump_modify db format "%.17g %.17g %.17g"', "run 0", "undump db",
                  'print "DEMFLOW-PASS1-COMPLETE"']
            return "\n".join(D) + "\n"
        D += settle("b")
        D += [
            'print "DEMFLOW-SETTLED $(step) ${ffz} $(c_zmax)"',
            "dump db all local 1 bodies2.txt c_bx[1] c_bx[2] c_bx[3] c_bm c_bi[1] c_bi[2] c_bi[3]",
            'dump_modify db format "' + " ".join(["%.17g"] * 7) + '"',
            "dump da all custom 1 atoms2.txt id mol x y z radius",
            'dump_modify da format "%d %d %.17g %.17g %.17g %.17g"', "run 0", "undump db", "undump da",
            # the plate: down to its start height (highest member point + gap) in whole records, then at the speed
            f"variable zt equal $(c_zmax+{_f(P['plate_gap'])})",
            f"variable npos equal $({_i(R)}*ceil(({_f(z_plate0)}-v_zt)/({_f(POSITION_SPEED)}*{_f(dt)}*{_i(R)})))",
            # one velocity expression, defined once (a redefined variable shifts the indices move/mesh holds)
            "variable s0 equal $(step+v_npos)",
            f"variable vz equal (step<=v_s0)*$(-({_f(z_plate0)}-v_zt)/(v_npos*{_f(dt)}))+(step>v_s0)*"
            f"{_f(-P['plate_speed'])}",
            "variable vx equal 0.0", "variable vy equal 0.0",
            "fix mvp all move/mesh mesh plate linear/variable v_vx v_vy v_vz",
            f"variable zp equal v_zt-{_f(P['plate_speed'])}*{_f(dt)}*(step-v_s0)",
            f"variable ps equal f_plate[3]/{_f(L * L)}",
            "variable pfz equal f_plate[3]",
            f'fix rec all print {_i(R)} "$(step) ${{ffz}} ${{pfz}}" file curve_raw.txt screen no title none',
            # pos (6 values: the member's centre first) shifts id, force_normal and ms_id by 6
            f"dump dw all local {_i(R)} walls.txt c_wc[7] c_wc[9] c_wc[10] c_wc[11] c_wc[12] c_wc[14] c_wc[1] c_wc[2]",
            'dump_modify dw format "%g %g %.17g %.17g %.17g %g %.17g %.17g"',
            "run ${npos}",
            'print "DEMFLOW-PLATE ${s0} ${zt} ${npos}"',
            "label LL", f"run {_i(R)} pre no post no",
            f'if "${{ps}} >= {_f(P["stress_max"])}" then "jump SELF EL"',
            f'if "${{zp}} < {_f(P["plate_z_min"])}" then "jump SELF EL"',
            "jump SELF LL", "label EL",
            'print "DEMFLOW-LOADED $(step) ${ps} ${zp}"',
            "dump dm all mesh/stl 1 plate_end_*.stl plate", "run 0", "undump dm",  # where LIGGGHTS has the plate
            'print "DEMFLOW-COMPLETE"',
        ]
        return "\n".join(D) + "\n"

    def write_deck(self, scene, sim, deckdir: Path):
        """Pass 1's deck (``deck1.in``) and the shared inputs; pass 2's deck is written by :meth:`run`
        once pass 1 has said how many bodies stay (:meth:`write_pass2`)."""
        deckdir = Path(deckdir)
        N = self._numbers(scene, sim)
        c, r = np.asarray(N["template"]["centres"]), np.asarray(N["template"]["radii"])
        (deckdir / "template.txt").write_text("".join(f"{_f(a)} {_f(b)} {_f(z)} {_f(q)}\n" for (a, b, z), q in zip(c, r)))
        _square_stl(deckdir / "floor.stl", N["protocol"]["box"], 0.0, True)
        _square_stl(deckdir / "plate.stl", N["protocol"]["box"], 0.0, False)
        N.pop("bodies")  # demflow's lattice is not used: LIGGGHTS inserts its own bodies
        atomic_json(deckdir / "protocol.json", N)
        (deckdir / "deck1.in").write_text(self._deck(N, N["protocol"]["n_insert"], 1))
        return [deckdir / k for k in ("deck1.in", "template.txt", "floor.stl", "plate.stl", "protocol.json")]

    def write_pass2(self, deckdir: Path) -> tuple[Path, int]:
        deckdir = Path(deckdir)
        N = self._protocol(deckdir)
        if BASE_MARKS[0] not in _text(deckdir / "log1.liggghts"):
            raise EngineOutputError(f"LIGGGHTS did not complete pass 1 (no completion mark in "
                                    f"{deckdir / 'log1.liggghts'}); rerun the engine")
        s, kt = self._settle_record(deckdir / "log1.liggghts", "a", N)
        if s < 0:
            raise EngineOutputError(f"LIGGGHTS pass 1 did not come to rest within settle_max (checks in "
                                    f"{deckdir / 'log1.liggghts'}); raise settle_max")
        xcm = self._bodies(deckdir / "bodies1.txt", 3, N["protocol"]["n_insert"])
        keep = int(np.count_nonzero(xcm[:, 2] <= N["protocol"]["trim"]))
        if keep == 0:
            raise EngineOutputError(f"LIGGGHTS pass 1 left no body below the trim height ({deckdir / 'bodies1.txt'})")
        atomic_json(deckdir / "pass1.json", dict(n_inserted=N["protocol"]["n_insert"], n_kept=keep, settle_steps=s))
        (deckdir / "deck2.in").write_text(self._deck(N, keep, 2))
        return deckdir / "deck2.in", keep

    def command(self, deckdir: Path, deck: str = "deck1.in", log: str = "log1.liggghts"):
        return ["stdbuf", "-o0", "-e0", self.path(), "-in", deck, "-log", log, "-echo", "none"]

    # ---------------------------------------------------------------- running
    def run(self, scene, workdir, *, timeout: float = 3000.0, sim=None):
        """Pass 1, the count below ``trim``, pass 2 (module docstring); returns (UniaxialRun, EngineRun).
        ``timeout`` bounds both passes together."""
        from ..build import build

        self.path()
        sim = sim or build(scene)
        workdir = Path(workdir)
        workdir.mkdir(parents=True, exist_ok=True)
        for old in ("uniaxial_out.json", "curve.csv", "snapshots.csv", "log1.liggghts", "log2.liggghts",
                    "bodies1.txt", "bodies2.txt", "atoms2.txt", "walls.txt", "curve_raw.txt", "deck2.in",
                    "pass1.json"):
            (workdir / old).unlink(missing_ok=True)
        for old in workdir.glob("plate_end_*.stl"):
            old.unlink()
        inputs = self.write_deck(scene, sim, workdir)
        t0 = time.perf_counter()
        cmds = []
        for pas in (1, 2):
            if pas == 2:
                deck2, _ = self.write_pass2(workdir)
                inputs.append(deck2)
            cmd = self.command(workdir, f"deck{pas}.in", f"log{pas}.liggghts")
            cmds.append(cmd)
            left = timeout - (time.perf_counter() - t0)
            self._invoke(cmd, workdir, workdir / f"engine{pas}.log", left, scene)
        wall = time.perf_counter() - t0
        res = self.read(scene, sim, workdir)
        run = EngineRun(engine=self.name, version=self.version(), command=cmds, wall_time_s=round(wall, 3),
                        date=time.strftime("%Y-%m-%dT%H:%M:%S"), inputs={p.name: sha256(p) for p in inputs})
        res.meta.update(engine=self.name, engine_version=run.version, wall_time_s=run.wall_time_s)
        return res, run

    def _invoke(self, cmd, workdir: Path, log: Path, timeout: float, scene):
        env = dict(os.environ, OMP_NUM_THREADS="1")
        if timeout <= 0:
            raise EngineTimeout(f"{self.name} ran out of time before {cmd[4]} of scene {scene.name!r}")
        with open(log, "w") as fh:
            proc = subprocess.Popen(cmd, cwd=workdir, stdout=fh, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                    env=env, start_new_session=True)
            try:
                rc = proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, 9)  # stdbuf and LIGGGHTS, this run's own process group
                proc.wait()
                raise EngineTimeout(f"{self.name} did not finish {cmd[4]} of scene {scene.name!r} within the time "
                                    f"left ({timeout:.0f} s; log: {log}); raise the timeout") from None
        if rc != 0:
            tail = log.read_text(errors="replace")[-2000:]
            raise EngineFailed(f"{self.name} exited with status {rc} on {cmd[4]} of scene {scene.name!r}; last lines "
                               f"of {log}:\n{tail}")

    # ---------------------------------------------------------------- reading
    @staticmethod
    def _protocol(outdir: Path) -> dict:
        f = Path(outdir) / "protocol.json"
        try:
            N = json.loads(f.read_text())
            N["protocol"]["record_every"], N["template"]["mass"]
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise EngineOutputError(f"LIGGGHTS deck record {f} is missing or corrupt ({e!r}); rerun the engine") from None
        return N

    @staticmethod
    def _settle_record(log: Path, tag: str, N: dict) -> tuple[int, float]:
        """(steps to rest, or −steps run if never at rest; the last kinetic energy) from the deck's checks."""
        text = _text(log)
        chk = int(N["protocol"]["settle_check_every"])
        rows = re.findall(rf"^DEMFLOW-SETTLE-{tag} (\S+) (\S+) (\S+)\s*$", text, flags=re.M)
        if not rows:
            raise _bad_output(log, None, f"no settle check {tag!r} (the run stopped before settling)")
        k, kt, thr = (float(v) for v in rows[-1])
        if [int(float(r[0])) for r in rows] != list(range(1, len(rows) + 1)) or not (math.isfinite(kt) and kt >= 0):
            raise _bad_output(log, None, f"settle checks {tag!r} are out of order or not finite")
        return (len(rows) * chk if kt < thr else -len(rows) * chk), kt

    @staticmethod
    def _bodies(path: Path, ncol: int, n: int) -> np.ndarray:
        """The one block of a body dump (``dump local``, ``n`` rows of ``ncol`` finite numbers)."""
        blocks = _blocks(path, ncol)
        if len(blocks) != 1:
            raise _bad_output(path, None, f"{len(blocks)} dump blocks where one is expected")
        rows = next(iter(blocks.values()))
        if len(rows) != n:
            raise _bad_output(path, None, f"{len(rows)} bodies where the deck inserted {n}")
        return rows

    def read(self, scene, sim, outdir: Path):
        outdir = Path(outdir)
        N = self._protocol(outdir)
        P = N["protocol"]
        T = N["template"]
        log = outdir / "log2.liggghts"
        text = _text(log)
        if "DEMFLOW-COMPLETE" not in text:
            raise EngineOutputError(f"LIGGGHTS did not complete pass 2 (no completion mark in {log}); the output is "
                                    "truncated; rerun the engine")
        try:
            p1 = json.loads((outdir / "pass1.json").read_text())
            n_ins, n = int(p1["n_inserted"]), int(p1["n_kept"])
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise EngineOutputError(f"{outdir / 'pass1.json'} is missing or corrupt ({e!r}); rerun the engine") from None
        m = re.search(r"^DEMFLOW-INSERTED (\S+)\s*$", text, flags=re.M)
        K = len(T["radii"])
        if not m or int(float(m.group(1))) != n * K:
            raise _bad_output(log, None, f"pass 2 inserted {m.group(1) if m else 'no'} member spheres, not {n} × {K} "
                              "(insert/pack found no room? raise the region)")
        st_a, _ = self._settle_record(log, "a", N)
        st_b, _ = self._settle_record(log, "b", N)
        m = re.search(r"^DEMFLOW-SETTLED (\S+) (\S+) (\S+)\s*$", text, flags=re.M)
        mp = re.search(r"^DEMFLOW-PLATE (\S+) (\S+) (\S+)\s*$", text, flags=re.M)
        if not (m and mp):
            raise _bad_output(log, None, "the settled-state or plate line is missing")
        _, ffz, _ = _numbers(log, None, " ".join(m.groups()), 3)
        s0, z0, _ = _numbers(log, None, " ".join(mp.groups()), 3)
        bodies = self._bodies(outdir / "bodies2.txt", 7, n)
        mass, inertia = bodies[:, 3], bodies[:, 4:7]
        if np.ptp(mass) > 0 or np.any(np.ptp(inertia, axis=0) > 0):
            raise _bad_output(outdir / "bodies2.txt", None, "the bodies' masses or inertias differ (one template)")
        body_of = self._check_members(outdir / "atoms2.txt", N, n)
        A = P["box"] ** 2
        dt = N["dt"]
        v = P["plate_speed"]
        R = int(P["record_every"])
        raw = _read_rows(outdir / "curve_raw.txt", 3)
        raw = raw[raw[:, 0] > s0]
        steps = raw[:, 0].astype(np.int64)
        if len(steps) == 0 or np.any(np.diff(steps) != R) or steps[0] != s0 + R:
            raise _bad_output(outdir / "curve_raw.txt", None, f"its loading records are not every {R} steps from "
                              f"step {int(s0) + R}")
        walls = _blocks(outdir / "walls.txt", 8)
        missing = [int(s) for s in steps if int(s) not in walls]
        if missing:
            raise _bad_output(outdir / "walls.txt", None, f"no contact block for loading steps {missing[:5]}")
        rows, snaps, nsnap = [], [], 0
        levels = list(P["snapshot_levels"])
        touched = None
        for (s, ffz_s, pfz_s) in raw:
            zp = z0 - v * dt * (s - s0)
            plate, floor = pfz_s / A, -ffz_s / A
            if touched is None and plate > 0:
                touched = zp
            w = walls[int(s)]
            if len(w):
                tag = w[:, 1].astype(np.int64)
                if not (np.all(np.isin(w[:, 0], (0.0, 1.0))) and np.all(tag >= 1) and np.all(tag <= len(body_of))):
                    raise _bad_output(outdir / "walls.txt", None, f"timestep {int(s)}: a mesh index or atom id is out "
                                      "of range")
                if not np.array_equal(body_of[tag - 1], w[:, 5].astype(np.int64)):
                    raise _bad_output(outdir / "walls.txt", None, f"timestep {int(s)}: a contact's ms_id is not its "
                                      "atom's body")
            fn = np.linalg.norm(w[:, 2:5], axis=1) if len(w) else np.zeros(0)
            per, where = {}, {}
            for mesh, name in ((0.0, "floor"), (1.0, "plate")):
                on = (w[:, 0] == mesh) & (fn > 0) if len(w) else np.zeros(0, bool)
                per[name], where[name] = per_particle_contacts(w[on, 5].astype(np.int64), fn[on], w[on, 6:8], P["box"])
            rows.append((int(s - s0), zp, (touched - zp) if touched is not None else 0.0, plate, floor,
                         per["plate"].size, per["floor"].size))
            while levels and plate >= levels[0]:  # one snapshot per level reached (several at one record)
                snaps += [(nsnap, plate, name, float(f), float(x), float(y)) for name in ("plate", "floor")
                          for f, (x, y) in zip(per[name], where[name])]
                nsnap += 1
                levels.pop(0)
        ml = re.search(r"^DEMFLOW-LOADED (\S+) (\S+) (\S+)\s*$", text, flags=re.M)
        if not ml or int(float(ml.group(1))) != int(raw[-1, 0]):
            raise _bad_output(outdir / "curve_raw.txt", None, "its last record is not the step where loading stopped")
        if not (rows[-1][3] >= P["stress_max"] or rows[-1][1] < P["plate_z_min"]):
            raise _bad_output(outdir / "curve_raw.txt", None, "loading stopped before the plate reached stress_max or "
                              "plate_z_min")
        self._check_plate(outdir / f"plate_end_{int(raw[-1, 0])}.stl", rows[-1][1])
        pd.DataFrame(rows, columns=list(CURVE_COLUMNS)).to_csv(outdir / "curve.csv", index=False)
        pd.DataFrame(snaps, columns=list(SNAPSHOT_COLUMNS)).to_csv(outdir / "snapshots.csv", index=False)
        out = dict(n_inserted=n_ins, n_particles=n, weight=n * float(mass[0]) * -float(N["gravity"][2]),
                   floor_settled=-float(ffz), settle_steps=[st_a, st_b], dt=dt, plate_start=float(z0),
                   clump_mass=float(mass[0]), clump_inertia=[float(x) for x in inertia[0]], n_snapshots=nsnap,
                   template_mass=T["mass"], template_inertia=T["moments"], pass1_settle_steps=p1["settle_steps"],
                   local_damping=0.0)
        atomic_json(outdir / "uniaxial_out.json", out)
        run = read_uniaxial_output(outdir, self.name, A)
        run.meta.update(n_snapshots=nsnap)
        return run

    @staticmethod
    def _check_plate(path: Path, z: float):
        """The plate mesh LIGGGHTS wrote at the step loading stopped (``plate_end_STEP.stl``) lies at the
        height computed from its steps (``dump mesh/stl`` prints 6 significant digits: to 1e-5 m)."""
        zs = []
        for k, ln in enumerate(_text(path).splitlines()):
            w = ln.split()
            if w[:1] == ["vertex"]:
                zs.append(_numbers(path, k + 1, " ".join(w[1:]), 3)[2])
        if len(zs) != 6:
            raise _bad_output(path, None, f"{len(zs)} plate vertices where two triangles have 6")
        if max(abs(v - z) for v in zs) > 1e-5:
            raise _bad_output(path, None, f"the plate is at z = {zs[0]}, its steps put it at {z}")

    @staticmethod
    def _check_members(path: Path, N: dict, n: int) -> np.ndarray:
        """Each atom's body (index atom id − 1) after checking that every body's members sit at the
        template's pairwise distances (periodic x, y unwrapped by the minimum image) and radii."""
        blocks = _blocks(path, 6, atoms=True)
        if len(blocks) != 1:
            raise _bad_output(path, None, f"{len(blocks)} dump blocks where one is expected")
        d = next(iter(blocks.values()))
        c = np.asarray(N["template"]["centres"], float)
        r = np.asarray(N["template"]["radii"], float)
        K = len(r)
        L = N["protocol"]["box"]
        d = d[np.argsort(d[:, 0])]
        if len(d) != n * K or not np.array_equal(d[:, 0], np.arange(1, n * K + 1)):
            raise _bad_output(path, None, f"it does not list atoms 1..{n * K} once each")
        body = d[:, 1].astype(np.int64)
        ids, counts = np.unique(body, return_counts=True)
        if len(ids) != n or np.any(counts != K):
            raise _bad_output(path, None, f"{len(ids)} bodies with member counts {sorted(set(counts.tolist()))}, not "
                              f"{n} of {K}")
        ref = np.linalg.norm(c[:, None] - c[None], axis=2)
        for b in ids:
            mem = d[body == b]
            x = mem[:, 2:5]
            dx = x[:, None] - x[None]
            dx[..., :2] -= L * np.round(dx[..., :2] / L)
            dist = np.linalg.norm(dx, axis=2)
            # members in LIGGGHTS's order: match each by radius and distances (the template's order is kept)
            if not (np.allclose(np.sort(mem[:, 5]), np.sort(r), rtol=1e-9, atol=0)
                    and np.allclose(np.sort(dist.ravel()), np.sort(ref.ravel()), rtol=0, atol=1e-9 * L)):
                raise _bad_output(path, None, f"body {b}: its member spheres are not the template's (radii or "
                                  "pairwise distances differ): the atom → body map is wrong")
        return body


def _blocks(path: Path, ncol: int, atoms: bool = False) -> dict:
    """{timestep: rows} of a LAMMPS dump (``dump local``/``custom``; :func:`demflow.engines.liggghts.dump_blocks`),
    every row ``ncol`` finite numbers; a repeated step (a run's setup) keeps the later block: the same state."""
    return {step: rows for step, _, rows in dump_blocks(path, ncol, atoms)}


__all__ = ["LiggghtsUniaxial3DEngine"]
