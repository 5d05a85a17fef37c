"""The figures of the miyata-uniaxial-3d pages: the engines' stress-settlement curves over demflow's seed
band and their force PDFs with fits (issue 14 item 5), the plate force maps, the force statistics, the bed's
micro-state and 3D pictures of the bed.
"""
from __future__ import annotations

import math

import numpy as np

from .miyata_uniaxial3d_statistics import SEED_MUETH, pooled_f, pooled_f_snaps
from .miyata_uniaxial3d_bands import band_of, engine_of


ENGINE_COLOURS = {"yade": "tab:red", "liggghts": "tab:blue"}


def engine_figures(ex, outdir) -> list:
    """The figure page of issue 14 item 5: the engines' stress-settlement curves over demflow's seed band,
    and the per-particle force PDFs on the plate and the floor with the q-model fits, linear and log axes."""
    import matplotlib.pyplot as plt

    from ..analysis.forces import fit_q_model, q_model_pdf
    from ..plotting import save_figure

    band = ex["band"]
    paths = []
    fig, (ax, ah) = plt.subplots(1, 2, figsize=(13, 4.8))
    top = min(float(u.curve.plate_stress.max()) for u in band.values())
    s_grid = np.linspace(0.0, top, 61)  # stress levels [Pa]: where each is first reached
    settle_rows, height_rows = [], []
    for u in band.values():
        c = u.curve
        first = np.maximum.accumulate(c.plate_stress.to_numpy())  # the running maximum: first reach
        settle_rows.append(np.interp(s_grid, first, c.settlement.to_numpy()))
        height_rows.append(np.interp(s_grid, first, c.plate_z.to_numpy()))
        ax.plot(c.settlement * 1e3, c.plate_stress / 1e3, color="0.75", lw=0.6)
        ah.plot(c.plate_z, c.plate_stress / 1e3, color="0.75", lw=0.6)
    for a, rows, scale in ((ax, np.asarray(settle_rows), 1e3), (ah, np.asarray(height_rows), 1.0)):
        lohi = np.array([band_of(rows[:, k]) for k in range(len(s_grid))])
        a.fill_betweenx(s_grid / 1e3, lohi[:, 0] * scale, lohi[:, 1] * scale, color="0.85", alpha=0.7,
                        label=f"demflow 95 % band ({len(band)} seeds; grey: each seed)")
    counts = {engine_of(e): sum(engine_of(x) == engine_of(e) for x in ex["engines"]) for e in ex["engines"]}
    shown = set()
    for e, u in ex["engines"].items():
        eng = engine_of(e)
        style = "-" if e.endswith("seed1") or " " not in e else "--"
        colour = ENGINE_COLOURS.get(eng, "k")
        # one legend entry per engine (its runs in one colour; solid: seed 1)
        label = (e if counts[eng] == 1 else f"{eng} ({counts[eng]} runs; solid: seed 1)") if eng not in shown else None
        shown.add(eng)
        ax.plot(u.curve.settlement * 1e3, u.curve.plate_stress / 1e3, style, color=colour, lw=1.0, label=label)
        ah.plot(u.curve.plate_z, u.curve.plate_stress / 1e3, style, color=colour, lw=1.0, label=label)
    for a in (ax, ah):
        for s in (100, 400):
            a.axhline(s, color="0.5", lw=0.6, ls=":")
        a.set_ylabel("plate stress [kPa]")
        a.legend(fontsize=8)
    ax.set_xlabel("settlement since the plate first touched [mm]")
    ax.set_title("stress-settlement (the band at fixed stresses: too wide to judge)")
    ah.set_xlabel("plate height [m]")
    ah.invert_xaxis()
    ah.set_title("stress vs plate height (the judged statistic)")
    paths.append(save_figure(fig, f"{outdir}/engines_stress_settlement.png"))

    fig, axs = plt.subplots(2, 2, figsize=(11, 8))
    # demflow's seeds pooled, and each engine's runs pooled
    runs = {f"demflow ({len(band)} seeds)": list(band.values())}
    for e, u in ex["engines"].items():
        runs.setdefault(engine_of(e), []).append(u)
    runs = {(k if k.startswith("demflow") or len(v) == 1 else f"{k} ({len(v)} runs)"): v for k, v in runs.items()}
    for row, wall in enumerate(("plate", "floor")):
        for col, scale in enumerate(("linear", "log")):
            a = axs[row, col]
            for name, us in runs.items():
                f = np.concatenate([pooled_f(v, wall) for v in us])
                if f.size < 3:  # the q-model fit needs three forces
                    continue
                edges = np.linspace(0, max(4.0, f.max()), 17) if scale == "linear" else np.logspace(-2, 1, 16)
                h, e_ = np.histogram(f, bins=edges, density=False)
                dens = h / (f.size * np.diff(e_))
                mid = 0.5 * (e_[1:] + e_[:-1]) if scale == "linear" else np.sqrt(e_[1:] * e_[:-1])
                N = fit_q_model(f).N
                colour = "k" if name.startswith("demflow") else ENGINE_COLOURS.get(engine_of(name), "k")
                keep = dens > 0 if scale == "log" else np.ones(dens.size, bool)  # empty bins off the log axes
                a.plot(mid[keep], dens[keep], "o-", color=colour, ms=3, lw=0.8, label=f"{name} (q-model N = {N:.2g})")
                x = np.linspace(0.01, 4, 200) if scale == "linear" else np.logspace(-2, 1, 200)
                a.plot(x, q_model_pdf(x, N), "--", color=colour, lw=0.8)
            x = np.linspace(0.01, 4, 200) if scale == "linear" else np.logspace(-2, 1, 200)
            a.plot(x, q_model_pdf(x, 3.0), ":", color="tab:green", label="q-model N = 3 (the seed's plate)")
            if scale == "log":
                a.set_xscale("log")
                a.set_yscale("log")
                a.set_ylim(1e-3, 10)
            a.set_xlabel(f"f = F/<F> on the {wall}, per particle")
            a.set_ylabel("P(f)")
            a.legend(fontsize=7)
    fig.suptitle("per-particle force PDFs at 400-600 kPa, each code's runs pooled (dashed: its q-model fit)")
    paths.append(save_figure(fig, f"{outdir}/engines_force_pdfs.png"))
    paths.append(engine_force_maps(ex, outdir))
    return paths


