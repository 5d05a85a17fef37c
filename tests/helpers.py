"""Small scenes for the property tests."""
import numpy as np

from demflow import (ContactModel, Discs, LinearLaw, Material, Outputs, Scene)
from demflow.cases.fixtures import box_walls as fixtures_box_walls, random_sequential_addition


def random_packing(n, seed, rmin=0.5, rmax=1.0, box=None):
    """Non-overlapping discs placed by rejection in a square box (deterministic for a seed); each
    try draws a radius in [rmin, rmax], then the centre."""
    rng = np.random.default_rng(seed)
    box = box or 3.0 * np.sqrt(n) * rmax
    x, y, r = random_sequential_addition(lambda g: g.uniform(rmin, rmax), (0.0, box, 0.0, box), rng, n=n)
    return x, y, r, box


def box_walls(box, material="wall"):
    return fixtures_box_walls(0.0, box, 0.0, box, material=material)


def gas_scene(x, y, r, v, om=None, *, ks=0.0, mu=0.0, cn=0.0, dt=None, n_steps=200, walls=(), normal="incremental",
              every=0, snapshots=()):
    law = LinearLaw(kn=1e5, ks=ks, cn=cn, friction=mu)
    return Scene(name="gas", discs=Discs(x=x, y=y, radius=r, material="g", velocity=v, angular_velocity=om),
                 materials={"g": Material(density=1.0), "wall": Material()},
                 laws={("g", "g"): law, ("g", "wall"): law}, walls=list(walls),
                 contact_model=ContactModel(normal=normal), dt=dt, n_steps=n_steps,
                 outputs=Outputs(every=every, snapshots=tuple(snapshots)))


def json_leaves(o):
    """Every leaf value of a JSON document (dicts and lists walked), for checking what a deck's data holds."""
    if isinstance(o, dict):
        for v in o.values():
            yield from json_leaves(v)
    elif isinstance(o, list):
        for v in o:
            yield from json_leaves(v)
    else:
        yield o
