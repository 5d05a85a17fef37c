"""3D spheres and the Hertz-Mindlin law: pure functions against closed forms, the neighbour list
against brute force, invariances, energy, determinism, checkpoints and clear errors."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

import demflow as df
from demflow.contacts.spheres import sphere_pairs, sphere_pairs_brute_force
from demflow.laws.hertz_mindlin import (effective_modulus, effective_shear_modulus, hertz_force, hertz_impact,
                                        hertz_stiffness, md_step)
from demflow.laws.restitution import hertz_restitution, zeta_exact, zeta_linear, zeta_yade
from demflow.state3d import Box3
from demflow.tolerances import tol

GLASS = df.Material(density=2800.0, young=4.8e10, poisson=0.2)


# ---------------------------------------------------------------------------- pure functions
def test_effective_moduli_identical_materials():
    E, nu = 7e10, 0.3
    G = E / (2 * (1 + nu))
    assert effective_modulus(E, nu, E, nu) == pytest.approx(E / (2 * (1 - nu * nu)), rel=1e-15)
    assert effective_shear_modulus(E, nu, E, nu) == pytest.approx(G / (2 * (2 - nu)), rel=1e-15)
    # a rigid partner: E* = E/(1-ν²)
    assert effective_modulus(E, nu, math.inf, 0.25) == pytest.approx(E / (1 - nu * nu), rel=1e-15)


def test_hertz_stiffness_is_the_derivative_and_energy_the_integral():
    E, R = 3e10, 0.004
    for d in (1e-7, 1e-5, 1e-4):
        h = d * 1e-6
        num = (hertz_force(E, R, d + h) - hertz_force(E, R, d - h)) / (2 * h)
        assert hertz_stiffness(E, R, d) == pytest.approx(num, rel=1e-7)
        work = quad(lambda x: hertz_force(E, R, x), 0, d, epsabs=0, epsrel=1e-12)[0]
        assert 8 / 15 * E * math.sqrt(R) * d ** 2.5 == pytest.approx(work, rel=1e-10)


def _md_path(targets, k0, muN, n=20000):
    """Drive md_step by displacement along a line through force targets; return (u, T) samples."""
    T, Tr, direction, br = 0.0, 0.0, 0.0, False
    u = 0.0
    us, Ts = [0.0], [0.0]
    du0 = muN / k0 / n
    for target in targets:
        sign = 1.0 if target < T else -1.0  # force on the body opposes the displacement
        while (T - target) * sign > 0:
            T, Tr, direction, br = md_step(T, Tr, direction, br, k0, sign * du0, muN)
            u += sign * du0
            us.append(u)
            Ts.append(T)
    return np.array(us), np.array(Ts)


def test_mindlin_deresiewicz_loading_and_unloading_follow_ch3_3_24_and_3_25():
    """ch3 eq 3.24 (loading) and 3.25 (unloading from T_s), with 8Ga/(2-ν) written k0 = 8G*a:
    δ(T) = 3μN/(2k0) [1 - (1 - T/μN)^{2/3}], δ_u = 3μN/(2k0) [2(1 - (T_s - T)/2μN)^{2/3} - (1 - T_s/μN)^{2/3} - 1]."""
    k0, muN = 1e6, 100.0
    c = 1.5 * muN / k0
    Ts = 80.0
    # our sign convention: the force is -T for a positive displacement; load to -T_s, unload to +T_s
    u, T = _md_path([-Ts, Ts], k0, muN)
    load = np.nonzero(np.diff(u) > 0)[0]
    i = load[len(load) // 2]
    t = -T[i]
    assert u[i] == pytest.approx(c * (1 - (1 - t / muN) ** (2 / 3)), rel=2e-4)
    k_turn = np.argmax(u)
    uT = u[k_turn]
    assert uT == pytest.approx(c * (1 - (1 - Ts / muN) ** (2 / 3)), rel=2e-4)
    for frac in (0.25, 0.5, 0.75):
        j = k_turn + int(frac * (len(u) - k_turn))
        t = -T[j]  # on the unloading branch, from T_s down
        du = c * (2 * (1 - (Ts - t) / (2 * muN)) ** (2 / 3) - (1 - Ts / muN) ** (2 / 3) - 1)
        assert u[j] == pytest.approx(du, rel=1e-3, abs=1e-4 * c)


def test_restitution_conventions():
    # YADE 2023.02a printed phys.betan = 0.2330248576834424 for en = 0.5 (ENGINES probe, this machine)
    assert zeta_yade(0.5) == pytest.approx(0.2330248576834424, rel=1e-14)
    for e in (0.1, 0.5, 0.95):
        assert hertz_restitution(zeta_exact(e)) == pytest.approx(e, abs=1e-8)
    # negative control: the linear-spring relation is not exact for Hertz (misses by > 1 % at e = 0.3)
    assert abs(hertz_restitution(zeta_linear(0.3)) - 0.3) > 0.01
    with pytest.raises(ValueError, match="e=1.5"):
        zeta_exact(1.5)


def _solve_ivp_restitution(zeta, rtol):
    """The same impact by scipy's DOP853 (the reference the BLAS-free integrator replaced)."""
    from scipy.integrate import solve_ivp
    b = 2.0 * zeta * np.sqrt(1.5)

    def rhs(_t, y):
        xi = max(y[0], 0.0)
        return (y[1], -max(xi ** 1.5 + b * xi ** 0.25 * y[1], 0.0))

    def released(_t, y):
        xi = max(y[0], 0.0)
        return xi ** 1.5 + b * xi ** 0.25 * y[1] if y[1] < 0 else 1.0
    released.terminal = True
    released.direction = -1
    sol = solve_ivp(rhs, (0.0, 20.0), (0.0, 1.0), events=released, rtol=rtol, atol=1e-14, method="DOP853")
    return float(-sol.y_events[0][0][1])


