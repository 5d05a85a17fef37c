"""Speed against accuracy, measured for one knob at a time (issue 17 item 1).

A :class:`TradeoffStudy` (freud-like: configure, ``compute()`` returns ``self``, then ``table`` and
``plot(ax=None)``) runs a registered case

1. at a *reference* setting (the finest the user can afford: parameter overrides),
2. at the *chaos floor*: the reference with a physically irrelevant change (``floor``, e.g. a density
   × 1.0001); its distance from the reference is how far any perturbation moves the case's
   observables (a chaotic packing's history diverges), so a knob's error is only meaningful above it,
3. once per value of each knob, every other parameter at the reference.

Observables are the case's own check values (every finite, non-informative check: what the case
claims to reproduce), or what its ``observables`` hook returns (e.g. a curve sampled on a grid), kept
to the names containing one of ``observables`` when that is given.  A run's *error* is the root mean square over observables of
|v − v_ref| / max(|v_ref|, scale), where ``scale`` guards zero references; what a run costs is recorded as its
wall time, its particle-steps (from each result's steps and particle count) and particle-steps per second of the
cost compared (below), with the simulation time split into DEM and fluid (BEM) time where the results record them.  Settings are compared by
their *cost*: the simulation time (DEM + fluid, or a protocol's own compute time) when every run records it, else
the wall time; the wall time adds what a knob does not change (building a packing, the analysis) and with it only
the host's noise (the photoelastic study's Δt 0.1 run took 7.8 s of wall time and 0.91 s of DEM time, its Δt 0.05
run 6.8 s and 1.82 s, README).  Runs go through
:func:`demflow.sweep.run_sweep` (serial by default, a Dask cluster on request).

The table marks the Pareto front of the settings (no other run is both cheaper and more accurate; the repeat of
the reference is left out: it is the timing's check, not a setting) and the
*recommended* setting: among the knob settings whose error is within ``accept`` × the chaos floor (default 2:
indistinguishable from the reference up to the floor's own noise), the most accurate of the cheapest, or the most
accurate knob setting when none is within it (``within_floor`` says which).  "Cheapest" is judged against how
far apart the costs of runs that should cost the same are (:func:`cost_noise`): the reference runs once more as the
study's last run (the same work, the same bits: determinism), and their relative difference is the host's noise
(:func:`timing_noise`); the chaos floor's run differs from the reference only physically irrelevantly, and its cost's
relative difference from the reference's (:func:`cost_floor`) is how far such a change moves the cost, the host's
noise included — in a protocol that runs until a target is reached (the 3D uniaxial case loads until a stress) the
work itself follows the chaotic trajectory (the floor run of 2026-11-28 did 25 % fewer particle-steps than the
reference).  Settings whose cost is within the larger of the two of the cheapest one's are equally cheap
(:func:`recommend`), so that the pick does not follow the host's noise or the chaos of one draw from run to run (it
did: the photoelastic study's three Δt settings, 6.2-6.7 s of wall time in one run, picked 0.1, 0.07 or 0.05 over ten
runs; the 3D study's K = 2, K = 4 and 8 cm/s, all within the chaos floor and 13-25 s of compute time each over the
runs of 2026-11-28, took turns while the repeat measured 0.2-5 %, README).  With ``warmup`` one untimed run compiles
the kernels first, so that no timed run pays for compilation (``True``: the last knob run; a dict:
overrides of the reference for a cheaper run that compiles the same kernels).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd


def _cost(run) -> dict:
    """Particle-steps, DEM and fluid seconds of a CaseRun's results, summed over the results that record them; NaN
    where none records it (a case whose results keep no step count shows no particle-steps/s, not 0).  A result's
    particle-steps are its ``particle_steps`` where it states them (a protocol whose stages have different particle
    counts), else its steps × its discs or spheres.  The fluid
    time is 0 where DEM time is recorded and fluid time is not (a dry case).  ``sim_s``, the time spent simulating:
    DEM + fluid where recorded, else the sum of a protocol's own ``compute_s`` (the 3D uniaxial case), else NaN."""
    steps = dem = bem = comp = 0.0
    has_steps = has_dem = has_bem = has_comp = False
    for res in run.results.values():
        meta = getattr(res, "meta", {}) or {}
        n = meta.get("n_discs") or meta.get("n_spheres") or 0
        if meta.get("particle_steps"):  # a protocol of stages with their own particle counts (the 3D uniaxial case)
            steps += float(meta["particle_steps"])
            has_steps = True
        elif meta.get("steps") and n:
            steps += float(meta["steps"]) * float(n)
            has_steps = True
        if meta.get("dem_s") is not None:
            dem += float(meta["dem_s"])
            has_dem = True
        b = meta.get("bem_s", meta.get("bem_seconds"))
        if b is not None:
            bem += float(b)
            has_bem = True
        if meta.get("compute_s") is not None:
            comp += float(meta["compute_s"])
            has_comp = True
    bem = bem if (has_bem or has_dem) else math.nan
    sim = (dem + bem) if has_dem else (bem if has_bem else (comp if has_comp else math.nan))
    return dict(particle_steps=steps if has_steps else math.nan, dem_s=dem if has_dem else math.nan, bem_s=bem,
                sim_s=sim)


