"""A 3D packing whose true critical time step is measured, not estimated (issue 17 item 3, 3D).

The packing is :func:`demflow.cases.stability_matrix.fcc` (the 3D cells of the stability matrix).
Face-centred cubic: hexagonal (111) layers stacked ABC between two planes, periodic along x and y,
every contact pre-compressed to the same overlap δ = ``overlap`` × R (the planes to the overlap whose
Hertz force equals the vertical pull of the three contacts a boundary layer lacks), so every sphere is
in equilibrium by symmetry.  Tiny random velocities and spins excite every mode; :func:`is_unstable`
says whether the kinetic energy grew, :func:`measured_critical_dt` bisects on Δt.  Nothing here reads
demflow's estimate.
"""
from __future__ import annotations

import warnings

import numpy as np

from critical_dt import GROWTH, bisect_stable, grows  # noqa: F401
from demflow import build
from demflow.cases.stability_matrix import FCC_E as E, FCC_NU as NU, FCC_PERTURBATION as PERTURBATION  # noqa: F401
from demflow.cases.stability_matrix import FCC_R as R, FCC_RHO as RHO, fcc  # noqa: F401


def kinetic(sim) -> float:
    s = sim.spheres
    return float(0.5 * np.sum(s.mass * np.sum(s.vel ** 2, 1)) + 0.5 * np.sum(0.4 * s.mass * s.r ** 2
                                                                           * np.sum(s.angvel ** 2, 1)))


def is_unstable(dt: float, n_steps: int = 3000, **kw) -> bool:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = build(fcc(dt=dt, allow_supercritical=True, **kw))
    return grows(sim, kinetic, n_steps)


def measured_critical_dt(lo: float, hi: float, rel: float = 5e-3, **kw) -> float:
    return bisect_stable(lambda dt: is_unstable(dt, **kw), lo, hi, rel)


def assert_refused_above_the_estimate(make, dt: float, words=()) -> None:
    """``build(make(dt=dt))`` refuses with the usual message (the field, the estimate, the fix, and ``words``);
    with allow_unsafe_dt it warns, with allow_supercritical it is silent."""
    import pytest

    from demflow import SceneError, UnsafeTimeStepWarning

    with pytest.raises(SceneError) as e:
        build(make(dt=dt))
    for w in ("scene.dt=", "safe critical time step", "give dt <=", "allow_unsafe_dt", "max_overlap", *words):
        assert w in str(e.value), str(e.value)
    with pytest.warns(UnsafeTimeStepWarning, match="allow_unsafe_dt=True"):
        build(make(dt=dt, allow_unsafe_dt=True))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        build(make(dt=dt, allow_supercritical=True))