@pytest.mark.parametrize("zeta", [0.0003, 0.015, 0.233, 1.13, 4.39])
def test_hertz_restitution_agrees_with_solve_ivp(zeta):
    t = tol("hertz.impact-integrator").value
    want = _solve_ivp_restitution(zeta, 1e-13)
    assert hertz_restitution(zeta) == pytest.approx(want, abs=t)
    # negative control: the same integrator at rtol 1e-6 misses by more than the tolerance (2e-9 to 3e-7)
    assert abs(hertz_restitution(zeta, rtol=1e-6) - want) > t


def test_zeta_does_not_depend_on_the_blas_kernels():
    """ζ enters every 3D run and the engine decks: its bits must be the same on every host.  Computed
    here under two OpenBLAS kernel sets (what an Intel AVX-512 host and an AMD host pick); before the
    integrator was made BLAS-free, ζ(0.5) was ...53708 with one and ...55498 with the other."""
    from blas_kernels import assert_same_output_under_both_kernel_sets

    assert_same_output_under_both_kernel_sets("from demflow.laws.restitution import zeta_exact as z; "
                                              "print([z(e).hex() for e in (0.1, 0.5, 0.9)])")


# ---------------------------------------------------------------------------- neighbour list
@pytest.mark.parametrize("px,py", [(False, False), (True, False), (True, True)])
def test_sphere_pairs_match_brute_force(px, py):
    rng = np.random.default_rng(3)
    n = 300
    L = 12.0
    pos = rng.uniform(0, L, (n, 3))
    r = rng.uniform(0.2, 0.6, n)
    box = Box3(periodic_x=px, periodic_y=py, x0=0.0, y0=0.0, lx=L if px else 0.0, ly=L if py else 0.0)
    pp = np.array([[0, 0, 0.0], [0, 0, L]])
    pn = np.array([[0, 0, 1.0], [0, 0, -1.0]])
    fast = sphere_pairs(pos, r, 0.1, box, pp, pn)
    slow = sphere_pairs_brute_force(pos, r, 0.1, box, pp, pn)
    for a, b in zip(fast, slow):
        np.testing.assert_array_equal(a, b)
        assert a.tobytes() == b.tobytes()  # to the bit: the shifts' signed zeros too
    # the one-pass search with too little room (a second pass) and with too much (trimmed): the same list
    for room in (0, 1, 10 * len(fast[0])):
        for a, b in zip(sphere_pairs(pos, r, 0.1, box, pp, pn, capacity=room), slow):
            assert a.tobytes() == b.tobytes()
    assert len(fast[0]) > 50 and (fast[1] >= n).any()  # sphere pairs and plane pairs were listed
    if px:
        assert fast[2][:, 0].any()  # and pairs across the periodic boundary


