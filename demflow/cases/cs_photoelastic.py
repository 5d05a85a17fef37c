"""cs-photoelastic: C&S's verification against the photoelastic disc test ("Verification test").

Stated (C&S): 197 discs (6 × R40, 7 × 35, 16 × 30, 33 × 25, 33 × 20, 36 × 18, 28 × 15, 38 × 10),
density 2000, four rigid walls; tan φ = 0.45 disc-disc, 0.17 disc-wall; kn = 1.5e9 and
ks = 1.0e9 (Table 1), ks = kn (Table 2), tan φ 0.40/0.08 with ks = kn (Table 3).  Experiment:
stage A F_H/F_V = 0.39; stage B: F_V raised by 4.348 % of F_V and F_H lowered by the same
amount (0.33).  C&S numerics (strain control): stage A 0.43/0.41/0.46, stage B 0.40/0.40/0.47;
ΔF/F (largest force sum on a disc / largest contact force) 0.1-2.6 %.

Lost, and assumed here (the report says so):

* the geometry (Fig. 10a, digitised by C&S): a seeded dense random packing with the same
  sizes (:mod:`~demflow.cases.photoelastic_packing`: frictionless isotropic jamming at a wall
  force F0 = 1e7, area fraction ≈ 0.82), the case's friction on from the first loading step;
* the wall numbering (Fig. 10): 1 bottom, 2 right, 3 top, 4 left — the only numbering that
  gives the signs of Tables 1-3 (wall 1's F_2 > 0, wall 3's < 0, wall 2's F_1 < 0, wall 4's > 0)
  with F the force of the wall on the assembly, as here;
* the strain path (C&S: "walls translated inward so that the ratio approximates the original
  value"; then "moved to the positions of Fig. 10b"): stage A = the top and bottom walls move
  in at ``speed`` while the side walls move out at ``side_ratio_a`` × speed for ``load_a``
  cycles; stage B = the same with ``side_ratio_b`` for ``load_b`` cycles (vertical force up,
  horizontal down, as in the experiment); each stage ends with ``rest`` cycles at rest.  The
  walls do not rotate (C&S's beams were free to rotate: their moments are reported as the
  eccentricity e/(L/2) instead);
* damping: contact dashpots only, cn = 2ζ√(m kn), cs = 2ζ√(m ks), ζ = 0.1 with m the mass of an
  R = 20 disc; no global damping, so that LIGGGHTS (which has none) runs the same scene;
* Δt = 0.1 × 2√(m_min/kn) (``dt_fraction``; the cycle counts are those at 0.1: a smaller fraction
  runs proportionally more cycles, so the walls move as far in the same time); normal force N = kn·δ
  (the form YADE and LIGGGHTS use; the packing starts pre-stressed, where the incremental form would
  start from zero force).

``other_tables`` = 0 leaves out the Table 2 and 3 runs and the fixed-side-wall stage B (informative
lines only); ``engine_refs`` = 0 leaves out the stored YADE and LIGGGHTS runs: both for a speed-accuracy
study (``tradeoff-cs-photoelastic``), which also reads :meth:`Photoelastic.observables`.

Stress-controlled variant (beyond C&S): the top and right walls are servo walls (thesis eqs
5.11-5.12) with the experiment's forces, stage A F_V = ``servo_fv`` and F_H = 0.39 F_V, stage B
F_V + 0.04348 F_V and F_H - 0.04348 F_V (0.33); bottom and left walls fixed.

Seed bands: the strain-controlled Table 1 case is repeated on ``n_seeds`` packings; every
statistic gets a 95 % prediction interval mean ± t(0.975, n-1)·s·√(1 + 1/n) (scipy.stats.t),
against which each engine's value is judged.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from ..analysis import forces as fstat
from ..analysis.micro import coordination_number, fabric_tensor
from ..plotting import contact_force_diagram, save_figure
from ..scene import ContactModel, Discs, LinearLaw, Material, Outputs, Phase, Scene, Servo
from .base import Case, CaseRun, Check, ReferencePlan
from .photoelastic_packing import DENSITY, INWARD, KN, WALLS, box_walls, min_mass, random_packing, ref_mass

SRC = "C&S (1979) verification test, Tables 1-3"
TABLES = {"table1": dict(ks=1.0e9, mu_dd=0.45, mu_dw=0.17), "table2": dict(ks=1.5e9, mu_dd=0.45, mu_dw=0.17),
          "table3": dict(ks=1.5e9, mu_dd=0.40, mu_dw=0.08)}
CS_RATIOS = {"table1": (0.43, 0.40), "table2": (0.41, 0.40), "table3": (0.46, 0.47)}  # C&S Figs 11-13
EXPERIMENT = (0.39, 0.33)
STEP_B = 0.04348  # C&S: F_V up by 4.348 % of F_V, F_H down by the same amount
CAS = {"bottom": 1, "right": 2, "top": 3, "left": 4}


def laws(table: str, zeta: float):
    t = TABLES[table]
    m = ref_mass()
    cn, cs = 2 * zeta * np.sqrt(m * KN), 2 * zeta * np.sqrt(m * t["ks"])
    return {("disc", "disc"): LinearLaw(kn=KN, ks=t["ks"], cn=cn, cs=cs, friction=t["mu_dd"]),
            ("disc", "wall"): LinearLaw(kn=KN, ks=t["ks"], cn=cn, cs=cs, friction=t["mu_dw"])}


def cycles(p, n) -> int:
    """``n`` cycles of the protocol (counted at Δt fraction 0.1) at the run's Δt fraction: a smaller
    fraction runs proportionally more cycles, so the walls move as far in the same time."""
    return int(round(n * 0.1 / p.get("dt_fraction", 0.1)))


def stage_steps(p):
    """(end of stage A, end of stage B) in cycles."""
    a = cycles(p, p["load_a"]) + cycles(p, p["rest"])
    return a, a + cycles(p, p["load_b"]) + cycles(p, p["rest"])


def servo_steps(p) -> int:
    """Cycles of each stage of the servo variant."""
    return cycles(p, p["servo_cycles"])


def strain_scene(packing, p, table="table1", name=None):
    """Strain-controlled stages A and B from ``packing`` (module docstring)."""
    v = p["speed"]
    phases = {}
    for w in WALLS:
        side = w in ("left", "right")
        d = np.asarray(INWARD[w])
        va = tuple((-p["side_ratio_a"] if side else 1.0) * v * d)
        vb = tuple((-p["side_ratio_b"] if side else 1.0) * v * d)
        phases[w] = (Phase(cycles(p, p["load_a"]), velocity=va), Phase(cycles(p, p["rest"])),
                     Phase(cycles(p, p["load_b"]), velocity=vb), Phase(cycles(p, p["rest"])))
    a, b = stage_steps(p)
    return _scene(packing, p, table, box_walls(*packing.box, phases=phases), b, (a, b),
                  name or f"photoelastic-{table}-seed{packing.seed}")


def servo_scene(packing, p, table="table1"):
    """Stress-controlled variant: top and right walls hold C&S's experimental forces."""
    fv = p["servo_fv"]
    fh = EXPERIMENT[0] * fv
    sa = servo_steps(p)
    g, vmax = p["servo_gain"], p["speed"]
    servos = {"top": Servo(fv, INWARD["top"], g, vmax, schedule=((sa, fv * (1 + STEP_B)),)),
              "right": Servo(fh, INWARD["right"], g, vmax, schedule=((sa, fh - STEP_B * fv),))}
    return _scene(packing, p, table, box_walls(*packing.box, servos=servos), 2 * sa, (sa, 2 * sa),
                  f"photoelastic-servo-seed{packing.seed}")


