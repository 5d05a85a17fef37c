"""The safe critical time step of ellipsoid packings (issue 17 item 3 for ellipsoids): build computes it
(:func:`demflow.ellipsoids3d._safe_step_ellipsoids`), refuses a step above it with the usual message, and it
lies below the measured limit of a pre-compressed ellipsoid lattice (bisected on Δt here, never reading the
estimate), and next to the sphere estimate when the axes are equal.

The lattice: one layer of aligned ellipsoids (semi-axes a > b > c along x, y, z) between a floor and a lid,
periodic along x and y, every contact (tip to tip along x and y, and the c tips on the planes) pre-compressed
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
from demflow import Box, Ellipsoids, HertzMindlinLaw, Material, Outputs3D, Plane, Scene3D, Spheres, build

AXES = (0.03, 0.02, 0.012)
E, NU, RHO = 7e10, 0.2, 2650.0
PERTURBATION = 1e-6  # [length/time]: displacements far below the pre-compression


def lattice(dt=None, nx=4, ny=4, overlap=0.01, friction=0.5, restitution=1.0, seed=3, **kw) -> Scene3D:
    a, b, c = AXES
    d = overlap * c
    lx, ly = nx * (2 * a - d), ny * (2 * b - d)
    g = np.array([((i + 0.5) * lx / nx, (j + 0.5) * ly / ny, 0.0) for j in range(ny) for i in range(nx)])
    n = len(g)
    rng = np.random.default_rng(seed)
    kw.setdefault("max_overlap", overlap)
    return Scene3D(
        name="ellipsoid-lattice", spheres=None,
        ellipsoids=Ellipsoids(axes=[AXES] * n, x=g[:, 0], y=g[:, 1], z=g[:, 2], material="rock",
                              velocity=PERTURBATION * rng.normal(size=(n, 3)),
                              angular_velocity=PERTURBATION / c * rng.normal(size=(n, 3))),
        materials={"rock": Material(density=RHO, young=E, poisson=NU)},
        laws={("rock", "rock"): HertzMindlinLaw(friction=friction, restitution=restitution)},
        planes=[Plane("floor", (0.0, 0.0, -(c - d)), (0.0, 0.0, 1.0), "rock"),
                Plane("lid", (0.0, 0.0, c - d), (0.0, 0.0, -1.0), "rock")],
        box=Box(periodic_x=(0.0, lx), periodic_y=(0.0, ly)), dt=dt, outputs=Outputs3D(every=0), **kw)


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
