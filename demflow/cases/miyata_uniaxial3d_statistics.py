"""What one run of the uniaxial protocol (demflow's, YADE's or LIGGGHTS's) is judged on: the statistics of
:func:`run_statistics` (the curve at fixed stresses, particles on the plate and floor, q-model N), the per-particle
forces f = F/<F> pooled over the snapshots, the curve's shape (:func:`monotone_steps`, :func:`stress_falls`,
:func:`regime_numbers`: Miyata Figs 32-33) and the particle-resampled bootstrap of a force statistic.
"""
from __future__ import annotations

import math

import numpy as np


STRESS_LEVELS_KPA = (100, 200, 300, 400, 500, 600)  # the curve sampled at fixed stresses (every run reaches them)


def _equal_forces(f) -> bool:
    """Whether the q-model sees these forces as all equal (its N infinite): fit_q_model's own criterion,
    ln<f> - <ln f> <= 0, over the positive forces."""
    f = np.asarray(f, float)
    f = f[f > 0]
    return bool(f.size and (np.ptp(f) == 0.0 or math.log(float(np.mean(f))) - float(np.mean(np.log(f))) <= 0.0))


def run_statistics(u) -> dict:
    """The statistics one run (:class:`demflow.engines.uniaxial3d.UniaxialRun`, any engine) is judged on:
    particles left after trimming, the bed's top before loading, the settlement [mm] where the plate stress
    first reaches each of :data:`STRESS_LEVELS_KPA` (the stress-settlement curve at fixed stresses),
    the particles on the plate and the floor (mean over the 400-600 kPa snapshots) and the q-model N of
    the per-particle forces f = F/<F> on each (pooled over the snapshots).  The curve is also given as the
    plate's height where each stress is first reached (the bed's height under that load): the settlement
    since the first touch starts at whichever particle stands highest, and its seed-to-seed spread is
    several times larger (measured, 8 seeds: 79-269 mm at 100 kPa, against a 4.5 cm s.d. of the height)."""
    from ..analysis.forces import fit_q_model
    from ..engines.uniaxial3d import PLATE_GAP

    c = u.curve
    out = {"particles after trimming": float(u.meta["n_particles"]),
           "bed top before loading [m]": float(u.meta["plate_start"]) - PLATE_GAP}
    for L in STRESS_LEVELS_KPA:
        hit = c[c.plate_stress >= L * 1e3]
        out[f"plate height at {L} kPa [m]"] = float(hit.plate_z.iloc[0]) if len(hit) else math.nan
    for L in STRESS_LEVELS_KPA:
        hit = c[c.plate_stress >= L * 1e3]
        out[f"settlement at {L} kPa [mm]"] = float(hit.settlement.iloc[0]) * 1e3 if len(hit) else math.nan
    for wall in ("plate", "floor"):
        fs = [f for f in u.snapshot_forces(wall) if f.size]
        out[f"particles on the {wall} (mean of snapshots)"] = float(np.mean([f.size for f in fs])) if fs else math.nan
        f = pooled_f(u, wall)
        # the fit needs 3 forces; one particle per snapshot gives f = 1 every time, and forces equal to round-off
        # give ln<f> - <ln f> <= 0 in floating point (the fit's own test): N infinite either way
        out[f"q-model N, {wall}"] = (math.nan if f.size < 3 else math.inf if _equal_forces(f)
                                     else float(fit_q_model(f).N))
    return out


def _pooled(forces) -> np.ndarray:
    """Per-snapshot force arrays, each normalised by its own mean (f = F/<F>), pooled; empty ones left out."""
    fs = [np.asarray(f) for f in forces if len(f)]
    return np.concatenate([f / f.mean() for f in fs]) if fs else np.zeros(0)


def pooled_f(u, wall: str = "plate") -> np.ndarray:
    """f = F/<F> per particle on ``wall`` of a :class:`~demflow.engines.uniaxial3d.UniaxialRun`, pooled."""
    return _pooled(u.snapshot_forces(wall))


def pooled_f_snaps(snaps, wall: str) -> np.ndarray:
    """f = F/<F> per particle on ``wall`` over demflow's snapshots (the protocol's dicts), pooled."""
    return _pooled(s[wall] for s in snaps)


