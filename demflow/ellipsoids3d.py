"""Build and run a 3D scene of ellipsoids (Miyata §2.4): :func:`build_ellipsoids` and
:class:`SimulationEllipsoids`.

:func:`demflow.build.build` calls :func:`build_ellipsoids` for a :class:`demflow.scene3d.Scene3D`
with ``ellipsoids``.  Each ellipsoid is a rigid body (:class:`demflow.state3d.Bodies3`: the closed-form
mass and principal moments of :func:`demflow.shapes.ellipsoid.ellipsoid_mass_properties`) with one
particle row (:class:`demflow.state3d.Spheres3`, radius = its bounding radius, the largest semi-axis,
which the neighbour list and the step-length test use) at its centre; the rotations, semi-axes and
smallest semi-axes are an :class:`demflow.state3d.Ellipsoids3`.  Walls, laws, damping, box and
records are the sphere scene's; the compiled cycle is
:func:`demflow.stepping_ellipsoids.run_steps_ellipsoids`.  Not (yet) supported with ellipsoids:
spheres or clumps in the same scene, fixed ellipsoids, adaptive damping.
"""
from __future__ import annotations

import math

import numpy as np

from . import libm
from .build3d import (_array, _check_safe_step, _chosen_step, _common_length, _law_family, _skin_and_box, _walls,
                      critical_estimate, particle_materials, quat_to_matrix, refuse_rotational_dashpot, time_step_laws)
from .contacts.ellipsoids import WARM_COLUMNS
from .scene import SceneError
from .shapes.ellipsoid import rotations
from .simulation3d import Simulation3D
from .state3d import Bodies3, Damping3, Ellipsoids3, Records3, Spheres3
from .stepping3d import MAX_OVERLAP_RATIO


class SimulationEllipsoids(Simulation3D):
    """A built ellipsoid scene (module docstring).  ``ell`` holds the semi-axes and rotations;
    ``bodies`` the rigid-body state (orientation quaternions, angular momentum); ``spheres`` one row
    per ellipsoid (centre, velocity, contact force and moment sums).  ``work[2]`` counts the Newton
    iterations of the contact solves."""

    def __init__(self, *, ellipsoids, **kw):
        self.ell = ellipsoids
        super().__init__(**kw)
        self.work = np.zeros(4)

    def _advance(self, n_steps: int, rec: Records3, rec_count: int):
        from .stepping_ellipsoids import run_steps_ellipsoids

        return run_steps_ellipsoids(n_steps, self.step, self.skin, self.spheres, self.ell, self.bodies, self.pairs,
                                    self.planes, self.tris, self.loading, self.law_params, self.g, self.damping,
                                    self.dt, rec, rec_count, self.work)

    def fixed_parts(self) -> dict:
        """As :meth:`Simulation3D.fixed_parts`, with the semi-axes."""
        return super().fixed_parts() | {"ellipsoids (semi-axes)": self.ell.axes}

    def deepest_overlap_now(self) -> float:
        """As :meth:`Simulation3D.deepest_overlap_now`, over the smaller of the pair's smallest semi-axes: the
        length ``scene.max_overlap`` is a fraction of for ellipsoids (:func:`_safe_step_ellipsoids`)."""
        return self._deepest_relative_to(self.ell.amin)

    _clump_table = False  # every ellipsoid is a body of its own: its row in ``spheres`` is the body

    def tables(self, include_records: bool = True) -> dict:
        """As :meth:`Simulation3D.tables`; the ``spheres`` table (also under ``ellipsoids``) carries
        the bodies' orientations and the semi-axes a1, a2, a3 (``r`` is the bounding radius)."""
        self.spheres.quat[:] = self.bodies.quat
        out = super().tables(include_records)
        t = out["spheres"]
        for a in range(3):
            t[f"a{a + 1}"] = self.ell.axes[:, a]
        out["ellipsoids"] = t
        return out


def _materials(scene, e, n):
    return particle_materials(scene, "ellipsoids", "ellipsoid", e.material, n)


