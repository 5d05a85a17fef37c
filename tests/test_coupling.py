"""The saturated (NePTune) coupling: scene checks, shrinking, fluid force, buoyancy, load transfer
(thesis §3.4, eq 4.39, §5.3.2)."""
import math

import numpy as np
import pytest

from demflow.bem.geometry import Domain, circle, rectangle
from demflow.bem.solve import Problem
from demflow.build import build
from demflow.coupling import outer_corners, shrunk_radii
from demflow.results import Results
from demflow.scene import (Discs, Fluid, LinearLaw, Material, Outputs, Scene, SceneError, Wall, WallLoad)


def box_walls(w, h):
    """Four walls counter-clockwise around the box |x| <= w/2, |y| <= h/2 (bottom, right, top, left)."""
    return [Wall("bottom", (0, -h / 2), (1, 0), -w / 2, w / 2, "w"), Wall("right", (w / 2, 0), (0, 1), -h / 2, h / 2, "w"),
            Wall("top", (0, h / 2), (-1, 0), -w / 2, w / 2, "w"), Wall("left", (-w / 2, 0), (0, -1), -h / 2, h / 2, "w")]


def scene(fluid=None, x=(0.0,), y=(0.0,), r=(0.5,), v=None, w=5.0, h=10.0, g=(0.0, -980.0), **kw):
    return Scene(name="sat", discs=Discs(list(x), list(y), list(r), "disc", velocity=v),
                 materials={"disc": Material(2.0), "w": Material()},
                 laws={("disc", "w"): LinearLaw(kn=1e5), ("disc", "disc"): LinearLaw(kn=1e5)},
                 walls=box_walls(w, h), gravity=g, dt=1e-4, fluid=fluid, outputs=Outputs(every=1),
                 allow_supercritical=True, **kw)


def test_dry_scene_builds_nothing_fluid():
    sim = build(scene())
    assert sim.fluid is None and not sim.has_external_force and sim.external_force.size == 0
    res = sim.run(5).results()
    assert len(res.fluid_forces) == 0 and len(res.pore_pressure) == 0 and "fluid_solves" not in res.meta


@pytest.mark.parametrize("fluid, words", [
    (Fluid(viscosity=0.0), "viscosity"),
    (Fluid(viscosity=1.0, density=-1.0), "density"),
    (Fluid(viscosity=1.0, stride=0), "stride"),
    (Fluid(viscosity=1.0, elements_per_disc=4), "elements_per_disc"),
    (Fluid(viscosity=1.0, min_gap=0.3), "min_gap"),
    (Fluid(viscosity=1.0, safety=2.0), "safety"),
    (Fluid(viscosity=1.0, boundary=("bottom", "right", "roof", "left")), "roof"),
    (Fluid(viscosity=1.0, boundary=("bottom", "left", "top", "right")), "clockwise"),
    (Fluid(viscosity=1.0, boundary=("bottom", "top", "right")), "parallel"),
    (Fluid(viscosity=1.0, loads=(WallLoad("top", 1.0, (1.0, -1.0)),)), "perpendicular"),
    (Fluid(viscosity=1.0, loads=(WallLoad("top", -1.0),)), r"scene\.fluid\.loads\[0\]\.force=-1\.0"),
])
def test_bad_fluid_input_is_refused_with_a_message(fluid, words):
    with pytest.raises(SceneError, match=words):
        build(scene(fluid))


def test_disc_outside_the_fluid_boundary_is_refused():
    walls = box_walls(5.0, 10.0) + [Wall("far", (0, 20.0), (1, 0), -1, 1, "w")]
    sc = scene(Fluid(viscosity=1.0, boundary=("bottom", "right", "top", "left")))
    sc.walls = walls
    sc.discs = Discs([0.0, 0.0], [0.0, 12.0], [0.5, 0.5], "disc")
    with pytest.raises(SceneError, match="outside the fluid boundary"):
        build(sc)


def test_shrinking_leaves_the_gap_and_only_shrinks_discs_that_need_it():
    corners = outer_corners(np.array([[-5.0, -5.0], [5.0, -5.0], [5.0, 5.0], [-5.0, 5.0]]),
                            np.array([[1.0, 0], [0, 1.0], [-1.0, 0], [0, -1.0]]))
    x = np.array([0.0, 1.5, -3.0, 4.5])  # 0 and 1 touch (r 0.5 + 1.0), 2 is free, 3 touches the right wall
    y = np.array([0.0, 0.0, 2.0, -2.0])
    r = np.array([0.5, 1.0, 0.7, 0.5])
    g = 0.02
    rp, gw, _ = shrunk_radii(x, y, r, corners, g)
    assert rp[2] == r[2]
    assert math.isclose(1.5 - rp[0] - rp[1], g, rel_tol=1e-12)
    assert math.isclose((r[0] - rp[0]) / (r[1] - rp[1]), r[0] / r[1], rel_tol=1e-12)  # shared ∝ radius
    assert math.isclose(5.0 - 4.5 - rp[3], g, rel_tol=1e-12)


