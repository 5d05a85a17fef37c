"""Engine capabilities: one table of feature → how each engine expresses it → measured consequence.

Each :class:`Feature` says what demflow does, how YADE and LIGGGHTS express it, and a verdict
per engine:

- ``exact``: the engine computes the same thing (``condition`` names any restriction on values,
  checked by the deck writer);
- ``equivalent with matching mode``: the engine computes demflow's *matching mode* (``needs``);
  a scene outside that mode is refused;
- ``differs``: the engine computes something else; ``consequence`` is the measured difference;
- ``cannot express``: the deck writer refuses a scene that uses the feature.

The same table renders the model-equivalence page (:func:`as_html`) and is consulted by the deck
writers (:func:`refuse_inexpressible`) so that what a page says and what a deck does cannot drift
apart.  The measurements are from the nine-disc comparison (cs-nine-disc-engines, 2026-11-21) and
``shared/ENGINES.md`` (YADE 2023.02a, LIGGGHTS-PUBLIC 3.8.0).
"""
from __future__ import annotations

import html
from dataclasses import dataclass
from typing import Callable

from .base import EngineUnsupported

EXACT = "exact"
MATCHING = "equivalent with matching mode"
DIFFERS = "differs"
CANNOT = "cannot express"
VERDICTS = (EXACT, MATCHING, DIFFERS, CANNOT)
ENGINE_NAMES = {"yade": "YADE", "liggghts": "LIGGGHTS"}


@dataclass(frozen=True)
class Expression:
    """How one engine expresses a feature: its construct, the verdict (one of :data:`VERDICTS`),
    and the condition on values (``exact``) or the measured consequence (``differs``)."""

    construct: str
    verdict: str
    note: str = ""
    uses: Callable | None = None  # this engine's own test of a scene (else the feature's ``uses``)
    remedy: str = ""  # this engine's own remedy (else the feature's)


@dataclass(frozen=True)
class Feature:
    """One row of the capabilities table.

    ``uses(scene)`` is True when a scene needs what a ``cannot express`` engine lacks, or leaves the
    matching mode of an ``equivalent with matching mode`` engine; ``remedy`` says what to do then.
    """

    key: str
    item: str
    demflow: str
    yade: Expression
    liggghts: Expression
    measured: str = "—"
    uses: Callable | None = None
    remedy: str = ""

    def expression(self, engine: str) -> Expression:
        return getattr(self, engine)


def _incremental_normal(scene) -> bool:
    return scene.contact_model.normal != "overlap"


def _thesis_sliding(scene) -> bool:
    return scene.contact_model.sliding != "cs"


def _cohesion(scene) -> bool:
    return any(law.cohesion != 0 for law in scene.laws.values())


def _global_damping(scene) -> bool:
    d = scene.damping
    return d.C > 0 or d.C_rot > 0 or d.alpha > 0


def _servo(scene) -> bool:
    return any(w.servo is not None for w in scene.walls)


def _fluid(scene) -> bool:
    return scene.fluid is not None


def _superquadrics(scene) -> bool:
    from ..scene import Superquadrics

    return isinstance(scene.discs, Superquadrics)


# Measured 2026-11-25 (tests/test_miyata_uniaxial2d_engines.py checks each against its tolerance)
MEASURED_2D = {
    "conformance-2d/yade": 1.9e-14,
    "conformance-2d/liggghts": 1.5e-14,  # max |Δx|/R over the snapshots, frictionless conformance scene, 3000 steps
    "lever-arm/conformance-yade": 1.8e-3,  # the same with friction (max |Δx|/R)
    "lever-arm/conformance-liggghts": 1.8e-3,
}
_M2 = MEASURED_2D