def build_ellipsoids(scene) -> SimulationEllipsoids:
    """Check an ellipsoid scene (already through :func:`demflow.scene3d.check_scene3d`) and return a
    :class:`SimulationEllipsoids` ready to run.  Errors name the field, the value, the rule and the fix."""
    e = scene.ellipsoids
    if scene.spheres is not None and len(scene.spheres):
        raise SceneError("scene.spheres is given with scene.ellipsoids; a scene has one particle family: give "
                         "spheres=None (or model the spheres as ellipsoids with equal axes)")
    if scene.clumps is not None:
        raise SceneError("scene.clumps is given with scene.ellipsoids; a scene has one particle family: give "
                         "clumps=None")
    if scene.adaptive_damping:
        raise SceneError("scene.adaptive_damping=True is not implemented for ellipsoids; give False and use "
                         "scene.damping or scene.local_damping")
    n = _common_length("scene.ellipsoids", e, ("x", "y", "z"))
    if n == 0:
        raise SceneError("scene.ellipsoids has no ellipsoids; give at least one centre or leave ellipsoids=None")
    pos = np.stack([_array(f"scene.ellipsoids.{a}", getattr(e, a), n) for a in "xyz"], axis=1)
    axes = _array("scene.ellipsoids.axes", e.axes, n, (3,))
    if np.any(axes <= 0):
        k, a = (int(v) for v in np.argwhere(axes <= 0)[0])
        raise SceneError(f"scene.ellipsoids.axes[{k}, {a}]={float(axes[k, a])!r} must be > 0; give three positive "
                         "semi-axes per ellipsoid")
    mats = _materials(scene, e, n)
    names = list(scene.materials)
    index = {m: k for k, m in enumerate(names)}
    mat = np.array([index[m] for m in mats], np.int64)
    rho = np.array([scene.materials[m].density for m in mats], np.float64)
    mass = rho * 4.0 / 3.0 * math.pi * axes.prod(axis=1)
    if np.any(mass <= 0):
        k = int(np.argmax(mass <= 0))
        raise SceneError(f"scene.materials[{mats[k]!r}].density (ellipsoid {k}) gives mass {mass[k]!r}; a mass "
                         "must be > 0: give a positive density")
    a2 = axes ** 2
    moments = mass[:, None] / 5.0 * np.stack([a2[:, 1] + a2[:, 2], a2[:, 0] + a2[:, 2], a2[:, 0] + a2[:, 1]], axis=1)
    q = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)) if e.orientation is None else \
        _array("scene.ellipsoids.orientation", e.orientation, n, (4,))
    norm = np.linalg.norm(q, axis=1)
    if np.any(np.abs(norm - 1.0) > 1e-9):
        k = int(np.argmax(np.abs(norm - 1.0)))
        raise SceneError(f"scene.ellipsoids.orientation[{k}] has norm {norm[k]:.12g}; give unit quaternions "
                         "(w, x, y, z)")
    q = q / norm[:, None]
    vel = np.zeros((n, 3)) if e.velocity is None else _array("scene.ellipsoids.velocity", e.velocity, n, (3,))
    w = (np.zeros((n, 3)) if e.angular_velocity is None
         else _array("scene.ellipsoids.angular_velocity", e.angular_velocity, n, (3,)))
    R = quat_to_matrix(q)
    L = np.einsum("bij,bj->bi", R, moments * np.einsum("bji,bj->bi", R, w))  # L = R I Rᵀ ω
    bodies = Bodies3(pos=pos.copy(), vel=vel.copy(), L=L, angvel=w.copy(), quat=q.copy(), mass=mass.copy(),
                     moments=moments, start=np.arange(n + 1, dtype=np.int64), offset=np.zeros((n, 3)))
    r = axes.max(axis=1)
    amin = axes.min(axis=1)

    walls = list(scene.planes) + list(scene.meshes)
    family, params, width = _law_family(scene, mats, names, index, walls)
    planes, tris, loading = _walls(scene, walls, index)
    skin, box = _skin_and_box(scene, r)

    # the Rayleigh time of a sphere of the smallest semi-axis and the material's density (conservative)
    dt_crit, how = critical_estimate(scene, family, mats, "ellipsoid", amin,
                                     rho * 4.0 / 3.0 * math.pi * libm.cube(amin), mass, "a_min")
    dt = _chosen_step(scene, dt_crit, how)
    dt_safe = _safe_step_ellipsoids(scene, family, axes, mass, moments, mats, mat, index, walls)
    _check_safe_step(scene, dt, dt_safe, ELLIPSOIDS_ESTIMATE)
    P = np.zeros((n, 16))
    sp = Spheres3(pos=pos, vel=vel, angvel=w, quat=q.copy(), r=r, mass=mass, inertia=moments.mean(axis=1),
                  inv_r2=1.0 / r ** 2, mat=mat, fixed=np.full(n, 2, np.int8), body=np.arange(n, dtype=np.int64),
                  FM=np.zeros((n, 6)), P=P, ref=np.zeros((n, 3)), img=np.zeros((n, 2), np.int64))
    rot = np.zeros((n, 9))
    rotations(q, rot)
    ell = Ellipsoids3(axes=axes, amin=amin, rot=rot)
    d = scene.damping
    refuse_rotational_dashpot(scene, bodies, "ellipsoids")
    sim = SimulationEllipsoids(
        ellipsoids=ell, scene=scene, spheres=sp, bodies=bodies, planes=planes, tris=tris, loading=loading, law=family,
        law_params=params, box=box, dt=dt, dt_crit=dt_crit, dt_safe=dt_safe, skin=skin, gravity=scene.gravity,
        width=width + WARM_COLUMNS,
        damping=Damping3(alpha=float(d.alpha), c_abs=float(d.C), c_rot_abs=float(d.C_rot),
                         local=float(scene.local_damping), adaptive=False, alpha_now=np.zeros(1),
                         prev_r=np.zeros((0, 3)), prev_dx=np.zeros((0, 3))))
    _refuse_initial_overlaps(sim)
    return sim


