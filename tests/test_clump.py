"""Clump templates: the ellipsoid cover and the mass properties of overlapping sphere unions."""
from __future__ import annotations

import math

import numpy as np
import pytest

from demflow.shapes.clump import (MIYATA_AXES, ClumpTemplate, ellipsoid_cover, ellipsoid_moments,
                                  ellipsoid_surface_distance, ellipsoid_volume, union_mass_properties)


def test_distance_to_the_ellipsoid_surface_matches_dense_sampling():
    ax = np.array(MIYATA_AXES)
    u, v = np.meshgrid(np.linspace(0, np.pi, 801), np.linspace(0, 2 * np.pi, 1601), indexing="ij")
    surf = np.stack([ax[0] * np.sin(u) * np.cos(v), ax[1] * np.sin(u) * np.sin(v), ax[2] * np.cos(u)], -1).reshape(-1, 3)
    pts = np.array([[0.0, 0.0, 0.0], [0.2, 0.05, -0.03], [-0.3, 0.0, 0.1], [0.0, 0.2, 0.0]])
    d = ellipsoid_surface_distance(pts, ax)
    brute = np.array([np.min(np.linalg.norm(surf - p, axis=1)) for p in pts])
    assert d[0] == pytest.approx(ax[2], rel=1e-12)
    np.testing.assert_allclose(d, brute, rtol=0, atol=2e-4)  # the sampled surface is 1e-3 rad apart
    assert np.all(d <= brute + 1e-12)


def test_union_mass_converges_and_counts_an_overlap_once():
    r, d, rho = 0.1, 0.12, 2000.0
    v1 = 4 / 3 * math.pi * r ** 3
    lens = math.pi * (4 * r + d) * (2 * r - d) ** 2 / 12  # two equal spheres, centres d apart
    exact = rho * (2 * v1 - lens)
    errs = []
    for f in (10, 20, 40):
        p = union_mass_properties([[0, 0, 0], [d, 0, 0]], [r, r], rho, h=r / f)
        errs.append(abs(p["mass"] / exact - 1))
    assert errs[2] < errs[0] and errs[2] < 1e-3
    assert p["com"] == pytest.approx([d / 2, 0, 0], abs=1e-12 + 1e-4 * r)
    one = union_mass_properties([[0.3, -0.2, 0.1]], [r], rho, h=r / 40)
    m1 = rho * v1
    assert one["mass"] == pytest.approx(m1, rel=1e-3)
    np.testing.assert_allclose(one["inertia"], 0.4 * m1 * r * r * np.eye(3), rtol=0, atol=3e-3 * 0.4 * m1 * r * r)


def test_ellipsoid_cover_stays_inside_and_converges_with_K():
    ax = np.array(MIYATA_AXES)
    fracs, moments = [], []
    for K in (4, 16, 64):
        c, r = ellipsoid_cover(ax, K)
        assert np.all(ellipsoid_surface_distance(c, ax) >= r - 1e-12)  # inscribed: never outside
        T = ClumpTemplate.from_spheres(c, r, mass=191.0)
        fracs.append(union_mass_properties(c, r, 1.0)["volume"] / ellipsoid_volume(ax))
        moments.append(T.moments / ellipsoid_moments(ax, 191.0))
    assert fracs[0] < fracs[1] < fracs[2] < 1.0
    assert fracs[2] > 0.9
    assert np.all(np.diff(np.abs(1 - np.array(moments)), axis=0) < 0)  # every moment closer with K
    assert np.all(np.abs(1 - moments[2]) < 0.06)


def test_template_is_in_its_principal_frame_with_the_given_mass():
    T = ClumpTemplate.ellipsoid_like(8)
    assert T.mass == pytest.approx(191.0, rel=1e-12)
    p = union_mass_properties(T.centres, T.radii, 1.0)
    assert np.linalg.norm(p["com"]) < 1e-12 + 1e-3 * T.radii.min()
    I = p["inertia"] * (191.0 / p["volume"])
    off = I - np.diag(np.diag(I))
    assert np.abs(off).max() < 1e-3 * np.abs(I).max()
    assert np.all(np.diff(T.moments) >= 0)  # ascending: the long axis has the smallest moment
    with pytest.raises(ValueError, match="K=0"):
        ellipsoid_cover(MIYATA_AXES, 0)