FEATURES: tuple[Feature, ...] = (
    Feature("discs-2d", "2D discs", "discs, m = ρπR², I = ½mR²",
            yade=Expression("spheres, blockedDOFs 'zXY', mass and inertia set per body to the disc values", EXACT),
            liggghts=Expression("dimension 2; `set density` gives ρπR², the integrator ½mR²", EXACT),
            measured="Fn at C agrees to 5e-11 (undamped, both engines)"),
    Feature("normal-spring", "normal spring",
            "incremental N += kN ṅΔt (thesis eq 2.13, default) or N = kN δ (`normal='overlap'`)",
            yade=Expression("N = kN δ", MATCHING), liggghts=Expression("N = kN δ", MATCHING),
            measured="incremental vs overlap on the nine-disc test: 6e-7 (Fn at C)", uses=_incremental_normal,
            remedy="run the scene with ContactModel(normal='overlap'), demflow's matching mode (the incremental "
                   "form differs by 6e-7 in Fn at C on the nine-disc test; compare it as a named difference)"),
    Feature("shear-spring", "shear spring", "scalar S on τ, incremental (eq 2.14)",
            yade=Expression("shear force vector rotated with the contact", EXACT, "in 2D"),
            liggghts=Expression("accumulated shear displacement projected on the tangent plane", EXACT, "in 2D"),
            measured="no difference above 1e-10 in compression"),
    Feature("pair-stiffness", "stiffness and dashpots per material pair",
            "a table per pair (disc-disc differs from disc-wall)",
            yade=Expression("per material, combined in series k1k2/(k1+k2): demflow writes 2× the disc-disc value "
                            "and solves the wall material's value from the disc-wall pair; where no wall value can "
                            "(k_dw ≥ 2 k_dd, e.g. Miyata Table 2), the deck creates each disc-wall contact from the "
                            "wall's geometry before the InteractionLoop and sets its ViscElPhys values to the pair's",
                            EXACT),
            liggghts=Expression("peratomtypepair tables (discs type 1.., walls after)", EXACT),
            measured="1e-12 (damped nine-disc, YADE)"),
    Feature("dashpots", "dashpots", "absolute cN, cS on half-step velocities (eqs 2.31-2.32)",
            yade=Expression("ViscEl cn, cs", EXACT),
            liggghts=Expression("absolute_damping on (else multiplied by m_eff)", EXACT),
            measured="damped nine-disc, YADE: 1e-12"),
    Feature("pair-friction", "friction per pair", "tan φ per pair",
            yade=Expression("tan(min(φ1, φ2)) of the two materials; a disc-wall value above the disc-disc one is set "
                            "on each disc-wall contact as it forms (as pair-stiffness)", EXACT),
            liggghts=Expression("coefficientFriction peratomtypepair", EXACT)),
    Feature("sliding-rule", "sliding rule",
            "C&S (default): |S| ≤ μFn + c, Fn with dashpot; shear dashpot off while sliding; thesis variant "
            "|S + D_S| ≤ |N tan φ + c| (`sliding='thesis'`)",
            yade=Expression("C&S rule", MATCHING), liggghts=Expression("C&S rule", MATCHING),
            uses=_thesis_sliding,
            remedy="run the scene with ContactModel(sliding='cs'), demflow's default and matching mode"),
    Feature("cohesion", "cohesion", "c in the sliding limit |S| ≤ μFn + c (LinearLaw.cohesion)",
            yade=Expression("ViscEl has no cohesion", CANNOT), liggghts=Expression("not in hooke/stiffness", CANNOT),
            uses=_cohesion, remedy="set LinearLaw(cohesion=0) for the engine run"),
    Feature("tension", "tension", "Fn ≥ 0", yade=Expression("clamped at 0", EXACT),
            liggghts=Expression("limitForce on", EXACT)),
    Feature("global-damping", "global damping",
            "C, C* or α (thesis eqs 2.27-2.28, C&S eq 34-36), implicit average",
            yade=Expression("a PyRunner adds the force that turns Newton's explicit update into eq 2.27 exactly",
                            EXACT),
            liggghts=Expression("fix addforce would be the explicit form, not eq 2.27", CANNOT),
            measured="damped nine-disc, YADE: Fn at C 4e-12", uses=_global_damping,
            remedy="run an undamped variant (GlobalDamping() with C = C_rot = alpha = 0), or use YADE"),
    Feature("walls", "walls", "finite segments (C&S Fig. 4); wall velocity taken at the wall's nearest point",
            yade=Expression("fixed boxes moved kinematically; the contact point is mid-overlap, where a rotating "
                            "wall's velocity is taken", DIFFERS,
                            "translation exact; rotation: damped distortion Fn at C 3e-4, wall shear 0.4 %; "
                            "undamped distortion 5.5 %, amplified by sliding"),
            liggghts=Expression("two-triangle STL meshes over a thick periodic z, move/mesh (one rotation origin "
                                "per wall)", DIFFERS,
                                "translation exact; rotation: undamped distortion 2.6 %, amplified by sliding"),
            measured="damped distortion (rotating walls), YADE: Fn at C 3e-4, wall shear 0.4 %; undamped "
                     "distortion: 2.6 % (LIGGGHTS), 5.5 % (YADE), amplified by sliding"),
    Feature("servo-walls", "servo walls", "thesis eqs 5.11-5.12",
            yade=Expression("no servo in the deck", CANNOT), liggghts=Expression("no servo in the deck", CANNOT),
            uses=_servo, remedy="replace the servo by prescribed Phase motion (e.g. the wall path of a demflow run)"),
    Feature("initial-velocity", "initial velocity", "v(-Δt/2)", yade=Expression("v(-Δt/2)", EXACT),
            liggghts=Expression("v(0): in scenes with gravity the deck gives v(−Δt/2) + a(0)Δt/2 (and ω likewise), "
                                "a(0) from demflow's forces at t = 0; without gravity v(−Δt/2) (the stored decks)",
                                EXACT, "with gravity: when no dashpot acts at t = 0 (LIGGGHTS's setup forces see v(0)); "
                                "without: when no force acts at t = 0"),
            measured="identical without gravity when no force acts at t = 0; miyata-uniaxial-2d conformance scene "
                     "(gravity, no contact at t = 0, frictionless): positions to "
                     f"{_M2['conformance-2d/liggghts']:.1g} R over 3000 steps; with contacts and dashpots at t = 0 the "
                     "same heap parted by 2.5e-4 R (settling back to 7e-10 R by step 3000), and by 0.76 % in the floor "
                     "force without the a(0)Δt/2 term"),
    Feature("gravity-2d", "gravity (2D)", "g on every disc", yade=Expression("NewtonIntegrator gravity", EXACT),
            liggghts=Expression("fix gravity (the deck had none before 2026-11-25: scenes with gravity ran without "
                                "it)", EXACT),
            measured="miyata-uniaxial-2d conformance scene (frictionless): positions to "
                     f"{_M2['conformance-2d/yade']:.1g} R (YADE), {_M2['conformance-2d/liggghts']:.1g} R (LIGGGHTS)"),
    Feature("periodic-2d", "periodic box (2D)", "periodic along x, minimum image; walls not repeated",
            yade=Expression("periodic cell (x: the period; y, z: 1000× the scene), walls as boxes longer than the "
                            "period (allowBiggerThanPeriod); disc-wall contacts created from the walls' geometry each "
                            "step (2023.02a's periodic collider misses some)", EXACT, "periodic along x only"),
            liggghts=Expression("boundary p f p, the wall meshes clipped to the period", EXACT,
                                "periodic along x only; horizontal walls moving along y only (else refused)"),
            measured="miyata-uniaxial-2d conformance scene (a disc across the boundary, frictionless): as gravity-2d"),
    Feature("periodic-y-2d", "periodic along y (2D)", "periodic along y, minimum image",
            yade=Expression("not written to the 2D deck", CANNOT), liggghts=Expression("not written to the 2D deck", CANNOT),
            uses=lambda scene: scene.box.periodic_y is not None,
            remedy="use a box periodic along x only (walls bound y)"),
    Feature("lever-arm-2d", "where the contact's tangential velocity and moment are taken (2D)",
            "at the disc radius R (C&S eqs 2.9-2.10, Miyata eqs 38-42: the surface point)",
            yade=Expression("at the contact point, mid-overlap: R − δ/2 (ViscEl law)", DIFFERS,
                            "the shear force and moment scale by (R − δ/2)/R"),
            liggghts=Expression("at the contact point R − δ/2", DIFFERS, "as YADE"),
            measured="spinning disc on the floor (δ/R = 0.1): YADE's first shear force / demflow's = (R − δ/2)/R to "
                     "1e-12 (asserted); with friction the conformance scene parts by "
                     f"{_M2['lever-arm/conformance-yade']:.2g} (YADE) and {_M2['lever-arm/conformance-liggghts']:.2g} "
                     "(LIGGGHTS) of R in 3000 steps; on miyata-uniaxial-2d-engines (δ/R up to ~0.1) the engines' "
                     "CS and CR statistics stay inside demflow's 8-seed band"),
    Feature("reported-forces", "reported contact forces", "total Fn, Fs on the finder (dashpots included)",
            yade=Expression("normalForce, shearForce on id2; the reader converts them to force on the finder",
                            DIFFERS, "shearForce excludes the shear dashpot D_S"),
            liggghts=Expression("pair/gran/local, wall/gran/local force on atom i, recomputed with end-of-step "
                                "velocities", DIFFERS, "dumped values of damped contacts can differ ~1 % from "
                                                       "those applied")),
    Feature("pore-fluid", "pore fluid (saturated scenes)", "BEM Stokes flow coupled every k steps (thesis §3.4)",
            yade=Expression("no coupled Stokes BEM in the deck", CANNOT),
            liggghts=Expression("no coupled Stokes BEM in the deck", CANNOT), uses=_fluid,
            remedy="run the dry scene (Scene.fluid = None) in the engine and the saturated one in demflow"),
    Feature("superquadrics-2d", "2D superquadrics", "|x/a|^n + |y/b|^n = 1 particles, Brent potential contact "
            "with circles of curvature (Miyata eqs 34-42; demflow.shapes.superquadric)",
            yade=Expression("no 2D superquadric shape", CANNOT),
            liggghts=Expression("superquadrics are 3D and compiled out of the Debian build", CANNOT),
            uses=_superquadrics,
            remedy="compare the circle cases (n = 2, a = b: discs) with the engines; superquadrics run in demflow only"),
)