def test_sphere_pairs_of_a_sparse_periodic_bed_two_cells_deep_return():
    """A few spheres in a wide periodic box spread over two cells in z: more cells than ~8 per sphere, and the
    count of z cells, halved as nc // 2 + 1, stayed at 2 for ever (two clumps that collided in a 1 × 1 m periodic
    box hung the run, 2026-11-27).  Run in a subprocess so that a regression fails instead of hanging the suite."""
    import subprocess
    import sys

    code = ("import numpy as np\n"
            "from demflow.contacts.spheres import sphere_pairs, sphere_pairs_brute_force\n"
            "from demflow.state3d import Box3\n"
            "pos = np.array([[0.2, 0.3, 0.5], [0.7, 0.6, 0.65], [0.4, 0.8, 0.58]])\n"
            "r = np.full(3, 0.05)\n"
            "box = Box3(periodic_x=True, periodic_y=True, x0=0.0, y0=0.0, lx=1.0, ly=1.0)\n"
            "e = np.zeros((0, 3))\n"
            "fast = sphere_pairs(pos, r, 0.01, box, e, e)\n"
            "slow = sphere_pairs_brute_force(pos, r, 0.01, box, e, e)\n"
            "assert all(np.array_equal(a, b) for a, b in zip(fast, slow))\n"
            "print('listed', len(fast[0]))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0 and "listed 0" in out.stdout, out.stderr[-2000:]


# ---------------------------------------------------------------------------- dynamics
def _pair_scene(offset=(0.0, 0.0, 0.0), rotation=None, box=df.Box(), name="pair"):
    R = 0.01
    p = np.array([[-R * 1.001, 0.0, 0.0], [R * 1.001, 0.003, 0.0]])
    v = np.array([[10.0, 0.0, 1.0], [-10.0, 0.0, 0.0]])
    w = np.array([[0.0, 50.0, 0.0], [0.0, 0.0, 0.0]])
    if rotation is not None:
        p, v, w = p @ rotation.T, v @ rotation.T, w @ rotation.T
    p = p + np.asarray(offset)
    return df.Scene3D(name=name, spheres=df.Spheres(x=p[:, 0], y=p[:, 1], z=p[:, 2], radius=[R, R], material="glass",
                                                    velocity=v, angular_velocity=w),
                      materials={"glass": GLASS},
                      laws={("glass", "glass"): df.HertzMindlinLaw(friction=0.3, restitution=0.7)},
                      n_steps=120, box=box)


def test_oblique_pair_is_invariant_under_rotation_and_translation():
    a = df.build(_pair_scene()).run()
    q, _ = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))
    b = df.build(_pair_scene(offset=(5.0, -2.0, 1.0), rotation=q)).run()
    assert a.tables()["records"].fn_max.max() > 0 and a.spheres.angvel[1, 2] != 0  # they did collide, with friction
    va = a.spheres.vel @ q.T
    np.testing.assert_allclose(b.spheres.vel, va, rtol=0, atol=1e-9 * 10)
    np.testing.assert_allclose(b.spheres.angvel, a.spheres.angvel @ q.T, rtol=0, atol=1e-7 * 50)


def test_pair_across_the_periodic_boundary_equals_the_open_pair():
    a = df.build(_pair_scene()).run()
    # the same pair straddling x = 0 of a periodic box [0, 0.2)
    b = df.build(_pair_scene(offset=(0.0, 0.1, 0.0), box=df.Box(periodic_x=(0.0, 0.2), periodic_y=(0.0, 0.2)),
                             name="pair-periodic")).run()
    assert b.pairs.shift[:, 0].any()
    np.testing.assert_allclose(b.spheres.vel, a.spheres.vel, rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.unwrapped_positions() - [0.0, 0.1, 0.0], a.spheres.pos, rtol=0, atol=1e-13)


def test_head_on_impact_matches_hertz_theory():
    from demflow.cases.hertz_impacts import impact_scene, run_impact

    m = run_impact(impact_scene("glass", 0.010, 10.0, plane=False), 20.0)
    for q in ("contact_time", "overlap_max", "force_max"):
        assert m[q] == pytest.approx(m["reference"][q], rel=tol("hertz.impact").value)
    # negative control: a 10 % softer modulus is caught
    soft = effective_modulus(0.9 * 4.8e10, 0.2, 0.9 * 4.8e10, 0.2)
    r = hertz_impact(soft, 0.005, m["reference"]["overlap_max"] * 0 + 2800 * 4 / 3 * math.pi * 1e-6 / 2, 20.0)
    assert abs(m["force_max"] / r["force_max"] - 1) > tol("hertz.impact").value


def _stack(n=9, dt_fraction=0.02, damping=0.0, name="stack"):
    """ch3's stack: n balls d = 1 m, m = 1.5708 kg, centres z = 0..n-1, bottom fixed, linear springs."""
    kn = 36 * 1.5708 * 9.81 / 0.14
    return df.Scene3D(name=name, spheres=df.Spheres(x=[0.0] * n, y=[0.0] * n, z=list(range(n)), radius=[0.5] * n,
                                                    material="ball", mass=[1.5708] * n, fixed=[True] + [False] * (n - 1)),
                      materials={"ball": df.Material(density=1.0)}, laws={("ball", "ball"): df.LinearLaw(kn=kn)},
                      gravity=(0.0, 0.0, -9.81), dt_fraction=dt_fraction, n_steps=4000,
                      local_damping=damping, outputs=df.Outputs3D(every=10, track_spheres=(n - 1,)))


