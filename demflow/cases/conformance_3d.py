"""conformance-3d: the same small 3D Hertz-Mindlin scenes in demflow, YADE and LIGGGHTS.

Scenes (each starts out of contact with no contact force acting, so v(0) and v(−Δt/2) differ only
by gravity, which the LIGGGHTS deck accounts for):

- ``head-on``: a glass and a limestone sphere of unlike radii and masses meet head on
  (frictionless, e = 0.5: the dashpot's reduced mass);
- ``oblique-plane``: a glass sphere with backspin hits a glass plane at 30° from the normal
  (μ = 0.3, e = 0.5: stick then slip);
- ``periodic-pair``: two glass spheres meet obliquely across x = 0 of a box periodic along x and y
  (μ = 0.3, e = 0.7, spins about z): the contact normal turns;
- ``moving-plate``: a glass sphere falls (gravity) onto a rigid plate moving at 0.1 m/s along x,
  bounces, slides and rolls; ``moving-plate-phases``: the plate's velocity then jumps twice during
  contact.

Each scene with a tangential force exists in both shear-spring modes: ``<scene>`` (incremental,
YADE's) and ``<scene>-total`` (LIGGGHTS's).  Variants that isolate a named difference:
``oblique-plane-no-shear-damping`` (e_t = 1), ``oblique-plane-r2`` (YADE run with its own R/2 box,
``compensate_walls=False``), ``periodic-pair-ratcheting`` (YADE's default
``avoidGranularRatcheting``), ``periodic-pair-dt2``/``-total-dt2`` (half Δt: the history-rotation
difference is first order in Δt), ``oblique-plane-lift`` (the plane starts rising at 0.3 m/s during
the contact: LIGGGHTS's contact sees a normal velocity switch one step late).
"""
from __future__ import annotations

import dataclasses
import math

from ..laws.hertz_mindlin import HertzMindlinLaw
from ..scene import Box, Material
from ..scene3d import Outputs3D, Plane, PlanePhase, Scene3D, Spheres
from .base import Case, CaseRun, Check, ParameterError

CASE = "conformance-3d"
GLASS = Material(density=2800.0, young=4.8e10, poisson=0.20)
LIMESTONE = Material(density=2500.0, young=2.0e10, poisson=0.25)
RIGID = Material(density=0.0, young=math.inf, poisson=0.30)
R = 0.005
DT_FRACTION = 0.1
LIFT_STEP = 40  # oblique-plane-lift: the plane's normal velocity switches at this step (during the contact)


def head_on(p) -> Scene3D:
    ra, rb = R, 0.6 * R
    gap = 0.004 * R
    law = HertzMindlinLaw(friction=0.0, restitution=0.5, tangential="none")
    return Scene3D(name="conf-head-on",
                   spheres=Spheres(x=[-ra - gap / 2, rb + gap / 2], y=[0.0, 0.0], z=[0.0, 0.0], radius=[ra, rb],
                                   material=["glass", "limestone"], velocity=[[1.0, 0.0, 0.0], [-1.5, 0.0, 0.0]]),
                   materials={"glass": GLASS, "limestone": LIMESTONE},
                   laws={("glass", "limestone"): law}, dt_fraction=p["dt_fraction"], n_steps=200,
                   outputs=Outputs3D(every=1))


def oblique_plane(p, shear_spring="incremental", restitution_tangential=None, friction_cap="total",
                  lift=False) -> Scene3D:
    a = math.radians(30.0)
    v = 1.0
    law = HertzMindlinLaw(friction=0.3, restitution=0.5, restitution_tangential=restitution_tangential,
                          shear_spring=shear_spring, friction_cap=friction_cap)
    return Scene3D(name="conf-oblique-plane",
                   spheres=Spheres(x=[0.0], y=[0.0], z=[R * 1.002], radius=[R], material="glass",
                                   velocity=[[v * math.sin(a), 0.0, -v * math.cos(a)]],
                                   angular_velocity=[[0.0, -60.0, 0.0]]),
                   materials={"glass": GLASS, "plate": GLASS},
                   laws={("glass", "plate"): law},
                   planes=[Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "plate",
                                 phases=(PlanePhase(LIFT_STEP, (0.0, 0.0, 0.0)), PlanePhase(180, (0.05, 0.0, 0.3)))
                                 if lift else ())],
                   dt_fraction=p["dt_fraction"], n_steps=220, outputs=Outputs3D(every=1))