# ---------------------------------------------------------------------------- clump dynamics
import demflow as df  # noqa: E402
from demflow.build3d import quat_to_matrix  # noqa: E402

ROCK = df.Material(density=2650.0, young=7e8, poisson=0.2)


def _drop_scene(kind: str, name: str):
    """A ball dropped spinning on a frictional floor: a sphere, or a one-sphere clump of the same
    mass and inertia (2/5 m r², as build computes it)."""
    r = 0.05
    m = 2650.0 * 4.0 / 3.0 * math.pi * r ** 3
    floor = df.Plane("floor", (0, 0, 0), (0, 0, 1), "rock")
    law = df.HertzMindlinLaw(friction=0.4, restitution=0.5)
    common = dict(name=name, materials={"rock": ROCK}, laws={("rock", "rock"): law}, planes=[floor],
                  gravity=(0.0, 0.0, -9.81), local_damping=0.1, outputs=df.Outputs3D(every=50, orientation=True))
    if kind == "sphere":
        return df.Scene3D(spheres=df.Spheres(x=[0.0], y=[0.0], z=[0.06], radius=[r], material="rock",
                                             velocity=[[0.3, 0.0, -0.5]], angular_velocity=[[0.0, 4.0, 1.0]]),
                          **common)
    T = ClumpTemplate(centres=np.zeros((1, 3)), radii=np.array([r]), mass=m, moments=np.full(3, 0.4 * m * r ** 2))
    return df.Scene3D(spheres=None, clumps=df.Clumps(T, x=[0.0], y=[0.0], z=[0.06], material="rock",
                                                     velocity=[[0.3, 0.0, -0.5]], angular_velocity=[[0.0, 4.0, 1.0]]),
                      **common)


def test_a_one_sphere_clump_equals_a_sphere_to_the_bit():
    a = df.build(_drop_scene("sphere", "ball-sphere")).run(4000)
    b = df.build(_drop_scene("clump", "ball-clump")).run(4000)
    assert a.tables()["records"].fn_max.max() > 0  # it hit the floor
    for k in ("pos", "vel", "angvel"):
        np.testing.assert_array_equal(b.spheres.__getattribute__(k), a.spheres.__getattribute__(k))
    np.testing.assert_array_equal(b.pairs.hist, a.pairs.hist)


def _top(dt_scale=1.0, steps=20000):
    """A torque-free asymmetric clump (three unequal members in a row and one off the line) spinning."""
    T = ClumpTemplate.from_spheres([[0.0, 0.0, 0.0], [0.08, 0.0, 0.0], [-0.05, 0.03, 0.0], [0.0, 0.0, 0.04]],
                                   [0.05, 0.04, 0.03, 0.03], density=2650.0, h=0.002)
    sc = df.Scene3D(name="top", spheres=None, materials={"rock": ROCK}, laws={("rock", "rock"): df.HertzMindlinLaw()},
                    clumps=df.Clumps(T, x=[0.0], y=[0.0], z=[0.0], material="rock", angular_velocity=[[3.0, 0.2, 5.0]]),
                    dt=2e-4 * dt_scale, outputs=df.Outputs3D(every=10))
    return T, sc