def _scene(packing, p, table, walls, n, snaps, name):
    return Scene(name=name, discs=Discs(x=packing.x, y=packing.y, radius=packing.r, material="disc"),
                 materials={"disc": Material(DENSITY), "wall": Material()}, laws=laws(table, p["zeta"]), walls=walls,
                 contact_model=ContactModel(normal="overlap"), dt=p.get("dt_fraction", 0.1) * 2.0 * np.sqrt(min_mass() / KN),
                 n_steps=n,
                 overlap_tolerance=1e-3, outputs=Outputs(every=p["every"], snapshots=tuple(snaps)),
                 description=f"C&S photoelastic test, {table}, packing seed {packing.seed}",
                 # Δt = 0.1 × 2√(m_min/kN) is 1.35-1.66× the safe estimate (integrate.safe_time_step: six
                 # smallest discs around a smallest one, dashpots ζ = 0.1 of the reference mass); this packing
                 # is looser and runs without the period-2 rotation of an unstable step (issue 17, measured)
                 allow_unsafe_dt=True)


# ----------------------------------------------------------------------------- stage quantities
def wall_table(contacts: pd.DataFrame) -> pd.DataFrame:
    """C&S Tables 1-3 quantities per wall from one snapshot's contacts (any engine).

    F1, F2 : force of the wall on the assembly [force] (C&S: components along axes 1, 2);
    e_rel : eccentricity of the normal wall force about the midpoint of the wall's side of the box
            over half that side's length, e/(L/2) (C&S Table 1 note 1), signed along the wall.
    """
    c = contacts[contacts.j < 0]
    # force on disc i from the wall: -(fn n + fs t), t = (ny, -nx) (demflow convention)
    fx = -(c.fn * c.nx + c.fs * c.ny)
    fy = -(c.fn * c.ny - c.fs * c.nx)
    side = {w: c[c.wall == w] for w in WALLS}
    pos = {w: (float(np.median(side[w].px)) if w in ("left", "right") else float(np.median(side[w].py)))
           if len(side[w]) else np.nan for w in WALLS}
    rows = []
    for w in WALLS:
        cw = side[w]
        horizontal = w in ("bottom", "top")
        lo, hi = (pos["left"], pos["right"]) if horizontal else (pos["bottom"], pos["top"])
        s = (cw.px if horizontal else cw.py) - 0.5 * (lo + hi)
        fn = cw.fn.to_numpy()
        e = float(np.sum(fn * s) / np.sum(fn)) / (0.5 * (hi - lo)) if fn.sum() > 0 else np.nan
        rows.append(dict(wall=w, cs_wall=CAS[w], F1=float(fx[cw.index].sum()), F2=float(fy[cw.index].sum()),
                         e_rel=e, contacts=len(cw)))
    return pd.DataFrame(rows).set_index("wall")


