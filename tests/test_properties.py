"""Properties that must hold for any input (Hypothesis)."""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demflow import build
from demflow.contacts.neighbours import pairs_brute_force, pairs_cell_search

from helpers import box_walls, gas_scene, random_packing

SETTINGS = settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _squeezed(seed, n=30):
    """A random packing with random velocities aimed inward, so contacts form."""
    x, y, r, box = random_packing(n, seed, box=2.2 * np.sqrt(n))
    rng = np.random.default_rng(seed + 1)
    v = rng.normal(0, 1.0, (len(x), 2)) + 0.5 * np.c_[box / 2 - x, box / 2 - y]
    om = rng.normal(0, 1.0, len(x))
    return x, y, r, v, om, box


@SETTINGS
@given(seed=st.integers(0, 10_000), ratio=st.sampled_from([1.0, 3.0, 10.0, 100.0]), skin=st.floats(0.0, 0.5))
def test_cell_search_equals_brute_force(seed, ratio, skin):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 300))
    r = rng.uniform(0.01, 0.01 * ratio, n)
    r[rng.integers(0, n)] = 0.01 * ratio  # make sure the largest radius is present
    x = rng.uniform(0, 2, n)
    y = rng.uniform(0, 1, n)
    wx = np.array([0.0, 2.0]); wy = np.array([0.0, 0.0]); bx = np.array([2.0, 2.0]); by = np.array([0.0, 1.0])
    f1, o1 = pairs_cell_search(x, y, r, skin, wx, wy, bx, by)
    f2, o2 = pairs_brute_force(x, y, r, skin, wx, wy, bx, by)
    assert np.array_equal(f1, f2) and np.array_equal(o1, o2)


@SETTINGS
@given(seed=st.integers(0, 10_000))
def test_newton_third_law_frictional(seed):
    """Contact forces and moments: Σ forces on discs = 0 with no walls, no gravity;
    hence total momentum is conserved exactly up to round-off."""
    x, y, r, v, om, _ = _squeezed(seed)
    sim = build(gas_scene(x, y, r, v, om, ks=8e4, mu=0.5, cn=5.0, n_steps=300, every=1))
    p0 = np.array([np.sum(sim.mass * sim.vx), np.sum(sim.mass * sim.vy)])
    sim.run()
    assert sim.results().energy.elastic.max() > 0, "the scene must make contacts"
    p1 = np.array([np.sum(sim.mass * sim.vx), np.sum(sim.mass * sim.vy)])
    scale = np.sum(sim.mass * np.hypot(sim.vx, sim.vy)) + 1.0
    assert np.all(np.abs(p1 - p0) < 1e-11 * scale)
    assert np.abs(sim.discs.Fx.sum()) < 1e-9 * (np.abs(sim.discs.Fx).sum() + 1)
    assert np.abs(sim.discs.Fy.sum()) < 1e-9 * (np.abs(sim.discs.Fy).sum() + 1)


def _final(x, y, r, v, om, **kw):
    sim = build(gas_scene(x, y, r, v, om, ks=8e4, mu=0.5, cn=5.0, n_steps=300, **kw)).run()
    return sim


@SETTINGS
@given(seed=st.integers(0, 10_000), dx=st.floats(-50, 50), dy=st.floats(-50, 50))
def test_translation_invariance(seed, dx, dy):
    x, y, r, v, om, _ = _squeezed(seed)
    a = _final(x, y, r, v, om)
    b = _final(x + dx, y + dy, r, v, om)
    assert np.allclose(a.x + dx, b.x, atol=1e-8) and np.allclose(a.vy, b.vy, atol=1e-8)


@SETTINGS
@given(seed=st.integers(0, 10_000), angle=st.floats(0, 2 * np.pi))
def test_rotation_invariance(seed, angle):
    x, y, r, v, om, _ = _squeezed(seed)
    c, s = np.cos(angle), np.sin(angle)
    a = _final(x, y, r, v, om)
    b = _final(c * x - s * y, s * x + c * y, r, np.c_[c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]], om)
    assert np.allclose(c * a.x - s * a.y, b.x, atol=1e-7)
    assert np.allclose(s * a.x + c * a.y, b.y, atol=1e-7)
    assert np.allclose(a.om, b.om, atol=1e-7)


@SETTINGS
@given(seed=st.integers(0, 10_000))
def test_relabelling_invariance(seed):
    x, y, r, v, om, _ = _squeezed(seed)
    perm = np.random.default_rng(seed).permutation(len(x))
    a = _final(x, y, r, v, om)
    b = _final(x[perm], y[perm], r[perm], v[perm], om[perm])
    assert np.allclose(a.x[perm], b.x, atol=1e-9) and np.allclose(a.om[perm], b.om, atol=1e-9)


@pytest.mark.parametrize("normal", ["overlap", "incremental"])
def test_energy_conserved_undamped_frictionless_drift_shrinks_with_dt(normal):
    """Frictionless, undamped discs in a box: total energy drifts less as Δt falls."""
    x, y, r, box = random_packing(40, 3, box=16.0)
    rng = np.random.default_rng(4)
    v = rng.normal(0, 2.0, (len(x), 2))
    drifts = []
    for frac in (0.1, 0.05, 0.025):
        sc = gas_scene(x, y, r, v, walls=box_walls(16.0), normal=normal, n_steps=1, every=1)
        sim = build(sc)
        dt = frac * sim.dt_crit
        sc.dt = dt
        sc.n_steps = int(round(3.0 / dt))
        sc.outputs = type(sc.outputs)(every=max(1, sc.n_steps // 400))
        e = build(sc).run().results().energy
        tot = (e.kinetic + e.elastic).to_numpy()
        drifts.append(np.max(np.abs(tot - tot[0])) / tot[0])
    assert drifts[0] < 0.05
    assert drifts[2] < drifts[0] / 3, drifts
