"""A 3D run resumed from a checkpoint continues as the run that never stopped, to the bit, also when particles
have crossed a periodic boundary since the last neighbour-list build.

Why this exists: until 2026-11-27 loading a checkpoint rebuilt the pair list, which wraps the particles that left
the box into it and restarts the rebuild schedule at the checkpoint's step.  The uninterrupted run wraps them at
its own next rebuild; x - L + v·dt and x + v·dt - L round differently, so a resumed periodic run parted from the
uninterrupted one by 1e-15 to 1e-14 m and then, a granular bed being chaotic, by everything (found when the resumed
``miyata-uniaxial-3d-ellipsoids-full`` bed loaded differently from an earlier run of the same settled bed).
Each scene here is taken to a step where a particle lies outside the box (crossed, not yet wrapped), checkpointed
there, and continued both ways.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import demflow as df
from demflow.shapes.clump import ClumpTemplate

ROCK = df.Material(density=2650.0, young=7e8, poisson=0.2)
L = 1.0


def _gas(kind: str, n: int = 36) -> df.Scene3D:
    """A dilute layer of particles on a floor, periodic along x and y, moving fast sideways: they cross the
    boundaries and collide."""
    rng = np.random.default_rng(3)
    g = int(np.ceil(np.sqrt(n)))
    x = (np.arange(n) % g + 0.5) * L / g
    y = (np.arange(n) // g + 0.5) * L / g
    z = 0.12 + 0.3 * rng.random(n)
    v = np.column_stack([rng.normal(0.0, 2.0, n), rng.normal(0.0, 2.0, n), rng.normal(0.0, 0.5, n)])
    common = dict(name=f"gas-{kind}", materials={"rock": ROCK},
                  laws={("rock", "rock"): df.HertzMindlinLaw(friction=0.4, restitution=0.5)},
                  planes=[df.Plane(name="floor", point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0), material="rock")],
                  box=df.Box(periodic_x=(0.0, L), periodic_y=(0.0, L)), gravity=(0.0, 0.0, -9.81), skin=0.02,
                  outputs=df.Outputs3D(every=0))
    if kind == "spheres":
        return df.Scene3D(spheres=df.Spheres(x=x, y=y, z=z, radius=[0.04] * n, material="rock", velocity=v),
                          dt_fraction=0.05, **common)
    if kind == "clumps":
        t = ClumpTemplate.from_spheres([[-0.025, 0.0, 0.0], [0.025, 0.0, 0.0]], [0.03, 0.03], density=2650.0)
        return df.Scene3D(spheres=None, clumps=df.Clumps(t, x=x, y=y, z=z, material="rock", velocity=v),
                          dt_fraction=0.04, **common)
    return df.Scene3D(spheres=None, ellipsoids=df.Ellipsoids(axes=[[0.06, 0.045, 0.03]] * n, x=x, y=y, z=z,
                                                              material="rock", velocity=v),
                      dt_fraction=0.03, **common)


def _outside(sim) -> bool:
    p = sim.spheres.pos[:, :2]
    return bool(np.any((p < 0.0) | (p >= L)))


@pytest.mark.parametrize("kind", ["spheres", "clumps", "ellipsoids"])
def test_a_resumed_periodic_run_continues_the_uninterrupted_one_to_the_bit(kind, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", df.UnsafeTimeStepWarning)
        sc = _gas(kind)
        a = df.build(sc)
        a.run(200)
        for _ in range(20000):  # on to a step where a particle has crossed and is not wrapped yet
            if _outside(a):
                break
            a.run(1)
        assert _outside(a), "no particle outside the box: the test would not see the wrap"
        path = a.save_checkpoint(tmp_path / "c.npz")
        b = df.build(sc).load_checkpoint(path)
        assert _outside(b)  # the state is taken over as it was, not wrapped
        a.run(1500)
        b.run(1500)
    assert np.abs(a.spheres.img).sum() > 0  # periodic images were used
    assert (a.pairs.ovl > 0).any() or a.n_rebuilds > 5
    for k in ("pos", "vel", "angvel", "img"):
        np.testing.assert_array_equal(getattr(b.spheres, k), getattr(a.spheres, k), err_msg=k)
    np.testing.assert_array_equal(b.pairs.hist, a.pairs.hist)
    if kind != "spheres":
        for k in ("pos", "vel", "L", "quat"):
            np.testing.assert_array_equal(getattr(b.bodies, k), getattr(a.bodies, k), err_msg=k)


def test_a_checkpoint_of_an_older_demflow_still_loads(tmp_path):
    """A checkpoint without the pair list's shifts and build positions (written before 2026-11-27) is loaded by
    listing the pairs afresh, as before."""
    sc = _gas("spheres")
    a = df.build(sc)
    a.run(300)
    path = a.save_checkpoint(tmp_path / "c.npz")
    with np.load(path) as z:
        old = {k: z[k] for k in z.files if k not in ("pair_shift", "ref", "plane_ref")}
    np.savez(tmp_path / "old.npz", **old)
    fresh = df.build(sc)
    built = fresh.n_rebuilds
    b = fresh.load_checkpoint(tmp_path / "old.npz")
    assert b.step == 300 and not _outside(b)  # listed afresh: every particle wrapped into the box
    assert b.n_rebuilds == built + 1
    assert df.build(sc).load_checkpoint(path).n_rebuilds == built  # a new checkpoint is taken over as it was
    b.run(100)
    assert np.isfinite(b.spheres.pos).all()