def test_elastic_stack_conserves_energy():
    sim = df.build(_stack()).run()
    rec = sim.tables()["records"]
    total = rec.kinetic_translation + rec.kinetic_rotation + rec.elastic + rec.potential
    assert total.iloc[0] == pytest.approx(554.74, rel=1e-5)  # ch3 §3.5.4.1
    drift = float(np.max(np.abs(total - total.iloc[0])) / total.iloc[0])
    assert drift < 1e-4
    assert rec.elastic.max() > 10.0  # the stack did compress


def test_same_scene_same_bits_and_checkpoint_resume(tmp_path):
    a = df.build(_stack(n=5, name="stack-ck"))
    a.run(700)
    b = df.build(_stack(n=5, name="stack-ck"))
    b.run(300)
    b.save_checkpoint(tmp_path / "ck.npz")
    c = df.build(_stack(n=5, name="stack-ck")).load_checkpoint(tmp_path / "ck.npz")
    c.run(400)
    np.testing.assert_array_equal(a.spheres.pos, c.spheres.pos)
    np.testing.assert_array_equal(a.spheres.vel, c.spheres.vel)
    np.testing.assert_array_equal(a.pairs.hist, c.pairs.hist)


def test_blow_up_is_reported_with_the_last_good_state(tmp_path, monkeypatch):
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))
    sc = _stack(n=5, name="stack-blowup")
    sim0 = df.build(sc)
    sc.dt = 30 * sim0.dt_crit
    sc.allow_supercritical = True
    sim = df.build(sc)
    with pytest.raises(df.BlowUpError) as err:
        sim.run(4000)
    df.build(sc).load_checkpoint(err.value.path)


def test_supercritical_dt_is_refused():
    sc = _stack(n=3, name="stack-dt")
    sc.dt = 1.0
    with pytest.raises(df.SceneError, match="exceeds the critical estimate"):
        df.build(sc)


@pytest.mark.parametrize("change,field", [
    (lambda s: s.materials.update(glass=df.Material(density=2800.0, young=4.8e10, poisson=0.7)), "poisson"),
    (lambda s: s.materials.update(glass=df.Material(density=2800.0)), "elastic constants"),
    (lambda s: setattr(s, "local_damping", 1.5), "scene.local_damping"),
    (lambda s: setattr(s, "gravity", (0.0, float("nan"), 0.0)), "scene.gravity"),
    (lambda s: s.laws.update({("glass", "glass"): df.HertzMindlinLaw(restitution=0.0)}), "restitution"),
    (lambda s: s.laws.update({("glass", "glass"): df.HertzMindlinLaw(damping="lammps")}), "damping"),
])
def test_bad_3d_input_is_refused_clearly(change, field):
    sc = _pair_scene()
    change(sc)
    with pytest.raises(df.SceneError, match=field):
        df.build(sc)


# ---------------------------------------------------------------------------- triangle meshes
def _drop(wall: str, at=(0.0, 0.0), angle_deg=0.0, name="drop"):
    """An aluminium-oxide sphere hitting a rigid flat wall at z = 0: a plane, or the square
    [-1, 1]² as two triangles ('square', shared diagonal) or four around the centre ('fan')."""
    import math as _m

    from demflow.cases.hertz_impacts import impact_scene

    R = 0.0025
    a = _m.radians(angle_deg)
    sc = impact_scene("aluminium-oxide", R, 3.9, plane=True, friction=0.3, restitution=0.5, name=name)
    sc.spheres = df.Spheres(x=[at[0]], y=[at[1]], z=[R * 1.001], radius=[R], material="ball",
                            velocity=[[3.9 * _m.sin(a), 0.0, -3.9 * _m.cos(a)]])
    if wall == "plane":
        sc.planes = [df.Plane("plane", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "rigid")]
        return sc
    sc.planes = []
    if wall == "square":
        v = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
        t = [(0, 1, 2), (0, 2, 3)]
    else:
        v = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0), (0, 0, 0)]
        t = [(0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)]
    sc.meshes = [df.TriangleMesh("mesh", v, t, "rigid")]
    return sc


@pytest.mark.parametrize("wall,at", [("square", (0.3, -0.2)), ("square", (0.0, 0.0)), ("fan", (0.0, 0.0)),
                                     ("fan", (0.2, 0.0))])
