"""The simple-shear specimen of thesis §5.4-5.6: 20 discs, their compression and the shear box.

Source values (thesis §5.4.1, Table 5.1): 3 discs R = 1.5 mm, 6 × 1.0 mm, 11 × 0.5 mm, generated
randomly in a 1 cm × 0.8 cm box; kN = kS = 1875e3, cN = cS = 34.323, φ_dd = 22°, φ_dw = 10°,
ρs = 2 g/cm³, no gravity, no global damping; loose: compressed with friction to 0.89 × 0.69 cm,
F_y = 8.1 kgF on wall 3; dense: compressed without friction, then a servo top wall to 8.1 kgF,
height 0.682 cm.

Units (stated inference).  The thesis labels forces gF but its dashpot 34.323 is exactly 5 % of
the mean over the three sizes of 2√(kN m) with kN = 1875e3 and m in grams (2√(1875e3·m) = 1029.8,
686.3, 343.1 for m = 0.1414, 0.0628, 0.0157 g; mean 686.4; 5 % = 34.32), the "5 % average critical
damping" it states: so its program used the numbers as given in one consistent system.  We do the
same: g, cm, s, and the force unit g·cm/s² that the thesis calls gF (F_y = 8100).  Unit thickness:
disc mass ρs π R².

What the lost Fig. 5.15 held, inferred and stated:
- The random arrangement: a seeded random sequential addition (largest discs first) in the
  1 × 0.8 cm box; the seed is a parameter.
- Walls 1 bottom, 2 right, 3 top, 4 left (the thesis's numbering: walls 2, 3, 4 move in, wall 1
  stays; walls 1 and 3 carry the shear forces S1, S3).
- Compression: walls 2 and 4 move in symmetrically to the stated width 0.89 cm while wall 3 is a
  servo wall (eqs 5.11-5.12) at F_y = 8.1 kgF, then a relaxation at that load.  The thesis moved
  wall 3 to a prescribed 0.69 cm for the loose array and took F_y as the force it found; with
  another random arrangement a prescribed height gives an arbitrary force, so we prescribe the
  force (as the thesis did for the dense array) and report the height and void ratio it gives.
- Shear kinematics (Figs 5.19, 5.26 lost): "the velocity of the bottom wall is deduced from the
  motion of the lateral walls because the bottom wall connections are hinged" (§5.3.3): the lateral
  walls rotate about their top ends at γ̇ and the bottom wall translates at γ̇H; wall 3 is a lid
  with no joint to the lateral walls: a servo wall (dry, constant F_y, volume changes) or fixed
  (saturated, constant volume; the unbalanced load goes to the fluid, §5.3.2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene import Discs, LinearLaw, Material, Outputs, Phase, Scene, Servo
from . import fixtures
from .shear_box import hinged_shear_phases

SIZES = ((3, 0.15), (6, 0.10), (11, 0.05))  # (count, radius [cm]), thesis Table 5.1
BOX = (1.0, 0.8)  # initial box [cm], thesis §5.4.1
KN = KS = 1875e3  # [force/cm]
CN = CS = 34.323  # [force/(cm/s)]
PHI_DD, PHI_DW = 22.0, 10.0  # friction angles [deg]
RHO_S, RHO_L, MU = 2.0, 1.0, 0.01  # g/cm³ (unit thickness: g/cm²), g/(cm·s)
FY = 8.1e3  # applied vertical force on wall 3 [force]: 8.1 kgF in the thesis's force unit
WIDTH = 0.89  # compressed width [cm]


def radii() -> np.ndarray:
    return np.concatenate([np.full(n, r) for n, r in SIZES])


def solid_area() -> float:
    return float(np.pi * np.sum(radii() ** 2))


def void_ratio(width: float, height: float) -> float:
    """e = void area / solid area (thesis §5.5.1: 0.89 × 0.69 cm gives 26.11 %)."""
    a = solid_area()
    return (width * height - a) / a


def damping_ratio_mean() -> float:
    """c / (mean over the three sizes of 2√(kN m)): the thesis's "5 % average critical damping"."""
    m = RHO_S * np.pi * np.array([r for _, r in SIZES]) ** 2
    return float(CN / np.mean(2.0 * np.sqrt(KN * m)))