def test_torque_free_asymmetric_top_follows_euler_and_conserves_L_and_energy():
    from scipy.integrate import solve_ivp

    T, sc = _top()
    sim = df.build(sc)
    I = T.moments
    assert len(set(np.round(I / I.max(), 6))) == 3  # asymmetric
    R0 = quat_to_matrix(sim.bodies.quat)[0]
    L0 = sim.bodies.L[0].copy()
    e0 = 0.5 * np.sum((R0.T @ L0) ** 2 / I)
    n = 20000
    sim.run(n)
    R = quat_to_matrix(sim.bodies.quat)[0]
    Lw = sim.bodies.L[0]
    # conserved: the world angular momentum exactly (no torque), the energy to O(Δt²)
    np.testing.assert_allclose(Lw, L0, rtol=1e-13, atol=1e-15)
    wb = R.T @ Lw / I
    assert 0.5 * np.sum(wb * wb * I) == pytest.approx(e0, rel=1e-4)
    # Euler's equations I ω̇ = (I ω) × ω in the body frame, from ω_b(0), to t = (n - 1/2)Δt (half step)
    wb0 = R0.T @ L0 / I

    def euler(_t, w):
        return np.cross(I * w, w) / I
    t_end = (n - 0.5) * sc.dt
    ref = solve_ivp(euler, (0.0, t_end), wb0, rtol=1e-12, atol=1e-14, method="DOP853").y[:, -1]
    R_half = quat_to_matrix(sim.bodies.quat)[0]
    wb_half = R_half.T @ sim.bodies.angvel[0]
    # convergence study (this test's scene): relative error 2.0e-6 at Δt = 2e-4 s and 5.0e-7 at Δt/2 (order 2.0);
    # 1e-5 keeps a 5x margin; the order check below fails a first-order scheme
    assert np.linalg.norm(wb_half - ref) / np.linalg.norm(ref) < 1e-5
    # the error falls with Δt (second order): half the step, a quarter of the error or less (+ margin)
    T2, sc2 = _top(dt_scale=0.5)
    sim2 = df.build(sc2).run(2 * n)
    wb2 = quat_to_matrix(sim2.bodies.quat)[0].T @ sim2.bodies.angvel[0]
    ref2 = solve_ivp(euler, (0.0, (2 * n - 0.5) * sc2.dt), wb0, rtol=1e-12, atol=1e-14, method="DOP853").y[:, -1]
    e1 = np.linalg.norm(wb_half - ref)
    e2 = np.linalg.norm(wb2 - ref2)
    assert e2 < 0.35 * e1


def test_a_clump_comes_to_rest_on_a_plane_and_members_never_touch_each_other():
    T = ClumpTemplate.ellipsoid_like(8, axes=(0.1, 0.07, 0.049), mass=5.0)
    sc = df.Scene3D(name="rest", spheres=None, materials={"rock": ROCK},
                    laws={("rock", "rock"): df.HertzMindlinLaw(friction=0.5, restitution=0.3)},
                    planes=[df.Plane("floor", (0, 0, 0), (0, 0, 1), "rock")],
                    clumps=df.Clumps(T, x=[0.0], y=[0.0], z=[0.12], material="rock",
                                     orientation=[[math.cos(0.3), math.sin(0.3), 0.0, 0.0]],
                                     angular_velocity=[[1.0, 2.0, 0.0]]),
                    gravity=(0.0, 0.0, -9.81), local_damping=0.2, outputs=df.Outputs3D(every=100))
    sim = df.build(sc).run(60000)
    rec = sim.tables()["records"]
    assert not np.any((sim.pairs.j < sim.n) & (sim.spheres.body[sim.pairs.i] == sim.spheres.body[np.minimum(sim.pairs.j, sim.n - 1)]))
    assert rec.kinetic_translation.iloc[-1] + rec.kinetic_rotation.iloc[-1] < 1e-9 * 5.0 * 9.81 * 0.1
    assert sim.planes.force[0, 2] == pytest.approx(-5.0 * 9.81, rel=1e-4)  # the floor carries the weight


def test_principal_axes_by_jacobi_match_lapack():
    """symmetric_eigen3 (the clump's principal frame without BLAS) against numpy's eigh on random symmetric
    matrices, and exact on diagonal and isotropic ones (a one-sphere clump)."""
    from demflow.shapes.clump import symmetric_eigen3
    from demflow.tolerances import tol

    t = tol("clump.principal-axes").value
    rng = np.random.default_rng(11)
    for _ in range(300):
        B = rng.normal(size=(3, 3)) * rng.uniform(1e-3, 1e3)
        A = B + B.T
        w, v = symmetric_eigen3(A)
        w_ref = np.linalg.eigh(A)[0]
        scale = np.max(np.abs(w_ref))
        assert np.max(np.abs(w - w_ref)) <= t * scale
        assert np.max(np.abs(A @ v - v * w)) <= t * scale
        assert np.max(np.abs(v.T @ v - np.eye(3))) <= t
    w, v = symmetric_eigen3(np.diag([3.0, 1.0, 2.0]))
    assert w.tolist() == [1.0, 2.0, 3.0] and np.array_equal(np.abs(v), np.eye(3)[:, [1, 2, 0]])
    w, v = symmetric_eigen3(2.0 * np.eye(3))
    assert w.tolist() == [2.0, 2.0, 2.0] and np.array_equal(v, np.eye(3))