def force_ratio(walls: pd.DataFrame) -> float:
    """F_H/F_V: mean normal force of walls 2 and 4 over that of walls 1 and 3."""
    fh = 0.5 * (abs(walls.loc["right", "F1"]) + abs(walls.loc["left", "F1"]))
    fv = 0.5 * (abs(walls.loc["bottom", "F2"]) + abs(walls.loc["top", "F2"]))
    return float(fh / fv)


def equilibrium_ratio(contacts: pd.DataFrame, n: int) -> float:
    """ΔF/F: the largest resultant contact force on any disc over the largest contact force (C&S note 2)."""
    fx = -(contacts.fn * contacts.nx + contacts.fs * contacts.ny).to_numpy()
    fy = -(contacts.fn * contacts.ny - contacts.fs * contacts.nx).to_numpy()
    i, j = contacts.i.to_numpy(), contacts.j.to_numpy()
    F = np.zeros((n, 2))
    np.add.at(F[:, 0], i, fx)
    np.add.at(F[:, 1], i, fy)
    k = j >= 0
    np.add.at(F[:, 0], j[k], -fx[k])
    np.add.at(F[:, 1], j[k], -fy[k])
    return float(np.hypot(F[:, 0], F[:, 1]).max() / np.hypot(contacts.fn, contacts.fs).max())


STATS = ("F_H/F_V", "ΔF/F", "q-model N", "tail decay", "Mueth b", "Mueth β", "z (no rattlers)", "rattlers",
         "fabric anisotropy", "zero-force share")


def stage_statistics(res, step, n_discs) -> dict:
    """Every statistic of one stage snapshot (any engine's results)."""
    c = res.contacts[res.contacts.step == step]
    walls = wall_table(c)
    nf = fstat.normalized_forces(res, step=step)
    q = fstat.fit_q_model(nf.f)
    tail = fstat.fit_exponential_tail(nf.f)
    mu = fstat.fit_mueth(nf.f)
    z = coordination_number(res, step=step)
    fab = fabric_tensor(res, step=step)
    ev = np.linalg.eigvalsh(fab)
    return {"F_H/F_V": force_ratio(walls), "ΔF/F": equilibrium_ratio(c, n_discs), "q-model N": q.N,
            "q-model CI": tuple(q.ci), "tail decay": tail.beta, "Mueth b": mu.b, "Mueth β": mu.beta,
            "z (no rattlers)": z.z_no_rattlers, "rattlers": float(z.n_rattlers),
            "fabric anisotropy": float(2 * (ev[-1] - ev[0]) / (ev[-1] + ev[0])),
            "zero-force share": nf.n_zero / max(nf.n_total, 1), "walls": walls, "f": nf.f}


def prediction_band(values, level=0.95):
    """95 % prediction interval for one more seed: mean ± t·s·√(1 + 1/n) (scipy.stats.t)."""
    v = np.asarray(values, float)
    n = len(v)
    h = stats.t.ppf(0.5 + level / 2, n - 1) * v.std(ddof=1) * np.sqrt(1 + 1 / n)
    return float(v.mean() - h), float(v.mean() + h)