def initial_discs(seed: int):
    """Seeded random sequential addition of the 20 discs (largest first) in the 1 × 0.8 cm box; an
    arrangement can jam (area fraction 0.61): it starts again, same stream, up to 1000 times."""
    W, H = BOX
    x, y, r = fixtures.random_sequential_addition(radii(), (0.0, W, 0.0, H), np.random.default_rng(seed), gap=1e-6,
                                                  tries=20_000, restarts=999)
    return x, y, r


def laws(friction: bool) -> dict:
    tdd = math.tan(math.radians(PHI_DD)) if friction else 0.0
    tdw = math.tan(math.radians(PHI_DW)) if friction else 0.0
    return {("disc", "disc"): LinearLaw(kn=KN, ks=KS, cn=CN, cs=CS, friction=tdd),
            ("disc", "wall"): LinearLaw(kn=KN, ks=KS, cn=CN, cs=CS, friction=tdw)}


def box_walls(x0, x1, y0, y1, phases=None, servos=None):
    """Walls 1-4 (bottom, right, top, left), counter-clockwise, long enough for the whole protocol."""
    return fixtures.box_walls(x0, x1, y0, y1, half_length=1.0, phases=phases, servos=servos)


@dataclass
class Specimen:
    """A compressed specimen: the simulation at the end of compression and relaxation."""

    kind: str  # "loose" | "dense"
    sim: object
    width: float
    height: float
    seed: int

    @property
    def void_ratio(self) -> float:
        return void_ratio(self.width, self.height)

    @property
    def fy(self) -> float:
        """The vertical force on wall 3 at the end of relaxation: the applied F_y of the shear
        (thesis §5.5.1: "taken as the force at the end of the relaxation period")."""
        return float(self.sim.wall_force[self.sim.wall_names.index("top"), 1])


def scene(name, x, y, r, walls, friction, density_scale=1.0, dt=None, n_steps=0, outputs=Outputs(every=0),
          fluid=None) -> Scene:
    return Scene(name=name, discs=Discs(x=np.asarray(x), y=np.asarray(y), radius=r, material="disc"),
                 materials={"disc": Material(RHO_S * density_scale), "wall": Material()},
                 laws=laws(friction), walls=walls, dt=dt, n_steps=n_steps, outputs=outputs, fluid=fluid,
                 overlap_tolerance=0.2, description="thesis §5.4-5.6 simple shear",
                 # Δt = 0.1 × 2√(m_min/kN) is 1.06× the safe estimate (integrate.safe_time_step: six smallest
                 # discs around a smallest one, ζ = 0.14 dashpots); the 20-disc specimens are looser (issue 17)
                 allow_unsafe_dt=True)