ELLIPSOIDS_ESTIMATE = (
    "ellipsoids (demflow.ellipsoids3d._safe_step_ellipsoids: each ellipsoid a rigid body, a contact force moving "
    "its surface point through the body's translation and rotation; Hertzian stiffness at the largest Gaussian "
    "radius of curvature ab/c and overlaps up to scene.max_overlap={max_overlap:g} of the smallest semi-axis; "
    "as many contacts as spheres the size of the thinnest semi-axis can touch the bounding sphere; dashpots)")

MOBILITY_MARGIN = 1.01  # the sampled surface maxima below are raised by 1 % (grid error measured < 0.1 %)


def surface_mobility(axes, mass: float, moments) -> tuple[float, float]:
    """The largest mobility [1/mass] of a surface point of an ellipsoid (semi-axes ``axes``, principal moments
    ``moments`` along them) under a unit force along the surface normal, and along a tangent: 1/m + (r × u)ᵀ
    I⁻¹ (r × u), maximised over the surface (a 90 × 180 grid of the ellipsoid's angles; tangent: the largest
    eigenvalue over the tangent plane), times MOBILITY_MARGIN.  A sphere: (1/m, 1/m + R²/I) = (1/m, 3.5/m)."""
    a = np.asarray(axes, np.float64)
    th, ph = np.meshgrid(np.linspace(0.0, math.pi, 91), np.linspace(0.0, 2.0 * math.pi, 181), indexing="ij")
    u = np.stack([libm.sin(th) * libm.cos(ph), libm.sin(th) * libm.sin(ph), libm.cos(th)], -1).reshape(-1, 3)
    r = u * a
    n = r / a ** 2
    n /= np.linalg.norm(n, axis=1)[:, None]
    inv_i = 1.0 / np.asarray(moments, np.float64)
    rn = np.cross(r, n)
    normal = float(np.max(np.sum(rn * rn * inv_i, 1)))
    # the tangent plane: two unit vectors t1, t2 ⊥ n; the quadratic form of t ↦ (r × t)ᵀ I⁻¹ (r × t) on it
    helper = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    t2 = np.cross(n, t1)
    c1, c2 = np.cross(r, t1), np.cross(r, t2)
    q11, q22, q12 = (np.sum(c1 * c1 * inv_i, 1), np.sum(c2 * c2 * inv_i, 1), np.sum(c1 * c2 * inv_i, 1))
    top = 0.5 * (q11 + q22) + np.sqrt(0.25 * (q11 - q22) ** 2 + q12 ** 2)
    return (MOBILITY_MARGIN * (1.0 / mass + normal), MOBILITY_MARGIN * (1.0 / mass + float(top.max())))