def test_a_flat_mesh_acts_as_the_plane_on_faces_edges_and_vertices(wall, at):
    """Face, shared-edge (the square's diagonal through the centre; the fan's spoke at y = 0) and
    shared-vertex (the fan's centre) contacts: one contact, as the plane, to round-off."""
    ref = df.build(_drop("plane", at, angle_deg=30.0)).run(600)
    sim = df.build(_drop(wall, at, angle_deg=30.0, name="drop-mesh")).run(600)
    assert ref.tables()["records"].fn_max.max() > 0
    np.testing.assert_allclose(sim.spheres.vel, ref.spheres.vel, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sim.spheres.angvel, ref.spheres.angvel, rtol=0, atol=1e-6)
    f_ref = ref.tables()["records"].plane_fz.to_numpy()
    f_mesh = sim.tables()["records"].mesh_fz.to_numpy()
    np.testing.assert_allclose(f_mesh, f_ref, rtol=1e-9, atol=1e-9 * np.abs(f_ref).max())


def test_a_convex_edge_returns_an_elastic_sphere_at_its_speed():
    """A roof of two triangles meeting at the ridge x = 0, z = 0 (slopes ±45°); an elastic, frictionless
    sphere falling on the ridge touches the edge only (one contact) and rebounds as from a plane
    (the same Hertz law with R* = R: the same O(Δt²) energy error of the leapfrog, 2.6e-5 here)."""
    sc = _drop("plane", (0.0, 0.0), name="ridge")
    sc.laws = {("ball", "rigid"): df.HertzMindlinLaw(restitution=1.0, tangential="none")}
    sc.planes = []
    v = [(-1, -1, -1), (0, -1, 0), (0, 1, 0), (-1, 1, -1), (1, -1, -1), (1, 1, -1)]
    sc.meshes = [df.TriangleMesh("roof", v, [(0, 1, 2), (0, 2, 3), (1, 4, 5), (1, 5, 2)], "rigid")]
    sim = df.build(sc).run(600)
    rec = sim.tables()["records"]
    assert rec.contacts.max() == 1 and rec.fn_max.max() > 0
    flat = _drop("plane", (0.0, 0.0), name="ridge-plane")
    flat.laws = sc.laws
    ref = df.build(flat).run(600)
    np.testing.assert_allclose(sim.spheres.vel, ref.spheres.vel, rtol=0, atol=1e-10)
    assert abs(sim.spheres.vel[0, 2] / 3.9 - 1) < 1e-4


def test_a_moving_mesh_pushes_like_a_moving_plane():
    def scene(kind):
        sc = _drop("plane" if kind == "plane" else "square", (0.3, 0.1), name=f"push-{kind}")
        sc.spheres = df.Spheres(x=[0.3], y=[0.1], z=[0.0025 * 1.001], radius=[0.0025], material="ball")
        ph = (df.PlanePhase(cycles=400, velocity=(0.0, 0.0, 0.5)),)
        if kind == "plane":
            sc.planes = [df.Plane("plane", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "rigid", phases=ph)]
        else:
            m = sc.meshes[0]
            sc.meshes = [df.TriangleMesh("mesh", m.vertices, m.triangles, "rigid", phases=ph)]
        return sc
    a = df.build(scene("plane")).run(500)
    b = df.build(scene("mesh")).run(500)
    assert a.spheres.vel[0, 2] > 0.5  # it was pushed and flew off
    np.testing.assert_allclose(b.spheres.vel, a.spheres.vel, rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.planes.point[0, 2], a.planes.point[0, 2], rtol=0, atol=1e-15)
    np.testing.assert_allclose(b.tris.v[:, 2::3], a.planes.point[0, 2], rtol=0, atol=1e-15)  # vertices moved too


def test_servo_plate_holds_its_target_force():
    """A sphere between a floor and a servo plate above it (no gravity): the plate comes down and holds
    F_A; the floor then carries F_A too (statics), and the overlap is Hertz's for F_A."""
    F = 50.0
    R = 0.01
    sc = df.Scene3D(name="servo", spheres=df.Spheres(x=[0.0], y=[0.0], z=[R], radius=[R], material="glass"),
                    materials={"glass": GLASS, "steel": df.Material(young=2e11, poisson=0.3)},
                    laws={("glass", "steel"): df.HertzMindlinLaw(friction=0.3, restitution=0.3)},
                    planes=[df.Plane("floor", (0, 0, 0), (0, 0, 1), "steel"),
                            df.Plane("plate", (0, 0, 2 * R + 1e-4), (0, 0, -1), "steel",
                                     servo=df.PlateServo(force=F, gain=0.05, v_max=0.05))],
                    local_damping=0.3, outputs=df.Outputs3D(every=100))
    sim = df.build(sc).run(30000)
    fz = sim.planes.force[:, 2]
    assert fz[1] == pytest.approx(F, rel=1e-3)    # the spheres push the plate up with F_A
    assert -fz[0] == pytest.approx(F, rel=1e-3)   # and the floor down with F_A
    E = effective_modulus(4.8e10, 0.2, 2e11, 0.3)
    delta = (F / (4 / 3 * E * math.sqrt(R))) ** (2 / 3)
    assert sim.pairs.ovl.max() == pytest.approx(delta, rel=1e-3)


