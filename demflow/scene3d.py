"""The declarative 3D scene: spheres, planes and loading plates (what is simulated, not how).

A :class:`Scene3D` lists spheres, plane walls (a floor, a loading plate with prescribed velocity
or servo control), materials, the contact law of every material pair (:class:`demflow.scene.LinearLaw`
or :class:`demflow.laws.hertz_mindlin.HertzMindlinLaw`), damping (mass-proportional ch3 eq 3.19 /
Miyata eq 32, local non-viscous Miyata eq 33), gravity, the time step, a box periodic along x
and/or y (:class:`demflow.scene.Box`) and the outputs.  :func:`demflow.build.build` checks it and
returns a :class:`demflow.simulation3d.Simulation3D`.

Units: any consistent system; a sphere's mass is 4/3 πR³ρ [mass] (ρ [mass/length³]) and its
moment of inertia 2/5 mR².  Positions, velocities and angular velocities are 3-vectors; the
velocities given are v(-Δt/2), as the central-difference (leapfrog) scheme holds them at half
steps (ch3 eqs 3.19-3.20).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .scene import Box, ContactModel, GlobalDamping, Material, SceneError, check_identifier


@dataclass
class Spheres:
    """Spheres as arrays: centres (x, y, z) [length], radius [length], material names.

    mass : optional per-sphere mass overriding 4/3 πR³ρ [mass] (inertia stays 2/5 mR²)
    velocity : optional (n, 3) initial velocity v(-Δt/2) [length/time]
    angular_velocity : optional (n, 3) [rad/time]
    fixed : optional (n,) booleans: a fixed sphere is not integrated; it keeps the velocity it was
            given (zero by default) and moves with it (ch3's stack: "the bottom element is not
            allowed to move")
    """

    x: Sequence[float]
    y: Sequence[float]
    z: Sequence[float]
    radius: Sequence[float]
    material: Sequence[str] | str
    mass: Sequence[float] | None = None
    velocity: Sequence[Sequence[float]] | None = None
    angular_velocity: Sequence[Sequence[float]] | None = None
    fixed: Sequence[bool] | None = None

    def __len__(self) -> int:
        return len(np.atleast_1d(self.x))


@dataclass
class Clumps:
    """Rigid clumps of spheres (bodies made of overlapping member spheres; no contacts inside one).

    template : a :class:`demflow.shapes.clump.ClumpTemplate` (members in its principal frame, mass,
               principal moments), the same for every clump
    x, y, z : centres of mass [length]
    orientation : optional (nb, 4) unit quaternions (w, x, y, z), body frame to world (default: identity)
    velocity, angular_velocity : optional (nb, 3) at the half step
    material : the members' material (contact law); the mass and inertia are the template's
    """

    template: object
    x: Sequence[float]
    y: Sequence[float]
    z: Sequence[float]
    material: str
    orientation: Sequence[Sequence[float]] | None = None
    velocity: Sequence[Sequence[float]] | None = None
    angular_velocity: Sequence[Sequence[float]] | None = None

    def __len__(self) -> int:
        return len(np.atleast_1d(self.x))


@dataclass(frozen=True)
class PlanePhase:
    """One phase of a plane's prescribed translation: ``velocity`` (vx, vy, vz) for ``cycles`` steps."""

    cycles: int
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class PlateServo:
    """Servo control of a plane (thesis eqs 5.11-5.12 in 3D): the plane presses on the spheres with
    target force ``force`` F_A [force] (along its normal, which points to the spheres); each step
    err = (F_A - F_C)/F_A with F_C the spheres' reaction, and the plane moves along its normal (towards
    the spheres) at min(v_max, |G·err|)·sign(err).
    ``gain`` G [length/time], ``v_max`` [length/time], active from step ``start``."""

    force: float
    gain: float
    v_max: float
    start: int = 0


@dataclass(frozen=True)
class Plane:
    """An infinite plane wall through ``point`` with unit ``normal`` pointing to the side the
    spheres are on.  ``phases`` prescribe its translation one after another (then it stops);
    ``servo`` makes it force-controlled (a loading plate)."""

    name: str
    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    material: str
    phases: tuple[PlanePhase, ...] = ()
    servo: PlateServo | None = None


@dataclass(frozen=True)
class TriangleMesh:
    """A rigid wall made of triangles (a silo, a funnel, a shaped plate): ``vertices`` (nv, 3)
    [length], ``triangles`` (nt, 3) vertex indices.  A sphere touches a triangle at the triangle's
    point closest to its centre (face, edge or vertex); an edge or vertex contact counts only when no
    face of the same mesh touches that sphere, and once for triangles sharing it.  ``phases``
    translate the whole mesh.  Meshes are not imaged across periodic boundaries."""

    name: str
    vertices: Sequence[Sequence[float]]
    triangles: Sequence[Sequence[int]]
    material: str
    phases: tuple[PlanePhase, ...] = ()


@dataclass(frozen=True)
class Outputs3D:
    """What a 3D run records.

    every : record plane forces and positions, energies, contact count and the tracked spheres
            every this many steps (0: never)
    snapshots : steps at which sphere states and contacts are kept
    track_spheres : sphere indices whose position and velocity are recorded every ``every`` steps
    orientation : integrate each sphere's orientation quaternion (it does not change a sphere's
                  dynamics: off unless the outputs need it)
    """

    every: int = 1
    snapshots: tuple[int, ...] = ()
    track_spheres: tuple[int, ...] = ()
    orientation: bool = False


@dataclass
class Scene3D:
    """Everything that defines a 3D sphere simulation.  Build it with :func:`demflow.build.build`.

    laws : {(material a, material b): LinearLaw or HertzMindlinLaw} (one family per scene)
    damping : mass-proportional damping C = αm, C* = αI (``GlobalDamping(alpha=...)``; ch3 eq 3.19,
              Miyata eq 32); absolute C, C_rot also accepted
    local_damping : Cundall's local non-viscous damping coefficient α_l (Miyata eq 33; YADE's
                    ``NewtonIntegrator.damping``): each force component is reduced by
                    α_l |F| in the direction of the motion, gravity included (YADE's default)
    adaptive_damping : adaptive dynamic relaxation for static solutions (ch3 §3.5.4.2; Underwood
                       1983): mass-proportional damping set every step to 2ω_min, ω_min² the
                       Rayleigh quotient of the last step's force and displacement increments
    dt : the time step, or None for ``dt_fraction`` × the critical estimate (linear: 2√(m/k);
         Hertz: the Rayleigh-wave time πR√(ρ/G)/(0.1631ν + 0.8766))
    skin : neighbour-list margin [length]; None = 0.2 × mean radius
    box : periodic along x and/or y (:class:`demflow.scene.Box`); z is never periodic
    """

    name: str
    spheres: Spheres | None
    materials: dict[str, Material]
    laws: dict
    planes: list[Plane] = field(default_factory=list)
    meshes: list[TriangleMesh] = field(default_factory=list)
    damping: GlobalDamping = GlobalDamping()
    local_damping: float = 0.0
    adaptive_damping: bool = False
    gravity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    dt: float | None = None
    dt_fraction: float = 0.1
    allow_supercritical: bool = False
    n_steps: int = 1000
    skin: float | None = None
    contact_model: ContactModel = ContactModel(normal="overlap")
    outputs: Outputs3D = Outputs3D()
    box: Box = Box()
    description: str = ""
    clumps: Clumps | None = None

    def law_for(self, a: str, b: str):
        """The law of a material pair, in either order; a clear error if none is declared."""
        if (a, b) in self.laws:
            return self.laws[(a, b)]
        if (b, a) in self.laws:
            return self.laws[(b, a)]
        raise SceneError(
            f"no contact law for material pair ({a!r}, {b!r}); add laws[({a!r}, {b!r})] = "
            "HertzMindlinLaw(...) or LinearLaw(kn=...) to the scene")


def _finite(where: str, v, *, positive=False, nonneg=False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise SceneError(f"{where}={v!r} is not a number; give a finite float")
    v = float(v)
    if not math.isfinite(v):
        raise SceneError(f"{where}={v!r} is not finite; give a finite number")
    if positive and v <= 0:
        raise SceneError(f"{where}={v} must be > 0")
    if nonneg and v < 0:
        raise SceneError(f"{where}={v} must be >= 0")
    return v


def _vector3(where: str, v) -> np.ndarray:
    try:
        a = np.asarray(v, dtype=np.float64)
    except (TypeError, ValueError):
        raise SceneError(f"{where}={v!r} is not three numbers; give (x, y, z)") from None
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise SceneError(f"{where}={v!r}: give three finite numbers (x, y, z)")
    return a


def check_scene3d(scene: Scene3D) -> None:
    """Refuse what cannot be built, naming the field, the value, the rule and the fix."""
    check_identifier("scene", scene.name)
    for name, m in scene.materials.items():
        check_identifier("material", name)
        if not isinstance(m, Material):
            raise SceneError(f"scene.materials[{name!r}]={m!r} is not a Material; give Material(density=...)")
        m.check(f"scene.materials[{name!r}]")
    for pair, law in scene.laws.items():
        if not (isinstance(pair, tuple) and len(pair) == 2 and all(p in scene.materials for p in pair)):
            raise SceneError(f"scene.laws key {pair!r} is not a pair of declared materials "
                             f"({sorted(scene.materials)})")
        if not hasattr(law, "check"):
            raise SceneError(f"scene.laws[{pair!r}]={law!r} is not a contact law; give HertzMindlinLaw(...) "
                             "or LinearLaw(kn=...)")
        law.check(pair)
    _finite("scene.local_damping", scene.local_damping, nonneg=True)
    if not isinstance(scene.adaptive_damping, bool):
        raise SceneError(f"scene.adaptive_damping={scene.adaptive_damping!r}: give True or False")
    if scene.local_damping >= 1.0:
        raise SceneError(f"scene.local_damping={scene.local_damping} must be < 1 (a coefficient of "
                         "Cundall's local damping; YADE uses 0.2-0.4)")
    scene.damping.check()
    _vector3("scene.gravity", scene.gravity)
    if scene.dt is not None:
        _finite("scene.dt", scene.dt, positive=True)
    _finite("scene.dt_fraction", scene.dt_fraction, positive=True)
    if isinstance(scene.n_steps, bool) or not isinstance(scene.n_steps, (int, np.integer)) or scene.n_steps < 0:
        raise SceneError(f"scene.n_steps={scene.n_steps!r}: give an integer >= 0")
    if scene.skin is not None:
        _finite("scene.skin", scene.skin, positive=True)
    scene.box.check()
    o = scene.outputs
    if isinstance(o.every, bool) or not isinstance(o.every, (int, np.integer)) or o.every < 0:
        raise SceneError(f"scene.outputs.every={o.every!r}: give an integer >= 0")
    names = set()
    for k, mh in enumerate(scene.meshes):
        check_identifier("mesh", mh.name)
        if mh.name in names:
            raise SceneError(f"scene.meshes[{k}].name={mh.name!r} is used twice; give each wall its own name")
        names.add(mh.name)
        try:
            v = np.asarray(mh.vertices, dtype=np.float64)
            t = np.asarray(mh.triangles)
        except (TypeError, ValueError):
            raise SceneError(f"scene.meshes[{k}]: vertices and triangles must be numeric arrays") from None
        if v.ndim != 2 or v.shape[1] != 3 or not np.all(np.isfinite(v)):
            raise SceneError(f"scene.meshes[{k}].vertices has shape {v.shape} or non-finite values; give (nv, 3) "
                             "finite coordinates")
        if t.ndim != 2 or t.shape[1] != 3 or t.shape[0] == 0 or not np.issubdtype(t.dtype, np.integer):
            raise SceneError(f"scene.meshes[{k}].triangles has shape {t.shape} (dtype {t.dtype}); give (nt, 3) "
                             "integer vertex indices")
        if t.min() < 0 or t.max() >= len(v):
            raise SceneError(f"scene.meshes[{k}].triangles index vertex {int(t.max())}; there are {len(v)} vertices")
        a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
        area2 = np.linalg.norm(np.cross(b - a, c - a), axis=1)
        if np.any(area2 <= 0):
            raise SceneError(f"scene.meshes[{k}] triangle {int(np.argmax(area2 <= 0))} is degenerate (zero area); "
                             "remove it")
        if mh.material not in scene.materials:
            raise SceneError(f"scene.meshes[{k}].material={mh.material!r} is not declared; add it to scene.materials")
        for q, ph in enumerate(mh.phases):
            if isinstance(ph.cycles, bool) or not isinstance(ph.cycles, (int, np.integer)) or ph.cycles < 0:
                raise SceneError(f"scene.meshes[{k}].phases[{q}].cycles={ph.cycles!r}: give an integer >= 0")
            _vector3(f"scene.meshes[{k}].phases[{q}].velocity", ph.velocity)
    for k, p in enumerate(scene.planes):
        check_identifier("plane", p.name)
        if p.name in names:
            raise SceneError(f"scene.planes[{k}].name={p.name!r} is used twice; give each plane its own name")
        names.add(p.name)
        _vector3(f"scene.planes[{k}].point", p.point)
        nrm = _vector3(f"scene.planes[{k}].normal", p.normal)
        if np.linalg.norm(nrm) == 0:
            raise SceneError(f"scene.planes[{k}].normal={p.normal!r} is zero; give the direction of the "
                             "spheres' side")
        if p.material not in scene.materials:
            raise SceneError(f"scene.planes[{k}].material={p.material!r} is not declared; add it to "
                             "scene.materials")
        for q, ph in enumerate(p.phases):
            if isinstance(ph.cycles, bool) or not isinstance(ph.cycles, (int, np.integer)) or ph.cycles < 0:
                raise SceneError(f"scene.planes[{k}].phases[{q}].cycles={ph.cycles!r}: give an integer >= 0")
            _vector3(f"scene.planes[{k}].phases[{q}].velocity", ph.velocity)
        if p.servo is not None:
            s = p.servo
            _finite(f"scene.planes[{k}].servo.force", s.force, positive=True)
            _finite(f"scene.planes[{k}].servo.gain", s.gain, positive=True)
            _finite(f"scene.planes[{k}].servo.v_max", s.v_max, positive=True)
            if isinstance(s.start, bool) or not isinstance(s.start, (int, np.integer)) or s.start < 0:
                raise SceneError(f"scene.planes[{k}].servo.start={s.start!r}: give an integer step >= 0")