def periodic_pair(p, shear_spring="incremental", dt_fraction=None) -> Scene3D:
    L = 0.03
    gap = 0.004 * R
    b = 0.4 * 2 * R  # impact parameter along y
    law = HertzMindlinLaw(friction=0.3, restitution=0.7, shear_spring=shear_spring)
    ax = L - math.sqrt((2 * R + gap) ** 2 - b * b) / 2
    bx = ax + math.sqrt((2 * R + gap) ** 2 - b * b) - L
    return Scene3D(name="conf-periodic-pair",
                   spheres=Spheres(x=[ax, bx], y=[0.5 * L - b / 2, 0.5 * L + b / 2], z=[0.01, 0.01], radius=[R, R],
                                   material="glass", velocity=[[1.0, 0.2, 0.0], [-1.0, -0.1, 0.0]],
                                   angular_velocity=[[0.0, 0.0, 40.0], [0.0, 0.0, -25.0]]),
                   materials={"glass": GLASS}, laws={("glass", "glass"): law},
                   box=Box(periodic_x=(0.0, L), periodic_y=(0.0, L)),
                   dt_fraction=dt_fraction or p["dt_fraction"], n_steps=200 * (2 if dt_fraction else 1),
                   outputs=Outputs3D(every=1))


def moving_plate(p, shear_spring="incremental", phases=False) -> Scene3D:
    """A glass sphere falls onto a rigid plate moving at 0.1 m/s along x, bounces, slides and rolls.
    With ``phases`` the plate's velocity then jumps to 0.15 m/s, to 0.05 m/s and to rest (velocity
    switches during contact)."""
    law = HertzMindlinLaw(friction=0.3, restitution=0.5, shear_spring=shear_spring)
    if phases:
        n = 26000
        ph = (PlanePhase(18000, (0.1, 0.0, 0.0)), PlanePhase(4000, (0.15, 0.0, 0.0)),
              PlanePhase(2000, (0.05, 0.0, 0.0)))
    else:
        n = 24000
        ph = (PlanePhase(n, (0.1, 0.0, 0.0)),)
    return Scene3D(name="conf-moving-plate" + ("-phases" if phases else ""),
                   spheres=Spheres(x=[0.0], y=[0.0], z=[R + 2e-6], radius=[R], material="glass"),
                   materials={"glass": GLASS, "steel": RIGID}, laws={("glass", "steel"): law},
                   planes=[Plane("plate", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "steel", phases=ph)],
                   gravity=(0.0, 0.0, -9.81), dt_fraction=p["dt_fraction"], n_steps=n, outputs=Outputs3D(every=40))


def r2_emulated(p) -> Scene3D:
    """oblique-plane with the plane YADE's own box gives a glass sphere: R* = R/2 scales kno and kso
    by 1/√2, which a glass plane of modulus E/(2√2 − 1) (same ν) gives at R* = R."""
    sc = oblique_plane(p)
    return dataclasses.replace(sc, name="conf-oblique-plane-r2-emulated", materials={
        "glass": GLASS, "plate": Material(density=GLASS.density, young=GLASS.young / (2 * math.sqrt(2) - 1),
                                          poisson=GLASS.poisson)})


SCENES = {"head-on": lambda p, spring: head_on(p),
          "oblique-plane": lambda p, spring: oblique_plane(p, spring),
          "oblique-plane-no-shear-damping": lambda p, spring: oblique_plane(p, spring, restitution_tangential=1.0),
          "oblique-plane-elastic-cap": lambda p, spring: oblique_plane(p, spring, friction_cap="elastic"),
          "oblique-plane-lift": lambda p, spring: oblique_plane(p, spring, lift=True),
          "oblique-plane-r2": lambda p, spring: oblique_plane(p, spring),
          "oblique-plane-r2-emulated": lambda p, spring: r2_emulated(p),
          "periodic-pair": lambda p, spring: periodic_pair(p, spring),
          "periodic-pair-ratcheting": lambda p, spring: periodic_pair(p, spring),
          "periodic-pair-dt2": lambda p, spring: periodic_pair(p, spring, dt_fraction=p["dt_fraction"] / 2),
          "moving-plate": lambda p, spring: moving_plate(p, spring),
          "moving-plate-phases": lambda p, spring: moving_plate(p, spring, phases=True)}