def test_a_3d_run_too_long_to_record_is_refused_up_front():
    sc = _stack(n=3, name="stack-long")
    sim = df.build(sc)
    with pytest.raises(df.SceneError, match="record less often"):
        sim.run(10 ** 15)
    with pytest.raises(df.SceneError, match="run\\(n_steps\\)"):
        sim.run(-5)
    assert sim.step == 0


# ---------------------------------------------------------------------------- meshes in a periodic box
def _grid_mesh(x0, y0, side, n, z=0.0, material="rigid", name="floor", **kw):
    """A flat square [x0, x0 + side] × [y0, y0 + side] at height z as n × n squares of two triangles each."""
    g = np.linspace(0.0, side, n + 1)
    v = [(x0 + a, y0 + b, z) for b in g for a in g]
    t = []
    for r in range(n):
        for c in range(n):
            p = r * (n + 1) + c
            t += [(p, p + 1, p + n + 2), (p, p + n + 2, p + n + 1)]
    return df.TriangleMesh(name, v, t, material, **kw)


def _periodic_drop(wall, name, x=0.005, y=0.0113):
    """The oblique drop of _drop (30°, along +x) in a box periodic along x and y, period 20 mm, at x."""
    sc = _drop("plane", (x, y), angle_deg=30.0, name=name)
    sc.box = df.Box(periodic_x=(0.0, 0.02), periodic_y=(0.0, 0.02))
    if isinstance(wall, df.TriangleMesh):
        sc.planes, sc.meshes = [], [wall]
    return sc


def test_a_mesh_outside_the_period_is_met_through_its_periodic_image():
    """A flat floor mesh lying over x in [10, 30] mm of a box periodic over [0, 20] mm (half of it beyond the
    period) carries a sphere dropped at x = 5 mm through its image as the plane z = 0 does (velocities to round-off,
    force on the mesh = force on the plane); without images the sphere meets nothing there and falls through."""
    ref = df.build(_periodic_drop(df.Plane("plane", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "rigid"), "pd-plane")).run(600)
    sim = df.build(_periodic_drop(_grid_mesh(0.01, 0.0, 0.02, 4), "pd-mesh")).run(600)
    f_ref = ref.tables()["records"].plane_fz.to_numpy()
    assert np.abs(f_ref).max() > 0
    np.testing.assert_allclose(sim.spheres.vel, ref.spheres.vel, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sim.spheres.angvel, ref.spheres.angvel, rtol=0, atol=1e-6)
    f_mesh = sim.tables()["records"].floor_fz.to_numpy()
    np.testing.assert_allclose(f_mesh, f_ref, rtol=1e-9, atol=1e-9 * np.abs(f_ref).max())
    assert ref.spheres.vel[0, 2] > 0  # it rebounded
    # negative control: the same mesh seen only where it lies
    with pytest.warns(df.PeriodicMeshWarning):
        off = df.build(_periodic_drop(_grid_mesh(0.01, 0.0, 0.02, 4, periodic_images=False), "pd-off")).run(600)
    assert off.tables()["records"].floor_fz.abs().max() == 0.0 and off.spheres.vel[0, 2] < 0


def test_a_sphere_crossing_the_boundary_stays_on_an_imaged_mesh():
    """A sphere rolling along +x over a floor mesh that covers the period once, shifted by half of it, crosses
    x = 20 mm (wrapped) and keeps its contact with the floor as on a plane."""
    def scene(wall, name):
        sc = _periodic_drop(wall, name, x=0.015)
        sc.spheres = df.Spheres(x=[0.015], y=[0.0113], z=[0.0025], radius=[0.0025], material="ball",
                                velocity=[[1.0, 0.0, 0.0]], angular_velocity=[[0.0, 1.0 / 0.0025, 0.0]])
        sc.gravity = (0.0, 0.0, -9.81)
        return sc

    ref = df.build(scene(df.Plane("plane", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "rigid"), "roll-plane"))
    sim = df.build(scene(_grid_mesh(0.01, 0.0, 0.02, 4), "roll-mesh"))
    steps = int(round(0.012 / 1.0 / sim.dt))  # 12 mm of travel: across x = 20 mm
    ref.run(steps)
    sim.run(steps)
    assert sim.spheres.pos[0, 0] < 0.01  # wrapped across the boundary
    rec, rec_ref = sim.tables()["records"], ref.tables()["records"]
    assert (rec_ref.contacts == 1).mean() > 0.9  # it rolls on the plane
    # the floor's force as the plane's (the contact count may differ where the overlap passes through zero)
    weight = 9.81 * float(sim.spheres.mass[0])
    np.testing.assert_allclose(rec.floor_fz.to_numpy(), rec_ref.plane_fz.to_numpy(), rtol=0, atol=1e-6 * weight)
    np.testing.assert_allclose(sim.spheres.pos, ref.spheres.pos, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sim.spheres.vel, ref.spheres.vel, rtol=0, atol=1e-7)


