"""How one run is judged against demflow's seeds (issue 14 item 4): the 95 % prediction band of the seeds and
the one rule every run is judged by (:func:`seed_band`, :func:`judge`), the plate forces' KS band, demflow's own
leave-one-out misses, and an engine's runs judged together as an ensemble (Welch's test with Holm's adjustment,
the miss share by Fisher's exact test); which band has which engine's physics (:func:`engine_band`).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..tolerances import tol
from .miyata_uniaxial3d_statistics import pooled_f, run_statistics


BAND_INFORMATIVE = tol("miyata3d.band-informative").value  # a wider seed band judges nothing: shown, not counted


def band_of(values) -> tuple[float, float]:
    """95 % prediction band of one more seed (:func:`demflow.cases.cs_photoelastic.prediction_band`),
    over the finite values."""
    from .cs_photoelastic import prediction_band

    v = np.asarray([x for x in values if math.isfinite(x)], float)
    return prediction_band(v) if v.size >= 3 else (math.nan, math.nan)


def ks_band(f: dict) -> tuple[np.ndarray, float]:
    """The KS distance of each demflow seed's pooled f (``f``: {seed: :func:`pooled_f`}) from the other seeds' pooled
    f, and the upper end of their 95 % prediction band: how far one more seed's distribution falls from the rest."""
    from scipy import stats

    d = [stats.ks_2samp(f[s], np.concatenate([g for q, g in f.items() if q != s])).statistic for s in f]
    return np.asarray(d), band_of(d)[1]


class BandSummary(NamedTuple):
    """What every engine run is judged against, computed once per band (:func:`band_summary`): each seed's
    :func:`run_statistics` (``per_seed``), the KS distances of :func:`ks_band` (``ks_seeds``, ``ks_hi``), the
    seeds' pooled plate forces (``pooled``), and demflow's own leave-one-out misses (``loo``:
    :func:`leave_one_out_misses`' (judged, outside, seeds with a miss))."""
    per_seed: dict
    ks_seeds: np.ndarray
    ks_hi: float
    pooled: np.ndarray
    loo: tuple


def band_summary(band: dict) -> BandSummary:
    """The :class:`BandSummary` of demflow's seed ``band`` ({seed: run})."""
    f = {s: pooled_f(u) for s, u in band.items()}
    per_seed = {s: run_statistics(u) for s, u in band.items()}
    ks_seeds, ks_hi = ks_band(f)
    return BandSummary(per_seed, ks_seeds, ks_hi, np.concatenate(list(f.values())), leave_one_out_misses(per_seed))


def ks_from_pooled(f: np.ndarray, pooled: np.ndarray) -> float:
    """The KS distance of one run's pooled plate forces ``f`` (:func:`pooled_f`) from demflow's pooled seeds
    (nan for a run without plate forces)."""
    from scipy import stats

    return float(stats.ks_2samp(f, pooled).statistic) if f.size else math.nan


def leave_one_out_misses(per_seed: dict) -> tuple[int, int, int]:
    """(judged, outside, seeds with a miss): each seed's :func:`run_statistics` against the 95 % band of the other
    seeds, by the rule engine runs are judged by (:func:`judge_value`: a non-finite value is outside, a value inside
    a band too wide to judge is not judged) — how often demflow itself would miss, per statistic and per run."""
    keys = list(next(iter(per_seed.values())))
    judged = outside = 0
    missed = set()
    for s, st in per_seed.items():
        for k in keys:
            verdict = judge_value(st[k], [v[k] for q, v in per_seed.items() if q != s])
            if verdict is None:
                continue
            judged += 1
            outside += not verdict
            if not verdict:
                missed.add(s)
    return judged, outside, len(missed)


ENSEMBLE_MIN_RUNS = 4  # an engine with this many stored runs is judged as an ensemble (one draw each below)
ENSEMBLE_ALPHA = tol("miyata3d.engine-ensemble").value


def vs_level(p: float) -> str:
    """'≥ 0.05' or '< 0.05': a p-value against the ensemble tests' level, as the line's name states it."""
    return f"{'≥' if p >= ENSEMBLE_ALPHA else '<'} {ENSEMBLE_ALPHA:g}"


class SeedBand(NamedTuple):
    """The 95 % band of demflow's seeds one statistic is judged against: ``lo``, ``hi`` (nan without one: fewer
    than 3 finite seeds), the seeds' finite ``mean``, and ``wide``: no band, or one wider than
    :data:`BAND_INFORMATIVE` of its mean (too wide for a value inside it to count as a pass)."""
    lo: float
    hi: float
    mean: float
    wide: bool


