"""The three validation problems of the thesis's Stokes BEM (thesis §4.4.1-4.4.3).

All lengths in units of the cylinder radius R (§4.4.1-2) or of the channel half-width a (§4.4.3),
μ = 1, U = 1, so forces per unit length are T/μU directly.  Sign convention: the force is the
one the fluid exerts on the body (demflow.bem.Solution.force).

Geometries (Figs 4.9, 4.11, 4.15-16 are lost; inferred, see ``assumptions``):
* §4.4.1: walls at y = ±5R (from eq 4.109); channel length 20R (inlet/outlet at x = ±10R):
  the drag changes by < 1e-5 relative between lengths 20R, 30R, 40R and 60R (measured).
* §4.4.2: the channel half-width is only in the figure.  With walls at ±b, the computed drag
  T/μU is 119.1, 99.3, 84.7, 52.4 for b/R = 1.9, 2.0, 2.1, 2.5 (L = 40R, 128 elements on the
  cylinder): only b = 2R (channel width 4R, a/b = 1/2) lands in 98.8-99.4, and the steepness
  (≈ 17 % per 0.1R) makes the inference sharp.  Channel length 20R (insensitive: 10R, 20R and 40R
  differ by < 1e-4).
* §4.4.3: channel half-width a (eq 4.113), particle height a ("the height of the particle, which is
  the half-width of the channel"), particle length unknown: U_p/U = 1.3105, 1.3024, 1.2958 for
  lengths a/2, a, 2a (long-particle limit 9/7 = 1.2857 by lubrication theory): the square a × a
  matches Bézine & Bonneau's 1.3041 and the thesis's own 1.3017.  Channel length 10a.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from ..bem import TABLE, Domain, Problem, channel, circle, rectangle
from ..tolerances import TOLERANCES
from .base import Case, CaseRun, Check
from ..plotting import finish_figure, save_figure

# Temporary home of the BEM tolerances (final home: demflow/tolerances.py, same names).


def _tol(name):
    return TOLERANCES[name]


def _against(name, value, reference, tname, source):
    t = _tol(name=tname)
    return Check(name, float(value), float(reference), t.value, source, t.why, relative=not t.absolute, kind=t.kind)


class BEMRun:
    """Results of one BEM solve: scalars in ``meta`` plus node tables; ``save`` writes them."""

    def __init__(self, sol, meta):
        self.sol = sol
        self.meta = dict(meta)

    def save(self, out):
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        d = self.sol.domain
        names = np.array([b.name for b in d.boundaries])[d.node_boundary]
        import pandas as pd

        pd.DataFrame(dict(boundary=names, x=d.nodes[:, 0], y=d.nodes[:, 1], nx=d.node_normal[:, 0],
                          ny=d.node_normal[:, 1], ux=self.sol.u[:, 0], uy=self.sol.u[:, 1], tx=self.sol.t[:, 0],
                          ty=self.sol.t[:, 1], p=self.sol.boundary_pressure())).to_csv(out / "nodes.csv", index=False)
        (out / "meta.json").write_text(json.dumps(self.meta, indent=2, default=float))
        return out


def _richardson(values):
    """O(h²) Richardson extrapolation of the last two of a halving sequence, and its correction."""
    v1, v2 = values[-2], values[-1]
    ext = v2 + (v2 - v1) / 3.0
    return ext, abs(ext - v2) / abs(ext)


def _cylinder_levels(levels, problem, quad) -> CaseRun:
    """Solve ``problem(n)`` for every mesh level n (elements on the cylinder); each level's drag T,
    lift, moment, solve time and size as a BEMRun in ``extras["levels"]``."""
    out = {}
    for n in levels:
        s, dt = _solve_timed(problem(n), quad)
        F = s.force("cylinder")
        out[f"n{n}"] = BEMRun(s, dict(n_cyl=n, T=F[0], Fy=F[1], M=s.moment("cylinder"), time_s=dt,
                                      n_unknowns=s.n_unknowns))
    return CaseRun(extras={"levels": out})


def _drag_levels(run):
    """(levels, drags T per level, the finest level's meta, Richardson extrapolation of T, its correction)."""
    results = run.extras["levels"]
    T = [r.meta["T"] for r in results.values()]
    ext, corr = _richardson(T)
    return results, T, list(results.values())[-1].meta, ext, corr


def _mesh_and_symmetry(corr, last, source, moment):
    """The Richardson remaining error of T/μU and the symmetry checks (|F_y|/T, and |M|/(T R) with ``moment``)."""
    out = [_against("remaining discretisation error (Richardson) of T/μU", corr, 0.0, "bem.mesh-converged", source),
           _against("transverse force |F_y|/T (symmetry)", abs(last["Fy"]) / abs(last["T"]), 0.0, "bem.symmetry",
                    source)]
    if moment:
        out.append(_against("moment |M|/(T R) (symmetry)", abs(last["M"]) / abs(last["T"]), 0.0, "bem.symmetry",
                            source))
    return out


def _solve_timed(pb, quad):
    t0 = time.perf_counter()
    s = pb.solve(quad=quad)
    return s, time.perf_counter() - t0


# ---------------------------------------------------------------------------------------------- §4.4.1
def cylinder_poiseuille_problem(n_cyl=128, length=20.0, half_width=5.0, R=1.0):
    """Fixed cylinder (radius R) midway in a channel |y| ≤ half_width, Poiseuille inflow and outflow
    u = 3/2 U (1 - (y/5R)²) (thesis eq 4.109), no slip on walls and cylinder.  Wall elements of the
    cylinder's element length (rounded)."""
    h = 2 * np.pi * R / n_cyl
    dom = Domain([channel(length, half_width, int(round(length / h)), 2 * int(round(half_width / h))),
                  circle((0.0, 0.0), R, n_cyl, "cylinder")])
    prof = lambda x, y: (1.5 * (1 - (y / half_width) ** 2), 0 * y)
    return Problem(dom, 1.0).velocity(("channel", "inlet"), prof).velocity(("channel", "outlet"), prof)


def cylinder_moving_planes_problem(n_cyl=128, length=20.0, half_width=2.0, R=1.0):
    """Fixed cylinder between planes moving at U = 1; u = U on the inlet and outlet (eq 4.111)."""
    h = 2 * np.pi * R / n_cyl
    dom = Domain([channel(length, half_width, int(round(length / h)), 2 * int(round(half_width / h))),
                  circle((0.0, 0.0), R, n_cyl, "cylinder")])
    return Problem(dom, 1.0).velocity("channel", (1.0, 0.0))


def free_rectangle_problems(n_side=40, length=10.0, particle_length=1.0, a=1.0):
    """Channel |y| ≤ a, square particle (height a, length ``particle_length``·a) at the centre.
    Returns (problem 1: particle at U_p = 1 in quiescent fluid; problem 2: particle fixed, Poiseuille
    inflow/outflow of mean velocity U = 1, eq 4.113)."""
    hp = a / n_side
    hw = 2 * hp

    def dom():
        return Domain([channel(length * a, a, int(round(length * a / hw)), int(round(2 * a / hw))),
                       rectangle(-0.5 * particle_length * a, -0.5 * a, 0.5 * particle_length * a, 0.5 * a,
                                 [int(round(particle_length * a / hp)), n_side] * 2, name="particle", hole=True)])

    d = dom()
    prof = lambda x, y: (1.5 * (1 - (y / a) ** 2), 0 * y)
    p1 = Problem(d, 1.0).rigid("particle", U=(1.0, 0.0))
    p2 = Problem(d, 1.0).velocity(("channel", "inlet"), prof).velocity(("channel", "outlet"), prof)
    return p1, p2


class _BEMCase(Case):
    def _levels(self, p):
        return [p["n"] // 2, p["n"]] if not p.get("refine", True) else [p["n"] // 4, p["n"] // 2, p["n"]]


class CylinderPoiseuille(_BEMCase):
    name = "thesis-bem-cylinder-poiseuille"
    title = "Fixed cylinder midway in a channel, Poiseuille flow: T/μU (thesis §4.4.1)"
    source = "thesis §4.4.1, eqs 4.109-4.110"
    assumptions = (
        "Walls at y = ±5R (eq 4.109); the channel length (lost Fig. 4.9) is taken as 20R: the drag changes "
        "by < 1e-5 relative for lengths 20R-60R (measured), so the length is immaterial once ≥ 20R.",
        "Cylinder discretised into n = 32, 64, 128 straight elements (default; walls with equal element "
        "length); Table 4.1 quadrature as in the thesis; the limit is estimated by O(h²) Richardson extrapolation.",
    )
    params = dict(n=128, length=20.0, quad=TABLE, refine=True)

    def run(self, p):
        return _cylinder_levels(self._levels(p), lambda n: cylinder_poiseuille_problem(n, p["length"]), p["quad"])

    def checks(self, run, p):
        results, T, last, ext, corr = _drag_levels(run)
        return [
            Check.condition("extrapolated T/μU inside the literature range 24.15-24.55", 24.15 <= ext <= 24.55, ext,
                            self.source, "Acceptance of issue 3: the refined value lies in the range quoted by the "
                            "thesis (Bézine & Bonneau 24.15, Takaisi 24.23, Harrison 24.55).", kind="source"),
            Check.condition("finest-mesh T/μU inside 24.15-24.55", 24.15 <= T[-1] <= 24.55, T[-1], self.source,
                            "The computed value itself, not only its extrapolation, is in the literature range.", kind="source"),
            Check.condition("monotone O(h²) convergence (successive changes shrink ≥ 3×)",
                            len(T) < 3 or abs(T[1] - T[0]) >= 3 * abs(T[2] - T[1]), T[-1], self.source,
                            "Straight elements on a circle and linear interpolation converge at O(h²): each halving "
                            "of the element size should cut the change by about 4.", kind="self-consistency"),
            *_mesh_and_symmetry(corr, last, self.source, moment=True),
            _thesis_info("thesis value T/μU = 24.20 (informative)", T[-1], 24.20, self.source),
        ]

    def figures(self, run, p, outdir):
        results = run.extras["levels"]
        s = list(results.values())[-1].sol
        return [_velocity_figure(s, (-6, 6), (-5, 5), "cylinder in Poiseuille flow: velocity (thesis Fig. 4.10)",
                                 f"{outdir}/velocity.png"),
                _traction_figure(s, (-6, 6), (-5.5, 5.5), "tractions on the fluid boundary",
                                 f"{outdir}/traction.png")]


class CylinderMovingPlanes(_BEMCase):
    name = "thesis-bem-cylinder-moving-planes"
    title = "Fixed cylinder between two planes moving at U: T/μU (thesis §4.4.2)"
    source = "thesis §4.4.2, eqs 4.111-4.112"
    assumptions = (
        "Channel width 4R (walls at ±2R) inferred from the literature values 98.8 and 99.4: the drag is "
        "119.1, 99.3, 84.7 for half-widths 1.9R, 2.0R, 2.1R (measured), so only 2R fits.",
        "Channel length 20R (lengths 10R-40R change the drag by < 1e-4); uniform u = U on inlet, outlet and walls.",
    )
    params = dict(n=128, length=20.0, half_width=2.0, quad=TABLE, refine=True)

    def run(self, p):
        return _cylinder_levels(self._levels(p), lambda n: cylinder_moving_planes_problem(n, p["length"], p["half_width"]),
                                p["quad"])

    def checks(self, run, p):
        results, T, last, ext, corr = _drag_levels(run)
        return [
            _against("T/μU vs Bézine & Bonneau (98.8)", T[-1], 98.8, "bem.moving-planes", self.source),
            _against("T/μU vs Bouard (99.4)", T[-1], 99.4, "bem.moving-planes", self.source),
            *_mesh_and_symmetry(corr, last, self.source, moment=False),
            _thesis_info("thesis value T/μU = 97.29 (informative)", T[-1], 97.29, self.source),
        ]

    def figures(self, run, p, outdir):
        results = run.extras["levels"]
        import matplotlib.pyplot as plt

        s = list(results.values())[-1].sol
        figs = [_velocity_figure(s, (-5, 5), (-2, 2), "cylinder between moving planes: velocity (Fig. 4.12)",
                                 f"{outdir}/velocity.png"),
                _traction_figure(s, (-5, 5), (-2.5, 2.5), "traction field on the fluid (Fig. 4.13)",
                                 f"{outdir}/traction.png")]
        x = np.concatenate([np.linspace(-p["length"] / 2 + 0.05, -1.01, 80), np.linspace(1.01, p["length"] / 2 - 0.05, 80)])
        u = s.interior_velocity(np.column_stack([x, 0 * x]))
        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.plot(x, u[:, 0], "k.-", ms=2)
        ax.set_xlabel("x / R")
        ax.set_ylabel("u / U on y = 0")
        ax.set_title("velocity on the symmetry axis (thesis Fig. 4.14)")
        path = f"{outdir}/axis_velocity.png"
        save_figure(fig, path)
        return figs + [path]


class FreeRectangle(_BEMCase):
    name = "thesis-bem-free-rectangle"
    title = "Square particle floating freely in channel Poiseuille flow: U_p/U (thesis §4.4.3)"
    source = "thesis §4.4.3, eqs 4.113-4.114"
    assumptions = (
        "Channel half-width a (eq 4.113); particle height a (text); particle length a (a square): inferred from "
        "U_p/U = 1.3105, 1.3024, 1.2958 for lengths a/2, a, 2a (measured) against 1.3041 (Bézine & Bonneau) and the "
        "thesis's 1.3017.",
        "Channel length 10a (inlet/outlet at ±5a, Poiseuille profile imposed there).",
        "Superposition of two solves as in the thesis: particle at U_p = 1 in quiescent fluid (force F_1) and particle "
        "fixed in Poiseuille flow of mean U = 1 (force F_2); U_p/U = -F_2/F_1.",
    )
    params = dict(n=40, length=10.0, particle_length=1.0, quad=TABLE, refine=True)

    def run(self, p):
        out = {}
        for n in self._levels(p):
            p1, p2 = free_rectangle_problems(n, p["length"], p["particle_length"])
            s1, t1 = _solve_timed(p1, p["quad"])
            s2, t2 = _solve_timed(p2, p["quad"])
            F1, F2 = s1.force("particle")[0], s2.force("particle")[0]
            ratio = -F2 / F1
            free = s1.combine(s2, ratio, 1.0)
            out[f"n{n}"] = BEMRun(free, dict(n_side=n, F1=F1, F2=F2, Up_over_U=ratio,
                                             Fy=free.force("particle")[1], M=free.moment("particle"),
                                             time_s=t1 + t2, n_unknowns=s1.n_unknowns))
        return CaseRun(extras={"levels": out})

    def checks(self, run, p):
        results = run.extras["levels"]
        r = [v.meta["Up_over_U"] for v in results.values()]
        last = list(results.values())[-1]
        ext, corr = _richardson(r)
        Fx = last.sol.force("particle")[0]
        return [
            _against("U_p/U vs Bézine & Bonneau (1.3041)", r[-1], 1.3041, "bem.free-rectangle", self.source),
            _against("remaining discretisation error (Richardson) of U_p/U", corr, 0.0, "bem.mesh-converged",
                     self.source),
            _against("net x-force on the free particle / F_2", abs(Fx) / abs(last.meta["F2"]), 0.0, "bem.symmetry",
                     self.source),
            _against("moment on the free particle / (F_2 a)", abs(last.meta["M"]) / abs(last.meta["F2"]), 0.0,
                     "bem.symmetry", self.source),
            _thesis_info("Tong & Fung finite elements 1.31 (informative)", r[-1], 1.31, self.source),
            _thesis_info("thesis value 1.3017 (informative)", r[-1], 1.3017, self.source),
        ]

    def figures(self, run, p, outdir):
        results = run.extras["levels"]
        import matplotlib.pyplot as plt

        s = list(results.values())[-1].sol
        d = s.domain
        figs = [_velocity_figure(s, (-2.5, 2.5), (-1, 1), "free square particle: velocity", f"{outdir}/velocity.png")]
        top = d.node_mask(("channel", "top"))
        x = d.nodes[top, 0]
        o = np.argsort(x)
        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.plot(x[o], -s.t[top, 0][o], "k-")  # shear stress the fluid exerts on the top wall, +x
        ax.set_xlim(-3, 3)
        ax.set_xlabel("x / a")
        ax.set_ylabel("wall shear stress τ_w / (μU/a)")
        ax.set_title("shear stress along the top wall (thesis Fig. 4.17)")
        path = f"{outdir}/wall_shear.png"
        save_figure(fig, path)
        figs.append(path)
        pr = s.boundary_pressure()
        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.plot(x[o], pr[top][o], "k-", label="top wall")
        part = d.node_boundary == d.index("particle")
        for side, st in (("top", "b-"), ("bottom", "b--")):
            m = d.node_mask(("particle", side))
            oo = np.argsort(d.nodes[m, 0])
            ax.plot(d.nodes[m, 0][oo], pr[m][oo], st, label=f"particle {side}")
        for side, st in (("left", "r."), ("right", "g.")):
            m = d.node_mask(("particle", side))
            ax.plot(d.nodes[m, 0], pr[m], st, label=f"particle {side} face")
        ax.set_xlim(-3, 3)
        path = finish_figure(fig, ax, f"{outdir}/pressure.png", xlabel="x / a",
                             ylabel="p / (μU/a)  (mean over channel boundary = 0)",
                             title="pressure on the walls and the particle (thesis Fig. 4.18)", legend_fontsize=7)
        del part
        return figs + [path]


def _thesis_info(name, value, reference, source):
    return Check.info(name, value, source, "Shown for comparison; not pass/fail.", reference=reference)


def _velocity_figure(s, xlim, ylim, title, path, nx=61, ny=25):
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon as MplPolygon

    from ..bem.geometry import points_in_polygon

    d = s.domain
    X, Y = np.meshgrid(np.linspace(*xlim, nx), np.linspace(ylim[0] * 0.98, ylim[1] * 0.98, ny))
    pts = np.column_stack([X.ravel(), Y.ravel()])
    outer = [b for b in d.boundaries if not b.hole][0]
    inside = points_in_polygon(pts, outer.ends)
    for b in d.boundaries:
        if b.hole:
            inside &= ~points_in_polygon(pts, b.ends)
    u = np.full((len(pts), 2), np.nan)
    u[inside] = s.interior_velocity(pts[inside])
    speed = np.hypot(u[:, 0], u[:, 1]).reshape(X.shape)
    fig, ax = plt.subplots(figsize=(7, 7 * (ylim[1] - ylim[0]) / (xlim[1] - xlim[0]) + 1.0))
    cs = ax.contourf(X, Y, speed, 20, cmap="viridis")
    fig.colorbar(cs, ax=ax, label="|u| / U")
    ax.streamplot(X, Y, u[:, 0].reshape(X.shape), u[:, 1].reshape(X.shape), color="w", density=1.2, linewidth=0.6)
    for b in d.boundaries:
        if b.hole:
            ax.add_patch(MplPolygon(b.ends, closed=True, color="0.6"))
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    save_figure(fig, path)
    return path


def _traction_figure(s, xlim, ylim, title, path):
    import matplotlib.pyplot as plt

    d = s.domain
    sel = (d.nodes[:, 0] >= xlim[0]) & (d.nodes[:, 0] <= xlim[1])
    fig, ax = plt.subplots(figsize=(7, 7 * (ylim[1] - ylim[0]) / (xlim[1] - xlim[0]) + 1.0))
    for b in d.boundaries:
        v = np.vstack([b.ends, b.ends[:1]])
        ax.plot(v[:, 0], v[:, 1], "k-", lw=0.8)
    ax.quiver(d.nodes[sel, 0], d.nodes[sel, 1], s.t[sel, 0], s.t[sel, 1], color="r", width=0.002)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal")
    ax.set_title(title + " (t = σn, n out of the fluid)", fontsize=9)
    save_figure(fig, path)
    return path


CASES = (CylinderPoiseuille(), CylinderMovingPlanes(), FreeRectangle())