# variant -> the engines that store a reference of it.  "<scene>" is in YADE's shear-spring mode
# (incremental), "<scene>-total" in LIGGGHTS's; head-on has no tangential force (both run it).
VARIANTS = {
    "head-on": ("yade", "liggghts"),
    "oblique-plane": ("yade",), "oblique-plane-total": ("liggghts",),
    "oblique-plane-no-shear-damping": ("yade",), "oblique-plane-no-shear-damping-total": ("liggghts",),
    "periodic-pair": ("yade",), "periodic-pair-total": ("liggghts",),
    "moving-plate": ("yade",), "moving-plate-total": ("liggghts",),
    # named differences: YADE with its own R/2 box; YADE's default avoidGranularRatcheting; half Δt
    "oblique-plane-r2": ("yade",), "periodic-pair-ratcheting": ("yade",),
    "periodic-pair-dt2": ("yade",), "periodic-pair-total-dt2": ("liggghts",),
    "moving-plate-phases": ("yade",), "moving-plate-phases-total": ("liggghts",),
    "oblique-plane-lift": ("yade",), "oblique-plane-lift-total": ("liggghts",),  # plane-velocity timing
}
CONFORMANCE = ("head-on", "oblique-plane", "oblique-plane-total", "oblique-plane-no-shear-damping",
               "oblique-plane-no-shear-damping-total", "periodic-pair", "periodic-pair-total", "moving-plate",
               "moving-plate-total", "periodic-pair-dt2", "periodic-pair-total-dt2", "moving-plate-phases",
               "moving-plate-phases-total", "oblique-plane-lift")
# the engine options of a variant (YADE's own geometry where a named difference is measured)
ENGINE_OPTIONS = {("oblique-plane-r2", "yade"): dict(compensate_walls=False),
                  ("periodic-pair-ratcheting", "yade"): dict(avoid_ratcheting=True)}


def scene(variant: str, p: dict) -> Scene3D:
    """The scene of a variant (module docstring); ``-total`` selects LIGGGHTS's shear-spring mode."""
    spring = "total" if "-total" in variant else "incremental"
    base = variant.replace("-total", "")
    if base not in SCENES:
        raise KeyError(f"no conformance-3d variant {variant!r}; variants: {', '.join(VARIANTS)}")
    return SCENES[base](p, spring)


def variants_for(engine: str) -> tuple[str, ...]:
    return tuple(v for v, es in VARIANTS.items() if engine in es)


def engine_for(engine: str, variant: str):
    """The engine object that runs ``variant`` (3D engines; YADE's own geometry where measured)."""
    from ..engines import get_engine3d

    return get_engine3d(engine, **ENGINE_OPTIONS.get((variant, engine), {}))


PARAMS = dict(dt_fraction=DT_FRACTION)

SRC = "YADE 2023.02a and LIGGGHTS-PUBLIC 3.8.0 (stored reference runs, reference_runs/conformance-3d)"


def conformance_tolerance(variant: str) -> str:
    """The tolerance a conformance variant is held to: round-off, except where the contact normal turns
    (the periodic pair), where the named history-rotation difference is the bound."""
    return "engines3d.history-rotation" if variant.startswith("periodic-pair") else "engines3d.round-off"


def demflow_runs(p: dict, variants) -> dict:
    """demflow's trajectory of every scene the comparisons need (each scene run once)."""
    from ..build import build
    from ..engines.base3d import demflow_trajectory

    need = set(variants) | {"oblique-plane-elastic-cap", "oblique-plane-r2-emulated"}
    same = {"oblique-plane-r2": "oblique-plane", "periodic-pair-ratcheting": "periodic-pair"}  # same scene
    runs, by_scene = {}, {}
    for v in sorted(need):
        key = same.get(v, v)
        if key not in by_scene:
            by_scene[key] = demflow_trajectory(build(scene(key, p)))
        runs[v] = by_scene[key]
    return runs


