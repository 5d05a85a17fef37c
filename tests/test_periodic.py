"""Periodic boxes in 2D (issue 12 item 4): minimum-image neighbour lists against brute force,
contacts across the boundary equal to the same contacts away from it, momentum and energy of a
crossing, unwrapped displacements, and a dense periodic packing equal to its 3×3 replica."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demflow import Box, Discs, LinearLaw, Material, Outputs, Scene, SceneError, build
from demflow.contacts.periodic import pairs_periodic, pairs_periodic_brute_force
from demflow.space import periodic_box, wrap

NO_WALLS = tuple(np.empty(0) for _ in range(4))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(1, 80), axes=st.sampled_from(["x", "y", "xy"]),
       ratio=st.floats(1.0, 20.0), skin=st.floats(0.0, 0.5))
def test_periodic_search_equals_brute_force(seed, n, axes, ratio, skin):
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.1, 0.1 * ratio, n)
    reach = 2 * r.max() + skin
    lx = ly = max(2.2 * reach, 1.5 * math.sqrt(n) * r.mean() * 2)
    box = periodic_box(-1.0, 2.0, lx if "x" in axes else math.inf, ly if "y" in axes else math.inf)
    x = rng.uniform(-1.0, -1.0 + lx, n)
    y = rng.uniform(2.0, 2.0 + ly, n)
    f, o, sx, sy = pairs_periodic(x, y, r, skin, *NO_WALLS, box)
    fb, ob, sxb, syb = pairs_periodic_brute_force(x, y, r, skin, *NO_WALLS, box)
    kb = np.argsort(fb * n + ob, kind="stable")
    assert np.array_equal(f, fb[kb]) and np.array_equal(o, ob[kb])
    assert np.array_equal(sx, sxb[kb]) and np.array_equal(sy, syb[kb])


def test_wrap_counts_periods():
    box = periodic_box(0.0, 0.0, 2.0, 3.0)
    x = np.array([-0.5, 4.5, 1.0])
    y = np.array([3.0, -6.5, 0.0])
    ix, iy = np.zeros(3, np.int64), np.zeros(3, np.int64)
    wrap(box, x, y, ix, iy)
    assert np.allclose(x, [1.5, 0.5, 1.0]) and list(ix) == [-1, 2, 0]
    assert np.allclose(y, [0.0, 2.5, 0.0]) and list(iy) == [1, -3, 0]


def _pair_scene(x0, L=10.0, ks=2e4, vy=0.3):
    """Two discs colliding obliquely along x, the pair centred at x0 in a box periodic in x and y."""
    law = LinearLaw(kn=1e5, ks=ks, friction=0.4)
    return Scene(name="pair", discs=Discs(x=[x0 - 1.2, x0 + 1.2], y=[5.0, 5.3], radius=[1.0, 0.9], material="g",
                                          velocity=[(2.0, vy), (-1.0, 0.0)]),
                 materials={"g": Material(density=1.0)}, laws={("g", "g"): law},
                 box=Box(periodic_x=(0.0, L), periodic_y=(0.0, L)), dt_fraction=0.02, n_steps=3000,
                 skin=0.05, outputs=Outputs(every=10, snapshots=tuple(range(800, 900, 4))))


def test_contact_across_the_boundary_equals_the_same_contact_inside():
    """The same oblique frictional collision, once in the middle of the box and once across the
    x boundary: relative motion, forces and history agree to round-off; momentum is conserved."""
    inside = build(_pair_scene(5.0)).run()
    across = build(_pair_scene(0.0)).run()  # disc 0 starts at x = -1.2, wrapped to 8.8
    xi, yi = inside.unwrapped_positions()
    xa, ya = across.unwrapped_positions()
    assert np.allclose(xa - (xi - 5.0), 0.0, atol=1e-9) and np.allclose(ya, yi, atol=1e-9)
    assert np.allclose(across.vx, inside.vx, atol=1e-9) and np.allclose(across.om, inside.om, atol=1e-9)
    ci, ca = inside.results().contacts, across.results().contacts
    assert len(ci) == len(ca) >= 5  # in contact at several snapshots, with a shear history
    assert np.array_equal(ci.step, ca.step)
    assert (ci.fs.abs() > 1e-3 * ci.fn).any()
    assert np.allclose(ca.fn, ci.fn, rtol=1e-9)
    assert np.allclose(ca.fs, ci.fs, rtol=1e-7, atol=1e-9 * float(ci.fn.max()))
    m = across.mass
    p0 = m[0] * 2.0 - m[1] * 1.0
    assert math.isclose(float((m * across.vx).sum()), p0, rel_tol=1e-12)
    assert across.ix[0] != 0 or across.ix[1] != 0  # it did cross


def test_elastic_crossing_conserves_energy():
    """Frictionless elastic collision across the boundary: momentum conserved to round-off, kinetic
    energy after equal to the same collision inside the box to 1e-12, and equal to the energy before
    within the linear spring's contact-onset error (measured 5.4e-4 at this Δt, 1.1e-4 at half of it:
    O(Δt), the contact starts and ends between steps)."""
    def ke(sim):
        return 0.5 * float((sim.mass * (sim.vx ** 2 + sim.vy ** 2)).sum())

    across, inside = build(_pair_scene(0.0, ks=0.0, vy=0.0)), build(_pair_scene(5.0, ks=0.0, vy=0.0))
    ke0, p0 = ke(across), (across.mass * across.vx).sum()
    across.run()
    inside.run()
    assert across.results().energy.elastic.iloc[-1] == 0.0  # apart again
    assert across.ix.any()  # it crossed
    assert math.isclose((across.mass * across.vx).sum(), p0, rel_tol=1e-13)
    assert math.isclose(ke(across), ke(inside), rel_tol=1e-12)
    assert abs(ke(across) / ke0 - 1) < 1e-3


def test_unwrapped_displacement_follows_the_velocity():
    law = LinearLaw(kn=1e5)
    sc = Scene(name="drift", discs=Discs(x=[0.5], y=[0.5], radius=[0.2], material="g", velocity=[(3.0, -2.0)]),
               materials={"g": Material(density=1.0)}, laws={("g", "g"): law},
               box=Box(periodic_x=(0.0, 1.0), periodic_y=(0.0, 1.0)), dt=1e-3, n_steps=5000)
    sim = build(sc).run()
    x, y = sim.unwrapped_positions()
    assert 0.0 <= sim.x[0] < 1.0 and 0.0 <= sim.y[0] < 1.0
    assert math.isclose(x[0], 0.5 + 3.0 * 5.0, rel_tol=1e-9) and math.isclose(y[0], 0.5 - 2.0 * 5.0, rel_tol=1e-9)
    assert sim.ix[0] == 15 and sim.iy[0] == -10


def test_small_period_refused():
    sc = _pair_scene(5.0, L=3.0)
    with pytest.raises(SceneError, match="twice the neighbour reach"):
        build(sc)


def _lattice(n_side=10, seed=3):
    """A dense polydisperse packing on a jittered triangular lattice, periodic in x and y."""
    rng = np.random.default_rng(seed)
    a = 1.0
    lx, ly = n_side * a, n_side * a * math.sqrt(3) / 2
    xs, ys = [], []
    for row in range(n_side):
        for col in range(n_side):
            xs.append((col + 0.5 * (row % 2)) * a)
            ys.append(row * a * math.sqrt(3) / 2)
    x = np.array(xs) + rng.uniform(-0.01, 0.01, len(xs))
    y = np.array(ys) + rng.uniform(-0.01, 0.01, len(xs))
    r = 0.5 * a * (1.0 + rng.uniform(0.0, 0.03, len(xs)))
    return x, y, r, lx, ly


def _dense_scene(x, y, r, box):
    law = LinearLaw(kn=1e5, ks=5e4, cn=10.0, friction=0.3)
    return Scene(name="dense", discs=Discs(x=x, y=y, radius=r, material="g"), materials={"g": Material(density=1.0)},
                 laws={("g", "g"): law}, box=box, dt_fraction=0.1, n_steps=3, overlap_tolerance=0.2, skin=0.05,
                 outputs=Outputs(every=0, snapshots=(0, 3)))


def test_dense_periodic_packing_equals_its_3x3_replica():
    """Contact count and pressure of a periodic packing equal those of the central cell of the same
    packing replicated 3×3 without periodicity (pairs whose finder is a central disc), at the start and
    after 3 steps (the replica's free edges are 10 discs from the centre)."""
    x, y, r, lx, ly = _lattice()
    n = len(x)
    per = build(_dense_scene(x, y, r, Box(periodic_x=(0.0, lx), periodic_y=(0.0, ly)))).run()
    X = np.concatenate([x + i * lx for j in (-1, 0, 1) for i in (-1, 0, 1)])
    Y = np.concatenate([y + j * ly for j in (-1, 0, 1) for i in (-1, 0, 1)])
    R = np.tile(r, 9)
    rep = build(_dense_scene(X, Y, R, Box())).run()
    cp, cr = per.results().contacts, rep.results().contacts
    for step in (0, 3):
        a = cp[cp.step == step]
        b = cr[(cr.step == step) & (cr.i >= 4 * n) & (cr.i < 5 * n)]
        assert len(a) > 2 * n  # dense: more than two contacts per disc
        assert len(a) == len(b)
        pa = float((a.fn * (r[a.i] + r[a.j] - a.overlap)).sum()) / (2 * lx * ly)
        pb = float((b.fn * (R[b.i] + R[b.j] - b.overlap)).sum()) / (2 * lx * ly)
        assert math.isclose(pa, pb, rel_tol=1e-9), (step, pa, pb)
        sa = np.sort(a.fs.to_numpy())
        sb = np.sort(b.fs.to_numpy())
        assert np.allclose(sa, sb, rtol=1e-7, atol=1e-9 * float(a.fn.max()))
