"""thesis-falling-disc: one disc falling midway between two parallel walls (thesis §5.1).

r = 0.5 cm, ρs = 2 g/cm², ρl = 1 g/cm², μ = 50 g/(cm·s), walls 2b = 5 cm apart and h = 40 cm
long, the disc at mid-height, released at rest under g = −980 cm/s² (cgs, unit thickness).

Reference.  Thesis eqs 5.1-5.6 with Takaisi's drag K give v∞ = −0.9535 cm/s; the thesis got
−0.9306 (2.4 %).  Takaisi's K is an O((r/b)²) approximation: πμ[8 − 4(r/b)²]/[2 ln(b/r) +
3.4486(r/b)² − 1.8312] = 16.144 μ at r/b = 0.2, whereas Faxén's series for the same problem
(Happel & Brenner §7-5: K = 4πμ/[ln(b/r) − 0.9157 + 1.7244(r/b)² − 1.7302(r/b)⁴ + 2.4056(r/b)⁶
− 4.5913(r/b)⁸]), whose first terms are Takaisi's denominator without the numerator's
−4(r/b)², gives 16.533 μ.  Our BEM drag converges to Faxén's (16.4699, 16.5166, 16.5285 μ for
32, 64, 128 elements on the disc; measured), i.e. v∞ = −0.9311 cm/s: the thesis's −0.9306 was
right and Takaisi's formula is 2.4 % off.  The acceptance "within 1 % of −0.9535" cannot be met
by a correct Stokes solution; the 1 % check is made against eq 5.6 with Faxén's drag, and the
difference from Takaisi's value is reported.

Assumptions: the two walls are closed by a bottom and a top wall at ±20 cm (the fluid is one
bounded domain; the drag changes by < 1e-4 relative when the box is made 60 cm long, measured
by the study in ``convergence``); the disc's eq 5.3 history is computed with K = the BEM
self-resistance of the same mesh, so the history check measures the time integration (the
half-step lag and the fluid stride), the terminal-velocity check the mesh.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..build import build
from ..plotting import save_figure
from ..scene import Discs, Fluid, LinearLaw, Material, Outputs, Scene
from .fixtures import box_walls
from .base import Case, CaseRun, Check

SRC = "thesis §5.1, eqs 5.1-5.6"
V_TAKAISI = -0.9535  # cm/s, thesis §5.1.1
V_THESIS = -0.9306  # cm/s, thesis §5.1.2


def takaisi_K(mu, r, b):
    """Thesis eq 5.1 [g/s per cm of thickness]."""
    e = (r / b) ** 2
    return math.pi * mu * (8 - 4 * e) / (2 * math.log(b / r) + 3.4486 * e - 1.8312)


def faxen_K(mu, r, b):
    """Faxén's series for a cylinder midway between two planes (Happel & Brenner) [g/s per cm]."""
    e = (r / b) ** 2
    return 4 * math.pi * mu / (math.log(b / r) - 0.9157 + 1.7244 * e - 1.7302 * e ** 2 + 2.4056 * e ** 3
                               - 4.5913 * e ** 4)


def terminal_velocity(K, p):
    """Eq 5.6: v∞ = π g r² (ρs − ρl)/K [cm/s]."""
    return math.pi * p["g"] * p["r"] ** 2 * (p["rho_s"] - p["rho_l"]) / K


def eq53_velocity(t, K, p):
    """Solution of eq 5.3 from rest: v(t) = (α/β)(1 − e^{−βt}), α = (1 − ρl/ρs) g, β = K/(Aρs)."""
    A = math.pi * p["r"] ** 2
    alpha = (1 - p["rho_l"] / p["rho_s"]) * p["g"]
    beta = K / (A * p["rho_s"])
    return alpha / beta * (1 - np.exp(-beta * np.asarray(t)))