def feature(key: str) -> Feature:
    """The row of ``key``; KeyError names the known keys."""
    for f in FEATURES:
        if f.key == key:
            return f
    raise KeyError(f"no feature {key!r} in the capabilities table; known: {', '.join(f.key for f in FEATURES)}")


def refuse_inexpressible(engine: str, scene, features: tuple[Feature, ...] | None = None) -> None:
    """Raise EngineUnsupported if ``scene`` uses a feature ``engine`` ('yade' or 'liggghts') cannot
    express, or leaves the matching mode it needs; the message names the feature, the engine, what
    the engine does instead and what to do.  Value-dependent limits (``exact`` with a condition)
    are checked by the deck writers themselves."""
    name = ENGINE_NAMES[engine]
    for f in FEATURES if features is None else features:
        e = f.expression(engine)
        uses = e.uses or f.uses
        if uses is None or e.verdict not in (CANNOT, MATCHING) or not uses(scene):
            continue
        what = "cannot express" if e.verdict == CANNOT else "expresses only demflow's matching mode of"
        raise EngineUnsupported(
            f"{name} {what} {f.item} (capabilities table, feature {f.key!r}): scene {scene.name!r} uses "
            f"{f.demflow}; {name} has {e.construct}. To run it in {name}: {e.remedy or f.remedy}")