def cluster_bootstrap(snaps, wall: str, statistic, n_resamples: int, level: float) -> tuple[float, float]:
    """Percentile interval at ``level`` of ``statistic`` (a function of pooled f) resampling the particles
    that touched ``wall`` with all their snapshots (scipy.stats.bootstrap over particle ids; each resample
    normalised to mean 1 again): the snapshots of one particle are not independent draws, so the particle is
    the unit resampled."""
    from scipy import stats

    ids = np.concatenate([s[f"{wall}_ids"] for s in snaps if len(s[wall])])
    f = pooled_f_snaps(snaps, wall)
    uniq, inv = np.unique(ids, return_inverse=True)
    order = np.argsort(inv, kind="stable")
    groups = np.split(f[order], np.cumsum(np.bincount(inv))[:-1])
    def resampled(k):
        fb = np.concatenate([groups[i] for i in k])
        return statistic(fb / fb.mean())  # f = F/<F> of the resampled bed

    res = stats.bootstrap((np.arange(uniq.size),), resampled,
                          vectorized=False, n_resamples=n_resamples, confidence_level=level, method="percentile",
                          random_state=np.random.default_rng(0))
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def monotone_steps(curve, samples: int = 21) -> np.ndarray:
    """Changes [Pa] of the plate stress between ``samples`` equally spaced settlements from the first touch to the
    end (the case's monotone check: none may be negative)."""
    on = curve[curve.settlement > 0]
    grid = np.linspace(on.settlement.min(), on.settlement.max(), samples)
    return np.diff(np.interp(grid, on.settlement.to_numpy(), on.plate_stress.to_numpy()))


def stress_falls(curve, deep: float = 0.05, past: float = 100e3) -> dict:
    """Falls of the plate stress below its running maximum, record by record: the deepest (``fall`` [Pa], ``rel``
    to the maximum it fell from, ``i_from`` / ``i_to`` the positions of that maximum and of the bottom), and how many
    separate falls go deeper than ``deep`` of the running maximum (``n_deep``), and of those, how many come once
    that maximum is past ``past`` [Pa] (``n_deep_past``)."""
    s = curve.plate_stress.to_numpy()
    run_max = np.maximum.accumulate(s)
    dd = run_max - s
    i = int(np.argmax(dd))
    rel = np.where(run_max > 0, dd / np.where(run_max > 0, run_max, 1.0), 0.0)
    flag = rel > deep

    def episodes(f):
        return int(np.sum(f[1:] & ~f[:-1]) + (f[0] if f.size else 0))

    return {"fall": float(dd[i]), "rel": float(rel[i]), "i_from": int(np.argmax(s[:i + 1])), "i_to": i,
            "n_deep": episodes(flag), "n_deep_past": episodes(flag & (run_max >= past))}


def first_reach(curve, stress: float) -> float:
    """Settlement [m] where the plate stress first reaches ``stress`` [Pa] (nan if it never does)."""
    hit = curve[curve.plate_stress >= stress]
    return float(hit.settlement.iloc[0]) if len(hit) else math.nan


REGIMES = (100e3, 400e3)  # Miyata §3.3, Fig. 32: initial 0-100, transitional 100-400, final > 400 kPa
SEED_MUETH = {"b": 0.75, "beta": 1.5}  # Miyata eq 61 as fitted to the seed's floor (a = 3 its normalisation)


def regime_numbers(curve) -> dict:
    """The stress-settlement curve's regimes (Fig. 32) and the plate contacts' rates (Fig. 33): secant stiffness
    [Pa/m] of the initial (first touch to 100 kPa) and transitional (100-400 kPa) regimes, of the first and
    second halves (by settlement) of the final regime (400 kPa to the end), the plate contacts' rate per kPa in
    each regime, and the floor contacts' spread (max - min)/mean from the first touch on."""
    on = curve[curve.settlement > 0]
    s1, s2 = first_reach(curve, REGIMES[0]), first_reach(curve, REGIMES[1])
    end_s, end_sig = float(curve.settlement.iloc[-1]), float(curve.plate_stress.iloc[-1])
    mid = 0.5 * (s2 + end_s)
    sig_mid = float(np.interp(mid, on.settlement.to_numpy(), on.plate_stress.to_numpy()))

    def contacts_at(stress):
        hit = curve[curve.plate_stress >= stress]
        return float(hit.plate_contacts.iloc[0]) if len(hit) else math.nan

    c0, c1, c2, c3 = contacts_at(1e-12), contacts_at(REGIMES[0]), contacts_at(REGIMES[1]), float(curve.plate_contacts.iloc[-1])
    fl = on.floor_contacts.to_numpy(float)
    return {"k initial": REGIMES[0] / s1, "k transitional": (REGIMES[1] - REGIMES[0]) / (s2 - s1),
            "k final, first half": (sig_mid - REGIMES[1]) / (mid - s2), "k final, second half": (end_sig - sig_mid) / (end_s - mid),
            "plate contacts per kPa, initial": (c1 - c0) / (REGIMES[0] / 1e3),
            "plate contacts per kPa, transitional": (c2 - c1) / ((REGIMES[1] - REGIMES[0]) / 1e3),
            "plate contacts per kPa, final": (c3 - c2) / ((end_sig - REGIMES[1]) / 1e3),
            "floor contacts spread": float((fl.max() - fl.min()) / fl.mean()), "floor contacts mean": float(fl.mean())}
