"""The declarative scene: what is simulated, not how.

A :class:`Scene` lists discs, walls, materials, the contact law of every material
pair, global damping, gravity, the time step, the loading protocol (wall motion
schedules and servo walls) and the outputs.  Nothing here runs: :func:`demflow.build.build`
checks a scene and turns it into a :class:`demflow.simulation.Simulation` that
allocates only what the declared physics needs.

Units are whatever consistent system the user chooses (the sources use SI, cgs and
C&S's "units"); docstrings give dimensions.  A 2D disc has unit thickness: its mass is
ρπR² [mass] with ρ [mass/length²·thickness] and its moment of inertia ½mR².
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

_IDENT = re.compile(r"^[A-Za-z][A-Za-z0-9_\-]{0,63}$")


class SceneError(ValueError):
    """A scene that cannot be built; the message names the value, the constraint and the fix."""


def check_identifier(kind: str, name: str) -> str:
    """Names (scene, material, wall) are identifiers: letters, digits, '_' and '-'.

    They may end up in engine decks (YADE decks are Python programs), so nothing else is
    accepted.
    """
    if not isinstance(name, str) or not _IDENT.match(name):
        raise SceneError(
            f"{kind} name {name!r} is not an identifier: use 1-64 characters, a letter "
            "first, then letters, digits, '_' or '-'"
        )
    return name


@dataclass(frozen=True)
class Material:
    """A material: density ρ [mass/length²] (2D: disc mass ρπR², unit thickness; 3D: sphere mass
    4/3 πR³ρ with ρ [mass/length³]); Young's modulus ``young`` E [force/length²] and Poisson's ratio
    ``poisson`` ν for the Hertz-Mindlin law (None where no such law uses the material)."""

    density: float = 0.0
    young: float | None = None
    poisson: float | None = None


@dataclass(frozen=True)
class LinearLaw:
    """Linear spring-dashpot-Coulomb law (thesis eqs 2.7-2.20, C&S eqs 8-27).

    kn, ks : normal and shear spring stiffness [force/length]
    cn, cs : normal and shear dashpot [force/(length/time)], absolute values
    friction : tan φ_μ, Coulomb coefficient (the smaller of the two materials' in C&S)
    cohesion : c [force], S_max = N tan φ + c (thesis eq 2.17)
    """

    kn: float
    ks: float = 0.0
    cn: float = 0.0
    cs: float = 0.0
    friction: float = 0.0
    cohesion: float = 0.0

    def check(self, pair: tuple[str, str]) -> None:
        for key in ("kn", "ks", "cn", "cs", "friction", "cohesion"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise SceneError(f"law {pair}: {key}={v!r} is not a finite number")
            if v < 0:
                raise SceneError(f"law {pair}: {key}={v} is negative; give {key} >= 0")
        if self.kn <= 0:
            raise SceneError(f"law {pair}: kn={self.kn} must be > 0 (a contact needs a normal spring)")


@dataclass(frozen=True)
class Box:
    """The space the discs live in: open (the default), or periodic along x and/or y.

    periodic_x : (x0, x1) [length], the period along x is x1 - x0 (None: not periodic in x)
    periodic_y : (y0, y1) [length], likewise along y
    A periodic axis wraps disc centres into [x0, x1) (image counters keep unwrapped
    displacements) and lists contacts across the boundary by minimum image; its period must be
    at least twice 2·r_max + skin.  Walls are not repeated: a floor in a box periodic along x
    should span it.
    """

    periodic_x: tuple[float, float] | None = None
    periodic_y: tuple[float, float] | None = None

    def check(self) -> None:
        for axis, b in (("x", self.periodic_x), ("y", self.periodic_y)):
            if b is None:
                continue
            try:
                lo, hi = (float(v) for v in b)
            except (TypeError, ValueError):
                raise SceneError(f"box periodic_{axis}={b!r}; give the bounds as two numbers (lo, hi)") from None
            if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
                raise SceneError(f"box periodic_{axis}=({lo}, {hi}); give finite bounds with hi > lo")

    @property
    def periodic(self) -> bool:
        return self.periodic_x is not None or self.periodic_y is not None


@dataclass(frozen=True)
class ContactModel:
    """Scene-wide choices of the contact law's variants.

    normal : "incremental" (N += kN Δn, thesis eqs 2.13/2.15, C&S eq 16/18) or
             "overlap" (N = kN δ, as YADE and LIGGGHTS compute it).
    sliding : "cs" (default; the elastic shear force is capped at μ·Fn + c with Fn the
              total normal force, dashpot included, and the shear dashpot acts only while
              not sliding: C&S "Damping", YADE, LIGGGHTS) or
              "thesis" (|S + D_S| <= S_max with S_max = |N tan φ + c|, thesis eq 2.20 note).
    """

    normal: str = "incremental"
    sliding: str = "cs"

    def check(self) -> None:
        if self.normal not in ("incremental", "overlap"):
            raise SceneError(f"contact model normal={self.normal!r}: use 'incremental' or 'overlap'")
        if self.sliding not in ("cs", "thesis"):
            raise SceneError(f"contact model sliding={self.sliding!r}: use 'cs' or 'thesis'")


@dataclass(frozen=True)
class GlobalDamping:
    """Global (ground) dashpots, thesis eqs 2.21-2.28 / C&S eqs 29-36.

    Either absolute coefficients ``C`` [force/(length/time)] and ``C_rot``
    [moment/(1/time)], or mass-proportional ``alpha`` [1/time] (C&S eq 34:
    C = αm, C* = αI).  Give one form, not both.
    """

    C: float = 0.0
    C_rot: float = 0.0
    alpha: float = 0.0

    def check(self) -> None:
        for key in ("C", "C_rot", "alpha"):
            v = getattr(self, key)
            if not math.isfinite(v) or v < 0:
                raise SceneError(f"global damping {key}={v} must be finite and >= 0")
        if self.alpha > 0 and (self.C > 0 or self.C_rot > 0):
            raise SceneError(
                "global damping: give either alpha (C&S eq 34) or C/C_rot (thesis eq 2.27), not both"
            )


@dataclass(frozen=True)
class Phase:
    """One phase of a wall's prescribed motion, lasting ``cycles`` time steps.

    velocity : (vx, vy) of the wall's reference point [length/time]
    omega : angular velocity [rad/time], counter-clockwise positive, about ``pivot``
            (default: the wall's reference point P, as in C&S Fig. 4)
    """

    cycles: int
    velocity: tuple[float, float] = (0.0, 0.0)
    omega: float = 0.0
    pivot: tuple[float, float] | None = None


@dataclass(frozen=True)
class Servo:
    """Servo control of a wall, thesis §5.5.2 eqs 5.11-5.12.

    The wall is pushed with force ``force`` [force] along ``direction`` (unit vector, the
    direction the applied load acts on the material).  Each step err = (F_A - F_C)/F_A with
    F_C the contact reaction along -direction; v = min(v_max, |G·err|)·sign(G·err) along
    ``direction``.  ``gain`` G [length/time], ``v_max`` [length/time].
    Active from step ``start`` (inclusive) on; before it the wall follows its phases.
    ``schedule`` : ((step, force), ...) changes the target: from each ``step`` on, F_A is that
    ``force`` [force] (a stress path, e.g. C&S's stage A → stage B).
    """

    force: float
    direction: tuple[float, float]
    gain: float
    v_max: float
    start: int = 0
    schedule: tuple[tuple[int, float], ...] = ()

    def force_at(self, step: int) -> float:
        """The target force F_A in effect at ``step``."""
        f = self.force
        for s, v in sorted(self.schedule):
            if step >= s:
                f = v
        return float(f)


@dataclass(frozen=True)
class Wall:
    """A finite straight wall as in C&S Fig. 4.

    The wall is the segment from A = P + h1·e to B = P + h2·e, with P = ``point`` and
    e = ``direction`` (normalised on build).  ``phases`` prescribe its motion one after
    another (after the last it holds still); ``servo`` makes it force-controlled.
    """

    name: str
    point: tuple[float, float]
    direction: tuple[float, float]
    h1: float
    h2: float
    material: str
    phases: tuple[Phase, ...] = ()
    servo: Servo | None = None


@dataclass(frozen=True)
class WallLoad:
    """An applied load on a wall of a saturated scene (thesis §5.3.2).

    The wall ``wall`` carries the applied force ``force`` F_A [force] along ``direction`` (the
    unit direction the load acts on the material, e.g. (0, -1) for a top wall).  At each fluid
    solve the unbalanced part F_A - F_C (F_C the discs' contact reaction against the load) is
    handed to the fluid as a uniform traction (F_A - F_C)/L along ``direction`` on that wall
    [force/length]; the wall's tangential velocity stays prescribed.  The wall must be
    perpendicular to ``direction`` and axis-aligned.
    """

    wall: str
    force: float
    direction: tuple[float, float] = (0.0, -1.0)


@dataclass(frozen=True)
class Fluid:
    """The pore fluid of a saturated scene (thesis §3.4, NePTune): Stokes flow solved by the BEM
    (:mod:`demflow.bem`) in the region bounded by the walls with the discs as holes.

    viscosity : μ [mass/(length·time)] (> 0)
    density : ρ_l [mass/length²] (unit thickness), for the buoyancy −ρ_l A g of eq 4.39
    boundary : the walls that bound the fluid, in counter-clockwise order around it (default:
               every wall of the scene in declaration order); consecutive walls' lines meet at
               the corners of the outer boundary
    elements_per_disc : BEM elements on each disc (an inscribed regular polygon)
    element_length : longest element on the walls [length], far from every disc (near a disc the
                     wall elements are graded down to the disc elements' length); None: the mean
                     disc radius
    min_gap : the gap [length] left between shrunk neighbours and against walls so that the fluid
              is one connected domain (thesis §3.4, §5.3.3: constant gap width, only the discs that
              need it are shrunk); None: 0.01 × the smallest radius (thesis §5.3.3: 0.05L for r = 5L)
    stride : k, the largest number of DEM steps between fluid solves (the fluid force is held
             between solves; an accuracy knob, see :mod:`demflow.coupling`)
    adaptive : shorten the stride where the drag relaxation time requires it
               (:func:`demflow.coupling.stable_stride`)
    safety : fraction of the explicit-drag stability limit 2τ used by the adaptive stride
    moments : apply the fluid moment on each disc as well as the force
    loads : applied loads handed to the fluid (:class:`WallLoad`)
    record_every : record fluid forces and wall pore pressure at every this many-th solve
    quadrature : BEM quadrature rule (0: thesis Table 4.1, -1: fine, n > 0: n-point Gauss)
    start : the step at which the liquid is added (thesis §5.3.3, §5.5.4: a dry compression, then
            the pores are filled); before it the scene runs dry, with no fluid solve
    """

    viscosity: float
    density: float = 0.0
    boundary: tuple[str, ...] | None = None
    elements_per_disc: int = 32
    element_length: float | None = None
    min_gap: float | None = None
    stride: int = 1
    adaptive: bool = True
    safety: float = 0.5
    moments: bool = True
    loads: tuple[WallLoad, ...] = ()
    record_every: int = 1
    quadrature: int = 0
    start: int = 0


@dataclass
class Discs:
    """Discs as arrays: centres (x, y) [length], radius [length], material names.

    mass : optional per-disc mass overriding ρπR² [mass]
    velocity : optional (n, 2) initial velocity; the central-difference scheme holds
               velocities at half steps, so this is v(-Δt/2) as in BALL.
    angular_velocity : optional (n,) [rad/time]
    """

    x: Sequence[float]
    y: Sequence[float]
    radius: Sequence[float]
    material: Sequence[str] | str
    mass: Sequence[float] | None = None
    velocity: Sequence[Sequence[float]] | None = None
    angular_velocity: Sequence[float] | None = None

    def __len__(self) -> int:
        return len(np.atleast_1d(self.x))


@dataclass(frozen=True)
class Outputs:
    """What the run records.

    every : record wall forces, tracked contacts and energies every this many steps
    snapshots : steps at which particle states and contact records are kept
    track_pairs : (a, b) pairs whose contact force is recorded every ``every`` steps;
                  a and b are disc indices, or ``"wall:NAME"`` for a wall
    """

    every: int = 1
    snapshots: tuple[int, ...] = ()
    track_pairs: tuple[tuple[int | str, int | str], ...] = ()


@dataclass
class Scene:
    """Everything that defines a 2D disc simulation.  Build it with :func:`demflow.build.build`.

    dt : the time step, or None for ``dt_fraction`` × 2√(m_min/k_max) (thesis §2.2.4.4)
    allow_supercritical : accept a dt above the critical estimate (refused otherwise)
    n_steps : default run length in steps (cycles)
    skin : neighbour-list margin (thesis DNTOL, eq 2.33) [length]; None = 0.2 × mean radius
    fluid : the pore fluid (:class:`Fluid`) of a saturated scene; None for a dry one
    box : the space (:class:`Box`): open by default, or periodic along x and/or y
    """

    name: str
    discs: Discs
    materials: dict[str, Material]
    laws: dict[tuple[str, str], LinearLaw]
    walls: list[Wall] = field(default_factory=list)
    contact_model: ContactModel = ContactModel()
    damping: GlobalDamping = GlobalDamping()
    gravity: tuple[float, float] = (0.0, 0.0)
    dt: float | None = None
    dt_fraction: float = 0.1
    allow_supercritical: bool = False
    n_steps: int = 1000
    skin: float | None = None
    overlap_tolerance: float = 1e-6
    outputs: Outputs = Outputs()
    description: str = ""
    fluid: Fluid | None = None  # a saturated scene (thesis §3.4); None: dry, nothing fluid is built
    box: Box = Box()

    def law_for(self, a: str, b: str) -> LinearLaw:
        """The law of a material pair, in either order; a clear error if none is declared."""
        if (a, b) in self.laws:
            return self.laws[(a, b)]
        if (b, a) in self.laws:
            return self.laws[(b, a)]
        raise SceneError(
            f"no contact law for material pair ({a!r}, {b!r}); add "
            f"laws[({a!r}, {b!r})] = LinearLaw(kn=...) to the scene"
        )