# ----------------------------------------------------------------------------- the case
class Photoelastic(Case):
    name = "cs-photoelastic"
    title = "C&S photoelastic verification: stages A/B, servo variant, force statistics, seed bands"
    source = SRC
    assumptions = (
        "Geometry (Fig. 10a) lost: seeded dense random packing of the 197 C&S discs (frictionless isotropic jamming "
        "at wall force 1e7, area fraction ≈ 0.82; method in demflow/cases/photoelastic_packing.py).",
        "Walls numbered 1 bottom, 2 right, 3 top, 4 left (the numbering that reproduces the signs of Tables 1-3); "
        "F = force of the wall on the assembly.",
        "Strain path: stage A top/bottom walls in at `speed`, side walls out at side_ratio_a × speed for load_a cycles; "
        "stage B the same with side_ratio_b for load_b cycles; `rest` cycles at rest after each. Walls do not rotate.",
        "Contact dashpots ζ = 0.1 (m of an R = 20 disc), no global damping (so LIGGGHTS runs the same scene); "
        "Δt = dt_fraction × 2√(m_min/kn), dt_fraction = 0.1 (cycle counts scale with 0.1/dt_fraction); N = kn·δ.",
        "Servo variant: top and right walls are servo walls (eqs 5.11-5.12) at the experiment's forces; bottom and "
        "left fixed; the ratio is that of the servo walls' contact reactions averaged over the last quarter of a stage.",
        "Seed band: 95 % prediction interval over n_seeds packings (t distribution); engines judged against it.",
    )
    params = dict(seed=1, n_seeds=8, speed=0.05, side_ratio_a=0.6, load_a=1800, side_ratio_b=1.5, load_b=1200,
                  rest=8000, zeta=0.1, every=100, servo_fv=5e8, servo_gain=0.5, servo_cycles=20000, dt_fraction=0.1,
                  other_tables=1, engine_refs=1)
    engines = ("yade", "liggghts")
    live = False

    def scenes(self, p):
        pk = random_packing(p["seed"])
        out = {t: strain_scene(pk, p, t) for t in TABLES}
        out["servo"] = servo_scene(pk, p)
        return out

    def run(self, p):
        from ..build import build

        out = {"packings": {}, "seeds": {}}
        a, b = stage_steps(p)
        for k in range(p["n_seeds"]):
            seed = p["seed"] + k
            pk = random_packing(seed)
            out["packings"][seed] = pk
            res = build(strain_scene(pk, p)).run().results()
            out["seeds"][seed] = {st: stage_statistics(res, s, len(pk.x)) for st, s in (("A", a), ("B", b))}
            if k == 0:
                out["demflow"] = res
        pk = out["packings"][p["seed"]]
        out["tables"] = {}
        out["fixed_sides_B"] = None
        if p["other_tables"]:
            for t in ("table2", "table3"):
                res = build(strain_scene(pk, p, t)).run().results()
                out["tables"][t] = {st: stage_statistics(res, s, len(pk.x)) for st, s in (("A", a), ("B", b))}
            # how much the stage-B band discriminates: the same run with the side walls fixed in stage B
            res = build(strain_scene(pk, dict(p, side_ratio_b=0.0), name=f"photoelastic-fixed-sides-seed{pk.seed}")
                        ).run().results()
            out["fixed_sides_B"] = stage_statistics(res, b, len(pk.x))["F_H/F_V"]
        out["tables"]["table1"] = out["seeds"][p["seed"]]
        res = build(servo_scene(pk, p)).run().results()
        out["servo"] = res
        out["servo_stats"] = {st: stage_statistics(res, s, len(pk.x))
                              for st, s in (("A", servo_steps(p)), ("B", 2 * servo_steps(p)))}
        out["engines"] = self._engines(p, pk) if p["engine_refs"] else {}
        out["engine_stats"] = {e: {st: stage_statistics(res, s, len(pk.x)) for st, s in (("A", a), ("B", b))}
                               for e, res in out["engines"].items()}
        return CaseRun({k: out.pop(k) for k in ("demflow", "servo")}, out)

    def reference_plan(self):
        return ReferencePlan(self.name, self.merged(), reference_variants, reference_scene)

    def comparison_case(self):
        return Photoelastic()

    # -- engines
    def _engines(self, p, pk):
        from ..engines import get_engine, reference

        stored = reference.available(self.name).get(f"seed{p['seed']}", [])
        out = {}
        for e in self.engines:
            if self.live:
                import tempfile

                with tempfile.TemporaryDirectory() as tmp:
                    out[e] = get_engine(e).run(strain_scene(pk, p), tmp)[0]
            elif e in stored:
                res = reference.load(self.name, f"seed{p['seed']}", e)
                made = res.meta.get("params")
                # a reference stored before a parameter existed was made with its default
                if made is not None and ({k: made.get(k, self.params[k]) for k in ENGINE_PARAMS}
                                         != {k: p[k] for k in ENGINE_PARAMS}):
                    raise ValueError(f"stored reference {self.name}/seed{p['seed']}/{e} was made with other parameters; "
                                     f"regenerate it (demflow reference {self.name} --engine {e}) or use the defaults")
                _same_packing(reference.location(self.name, f"seed{p['seed']}", e), pk)
                out[e] = res
        return out

    def checks(self, run, p):
        out = []
        src = SRC
        # strain-controlled, every seed
        for seed, st in run.extras["seeds"].items():
            for stage, (lo, hi) in (("A", (0.39, 0.46)), ("B", (0.33, 0.47))):
                r = st[stage]["F_H/F_V"]
                out.append(Check.condition(f"table1 seed {seed}, stage {stage}: F_H/F_V in [{lo}, {hi}] "
                                           f"(experiment to C&S numerics)", lo <= r <= hi, r, src,
                                           "Acceptance: the range from the experiment to C&S's numerical ratios", kind="source"))
                out.append(Check.against(f"table1 seed {seed}, stage {stage}: ΔF/F below 3 %", st[stage]["ΔF/F"], 0.0,
                                         "photoelastic.equilibrium", src))
        # what C&S's stage B does that the reconstructed strain path does not (Fig. 10b, the wall positions, is lost)
        seeds = run.extras["seeds"]
        fv = {k: np.array([0.5 * (abs(st[k]["walls"].loc["bottom", "F2"]) + abs(st[k]["walls"].loc["top", "F2"]))
                           for st in seeds.values()]) for k in ("A", "B")}
        growth = fv["B"] / fv["A"]
        out.append(Check.miss(
            f"stage B / stage A vertical wall force F_V, seeds 1-{len(seeds)} (C&S Tables 1-3: 3.4-5.8×; "
            f"demflow {growth.min():.2f}-{growth.max():.2f}×; value: the mean)", float(growth.mean()), 3.4, src,
            f"Stage B's wall displacements are in the lost Fig. 10b; the reconstruction moves the top and bottom "
            f"walls in for {p['load_b']} cycles ({p['load_b'] / p['load_a']:.2f}× stage A's) while the side walls "
            f"move out at {p['side_ratio_b']}× that speed, chosen for the stage-B ratio F_H/F_V, not for the force "
            "level: the vertical force barely changes, where C&S's grows 3.4-5.8×."))
        ra = np.array([st["A"]["F_H/F_V"] for st in seeds.values()])
        rb = np.array([st["B"]["F_H/F_V"] for st in seeds.values()])
        drops = int(np.sum(rb < ra))
        out.append(Check.miss(
            f"F_H/F_V falls from stage A to stage B (experiment 0.39 → 0.33, C&S Table 1 0.43 → 0.40): change B − A, "
            f"mean over seeds 1-{len(seeds)} (falls in {drops} of {len(seeds)})", float(np.mean(rb - ra)), -0.03, src,
            f"The change's sign depends on the packing: it falls in {drops} of {len(seeds)} seeds and rises in the "
            f"others (range {np.min(rb - ra):+.3f} to {np.max(rb - ra):+.3f}); stage B's strain path (Fig. 10b) is "
            "lost, and the reconstruction's is too mild to move the ratio by C&S's −0.03 reliably (see the stage-B "
            "force above).", relative=False))
        fixed = run.extras["fixed_sides_B"]
        if fixed is not None:
            out.append(Check.info(
                f"stage B band [0.33, 0.47] with the side walls fixed in stage B (seed {p['seed']}): F_H/F_V", fixed, src,
                f"How much the stage-B band says: with the side walls not moving at all in stage B the ratio is "
                f"{fixed:.3f}, {'inside' if 0.33 <= fixed <= 0.47 else 'outside'} the band, so a stage-B pass "
                f"{'does not show that the strain path is right' if 0.33 <= fixed <= 0.47 else 'depends on the side walls moving'}."))
        for t in (t for t in ("table2", "table3") if t in run.extras["tables"]):
            for stage in ("A", "B"):
                r = run.extras["tables"][t][stage]["F_H/F_V"]
                out.append(Check.info(f"{t} seed {p['seed']}, stage {stage}: F_H/F_V (C&S {CS_RATIOS[t]['AB'.index(stage)]})",
                                      r, src, "Information: C&S's ratio for this parameter set, other packing"))
        # stress-controlled
        sv = run.results["servo"].wall_forces
        sa = servo_steps(p)
        targets = {"A": EXPERIMENT[0], "B": (EXPERIMENT[0] - STEP_B) / (1 + STEP_B)}
        for stage, (s0, s1) in (("A", (0.75 * sa, sa)), ("B", (1.75 * sa, 2 * sa))):
            out.append(Check.against(f"servo, stage {stage}: the servo walls' own force ratio (right over top, the "
                                     f"controlled variable) held at {targets[stage]:.4f} (mean over the stage's last "
                                     "quarter)", servo_ratio(sv, s0, s1), targets[stage],
                                     "photoelastic.servo-hold", src + "; experiment's forces"))
            sst = run.extras["servo_stats"][stage]
            w = sst["walls"]
            out.append(Check.miss(
                f"servo, stage {stage}: the assembly's F_H/F_V measured as in the strain stages (walls 2 and 4 over 1 "
                f"and 3) vs the experiment's {EXPERIMENT['AB'.index(stage)]}", sst["F_H/F_V"],
                EXPERIMENT["AB".index(stage)], src,
                f"The servo sets the right wall's force against the top's; friction on the top and bottom walls "
                f"(tan φ_dw = 0.17) carries part of the horizontal load, so the fixed left wall pushes "
                f"{abs(w.loc['left', 'F1']) / abs(w.loc['right', 'F1']):.2f}× the right wall's force and the bottom "
                f"carries {abs(w.loc['bottom', 'F2']) / abs(w.loc['top', 'F2']):.2f}× the top's: the assembly's ratio "
                "is not the controlled one. A servo on the mean of opposite walls would be needed."))
            out.append(Check.against(f"servo, stage {stage}: ΔF/F below 3 %", run.extras["servo_stats"][stage]["ΔF/F"], 0.0,
                                     "photoelastic.equilibrium", src))
        # engines vs demflow, judged against the seed band
        bands = seed_bands(run) if run.extras["engine_stats"] else None
        ref = run.extras["seeds"][p["seed"]]
        for e, per_stage in run.extras["engine_stats"].items():
            for stage, st in per_stage.items():
                ks = stats.ks_2samp(ref[stage]["f"], st["f"])
                out.append(Check.condition(f"{e} vs demflow, stage {stage}: two-sample KS on f = F/<F> does not reject "
                                           f"at 5 % (p = {ks.pvalue:.3g})", ks.pvalue >= 0.05, ks.pvalue, src,
                                           "Acceptance: same packing and protocol; the KS p-value must be ≥ 0.05", kind="cross-code"))
                lo, hi = bands[stage]["q-model N"]
                N = st["q-model N"]
                out.append(Check.condition(f"{e}, stage {stage}: q-model N = {N:.3g} inside demflow's seed band "
                                           f"[{lo:.3g}, {hi:.3g}]", lo <= N <= hi, N, src,
                                           "Acceptance: engine difference judged against the seed-to-seed band", kind="cross-code"))
        return out

    def observables(self, run, p):
        """For a speed-accuracy study: on the first seed's strain-controlled run, per stage, F_H/F_V, the mean
        vertical wall force F_V, z without rattlers, the fabric anisotropy and the q-model N; on the servo
        variant, per stage, the servo walls' held ratio and the assembly's F_H/F_V."""
        out = {}
        st = run.extras["seeds"][p["seed"]]
        for stage in ("A", "B"):
            w = st[stage]["walls"]
            out[f"stage {stage}: F_H/F_V"] = st[stage]["F_H/F_V"]
            out[f"stage {stage}: F_V"] = 0.5 * (abs(w.loc["bottom", "F2"]) + abs(w.loc["top", "F2"]))
            for k in ("z (no rattlers)", "fabric anisotropy", "q-model N"):
                out[f"stage {stage}: {k}"] = float(st[stage][k])
        sa = servo_steps(p)
        wf = run.results["servo"].wall_forces
        for stage, (s0, s1) in (("A", (0.75 * sa, sa)), ("B", (1.75 * sa, 2 * sa))):
            out[f"servo, stage {stage}: servo walls' ratio"] = servo_ratio(wf, s0, s1)
            out[f"servo, stage {stage}: assembly F_H/F_V"] = run.extras["servo_stats"][stage]["F_H/F_V"]
        return out

    def tables(self, run, p):
        """The statistics table with bands (report page)."""
        return [(f"Stage {stage}: statistics, demflow seed band vs engines (same packing, seed {p['seed']})",
                 statistics_table(run, p, stage)) for stage in ("A", "B")] + [
            (f"Stage {stage}: wall forces (C&S Tables 1-3 quantities), seed {p['seed']}", wall_forces_table(run, p, stage))
            for stage in ("A", "B")]

    def figures(self, run, p, outdir):
        return photoelastic_figures(run, p, outdir)


