"""The safe critical time step of 3D sphere packings (issue 17 item 3 in 3D): safe against the measured
limit of a dense face-centred cubic Hertz packing (tests/critical_dt3d.py bisects on Δt, never reading the
estimate), refused above it by build with the usual message.

Measured (2026-11-24): frictional elastic packing limit 1.62 × the estimate (0.49 × the Rayleigh step at
1 % overlap), with restitution 0.5 dashpots 2.38 ×, frictionless 1.93 × — safe, within a factor 2.4.
"""
import math
import warnings

import pytest

import critical_dt3d as cd
import demflow as df
from demflow import (LinearLaw, Material, Outputs3D, Scene3D, SceneError, Spheres,
                     build)


def _estimate(**kw):
    return build(cd.fcc(dt=1e-12, allow_supercritical=True, **kw)).dt_safe


@pytest.mark.parametrize("kw", [dict(), dict(restitution=0.5)], ids=["elastic", "damped"])
def test_fcc_hertz_packing_estimate_is_safe(kw):
    est = _estimate(**kw)
    assert cd.is_unstable(3.0 * est, **kw) or cd.is_unstable(4.0 * est, **kw)  # the limit is within reach
    measured = cd.measured_critical_dt(est, 4.0 * est, rel=2e-2, **kw)  # asserts est itself is stable
    assert est <= measured, (est, measured)
    if not kw:  # the stability matrix's 3D cells take the elastic packing's limit as FCC_CRITICAL × the estimate
        from demflow.cases.stability_matrix import FCC_CRITICAL
        assert measured / est == pytest.approx(FCC_CRITICAL, rel=2e-2), measured / est


def test_larger_overlap_means_stiffer_hertz_contacts_and_a_smaller_step():
    """k ∝ √δ: 16 × the overlap makes every spring 4 × stiffer and the elastic packing's step 2 × smaller."""
    a, b = _estimate(overlap=0.01), _estimate(overlap=0.16)
    assert b < a and a / b == pytest.approx(2.0, rel=0.05)


def _column(n=5, **kw):
    return Scene3D(name="column", spheres=Spheres(x=[0.0] * n, y=[0.0] * n, z=[float(k) for k in range(n)],
                                                  radius=[0.5] * n, material="ball"),
                   materials={"ball": Material(density=1.0)}, laws={("ball", "ball"): LinearLaw(kn=1e4)},
                   outputs=Outputs3D(every=0), **kw)


def test_build_refuses_above_the_estimate_with_the_fix():
    sim = build(_column())
    dt = 1.5 * sim.dt_safe
    assert dt < sim.dt_crit  # between the estimates: only the safe one refuses
    cd.assert_refused_above_the_estimate(_column, dt)


def test_max_contacts_bounds_the_neighbours():
    """A column declared to touch at most two gets a larger safe step than a packing of the same spheres."""
    assert build(_column(max_contacts=2)).dt_safe > build(_column()).dt_safe


@pytest.mark.parametrize("bad", [0.0, -0.1, 0.6, math.nan, True])
def test_max_overlap_is_validated(bad):
    with pytest.raises(SceneError, match="scene.max_overlap"):
        build(_column(max_overlap=bad))


def test_max_contacts_is_validated():
    with pytest.raises(SceneError, match="scene.max_contacts"):
        build(_column(max_contacts=0))


def _declared(max_overlap, **kw):
    sc = cd.fcc(**kw)
    sc.max_overlap = max_overlap
    return sc


def test_contacts_deeper_than_the_declared_overlap_warn_when_dt_is_above_the_estimate_there():
    """The face-centred cubic packing pre-compressed to 1 % of the radius between the spheres and to
    1 % × (3 (h/d)/√2)^(2/3) = 1.442 % at the planes, declared to reach only 0.4 %, stepped at the safe step
    for 0.4 %: at 1.442 % the Hertzian springs are (1.442/0.4)^½ = 1.9× stiffer, the safe step
    (0.4/1.442)^¼ = 0.73× as long, so the run warns, naming the depth and the field to declare; declared at
    1.5 % and stepped at its own estimate, the same packing runs silently."""
    plane = 0.01 * (3.0 * math.sqrt(2.0 / 3.0) / math.sqrt(2.0)) ** (2.0 / 3.0)
    sc = _declared(0.004, n_steps=50)
    sc.dt = df.build(_declared(0.004, dt=1e-12, allow_supercritical=True)).dt_safe
    sim = df.build(sc)
    with pytest.warns(df.UnsafeTimeStepWarning, match=r"deeper than scene.max_overlap=0.004.*max_overlap >= 0.01442"):
        sim.run()
    assert sim.deepest_overlap == pytest.approx(plane, rel=1e-3)
    ok = _declared(0.015, n_steps=50)
    ok.dt = df.build(_declared(0.015, dt=1e-12, allow_supercritical=True)).dt_safe
    short = _declared(0.004, n_steps=50)  # deeper than declared, but dt below the safe step at that depth
    short.dt = 0.7 * sc.dt
    with warnings.catch_warnings():
        warnings.simplefilter("error", df.UnsafeTimeStepWarning)
        df.build(ok).run()
        df.build(short).run()