def run_observed(job) -> dict:
    """One run of a study: (case name, overrides) → its observables (check name → value) and cost.
    Top level: picklable for a Dask worker."""
    from .cases.base import counted
    from .sweep import timed_case_run

    case, p, run, checks, wall = timed_case_run(*job)
    obs = case.observables(run, p)
    if obs is None:
        obs = {c.name: float(c.value) for c in counted(checks)}
    obs = {k: float(v) for k, v in obs.items() if math.isfinite(v)}
    return dict(observables=obs, wall_s=wall, **_cost(run))


REPEAT = "reference (repeat)"


def _relative_difference(table: pd.DataFrame, run: str, cost: str) -> float:
    """|t_run - t_ref| / t_ref of the reference's cost (column ``cost``: seconds) and run ``run``'s; 0 without either
    row, a positive reference time or a finite time of ``run``."""
    ref = table[table.run == "reference"][cost]
    other = table[table.run == run][cost]
    if ref.empty or other.empty or not float(ref.iloc[0]) > 0 or not math.isfinite(float(other.iloc[0])):
        return 0.0
    return abs(float(other.iloc[0]) - float(ref.iloc[0])) / float(ref.iloc[0])


def timing_noise(table: pd.DataFrame, cost: str = "wall_s") -> float:
    """How far apart the costs (column ``cost``: seconds) of two runs doing the same work are in this study: the
    reference runs first and once more last (the repeat: the same parameters, the same steps, the same bits), so
    |t_repeat - t_ref| / t_ref is the host's noise between two runs of the study, over the study's whole duration.
    0 without a repeat run or a reference time."""
    return _relative_difference(table, REPEAT, cost)


def cost_floor(table: pd.DataFrame, cost: str = "wall_s") -> float:
    """How far the chaos floor's run's cost (column ``cost``: seconds) is from the reference's, |t_floor - t_ref| / t_ref:
    a physically irrelevant change moves a run's cost that much (the host's noise, and where the run's length follows
    the trajectory, the work itself).  0 without a floor run or a reference time."""
    return _relative_difference(table, "chaos floor", cost)


def cost_noise(table: pd.DataFrame, cost: str = "wall_s") -> float:
    """The relative cost difference below which two settings are equally cheap: the larger of :func:`timing_noise`
    (the reference against its repeat) and :func:`cost_floor` (the reference against the chaos floor's run)."""
    return max(timing_noise(table, cost), cost_floor(table, cost))


COST_BASIS = {"sim_s": "simulation time", "wall_s": "wall time"}


def tie_rule(noise: float, cost: str = "wall_s", floor_noise: float | None = None) -> str:
    """The sentence that says how the recommendation treats the cost's noise (the page and ``demflow tradeoff``):
    ``noise`` the host's (:func:`timing_noise`), ``floor_noise`` the chaos floor's (:func:`cost_floor`; None: the study
    has no floor run); the band is the larger of the two."""
    what = COST_BASIS[cost]
    if floor_noise is None:
        return (f"Settings are compared by {what}; {what}s within {noise:.0%} of the cheapest count as equally cheap "
                "(the reference run and its repeat, the study's first and last runs, differ by that much: the host's "
                "noise), and the most accurate of those is recommended.")
    return (f"Settings are compared by {what}; {what}s within {max(noise, floor_noise):.0%} of the cheapest count as "
            f"equally cheap (the larger of two differences between runs that should cost the same: the reference run "
            f"and its repeat, the study's first and last runs, {noise:.0%} apart: the host's noise; the chaos floor's "
            f"run and the reference, {floor_noise:.0%} apart: what a physically irrelevant change does to the cost), "
            "and the most accurate of those is recommended.")


def took(row, cost: str = "wall_s") -> str:
    """A run's time as a study page's text states it: its wall time, and the simulation time where that is the cost
    compared."""
    if cost == "sim_s":
        return f"{row['wall_s']:.3g} s ({row['sim_s']:.3g} s simulating)"
    return f"{row['wall_s']:.3g} s"