class Conformance3D(Case):
    name = CASE
    title = "3D engine conformance: Hertz-Mindlin spheres in demflow, YADE and LIGGGHTS"
    source = SRC
    assumptions = (
        "Small scenes that start out of contact with no contact force acting (module docstring); the same Scene3D "
        "is written as a YADE and a LIGGGHTS deck (demflow.engines.yade3d, liggghts3d).",
        "demflow's shear-spring matching modes: 'incremental' against YADE, 'total' against LIGGGHTS; damping ratios "
        "are passed to both engines as demflow computes them (YADE betan/betas; LIGGGHTS a restitution solved for ζ).",
        "Trajectory difference: the largest of |Δx|/R, |Δv|/V, |Δω|R/V and |ΔF_plane|/F_max over every recorded "
        "step (V the largest speed, F_max the largest plane force of demflow's run).",
        "The engines' results are the stored reference runs, verified against their sha256 before use.",
    )
    params = dict(PARAMS)
    engines = ("yade", "liggghts")
    live = False

    @staticmethod
    def page_sections():
        from ..engines.capabilities import FEATURES_3D, as_html

        return [("Model-equivalence table (3D)", as_html(FEATURES_3D))]

    def reference_plan(self):
        from .base import ReferencePlan

        return ReferencePlan(CASE, self.merged(), variants_for, scene, engine=engine_for)

    def comparison_case(self):
        return Conformance3D()

    def engine_runs(self, p: dict) -> dict:
        """{(variant, engine): Trajectory3D} from the stored references (or the live engines)."""
        import tempfile

        from ..engines import reference
        from ..engines.base3d import Trajectory3D

        out = {}
        stored = reference.available(CASE)
        for v, engines in VARIANTS.items():
            for e in engines:
                if e not in self.engines:
                    continue
                if self.live:
                    with tempfile.TemporaryDirectory() as tmp:
                        out[(v, e)] = engine_for(e, v).run(scene(v, p), tmp)[0]
                elif e in stored.get(v, []):
                    res = reference.load(CASE, v, e, loader=Trajectory3D.load)
                    if res.meta.get("params") not in (None, p):
                        raise ParameterError(
                            f"case {CASE!r} compares demflow with engine runs stored with {res.meta.get('params')} "
                            f"({CASE}/{v}/{e}); with {p} there is none to compare with: run it with the default "
                            "parameters (demflow reference makes its runs with them)")
                    out[(v, e)] = res
        return out

    def run(self, p):
        engines = self.engine_runs(p)
        runs = demflow_runs(p, VARIANTS)
        return CaseRun({v: runs[v] for v in VARIANTS}, {"demflow": runs, "engines": engines})

    def checks(self, run, p):
        from ..engines.base3d import trajectory_difference as diff

        D, E = run.extras["demflow"], run.extras["engines"]
        out = []
        for v in CONFORMANCE:
            for e in VARIANTS[v]:
                if (v, e) in E:
                    out.append(Check.against(f"{v}: {e} vs demflow, trajectory difference", diff(D[v], E[(v, e)])["max"],
                                             0.0, conformance_tolerance(v), SRC))
        if ("oblique-plane-r2", "yade") in E:
            y = E[("oblique-plane-r2", "yade")]
            out.append(Check.against("oblique-plane, YADE's own box (R* = R/2) vs demflow with a plane 1/√2 as stiff",
                                     diff(D["oblique-plane-r2-emulated"], y)["max"], 0.0, "engines3d.round-off", SRC))
            out.append(Check.info("named difference r2-wall: YADE's own box vs demflow's plane, trajectory difference",
                                  diff(D["oblique-plane"], y)["max"], SRC, "YADE's box-sphere contact takes R* = R/2 "
                                  "(kno, kso 1/√2 of the flat-wall values); the deck compensates it"))
        for e, v2, v1 in (("yade", "periodic-pair-dt2", "periodic-pair"),
                          ("liggghts", "periodic-pair-total-dt2", "periodic-pair-total")):
            if (v1, e) in E and (v2, e) in E:
                ratio = diff(D[v2], E[(v2, e)])["max"] / diff(D[v1], E[(v1, e)])["max"]
                out.append(Check.against(f"named difference history-rotation ({e}): difference at Δt/2 over at Δt",
                                         ratio, 0.5, "engines3d.first-order", SRC))
        if ("periodic-pair-ratcheting", "yade") in E:
            out.append(Check.info("named difference: YADE's default avoidGranularRatcheting (lever arm R, not R − δ/2), "
                                  "periodic pair", diff(D["periodic-pair"], E[("periodic-pair-ratcheting", "yade")])["max"],
                                  SRC, "Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=True) is YADE's default; the "
                                  "deck sets it False"))
        for base in ("oblique-plane", "periodic-pair", "moving-plate"):
            out.append(Check.info(f"named difference shear-spring-3d: demflow total vs incremental, {base}",
                                  diff(D[base], D[base + "-total"])["max"], SRC,
                                  "LIGGGHTS: k_t(now) × total displacement; YADE: increments with the tangent k_t"))
            if (base, "yade") in E and (base + "-total", "liggghts") in E:
                out.append(Check.info(f"LIGGGHTS vs YADE, {base} (their own modes)",
                                      diff(E[(base, "yade")], E[(base + "-total", "liggghts")])["max"], SRC,
                                      "equals demflow's mode difference above (each engine matches its mode)"))
        if ("oblique-plane-lift-total", "liggghts") in E:
            d, li = D["oblique-plane-lift-total"], E[("oblique-plane-lift-total", "liggghts")]
            out.append(Check.against(f"oblique-plane-lift: LIGGGHTS vs demflow up to the plane's normal velocity switch "
                                     f"(step {LIFT_STEP})", diff(d, li, until=LIFT_STEP)["max"], 0.0,
                                     "engines3d.round-off", SRC))
            out.append(Check.info("named difference plane-velocity-timing: LIGGGHTS vs demflow after a normal velocity "
                                  "switch (0 → 0.3 m/s during contact)", diff(d, li)["max"], SRC,
                                  "LIGGGHTS's mesh contact sees the velocity that moved the mesh into place (the "
                                  "previous step's at a switch); demflow and YADE that of the step ahead"))
        out.append(Check.info("named difference shear-damping-ratio: e_t = 1 vs e_t = e_n, oblique-plane",
                              diff(D["oblique-plane"], D["oblique-plane-no-shear-damping"])["max"], SRC,
                              "LIGGGHTS ties ζ_t to ζ_n (or none); YADE's betas is free"))
        cap = diff(D["oblique-plane"], D["oblique-plane-elastic-cap"])["max"]
        out.append(Check.info("named difference friction-cap-3d: Coulomb on the elastic vs the total normal force, "
                              "oblique-plane", cap, SRC, "both engines cap with the total normal force"))
        if ("oblique-plane", "yade") in E:
            d = diff(D["oblique-plane-elastic-cap"], E[("oblique-plane", "yade")])["max"]
            out.append(Check.condition("negative control: YADE vs demflow with the elastic cap exceeds round-off",
                                       d > 1e3 * 1e-11, d, SRC, "the conformance checks can tell the two caps apart",
                                       kind="cross-code"))
        return out

    def tables(self, run, p):
        import pandas as pd

        from ..engines.base3d import trajectory_difference as diff

        D, E = run.extras["demflow"], run.extras["engines"]
        rows = []
        for (v, e), res in sorted(E.items()):
            ref = D["oblique-plane-r2-emulated"] if v == "oblique-plane-r2" else D[v]
            d = diff(ref, res)
            rows.append({"variant": v, "engine": e, "steps": d["steps"], "|Δx|/R": d["position"],
                         "|Δv|/V": d["velocity"], "|Δω|R/V": d["angular"], "|ΔF|/F": d["plane"]})
        return [("Trajectory differences from demflow (matching mode; oblique-plane-r2 against the emulated R/2 "
                 "plane)", pd.DataFrame(rows))]
