"""thesis-simple-shear: 20-disc simple shear, loose/dense × dry/saturated (thesis §5.4-5.6).

The specimen, its compression and the shear box are in :mod:`demflow.cases.simple_shear_setup`
(every inference from the lost figures is stated there).  Dry shear: wall 3 is a servo lid at the
vertical force F_y (volume changes).  Saturated shear: wall 3 is fixed (constant volume) and the
unbalanced load F_y − F_C is handed to the liquid (μ = 0.01, water) as a traction on wall 3 (thesis
§5.3.2); the pore pressure along every wall is the BEM's.

Speed knobs (measured, see ``tradeoff-thesis-simple-shear``): the shear rate γ̇ (not given in the
thesis; 0.05 /s is converged for the dry runs: γ̇ = 0.02 changes the height curve by < 0.02 % of H),
the density scaling of the saturated shear (thesis §5.5.3.1: the run is quasi-static, a denser disc
allows a larger Δt and, since the drag relaxation time m/K grows with m, a longer fluid stride), the
elements per disc and the fluid stride.
"""
from __future__ import annotations

import time

import math

import numpy as np
import pandas as pd

from ..build import build
from ..plotting import contact_force_diagram, save_figure
from . import simple_shear_setup as setup
from .base import Case, CaseRun, Check

SRC = "thesis §5.4-5.6, Figs 5.15-5.49"
VARIANTS = ("loose-dry", "dense-dry", "loose-saturated", "dense-saturated")


def run_variant(spec, saturated, p):
    """Shear one compressed specimen; Results with the specimen and timing in ``meta``."""
    fluid_kw = dict(elements_per_disc=int(p["elements"]), element_length=float(p["element_length"]),
                    min_gap=float(p["min_gap"]), stride=int(p["stride"]), safety=float(p["safety"]), moments=False)
    scale = float(p["sat_density_scale"] if saturated else p["density_scale"])
    sc = setup.shear_scene(spec, saturated, rate=float(p["rate"]), gamma_max=float(p["gamma_max"]),
                           density_scale=scale, fluid_kw=fluid_kw)
    t0 = time.perf_counter()
    sim = build(sc).continue_from(spec.sim)
    t_build = time.perf_counter() - t0
    sim.run()
    wall = time.perf_counter() - t0
    res = sim.results()
    res.meta.update(kind=spec.kind, saturated=saturated, width=spec.width, height=spec.height,
                    void_ratio=spec.void_ratio, fy=spec.fy, rate=float(p["rate"]), dt=sim.dt,
                    density_scale=scale, wall_s=wall, build_s=t_build, dem_s=sim.dem_s,
                    bem_s=(wall - sim.dem_s) if saturated else 0.0,
                    solves=len(sim.fluid.strides) if saturated else 0)
    return res


def curves(res) -> pd.DataFrame:
    """Per recorded step: γ [-], S1, S3 (contact shear force on walls 1 and 3), S = (S3 − S1)/2,
    height change dh [% of H], contact force sums on the four walls ΣFx, ΣFy [force]."""
    m = res.meta
    wf = res.wall_forces
    piv = wf.pivot_table(index="step", columns="wall", values=["fx", "fy", "py"])
    out = pd.DataFrame(index=piv.index)
    out["gamma"] = piv.index.to_numpy() * m["dt"] * m["rate"]
    out["S1"] = piv["fx"]["bottom"]
    out["S3"] = piv["fx"]["top"]
    out["S"] = 0.5 * (out.S3 - out.S1)
    out["F1"] = piv["fy"]["bottom"]
    out["F3"] = piv["fy"]["top"]
    out["dh"] = (piv["py"]["top"] - piv["py"]["bottom"] - m["height"]) / m["height"] * 100.0
    out["sum_fx"] = piv["fx"].sum(axis=1)
    out["sum_fy"] = piv["fy"].sum(axis=1)
    return out.reset_index()


def pressures(res) -> pd.DataFrame:
    """Per fluid solve: γ, mean pore pressure on walls 1 and 3 (p1, p3) and its range along each
    [force/length²], and the fluid force sums on the four walls."""
    m = res.meta
    pp = res.pore_pressure
    g = pp.groupby(["step", "wall"]).p
    mean, lo, hi = g.mean().unstack(), g.min().unstack(), g.max().unstack()
    out = pd.DataFrame(index=mean.index)
    out["gamma"] = mean.index.to_numpy() * m["dt"] * m["rate"]
    for w, k in (("bottom", "1"), ("top", "3")):
        out["p" + k], out["p" + k + "_min"], out["p" + k + "_max"] = mean[w], lo[w], hi[w]
    fw = res.fluid_walls.groupby("step")[["fx", "fy"]].sum()
    out["fluid_fx"], out["fluid_fy"] = fw.fx, fw.fy
    return out.reset_index()