def as_html(features: tuple[Feature, ...] | None = None) -> str:
    """The model-equivalence page's table: one row per feature (default :data:`FEATURES`, the 2D
    rows), each engine's construct with its verdict and condition or measured consequence."""
    cols = ["feature", "demflow", "YADE", "YADE verdict", "LIGGGHTS", "LIGGGHTS verdict", "measured"]
    head = "".join(f"<th>{c}</th>" for c in cols)

    def verdict(e):
        return e.verdict + (f": {e.note}" if e.note else "")

    rows = "".join(
        "<tr>" + "".join(f"<td>{html.escape(v)}</td>" for v in (
            f.item, f.demflow, f.yade.construct, verdict(f.yade), f.liggghts.construct, verdict(f.liggghts),
            f.measured)) + "</tr>" for f in (FEATURES if features is None else features))
    return f"<table><tr>{head}</tr>{rows}</table>"


# ------------------------------------------------------------------------------------------ 3D spheres
# The rows of the 3D harness (demflow.engines.yade3d, liggghts3d): Scene3D with the Hertz-Mindlin law.
# Measured on the conformance-3d case (reference_runs/conformance-3d, tests/test_conformance3d.py).
def _laws3d(scene):
    return list(scene.laws.values())


def _hertz(law) -> bool:
    from ..laws.hertz_mindlin import HertzMindlinLaw

    return isinstance(law, HertzMindlinLaw)


def _tangential(law) -> bool:
    return _hertz(law) and law.tangential != "none" and law.friction > 0


def _linear_3d(scene) -> bool:
    return any(not _hertz(law) for law in _laws3d(scene))


def _not_incremental(scene) -> bool:
    return any(_tangential(law) and law.shear_spring != "incremental" for law in _laws3d(scene))


def _not_total(scene) -> bool:
    return any(_tangential(law) and law.shear_spring != "total" for law in _laws3d(scene))


def _md(scene) -> bool:
    return any(_tangential(law) and law.tangential == "mindlin-deresiewicz" for law in _laws3d(scene))


def _elastic_cap(scene) -> bool:
    return any(_tangential(law) and law.friction_cap != "total" for law in _laws3d(scene))


def _global_damping_3d(scene) -> bool:
    d = scene.damping
    return d.C > 0 or d.C_rot > 0 or d.alpha > 0


def _local_damping(scene) -> bool:
    return scene.local_damping > 0


def _servo_3d(scene) -> bool:
    return any(p.servo is not None for p in scene.planes)


def _fixed(scene) -> bool:
    return scene.spheres.fixed is not None and any(bool(f) for f in scene.spheres.fixed)


