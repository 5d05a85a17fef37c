"""The model-equivalence table: how each engine expresses each part of a demflow scene.

Every row says what demflow does, what YADE and LIGGGHTS do, whether the engine expresses it
exactly (in demflow's matching mode), and the measured consequence where it does not.
The measurements are from the nine-disc comparison (cs-nine-disc-engines, 2026-11-21).
"""
from __future__ import annotations

ROWS = [
    dict(item="2D discs",
         demflow="discs, m = ρπR², I = ½mR²",
         yade="spheres, blockedDOFs 'zXY', mass and inertia set per body to the disc values",
         liggghts="dimension 2; `set density` gives ρπR², the integrator ½mR²",
         exact="yes", measured="Fn at C agrees to 5e-11 (undamped, both engines)"),
    dict(item="normal spring",
         demflow="incremental N += kN ṅΔt (thesis eq 2.13, default) or N = kN δ (`normal='overlap'`)",
         yade="N = kN δ", liggghts="N = kN δ",
         exact="in matching mode (normal='overlap')",
         measured="incremental vs overlap on the nine-disc test: 6e-7 (Fn at C)"),
    dict(item="shear spring",
         demflow="scalar S on τ, incremental (eq 2.14)", yade="shear force vector rotated with the contact",
         liggghts="accumulated shear displacement projected on the tangent plane",
         exact="equivalent in 2D", measured="no difference above 1e-10 in compression"),
    dict(item="stiffness and dashpots per material pair",
         demflow="a table per pair (disc-disc differs from disc-wall)",
         yade="per material, combined in series k1k2/(k1+k2): demflow writes 2× the disc-disc value and solves the "
              "wall material's value from the disc-wall pair",
         liggghts="peratomtypepair tables (discs type 1.., walls after)",
         exact="yes (YADE needs 2 k_dd > k_dw)", measured="1e-12 (damped nine-disc, YADE)"),
    dict(item="dashpots", demflow="absolute cN, cS on half-step velocities (eqs 2.31-2.32)",
         yade="ViscEl cn, cs", liggghts="absolute_damping on (else multiplied by m_eff)",
         exact="yes", measured="damped nine-disc, YADE: 1e-12"),
    dict(item="friction per pair", demflow="tan φ per pair", yade="tan(min(φ1, φ2)) of the two materials",
         liggghts="coefficientFriction peratomtypepair", exact="yes when disc-wall ≤ disc-disc (YADE)",
         measured="—"),
    dict(item="sliding rule", demflow="C&S (default): |S| ≤ μFn + c, Fn with dashpot; shear dashpot off while sliding; "
                                      "thesis variant |S + D_S| ≤ |N tan φ + c|",
         yade="C&S rule", liggghts="C&S rule", exact="C&S rule only; cohesion not expressed (refused)", measured="—"),
    dict(item="tension", demflow="Fn ≥ 0", yade="clamped at 0", liggghts="limitForce on", exact="yes", measured="—"),
    dict(item="global damping", demflow="C, C* or α (thesis eqs 2.27-2.28, C&S eq 34-36), implicit average",
         yade="a PyRunner adds the force that turns Newton's explicit update into eq 2.27 exactly",
         liggghts="not expressed (refused): fix addforce would be the explicit form",
         exact="YADE yes; LIGGGHTS no", measured="damped nine-disc, YADE: Fn at C 4e-12"),
    dict(item="walls", demflow="finite segments (C&S Fig. 4); wall velocity taken at the wall's nearest point",
         yade="fixed boxes moved kinematically; the contact point is mid-overlap, where a rotating wall's velocity is "
              "taken", liggghts="two-triangle STL meshes over a thick periodic z, move/mesh",
         exact="translation yes; rotation no (YADE: velocity point)",
         measured="damped distortion (rotating walls), YADE: Fn at C 3e-4, wall shear 0.4 %; undamped distortion: "
                  "2.6 % (LIGGGHTS), 5.5 % (YADE), amplified by sliding"),
    dict(item="initial velocity", demflow="v(-Δt/2)", yade="v(-Δt/2)", liggghts="v(0)",
         exact="identical when no force acts at t = 0", measured="—"),
    dict(item="servo walls", demflow="thesis eqs 5.11-5.12", yade="not expressed (refused)",
         liggghts="not expressed (refused)", exact="no", measured="—"),
]


def as_html() -> str:
    import html

    cols = ["item", "demflow", "yade", "liggghts", "exact", "measured"]
    head = "".join(f"<th>{c}</th>" for c in cols)
    rows = "".join("<tr>" + "".join(f"<td>{html.escape(r[c])}</td>" for c in cols) + "</tr>" for r in ROWS)
    return f"<table><tr>{head}</tr>{rows}</table>"