def equilibrium(res) -> tuple[float, float]:
    """(rms, max) over the shear of |Σ forces on the four walls| / F_y; contact forces, plus the
    fluid's for a saturated run (at the solves, where both are known)."""
    c = curves(res)
    if res.meta["saturated"]:
        pr = pressures(res).set_index("step")
        c = c.set_index("step").join(pr[["fluid_fx", "fluid_fy"]], how="inner").reset_index()
        fx, fy = c.sum_fx + c.fluid_fx, c.sum_fy + c.fluid_fy
    else:
        fx, fy = c.sum_fx, c.sum_fy
    mag = np.hypot(fx, fy) / res.meta["fy"]
    return float(np.sqrt(np.mean(mag ** 2))), float(mag.max())


def dry_behaviour(res) -> dict:
    c = curves(res)
    k = int(np.argmin(c.dh))
    # how much of the lids' Coulomb bound the shear force uses: S / (tan φ_dw × mean lid normal force)
    lid_n = 0.5 * (c.F1.abs() + c.F3.abs()).to_numpy()
    bound = math.tan(math.radians(setup.PHI_DW)) * lid_n
    use = np.where(bound > 0, c.S.to_numpy() / np.where(bound > 0, bound, 1.0), 0.0)
    return dict(dh_max=float(c.dh.max()), dh_min=float(c.dh.min()), gamma_min=float(c.gamma.iloc[k]),
                dh_end=float(c.dh.iloc[-1]), peak_S=float(c.S.max() / res.meta["fy"]),
                lid_bound_use=float(use.max()))


def wet_behaviour(res) -> dict:
    pr = pressures(res)
    sig = res.meta["fy"] / res.meta["width"]
    p = 0.5 * (pr.p1 + pr.p3).to_numpy() / sig
    k = int(np.argmax(p))
    return dict(p_start=float(p[0]), p_max=float(p[k]), gamma_max=float(pr.gamma.iloc[k]), p_end=float(p[-1]),
                p13=float(np.median(np.abs(pr.p1 - pr.p3)) / sig),
                peak_S=float(curves(res).S.max() / res.meta["fy"]))


