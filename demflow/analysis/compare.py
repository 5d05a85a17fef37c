"""Comparing results of different engines (or runs): time series, curves, distributions.

All functions take plain arrays or the common result tables, so they never depend on which
engine produced the data.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats


@dataclass
class SeriesComparison:
    """Two histories on their common steps."""

    n: int
    equilibrium_a: float
    equilibrium_b: float
    equilibrium_rel: float  # |b - a| / |a| of the equilibrium values
    max_rel: float  # max |b - a| / max |a| over the common steps
    rms_rel: float


def equilibrium(values, steps=None, after=None, how="mean"):
    """Equilibrium value of a history: the mean after step ``after`` (oscillating runs) or the last value."""
    v = np.asarray(values, dtype=float)
    if how == "last":
        return float(v[-1])
    if after is not None and steps is not None:
        v = v[np.asarray(steps) >= after]
    return float(v.mean())


def compare_series(steps_a, a, steps_b, b, *, after=None, how="mean") -> SeriesComparison:
    """Compare two histories sampled at (possibly different) steps, on the steps they share."""
    steps_a, steps_b = np.asarray(steps_a), np.asarray(steps_b)
    common, ia, ib = np.intersect1d(steps_a, steps_b, return_indices=True)
    if common.size == 0:
        raise ValueError("the two histories share no step")
    a = np.asarray(a, dtype=float)[ia]
    b = np.asarray(b, dtype=float)[ib]
    scale = np.max(np.abs(a)) or 1.0
    d = b - a
    ea = equilibrium(a, common, after, how)
    eb = equilibrium(b, common, after, how)
    return SeriesComparison(n=int(common.size), equilibrium_a=ea, equilibrium_b=eb,
                            equilibrium_rel=abs(eb - ea) / abs(ea) if ea else abs(eb - ea),
                            max_rel=float(np.max(np.abs(d)) / scale), rms_rel=float(np.sqrt(np.mean(d * d)) / scale))


def compare_curves(xa, ya, xb, yb, n=200):
    """Max and RMS relative difference of two curves on a common abscissa (their overlap)."""
    lo = max(np.min(xa), np.min(xb))
    hi = min(np.max(xa), np.max(xb))
    x = np.linspace(lo, hi, n)
    fa = np.interp(x, xa, ya)
    fb = np.interp(x, xb, yb)
    scale = np.max(np.abs(fa)) or 1.0
    return dict(max_rel=float(np.max(np.abs(fb - fa)) / scale), rms_rel=float(np.sqrt(np.mean((fb - fa) ** 2)) / scale))


def compare_distributions(a, b, bins=20, range_=None):
    """Histograms on common bins, the two-sample Kolmogorov-Smirnov test (scipy.stats.ks_2samp)
    and, for normalised contact forces f = F/<F>, the q-model N (with its CI) of each sample."""
    from .forces import fit_q_model

    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    range_ = range_ or (min(a.min(), b.min()), max(a.max(), b.max()))
    ha, edges = np.histogram(a, bins=bins, range=range_, density=True)
    hb, _ = np.histogram(b, bins=edges, density=True)
    ks = stats.ks_2samp(a, b)
    qa, qb = fit_q_model(a / a.mean()), fit_q_model(b / b.mean())
    return dict(edges=edges, pdf_a=ha, pdf_b=hb, ks_statistic=float(ks.statistic), ks_pvalue=float(ks.pvalue),
                q_model_a=(qa.N, qa.ci), q_model_b=(qb.N, qb.ci))