def reference_variants(engine: str) -> tuple[str, ...]:
    """Variants stored under reference_runs/cs-photoelastic/: the default packing seed (both engines)."""
    return (f"seed{Photoelastic.params['seed']}",)


def reference_scene(variant: str, p: dict):
    """The strain-controlled Table 1 scene on the packing of seed ``variant`` ("seed<N>")."""
    seed = int(variant.removeprefix("seed"))
    return strain_scene(random_packing(seed), dict(p, seed=seed))


ENGINE_PARAMS = ("seed", "speed", "side_ratio_a", "load_a", "side_ratio_b", "load_b", "rest", "zeta", "every",
                 "dt_fraction")


def _same_packing(path, pk):
    """The stored engine run started from this packing (its scene.json), or a clear error."""
    import json

    d = json.loads((path / "scene.json").read_text())["discs"]
    dx = max(np.max(np.abs(np.asarray(d["x"]) - pk.x)), np.max(np.abs(np.asarray(d["y"]) - pk.y)))
    if not (len(d["x"]) == len(pk.x) and np.allclose(d["r"], pk.r, rtol=0, atol=0) and dx <= 1e-9):
        raise ValueError(f"the stored reference {path} started from another packing than demflow regenerates for "
                         f"seed {pk.seed} (max position difference {dx:.3g}); regenerate the reference")


