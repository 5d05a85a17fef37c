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

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .scene import (Box, ContactModel, GlobalDamping, Material, SceneError, check_choice, check_flag, check_items,
                    check_name, check_number, check_type, check_vector, check_whole, is_number)


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
        return len(self.x) if hasattr(self.x, "__len__") and not isinstance(self.x, (str, bytes)) else 1


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
        return len(self.x) if hasattr(self.x, "__len__") and not isinstance(self.x, (str, bytes)) else 1


@dataclass
class Ellipsoids:
    """Ellipsoids (Miyata §2.4, eq 43): each a rigid body with semi-axes a1, a2, a3 along its body axes.

    axes : (n, 3) semi-axes [length], each > 0 (equal axes: a sphere)
    x, y, z : centres [length]
    material : a material name, or one per ellipsoid; the mass is 4/3 π a1 a2 a3 ρ, the principal
               moments m(a2² + a3²)/5, m(a1² + a3²)/5, m(a1² + a2²)/5
    orientation : optional (n, 4) unit quaternions (w, x, y, z), body frame to world (default: identity)
    velocity, angular_velocity : optional (n, 3) at the half step (angular velocity in the world frame)
    A scene with ellipsoids has no spheres or clumps (one particle family per scene).
    """

    axes: Sequence[Sequence[float]]
    x: Sequence[float]
    y: Sequence[float]
    z: Sequence[float]
    material: Sequence[str] | str
    orientation: Sequence[Sequence[float]] | None = None
    velocity: Sequence[Sequence[float]] | None = None
    angular_velocity: Sequence[Sequence[float]] | None = None

    def __len__(self) -> int:
        return len(self.x) if hasattr(self.x, "__len__") and not isinstance(self.x, (str, bytes)) else 1


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
    translate the whole mesh.

    periodic_images : in a box periodic along x or y, a particle meets each triangle through its
        nearest periodic image (the mesh may lie anywhere, across or outside the period, as with
        particles).  Each triangle must then be narrower than period − 2·(r_max + skin) along every
        periodic axis, so that no particle reaches two images of one triangle (build refuses a wider
        one: split it).  ``False``: no images, a particle wrapped across the boundary meets the
        mesh only where it lies (build warns, ``PeriodicMeshWarning``, for a mesh within a particle's
        reach of a periodic boundary)."""

    name: str
    vertices: Sequence[Sequence[float]]
    triangles: Sequence[Sequence[int]]
    material: str
    phases: tuple[PlanePhase, ...] = ()
    periodic_images: bool = True


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
    allow_unsafe_dt : accept a dt above the safe critical estimate of a packing
        (:func:`demflow.integrate.safe_time_step_3d`: every sphere with as many contacts as can touch it,
        rotations coupled by the tangential springs, dashpots; Hertzian stiffness at ``max_overlap``;
        ellipsoids: :func:`demflow.ellipsoids3d._safe_step_ellipsoids`) with an UnsafeTimeStepWarning (``allow_supercritical`` accepts any dt, silently)
    max_overlap : the largest overlap the scene's contacts are expected to reach, as a fraction of the
        smaller radius (ellipsoids: of the smaller smallest semi-axis); the safe estimate of a Hertzian scene takes the stiffness there (k ∝ √δ); a
        run whose overlaps exceed it is outside what the estimate covers (0 < max_overlap <= 0.5)
    max_contacts : the most contacts a sphere of this scene can have, when its geometry says so (a column
        or a chain: 2); None: as many as can touch it (:func:`demflow.integrate.kissing_number_3d`)
    skin : neighbour-list margin [length]; None = 0.2 × mean radius
    box : periodic along x and/or y (:class:`demflow.scene.Box`); z is never periodic
    energy_check : what a window of steps whose energy balance shows created energy does (issue 17 item
        4: an unstable step, e.g. Hertz contacts far deeper than ``max_overlap``, or a dt accepted with
        ``allow_supercritical``): "raise" BlowUpError with the last good state (default) or "warn"
        (EnergyBalanceWarning, the run goes on); :meth:`demflow.simulation3d.Simulation3D._balance_close`
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
    allow_unsafe_dt: bool = False
    max_overlap: float = 0.01
    max_contacts: int | None = None
    outputs: Outputs3D = Outputs3D()
    box: Box = Box()
    description: str = ""
    energy_check: str = "raise"
    clumps: Clumps | None = None
    ellipsoids: Ellipsoids | None = None

    def law_for(self, a: str, b: str):
        """The law of a material pair, in either order; a clear error if none is declared."""
        if (a, b) in self.laws:
            return self.laws[(a, b)]
        if (b, a) in self.laws:
            return self.laws[(b, a)]
        raise SceneError(
            f"no contact law for material pair ({a!r}, {b!r}); add laws[({a!r}, {b!r})] = "
            "HertzMindlinLaw(...) or LinearLaw(kn=...) to the scene")


def _vector3(path: str, v, nonzero: bool = False) -> np.ndarray:
    return np.array(check_vector(path, v, 3, nonzero=nonzero))


def _phases(path: str, phases) -> None:
    check_items(path, phases)
    for q, ph in enumerate(phases):
        check_type(f"{path}[{q}]", ph, PlanePhase)
        check_whole(f"{path}[{q}].cycles", ph.cycles)
        _vector3(f"{path}[{q}].velocity", ph.velocity)


def check_scene3d(scene: Scene3D) -> None:
    """Refuse what cannot be built, naming the field (a dotted path), the value, the rule and the fix.
    The per-sphere arrays are checked entry by entry in :func:`demflow.build3d.build3d`."""
    check_name("scene.name", scene.name)
    check_type("scene.materials", scene.materials, dict)
    for name, m in scene.materials.items():
        check_name(f"scene.materials key {name!r}", name)
        check_type(f"scene.materials[{name!r}]", m, Material)
        m.check(f"scene.materials[{name!r}]")
    check_type("scene.laws", scene.laws, dict)
    for pair, law in scene.laws.items():
        if not (isinstance(pair, tuple) and len(pair) == 2 and all(isinstance(p, str) and p in scene.materials
                                                                    for p in pair)):
            raise SceneError(f"scene.laws key {pair!r} is not a pair of declared materials "
                             f"({sorted(scene.materials)}); give (material, material)")
        if not hasattr(law, "check"):
            raise SceneError(f"scene.laws[{pair!r}]={law!r} is not a contact law; give HertzMindlinLaw(...) "
                             "or LinearLaw(kn=...)")
        law.check(pair)
    check_number("scene.local_damping", scene.local_damping, ge=0.0, lt=1.0)
    check_flag("scene.adaptive_damping", scene.adaptive_damping)
    check_flag("scene.allow_supercritical", scene.allow_supercritical)
    check_flag("scene.allow_unsafe_dt", scene.allow_unsafe_dt)
    check_choice("scene.energy_check", scene.energy_check, ("raise", "warn"))
    check_number("scene.max_overlap", scene.max_overlap, gt=0.0, le=0.5)
    if scene.max_contacts is not None:
        check_whole("scene.max_contacts", scene.max_contacts)
        if scene.max_contacts < 1:
            raise SceneError(f"scene.max_contacts={scene.max_contacts!r} must be >= 1; give the most contacts a "
                             "sphere can have, or None")
    scene.damping.check("scene.damping")
    scene.contact_model.check("scene.contact_model")
    _vector3("scene.gravity", scene.gravity)
    if scene.dt is not None:
        check_number("scene.dt", scene.dt, gt=0.0, unit="time")
    check_number("scene.dt_fraction", scene.dt_fraction, gt=0.0)
    check_whole("scene.n_steps", scene.n_steps)
    if scene.skin is not None:
        check_number("scene.skin", scene.skin, gt=0.0, unit="length")
    check_type("scene.box", scene.box, Box)
    scene.box.check("scene.box")
    o = scene.outputs
    check_type("scene.outputs", o, Outputs3D)
    check_whole("scene.outputs.every", o.every)
    check_flag("scene.outputs.orientation", o.orientation)
    check_items("scene.outputs.snapshots", o.snapshots)
    for k, st in enumerate(o.snapshots):
        check_whole(f"scene.outputs.snapshots[{k}]", st)
    check_items("scene.outputs.track_spheres", o.track_spheres)
    n_spheres = 0 if scene.spheres is None else len(scene.spheres)
    if scene.ellipsoids is not None:
        check_type("scene.ellipsoids", scene.ellipsoids, Ellipsoids)
        n_spheres = len(scene.ellipsoids)
    for k, i in enumerate(o.track_spheres):
        if is_number(i) and float(i) > n_spheres - 1 >= 0:
            raise SceneError(f"scene.outputs.track_spheres[{k}]={i!r} is not a sphere of this scene: its spheres are "
                             f"numbered 0 to {n_spheres - 1}")
        check_whole(f"scene.outputs.track_spheres[{k}]", i, le=max(n_spheres - 1, 0))
        if n_spheres == 0:
            raise SceneError(f"scene.outputs.track_spheres[{k}]={i!r}: the scene has no spheres to track")
    names = set()
    check_items("scene.meshes", scene.meshes)
    for k, mh in enumerate(scene.meshes):
        path = f"scene.meshes[{k}]"
        check_type(path, mh, TriangleMesh)
        check_name(f"{path}.name", mh.name)
        if mh.name in names:
            raise SceneError(f"{path}.name={mh.name!r} is used twice; give each wall its own name")
        names.add(mh.name)
        try:
            v = np.asarray(mh.vertices, dtype=np.float64)
        except (TypeError, ValueError):
            raise SceneError(f"{path}.vertices={mh.vertices!r} is not an array of numbers; give (nv, 3) "
                             "coordinates") from None
        if v.ndim != 2 or v.shape[1] != 3 or not np.all(np.isfinite(v)):
            raise SceneError(f"{path}.vertices has shape {v.shape} or non-finite values; give (nv, 3) finite "
                             "coordinates")
        t = np.asarray(mh.triangles)
        if t.ndim != 2 or t.shape[1] != 3 or t.shape[0] == 0 or not np.issubdtype(t.dtype, np.integer):
            raise SceneError(f"{path}.triangles has shape {t.shape} (dtype {t.dtype}); give (nt, 3) integer "
                             "vertex indices")
        if t.min() < 0 or t.max() >= len(v):
            k, c = (int(x[0]) for x in np.nonzero((t < 0) | (t >= len(v))))
            raise SceneError(f"{path}.triangles[{k}, {c}]={int(t[k, c])} is not a vertex index: there are {len(v)} "
                             f"vertices, numbered 0 to {len(v) - 1}; give indices in that range")
        a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
        area2 = np.linalg.norm(np.cross(b - a, c - a), axis=1)
        if np.any(area2 <= 0):
            raise SceneError(f"{path}.triangles[{int(np.argmax(area2 <= 0))}] is degenerate (zero area); "
                             "remove it")
        if mh.material not in scene.materials:
            raise SceneError(f"{path}.material={mh.material!r} is not declared; add it to scene.materials")
        _phases(f"{path}.phases", mh.phases)
        check_flag(f"{path}.periodic_images", mh.periodic_images)
    check_items("scene.planes", scene.planes)
    for k, p in enumerate(scene.planes):
        path = f"scene.planes[{k}]"
        check_type(path, p, Plane)
        check_name(f"{path}.name", p.name)
        if p.name in names:
            raise SceneError(f"{path}.name={p.name!r} is used twice; give each wall its own name")
        names.add(p.name)
        _vector3(f"{path}.point", p.point)
        _vector3(f"{path}.normal", p.normal, nonzero=True)
        if not isinstance(p.material, str) or p.material not in scene.materials:
            raise SceneError(f"{path}.material={p.material!r} is not declared; add it to scene.materials")
        _phases(f"{path}.phases", p.phases)
        if p.servo is not None:
            sv = p.servo
            check_type(f"{path}.servo", sv, PlateServo)
            check_number(f"{path}.servo.force", sv.force, gt=0.0, unit="force")
            check_number(f"{path}.servo.gain", sv.gain, gt=0.0, unit="length/time")
            check_number(f"{path}.servo.v_max", sv.v_max, gt=0.0, unit="length/time")
            check_whole(f"{path}.servo.start", sv.start)
    if scene.spheres is not None:
        check_type("scene.spheres", scene.spheres, Spheres)
    if scene.clumps is not None:
        check_type("scene.clumps", scene.clumps, Clumps)
