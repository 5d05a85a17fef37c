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
import numbers
import re
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_\-]{0,63}")  # matched in full (re.fullmatch: no trailing newline)
_IDENT_RULE = "use 1-64 characters, a letter first, then letters, digits, '_' or '-'"


class SceneError(ValueError):
    """A scene that cannot be built; the message names the field, the value, the constraint and the fix."""


class EnergyBalanceWarning(UserWarning):
    """A chunk's energy balance did not close (an unstable step) in a scene with ``energy_check="warn"``."""


class UnsafeTimeStepWarning(UserWarning):
    """A scene runs with a time step above the safe critical estimate because it asked to
    (``allow_supercritical=True``)."""


class PeriodicMeshWarning(UserWarning):
    """A triangle mesh of a 3D scene comes within a particle's reach of a periodic boundary (or crosses it):
    mesh contacts take no periodic image, so a particle wrapped across that boundary meets the mesh as it lies
    on the other side, not as its image would."""


def check_identifier(kind: str, name: str) -> str:
    """Names (scene, material, wall) are identifiers: letters, digits, '_' and '-'.

    They may end up in engine decks (YADE decks are Python programs), so nothing else is
    accepted.
    """
    if not isinstance(name, str) or not _IDENT.fullmatch(name):
        raise SceneError(f"{kind} name {name!r} is not an identifier: {_IDENT_RULE}")
    return name


# ---------------------------------------------------------------------------- field checks
# Every check names the field by its dotted path from the scene (``scene.walls[2].servo.v_max``),
# the value, the rule it breaks and the fix, and returns the value in its plain Python form.

def is_number(v) -> bool:
    """A real number: int, float or a NumPy integer/floating scalar, never a bool."""
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))


def type_phrase(v) -> str:
    """'a str', 'an int': the type of ``v`` with its article, for messages."""
    name = type(v).__name__
    return f"{'an' if name[0] in 'aeiou' else 'a'} {name}"


def _bounds_text(gt, ge, lt, le) -> str:
    parts = [f"> {gt:g}" if gt is not None else f">= {ge:g}" if ge is not None else "",
             f"< {lt:g}" if lt is not None else f"<= {le:g}" if le is not None else ""]
    return " and ".join(p for p in parts if p)


def check_number(path: str, v, *, gt=None, ge=None, lt=None, le=None, unit: str = "") -> float:
    """A finite real number within the given bounds (gt: >, ge: >=, lt: <, le: <=)."""
    rule = _bounds_text(gt, ge, lt, le)
    fix = f"give a finite number{' ' + rule if rule else ''}{' [' + unit + ']' if unit else ''}"
    if not is_number(v):
        raise SceneError(f"{path}={v!r} is {type_phrase(v)}, not a number; {fix}")
    try:
        f = float(v)
    except OverflowError:
        f = math.inf
    if not math.isfinite(f):
        raise SceneError(f"{path}={v!r} is not finite; {fix}")
    if ((gt is not None and not f > gt) or (ge is not None and not f >= ge) or (lt is not None and not f < lt)
            or (le is not None and not f <= le)):
        raise SceneError(f"{path}={v!r} breaks the rule {path.rsplit('.', 1)[-1]} {rule}; {fix}")
    return f


# step counts and other whole numbers stay far below what an int64 step counter holds
MAX_WHOLE = 2 ** 62


def check_whole(path: str, v, *, ge: int = 0, le: int = MAX_WHOLE, allowed=None) -> int:
    """A whole number (an int, or a float with an integral value) with ge <= v <= le (and in
    ``allowed`` when given)."""
    fix = (f"give one of {list(allowed)}" if allowed is not None else
           f"give a whole number >= {ge}" + (f" and <= {le}" if le != MAX_WHOLE else ""))
    if not is_number(v):
        raise SceneError(f"{path}={v!r} is {type_phrase(v)}, not a whole number; {fix}")
    if isinstance(v, (numbers.Integral, np.integer)):
        k = int(v)
    else:
        f = float(v)
        if not (math.isfinite(f) and f.is_integer()):
            raise SceneError(f"{path}={v!r} is not a whole number; {fix}")
        k = int(f)
    if k > le:
        why = "the largest count demflow takes" if le == MAX_WHOLE else "the largest allowed here"
        raise SceneError(f"{path}={v!r} is above {le}, {why}; give a whole number from {ge} to {le}")
    if k < ge or (allowed is not None and k not in allowed):
        raise SceneError(f"{path}={v!r} is out of range; {fix}")
    return k