def test_a_triangle_too_wide_for_periodic_images_is_refused():
    with pytest.raises(df.SceneError, match=r"triangle 0 is 0\.02 wide along x.*Split it"):
        df.build(_periodic_drop(_grid_mesh(0.0, 0.0, 0.02, 1), "wide"))
    # the same mesh without images builds (and is named for the boundary it reaches)
    with pytest.warns(df.PeriodicMeshWarning):
        df.build(_periodic_drop(_grid_mesh(0.0, 0.0, 0.02, 1, periodic_images=False), "wide-off"))


def test_engine_decks_refuse_meshes(tmp_path):
    from demflow.engines import EngineUnsupported, get_engine3d

    import dataclasses

    for engine, spring in (("yade", "incremental"), ("liggghts", "total")):  # each engine's matching shear spring
        sc = _drop("square", (0.0, 0.0), name="deck_mesh")
        sc.laws = {k: dataclasses.replace(v, shear_spring=spring) for k, v in sc.laws.items()}
        with pytest.raises(EngineUnsupported, match="triangle meshes .'mesh'."):
            get_engine3d(engine).write_deck(sc, df.build(sc), tmp_path / engine)
        (tmp_path / engine).mkdir()
        sc.meshes, sc.planes = [], [df.Plane("plane", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "rigid")]  # control: a plane
        get_engine3d(engine).write_deck(sc, df.build(sc), tmp_path / engine)


@pytest.mark.parametrize("at", [(0.0151, 0.01), (0.015, 0.01), (0.0151, 0.0113)])
def test_a_sphere_on_a_shared_edge_of_a_flat_mesh_acts_as_on_the_plane(at):
    """The oblique drop of _drop onto a flat 4 × 4 grid of 5 mm squares, landing on a shared edge (y = 10 mm: no face
    contact there), on a vertex where six triangles meet, and inside a face: one contact, as the plane.  Before the
    rule that drops an edge or vertex point another touching triangle holds with a closer point of its own, the vertex
    at (15, 10) mm counted as a second contact on the edge (velocity 0.026 m/s off the plane's)."""
    def drop(wall, name):
        sc = _drop("plane", at, angle_deg=30.0, name=name)
        if isinstance(wall, df.TriangleMesh):
            sc.planes, sc.meshes = [], [wall]
        return sc

    ref = df.build(drop(df.Plane("plane", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "rigid"), "edge-plane")).run(600)
    sim = df.build(drop(_grid_mesh(0.0, 0.0, 0.02, 4), "edge-mesh")).run(600)
    assert np.abs(ref.tables()["records"].plane_fz).max() > 0
    assert sim.tables()["records"].contacts.max() == 1
    np.testing.assert_allclose(sim.spheres.vel, ref.spheres.vel, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sim.spheres.angvel, ref.spheres.angvel, rtol=0, atol=1e-6)


def test_a_lone_sphere_builds_and_flies_and_no_law_at_all_is_a_clear_error():
    """A scene where nothing can touch (one sphere, no wall) takes its law family from the laws declared between
    its materials (it was refused with "mixes contact-law families ([])"); with no law declared at all the
    error says what to declare."""
    mats = {"m": df.Material(density=2650.0, young=7e9, poisson=0.2)}
    one = df.Spheres(x=[0.0], y=[0.0], z=[0.0], radius=[0.01], material="m", velocity=[[1.0, 0.0, 0.0]])
    sim = df.build(df.Scene3D(name="one", spheres=one, materials=mats, n_steps=10,
                              laws={("m", "m"): df.HertzMindlinLaw(friction=0.3, restitution=0.5)})).run()
    assert sim.spheres.pos[0, 0] == pytest.approx(10 * sim.dt, rel=1e-12)
    with pytest.raises(df.SceneError, match=r"no particle can touch .* declare one, e\.g\. laws\[\('m', 'm'\)\]"):
        df.build(df.Scene3D(name="one", spheres=one, materials=mats, laws={}, n_steps=10))


