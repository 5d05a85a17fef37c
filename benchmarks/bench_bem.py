"""Stokes BEM benchmarks (issue 3): cost scaling, speed-accuracy trade, near-contact accuracy.

    PYTHONPATH=. python benchmarks/bench_bem.py [scaling] [accuracy] [contact] [--max-unknowns 10000]

Writes benchmarks/results/bem_{scaling,accuracy,contact}.{json,md,png}.

* scaling: cylinder translating inside a concentric cylinder (inner n, outer 2n elements,
  12 n unknowns), Table 4.1 quadrature; assembly (Numba, parallel over source nodes) and LU solve
  (LAPACK getrf/getrs via scipy) wall times vs unknowns; power-law exponents fitted on the
  largest sizes.
* accuracy: same problem, error of the drag against the exact value
  4πμU/(ln(b/a) - (b²-a²)/(b²+a²)) for elements per boundary × quadrature rule, with times.
* contact: two discs (R = 1) in a circular container (radius 8); disc A moves at U = 1 towards
  the fixed disc B across a gap g = 0.5 ... 0.01 R; x-force on B with Table 4.1 and with the FINE
  rule, against a reference from the FINE rule on a 4× finer mesh.
"""
from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from demflow.bem import FINE, TABLE, Domain, Problem, circle  # noqa: E402
from demflow.bem.exact import annulus_translation_drag  # noqa: E402

OUT = Path(__file__).resolve().parent / "results"
A, B, U, MU = 1.0, 2.0, 1.0, 1.0
QNAME = {TABLE: "Table 4.1", FINE: "fine"}


def annulus(n, quad):
    dom = Domain([circle((0, 0), B, 2 * n, "outer", hole=False), circle((0, 0), A, n, "inner")])
    s = Problem(dom, MU).rigid("inner", U=(U, 0.0)).solve(quad=quad)
    return s


def env():
    return dict(machine=platform.machine(), python=platform.python_version(), cores=os.cpu_count(),
                numba_threads=__import__("numba").get_num_threads())


