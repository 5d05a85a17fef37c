"""Walls: servo control (thesis eqs 5.11-5.12), moments, prescribed rotation about a point."""
import numpy as np
import pytest

from demflow import Discs, GlobalDamping, LinearLaw, Material, Outputs, Phase, Scene, Servo, Wall, build


def column(servo_force, gain=0.5, v_max=0.5, n=3):
    """n discs stacked between a floor and a servo-controlled top wall, no gravity."""
    law = LinearLaw(kn=1e6, cn=2e3)
    top = 2.0 * n + 0.01
    return Scene(name="servo-column",
                 discs=Discs(x=[0.0] * n, y=[1.0 + 2 * k for k in range(n)], radius=[1.0] * n, material="d"),
                 materials={"d": Material(density=1.0), "w": Material()},
                 laws={("d", "d"): law, ("d", "w"): law},
                 walls=[Wall("floor", (0.0, 0.0), (1.0, 0.0), -3, 3, "w"),
                        Wall("top", (0.0, top), (1.0, 0.0), -3, 3, "w",
                             servo=Servo(force=servo_force, direction=(0.0, -1.0), gain=gain, v_max=v_max))],
                 damping=GlobalDamping(alpha=5.0), n_steps=20000, outputs=Outputs(every=100))


def test_servo_wall_holds_its_force():
    F = 5e3
    sim = build(column(F)).run()
    w = sim.results().wall("top")
    assert w.fy.iloc[-1] == pytest.approx(F, rel=1e-3)  # discs push the top wall up with F
    floor = sim.results().wall("floor")
    assert -floor.fy.iloc[-1] == pytest.approx(F, rel=1e-3)  # and the floor carries it
    # the wall moved down to make contact and compress the column by 4 overlaps of F/kn
    assert w.py.iloc[-1] == pytest.approx(2.0 * 3 - 4 * F / 1e6, abs=1e-4)


def test_servo_speed_is_capped_by_v_max():
    sim = build(column(5e3, gain=1e3, v_max=0.05))
    sim.run(200)
    w = sim.results().wall("top")
    dy = np.diff(w.py.to_numpy())
    assert np.all(np.abs(dy) <= 0.05 * sim.dt * 100 * (1 + 1e-9))


def test_wall_moment_about_its_point():
    """A disc resting on a floor at distance d from the floor's point P: M_P = d × W."""
    d = 1.5
    sc = Scene(name="moment", discs=Discs(x=[d], y=[1.0], radius=[1.0], material="d"),
               materials={"d": Material(density=1.0), "w": Material()},
               laws={("d", "w"): LinearLaw(kn=1e6, cn=1e3)},
               walls=[Wall("floor", (0.0, 0.0), (1.0, 0.0), -5, 5, "w")],
               gravity=(0.0, -10.0), damping=GlobalDamping(alpha=5.0), n_steps=20000, outputs=Outputs(every=100))
    sim = build(sc).run()
    w = sim.results().wall("floor")
    W = sim.mass[0] * 10.0
    assert w.fy.iloc[-1] == pytest.approx(-W, rel=1e-6)
    assert w.moment.iloc[-1] == pytest.approx(-d * W, rel=1e-3)  # force -W at x = d: M = d·(-W)


def test_wall_rotation_about_a_pivot():
    """A free wall rotated about a pivot by ω for N steps ends at angle ωNΔt, P rotated about the pivot."""
    om, N = 0.3, 1000
    sc = Scene(name="rot", discs=Discs(x=[10.0], y=[10.0], radius=[0.5], material="d"),
               materials={"d": Material(density=1.0), "w": Material()},
               laws={("d", "w"): LinearLaw(kn=1e4)},
               walls=[Wall("arm", (2.0, 0.0), (1.0, 0.0), -1, 1, "w", phases=(Phase(N, omega=om, pivot=(0.0, 0.0)),))],
               dt=1e-3, n_steps=N + 10, outputs=Outputs(every=1))
    sim = build(sc).run()
    a = om * N * 1e-3
    assert sim.wpx[0] == pytest.approx(2.0 * np.cos(a), abs=1e-12)
    assert sim.wpy[0] == pytest.approx(2.0 * np.sin(a), abs=1e-12)
    assert np.arctan2(sim.wey[0], sim.wex[0]) == pytest.approx(a, abs=1e-12)


def test_mesh_near_a_periodic_boundary_warns():
    """A mesh with periodic_images=False within a particle's reach of a periodic boundary is named at build
    (PeriodicMeshWarning), once per axis, and the warning points at the caller's line; the same kind of ramp kept
    that far inside the period is not."""
    import sys
    import warnings
    from pathlib import Path

    import demflow as df

    sys.path.insert(0, str(Path(__file__).parent))
    import golden3d_scenes as g3

    with pytest.warns(df.PeriodicMeshWarning) as got:
        build(g3.settling_bed())  # its ramp spans the whole period along x and y, without images
    warned = [w for w in got if issubclass(w.category, df.PeriodicMeshWarning)]
    msgs = [str(w.message) for w in warned]
    assert len(msgs) == 2 and "along x" in msgs[0] and "along y" in msgs[1] and "'ramp'" in msgs[0]
    assert "periodic_images=True" in msgs[0]
    assert all(Path(w.filename).resolve() == Path(__file__).resolve() for w in warned), [w.filename for w in warned]
    with warnings.catch_warnings():
        warnings.simplefilter("error", df.PeriodicMeshWarning)
        build(g3.ellipsoid_bed())  # its ramp stays 6 mm inside, more than r_max + skin
