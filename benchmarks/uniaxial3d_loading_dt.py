"""Is the stress drop of the ellipsoid full bed a time-step artefact?  Rerun its loading at another Δt.

    python benchmarks/uniaxial3d_loading_dt.py [--dt-fraction 0.1] [--out /tmp/uniaxial3d-dt]

Needs the settled beds of ``demflow validate --case miyata-uniaxial-3d-ellipsoids-full`` (its checkpoints under
.demflow/checkpoints/): their settle1/settle2 states are copied into a fresh checkpoint directory for the given
``dt_fraction``, so the loading (and only the loading) runs from the very bed the page loaded, at the new Δt.
Prints, for the page's run and for the rerun, the largest drop of the plate stress from its running maximum
(where and how large) and the settlements at 100 and 400 kPa; the rerun's curve goes to OUT/curve.parquet.
Run on 2026-11-25 with --dt-fraction 0.1 (1753 s, one core): see README, miyata-uniaxial-3d-ellipsoids-full.
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
from demflow.cases.miyata_uniaxial3d import ProtocolCheckpoints, protocol_run

CASE = "miyata-uniaxial-3d-ellipsoids-full"


def largest_drop(c: pd.DataFrame) -> str:
    dd = c.plate_stress.cummax() - c.plate_stress
    i = dd.idxmax()
    j = c.plate_stress[:i + 1].idxmax()
    at = {lev: float(c.settlement[(c.plate_stress >= lev).idxmax()]) for lev in (100e3, 400e3)}
    return (f"largest drop {dd[i] / 1e3:.1f} kPa: {c.plate_stress[j] / 1e3:.1f} kPa at step {int(c.step[j])} "
            f"(settlement {1e3 * c.settlement[j]:.1f} mm) to {c.plate_stress[i] / 1e3:.1f} kPa at step {int(c.step[i])}; "
            f"settlement at 100 / 400 kPa {1e3 * at[100e3]:.1f} / {1e3 * at[400e3]:.1f} mm")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dt-fraction", type=float, default=0.1)
    ap.add_argument("--out", default="/tmp/uniaxial3d-dt")
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    case = get_case(CASE)
    page = ProtocolCheckpoints(case.params["checkpoint_dir"], case.merged())
    done = sorted(glob.glob(str(page.path("loading-*.pkl"))))
    if not (page.path("settle2.done").exists() and done):
        raise SystemExit(f"no completed run in {page.dir}: run 'demflow validate --case {CASE}' first")
    with open(done[-1], "rb") as f:
        print("page's run:", largest_drop(pd.DataFrame(pickle.load(f)["rows"])))
    out = Path(a.out)
    p = case.merged({"dt_fraction": a.dt_fraction, "checkpoint_dir": str(out / "checkpoints")})
    new = ProtocolCheckpoints(p["checkpoint_dir"], p)
    new.dir.mkdir(parents=True, exist_ok=True)
    for name in ("settle1.npz", "settle1.done", "settle2.npz", "settle2.done"):
        shutil.copy(page.path(name), new.path(name))
    t = time.perf_counter()
    run = protocol_run(p)
    run["curve"].to_parquet(out / "curve.parquet")
    print(f"rerun at dt_fraction {a.dt_fraction} (dt {run['dt']:.4g} s, {time.perf_counter() - t:.0f} s):",
          largest_drop(run["curve"]))


if __name__ == "__main__":
    main()