class SimpleShear(Case):
    name = "thesis-simple-shear"
    title = "Simple shear of 20 discs: loose/dense × dry/saturated (thesis §5.4-5.6)"
    source = SRC
    assumptions = (
        "Units: the thesis's numbers in one consistent system (g, cm, s; its 'gF' is the program's force unit): "
        "cN = 34.323 is then exactly 5 % of the mean critical damping, as the text states (measured 0.04999).",
        "The random arrangement of Fig. 5.15 is lost: seeded random sequential addition (seed a parameter) in the "
        "1 × 0.8 cm box; the seed ensemble table shows how much the behaviour depends on it.",
        "Compression: walls 2, 3, 4 move in at the thesis's ratio (wall 3 twice as fast as 2 and 4) until the force on "
        "wall 3 reaches 8.1 kgF; relaxation with the walls held (loose) or a servo lid at 8.1 kgF without friction "
        "(dense, §5.6.1.1); F_y is the wall-3 force at the end of relaxation (§5.5.1). Width, height and e are "
        "reported against the thesis's 0.89 × 0.69 cm (e 26.11 %) and 0.682 cm (e 24.65 %).",
        "Shear: lateral walls rotate about their top ends at γ̇, the bottom wall translates at γ̇H (the hinged bottom "
        "of §5.3.3), wall 3 is a lid: servo at F_y (dry) or fixed (saturated). γ̇ = 0.05 /s (not given; converged "
        "for the dry runs, see the study).",
        "Saturated: minimum fluid gap 0.005 cm (0.1 × the smallest radius: the thesis's gap for this case is not "
        "given; it notes the fluid forces came out small, 'either the gap is too big or the viscosity too small'); "
        "fluid moments not applied; density scaled ×100 in the saturated shear (quasi-static, §5.5.3.1), error "
        "measured by tradeoff-thesis-simple-shear.",
    )
    params = dict(seed=1, rate=0.05, gamma_max=0.105, density_scale=1.0, sat_density_scale=100.0, elements=16,
                  element_length=0.05, min_gap=0.005, stride=1_000_000, safety=0.5, variants=",".join(VARIANTS),
                  ensemble="1,2,3,4,5,6,7,8")

    @staticmethod
    def _specimens(p):
        """The compressed specimens the variants of ``p`` need, each compressed once: {kind: Specimen}."""
        kinds = dict.fromkeys(v.split("-")[0] for v in str(p["variants"]).split(","))
        return {kind: setup.compress(kind, int(p["seed"])) for kind in kinds}

    def scenes(self, p):
        specs = self._specimens(p)
        out = {}
        for v in str(p["variants"]).split(","):
            kind, state = v.split("-")
            out[v] = setup.shear_scene(specs[kind], state == "saturated", rate=float(p["rate"]),
                                       gamma_max=float(p["gamma_max"]))
        return out

    def run(self, p):
        specs = self._specimens(p)
        out = {}
        for v in str(p["variants"]).split(","):
            kind, state = v.split("-")
            out[v] = run_variant(specs[kind], state == "saturated", p)
        done = {(int(p["seed"]), kind): (specs[kind], out[f"{kind}-dry"]) for kind in specs if f"{kind}-dry" in out}
        return CaseRun(out, {"ensemble": self.ensemble(p, done) if p["ensemble"] else None})

    @staticmethod
    def ensemble(p, done=None) -> pd.DataFrame:
        """Dry shear of both specimens for every seed of ``p['ensemble']`` (DEM only: seconds);
        ``done`` maps (seed, kind) to an already sheared (Specimen, Results) to reuse."""
        rows = []
        done = done or {}
        for seed in [int(s) for s in str(p["ensemble"]).split(",") if s]:
            for kind in ("loose", "dense"):
                if (seed, kind) in done:
                    spec, res = done[(seed, kind)]
                else:
                    spec = setup.compress(kind, seed)
                    res = run_variant(spec, False, p)
                b = dry_behaviour(res)
                rows.append(dict(seed=seed, specimen=kind, width=spec.width, height=spec.height,
                                 e=spec.void_ratio, contracts_throughout=b["dh_max"] <= 0.02,
                                 contracts_then_dilates=b["dh_min"] < -0.02 and b["dh_end"] > b["dh_min"] + 0.2,
                                 **b))
        return pd.DataFrame(rows)

    def checks(self, run, p):
        results = run.results
        out = []
        for v, res in results.items():
            kind, state = v.split("-")
            rms, mx = equilibrium(res)
            out.append(Check.against(f"{v}: static equilibrium, rms |Σ wall forces| / F_y over the shear (max {mx:.3g})",
                                     rms, 0.0, "simple-shear.equilibrium", SRC))
            if state == "dry":
                b = dry_behaviour(res)
                if kind == "loose":
                    out.append(Check.condition(
                        "loose-dry contracts throughout: largest height change [% of H] <= 0.02", b["dh_max"] <= 0.02 and
                        b["dh_min"] < 0, b["dh_max"], SRC, "Thesis Fig. 5.23: 'the array is always compressing'; 0.02 % "
                        "of H is the servo lid's noise (its height wanders by ±0.01 % at rest).", kind="source"))
                else:
                    out.append(Check.condition(
                        "dense-dry contracts then dilates: final − smallest height change [% of H] > 0.2, minimum "
                        f"{b['dh_min']:.3f} % at γ = {100 * b['gamma_min']:.2f} %",
                        b["dh_min"] < -0.02 and b["gamma_min"] < 0.9 * p["gamma_max"] and b["dh_end"] > b["dh_min"] + 0.2,
                        b["dh_end"] - b["dh_min"], SRC, "Thesis Fig. 5.40: 'the volume initially decreases before starting "
                        "to increase steadily'; 0.2 % of H is 10× the servo lid's noise.", kind="source"))
                thesis = 0.2 if kind == "loose" else 0.19
                cap = math.tan(math.radians(setup.PHI_DW))
                out.append(Check.miss(
                    f"{v}: peak S/F_y (thesis {thesis})", b["peak_S"], thesis, SRC,
                    f"The shear force S is carried by the lids' contacts, whose Coulomb bound is tan φ_dw = tan "
                    f"{setup.PHI_DW:g}° = {cap:.3f} of the lid's normal force: S/F_y cannot exceed about {cap:.3f} "
                    f"(F_y held by the servo), below the thesis's {thesis}. Measured here: S reaches "
                    f"{100 * b['lid_bound_use']:.0f} % of that bound; over seeds 1-8 (ensemble table) the peaks "
                    "stay at or below it. What lets the thesis's specimens go higher (rough or toothed lids, a "
                    "different S) is not in the text."))
                m = res.meta
                e_thesis = 0.2611 if kind == "loose" else 0.2465
                out.append(Check.miss(
                    f"{kind} specimen void ratio (thesis {100 * e_thesis:.2f} %)", m["void_ratio"], e_thesis, SRC,
                    f"The thesis's 20-disc arrangement (Fig. 5.15) is lost; this seed's random arrangement, "
                    f"compressed by the thesis's protocol to F_y, jams at {m['width']:.4f} × {m['height']:.4f} cm "
                    f"(thesis {0.89:.2f} × {0.69 if kind == 'loose' else 0.682:g} cm): the void ratio is the "
                    "arrangement's. The seed-ensemble table gives e for seeds 1-8."))
            else:
                b = wet_behaviour(res)
                if kind == "loose":
                    out.append(Check.condition(
                        "loose-saturated: pore pressure rises (largest mean p on walls 1, 3 − start, in units of F_y/W, "
                        "> 0.1)", b["p_max"] - b["p_start"] > 0.1 and b["p_end"] > b["p_start"], b["p_max"] - b["p_start"],
                        SRC, "Thesis Fig. 5.32: the pore pressure increases, sharply near γ ≈ 4 %, then eases.", kind="source"))
                else:
                    out.append(Check.condition(
                        "dense-saturated: pore pressure rises then drops (peak − start > 0.05 and peak − end > 0.1, "
                        f"F_y/W units; peak at γ = {100 * b['gamma_max']:.2f} %)",
                        b["p_max"] - b["p_start"] > 0.05 and b["p_max"] - b["p_end"] > 0.1
                        and b["gamma_max"] < 0.9 * p["gamma_max"], b["p_max"] - b["p_end"], SRC,
                        "Thesis Fig. 5.48: 'a steady decrease of pore pressure after an initial increase'.", kind="source"))
                out.append(Check.against(f"{v}: walls 1 and 3 carry the same pore pressure (median |p1 − p3| / (F_y/W))",
                                         b["p13"], 0.0, "simple-shear.incompressible", SRC))
        return out

    def observables(self, run, p):
        """For a speed-accuracy study: per saturated variant, the mean pore pressure on walls 1 and 3 [F_y/W]
        and the shear force S [F_y] at 12 equally spaced strains up to γ_max (interpolated); per dry variant,
        the height change [% of H] and S [F_y] there."""
        grid = np.linspace(0.0, float(p["gamma_max"]), 13)[1:]
        out = {}
        for v, res in run.results.items():
            m = res.meta
            c = curves(res)
            if m["saturated"]:
                pr = pressures(res)
                first = np.interp(grid, pr.gamma, 0.5 * (pr.p1 + pr.p3) / (m["fy"] / m["width"]))
                what = "p [F_y/W]"
            else:
                first, what = np.interp(grid, c.gamma, c.dh), "dh [% of H]"
            S = np.interp(grid, c.gamma, c.S / m["fy"])
            for g, a, b in zip(grid, first, S):
                out[f"{v}: {what} at γ = {100 * g:.2f} %"] = float(a)
                out[f"{v}: S [F_y] at γ = {100 * g:.2f} %"] = float(b)
        return out

    def tables(self, run, p):
        results = run.results
        rows = []
        thesis = {"loose": (0.89, 0.69, 0.2611), "dense": (0.89, 0.682, 0.2465)}
        for v, res in results.items():
            m = res.meta
            kind, state = v.split("-")
            b = dry_behaviour(res) if state == "dry" else wet_behaviour(res)
            rms, mx = equilibrium(res)
            rows.append(dict(variant=v, width=m["width"], height=m["height"], e=m["void_ratio"],
                             thesis_WxH_e=f"{thesis[kind][0]} × {thesis[kind][1]}, {thesis[kind][2]}", F_y=m["fy"],
                             peak_S_over_Fy=b["peak_S"], dh_min=b.get("dh_min"), dh_end=b.get("dh_end"),
                             p_max=b.get("p_max"), p_end=b.get("p_end"), equilibrium_rms=rms, equilibrium_max=mx,
                             density_scale=m["density_scale"], dt=m["dt"], solves=m["solves"], wall_s=m["wall_s"],
                             dem_s=m["dem_s"], bem_s=m["bem_s"]))
        out = [("Variants (dh in % of H; p in units of F_y/W; times in s on this machine)", pd.DataFrame(rows))]
        ens = run.extras.get("ensemble")
        if ens is not None and len(ens):
            out.append(("Seed ensemble, dry shear (how much the lost arrangement matters)", ens))
        return out

    def figures(self, run, p, outdir):
        results = run.results
        import matplotlib.pyplot as plt

        figs = []
        for v, res in results.items():
            m = res.meta
            steps = sorted(set(res.particles.step))
            shots = [s for s in steps if s > 0]
            fig, axs = plt.subplots(1, len(shots), figsize=(4.5 * len(shots), 4))
            for ax, s in zip(np.atleast_1d(axs), shots):
                contact_force_diagram(res, step=s, ax=ax)
                q = res.particles[res.particles.step == s]
                ax.set_xlim(float((q.x - q.radius).min()) - 0.08, float((q.x + q.radius).max()) + 0.08)
                ax.set_ylim(float((q.y - q.radius).min()) - 0.08, float((q.y + q.radius).max()) + 0.08)
                ax.set_title(f"{v}: γ = {100 * s * m['dt'] * m['rate']:.1f} %")
            figs.append(save_figure(fig, f"{outdir}/{v}-contact-forces.png"))
            c = curves(res)
            n = 4 if m["saturated"] else 3
            fig, axs = plt.subplots(1, n, figsize=(4.2 * n, 3.6))
            g = 100 * c.gamma
            axs[0].plot(g, -c.S1, lw=0.8, label="−S1 (wall 1)")
            axs[0].plot(g, c.S3, lw=0.8, label="S3 (wall 3)")
            axs[0].plot(g, c.S, lw=1.2, color="k", label="mean S")
            axs[0].set_ylabel("shear force [gF]")
            axs[0].legend(fontsize=7)
            pr = pressures(res) if m["saturated"] else None
            if m["saturated"]:
                gp = 100 * pr.gamma
                for k, col in (("1", "C0"), ("3", "C3")):
                    axs[1].plot(gp, pr["p" + k], color=col, lw=1, label=f"wall {k} (mean)")
                    axs[1].fill_between(gp, pr[f"p{k}_min"], pr[f"p{k}_max"], color=col, alpha=0.2, lw=0)
                axs[1].axhline(m["fy"] / m["width"], color="k", ls=":", lw=0.8, label="F_y/W")
                axs[1].set_ylabel("pore pressure change [gF/cm]")
                axs[1].legend(fontsize=7)
                j = 2
            else:
                axs[1].plot(g, c.dh, color="k", lw=1)
                axs[1].set_ylabel("height change [% of H]")
                j = 2
            axs[j].plot(g, c.sum_fx, lw=0.8, label="Σ Fx (contacts)")
            axs[j].plot(g, c.sum_fy, lw=0.8, label="Σ Fy (contacts)")
            axs[j].set_ylabel("force sum on the 4 walls [gF]")
            axs[j].legend(fontsize=7)
            if m["saturated"]:
                axs[3].plot(100 * pr.gamma, pr.fluid_fx, lw=0.8, label="Σ Fx (fluid)")
                axs[3].plot(100 * pr.gamma, pr.fluid_fy, lw=0.8, label="Σ Fy (fluid)")
                axs[3].set_ylabel("fluid force sum on the walls [gF]")
                axs[3].legend(fontsize=7)
            for a in axs:
                a.set_xlabel("γ [%]")
            fig.suptitle(v)
            figs.append(save_figure(fig, f"{outdir}/{v}-curves.png"))
            if m["saturated"]:
                figs.append(self._vectors(res, v, outdir))
        return figs

    @staticmethod
    def _vectors(res, v, outdir):
        """Disc velocity and fluid force vectors at the solves nearest γ = 4.9 % and 10.5 % (Figs 5.28, 5.30)."""
        import matplotlib.pyplot as plt
        from matplotlib.patches import Circle

        m = res.meta
        ff = res.fluid_forces
        solves = np.array(sorted(set(ff.step)))
        fig, axs = plt.subplots(2, 2, figsize=(9, 8))
        for row, gam in enumerate((0.049, 0.105)):
            s = solves[np.argmin(np.abs(solves * m["dt"] * m["rate"] - gam))]
            f = ff[ff.step == s].sort_values("id")
            parts = res.particles
            r = parts[parts.step == parts.step.min()].sort_values("id").radius.to_numpy()
            for col, (u, w, what) in enumerate(((f.vx, f.vy, "velocity"), (f.fx, f.fy, "fluid force"))):
                ax = axs[row, col]
                for x, y, rr in zip(f.x, f.y, r):
                    ax.add_patch(Circle((x, y), rr, fill=False, lw=0.5, color="0.5"))
                ax.quiver(f.x, f.y, u, w, angles="xy", color="C0" if col == 0 else "C3")
                ax.set_aspect("equal")
                ax.autoscale_view()
                ax.set_title(f"{v}: {what}, γ = {100 * s * m['dt'] * m['rate']:.1f} %")
        return save_figure(fig, f"{outdir}/{v}-velocity-fluid-force.png")
