"""Is Fig. 35's miss (plate forces: q-model N = 3 in the seed, about 1 here) the fitting method's?  Fit the q-model
(Miyata eq 62) to the same pooled plate and floor forces f = F/<F> of a full uniaxial run in several ways.

    python benchmarks/uniaxial3d_fit_methods.py LOADING.pkl [LOADING.pkl ...]

LOADING.pkl: a loading checkpoint of a full run (``demflow validate --case miyata-uniaxial-3d-ellipsoids-full`` keeps
it under .demflow/checkpoints/; benchmarks/uniaxial3d_loading_dt.py --seed N under its --out).  For each wall: the
maximum-likelihood N of the page (:func:`demflow.analysis.forces.fit_q_model`), the method of moments (a gamma law
of mean 1 has variance 1/N), and least squares of the q-model density against a histogram on linear axes with bins
of 0.1, 0.2, 0.25 and 0.5 over 0 <= f < 4 (how a fit to a printed histogram would be made).  Also the share of
forces below 0.1 <F> (the q-model with N = 3 puts 0.36 % there), and the maximum-likelihood N once the forces below
0.1, 0.2 and 0.3 <F> are left out (as if the lightest contacts were not counted) and the rest renormalised.  Results: benchmarks/results/uniaxial3d_fit_methods.txt.
"""
from __future__ import annotations

import argparse
import pickle

import numpy as np
from scipy import optimize, stats

from demflow.analysis.forces import fit_q_model
from demflow.cases.miyata_uniaxial3d_statistics import pooled_f_snaps

BINS = (0.1, 0.2, 0.25, 0.5)
CUTS = (0.1, 0.2, 0.3)  # leave out the forces below this fraction of <F>, renormalise, fit again


def q_density(f, N):
    return stats.gamma.pdf(f, N, scale=1.0 / N)


def lsq_histogram(f: np.ndarray, width: float) -> float:
    edges = np.arange(0.0, 4.0 + 1e-9, width)
    h, _ = np.histogram(f, edges)
    h = h / (f.size * width)
    c = 0.5 * (edges[1:] + edges[:-1])
    r = optimize.minimize_scalar(lambda u: float(np.sum((q_density(c, np.exp(u)) - h) ** 2)),
                                 bounds=(np.log(0.2), np.log(20.0)), method="bounded")
    return float(np.exp(r.x))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("loading", nargs="+")
    a = ap.parse_args()
    print(f"q-model N = 3 puts {100 * stats.gamma.cdf(0.1, 3, scale=1 / 3):.2f} % of forces below 0.1 <F>")
    print("run | wall | forces | share below 0.1 | N max. likelihood (95 %) | N moments 1/var | N least squares on "
          + " / ".join(f"bins {w}" for w in BINS) + " | N max. likelihood without f < " + " / ".join(map(str, CUTS)))
    for path in a.loading:
        with open(path, "rb") as fh:
            st = pickle.load(fh)
        for wall in ("plate", "floor"):
            f = pooled_f_snaps(st["snaps"], wall)
            ml = fit_q_model(f)
            print(f"{path} | {wall} | {f.size} | {100 * np.mean(f < 0.1):.1f} % | {ml.N:.2f} ({ml.ci[0]:.2f}-{ml.ci[1]:.2f}) | "
                  f"{1.0 / np.var(f):.2f} | " + " / ".join(f"{lsq_histogram(f, w):.2f}" for w in BINS) + " | "
                  + " / ".join(f"{fit_q_model(f[f >= c] / f[f >= c].mean()).N:.2f}" for c in CUTS))


if __name__ == "__main__":
    main()