def test_fluid_force_is_the_bem_force_of_the_same_configuration():
    """Brute force: the force the run applies at step 0 is the one of a hand-built BEM problem."""
    v = [[0.3, -1.2]]
    sim = build(scene(Fluid(viscosity=10.0, density=1.0, elements_per_disc=24, element_length=0.5, adaptive=False),
                      x=(0.4,), y=(0.7,), v=v))
    sim.run(1)
    res = sim.results()
    f0 = res.fluid_forces.iloc[0]
    dom = sim.fluid.last_solution.domain
    # the same mesh built by hand: the rectangle of the walls with the run's graded wall nodes
    outer = dom.boundaries[0]
    hole = circle((0.4, 0.7), 0.5, 24, name="d0")
    assert np.allclose(dom.boundaries[1].ends, hole.ends)
    pb = Problem(Domain([outer, hole]), 10.0)
    pb.rigid("d0", U=(0.3, -1.2), center=(0.4, 0.7))
    F = pb.solve().force("d0")
    assert np.allclose([f0.fx, f0.fy], F, rtol=1e-12, atol=0)
    assert F[1] > 0 and F[0] < 0  # drag opposes the motion
    # and a uniform fine mesh (rectangle helper) agrees to discretisation error
    pb2 = Problem(Domain([rectangle(-2.5, -5, 2.5, 5, [40, 80, 40, 80], name="box"), circle((0.4, 0.7), 0.5, 48, "d0")]), 10.0)
    pb2.rigid("d0", U=(0.3, -1.2), center=(0.4, 0.7))
    F2 = pb2.solve().force("d0")
    assert np.allclose(F, F2, rtol=0.02)


def test_buoyancy_is_minus_rho_l_a_g():
    """Eq 4.39: at rest the fluid drag is zero and the external force is the buoyancy ρ_l π R² |g| upwards."""
    sim = build(scene(Fluid(viscosity=10.0, density=1.3, adaptive=False), r=(0.5,)))
    sim.run(1)
    assert abs(sim.external_force[0, 0]) < 1e-9
    assert math.isclose(sim.external_force[0, 1], 1.3 * math.pi * 0.25 * 980.0, rel_tol=1e-12)
    # a disc lighter than the fluid rises
    sc = scene(Fluid(viscosity=1.0, density=3.0, adaptive=False))
    sim = build(sc)
    sim.run(50)
    assert sim.vy[0] > 0


def test_loaded_wall_without_contacts_hands_the_whole_load_to_the_fluid():
    """Thesis §5.3.2: with no contact on the loaded wall the fluid carries F_A; at rest the pressure is
    uniform (incompressible Stokes, no gravity) and equals F_A / L along every wall."""
    F_A, W = 1000.0, 5.0
    sim = build(scene(Fluid(viscosity=2.0, loads=(WallLoad("top", F_A, (0.0, -1.0)),), adaptive=False),
                      x=(-1.0, 1.0), y=(0.0, -2.0), r=(0.5, 0.7), g=(0.0, 0.0)))
    sim.run(1)
    res = sim.results()
    pp = res.pore_pressure
    assert set(pp.wall) == {"bottom", "right", "top", "left"}
    assert np.allclose(pp.p, F_A / W, rtol=1e-6)
    top = res.fluid_walls[res.fluid_walls.wall == "top"].iloc[0]
    assert math.isclose(top.fy, F_A, rel_tol=1e-9)  # the fluid pushes back up with F_A


def test_fluid_tables_save_and_load(tmp_path):
    sim = build(scene(Fluid(viscosity=10.0, density=1.0, adaptive=False)))
    res = sim.run(3).results()
    res.save(tmp_path / "r")
    back = Results.load(tmp_path / "r")
    for t in ("fluid_forces", "fluid_walls", "pore_pressure"):
        assert len(getattr(back, t)) == len(getattr(res, t)) > 0
    assert np.allclose(back.fluid_forces.fy, res.fluid_forces.fy)
