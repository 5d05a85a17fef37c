"""Staged protocols: a simulation continues from another's state (contacts keep their history), and
the liquid can be added at a step (thesis §5.3.3, §5.5.4: dry compression first, then saturation)."""
import numpy as np
import pytest

from demflow.build import build
from demflow.scene import Discs, Fluid, LinearLaw, Material, Outputs, Scene, Wall


def slope_scene(name="slope", friction=0.5, x=(0.0, 2.2), y=(1.0, 1.0), v=None, fluid=None):
    """Two discs resting on a floor under a tilted gravity: static friction (the shear spring's
    history) is what holds them; lose the history and they slip."""
    return Scene(name=name, discs=Discs(list(x), list(y), [1.0, 1.0], "d", velocity=v),
                 materials={"d": Material(1.0), "w": Material()},
                 laws={("d", "w"): LinearLaw(kn=1e5, ks=1e5, cn=50.0, cs=50.0, friction=friction),
                       ("d", "d"): LinearLaw(kn=1e5, ks=1e5, cn=50.0, cs=50.0, friction=friction)},
                 walls=[Wall("floor", (0, 0), (1, 0), -10, 10, "w"), Wall("right", (10, 5), (0, 1), -5, 5, "w"),
                        Wall("top", (0, 10), (-1, 0), -10, 10, "w"), Wall("left", (-10, 5), (0, -1), -5, 5, "w")],
                 gravity=(3.0, -10.0), dt=2e-4, outputs=Outputs(every=0), fluid=fluid, overlap_tolerance=0.01)


def test_continue_from_keeps_contact_history_exactly():
    one = build(slope_scene()).run(6000)
    first = build(slope_scene()).run(3000)
    second = build(slope_scene(x=first.x, y=first.y)).continue_from(first).run(3000)
    assert np.abs(second.x - one.x).max() < 1e-12 and np.abs(second.vx - one.vx).max() < 1e-12
    assert second.step == 3000 and np.abs(second.hist).max() > 0
    # control: the same positions in a fresh build lose the shear springs and the discs move
    fresh = build(slope_scene(x=first.x, y=first.y)).run(3000)
    assert np.abs(fresh.x - one.x).max() > 1e-6


def test_continue_from_refuses_other_discs():
    a = build(slope_scene())
    b = build(Scene(name="one", discs=Discs([0.0], [1.0], [1.0], "d"), materials={"d": Material(1.0), "w": Material()},
                    laws={("d", "w"): LinearLaw(kn=1e5)}, walls=slope_scene().walls, dt=2e-4))
    with pytest.raises(ValueError, match="same discs"):
        b.continue_from(a)


def test_fluid_start_runs_dry_until_the_liquid_is_added():
    fluid = Fluid(viscosity=0.5, density=0.0, elements_per_disc=16, stride=50, adaptive=False, start=400)
    wet = build(slope_scene(fluid=fluid, friction=0.0)).run(600)
    dry = build(slope_scene(friction=0.0)).run(400)
    assert wet.fluid.strides[0][0] == 400  # the first solve is at the start step
    part = build(slope_scene(fluid=fluid, friction=0.0)).run(400)
    assert np.array_equal(part.x, dry.x) and np.array_equal(part.vx, dry.vx)  # dry up to the start
    assert np.abs(wet.external_force).max() > 0