# Sizes of the named differences, measured on conformance-3d (2026-11-24, YADE 2023.02a, LIGGGHTS 3.8.0):
# the trajectory difference max(|Δx|/R, |Δv|/V, |Δω|R/V, |ΔF_plane|/F_max) over every recorded step
# (demflow.engines.base3d.trajectory_difference).  tests/test_conformance3d.py recomputes each one and
# checks it against this table; tests/reference_contact.py reproduces each engine by flipping one switch.
MEASURED_3D = {
    # the largest engine-vs-demflow difference where the models are equivalent: the 24 000-step moving plate,
    # whose size follows the last bits of ζ (9.8e-12 with the solve_ivp ζ until 2026-11-25, 4.6e-11 with the
    # BLAS-free one, 1.3e-10 relative apart; demflow vs the Python reference model there: 3.4e-11)
    "round-off": 4.6e-11,
    "shear-spring-3d/oblique-plane": 0.254,  # demflow total vs incremental (= LIGGGHTS vs YADE)
    "shear-spring-3d/periodic-pair": 0.0544,
    "history-rotation/yade": 3.0e-10,  # periodic pair, engine vs demflow; half at Δt/2
    "history-rotation/liggghts": 5.1e-10,
    "plane-velocity-timing": 0.171,  # LIGGGHTS, oblique-plane-lift (normal velocity 0 -> 0.3 m/s in contact)
    "r2-wall": 0.182,  # YADE's own box vs demflow's plane, oblique-plane
    "friction-cap-3d": 0.423,  # demflow elastic vs total cap, oblique-plane
    "shear-damping-ratio": 0.314,  # demflow e_t = 1 vs e_t = e_n, oblique-plane
    "avoid-ratcheting": 1.9e-4,  # YADE's default avoidGranularRatcheting vs demflow, periodic pair
    "initial-velocity-3d": 0.030,  # demflow with v(0) taken as v(-Δt/2) under gravity, moving-plate
}
_M = MEASURED_3D

def _ellipsoids(scene) -> bool:
    return getattr(scene, "ellipsoids", None) is not None


