"""How large must the periodic box be for the plate's stress-settlement curve to rise monotonically?  (Issue 14:
the reduced `miyata-uniaxial-3d` variant is left out of the default validate because in its 2 x 2 m box the
curve's monotone check fails.)

    python benchmarks/uniaxial3d_box_study.py --boxes 2 3 4 --seeds 1 2 3 [--shape clumps] [--out /tmp/box-study]

Runs the case's whole protocol (:func:`demflow.cases.miyata_uniaxial3d_protocol.protocol_run`: insertion, settling, trim at
2.0 m, loading at 2 cm/s to 600 kPa) for each box side and seed, one seed at a time on one core, with the number
of inserted particles scaled with the box's area (the reduced variant's 80 per 4 m^2; every other parameter the
case's).  Prints one row per run: particles kept, particles on the plate at 100 and 400 kPa, the case's own
monotone check (21 equally spaced settlements), the largest drop of the plate stress below its running maximum
(absolute, and relative to that maximum) and where it came, the number of drops deeper than 5 % of the running
maximum (all, and those once it is past 100 kPa), and the compute time.  Each run's curve goes to
OUT/box<L>-seed<S>.parquet; ``--summarise`` prints the rows again from those files, ``--engines`` adds the stored
YADE and LIGGGHTS runs of the reduced variant.  Results:
benchmarks/results/uniaxial3d_box_study.txt; see README, miyata-uniaxial-3d.
"""
from __future__ import annotations

import argparse
import pickle
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from demflow.cases import get_case
from demflow.cases.miyata_uniaxial3d_statistics import monotone_steps, stress_falls
from demflow.cases.miyata_uniaxial3d_protocol import protocol_run

PER_M2 = 80 / 4.0  # the reduced variant's insertion density
DEEP = 0.05  # a drop deeper than this fraction of the running maximum is counted


def plate_count(c: pd.DataFrame, level: float) -> float:
    k = int((c.plate_stress >= level).to_numpy().argmax())
    return float(c.plate_contacts.iloc[k])


def row(label: str, c: pd.DataFrame, kept, seconds=None) -> str:
    steps = monotone_steps(c)
    d = stress_falls(c, DEEP, 100e3)
    k = d["i_from"]
    return (f"{label} | {kept} | {plate_count(c, 100e3):.0f} / {plate_count(c, 400e3):.0f} | "
            f"{'yes' if np.all(steps >= 0) else 'no'} ({steps.min() / 1e3:+.1f}) | {d['fall'] / 1e3:.1f} "
            f"({100 * d['rel']:.0f} %) from {c.plate_stress.iloc[k] / 1e3:.0f} at {1e3 * c.settlement.iloc[k]:.0f} | "
            f"{d['n_deep']} / {d['n_deep_past']} | "
            f"{'' if seconds is None else f'{seconds:.0f}'}")


HEADER = ("run | kept | plate particles at 100 / 400 kPa | monotone (21 samples; min step kPa) | "
          "largest drop kPa (rel.) from kPa at mm | drops > 5 % (all / past 100 kPa) | compute s")


def engines() -> None:
    """The same numbers for the stored YADE and LIGGGHTS runs of the reduced variant (2 x 2 m box)."""
    from demflow.engines import reference

    root = reference.root() / "miyata-uniaxial-3d"
    for f in sorted(root.glob("seed*/*/curve.parquet")):
        print(row(f"2 m, {f.parent.name} {f.parent.parent.name}", pd.read_parquet(f), "-"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--boxes", type=float, nargs="*", default=[2.0, 3.0, 4.0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--shape", default="clumps", choices=("clumps", "ellipsoids"))
    ap.add_argument("--out", default="/tmp/box-study")
    ap.add_argument("--engines", action="store_true", help="also the stored YADE and LIGGGHTS runs (2 x 2 m box)")
    ap.add_argument("--summarise", action="store_true", help="only print the rows of the runs already in OUT")
    ap.add_argument("--also", nargs="*", default=[], help="rows for other loading curves too: a curve.parquet (as "
                    "uniaxial3d_loading_dt.py writes) or a loading-*.pkl checkpoint of a full page")
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    case = get_case("miyata-uniaxial-3d")
    print(f"shape {a.shape}; {PER_M2:g} inserted per m^2; a deep drop is one below {100 * DEEP:g} % of the running max")
    print(HEADER)
    if a.engines:
        engines()
    for path in a.also:
        if path.endswith(".pkl"):
            with open(path, "rb") as fh:
                c = pd.DataFrame(pickle.load(fh)["rows"])
        else:
            c = pd.read_parquet(path)
        print(row(path, c, "-"))
    for box in a.boxes:
        for seed in a.seeds:
            f = out / f"box{box:g}-seed{seed}.parquet"
            if a.summarise:
                if f.exists():
                    print(row(f"{box:g} m, seed {seed}", pd.read_parquet(f), "-"), flush=True)
                continue
            n = int(round(PER_M2 * box * box))
            p = case.merged({"box": box, "n_insert": n, "seed": seed, "shape": a.shape, "band_seeds": 1,
                             "engine_refs": 0, "undamped_band": 0, "progress": False,
                             "checkpoint_dir": str(out / "checkpoints")})
            t = time.perf_counter()
            r = protocol_run(p)
            r["curve"].to_parquet(f)
            print(row(f"{box:g} m, seed {seed}", r["curve"], r["n_particles"], time.perf_counter() - t), flush=True)


if __name__ == "__main__":
    main()
