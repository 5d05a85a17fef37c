"""YADE (Debian package ``yade``, 2023.02a) on 3D sphere scenes: deck writer, runner and reader.

How a :class:`~demflow.scene3d.Scene3D` with the Hertz-Mindlin law is expressed (the capabilities
table, :data:`demflow.engines.capabilities.FEATURES_3D`, says it row by row and the writer refuses
through it what YADE cannot express):

- spheres with demflow's mass and inertia per body; ``FrictMat`` per sphere material with its E, ν;
  ``Ip2_FrictMat_FrictMat_MindlinPhys`` computes kno = 4/3 E*√R*, kso = 8G*√R* with demflow's
  E* and G* (:func:`yade_moduli`, measured on 2023.02a);
- ``betan``, ``betas`` per material pair are demflow's damping ratios ζ_n, ζ_t (YADE's dashpot is
  2β√(m̄ k) with the tangent stiffnesses and m̄ the reduced mass: any demflow convention is exact);
  the friction angle per pair is atan μ (``frictAngle`` MatchMaker);
- ``Law2_ScGeom_MindlinPhys_Mindlin``: incremental shear force, rotated with the contact (demflow
  ``shear_spring='incremental'``), Coulomb on the total normal force;
- each plane is a ``Box`` whose material is chosen so that YADE's box-sphere geometry (both
  reference radii = R, so R* = R/2) gives demflow's kno and kso exactly (:func:`wall_material`);
  ``compensate_walls=False`` writes the plane's own material instead (YADE's R/2 wall, measured);
- planes move with their prescribed velocity, set before the InteractionLoop of each step.

``benchmark=True`` (speed runs, ``benchmarks/bench_engines3d.py``) writes the same ``scene.json`` with
the fixed program ``decks/yade_spheres3d_bench.py``: no PyRunner during the steps (static planes only;
moving ones are refused) and, after the run, only contact counts, kinetic energy and plane forces
(:func:`read_benchmark_output`).  The conformance decks are unchanged.
"""
from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np

from ..scene import check_identifier
from .base import EngineUnsupported, atomic_json
from .base3d import BenchmarkSummary, read_json_output, recorded_steps, scene3d_numbers, trajectory_from_arrays
from .capabilities import FEATURES_3D, refuse_inexpressible
from .yade import YadeEngine, _array, _bad, _entry


def yade_moduli(Ea, nua, Eb, nub) -> tuple[float, float]:
    """(E*, G*) as YADE 2023.02a's Ip2_FrictMat_FrictMat_MindlinPhys combines two materials
    (kno = 4/3 E*√R*, kso = 8G*√R*; measured: phys.kso of a glass sphere on a box of another material
    equals 8G*√R* with 1/G* = (2 − ν₁)/G₁ + (2 − ν₂)/G₂, as demflow and LIGGGHTS)."""
    E = 1.0 / ((1.0 - nua ** 2) / Ea + (1.0 - nub ** 2) / Eb)
    G = 1.0 / (2.0 * (2.0 - nua) * (1.0 + nua) / Ea + 2.0 * (2.0 - nub) * (1.0 + nub) / Eb)
    return E, G


def wall_material(Ea: float, nua: float, Estar: float, Gstar: float) -> tuple[float, float]:
    """(E_w, ν_w) of a box material that makes YADE's box-sphere contact (R* = R/2) reproduce a plane
    contact of effective moduli E*, G* (R* = R): YADE's E* and G* of the sphere against the box must be
    √2 E* and √2 G*.  The box's compliances c₁ = (1 − ν_w²)/E_w and c₂ = 2(2 − ν_w)(1 + ν_w)/E_w follow;
    their ratio gives ν_w = (4c₁ − c₂)/(2c₁ − c₂), then E_w = (1 − ν_w²)/c₁.  For a plane of the
    sphere's own material this is E/(√2 − 1) with the same ν (ENGINES.md); for a rigid plane the
    compliances are negative (E_w = −E/(1 − 1/√2), same ν).  Fictitious values: a compensation, not a
    material (YADE only combines them)."""
    c1 = 1.0 / (math.sqrt(2.0) * Estar) - (1.0 - nua ** 2) / Ea
    c2 = 1.0 / (math.sqrt(2.0) * Gstar) - 2.0 * (2.0 - nua) * (1.0 + nua) / Ea
    den = 2.0 * c1 - c2
    nuw = (4.0 * c1 - c2) / den if den != 0.0 else math.nan
    Ew = (1.0 - nuw ** 2) / c1 if c1 != 0.0 else math.nan
    if not (math.isfinite(Ew) and Ew != 0.0 and math.isfinite(nuw)):
        raise EngineUnsupported(f"no YADE box material reproduces this plane contact (E*={Estar}, G*={Gstar}, "
                                f"sphere E={Ea}, ν={nua}) (capabilities feature 'walls-3d'); run LIGGGHTS")
    return Ew, nuw