def test_clump_templates_do_not_depend_on_the_blas_kernels():
    """A clump's principal frame enters every clump run: the same bits under OpenBLAS's Haswell and SkylakeX
    kernels (with LAPACK's eigh and a matrix product the K = 8 template differed in the last bits)."""
    from blas_kernels import assert_same_output_under_both_kernel_sets

    assert_same_output_under_both_kernel_sets(
        "import hashlib, numpy as np; from demflow.shapes.clump import ClumpTemplate; h = hashlib.sha256()\n"
        "for K in (1, 3, 8, 12, 24):\n"
        "    T = ClumpTemplate.ellipsoid_like(K)\n"
        "    h.update(T.centres.tobytes() + T.moments.tobytes() + np.float64(T.mass).tobytes())\n"
        "print(h.hexdigest())")


@pytest.mark.parametrize("centres,radii,kw,words", [
    ([[0, 0, 0], [0.01, 0, 0]], [0.0, 0.01], dict(density=2800.0), r"radii\[0\]=0.0 must be > 0"),
    ([[0, 0, 0], [0.01, 0, 0]], [-0.01, 0.01], dict(density=2800.0), r"radii\[0\]=-0.01 must be > 0"),
    ([[0, 0, math.nan], [0.01, 0, 0]], [0.01, 0.01], dict(density=2800.0), r"centres\[0\]=.* is not finite"),
    ([[0, 0, 0]], [0.01], dict(mass=-1.0), "mass=-1.0 must be a finite number > 0"),
    (np.zeros((0, 3)), [], dict(mass=1.0), "give K >= 1 centres"),
    ([[0, 0, 0], [0.01, 0, 0]], [0.01], dict(mass=1.0), "give K >= 1 centres"),
])
def test_a_template_of_bad_members_is_refused(centres, radii, kw, words):
    """Radius 0 or -0.01 or a NaN centre gave a NaN template (only NumPy warnings), mass -1 negative moments, no
    member a bare NumPy reduction error."""
    with pytest.raises(ValueError, match=words):
        ClumpTemplate.from_spheres(centres, radii, **kw)


@pytest.mark.parametrize("change,words", [
    (dict(radii=np.array([0.0])), r"scene.clumps.template.radii\[0\]=0.0 must be > 0"),
    (dict(centres=np.array([[math.nan, 0.0, 0.0]])), r"scene.clumps.template.centres\[0\]=.* is not finite"),
    (dict(mass=0.0), "scene.clumps.template.mass=0.0 must be a finite number > 0"),
    (dict(moments=np.array([-1.0, 1.0, 1.0])), "scene.clumps.template.moments=.* must be three finite"),
    (dict(centres=np.zeros((2, 3))), "scene.clumps.template: 2 centres"),
])
def test_build_refuses_a_bad_template_by_its_path(change, words):
    """A template made by hand (not through from_spheres) is checked by build: a zero radius raised 'cannot convert
    float NaN to integer' in the neighbour search, a negative one a time-step message, negative moments built."""
    import dataclasses

    import demflow as df

    T = dataclasses.replace(ClumpTemplate.from_spheres([[0.0, 0.0, 0.0]], [0.01], density=2800.0), **change)
    scene = df.Scene3D(name="bad-template", spheres=None, clumps=df.Clumps(T, x=[0.0], y=[0.0], z=[0.1], material="g"),
                       materials={"g": df.Material(density=2800.0, young=7e9, poisson=0.2)},
                       laws={("g", "g"): df.HertzMindlinLaw(friction=0.3)},
                       planes=[df.Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "g")])
    with pytest.raises(df.SceneError, match=words):
        df.build(scene)