FEATURES_3D: tuple[Feature, ...] = (
    Feature("ellipsoids-3d", "3D ellipsoids", "Ellipsoids: Lin & Ng geometric-potential contact, R_e from the "
            "principal curvatures (Miyata eqs 43-59; demflow.shapes.ellipsoid)",
            yade=Expression("no ellipsoid shape in the deck (YADE's are polyhedra or clumps)", CANNOT),
            liggghts=Expression("no ellipsoid pair style in LIGGGHTS-PUBLIC 3.8 (superquadrics compiled out)",
                                CANNOT),
            uses=_ellipsoids, remedy="run ellipsoid-like clumps (Clumps) in the engines and the ellipsoids in demflow"),
    Feature("law-3d", "Hertz-Mindlin law (3D)", "HertzMindlinLaw: F = 4/3 E*√R* δ^{3/2}, k_t = 8G*√(R*δ)",
            yade=Expression("FrictMat + Ip2_FrictMat_FrictMat_MindlinPhys(betan, betas, frictAngle) + "
                            "Law2_ScGeom_MindlinPhys_Mindlin; kno = 4/3 E*√R*, kso = 8G*√R* (2023.02a: series G*, "
                            "also for unlike materials)", EXACT),
            liggghts=Expression("pair_style gran model hertz tangential history limitForce on (Yeff, Geff per type "
                                "pair)", EXACT),
            measured=f"trajectories equal to round-off (≤ {_M['round-off']:.2g}) on every conformance-3d scene "
                     "where the models are equivalent"),
    Feature("linear-law-3d", "linear law (3D)", "LinearLaw between spheres",
            yade=Expression("not in the 3D deck", CANNOT), liggghts=Expression("not in the 3D deck", CANNOT),
            uses=_linear_3d,
            remedy="give every material pair a HertzMindlinLaw (the 3D decks express the Hertz-Mindlin law only)"),
    Feature("mindlin-deresiewicz", "Mindlin-Deresiewicz tangential law", "tangential='mindlin-deresiewicz' "
            "(ch3 eqs 3.24-3.25: loading/unloading/reloading stiffness)",
            yade=Expression("Law2_ScGeom_MindlinPhys_Mindlin is the no-slip stiffness only", CANNOT),
            liggghts=Expression("tangential history is the no-slip stiffness only", CANNOT), uses=_md,
            remedy="run the scene with tangential='mindlin' (both engines' law)"),
    Feature("shear-spring-3d", "Mindlin shear spring (3D)",
            "`shear_spring='incremental'`: T += −k_t v_t Δt (k_t = 8G*a now); `'total'`: u += v_t Δt, T = −k_t u",
            yade=Expression("shearElastic −= ks·v_s Δt (incremental)", MATCHING, uses=_not_incremental,
                            remedy="run the scene with HertzMindlinLaw(shear_spring='incremental'), YADE's matching "
                                   "mode"),
            liggghts=Expression("tangential history: shear += v_t Δt, F_t = −k_t·shear (total: k_t now × all of "
                                "the displacement)", MATCHING, uses=_not_total,
                                remedy="run the scene with HertzMindlinLaw(shear_spring='total'), LIGGGHTS's "
                                       "matching mode"),
            measured=f"total vs incremental: {_M['shear-spring-3d/oblique-plane']:.3g} (oblique-plane, stick then "
                     f"slip), {_M['shear-spring-3d/periodic-pair']:.3g} (periodic pair); LIGGGHTS vs YADE is the same "
                     "number; none where the overlap does not change while sticking (moving plate)"),
    Feature("friction-cap-3d", "Coulomb cap (3D)", "|T| ≤ μ·Fn with Fn total (`friction_cap='total'`) or its "
            "elastic part (`'elastic'`)",
            yade=Expression("maxFs = |normalForce| tan φ, normalForce with the dashpot", MATCHING),
            liggghts=Expression("Ft_friction = μ|Fn|, Fn with the dashpot", MATCHING),
            measured=f"elastic vs total: {_M['friction-cap-3d']:.3g} (oblique-plane, e = 0.5)", uses=_elastic_cap,
            remedy="run the scene with HertzMindlinLaw(friction_cap='total'), both engines' rule"),
    Feature("damping-3d", "normal and tangential dashpots (3D)",
            "c = 2ζ√(m* k) with the tangent stiffness, Fn ≥ 0; ζ from e by a convention ('exact', 'yade', "
            "'liggghts')",
            yade=Expression("betan = ζ_n, betas = ζ_t per material pair (c = 2β√(m̄ k))", EXACT,
                            "any convention: the deck passes demflow's ζ"),
            liggghts=Expression("coefficientRestitution e' per type pair with √(5/6)|ln e'|/√(ln²e' + π²) = ζ_n",
                                EXACT, "ζ_n < √(5/6); ζ_t = ζ_n, or 0 (tangential_damping off); other values are "
                                       "refused"),
            measured="round-off with e = 0.5 and 0.7 ('exact' convention) in both engines"),
    Feature("shear-damping-ratio", "tangential dashpot vs normal dashpot",
            "ζ_t from restitution_tangential (None: ζ_t = ζ_n), c_t = 2ζ_t√(m* k_t)",
            yade=Expression("betas free per pair (es or betas); c_s/c_n = (β_s/β_n)√(k_s/k_n)", EXACT),
            liggghts=Expression("one β: γ_t/γ_n = √(S_t/S_n) (ζ_t = ζ_n), or 0", EXACT,
                                "ζ_t ∈ {ζ_n, 0}; other values refused"),
            measured=f"e_t = 1 vs e_t = e_n: {_M['shear-damping-ratio']:.3g} (oblique-plane); both engines "
                     "reproduce each to round-off"),
    Feature("dashpot-mass-3d", "dashpot mass", "m* = m_i m_j/(m_i + m_j) of the spheres (plane: m_i)",
            yade=Expression("m̄ of the two bodies' state.mass (a clump member's own mass)", EXACT,
                            "for spheres the member is the body: they coincide"),
            liggghts=Expression("meff of the two atoms (multisphere: the body mass)", EXACT,
                                "for spheres they coincide"),
            measured="head-on (unlike masses, e = 0.5): round-off in both engines"),
    Feature("walls-3d", "planes (3D)", "infinite planes, contact R* = R, prescribed translation",
            yade=Expression("Box bodies with a compensating material (the box-sphere R* is R/2): YADE's E*, G* of "
                            "the sphere against it are √2 demflow's; placed at demflow's plane point with the step's "
                            "velocity before each InteractionLoop", EXACT,
                            "one sphere material per plane (else refused); a rigid plane gets a negative fictitious "
                            "modulus"),
            liggghts=Expression("one-triangle STL mesh per plane in one fix wall/gran (reff = R; a rigid plane "
                                "E = 1e300), fix move/mesh linear/variable", EXACT, "no planes in a periodic box"),
            measured="round-off (oblique-plane, rigid moving plate, plate velocity switches)"),
    Feature("r2-wall", "YADE's own box-sphere radius", "R* = R against a plane",
            yade=Expression("refR1 = refR2 = R: R* = R/2, kno and kso 1/√2 of the flat-wall values", DIFFERS,
                            "compensated in the deck (walls-3d)"),
            liggghts=Expression("reff = radius for walls", EXACT),
            measured=f"uncompensated YADE box vs demflow's plane: {_M['r2-wall']:.3g} (oblique-plane); equal to "
                     "round-off to demflow with a plane 1/√2 as stiff"),
    Feature("plane-velocity-timing", "plane velocity in the contact at a velocity switch",
            "the contact at step n sees the plane's velocity of step n (the one that moves it to step n + 1)",
            yade=Expression("box velocity set before the InteractionLoop of each step", EXACT),
            liggghts=Expression("the mesh contact sees the velocity that moved the mesh into place; the deck switches "
                                "the in-plane part of the velocity one step early (exact: a plane's own in-plane "
                                "displacement changes no contact)", DIFFERS,
                                "a normal velocity switch during contact is seen one step late"),
            measured=f"normal velocity 0 → 0.3 m/s during contact: {_M['plane-velocity-timing']:.3g} (LIGGGHTS, "
                     "oblique-plane-lift); in-plane switches: round-off (moving-plate-phases)"),
    Feature("history-rotation", "tangential history when the contact normal turns",
            "projected onto the new tangent plane and rescaled to its length, before the increment (default); "
            "HertzMindlinLaw(history_rotation='project'): after the increment, projected without rescaling",
            yade=Expression("ScGeom::rotate: T −= T × (n_old × n), then the twist about n", DIFFERS,
                            "O(θ²) per step (θ the normal's turn per step): first order in Δt"),
            liggghts=Expression("shear += v_t Δt, then projected onto the tangent plane (no rescale)", DIFFERS,
                                "O(θ²) per step with demflow's default: first order in Δt; demflow's "
                                "history_rotation='project' is this rule (round-off on the periodic pair)"),
            measured=f"periodic pair (1.4e-3 rad turn over 52 steps): {_M['history-rotation/yade']:.2g} (YADE), "
                     f"{_M['history-rotation/liggghts']:.2g} (LIGGGHTS), halved at Δt/2; each engine's own rule "
                     "reproduces it to round-off, and demflow with history_rotation='project' reproduces LIGGGHTS's "
                     "run to round-off"),
    Feature("avoid-ratcheting", "velocity at the contact point (sphere pairs)", "lever arms R − δ/2",
            yade=Expression("Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False) in the deck; YADE's default "
                            "True changes the relative velocity", EXACT, "with the deck's setting"),
            liggghts=Expression("cr = R − δ/2", EXACT),
            measured=f"YADE's default vs demflow: {_M['avoid-ratcheting']:.2g} (periodic pair; not a plain lever arm "
                     "R: that misses YADE's run by 3e-4)"),
    Feature("initial-velocity-3d", "initial velocity (3D)", "v(−Δt/2)",
            yade=Expression("v(−Δt/2)", EXACT),
            liggghts=Expression("v(0): the deck gives v(−Δt/2) + gΔt/2", EXACT,
                                "when no contact acts at t = 0 (else off by F_c(0)Δt/2m in the first half step)"),
            measured=f"taking v(0) as v(−Δt/2) under gravity: {_M['initial-velocity-3d']:.2g} (moving-plate)"),
    Feature("periodic-3d", "periodic box (3D)", "periodic along x and/or y, minimum image",
            yade=Expression("periodic cell along x, y and z (z period 1000× the scene)", EXACT,
                            "periodic along both x and y (else refused)"),
            liggghts=Expression("boundary p p f (or p f f, f p f)", EXACT),
            measured="periodic pair: round-off against each engine's own history rotation"),
    Feature("global-damping-3d", "mass-proportional damping (3D)", "C = αm, C* = αI (ch3 eq 3.19)",
            yade=Expression("not in the 3D deck", CANNOT), liggghts=Expression("not in the 3D deck", CANNOT),
            uses=_global_damping_3d, remedy="run the scene with GlobalDamping() (no mass-proportional damping)"),
    Feature("local-damping-3d", "local non-viscous damping", "Cundall's α_l on each force component (Miyata eq 33)",
            yade=Expression("NewtonIntegrator(damping) would be it; not in the 3D deck (not measured)", CANNOT),
            liggghts=Expression("no local damping in LIGGGHTS", CANNOT),
            uses=_local_damping, remedy="run the scene with local_damping=0"),
    Feature("servo-plates", "servo plates", "PlateServo (thesis eqs 5.11-5.12 in 3D)",
            yade=Expression("not in the 3D deck", CANNOT), liggghts=Expression("not in the 3D deck", CANNOT),
            uses=_servo_3d, remedy="replace the servo by prescribed PlanePhase motion"),
    Feature("fixed-spheres", "fixed spheres", "Spheres(fixed=...): not integrated, moving with their velocity",
            yade=Expression("not in the 3D deck", CANNOT), liggghts=Expression("not in the 3D deck", CANNOT),
            uses=_fixed, remedy="make every sphere free (Spheres(fixed=None))"),
)