class FallingDisc(Case):
    name = "thesis-falling-disc"
    title = "One disc falling between two parallel walls in a viscous fluid (thesis §5.1)"
    source = SRC
    assumptions = (
        "The channel is closed by bottom and top walls at ±h/2 = ±20 cm (the fluid is a bounded domain).",
        "Takaisi's eq 5.1 is an O((r/b)²) approximation 2.4 % below Faxén's series (which the BEM converges to); "
        "the terminal velocity is checked against eq 5.6 with Faxén's drag, Takaisi's −0.9535 is reported.",
        "The velocity history is checked against eq 5.3 with K = the BEM self-resistance on the same mesh.",
        "Minimum fluid gap 0.1 cm (0.2 r): it only sets the fluid time-step bound (the disc never nears a wall).",
    )
    params = dict(mu=50.0, r=0.5, rho_s=2.0, rho_l=1.0, b=2.5, h=40.0, g=-980.0, dt=1e-4, t_end=0.02,
                  elements=64, element_length=1.0, min_gap=0.1, strides="1,4,16", study="16,32,64,128", dt_study=1)

    def scene(self, p, stride=1, elements=None, dt=None, adaptive=False, mu=None, allow=False, name=None):
        b, h = p["b"], p["h"]
        walls = box_walls(-b, b, -h / 2, h / 2)
        dt = p["dt"] if dt is None else dt
        return Scene(
            name=name or f"falling-disc-k{stride}", discs=Discs([0.0], [0.0], [p["r"]], "disc"),
            materials={"disc": Material(p["rho_s"]), "wall": Material()},
            laws={("disc", "wall"): LinearLaw(kn=1e5)}, walls=walls, gravity=(0.0, p["g"]), dt=dt,
            n_steps=int(round(p["t_end"] / dt)), outputs=Outputs(every=0), allow_supercritical=allow,
            fluid=Fluid(viscosity=p["mu"] if mu is None else mu, density=p["rho_l"],
                        elements_per_disc=elements or p["elements"], element_length=p["element_length"],
                        min_gap=p["min_gap"], stride=stride, adaptive=adaptive),
            description="thesis §5.1 falling disc")

    def scenes(self, p):
        out = {f"k{k}": self.scene(p, stride=int(k)) for k in str(p["strides"]).split(",")}
        if p["dt_study"]:  # the Δt/2 twin of the stride-1 run (the order check); 0 leaves it out
            out["k1-half-dt"] = self.scene(p, stride=1, dt=0.5 * p["dt"], name="falling-disc-k1-half-dt")
        return out

    def run(self, p):
        out = {}
        for name, sc in self.scenes(p).items():
            t0 = time.perf_counter()
            sim = build(sc)
            sim.run()
            res = sim.results()
            res.meta["wall_s"] = time.perf_counter() - t0
            res.meta["K_bem"] = float(sim.fluid.K0[0])
            out[name] = res
        # mesh study: the BEM self-resistance of the initial configuration (= the drag the terminal
        # velocity balances) for a halving sequence of element sizes
        study = {}
        for n in (int(s) for s in str(p["study"]).split(",")):
            sim = build(self.scene(p, elements=n, name=f"falling-disc-mesh{n}"))
            study[n] = float(sim.fluid.K0[0])
        return CaseRun(out, {"mesh-study": study})

    @staticmethod
    def velocity(res):
        """(t, vy): the disc velocity each fluid solve saw, v_{i−1/2} at step i, i.e. at time (i − ½)Δt."""
        ff = res.fluid_forces
        return ff.time.to_numpy() - 0.5 * res.meta["dt"], ff.vy.to_numpy()

    def checks(self, run, p):
        results = run.results
        out = []
        K_fax = faxen_K(p["mu"], p["r"], p["b"])
        v_fax = terminal_velocity(K_fax, p)
        base = results["k1"]
        t, v = self.velocity(base)
        out.append(Check.against("terminal velocity vs eq 5.6 with Faxén's drag [cm/s]", v[-1], v_fax,
                                 "falling-disc.terminal", SRC + "; Faxén (Happel & Brenner)"))
        study = run.extras["mesh-study"]
        ns = sorted(study)
        Ks = [study[n] for n in ns]
        ext = Ks[-1] + (Ks[-1] - Ks[-2]) / 3.0
        K_used = study.get(p["elements"], base.meta["K_bem"])
        out.append(Check.against(f"mesh: Richardson error of the drag at {p['elements']} elements per disc",
                                 abs(K_used - ext) / ext, 0.0, "bem.mesh-converged", "convergence study (O(h²))"))
        v_exact = eq53_velocity(t, base.meta["K_bem"], p)
        err = float(np.max(np.abs(v - v_exact)) / abs(v_exact[-1]))
        out.append(Check.against("history: max |v − v_eq5.3| / |v∞| (stride 1)", err, 0.0,
                                 "falling-disc.history", "thesis eq 5.3"))
        hx = float(np.max(np.abs(base.fluid_forces.fx.to_numpy())) / np.max(np.abs(base.fluid_forces.fy.to_numpy())))
        out.append(Check.against("symmetry: horizontal / vertical fluid force", hx, 0.0, "bem.symmetry", SRC))
        if "k1-half-dt" in results:
            th, vh = self.velocity(results["k1-half-dt"])
            err_h = float(np.max(np.abs(vh - eq53_velocity(th, results["k1-half-dt"].meta["K_bem"], p)))
                          / abs(v_exact[-1]))
            out.append(Check.against("Δt study: history error at Δt over that at Δt/2 (first order: 2)", err / err_h,
                                     2.0, "falling-disc.order", "order of the lagged explicit drag (demflow.coupling)"))
        for name, res in results.items():
            if name in ("k1", "k1-half-dt"):
                continue
            tk, vk = self.velocity(res)
            ek = float(np.max(np.abs(vk - eq53_velocity(tk, res.meta["K_bem"], p))) / abs(v_exact[-1]))
            out.append(_info(f"stride {name}: max |v − v_eq5.3| / |v∞| (accuracy knob, not pass/fail)", ek, 0.0, SRC))
        out.append(_info("Takaisi's v∞ (eq 5.1, 5.6) [cm/s]: our value vs it", v[-1], V_TAKAISI, SRC))
        out.append(_info("thesis's computed v∞ [cm/s]: our value vs it", v[-1], V_THESIS, SRC))
        return out

    def observables(self, run, p):
        """For a speed-accuracy study: the stride-1 disc velocity at an eighth, a quarter, half and all of
        t_end (interpolated between the solves) and its drag K from the BEM [cgs]."""
        res = run.results["k1"]
        t, v = self.velocity(res)
        out = {f"v(t = {f:g} t_end) [cm/s]": float(np.interp(f * p["t_end"], t, v)) for f in (0.125, 0.25, 0.5, 1.0)}
        out["drag K (BEM self-resistance) [g/s]"] = float(res.meta["K_bem"])
        return out

    def figures(self, run, p, outdir):
        results = run.results
        import matplotlib.pyplot as plt

        fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
        K = results["k1"].meta["K_bem"]
        for name, res in results.items():
            t, v = self.velocity(res)
            a1.plot(t, v, ".-" if name != "k1" else "-", ms=2, lw=1, label=f"demflow, {name}")
            acc = np.gradient(v, t)
            a2.plot(t, acc, lw=1, label=f"demflow, {name}")
        tt = np.linspace(0, p["t_end"], 400)
        a1.plot(tt, eq53_velocity(tt, K, p), "k:", label="eq 5.3 (K from the BEM)")
        a1.plot(tt, eq53_velocity(tt, takaisi_K(p["mu"], p["r"], p["b"]), p), "r--", lw=0.8, label="eq 5.3, Takaisi K")
        beta = K / (math.pi * p["r"] ** 2 * p["rho_s"])
        a2.plot(tt, terminal_velocity(K, p) * beta * np.exp(-beta * tt), "k:", label="eq 5.3")
        a1.set_xlabel("time [s]")
        a1.set_ylabel("vertical velocity [cm/s]")
        a1.set_title("disc velocity (thesis Fig. 5.2)")
        a2.set_xlabel("time [s]")
        a2.set_ylabel("vertical acceleration [cm/s²]")
        a2.set_title("disc acceleration (thesis Fig. 5.3)")
        a1.legend(fontsize=7)
        a2.legend(fontsize=7)
        return [save_figure(fig, f"{outdir}/velocity.png")]


def _info(name, value, reference, source):
    return Check.info(name, value, source, "Shown for comparison; not pass/fail.", reference=reference)