def compress(kind: str, seed: int, *, speed: float = 0.05, relax_time: float = 0.4, gain: float = 0.5,
             v_max: float = 0.2, density_scale: float = 1.0, chunk: int = 100) -> Specimen:
    """Compression and relaxation (thesis §5.5.1 loose: with friction; §5.6.1.1 dense: without).

    Walls 2, 3 and 4 move in (wall 3 at ``speed`` [cm/s], walls 2 and 4 at half of it, the
    thesis's ratio: 0.8 → 0.69 cm while 1 → 0.89 cm) until the force on wall 3 reaches F_y;
    then ``relax_time`` [s] of relaxation: loose, all walls held (the thesis then takes F_y as the
    force at the end of relaxation: :attr:`Specimen.fy`); dense, frictionless, wall 3 a servo wall
    at F_y (§5.6.1.1).  Contact history is kept across the stages (Simulation.continue_from).
    """
    from ..build import build

    x, y, r = initial_discs(seed)
    W, H = BOX
    friction = kind == "loose"
    probe = build(scene("probe", x, y, r, box_walls(0, W, 0, H), friction, density_scale))
    dt = probe.dt
    n_max = int(round(0.5 * H / (speed * dt)))
    phases = {"right": (Phase(n_max, velocity=(-0.5 * speed, 0.0)),),
              "left": (Phase(n_max, velocity=(0.5 * speed, 0.0)),),
              "top": (Phase(n_max, velocity=(0.0, -speed)),)}
    sim = build(scene(f"simple-shear-{kind}-compression", x, y, r, box_walls(0, W, 0, H, phases), friction,
                      density_scale, dt=dt, n_steps=n_max))
    top = sim.wall_names.index("top")
    fixtures.run_until(sim, lambda s: s.wall_force[top, 1] >= FY, max_step=n_max, chunk=chunk,
                       what=f"compression of seed {seed}: the force on wall 3 reaching F_y = {FY}")
    P = dict(zip(sim.wall_names, zip(sim.wpx, sim.wpy)))
    box = (float(P["left"][0]), float(P["right"][0]), float(P["bottom"][1]), float(P["top"][1]))
    servos = {"top": Servo(FY, (0.0, -1.0), gain, v_max)} if kind == "dense" else {}
    n_relax = int(round(relax_time / dt))
    relax = build(scene(f"simple-shear-{kind}-relaxation", sim.x, sim.y, r, box_walls(*box, servos=servos), friction,
                        density_scale, dt=dt, n_steps=n_relax)).continue_from(sim).run()
    P = dict(zip(relax.wall_names, zip(relax.wpx, relax.wpy)))
    return Specimen(kind, relax, float(P["right"][0] - P["left"][0]), float(P["top"][1] - P["bottom"][1]), seed)


def shear_scene(spec: Specimen, saturated: bool, *, rate: float = 0.1, gamma_max: float = 0.105,
                gain: float = 0.5, v_max: float = 0.2, every_gamma: float = 2e-4, snapshots_at=(0.049, 0.105),
                density_scale: float = 1.0, fluid_kw=None) -> Scene:
    """The shear stage from a compressed specimen (continue with ``build(scene).continue_from(spec.sim)``).

    Walls 2 and 4 rotate about their top ends at γ̇ = ``rate`` [1/s] (counter-clockwise: their lower
    ends move in +x), wall 1 translates at γ̇H in +x, until γ = ``gamma_max``.  Dry: wall 3 is a
    servo lid at F_y.  Saturated: wall 3 is fixed (constant volume) and the liquid (μ = 0.01) takes
    the unbalanced load F_y − F_C as a traction on it (thesis §5.3.2, :class:`WallLoad`).
    ``density_scale`` multiplies the disc density for the shear (a quasi-static run's speed knob,
    thesis §5.5.3.1: inertia is negligible, so a denser disc allows a larger Δt); Δt is then
    0.1 × 2√(m_min/k).  Wall forces are recorded every ``every_gamma`` of shear strain.
    """
    from ..scene import Fluid, WallLoad

    sim = spec.sim
    P = dict(zip(sim.wall_names, zip(sim.wpx, sim.wpy)))
    x0, x1 = float(P["left"][0]), float(P["right"][0])
    y0, y1 = float(P["bottom"][1]), float(P["top"][1])
    H = y1 - y0
    dt = sim.dt * math.sqrt(density_scale)
    n = int(round(gamma_max / (rate * dt)))
    every = max(1, int(round(every_gamma / (rate * dt))))
    phases = hinged_shear_phases(x0, x1, y1, H, rate, n)
    servos = {} if saturated else {"top": Servo(spec.fy, (0.0, -1.0), gain, v_max)}
    snaps = tuple(sorted({0, n} | {int(round(g / (rate * dt))) for g in snapshots_at if g <= gamma_max}))
    fluid = None
    if saturated:
        kw = dict(viscosity=MU, density=RHO_L, loads=(WallLoad("top", spec.fy),))
        kw.update(fluid_kw or {})
        fluid = Fluid(**kw)
    scale = sim.scene.materials["disc"].density / RHO_S * density_scale
    return scene(f"simple-shear-{spec.kind}-{'saturated' if saturated else 'dry'}", sim.x, sim.y, sim.r,
                 box_walls(x0, x1, y0, y1, phases, servos), True, scale, dt=dt, n_steps=n,
                 outputs=Outputs(every=every, snapshots=snaps), fluid=fluid)