# The uniaxial protocol decks (miyata-uniaxial-3d: demflow.engines.yade_uniaxial3d, liggghts_uniaxial3d): what
# each engine does differently from demflow on that case.  Rendered on the case's report page; the sphere decks
# above are unaffected (none of these rows refuses a scene).
FEATURES_UNIAXIAL_3D: tuple[Feature, ...] = (
    Feature("clumps-3d", "rigid clumps of spheres", "Clumps: members in the template's principal frame, 191 kg and "
            "the union's principal moments (voxel integration), no contacts inside a clump",
            yade=Expression("appendClumped(discretization=15) of demflow's member spheres at demflow's insertion "
                            "positions and orientations; mass and principal moments set to demflow's, axis by axis "
                            "(|cos| ≥ 0.99 checked); each member's state.mass = its clump's (YADE's dashpot takes "
                            "member masses, demflow's the body's)", EXACT),
            liggghts=Expression("fix particletemplate/multisphere with demflow's mass and inertia_tensor, fix "
                                "multisphere; the bed is LIGGGHTS's own (insert/pack: bodies come only from "
                                "insertion fixes)", DIFFERS, "another random bed (compared statistically)"),
            measured="mass and moments equal the template's to 1e-12 in both engines (tests/test_uniaxial3d_yade.py, "
                     "tests/test_uniaxial3d_liggghts.py). LIGGGHTS's bed isolated: demflow's own beds inserted by the "
                     "deck's insert/pack rule (insertion='random', "
                     "demflow.cases.miyata_uniaxial3d_protocol.random_insertion), 8 seeds without local damping, settle 71 mm at 100 kPa on average against 95 mm on demflow's "
                     "lattice, and their band [-69, 211] mm still leaves out LIGGGHTS seed 1's 213 mm "
                     "(benchmarks/uniaxial3d_insertion_study.py, results/uniaxial3d_insertion_study.txt, 2026-11-27)"),
    Feature("trim-3d", "removing the particles above the trim height", "the next stage is built from the kept "
            "bodies (demflow.cases.miyata_uniaxial3d_protocol.next_stage)",
            yade=Expression("deleteClumpBody, then a fresh InsertionSortCollider (2023.02a hangs after a deletion in "
                            "a periodic scene)", EXACT),
            liggghts=Expression("delete_atoms leaves orphan members in a periodic box: pass 1 counts the bodies at "
                                "or below the trim height, pass 2 inserts that many into a fresh run", DIFFERS,
                                "a new random bed of the kept size, not pass 1's bed minus its top")),
    Feature("local-damping-uniaxial", "local non-viscous damping (uniaxial protocol)",
            "Cundall's α_l = 0.3 on each component of a body's force and torque, gravity included (Miyata eq 33)",
            yade=Expression("NewtonIntegrator(damping=α_l): the same rule, f(1 − α_l sgn(f(v + fΔt/2m))), "
                            "dampGravity on", EXACT),
            liggghts=Expression("none: fix multisphere has no damping option (documentation and source); the bed "
                                "settles and is loaded with the dashpots only", DIFFERS,
                                "see the cross-code checks of miyata-uniaxial-3d")),
    Feature("plate-detection-yade", "plate contacts in a periodic bed of clumps", "every overlap with the plate is a "
            "contact from the step it begins",
            yade=Expression("InsertionSortCollider(allowBiggerThanPeriod=True) with a box wider than the period "
                            "missed member-plate contacts (measured: the plate sank 23 mm into a member whose centre "
                            "had x < 0, unseen, while utils.createInteraction found the overlap); the deck's watchdog "
                            "creates any missing plate or floor contact every 10 steps", EXACT,
                            "a contact starts at most 10 steps (5 µm of plate travel) late; the count is in the run's "
                            "output (contacts_made_by_watchdog)"),
            liggghts=Expression("mesh walls (fix wall/gran)", EXACT)),
    Feature("shear-spring-uniaxial", "Mindlin shear spring (uniaxial protocol)", "incremental (YADE's), "
            "demflow's default",
            yade=Expression("Law2_ScGeom_MindlinPhys_Mindlin: incremental", EXACT),
            liggghts=Expression("tangential history: total displacement × the current k_t", DIFFERS,
                                "the stored force grows with the overlap under compression (feature shear-spring-3d)"),
            measured="isolated with demflow's shear_spring='total' (the case's parameter), 8 seeds without local "
                     "damping: settlement at 100 kPa 101 mm on average (95 mm incremental), band [-8, 211] mm; with "
                     "LIGGGHTS's insertion as well (its three differences together) 89 mm, band [-26, 204] mm: LIGGGHTS "
                     "seed 1 (bed top 2.18 m, settlement 213 mm at 100 kPa) stays outside every such band, seed 2 "
                     "inside all (benchmarks/uniaxial3d_insertion_study.py, 2026-11-27)"),
)