def _safe_step_ellipsoids(scene, family, axes, mass, moments, mats, mat, index, walls) -> float:
    """The safe critical time step of a packing of ellipsoids [time]: :func:`demflow.integrate.safe_time_step`'s
    Gershgorin bound, each ellipsoid a rigid body:

    - mobility: a unit force at a surface point moves it by 1/m + (r × u)ᵀ I⁻¹ (r × u) at most
      (:func:`surface_mobility`: along the normal, whose line misses the centre of a non-sphere, and along a
      tangent), which takes the place of 1/m and 1/m + R²/I of a sphere;
    - stiffness: the Hertz law at the largest expected overlap δ <= max_overlap × c (c the smallest
      semi-axis) and the largest equivalent radius.  R* = 1/(2√(AB)) (Johnson), and the relative
      curvature of two convex bodies is the sum of theirs, so by Minkowski's determinant inequality
      R* <= Rg₁Rg₂/(Rg₁ + Rg₂) with Rg = 1/√K the Gaussian radius of curvature, at most ab/c on an ellipsoid
      with a >= b >= c (at the ends of its c axis); a plane has Rg = ∞;
    - contacts: at most the kissing bound of :func:`demflow.integrate.kissing_number_3d` for the bounding
      sphere (radius a) and spheres of the thinnest semi-axis in the scene (an assumption, not a theorem
      for ellipsoids: measured safe in ``tests/test_ellipsoid_time_step.py``), at most every other
      ellipsoid and wall, and at most ``scene.max_contacts``.
    """
    from .integrate import kissing_number_3d, safe_time_step

    s = np.sort(axes, axis=1)[:, ::-1]
    a, c = s[:, 0], s[:, 2]
    rg = s[:, 0] * s[:, 1] / s[:, 2]
    mob = {}
    mu_n, mu_t = np.empty(len(a)), np.empty(len(a))
    for k in range(len(a)):
        key = (tuple(axes[k]), float(mass[k]), tuple(moments[k]))
        if key not in mob:
            mob[key] = surface_mobility(axes[k], float(mass[k]), moments[k])
        mu_n[k], mu_t[k] = mob[key]
    # safe_time_step takes the normal mobility as 1/mass and the tangential one as 1/mass + r²/inertia
    extra = mu_t - mu_n
    inertia = np.where(extra > 0.0, a ** 2 / np.where(extra > 0.0, extra, 1.0), np.inf)
    pair_laws, wall_laws = time_step_laws(scene, family, mats, mat, index, walls, rg, mass,
                                          lambda f, sel: f(rg[sel], mass[sel], c[sel]))
    partners = np.full(len(a), len(a) - 1 + len(walls), np.float64)
    if scene.max_contacts is not None:
        partners = np.minimum(partners, scene.max_contacts)
    c_min = float(c.min())
    return float(safe_time_step(a, 1.0 / mu_n, inertia, mat, pair_laws, wall_laws,
                                kissing=lambda R, _r: kissing_number_3d(R, c_min), partners=partners)["dt"])


def contact_pass(sim: SimulationEllipsoids, recording: bool = False):
    """One ellipsoid pair pass at the current state (forces into ``sim.spheres.FM``, per-pair outputs
    into ``sim.pairs``; the history advances as in a step): (status, elastic energy, iterations, energy
    the contacts dissipated)."""
    from .contacts.ellipsoids import ellipsoid_forces

    rotations(sim.bodies.quat, sim.ell.rot)
    return ellipsoid_forces(sim.spheres, sim.ell, sim.pairs, sim.planes, sim.tris, sim.law_params, sim.dt, recording,
                            MAX_OVERLAP_RATIO)


def _refuse_initial_overlaps(sim: SimulationEllipsoids) -> None:
    """An overlap beyond the blow-up limit at step 0 is bad input, not a blow-up: name the pair."""
    hist = sim.pairs.hist.copy()
    status, _, _, _ = contact_pass(sim)
    sim.pairs.hist[:] = hist
    sim.spheres.FM[:] = 0.0
    sim.planes.force[:] = 0.0
    if status:
        p = sim.pairs
        n, nw = sim.n, sim.n_planes
        amin = sim.ell.amin
        rmin = np.where(p.j < n, np.minimum(amin[p.i], amin[np.minimum(p.j, n - 1)]), amin[p.i])
        k = int(np.argmax(p.ovl / rmin))
        j = int(p.j[k])
        names = [pl.name for pl in sim.scene.planes] + [m.name for m in sim.scene.meshes]
        other = (f"ellipsoid {j}" if j < n else f"wall {names[j - n]!r}" if j < n + nw
                 else f"mesh {names[int(sim.tris.wall[j - n - nw])]!r} (triangle {j - n - nw})")
        raise SceneError(f"ellipsoid {int(p.i[k])} overlaps {other} by {p.ovl[k]:.4g} at the start, more than "
                         f"{MAX_OVERLAP_RATIO:.0%} of the smaller semi-axis ({rmin[k]:.4g}); move them apart")