def sphere_pair_stiffness(p, m) -> None:
    """Check that YADE's moduli of a sphere-sphere material pair are demflow's (to round-off)."""
    a, b = m[p["a"]], m[p["b"]]
    E, G = yade_moduli(a["young"], a["poisson"], b["young"], b["poisson"])
    if not (math.isclose(E, p["Estar"], rel_tol=1e-13) and math.isclose(G, p["Gstar"], rel_tol=1e-13)):
        raise EngineUnsupported(f"YADE's moduli for materials ({p['a']}, {p['b']}) are E*={E}, G*={G}; demflow's "
                                f"{p['Estar']}, {p['Gstar']}")


def read_benchmark_output(path: Path) -> dict:
    """The benchmark deck's summary (steps, sphere_contacts, plane_contacts, kinetic, planes), refusing a
    missing or incomplete file."""
    return BenchmarkSummary(read_json_output(Path(path), "YADE"))


class Yade3DEngine(YadeEngine):
    """YADE on a :class:`~demflow.scene3d.Scene3D` (module docstring); the executable, version and command
    line are the 2D engine's.  ``compensate_walls=False`` writes YADE's own box (R* = R/2) and
    ``avoid_ratcheting=True`` YADE's default sphere-sphere geometry: both only to measure them."""

    deck = "yade_spheres3d.py"
    bench_deck = "yade_spheres3d_bench.py"

    def __init__(self, compensate_walls: bool = True, avoid_ratcheting: bool = False, benchmark: bool = False):
        self.compensate_walls = compensate_walls
        self.avoid_ratcheting = avoid_ratcheting
        self.benchmark = benchmark

    def write_deck(self, scene, sim, deckdir: Path):
        check_identifier("scene", scene.name)  # before any message or file names it
        refuse_inexpressible(self.name, scene, FEATURES_3D)
        S = scene3d_numbers(scene, sim)
        if self.benchmark and any(any(c != 0.0 for ph in pl["phases"] for c in ph["v"]) for pl in S["planes"]):
            raise EngineUnsupported("YADE's benchmark deck has static planes only (no PyRunner during the steps); "
                                    "run a scene with moving planes with benchmark=False")
        M = S["materials"]
        ym, pairs = {}, []
        for p in S["sphere_pairs"]:
            sphere_pair_stiffness(p, M)
            for m in (p["a"], p["b"]):
                ym[m] = dict(young=M[m]["young"], poisson=M[m]["poisson"])
            pairs.append(dict(a=p["a"], b=p["b"], betan=p["zn"], betas=p["zt"], phi=math.atan(p["mu"])))
        for m in set(S["spheres"]["material"]):
            ym.setdefault(m, dict(young=M[m]["young"], poisson=M[m]["poisson"]))
        for k, pl in enumerate(S["planes"]):
            wname = f"wall{k}"
            fits = [p for p in S["plane_pairs"] if p["b"] == pl["material"]]
            if self.compensate_walls:
                sols = [wall_material(M[p["a"]]["young"], M[p["a"]]["poisson"], p["Estar"], p["Gstar"]) for p in fits]
                Ew, nuw = sols[0]
                for (e2, n2), p in zip(sols[1:], fits[1:]):
                    if not (math.isclose(e2, Ew, rel_tol=1e-12) and math.isclose(n2, nuw, rel_tol=1e-12)):
                        raise EngineUnsupported(
                            f"plane {pl['name']!r} meets sphere materials {[f['a'] for f in fits]}; one compensated "
                            "YADE box material cannot give every pair demflow's stiffness (capabilities feature "
                            "'walls-3d'); give the spheres one material or run LIGGGHTS")
            else:
                if M[pl["material"]]["rigid"]:
                    raise EngineUnsupported(f"plane {pl['name']!r} is rigid (E = inf): YADE's own wall material "
                                            "cannot be rigid; compensate the walls or give the plane a finite modulus")
                Ew, nuw = M[pl["material"]]["young"], M[pl["material"]]["poisson"]
            ym[wname] = dict(young=Ew, poisson=nuw)
            pl["yade_material"] = wname
            for p in fits:
                pairs.append(dict(a=p["a"], b=wname, betan=p["zn"], betas=p["zt"], phi=math.atan(p["mu"])))
        for a in list(ym):  # every material pair needs a MatchMaker entry (unused ones: zeros)
            for b in list(ym):
                if not any({q["a"], q["b"]} == {a, b} for q in pairs):
                    pairs.append(dict(a=a, b=b, betan=0.0, betas=0.0, phi=0.0))
        S["yade_materials"] = ym
        S["yade_pairs"] = pairs
        x = np.array([S["spheres"][c] for c in ("x", "y", "z")])
        r = np.asarray(S["spheres"]["r"])
        extent = float(np.max(x.max(axis=1) - x.min(axis=1))) + 4 * float(r.max())
        b = S["box"]
        periodic = b["periodic_x"] or b["periodic_y"]
        if periodic and not (b["periodic_x"] and b["periodic_y"]):
            raise EngineUnsupported("YADE's periodic cell is periodic along x, y and z: a box periodic along one of x, "
                                    "y only is not expressed (capabilities feature 'periodic-3d'); make it periodic "
                                    "along both")
        span = max(extent, b["lx"], b["ly"])
        S["box"] = dict(periodic=periodic, lx=b["lx"], ly=b["ly"], lz=1e3 * span)
        S["yade_shift"] = [-b["x0"], -b["y0"], 0.0] if periodic else [0.0, 0.0, 0.0]
        S["wall_half_size"] = 100.0 * span
        S["wall_thickness"] = 4.0 * float(r.max())
        S["avoid_ratcheting"] = bool(self.avoid_ratcheting)
        S["compensate_walls"] = bool(self.compensate_walls)
        atomic_json(deckdir / "scene.json", S)
        deck = deckdir / "deck.py"
        program = self.bench_deck if self.benchmark else self.deck
        deck.write_text(resources.files("demflow.engines.decks").joinpath(program).read_text())
        return [deck, deckdir / "scene.json"]

    def read(self, scene, sim, outdir: Path):
        if self.benchmark:
            return read_benchmark_output(Path(outdir) / "yade_out.json")
        f = Path(outdir) / "yade_out.json"
        out = read_json_output(f, "YADE")
        rec = _entry(f, out, "rec", dict)
        want_s, want_p = recorded_steps(sim)
        got = {}
        for key, want in (("sphere_steps", want_s), ("plane_steps", want_p)):
            got[key] = _array(f, f"rec.{key}", _entry(f, rec, key, list), (-1,))
            if not np.array_equal(got[key], want):
                raise _bad(f, f"rec.{key}", f"records steps {got[key][:4].tolist()}... ({got[key].shape[0]}), the "
                                            f"deck records {want[:4].tolist()}... ({want.shape[0]})")
        spheres = _array(f, "rec.spheres", _entry(f, rec, "spheres", list), (len(want_s), sim.n, 9))
        planes = _array(f, "rec.planes", _entry(f, rec, "planes", list), (len(want_p), sim.n_planes, 3))
        res = trajectory_from_arrays(sim, "yade", want_s, spheres, want_p, planes)
        res.meta.update(compensate_walls=self.compensate_walls, avoid_ratcheting=self.avoid_ratcheting)
        return res