def test_hertz_parameter_type_compiles_mindlin_deresiewicz_only_where_a_pair_uses_it():
    """A scene none of whose pairs uses Mindlin-Deresiewicz gets HertzParams (its pair pass compiled without that
    branch), one with any such pair HertzParamsMD; the two compiled passes give the same bits on a scene without
    it (the golden bed: planes, a servo plate, a triangle ramp, periodic images, local damping), so the
    specialised pass is the general one with a branch it never takes left out."""
    import dataclasses

    import golden3d_scenes as g3  # tests/ is on the path (as for test_manifest.py)
    from demflow.laws.hertz_mindlin import HertzParams, HertzParamsMD

    scene = g3.settling_bed()
    plain, general = df.build(scene), df.build(scene)
    assert type(plain.law_params) is HertzParams
    general.law_params = HertzParamsMD(*general.law_params)
    plain.run(400)
    general.run(400)
    for name in ("pos", "vel", "angvel", "quat"):
        np.testing.assert_array_equal(getattr(plain.spheres, name), getattr(general.spheres, name), err_msg=name)
    np.testing.assert_array_equal(plain.pairs.hist, general.pairs.hist)
    np.testing.assert_array_equal(plain.planes.force, general.planes.force)
    # one Mindlin-Deresiewicz pair among two: the general type, and the history wide enough for it
    md = dataclasses.replace(scene.laws[("grain", "steel")], tangential="mindlin-deresiewicz")
    mixed = df.build(dataclasses.replace(scene, laws={**scene.laws, ("grain", "steel"): md}))
    assert type(mixed.law_params) is HertzParamsMD
    assert mixed.pairs.hist.shape[1] == 8


# ---------------------------------------------------------------------------- history rotation modes
@pytest.mark.parametrize("spring", ["incremental", "total"])
def test_history_rotation_project_projects_after_the_increment(spring):
    """history_rotation='project' (LIGGGHTS's rule): the law increments the spring, then drops its component along
    n, without rescaling; 'rescale' leaves the row to the pass (the law adds only the increment).  Checked on the
    law's compiled body against the rule written out here."""
    from demflow.laws.hertz_mindlin import (ROTATION_PROJECT, ROTATION_RESCALE, SHEAR_INCREMENTAL, SHEAR_TOTAL,
                                            TANGENTIAL_MINDLIN, CAP_TOTAL, hertz_contact3)

    E, G, mu, zn, zt = 7e10, 2.7e10, 10.0, 0.0, 0.0  # no dashpots, a cap far away: the spring alone
    n = np.array([0.6, 0.0, 0.8])
    h = np.array([2e-7, 1e-7, 1e-7]) if spring == "total" else np.array([3.0, 1.0, 1.0])  # n·h != 0
    vt = np.array([0.8, 0.3, -0.6]) * 1e-3  # tangential (vt·n = 0)
    dt, rstar, overlap, meff = 1e-6, 1e-3, 1e-6, 1e-3
    mode = SHEAR_TOTAL if spring == "total" else SHEAR_INCREMENTAL
    row = (h[0], h[1], h[2], 0.0, 0.0, 0.0, 0.0, 0.0)
    kt = 8.0 * G * math.sqrt(rstar * overlap)
    out = {}
    for rot in (ROTATION_RESCALE, ROTATION_PROJECT):
        Fn, Tx, Ty, Tz, sliding, diss, new = hertz_contact3(E, G, mu, zn, zt, TANGENTIAL_MINDLIN, mode, CAP_TOTAL, rot,
                                                           row, meff, rstar, overlap, 0.0, vt[0], vt[1], vt[2],
                                                           n[0], n[1], n[2], dt, False)
        assert not sliding
        out[rot] = (np.array([Tx, Ty, Tz]), np.array(new[:3]))
    if spring == "total":
        u = h + vt * dt
        want_rescale = -kt * u
        u_p = u - (u @ n) * n
        want_project = -kt * u_p
        np.testing.assert_allclose(out[ROTATION_PROJECT][1], u_p, rtol=1e-14, atol=1e-14 * np.abs(u).max())
    else:
        T = h - kt * vt * dt
        want_rescale = T
        want_project = T - (T @ n) * n
        np.testing.assert_allclose(out[ROTATION_PROJECT][1], want_project, rtol=1e-14, atol=1e-14 * np.abs(T).max())
    scale = np.abs(want_rescale).max()
    np.testing.assert_allclose(out[ROTATION_RESCALE][0], want_rescale, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(out[ROTATION_PROJECT][0], want_project, rtol=0, atol=1e-13 * scale)
    assert abs(out[ROTATION_PROJECT][0] @ n) < 1e-13 * scale  # in the tangent plane
    assert abs(out[ROTATION_RESCALE][0] @ n) > 0.1 * scale  # the law alone does not project (the pass turns it)
