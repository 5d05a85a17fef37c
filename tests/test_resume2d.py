"""A 2D disc run resumed from a checkpoint continues as the run that never stopped, to the bit, also when discs have
crossed a periodic boundary since the last neighbour-list build (the 3D twin is tests/test_resume3d.py).

Why this exists: until 2026-11-27 loading a 2D checkpoint rebuilt the pair list, which wraps the discs that left the
box into it, re-orders them spatially and restarts the rebuild schedule at the checkpoint's step.  The uninterrupted
run wraps them at its own next rebuild; x - L + v·dt and x + v·dt - L round differently, so a resumed periodic run
parted from the uninterrupted one (the unwrapped positions of the scenes below by 1.8e-15 m, and 2.7e-15 m with the
servo lid, within 1500 steps; found by a user-path review, the README saying "to the bit").  An open box was already
exact: nothing wraps.
"""
from __future__ import annotations

import numpy as np
import pytest

import demflow as df

L = 6.0


def _scene(periodic: bool, servo: bool) -> df.Scene:
    """Two rows of six discs sliding sideways on a frictional floor (periodic along x: they cross the boundary);
    with ``servo`` a lid pressed down on them by a servo."""
    xs = [0.5 + i for i in range(6)] * 2
    ys = [0.5] * 6 + [1.5] * 6
    law = df.LinearLaw(kn=1e7, ks=1e7, cn=1e4, friction=0.5)
    walls = [df.Wall("floor", point=(0.0, 0.0), direction=(1.0, 0.0), h1=-1.0, h2=L + 1.0, material="w")]
    if servo:
        walls.append(df.Wall("lid", point=(0.0, 2.0), direction=(1.0, 0.0), h1=-1.0, h2=L + 1.0, material="w",
                             servo=df.Servo(force=2e4, direction=(0.0, -1.0), gain=0.5, v_max=0.5)))
    return df.Scene(name="resume2d", discs=df.Discs(x=xs, y=ys, radius=[0.45] * 12, material="d",
                                                    velocity=[[3.0, 0.0]] * 12),
                    materials={"d": df.Material(density=2000.0), "w": df.Material()},
                    laws={("d", "d"): law, ("d", "w"): law}, walls=walls, damping=df.GlobalDamping(C=0.0),
                    gravity=(0.0, -10.0), dt=2e-4, n_steps=3000,
                    box=df.Box(periodic_x=(0.0, L)) if periodic else df.Box(), outputs=df.Outputs(every=10))


def _outside(sim) -> bool:
    return bool(np.any((sim.discs.x < 0.0) | (sim.discs.x >= L)))


@pytest.mark.parametrize("periodic,servo", [(True, False), (True, True), (False, True)])
def test_a_resumed_2d_run_continues_the_uninterrupted_one_to_the_bit(periodic, servo, tmp_path):
    sc = _scene(periodic, servo)
    a = df.build(sc)
    a.run(300)
    if periodic:
        for _ in range(5000):  # on to a step where a disc has crossed and is not wrapped yet
            if _outside(a):
                break
            a.run(1)
        assert _outside(a), "no disc outside the box: the test would not see the wrap"
    path = a.save_checkpoint(tmp_path / "c.npz")
    b = df.build(sc).load_checkpoint(path)
    assert _outside(b) == _outside(a)  # the state is taken over as it was, not wrapped
    ra, rb = a.rebuilds, b.rebuilds
    a.run(1500)
    b.run(1500)
    if periodic:
        assert np.abs(a.ix).sum() > 0  # the discs crossed the boundary
    assert a.rebuilds - ra > 2  # the lists were rebuilt on the way (and wrapped the discs)
    assert b.rebuilds - rb == a.rebuilds - ra  # at the same steps
    for k in ("x", "y", "th", "vx", "vy", "om"):
        np.testing.assert_array_equal(getattr(b.discs, k), getattr(a.discs, k), err_msg=k)
    np.testing.assert_array_equal(b.ix, a.ix)
    np.testing.assert_array_equal(b.pairs.hist, a.pairs.hist)
    np.testing.assert_array_equal(b.walls.py, a.walls.py)
    np.testing.assert_array_equal(b.walls.force, a.walls.force)


def test_a_2d_checkpoint_written_before_the_list_state_was_kept_still_loads(tmp_path):
    """A checkpoint of the older format (no pair-list build in it) loads, its list built afresh from the positions."""
    sc = _scene(True, False)
    a = df.build(sc)
    a.run(500)
    path = a.save_checkpoint(tmp_path / "new.npz")
    with np.load(path) as z:
        old = {k: z[k] for k in z.files if k not in ("sx", "sy", "perm", "xref", "yref", "disp_walls")}
    np.savez(tmp_path / "old.npz", **old)
    b = df.build(sc)
    n0 = b.rebuilds
    b.load_checkpoint(tmp_path / "old.npz")
    assert b.rebuilds == n0 + 1  # the old path: one rebuild at load
    c = df.build(sc)
    n0 = c.rebuilds
    c.load_checkpoint(path)
    assert c.rebuilds == n0  # the new path: the list as it was
    assert b.step == c.step == 500
    np.testing.assert_array_equal(b.discs.vx, a.discs.vx)
    b.run(200)  # and runs on
    assert np.all(np.isfinite(b.discs.x))
