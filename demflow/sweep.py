"""Sweeps on Dask: many independent runs of a case (seed ensembles, parameter studies), one table.

:func:`run_sweep` maps a picklable function over items on a Dask cluster and returns the results in
the items' order; :func:`case_sweep` runs a registered case once per parameter set and gathers every
check's value into one pandas table (``demflow sweep CASE --set seed=1,2,...``).  Where it runs:

- ``scheduler=None`` or ``"local"``: a local cluster of ``workers`` processes (default: one per core),
  one thread each, started for the sweep and closed after it; each worker's parallel kernels get the
  cores divided among the workers (one each by default), so the processes do not oversubscribe the
  machine (two workers each running a two-thread kernel on two cores is slower than either alone);
- ``scheduler="serial"``: in this process, one item after another (what the tests compare with);
- ``scheduler="tcp://host:port"``: an existing ``dask.distributed`` scheduler.

Each run is the same computation wherever it runs (a case's runs depend on their parameters only, and
demflow's results do not depend on the thread count), so a sweep's table is identical on any scheduler;
``tests/test_sweep.py`` checks it.  Numba's on-disk cache is shared by the worker processes: a
kernel compiled once is loaded, not recompiled, by the others.
"""
from __future__ import annotations

import itertools
import os
import time

import pandas as pd


def _client(scheduler, workers):
    import dask
    from dask.distributed import Client, LocalCluster

    if scheduler in (None, "local"):
        n = int(workers or os.cpu_count() or 1)
        # Dask's statistical profiler samples every worker thread each 10 ms; the runs are long kernel
        # calls a stack sample says nothing about, and it cost 3-5 % of each run's wall time (measured
        # on thesis-simple-shear, benchmarks/bench_sweep.py).  Only this cluster's workers are affected.
        with dask.config.set({"distributed.worker.profile.enabled": False}):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                                   silence_logs=40)
        return Client(cluster), cluster
    return Client(scheduler), None


class _WithKernelThreads:
    """``fn`` run with Numba's parallel kernels limited to ``threads`` threads (picklable: a worker
    process applies the limit before each item; results do not depend on it, only speed)."""

    def __init__(self, fn, threads: int):
        self.fn, self.threads = fn, int(threads)

    def __call__(self, item):
        import numba

        numba.set_num_threads(max(1, min(self.threads, numba.config.NUMBA_NUM_THREADS)))
        return self.fn(item)


def run_sweep(fn, items, *, scheduler=None, workers=None, progress: bool | None = None) -> list:
    """[fn(item) for item in items], computed on Dask (module docstring), in the items' order."""
    from . import progress as prog

    items = list(items)
    if scheduler == "serial":
        return [fn(it) for it in prog.iterate(items, "sweep", "run", show=progress)]
    from dask.distributed import as_completed

    client, cluster = _client(scheduler, workers)
    if cluster is not None:
        fn = _WithKernelThreads(fn, (os.cpu_count() or 1) // len(cluster.workers))
    try:
        futures = client.map(fn, items, pure=False)
        index = {f.key: k for k, f in enumerate(futures)}
        out = [None] * len(items)
        with prog.bar(len(items), "sweep", "run", show=progress, leave=True) as bar:
            for f in as_completed(futures):
                out[index[f.key]] = f.result()
                bar.update(1)
        return out
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def parameter_grid(sets: dict) -> list[dict]:
    """Every combination of the listed values: {"seed": [1, 2], "dt": [1e-4]} → [{seed 1, dt 1e-4}, ...]."""
    keys = list(sets)
    return [dict(zip(keys, combo)) for combo in itertools.product(*(sets[k] for k in keys))]


def timed_case_run(name: str, overrides: dict):
    """Run registered case ``name`` with ``overrides``: (case, parameters, CaseRun, checks, wall seconds)."""
    from .cases import get_case

    case = get_case(name)
    p = case.merged(overrides)
    t0 = time.perf_counter()
    run = case.run(p)
    wall = time.perf_counter() - t0
    return case, p, run, case.checks(run, p), wall


def run_case_checks(job: tuple) -> list[dict]:
    """One run of a registered case: (case name, parameter overrides) → a row per check (value,
    reference, error, passed, kind) with the overrides and the wall time. Top level: picklable."""
    name, overrides = job
    _, _, _, checks, wall = timed_case_run(name, overrides)
    return [dict(**overrides, check=c.name, kind=c.kind, value=c.value, reference=c.reference, error=c.error,
                 passed=c.passed, wall_s=wall) for c in checks]


def case_sweep(name: str, sets: dict, *, scheduler=None, workers=None, progress: bool | None = None) -> pd.DataFrame:
    """Run case ``name`` once per combination of ``sets`` (parameter → values) and return one table:
    a row per run and check (module docstring)."""
    jobs = [(name, over) for over in parameter_grid(sets)]
    rows = run_sweep(run_case_checks, jobs, scheduler=scheduler, workers=workers, progress=progress)
    return pd.DataFrame([r for run in rows for r in run])


__all__ = ["run_sweep", "parameter_grid", "timed_case_run", "run_case_checks", "case_sweep"]