def servo_ratio(wf: pd.DataFrame, s0, s1) -> float:
    """Mean F_H/F_V of the servo walls (right, top) between steps s0 and s1."""
    d = wf[(wf.step >= s0) & (wf.step <= s1)]
    fh = d[d.wall == "right"].fx.to_numpy()
    fv = d[d.wall == "top"].fy.to_numpy()
    return float(np.mean(np.abs(fh)) / np.mean(np.abs(fv)))


def seed_bands(run) -> dict:
    out = {}
    for stage in ("A", "B"):
        out[stage] = {k: prediction_band([s[stage][k] for s in run.extras["seeds"].values()]) for k in STATS}
    return out


def statistics_table(run, p, stage) -> pd.DataFrame:
    bands = seed_bands(run)
    cols = {}
    vals = {k: [s[stage][k] for s in run.extras["seeds"].values()] for k in STATS}
    cols["demflow mean over seeds"] = {k: np.mean(v) for k, v in vals.items()}
    cols["demflow s.d."] = {k: np.std(v, ddof=1) for k, v in vals.items()}
    cols["band low"] = {k: bands[stage][k][0] for k in STATS}
    cols["band high"] = {k: bands[stage][k][1] for k in STATS}
    cols[f"demflow seed {p['seed']}"] = {k: run.extras["seeds"][p["seed"]][stage][k] for k in STATS}
    for e, per_stage in run.extras["engine_stats"].items():
        cols[e] = {k: per_stage[stage][k] for k in STATS}
    return pd.DataFrame(cols).loc[list(STATS)]