def engine_force_maps(ex, outdir) -> str:
    """Miyata Fig. 34 for every engine side by side: the plate and floor force maps of the first snapshot
    (400 kPa) of demflow's first seed and of each engine's run of that seed; each particle at the point where it
    touches the wall (:func:`wall_contact_points`), disc area ∝ its force on one scale per wall."""
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    first = next(iter(ex["band"]))
    # demflow's first seed and each engine's run of the same seed (one map per engine: the others are more draws)
    runs = {f"demflow seed{first}": ex["band"][first],
            **{e: u for e, u in ex["engines"].items() if " " not in e or e.endswith(f" seed{first}")}}
    L = float(np.sqrt(ex["area"]))
    fig, axs = plt.subplots(2, len(runs), figsize=(3.6 * len(runs), 7.4), squeeze=False)
    for row, wall in enumerate(("plate", "floor")):
        top = max((float(u.snapshot_points(wall)[0].max()) for u in runs.values() if len(u.snapshot_points(wall)[0])),
                  default=1.0)
        for col, (name, u) in enumerate(runs.items()):
            a = axs[row, col]
            f, xy = u.snapshot_points(wall)
            stress = u.snapshots.stress[u.snapshots.snapshot == 0]
            colour = ENGINE_COLOURS.get(engine_of(name), "0.3")
            if len(f) and np.all(np.isfinite(xy)):
                a.scatter(xy[:, 0], xy[:, 1], s=500 * f / top, c=colour, alpha=0.6, edgecolors="k", linewidths=0.4)
            else:
                a.text(0.5, 0.5, "no contact points stored", ha="center", va="center", transform=a.transAxes)
            a.set_xlim(0, L)
            a.set_ylim(0, L)
            a.set_aspect("equal")
            a.set_title(f"{name}: {wall} at {float(stress.iloc[0]) / 1e3 if len(stress) else math.nan:.0f} kPa "
                        f"({len(f)} particles)", fontsize=8)
            a.set_xlabel("x [m]", fontsize=8)
            a.set_ylabel("y [m]", fontsize=8)
    fig.suptitle("force maps at the first snapshot (Miyata Fig. 34; disc area ∝ force, one scale per wall)")
    return save_figure(fig, f"{outdir}/engines_force_maps.png")


