"""A seeded dense random packing of C&S's 197 photoelastic discs in a four-wall box.

C&S digitised the disc positions of De Josselin de Jong & Verruijt's photograph (Fig. 10a); the
figure is lost, so demflow generates a packing with the same size distribution (C&S
"Verification test": 6 × R40, 7 × 35, 16 × 30, 33 × 25, 33 × 20, 36 × 18, 28 × 15, 38 × 10,
density 2000).  The method, deterministic for a given seed:

1. random sequential addition, largest discs first, uniformly in a square box at area
   fraction ``phi_rsa`` (no overlaps; ``numpy.random.default_rng(seed)``), then the order of the
   discs is shuffled with the same generator (so ids do not follow size);
2. *fast approach*: the four walls move inward at ``approach_speed`` until the area fraction
   reaches ``phi_approach`` (just below jamming), frictionless discs with contact dashpots;
3. *servo relaxation*: each wall becomes a servo wall (thesis eqs 5.11-5.12) pushing with
   ``F0`` until the frictionless assembly jams under an isotropic load;
4. *hold*: the walls stop where the servo left them and the assembly comes to rest (contact
   dashpots only).

No global damping is used: a mass-proportional drag lets a wall that pushes slowly through a
loose assembly build "forces" that are only drag (measured: with ζ_global = 0.3 the seed-1
packing held F0 at area fraction 0.80 and fell apart, every contact opening, when released
between fixed walls; with contact dashpots only it jams at 0.817 and keeps its contacts).

The packing is frictionless-jammed (dense, isotropic); the case's friction applies from the
first loading step on.  The result is returned as arrays (positions, radii, wall lines) with
the state's contact forces at F0 (overlaps ≈ F0/kn per contact, below 1e-3 R).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Discs, LinearLaw, Material, Outputs, Phase, Scene, Servo
from . import fixtures
from .fixtures import WALLS  # C&S walls 1-4 (inferred from the signs of Tables 1-3)

SIZES = ((40.0, 6), (35.0, 7), (30.0, 16), (25.0, 33), (20.0, 33), (18.0, 36), (15.0, 28), (10.0, 38))
DENSITY = 2000.0
KN = 1.5e9
INWARD = {"bottom": (0.0, 1.0), "right": (-1.0, 0.0), "top": (0.0, -1.0), "left": (1.0, 0.0)}


def radii() -> np.ndarray:
    """The 197 radii of C&S, largest first."""
    return np.concatenate([np.full(n, r) for r, n in SIZES])


def ref_mass() -> float:
    """Mass of an R = 20 disc (the median size), used to scale dashpots [mass]."""
    return DENSITY * np.pi * 20.0 ** 2


def min_mass() -> float:
    return DENSITY * np.pi * min(r for r, _ in SIZES) ** 2


@dataclass
class Packing:
    """Disc centres and radii, the box [x0, x1] × [y0, y1] the walls form, and how it was made."""

    x: np.ndarray
    y: np.ndarray
    r: np.ndarray
    box: tuple[float, float, float, float]
    seed: int
    F0: float
    steps: int

    @property
    def area_fraction(self) -> float:
        x0, x1, y0, y1 = self.box
        return float(np.pi * np.sum(self.r ** 2) / ((x1 - x0) * (y1 - y0)))


def random_sequential_addition(r, phi, rng):
    """Place discs of radii ``r`` (in the given order) without overlap in a square box.

    Returns x, y and the box side L [length] with πΣr²/L² = phi (:func:`.fixtures.random_sequential_addition`).
    """
    L = float(np.sqrt(np.pi * np.sum(r * r) / phi))
    x, y, _ = fixtures.random_sequential_addition(r, (0.0, L, 0.0, L), rng)
    return x, y, L


def box_walls(x0, x1, y0, y1, material="wall", phases=None, servos=None):
    """Four walls (C&S 1-4: bottom, right, top, left) long enough to close the box at any stage."""
    return fixtures.box_walls(x0, x1, y0, y1, half_length=1.5 * max(x1 - x0, y1 - y0), counter_clockwise=False,
                              material=material, phases=phases, servos=servos)


def random_packing(seed: int, *, phi_rsa: float = 0.5, phi_approach: float = 0.80, approach_speed: float = 1.0,
                   F0: float = 1e7, servo_gain: float = 0.02, relax_steps: int = 300_000,
                   hold_steps: int = 20_000, zeta_contact: float = 0.1) -> Packing:
    """The seeded dense packing (module docstring).  Units: C&S's "units" throughout.

    F0 : isotropic wall force at the end [force]; servo_gain: G = v_max of eq 5.12 [length/time],
    kept below F0/(kn Δt) so one servo step changes a contact force by less than F0.
    """
    from ..build import build

    rng = np.random.default_rng(seed)
    r = radii()
    x, y, L = random_sequential_addition(r, phi_rsa, rng)
    order = rng.permutation(len(r))
    x, y, r = x[order], y[order], r[order]
    area = float(np.pi * np.sum(r * r))
    L1 = float(np.sqrt(area / phi_approach))
    dt = 0.1 * 2.0 * np.sqrt(min_mass() / KN)
    n1 = int((L - L1) / 2.0 / (approach_speed * dt))
    m = ref_mass()
    law = LinearLaw(kn=KN, ks=0.0, cn=2.0 * zeta_contact * np.sqrt(m * KN), friction=0.0)
    phases = {w: (Phase(n1, velocity=tuple(approach_speed * np.asarray(INWARD[w]))),) for w in WALLS}
    servos = {w: Servo(F0, INWARD[w], servo_gain, servo_gain, start=n1) for w in WALLS}
    box = (0.0, L, 0.0, L)
    for stage, (n, walls) in enumerate(((n1 + relax_steps, dict(phases=phases, servos=servos)), (hold_steps, {}))):
        scene = Scene(name=f"photoelastic-packing-{seed}", discs=Discs(x=x, y=y, radius=r, material="disc"),
                      materials={"disc": Material(DENSITY), "wall": Material()},
                      laws={("disc", "disc"): law, ("disc", "wall"): law}, walls=box_walls(*box, **walls),
                      contact_model=_overlap_model(), dt=dt, n_steps=n, overlap_tolerance=1e-3,
                      outputs=Outputs(every=0, snapshots=(n,)))
        sim = build(scene).run(threads=1)
        res = sim.results()
        p = res.particles
        p = p[p.step == n].sort_values("id")
        x, y = p.x.to_numpy().copy(), p.y.to_numpy().copy()
        P = dict(zip(sim.wall_names, zip(sim.wpx, sim.wpy)))  # wall reference points now
        box = (float(P["left"][0]), float(P["right"][0]), float(P["bottom"][1]), float(P["top"][1]))
    return Packing(x=x, y=y, r=r.copy(), box=box, seed=seed, F0=F0, steps=n1 + relax_steps + hold_steps)


def _overlap_model():
    from ..scene import ContactModel

    return ContactModel(normal="overlap")
