"""The safe critical time step of ellipsoid packings (issue 17 item 3 for ellipsoids): build computes it
(:func:`demflow.ellipsoids3d._safe_step_ellipsoids`), refuses a step above it with the usual message, and it
lies below the measured limit of a pre-compressed ellipsoid lattice (bisected on Δt here, never reading the
estimate), and next to the sphere estimate when the axes are equal.

The lattice (demflow.cases.stability_matrix.ellipsoid_lattice, also the stability matrix's ellipsoid row): one
layer of aligned ellipsoids (semi-axes a > b > c along x, y, z) between a floor and a lid, periodic along x and y, every contact (tip to tip along x and y, and the c tips on the planes) pre-compressed
to the overlap ``overlap`` × c, so every body is in equilibrium by symmetry; tiny random velocities and spins
excite every mode.  The stiffest contacts of an ellipsoid are on its flattest face (the c tips), which here
meet the planes.

Measured (2026-11-25): limit 3.81 × the estimate elastic, 9.0 × with restitution 0.5 dashpots, 2.25 × with
the lattice's 6 contacts declared (max_contacts=6; the estimate otherwise counts the kissing bound, 47 here).
"""
import warnings

import numpy as np
import pytest

from critical_dt import bisect_stable, grows
from critical_dt3d import assert_refused_above_the_estimate
from demflow import Ellipsoids, HertzMindlinLaw, Material, Outputs3D, Plane, Scene3D, Spheres, build
from demflow.cases.stability_matrix import ELL_CRITICAL, FCC_E as E, FCC_NU as NU, FCC_RHO as RHO
from demflow.cases.stability_matrix import ellipsoid_lattice as lattice


def kinetic(sim) -> float:
    b = sim.bodies
    return float(0.5 * np.sum(b.mass * np.sum(b.vel ** 2, 1)) + 0.5 * np.sum(np.sum(b.angvel * b.L, 1)))


def unstable(dt, **kw) -> bool:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = build(lattice(dt=dt, allow_supercritical=True, **kw))
    return grows(sim, kinetic, 3000)


def estimate(**kw) -> float:
    return build(lattice(dt=1e-12, allow_supercritical=True, **kw)).dt_safe


def test_the_lattice_is_in_equilibrium():
    """Pre-compressed and at rest, the lattice stays at rest: every contact force is balanced."""
    sc = lattice(dt=0.5 * estimate())
    sc.ellipsoids.velocity = None
    sc.ellipsoids.angular_velocity = None
    sim = build(sc)
    sim.run(200)
    assert np.abs(sim.bodies.vel).max() < 1e-9 and np.abs(sim.bodies.angvel).max() < 1e-6


@pytest.mark.parametrize("kw", [dict(), dict(restitution=0.5), dict(max_contacts=6)],
                         ids=["elastic", "damped", "elastic-6-contacts-declared"])
def test_estimate_is_below_the_measured_limit(kw):
    est = estimate(**kw)
    hi = est
    while not unstable(hi, **kw):  # the limit, found without the estimate's help beyond a start
        hi *= 2.0
        assert hi < 64 * est, "no instability within 64 × the estimate: the lattice does not probe the limit"
    measured = bisect_stable(lambda dt: unstable(dt, **kw), hi / 2.0 if hi > est else est / 2.0, hi, 2e-2)
    assert est <= measured, (est, measured)
    if not kw:  # the stability matrix's ellipsoid cells take the limit as ELL_CRITICAL × the estimate
        assert measured / est == pytest.approx(ELL_CRITICAL, rel=2e-2), measured / est
    print(f"ellipsoid lattice {kw}: estimate {est:.4g}, measured limit {measured:.4g} = {measured / est:.2f} ×")


def test_equal_axes_give_about_the_sphere_estimate():
    """a = b = c: the ellipsoid estimate counts the rotation under the normal force too (a sphere's normal
    force passes through its centre), so it lies a little below the sphere estimate, never above."""
    r, pos = 0.01, np.array([[0.0, 0.0, 0.011], [0.03, 0.0, 0.011]])
    mat = {"rock": Material(density=RHO, young=E, poisson=NU)}
    law = {("rock", "rock"): HertzMindlinLaw(friction=0.5)}
    floor = [Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "rock")]
    s = build(Scene3D(name="s", spheres=Spheres(x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], radius=[r, r], material="rock"),
                      materials=mat, laws=law, planes=floor, dt=1e-12, outputs=Outputs3D(every=0))).dt_safe
    e = build(Scene3D(name="e", spheres=None, ellipsoids=Ellipsoids(axes=[(r, r, r)] * 2, x=pos[:, 0], y=pos[:, 1], z=pos[:, 2],
                                                     material="rock"),
                      materials=mat, laws=law, planes=floor, dt=1e-12, outputs=Outputs3D(every=0))).dt_safe
    assert 0.8 * s <= e <= s, (e, s)


def test_build_refuses_above_the_estimate_with_the_fix():
    assert_refused_above_the_estimate(lattice, 1.5 * estimate(), ("ellipsoids",))


def test_flatter_ellipsoids_and_deeper_overlaps_need_smaller_steps():
    """k ∝ √(R δ): 16 × the declared overlap halves the step; and max_contacts bounds the count."""
    a, b = estimate(overlap=0.01), estimate(overlap=0.16)
    assert a / b == pytest.approx(2.0, rel=0.05)
    assert estimate(max_contacts=6) > estimate()


def test_above_the_measured_limit_a_run_is_stopped_not_silent():
    """The stability matrix's rule for ellipsoids: stepped at 1.05 × and 1.2 × the lattice's measured limit
    (build told to accept it), the run is stopped by BlowUpError (the energy balance: the overlaps stay
    small); at 0.9 × it runs 3000 steps without error."""
    from demflow import BlowUpError

    measured = bisect_stable(unstable, estimate(), 16.0 * estimate(), 2e-2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        build(lattice(dt=0.9 * measured, allow_supercritical=True)).run(3000)
        for f in (1.05, 1.2):
            with pytest.raises(BlowUpError, match="energy balance"):
                build(lattice(dt=f * measured, allow_supercritical=True)).run(3000)


def test_deepest_overlap_is_a_fraction_of_the_smallest_semi_axis():
    """The lattice's contacts are pre-compressed to 1 % of c; the run reports that depth relative to c
    (the length max_overlap refers to for ellipsoids), not to the bounding radius a = 2.5 c."""
    sim = build(lattice(dt=0.5 * estimate()))
    sim.run(10)
    assert sim.deepest_overlap_now() == pytest.approx(0.01, rel=0.05)