def force_statistics_figure(ex, outdir) -> str:
    """Miyata Figs 35 and 37 for one run: the PDFs of f = F/<F> per particle on the plate and the floor
    (10 snapshots at 400-600 kPa) with the seed's q-model N = 3 and Mueth law and this run's fits, and the load
    support (share of the load carried by each class of f)."""
    import matplotlib.pyplot as plt

    from ..analysis.forces import fit_mueth, fit_q_model, load_support, mueth_pdf, q_model_pdf
    from ..plotting import save_figure

    fig, axs = plt.subplots(1, 3, figsize=(15, 4.2))
    x = np.linspace(0.01, 5.0, 300)
    for a, wall in zip(axs[:2], ("plate", "floor")):
        f = pooled_f_snaps(ex["snapshots"], wall)
        if f.size < 5:
            continue
        a.hist(f, bins=np.linspace(0, max(5.0, f.max()), 26), density=True, color="0.8", label=f"{wall}, per particle ({f.size})")
        a.plot(x, q_model_pdf(x, 3.0), "r:", label="q-model N = 3 (the seed's plate)")
        a.plot(x, mueth_pdf(x, SEED_MUETH["b"], SEED_MUETH["beta"]), "b:", label="Mueth b = 0.75, β = 1.5 (the seed's floor)")
        N = fit_q_model(f).N
        mu = fit_mueth(f, impose_mean=True)
        a.plot(x, q_model_pdf(x, N), "r-", lw=1, label=f"q-model fit N = {N:.2g}")
        a.plot(x, mueth_pdf(x, mu.b, mu.beta), "b-", lw=1, label=f"Mueth fit b = {mu.b:.2f}, β = {mu.beta:.2f}")
        a.set_xlabel("f = F/<F>")
        a.set_ylabel("P(f)")
        a.set_title(f"{wall} (Fig. 35)")
        a.legend(fontsize=7)
    a = axs[2]
    for wall, style in (("plate", "r-o"), ("floor", "b--s")):
        f = pooled_f_snaps(ex["snapshots"], wall)
        if f.size < 5:
            continue
        ls = load_support(f, bins=np.linspace(0, 5, 21))
        a.plot(ls.centers, ls.density, style, ms=3, label=f"{wall}: small {ls.classes[(0.0, 0.5)]:.0%}, medium "
               f"{ls.classes[(0.5, 2.0)]:.0%}, large {ls.classes[(2.0, np.inf)]:.0%}")
    for v in (0.5, 2.0):
        a.axvline(v, color="0.6", lw=0.7, ls=":")
    a.set_xlabel("f = F/<F>")
    a.set_ylabel("share of the load per unit f")
    a.set_title("load support (Fig. 37)")
    a.legend(fontsize=7)
    return save_figure(fig, f"{outdir}/force_statistics.png")