def wall_forces_table(run, p, stage) -> pd.DataFrame:
    frames = {"demflow": run.extras["seeds"][p["seed"]][stage]["walls"]}
    for e, per_stage in run.extras["engine_stats"].items():
        frames[e] = per_stage[stage]["walls"]
    frames["demflow servo"] = run.extras["servo_stats"][stage]["walls"]
    return pd.concat(frames, names=["engine"])[["cs_wall", "F1", "F2", "e_rel", "contacts"]]


def _diagram(res, step, ax):
    """C&S-style contact-force plot, framed on the discs (the walls are longer than the box)."""
    contact_force_diagram(res, step=step, ax=ax)
    q = res.particles[res.particles.step == step]
    m = 0.03 * float(q.x.max() - q.x.min())
    ax.set_xlim(float((q.x - q.radius).min()) - m, float((q.x + q.radius).max()) + m)
    ax.set_ylim(float((q.y - q.radius).min()) - m, float((q.y + q.radius).max()) + m)


def photoelastic_figures(run, p, outdir):
    import matplotlib.pyplot as plt

    paths = []
    a, b = stage_steps(p)
    runs = {"demflow": run.results["demflow"], **run.extras["engines"]}
    fig, axs = plt.subplots(2, len(runs) + 1, figsize=(4.2 * (len(runs) + 1), 8.4))
    axs = np.atleast_2d(axs)
    for row, (stage, step) in enumerate((("A", a), ("B", b))):
        for col, (e, res) in enumerate(runs.items()):
            _diagram(res, step, axs[row, col])
            r = force_ratio(wall_table(res.contacts[res.contacts.step == step]))
            axs[row, col].set_title(f"{e}, stage {stage}: F_H/F_V = {r:.3f}", fontsize=9)
        sv = run.results["servo"]
        s = servo_steps(p) * (1 if stage == "A" else 2)
        _diagram(sv, s, axs[row, -1])
        w = wall_table(sv.contacts[sv.contacts.step == s])
        r = abs(w.loc["right", "F1"] / w.loc["top", "F2"])
        axs[row, -1].set_title(f"demflow servo, stage {stage}: applied F_H/F_V = {r:.3f}", fontsize=9)
    paths.append(save_figure(fig, f"{outdir}/force_plots.png", dpi=90))

    # PDFs with fits, linear and log
    bands = seed_bands(run)
    fig, axs = plt.subplots(2, 2, figsize=(11, 8))
    for row, (stage, step) in enumerate((("A", a), ("B", b))):
        for col, scale in enumerate(("linear", "log")):
            ax = axs[row, col]
            for e, res in runs.items():
                f = fstat.normalized_forces(res, step=step).f
                pdf = fstat.force_pdf(f, bins="linear" if scale == "linear" else "log")
                k = pdf.density > 0  # empty bins are not drawn (log axes)
                ax.plot(pdf.centers[k], pdf.density[k], "o-" if e == "demflow" else "s--", ms=3, lw=1, label=e)
            f = run.extras["seeds"][p["seed"]][stage]["f"]
            x = np.linspace(1e-3, max(f.max(), 4), 300)
            q = fstat.fit_q_model(f)
            ax.plot(x, fstat.q_model_pdf(x, q.N), "k-", lw=1, label=f"q-model N = {q.N:.2f}")
            mu = fstat.fit_mueth(f)
            ax.plot(x, fstat.mueth_pdf(x, mu.b, mu.beta), "k:", lw=1, label=f"Mueth b = {mu.b:.2f}, β = {mu.beta:.2f}")
            lo, hi = bands[stage]["q-model N"]
            ax.fill_between(x, fstat.q_model_pdf(x, lo), fstat.q_model_pdf(x, hi), color="0.85",
                            label="q-model, seed band of N")
            ax.set_yscale(scale)
            if scale == "log":
                ax.set_xscale("log")
                ax.set_ylim(1e-3, 3)
            ax.set_xlabel("f = F/<F>")
            ax.set_ylabel("P(f)")
            ax.set_title(f"stage {stage}, {scale} axes")
            ax.legend(fontsize=7)
    paths.append(save_figure(fig, f"{outdir}/force_pdfs.png", dpi=90))

    # servo histories
    wf = run.results["servo"].wall_forces
    fig, ax = plt.subplots(figsize=(8, 3.5))
    top = wf[wf.wall == "top"]
    right = wf[wf.wall == "right"]
    ax.plot(top.step, np.abs(right.fx.to_numpy()) / np.maximum(np.abs(top.fy.to_numpy()), 1e-30), lw=1)
    sa = servo_steps(p)
    for (s0, s1), tgt in (((0, sa), EXPERIMENT[0]), ((sa, 2 * sa), (EXPERIMENT[0] - STEP_B) / (1 + STEP_B))):
        ax.hlines(tgt, s0, s1, colors="k", linestyles="--")
    ax.set_ylim(0, 1)
    ax.set_xlabel("cycles")
    ax.set_ylabel("F_H/F_V (servo walls)")
    ax.set_title("stress-controlled variant: targets 0.39 (A) and 0.332 (B)")
    paths.append(save_figure(fig, f"{outdir}/servo_ratio.png", dpi=100))

    # seed scatter of the ratio
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for stage, m in (("A", "o"), ("B", "s")):
        r = [s[stage]["F_H/F_V"] for s in run.extras["seeds"].values()]
        ax.plot(list(run.extras["seeds"]), r, m, label=f"stage {stage}")
    ax.axhspan(0.39, 0.46, color="C0", alpha=0.1)
    ax.axhspan(0.33, 0.47, color="C1", alpha=0.1)
    ax.set_xlabel("packing seed")
    ax.set_ylabel("F_H/F_V")
    ax.legend(fontsize=8)
    paths.append(save_figure(fig, f"{outdir}/seed_ratios.png", dpi=100))
    return paths