def check_flag(path: str, v) -> bool:
    """A bool (True or False; NumPy's bool too), not a number or a string."""
    if not isinstance(v, (bool, np.bool_)):
        raise SceneError(f"{path}={v!r} is {type_phrase(v)}, not a bool; give True or False")
    return bool(v)


def check_choice(path: str, v, options) -> str:
    """One of ``options`` (strings), compared exactly."""
    if not (isinstance(v, str) and v in options):
        raise SceneError(f"{path}={v!r} is not one of {list(options)}; give one of them")
    return v


def check_name(path: str, v) -> str:
    """An identifier (see :func:`check_identifier`), matched in full."""
    if not isinstance(v, str) or not _IDENT.fullmatch(v):
        raise SceneError(f"{path}={v!r} is not an identifier: {_IDENT_RULE}")
    return v


def check_items(path: str, v, *, kinds=(tuple, list)) -> list:
    """A sequence (tuple or list; never a string), as a list."""
    if isinstance(v, np.ndarray) and v.ndim == 1 and np.ndarray in kinds:
        return list(v)
    if not isinstance(v, tuple(k for k in kinds if k is not np.ndarray)):
        raise SceneError(f"{path}={v!r} is {type_phrase(v)}; give a "
                         f"{' or '.join(k.__name__ for k in kinds)} of entries")
    return list(v)


def check_vector(path: str, v, n: int = 2, *, nonzero: bool = False, unit: str = "") -> tuple:
    """A tuple of ``n`` finite numbers (a non-zero vector of finite length with ``nonzero``)."""
    what = f"{n} finite numbers" + (", not all zero" if nonzero else "") + (f" [{unit}]" if unit else "")
    if isinstance(v, np.ndarray):
        v = tuple(v.tolist()) if v.ndim == 1 else v
    if not isinstance(v, (tuple, list)) or len(v) != n:
        raise SceneError(f"{path}={v!r} is not a vector of {n} numbers; give {what}")
    out = tuple(check_number(f"{path}[{k}]", c) for k, c in enumerate(v))
    if nonzero and not (0.0 < math.hypot(*out) < math.inf):
        raise SceneError(f"{path}={v!r} has length {math.hypot(*out):g}; give {what}, with a finite length")
    return out


def check_type(path: str, v, cls, what: str = ""):
    """``v`` is an instance of ``cls``."""
    if not isinstance(v, cls):
        names = " or ".join(c.__name__ for c in (cls if isinstance(cls, tuple) else (cls,)))
        raise SceneError(f"{path}={v!r} is {type_phrase(v)}; give a {names}{what}")
    return v