def micro_figure(ex, outdir) -> str:
    """The bed's coordination, fabric and average stress (ch3 eq 3.17) against the plate stress during loading,
    with the statics of a bed at rest (:func:`demflow.analysis.micro3d.statics_stress_zz`) for σ_zz."""
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    c = ex["curve"]
    on = c[c.settlement > 0]
    sp = on.plate_stress / 1e3
    fig, axs = plt.subplots(1, 3, figsize=(15, 4))
    axs[0].plot(sp, on.coordination, "k-", label="z (body pairs, walls left out)")
    axs[0].plot(sp, on.coordination_walls, "k--", label="z with the plate and floor")
    axs[0].set_ylabel("contacts per particle")
    for k, style in (("xx", "r-"), ("yy", "g-"), ("zz", "b-")):
        axs[1].plot(sp, on[f"fabric_{k}"], style, label=f"φ_{k}")
    axs[1].axhline(1 / 3, color="0.6", lw=0.7, ls=":")
    axs[1].set_ylabel("fabric of the contact normals")
    for k, style in (("xx", "r-"), ("yy", "g-"), ("zz", "b-")):
        axs[2].plot(sp, on[f"stress_{k}"] / 1e3, style, label=f"σ_{k}")
    axs[2].plot(sp, on.stress_zz_statics / 1e3, "k:", label="σ_zz of statics: σ_plate + (W/A) Z̄/H")
    axs[2].set_ylabel("average stress of the bed [kPa] (compression +)")
    for a in axs:
        a.set_xlabel("plate stress [kPa]")
        a.legend(fontsize=7)
    fig.suptitle("bed micro-state during loading")
    return save_figure(fig, f"{outdir}/bed_micro_state.png")


def bed_figures(ex, outdir) -> list:
    """The bed at the end of loading as a 3D picture (matplotlib: member spheres as points sized by radius,
    coloured by height) and as VTK for ParaView (``bed_end.vtu``: member centres with radius and body;
    Glyph filter, sphere, scale by radius × 2), and the plate and floor force maps of the first snapshot
    (400 kPa, Miyata Fig. 34: each particle where it touches the wall, :func:`wall_contact_points` — its centre
    for runs kept before those points were — disc area ∝ its force)."""
    import matplotlib.pyplot as plt

    from ..plotting import save_figure
    from ..vtk import write_points

    bed = ex["bed"]
    paths = [str(write_points(f"{outdir}/bed_end.vtu", bed["pos"], {"radius": bed["r"], "body": bed["body"].astype(float)}))]
    fig = plt.figure(figsize=(16, 5))
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    pos, r = bed["pos"], bed["r"]
    ax.scatter(pos[:, 0], pos[:, 1], pos[:, 2], s=(r / r.max()) ** 2 * 60, c=pos[:, 2], cmap="viridis", depthshade=True)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"bed at the end of loading (plate at {bed['plate_z']:.3f} m)", fontsize=9)
    snaps = [s for s in ex["snapshots"] if s.get("plate_xy") is not None and len(s["plate"])]
    L = bed["box"]
    for k, wall in enumerate(("plate", "floor")):
        a2 = fig.add_subplot(1, 3, 2 + k)
        s = snaps[0] if snaps else None  # Fig. 34: the first snapshot, at 400 kPa
        if s is None or s.get(f"{wall}_xy") is None or not len(s[wall]):
            a2.set_axis_off()
            continue
        xy = np.mod(s[f"{wall}_cxy"] if s.get(f"{wall}_cxy") is not None else s[f"{wall}_xy"], L)
        f = s[wall]
        a2.scatter(xy[:, 0], xy[:, 1], s=600 * f / f.max() * min(1.0, 40.0 / f.size), c="tab:red"
                   if wall == "plate" else "tab:blue", alpha=0.6, edgecolors="k", linewidths=0.4)
        if f.size <= 40:
            for (x, y), v in zip(xy, f):
                a2.annotate(f"{v / 1e3:.0f} kN", (x, y), fontsize=7, ha="center", va="center")
        a2.set_xlim(0, L)
        a2.set_ylim(0, L)
        a2.set_aspect("equal")
        a2.set_title(f"{wall} force map at {s['stress'] / 1e3:.0f} kPa (area ∝ force; {f.size} particles)", fontsize=9)
        a2.set_xlabel("x [m]")
        a2.set_ylabel("y [m]")
    paths.append(save_figure(fig, f"{outdir}/bed_and_plate_map.png"))
    return paths