def scaling(max_unknowns):
    annulus(8, TABLE)  # compile
    rows = []
    for n in (40, 80, 160, 320, 480, 640, 833):
        if 12 * n > max_unknowns:
            break
        s = annulus(n, TABLE)
        F_ex = annulus_translation_drag(A, B, U, MU)
        err = abs(s.force("inner")[0] - F_ex) / abs(F_ex)
        rows.append(dict(unknowns=s.n_unknowns, assembly_s=s.assembly_s, solve_s=s.solve_s, rel_error=err))
        print(rows[-1], flush=True)
    N = np.array([r["unknowns"] for r in rows], float)
    big = N >= N.max() / 4
    fit = {k: float(np.polyfit(np.log(N[big]), np.log([r[k] for r, b in zip(rows, big) if b]), 1)[0])
           for k in ("assembly_s", "solve_s")}
    res = dict(env=env(), rows=rows, exponent=fit)
    (OUT / "bem_scaling.json").write_text(json.dumps(res, indent=2))
    md = ["| unknowns | assembly [s] | solve (LU) [s] | solve share | drag error |", "|---:|---:|---:|---:|---:|"]
    for r in rows:
        md.append(f"| {r['unknowns']} | {r['assembly_s']:.3f} | {r['solve_s']:.3f} | "
                  f"{r['solve_s'] / (r['assembly_s'] + r['solve_s']):.0%} | {r['rel_error']:.2e} |")
    md.append(f"\nfitted exponents (largest sizes): assembly ∝ N^{fit['assembly_s']:.2f}, solve ∝ N^{fit['solve_s']:.2f}; "
              f"{env()}")
    (OUT / "bem_scaling.md").write_text("\n".join(md) + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.loglog(N, [r["assembly_s"] for r in rows], "o-", label=f"assembly (∝ N^{fit['assembly_s']:.2f})")
    ax.loglog(N, [r["solve_s"] for r in rows], "s-", label=f"LU solve (∝ N^{fit['solve_s']:.2f})")
    ax.set_xlabel("unknowns N")
    ax.set_ylabel("wall time [s]")
    ax.legend()
    ax.set_title("BEM cost vs unknowns (2 cores)")
    fig.tight_layout()
    fig.savefig(OUT / "bem_scaling.png", dpi=110)


def accuracy():
    annulus(8, FINE)
    annulus(8, 2)
    F_ex = annulus_translation_drag(A, B, U, MU)
    rows = []
    for quad in (2, 4, 8, 16, TABLE, FINE):
        for n in (16, 32, 64, 128, 256):
            s = annulus(n, quad)
            rows.append(dict(quad=QNAME.get(quad, f"{quad}-point"), elements=n, unknowns=s.n_unknowns,
                             rel_error=abs(s.force("inner")[0] - F_ex) / abs(F_ex),
                             assembly_s=s.assembly_s, solve_s=s.solve_s))
            print(rows[-1], flush=True)
    (OUT / "bem_accuracy.json").write_text(json.dumps(dict(env=env(), rows=rows), indent=2))
    md = ["| rule | elements (inner) | unknowns | drag error | order | assembly [s] | solve [s] |",
          "|---|---:|---:|---:|---:|---:|---:|"]
    prev = None
    for r in rows:
        o = "" if prev is None or prev["quad"] != r["quad"] else f"{np.log2(prev['rel_error'] / r['rel_error']):.2f}"
        md.append(f"| {r['quad']} | {r['elements']} | {r['unknowns']} | {r['rel_error']:.2e} | {o} | "
                  f"{r['assembly_s']:.3f} | {r['solve_s']:.3f} |")
        prev = r
    (OUT / "bem_accuracy.md").write_text("\n".join(md) + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for q in dict.fromkeys(r["quad"] for r in rows):
        rr = [r for r in rows if r["quad"] == q]
        ax1.loglog([r["elements"] for r in rr], [r["rel_error"] for r in rr], "o-", label=q)
        ax2.loglog([r["assembly_s"] + r["solve_s"] for r in rr], [r["rel_error"] for r in rr], "o-", label=q)
    ax1.set_xlabel("elements on the inner cylinder (outer: 2×)")
    ax1.set_ylabel("relative drag error")
    ax2.set_xlabel("assembly + solve [s]")
    ax1.legend(fontsize=8)
    ax1.set_title("error vs elements and Gauss rule")
    ax2.set_title("error vs cost")
    fig.tight_layout()
    fig.savefig(OUT / "bem_accuracy.png", dpi=110)


def two_discs(gap, n, quad):
    xa, xb = -(1 + gap / 2), 1 + gap / 2
    dom = Domain([circle((0, 0), 8.0, 256, "box", hole=False), circle((xa, 0), 1.0, n, "A"), circle((xb, 0), 1.0, n, "B")])
    return Problem(dom, MU).rigid("A", U=(U, 0.0)).solve(quad=quad).force("B")[0]


def contact(n=128):
    rows = []
    for gap in (0.5, 0.2, 0.1, 0.05, 0.02, 0.01):
        ref = two_discs(gap, 4 * n, FINE)
        r = dict(gap=gap, elements=n, element_over_gap=2 * np.pi / n / gap, F_ref=ref)
        for quad in (TABLE, FINE):
            t = time.perf_counter()
            F = two_discs(gap, n, quad)
            r[QNAME[quad]] = dict(F=F, rel_error=abs(F - ref) / abs(ref), time_s=time.perf_counter() - t)
        r["Table 4.1 on the 4× mesh"] = dict(F=(f4 := two_discs(gap, 4 * n, TABLE)), rel_error=abs(f4 - ref) / abs(ref))
        rows.append(r)
        print(r, flush=True)
    (OUT / "bem_contact.json").write_text(json.dumps(dict(env=env(), rows=rows), indent=2))
    md = ["Error of the force on the fixed disc against F_ref (fine rule, 4× mesh).  The last column compares "
          "Table 4.1 with the fine rule on that same 4× mesh: the quadrature error alone.",
          "",
          "| gap/R | L/gap | F_ref (fine, 4× mesh) | Table 4.1 error | fine error | Table 4.1 vs fine, 4× mesh |",
          "|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        md.append(f"| {r['gap']} | {r['element_over_gap']:.2f} | {r['F_ref']:.4g} | {r['Table 4.1']['rel_error']:.2e} | "
                  f"{r['fine']['rel_error']:.2e} | {r['Table 4.1 on the 4× mesh']['rel_error']:.2e} |")
    (OUT / "bem_contact.md").write_text("\n".join(md) + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4))
    g = [r["gap"] for r in rows]
    ax.loglog(g, [r["Table 4.1"]["rel_error"] for r in rows], "o-", label=f"Table 4.1, {n} elements/disc")
    ax.loglog(g, [r["fine"]["rel_error"] for r in rows], "s-", label=f"fine rule, {n} elements/disc")
    ax.loglog(g, [r["Table 4.1 on the 4× mesh"]["rel_error"] for r in rows], "^--", label=f"Table 4.1, {4 * n} elements/disc")
    ax.set_xlabel("gap / R")
    ax.set_ylabel("relative error of the force on the fixed disc")
    ax.legend(fontsize=8)
    ax.set_title("near contact: two discs")
    fig.tight_layout()
    fig.savefig(OUT / "bem_contact.png", dpi=110)


def contact_quadrature():
    """Quadrature error alone (Table 4.1 vs FINE on the same mesh) down to coarse meshes, where
    elements are up to 20× longer than the gap (ϱ < 0.1: Table 4.1's 32-point band)."""
    rows = []
    for n in (32, 64, 128):
        for gap in (0.1, 0.05, 0.02, 0.01):
            t0 = time.perf_counter()
            ft = two_discs(gap, n, TABLE)
            t1 = time.perf_counter()
            ff = two_discs(gap, n, FINE)
            t2 = time.perf_counter()
            rows.append(dict(elements=n, gap=gap, L_over_gap=2 * np.pi / n / gap, F_table=ft, F_fine=ff,
                             quad_error=abs(ft - ff) / abs(ff), time_table_s=t1 - t0, time_fine_s=t2 - t1))
            print(rows[-1], flush=True)
    (OUT / "bem_contact_quadrature.json").write_text(json.dumps(dict(env=env(), rows=rows), indent=2))
    md = ["| elements/disc | gap/R | L/gap | F (fine) | Table 4.1 − fine (relative) | time Table / fine [s] |",
          "|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        md.append(f"| {r['elements']} | {r['gap']} | {r['L_over_gap']:.1f} | {r['F_fine']:.4g} | {r['quad_error']:.1e} | "
                  f"{r['time_table_s']:.2f} / {r['time_fine_s']:.2f} |")
    (OUT / "bem_contact_quadrature.md").write_text("\n".join(md) + "\n")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    mx = 10000
    if "--max-unknowns" in sys.argv:
        mx = int(sys.argv[sys.argv.index("--max-unknowns") + 1])
    what = args or ["accuracy", "contact", "scaling"]
    if "accuracy" in what:
        accuracy()
    if "contact" in what:
        contact()
    if "contact_quadrature" in what:
        contact_quadrature()
    if "scaling" in what:
        scaling(mx)