@dataclass(frozen=True)
class Material:
    """A material: density ρ [mass/length²] (2D: disc mass ρπR², unit thickness; 3D: sphere mass
    4/3 πR³ρ with ρ [mass/length³]); Young's modulus ``young`` E [force/length²] and Poisson's ratio
    ``poisson`` ν for the Hertz-Mindlin law (None where no such law uses the material)."""

    density: float = 0.0
    young: float | None = None
    poisson: float | None = None

    def check(self, path: str) -> None:
        check_number(f"{path}.density", self.density, ge=0.0, unit="mass/length²")
        if self.young is not None and not (is_number(self.young) and float(self.young) == math.inf):
            check_number(f"{path}.young", self.young, gt=0.0, unit="force/length²; inf: a rigid wall")
        if self.poisson is not None:
            check_number(f"{path}.poisson", self.poisson, gt=-1.0, lt=0.5)


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
        """``pair`` is the law's key in scene.laws; the message names scene.laws[pair].<field>."""
        path = f"scene.laws[{pair!r}]"
        check_number(f"{path}.kn", self.kn, gt=0.0, unit="force/length; a contact needs a normal spring")
        for key, unit in (("ks", "force/length"), ("cn", "force·time/length"), ("cs", "force·time/length"),
                          ("friction", "tan φ"), ("cohesion", "force")):
            check_number(f"{path}.{key}", getattr(self, key), ge=0.0, unit=unit)


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

    def check(self, path: str = "scene.box") -> None:
        for axis, b in (("x", self.periodic_x), ("y", self.periodic_y)):
            if b is None:
                continue
            lo, hi = check_vector(f"{path}.periodic_{axis}", b, 2, unit="length")
            if not hi > lo:
                raise SceneError(f"{path}.periodic_{axis}={b!r} has hi <= lo; give finite bounds (lo, hi) with hi > lo")

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

    def check(self, path: str = "scene.contact_model") -> None:
        check_choice(f"{path}.normal", self.normal, ("incremental", "overlap"))
        check_choice(f"{path}.sliding", self.sliding, ("cs", "thesis"))


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

    def check(self, path: str = "scene.damping") -> None:
        for key, unit in (("C", "force·time/length"), ("C_rot", "force·length·time"), ("alpha", "1/time")):
            check_number(f"{path}.{key}", getattr(self, key), ge=0.0, unit=unit)
        if self.alpha > 0 and (self.C > 0 or self.C_rot > 0):
            raise SceneError(
                f"{path}: alpha={self.alpha!r} together with C={self.C!r}, C_rot={self.C_rot!r}; give either "
                "alpha (C&S eq 34) or C/C_rot (thesis eq 2.27), not both"
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

    def check(self, path: str) -> None:
        check_whole(f"{path}.cycles", self.cycles)
        check_vector(f"{path}.velocity", self.velocity, 2, unit="length/time")
        check_number(f"{path}.omega", self.omega, unit="rad/time")
        if self.pivot is not None:
            check_vector(f"{path}.pivot", self.pivot, 2, unit="length")


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

    def check(self, path: str) -> None:
        check_number(f"{path}.force", self.force, gt=0.0, unit="force")
        check_vector(f"{path}.direction", self.direction, 2, nonzero=True)
        check_number(f"{path}.gain", self.gain, gt=0.0, unit="length/time")
        check_number(f"{path}.v_max", self.v_max, gt=0.0, unit="length/time")
        check_whole(f"{path}.start", self.start)
        for k, entry in enumerate(check_items(f"{path}.schedule", self.schedule)):
            if not (isinstance(entry, (tuple, list)) and len(entry) == 2):
                raise SceneError(f"{path}.schedule[{k}]={entry!r} is not a (step, force) pair; give "
                                 "(whole step >= 0, force > 0)")
            check_whole(f"{path}.schedule[{k}].step", entry[0])
            check_number(f"{path}.schedule[{k}].force", entry[1], gt=0.0, unit="force")

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

    def check(self, path: str, materials) -> None:
        """Fields of one wall (``materials``: the scene's declared material names)."""
        check_name(f"{path}.name", self.name)
        check_vector(f"{path}.point", self.point, 2, unit="length")
        check_vector(f"{path}.direction", self.direction, 2, nonzero=True)
        h1 = check_number(f"{path}.h1", self.h1, unit="length")
        h2 = check_number(f"{path}.h2", self.h2, unit="length")
        if not h1 < h2:
            raise SceneError(f"{path}.h1={self.h1!r}, {path}.h2={self.h2!r} (wall {self.name!r}); need h1 < h2 "
                             "(the endpoints are P + h1·e and P + h2·e)")
        if not (isinstance(self.material, str) and self.material in materials):
            raise SceneError(f"{path}.material={self.material!r} (wall {self.name!r}) is not declared; add it to "
                             f"scene.materials (declared: {sorted(materials)})")
        for k, ph in enumerate(check_items(f"{path}.phases", self.phases)):
            check_type(f"{path}.phases[{k}]", ph, Phase)
            ph.check(f"{path}.phases[{k}]")
        if self.servo is not None:
            check_type(f"{path}.servo", self.servo, Servo, " or None")
            self.servo.check(f"{path}.servo")


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

    def check(self, path: str) -> None:
        check_name(f"{path}.wall", self.wall)
        check_number(f"{path}.force", self.force, gt=0.0, unit="force")
        check_vector(f"{path}.direction", self.direction, 2, nonzero=True)


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

    def check(self, path: str = "scene.fluid") -> None:
        """Every field on its own (the walls it names and its geometry are checked by build)."""
        check_number(f"{path}.viscosity", self.viscosity, gt=0.0, unit="mass/(length·time)")
        check_number(f"{path}.density", self.density, ge=0.0, unit="mass/length²")
        if self.boundary is not None:
            for k, b in enumerate(check_items(f"{path}.boundary", self.boundary)):
                check_name(f"{path}.boundary[{k}]", b)
        check_whole(f"{path}.elements_per_disc", self.elements_per_disc, ge=8)
        for key in ("element_length", "min_gap"):
            if getattr(self, key) is not None:
                check_number(f"{path}.{key}", getattr(self, key), gt=0.0, unit="length")
        check_whole(f"{path}.stride", self.stride, ge=1)
        check_flag(f"{path}.adaptive", self.adaptive)
        check_number(f"{path}.safety", self.safety, gt=0.0, le=1.0)
        check_flag(f"{path}.moments", self.moments)
        for k, ld in enumerate(check_items(f"{path}.loads", self.loads)):
            check_type(f"{path}.loads[{k}]", ld, WallLoad)
            ld.check(f"{path}.loads[{k}]")
        check_whole(f"{path}.record_every", self.record_every, ge=1)
        check_whole(f"{path}.quadrature", self.quadrature, ge=-1, allowed=(0, -1, 1, 2, 4, 8, 16, 32, 64))
        check_whole(f"{path}.start", self.start)


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


# Superquadric exponent range (Miyata §2.3: "1 < n <= 10", smooth convex shapes)
SUPERQUADRIC_N_MIN = 1.0  # exclusive
SUPERQUADRIC_N_MAX = 10.0


@dataclass
class Superquadrics:
    """2D superquadric particles |x/a|^n + |y/b|^n <= 1 in their body frame (Miyata eq 34), the
    shape family that :func:`demflow.build.build` runs on :mod:`demflow.simulation_sq2d` when
    ``scene.discs`` is one of these.

    x, y : centroids [length]; a, b : semi-axes along the body's x and y [length] (> 0);
    n : exponent, 1 < n <= 10 (n = 2, a = b: a disc of radius a); theta : orientation of the body's
    x axis [rad] (default 0); material : one name or one per particle; mass : optional, overriding
    ρ·area (the moment of inertia is scaled with it); velocity (n, 2) at -Δt/2 [length/time];
    angular_velocity [rad/time].
    restitution : e in (0, 1], Miyata eq 17: every contact (walls too, m* = m there) gets the normal
                  dashpot c_n = 2 ln(1/e) √(k_n m*/(π² + ln²(1/e))) on top of the law's cn; None: none.
    tolerance : Brent's tolerance on the surface parameter α [rad] (a speed-accuracy knob).
    window : half-width of the warm-start bracket around the last step's α [rad].
    max_overlap : a run blows up (BlowUpError) when an overlap exceeds this fraction of the pair's
                  smaller semi-axis (default 0.5, as the disc cycle's half a radius).
    """

    x: Sequence[float]
    y: Sequence[float]
    a: Sequence[float]
    b: Sequence[float]
    n: Sequence[float]
    material: Sequence[str] | str
    theta: Sequence[float] | None = None
    mass: Sequence[float] | None = None
    velocity: Sequence[Sequence[float]] | None = None
    angular_velocity: Sequence[float] | None = None
    restitution: float | None = None
    tolerance: float = 1e-9
    window: float = math.pi / 8
    max_overlap: float = 0.5

    def __len__(self) -> int:
        return len(np.atleast_1d(self.x))

    def check(self, path: str) -> None:
        """The per-particle shape fields and the knobs, each entry by its path (``scene.discs.n[3]``).
        The arrays (lengths, materials, masses, velocities) are checked by the build."""
        # x sets the count: checked first, so that a bad x is named as itself, not as a length mismatch
        if isinstance(self.x, np.ndarray) and self.x.ndim != 1:
            raise SceneError(f"{path}.x is an array of shape {self.x.shape}; give a 1-D list or array of numbers, "
                             "one centroid x per particle")
        xs = check_items(f"{path}.x", self.x, kinds=(tuple, list, np.ndarray))
        for k, e in enumerate(xs):
            check_number(f"{path}.x[{k}]", e, unit="length")
        count = len(xs)
        for key, rule, unit in (("a", dict(gt=0.0), "length"), ("b", dict(gt=0.0), "length"),
                                ("n", dict(gt=SUPERQUADRIC_N_MIN, le=SUPERQUADRIC_N_MAX),
                                 "Miyata §2.3: smooth convex superquadrics, 1 < n <= 10")):
            v = getattr(self, key)
            items = check_items(f"{path}.{key}", v, kinds=(tuple, list, np.ndarray))
            if len(items) != count:
                raise SceneError(f"{path}.{key} has {len(items)} entries for {count} particles ({path}.x has "
                                 f"{count}); give one per particle")
            for k, e in enumerate(items):
                check_number(f"{path}.{key}[{k}]", e, unit=unit, **rule)
        if self.restitution is not None:
            check_number(f"{path}.restitution", self.restitution, gt=0.0, le=1.0, unit="Miyata eq 17")
        check_number(f"{path}.tolerance", self.tolerance, gt=0.0, lt=1.0, unit="rad")
        check_number(f"{path}.window", self.window, gt=0.0, le=math.pi, unit="rad")
        check_number(f"{path}.max_overlap", self.max_overlap, gt=0.0, lt=1.0, unit="fraction of the smaller semi-axis")


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

    def check(self, path: str = "scene.outputs") -> None:
        """Every field on its own (build checks the tracked bodies against the scene's discs and walls)."""
        check_whole(f"{path}.every", self.every)
        seen = {}
        for k, s in enumerate(check_items(f"{path}.snapshots", self.snapshots, kinds=(tuple, list, np.ndarray))):
            step = check_whole(f"{path}.snapshots[{k}]", s)
            if step in seen:
                raise SceneError(f"{path}.snapshots[{k}]={s!r} repeats snapshots[{seen[step]}]: a step's snapshot would "
                                 "be kept twice (its rows doubled in the tables); give each step once")
            seen[step] = k
        for k, pair in enumerate(check_items(f"{path}.track_pairs", self.track_pairs)):
            if not (isinstance(pair, (tuple, list)) and len(pair) == 2):
                raise SceneError(f"{path}.track_pairs[{k}]={pair!r} is not a pair (a, b); give two bodies, each a "
                                 "disc index or 'wall:NAME'")


@dataclass
class Scene:
    """Everything that defines a 2D disc simulation.  Build it with :func:`demflow.build.build`.

    discs : the particles: :class:`Discs`, or :class:`Superquadrics` (the 2D superquadric shape family,
            run by :mod:`demflow.simulation_sq2d`)

    dt : the time step, or None for ``dt_fraction`` × 2√(m_min/k_max) (thesis §2.2.4.4)
    allow_supercritical : accept a dt above the critical estimates (refused otherwise)
    allow_unsafe_dt : accept a dt above the safe critical estimate of a packing
        (:func:`demflow.integrate.safe_time_step`: several contacts per disc, rotations coupled by the
        shear springs, dashpots) but below the single-spring one, with an UnsafeTimeStepWarning; for a
        scene whose packing is known to be looser than the estimate's worst case (the energy check
        still stops a run that grows unstable: BlowUpError)
    energy_check : what a chunk whose energy balance does not close does (issue 17: the steps created
        energy, an unstable step): "raise" BlowUpError with the last good state (default), or "warn"
        (EnergyBalanceWarning, the run goes on: for a shipped case known to be unstable whose results are
        kept until its owner decides)
    n_steps : default run length in steps (cycles)
    skin : neighbour-list margin (thesis DNTOL, eq 2.33) [length]; None = 0.2 × mean radius
    fluid : the pore fluid (:class:`Fluid`) of a saturated scene; None for a dry one
    box : the space (:class:`Box`): open by default, or periodic along x and/or y
    """

    name: str
    discs: Discs | Superquadrics
    materials: dict[str, Material]
    laws: dict[tuple[str, str], LinearLaw]
    walls: list[Wall] = field(default_factory=list)
    contact_model: ContactModel = ContactModel()
    damping: GlobalDamping = GlobalDamping()
    gravity: tuple[float, float] = (0.0, 0.0)
    dt: float | None = None
    dt_fraction: float = 0.1
    allow_supercritical: bool = False
    allow_unsafe_dt: bool = False
    energy_check: str = "raise"
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
            f"scene.laws has no contact law for material pair ({a!r}, {b!r}), which can meet; add "
            f"scene.laws[({a!r}, {b!r})] = LinearLaw(kn=...)"
        )
