"""Small scenes for the property tests."""
import numpy as np

from demflow import (ContactModel, Discs, GlobalDamping, LinearLaw, Material, Outputs, Scene, Wall)


def random_packing(n, seed, rmin=0.5, rmax=1.0, box=None):
    """Non-overlapping discs placed by rejection in a square box (deterministic for a seed)."""
    rng = np.random.default_rng(seed)
    box = box or 3.0 * np.sqrt(n) * rmax
    xs, ys, rs = [], [], []
    tries = 0
    while len(xs) < n and tries < 100000:
        tries += 1
        r = rng.uniform(rmin, rmax)
        x, y = rng.uniform(r, box - r, 2)
        if all((x - a) ** 2 + (y - b) ** 2 >= (r + c) ** 2 for a, b, c in zip(xs, ys, rs)):
            xs.append(x); ys.append(y); rs.append(r)
    return np.array(xs), np.array(ys), np.array(rs), box


def box_walls(box, material="wall"):
    return [Wall("bottom", (0.0, 0.0), (1.0, 0.0), 0.0, box, material),
            Wall("right", (box, 0.0), (0.0, 1.0), 0.0, box, material),
            Wall("top", (box, box), (-1.0, 0.0), 0.0, box, material),
            Wall("left", (0.0, box), (0.0, -1.0), 0.0, box, material)]


def gas_scene(x, y, r, v, om=None, *, ks=0.0, mu=0.0, cn=0.0, dt=None, n_steps=200, walls=(), normal="incremental",
              every=0, snapshots=()):
    law = LinearLaw(kn=1e5, ks=ks, cn=cn, friction=mu)
    return Scene(name="gas", discs=Discs(x=x, y=y, radius=r, material="g", velocity=v, angular_velocity=om),
                 materials={"g": Material(density=1.0), "wall": Material()},
                 laws={("g", "g"): law, ("g", "wall"): law}, walls=list(walls),
                 contact_model=ContactModel(normal=normal), dt=dt, n_steps=n_steps,
                 outputs=Outputs(every=every, snapshots=tuple(snapshots)))
