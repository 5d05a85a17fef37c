"""Does the ellipsoid full bed's loading depend on Δt, on the plate speed or on the local damping?  Rerun the
loading (only the loading) from the very bed the page loaded, with one of them changed.

    python benchmarks/uniaxial3d_loading_dt.py [--dt-fraction 0.1] [--plate-speed 0.04] [--local-damping 0.0]
                                               [--out /tmp/uniaxial3d-dt]
    python benchmarks/uniaxial3d_loading_dt.py --seed 2 [--out ...]   # the whole protocol on another seed's bed

Needs the settled beds of ``demflow validate --case miyata-uniaxial-3d-ellipsoids-full`` (its checkpoints under
.demflow/checkpoints/): their settle1/settle2 states are copied into a fresh checkpoint directory for the changed
parameters, so the loading runs from the page's bed.  Prints, for the page's run and for the rerun, the largest drop
of the plate stress from its running maximum (where and how large), the settlements at 100 and 400 kPa, and the
seed's statements judged as on the page (Figs 32, 33, 35 and 37: :func:`seed_statement_checks`); the rerun's curve
goes to OUT/curve.parquet.  A changed local damping applies to the loading only (the settled bed is the page's).
``--seed`` instead runs the whole protocol (insertion, settling, trim, loading) for another seed: a different bed.
Results: benchmarks/results/uniaxial3d_loading_dt.txt (Δt) and uniaxial3d_loading_rerun.txt (plate speed, local
damping); see README, miyata-uniaxial-3d-ellipsoids-full.
"""
from __future__ import annotations

import argparse
import glob
import pickle
import shutil
import time
import warnings
from pathlib import Path

import pandas as pd

from demflow.cases import get_case
from demflow.cases.miyata_uniaxial3d_protocol import ProtocolCheckpoints, protocol_run
from demflow.cases.miyata_uniaxial3d import seed_statement_checks
from demflow.cases.miyata_uniaxial3d_statistics import stress_falls

CASE = "miyata-uniaxial-3d-ellipsoids-full"


def largest_drop(c: pd.DataFrame) -> str:
    d = stress_falls(c)
    i, j = d["i_to"], d["i_from"]
    at = {lev: float(c.settlement[(c.plate_stress >= lev).idxmax()]) for lev in (100e3, 400e3)}
    return (f"largest drop {d['fall'] / 1e3:.1f} kPa: {c.plate_stress[j] / 1e3:.1f} kPa at step {int(c.step[j])} "
            f"(settlement {1e3 * c.settlement[j]:.1f} mm) to {c.plate_stress[i] / 1e3:.1f} kPa at step {int(c.step[i])}; "
            f"settlement at 100 / 400 kPa {1e3 * at[100e3]:.1f} / {1e3 * at[400e3]:.1f} mm")


def statements(curve: pd.DataFrame, snaps, area: float) -> str:
    """The seed's statements (the page's checks of them) on a loading: one line each, PASS/MISS and its text."""
    checks = seed_statement_checks({"curve": curve, "snapshots": snaps, "area": area})
    return "\n".join(f"    {'PASS' if c.passed else 'MISS'} {c.name} [value {c.value:.4g}]" for c in checks)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dt-fraction", type=float, default=None, help="(default: the case's, 0.2)")
    ap.add_argument("--plate-speed", type=float, default=None, help="[m/s] (default: the case's, 0.02)")
    ap.add_argument("--local-damping", type=float, default=None, help="during the loading (default: the case's, 0.3)")
    ap.add_argument("--seed", type=int, default=None, help="the whole protocol on this seed's bed (no loading rerun)")
    ap.add_argument("--out", default="/tmp/uniaxial3d-dt")
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    case = get_case(CASE)
    page_p = case.merged()
    page = ProtocolCheckpoints(case.params["checkpoint_dir"], page_p)
    done = sorted(glob.glob(str(page.path("loading-*.pkl"))))
    if not (page.path("settle2.done").exists() and done):
        raise SystemExit(f"no completed run in {page.dir}: run 'demflow validate --case {CASE}' first")
    with open(done[-1], "rb") as f:
        st = pickle.load(f)
    curve = pd.DataFrame(st["rows"])
    area = float(page_p["box"]) ** 2
    print(f"page's run (dt_fraction {page_p['dt_fraction']}, plate speed {page_p['plate_speed']} m/s, local damping "
          f"{page_p['local_damping']}):", largest_drop(curve))
    print(statements(curve, st["snaps"], area))
    out = Path(a.out)
    change = {"checkpoint_dir": str(out / "checkpoints")}
    for key, v in (("dt_fraction", a.dt_fraction), ("plate_speed", a.plate_speed), ("local_damping", a.local_damping)):
        if v is not None:
            change[key] = v
    if a.seed is not None:
        change["seed"] = a.seed
    p = case.merged(change)
    new = ProtocolCheckpoints(p["checkpoint_dir"], p)
    new.dir.mkdir(parents=True, exist_ok=True)
    if a.seed is None:  # the loading only, from the page's settled bed
        for name in ("settle1.npz", "settle1.done", "settle2.npz", "settle2.done"):
            shutil.copy(page.path(name), new.path(name))
    t = time.perf_counter()
    run = protocol_run(p)
    run["curve"].to_parquet(out / "curve.parquet")
    what = f"seed {a.seed} (the whole protocol: {run['n_particles']} particles kept)" if a.seed is not None else "rerun"
    print(f"{what} at dt_fraction {p['dt_fraction']}, plate speed {p['plate_speed']} m/s, local damping "
          f"{p['local_damping']} (dt {run['dt']:.4g} s, {time.perf_counter() - t:.0f} s):", largest_drop(run["curve"]))
    print(statements(run["curve"], run["snapshots"], run["area"]))


if __name__ == "__main__":
    main()