def recommend(table: pd.DataFrame, floor_error: float, accept: float, noise: float,
              cost: str = "wall_s") -> tuple[int, bool]:
    """(row index of the recommended knob run, whether it is within the floor): among the knob runs whose error is
    within ``accept`` × ``floor_error``, those whose cost (column ``cost``) is within ``noise`` (relative) of the cheapest are
    equally cheap, and the most accurate of them is picked; when none is within the floor, the most accurate knob
    run."""
    knobs = table[table.knob != ""]
    ok = knobs[knobs.error <= accept * floor_error]
    if not len(ok):
        return knobs.error.idxmin(), False
    tied = ok[ok[cost] <= ok[cost].min() * (1.0 + noise)]
    return tied.error.idxmin(), True


def pareto_front(cost, error) -> np.ndarray:
    """Boolean mask of the non-dominated points (lower cost and lower error are better)."""
    cost, error = np.asarray(cost, float), np.asarray(error, float)
    keep = np.ones(cost.size, bool)
    for i in range(cost.size):
        dominated = (cost <= cost[i]) & (error <= error[i]) & ((cost < cost[i]) | (error < error[i]))
        keep[i] = not dominated.any()
    return keep


class TradeoffStudy:
    """One knob at a time against a reference and a chaos floor (module docstring).

    case: a registered case name; knobs: {parameter: [values]}; reference: overrides of the case's
    defaults for the reference run; floor: overrides applied on top of the reference for the chaos
    floor run (None: no floor, errors are then judged against ``accept`` × 0); scale: the smallest
    reference magnitude an observable's relative error divides by; accept: the recommended run's
    error may be this many times the floor's; observables: keep only the observables whose names
    contain one of these strings (None: all); warmup: True, False or overrides (module docstring)."""

    def __init__(self, case: str, knobs: dict, reference: dict | None = None, floor: dict | None = None,
                 scale: float = 1e-12, accept: float = 2.0, scheduler: str | None = "serial", workers=None,
                 warmup: bool | dict = True, observables=None):
        from .cases import get_case

        c = get_case(case)
        for k in list(knobs) + list(reference or {}) + list(floor or {}):
            if k not in c.params:
                raise KeyError(f"case {case!r} has no parameter {k!r}; parameters: {sorted(c.params)}")
        if not knobs or any(len(list(v)) == 0 for v in knobs.values()):
            raise ValueError(f"knobs={knobs!r}: give at least one knob with at least one value")
        if not (accept >= 1.0):
            raise ValueError(f"accept={accept!r}: the recommended run's error bound is accept × floor, accept ≥ 1")
        self.case, self.knobs = case, {k: list(v) for k, v in knobs.items()}
        self.reference, self.floor = dict(reference or {}), (dict(floor) if floor else None)
        self.scale, self.accept = float(scale), float(accept)
        self.scheduler, self.workers = scheduler, workers
        self.warmup = dict(warmup) if isinstance(warmup, dict) else bool(warmup)
        for k in self.warmup if isinstance(self.warmup, dict) else ():
            if k not in c.params:
                raise KeyError(f"case {case!r} has no parameter {k!r}; parameters: {sorted(c.params)}")
        self.observables = [str(o) for o in observables] if observables else None
        self.table: pd.DataFrame | None = None
        self.runs: list[dict] = []
        for *_, overrides in self._jobs():  # every run's parameters of their defaults' kinds, before any run
            c.merged(overrides)

    def _jobs(self):
        jobs = [("reference", None, None, dict(self.reference))]
        if self.floor:
            jobs.append(("chaos floor", None, None, dict(self.reference, **self.floor)))
        for k, values in self.knobs.items():
            for v in values:
                jobs.append((f"{k} = {v}", k, v, dict(self.reference, **{k: v})))
        jobs.append((REPEAT, None, None, dict(self.reference)))  # last: the timing noise over the whole study
        return jobs

    def compared(self, obs: dict, ref: dict) -> int:
        """How many observables a run's error is over (those of the reference it has, after the filter)."""
        return sum(k in obs and (self.observables is None or any(o in k for o in self.observables)) for k in ref)

    def error(self, obs: dict, ref: dict) -> float:
        common = [k for k in ref if k in obs]
        if self.observables is not None:
            common = [k for k in common if any(o in k for o in self.observables)]
        if not common:
            return math.nan
        d = [abs(obs[k] - ref[k]) / max(abs(ref[k]), self.scale) for k in common]
        return float(np.sqrt(np.mean(np.square(d))))

    def compute(self) -> "TradeoffStudy":
        from .sweep import run_sweep

        jobs = self._jobs()
        if isinstance(self.warmup, dict):  # compile the kernels before anything is timed (serial runs share
            run_observed((self.case, dict(self.reference, **self.warmup)))  # this process)
        elif self.warmup:
            run_observed((self.case, jobs[-2][3]))  # the last knob run (the repeat is last)
        self.runs = run_sweep(run_observed, [(self.case, over) for *_, over in jobs], scheduler=self.scheduler,
                              workers=self.workers)
        ref = self.runs[0]["observables"]
        rows = []
        for (label, knob, value, over), r in zip(jobs, self.runs):
            rows.append(dict(run=label, knob=knob or "", value=value, error=self.error(r["observables"], ref),
                             observables=self.compared(r["observables"], ref), wall_s=r["wall_s"],
                             particle_steps=r["particle_steps"],  # NaN where the results record no step count (_cost)
                             dem_s=r["dem_s"], fluid_s=r["bem_s"], sim_s=r["sim_s"]))
        t = pd.DataFrame(rows)
        t["value"] = pd.Series([r["value"] for r in rows], dtype=object)  # each knob's own type (int, float, str)
        floor = float(t.loc[t.run == "chaos floor", "error"].iloc[0]) if self.floor else 0.0
        t["error_over_floor"] = t.error / floor if floor > 0 else math.nan
        # the cost compared: the simulation time when every run records it (module docstring), else the wall time
        self.cost = "sim_s" if bool((t.sim_s > 0).all()) else "wall_s"
        # particle-steps per second of that cost: the speed of the simulation itself where the runs record its time
        t["particle_steps_per_s"] = t.particle_steps / t[self.cost].where(t[self.cost] > 0)
        # the front of the settings: the repeat is the reference's timing check, not a setting of its own
        t["pareto"] = False
        settings = t.run != REPEAT
        t.loc[settings, "pareto"] = pareto_front(t.loc[settings, self.cost], t.loc[settings, "error"])
        self.timing_noise = timing_noise(t, self.cost)
        self.cost_floor = cost_floor(t, self.cost) if self.floor else None
        self.cost_noise = cost_noise(t, self.cost)
        pick, self.within_floor = recommend(t, floor, self.accept, self.cost_noise, self.cost)
        self.repeat_identical = self.runs[-1]["observables"] == ref  # determinism: the same bits
        t["recommended"] = False
        t.loc[pick, "recommended"] = True
        self.floor_error = floor
        self.table = t
        return self

    def reason(self) -> tuple[str, str]:
        """Why the recommended run was picked, as the page and ``demflow tradeoff`` state it: (the rule that picked it,
        the tie sentence of :func:`tie_rule` when the costs decided, '' when no setting is within the floor and the
        most accurate one was taken whatever its cost)."""
        if self.table is None:
            raise RuntimeError("call compute() first")
        if self.within_floor:
            return (f"the most accurate of the equally cheap within {self.accept:g} × the chaos floor "
                    f"{self.floor_error:.3g}", tie_rule(self.timing_noise, self.cost, self.cost_floor))
        return (f"none is within {self.accept:g} × the chaos floor {self.floor_error:.3g}: the most accurate", "")

    @property
    def recommended(self) -> dict:
        """The recommended run's row (as a dict)."""
        if self.table is None:
            raise RuntimeError("call compute() first")
        return self.table[self.table.recommended].iloc[0].to_dict()

    def plot(self, ax=None):
        """Error against the cost compared (simulation or wall time), one marker per run, the Pareto front joined,
        the chaos floor as a band, the recommended run ringed."""
        import matplotlib.pyplot as plt

        if self.table is None:
            raise RuntimeError("call compute() first")
        if ax is None:
            _, ax = plt.subplots(figsize=(6, 4))
        t = self.table
        tiny = max(self.floor_error, 1e-16) * 1e-3 if self.floor_error > 0 else 1e-16
        err = t.error.clip(lower=tiny)
        for knob in t.knob.unique():
            s = t[t.knob == knob]
            ax.scatter(s[self.cost], err[s.index], label=knob or "reference / floor / repeat", zorder=3)
            for _, r in s.iterrows():
                ax.annotate(str(r.value) if knob else r.run, (r[self.cost], err[r.name]), fontsize=7,
                            xytext=(3, 3), textcoords="offset points")
        front = t[t.pareto].sort_values(self.cost)
        ax.plot(front[self.cost], err[front.index], "k--", lw=0.8, label="Pareto front")
        if self.floor_error > 0:
            ax.axhspan(tiny, self.accept * self.floor_error, color="0.85", zorder=0,
                       label=f"≤ {self.accept:g} × chaos floor")
        rec = t[t.recommended]
        ax.scatter(rec[self.cost], err[rec.index], s=160, facecolors="none", edgecolors="r", label="recommended")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(f"{COST_BASIS[self.cost]} [s]")
        ax.set_ylabel("rms relative error of the observables vs the reference")
        ax.set_title(f"{self.case}: speed vs accuracy", fontsize=9)
        ax.legend(fontsize=7)
        return ax


__all__ = ["REPEAT", "TradeoffStudy", "cost_floor", "cost_noise", "pareto_front", "recommend", "run_observed", "tie_rule",
           "timing_noise", "took"]