def seed_band(vals) -> SeedBand:
    """The :class:`SeedBand` of the seeds' values ``vals`` of one statistic (non-finite ones left out)."""
    lo, hi = band_of(vals)
    finite = [x for x in vals if math.isfinite(x)]
    mean = float(np.mean(finite)) if finite else math.nan
    return SeedBand(lo, hi, mean, not (math.isfinite(lo) and 0.5 * (hi - lo) <= BAND_INFORMATIVE * abs(mean)))


def judge_value(v: float, vals) -> bool | None:
    """One run's statistic ``v`` against the 95 % band of the seeds' ``vals``: the one rule engine runs, demflow's
    own seeds (:func:`leave_one_out_misses`) and the page's per-run lines are judged by.  False outside (a
    non-finite value, e.g. a stress never reached, is outside), True inside, None when it cannot be judged (no
    band, or inside a band wider than :data:`BAND_INFORMATIVE` of its mean: a value outside even it is a miss)."""
    return judge(v, seed_band(vals))


def judge(v: float, b: SeedBand) -> bool | None:
    """:func:`judge_value` against a band ``b`` already formed (:func:`seed_band`)."""
    if not math.isfinite(b.lo):
        return None
    inside = bool(b.lo <= v <= b.hi)
    return None if inside and b.wide else inside


def run_has_miss(st: dict, per_seed: dict) -> bool:
    """Whether a run's statistics ``st`` miss the band of ``per_seed`` ({seed: statistics}) in any judged one."""
    return any(judge_value(st[k], [v[k] for v in per_seed.values()]) is False for k in st)


def holm(p: dict) -> dict:
    """Holm's step-down adjustment of the p-values ``p`` ({name: p}; non-finite ones left out and kept as they
    are): the family-wise error over the finite ones stays at the level each adjusted p is compared with."""
    names = sorted((k for k, v in p.items() if math.isfinite(v)), key=lambda k: p[k])
    m = len(names)
    out = dict(p)
    running = 0.0
    for i, k in enumerate(names):
        running = max(running, min(1.0, (m - i) * p[k]))
        out[k] = running
    return out


def ensemble_comparison(demflow: dict, engine: dict) -> dict[str, dict]:
    """An engine's runs against demflow's seeds as two samples, per statistic of :func:`run_statistics`
    (``demflow``, ``engine``: {label: statistics}): means, s.d., Welch's two-sided p
    (:func:`demflow.cases.miyata_ksweep.compare_shapes`, the K-sweep's rule) and Holm's adjustment of those p
    over the statistics ("holm p")."""
    from .miyata_ksweep import compare_shapes

    rows = compare_shapes({"demflow": demflow, "engine": engine}, reference="demflow")
    eng = rows["engine"]
    adj = holm({k: r["welch p"] for k, r in eng.items()})
    for k, r in eng.items():
        r["holm p"] = adj[k]
        r["demflow mean"], r["demflow sd"], r["demflow n"] = (rows["demflow"][k]["mean"], rows["demflow"][k]["sd"],
                                                              rows["demflow"][k]["n"])
    return eng


def miss_rate_test(engine_misses: int, engine_runs: int, demflow_misses: int, demflow_runs: int) -> float:
    """One-sided Fisher exact p that an engine's runs miss demflow's band more often than demflow's own seeds
    do (each seed against the band of the others): runs with at least one miss out of runs, per side."""
    from scipy import stats

    table = [[engine_misses, engine_runs - engine_misses], [demflow_misses, demflow_runs - demflow_misses]]
    return float(stats.fisher_exact(table, alternative="greater").pvalue)


def engine_of(label: str) -> str:
    """The engine of a run label ("yade seed2" → "yade")."""
    return label.split()[0]


def engine_variants(p) -> tuple[str, ...]:
    """The stored engine runs of this protocol: one per seed, seed .. seed + engine_seeds - 1 (each engine run
    is one draw of a chaotic bed, judged like one more demflow seed)."""
    return tuple(f"seed{int(p['seed']) + k}" for k in range(int(p["engine_seeds"])))


def engine_band(ex, engine: str) -> dict:
    """The demflow seed band with ``engine``'s physics: without local damping for an engine whose
    capabilities row local-damping-uniaxial says it differs (LIGGGHTS), else the case's own band."""
    from ..engines.capabilities import DIFFERS, FEATURES_UNIAXIAL_3D

    row = next(f for f in FEATURES_UNIAXIAL_3D if f.key == "local-damping-uniaxial")
    if getattr(row, engine).verdict == DIFFERS and len(ex.get("band_undamped", {})) >= 3:
        return ex["band_undamped"]
    return ex["band"]
