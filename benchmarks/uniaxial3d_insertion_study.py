"""Do LIGGGHTS's own insertion or its shear spring explain its misses on `miyata-uniaxial-3d`?  (Issue 14 item 4: every engine
statistic outside demflow's seed band must be explained by a row of the capabilities table with a test that
isolates it.)

    python benchmarks/uniaxial3d_insertion_study.py [--seeds 1 2 3 4 5 6 7 8] [--workers 2]

LIGGGHTS is judged against demflow's band without local damping (capabilities row local-damping-uniaxial), yet
it differs in one more way the band does not share (row clumps-3d): its bed is its own, ``fix insert/pack`` at
random points of a region 5x taller than the bodies' bounding spheres (volume fraction 0.2), where demflow
inserts on a loose lattice.  On the page of 2026-11-27 LIGGGHTS seed 1's settlement at 100 and 600 kPa (213, 270
mm) lies above that band (at most 200 and 260 mm).  The last documented difference is the shear spring (row
shear-spring-uniaxial: LIGGGHTS stores the total tangential displacement).  This runs the case's whole protocol
without local damping for the given seeds four times: with demflow's lattice or ``insertion="random"`` (the same
region and placement rule as the LIGGGHTS deck, :func:`demflow.cases.miyata_uniaxial3d_protocol.random_insertion`), each
with the incremental or the ``shear_spring="total"`` Mindlin spring; it prints each statistic's 95 % prediction
band per arm (:func:`~demflow.cases.miyata_uniaxial3d_bands.band_of`, the page's rule) beside the stored LIGGGHTS runs,
and whether each LIGGGHTS value lies inside each band.  Dask, 2 workers.
Results: benchmarks/results/uniaxial3d_insertion_study.txt; see README, miyata-uniaxial-3d.
"""
from __future__ import annotations

import argparse
import math
import time
import warnings

import numpy as np

from demflow.cases import get_case
from demflow.cases.miyata_uniaxial3d_bands import band_of
from demflow.cases.miyata_uniaxial3d_protocol import protocol_run
from demflow.cases.miyata_uniaxial3d_statistics import run_statistics
from demflow.engines.uniaxial3d import UniaxialRun
from demflow.sweep import run_sweep

KEYS = ("particles after trimming", "bed top before loading [m]", "plate height at 100 kPa [m]",
        "plate height at 400 kPa [m]", "plate height at 600 kPa [m]", "settlement at 100 kPa [mm]",
        "settlement at 400 kPa [mm]", "settlement at 600 kPa [mm]", "particles on the plate (mean of snapshots)",
        "particles on the floor (mean of snapshots)")


ARMS = (("lattice", "incremental"), ("random", "incremental"), ("lattice", "total"), ("random", "total"))


def label(arm) -> str:
    return f"{arm[0]}/{arm[1]}"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(1, 9)))
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    base = get_case("miyata-uniaxial-3d").merged({"local_damping": 0.0, "progress": False})
    items = [dict(base, seed=s, insertion=ins, shear_spring=spring) for ins, spring in ARMS for s in a.seeds]
    t0 = time.perf_counter()
    runs = run_sweep(protocol_run, items, workers=a.workers, progress=False)
    wall = time.perf_counter() - t0
    stats = {label(arm): [] for arm in ARMS}
    for it, r in zip(items, runs):
        stats[label((it["insertion"], it["shear_spring"]))].append(run_statistics(UniaxialRun.from_case(r)))
    from demflow.engines import reference

    lig = {}
    for variant in ("seed1", "seed2"):
        u = reference.load("miyata-uniaxial-3d", variant, "liggghts", loader=UniaxialRun.load)
        lig[variant] = run_statistics(u)
    names = [label(arm) for arm in ARMS]
    print(f"# {len(a.seeds)} seeds ({a.seeds[0]}-{a.seeds[-1]}) x {len(ARMS)} arms (insertion/shear spring), "
          f"local_damping 0, the case's other parameters; {wall:.0f} s wall on {a.workers} workers "
          f"({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())})")
    print("statistic | " + " | ".join(f"{n}: mean [band]" for n in names) + " | liggghts seed1 (inside each band) | "
          "liggghts seed2 (inside each band)")
    for k in KEYS:
        cells = [k]
        bands = {}
        for n in names:
            v = [s[k] for s in stats[n]]
            bands[n] = band_of(v)
            cells.append(f"{np.nanmean(v):.4g} [{bands[n][0]:.4g}, {bands[n][1]:.4g}]")
        for variant in ("seed1", "seed2"):
            x = lig[variant][k]
            inside = ["yes" if bands[n][0] <= x <= bands[n][1] else "NO" for n in names]
            cells.append(f"{x:.4g} ({' / '.join(inside)})" if math.isfinite(x) else "—")
        print(" | ".join(cells))
    for k in ("settlement at 100 kPa [mm]", "settlement at 600 kPa [mm]", "bed top before loading [m]"):
        print(f"per seed, {k}: " + "; ".join(f"{n} " + ", ".join(f"{s[k]:.4g}" for s in stats[n]) for n in names))


if __name__ == "__main__":
    main()
