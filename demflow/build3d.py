"""Build a 3D sphere scene: check it, allocate what its physics needs, select the compiled law.

:func:`demflow.build.build` calls :func:`build3d` for a :class:`demflow.scene3d.Scene3D`.
"""
from __future__ import annotations

import math

import numpy as np

from . import libm
from .laws.hertz_mindlin import HertzMindlin
from .laws.linear import Linear
from .scene import SceneError, is_number, type_phrase
from .scene3d import Scene3D, Spheres, check_scene3d
from .simulation3d import Simulation3D
from .state3d import Bodies3, Box3, Damping3, Loading3, Planes3, Spheres3, Triangles3

FAMILIES_3D = (Linear, HertzMindlin)


def rayleigh_time_step(r: np.ndarray, mass: np.ndarray, young: np.ndarray, poisson: np.ndarray) -> float:
    """The Rayleigh-wave time step min πR√(ρ/G)/(0.1631ν + 0.8766) (Li et al. 2005; YADE's
    ``RayleighWaveTimeStep``), with ρ = m / (4/3 πR³) and G = E / 2(1 + ν) per sphere [time]."""
    rho = mass / (4.0 / 3.0 * math.pi * libm.cube(r))
    G = young / (2.0 * (1.0 + poisson))
    return float(np.min(math.pi * r * np.sqrt(rho / G) / (0.1631 * poisson + 0.8766)))


def _array(where: str, v, n: int, shape=None, dtype=np.float64) -> np.ndarray:
    """Per-sphere numbers (``dtype`` float64: finite reals, no bools) or flags (bool: bools only) of
    shape (n,) + shape, each entry checked; the message names the entry."""
    want = (n,) + (shape or ())
    if isinstance(v, np.ndarray) and v.dtype.kind == ("f" if dtype == np.float64 else "b"):
        a = v  # fast path for arrays of the right kind
    else:
        try:
            a = np.empty(len(v), dtype=object) if shape is None and isinstance(v, (list, tuple)) else None
            if a is not None:
                a[:] = list(v)  # entries kept as given (a list entry stays one object: refused below)
            else:
                a = np.array(v, dtype=object)
        except (TypeError, ValueError):
            raise SceneError(f"{where}={v!r} cannot be read as an array; give {want} values") from None
    if a.shape != want:
        raise SceneError(f"{where} has shape {a.shape}, not {want}; give one entry per sphere")
    if a.dtype == object:
        for idx, x in np.ndenumerate(a):
            ok = is_number(x) if dtype == np.float64 else isinstance(x, (bool, np.bool_))
            if not ok:
                what = "a finite number" if dtype == np.float64 else "True or False"
                raise SceneError(f"{where}[{', '.join(map(str, idx))}]={x!r} is {type_phrase(x)}; give {what}")
    a = a.astype(dtype)
    if dtype == np.float64 and not np.all(np.isfinite(a)):
        idx = tuple(int(c) for c in np.argwhere(~np.isfinite(a))[0])
        raise SceneError(f"{where}[{', '.join(map(str, idx))}]={float(a[idx])!r} is not finite; give finite numbers")
    return a


def _common_length(path: str, obj, keys) -> int:
    """The number of entries of the arrays ``keys`` of ``obj``, which must agree."""
    lens = []
    for k in keys:
        v = getattr(obj, k)
        if isinstance(v, (str, bytes)) or not hasattr(v, "__len__"):
            raise SceneError(f"{path}.{k}={v!r} is {type_phrase(v)}, not a sequence of numbers; give one per entry")
        lens.append(len(v))
    if len(set(lens)) != 1:
        raise SceneError(f"{', '.join(f'{path}.{k}' for k in keys)} have lengths {', '.join(map(str, lens))}; give the "
                         "same number of entries in each")
    return lens[0]


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (nb, 3, 3) of unit quaternions (nb, 4) (w, x, y, z): body frame -> world."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], 1)


def _no_bodies() -> Bodies3:
    z3 = np.zeros((0, 3))
    return Bodies3(pos=z3, vel=z3.copy(), L=z3.copy(), angvel=z3.copy(), quat=np.zeros((0, 4)), mass=np.zeros(0),
                   moments=z3.copy(), start=np.zeros(1, np.int64), offset=z3.copy())


def _clumps(c, index, first: int):
    """Bodies3 of the clumps and their members as particles (appended after ``first`` free spheres)."""
    from .shapes.clump import ClumpTemplate, check_template

    T = c.template
    if not isinstance(T, ClumpTemplate):
        raise SceneError(f"scene.clumps.template={T!r} is not a ClumpTemplate; build one with "
                         "ClumpTemplate.ellipsoid_like(K) or ClumpTemplate.from_spheres(...)")
    check_template("scene.clumps.template", T, SceneError)
    nb = _common_length("scene.clumps", c, ("x", "y", "z"))
    pos = np.stack([_array(f"scene.clumps.{a}", getattr(c, a), nb) for a in "xyz"], axis=1)
    q = np.tile([1.0, 0.0, 0.0, 0.0], (nb, 1)) if c.orientation is None else \
        _array("scene.clumps.orientation", c.orientation, nb, (4,))
    norm = np.linalg.norm(q, axis=1)
    if np.any(np.abs(norm - 1.0) > 1e-9):
        k = int(np.argmax(np.abs(norm - 1.0)))
        raise SceneError(f"scene.clumps.orientation[{k}] has norm {norm[k]:.12g}; give unit quaternions (w, x, y, z)")
    if nb == 0:
        raise SceneError("scene.clumps has no clumps; give positions or leave scene.clumps=None")
    vel = np.zeros((nb, 3)) if c.velocity is None else _array("scene.clumps.velocity", c.velocity, nb, (3,))
    w = (np.zeros((nb, 3)) if c.angular_velocity is None
         else _array("scene.clumps.angular_velocity", c.angular_velocity, nb, (3,)))
    if not isinstance(c.material, str) or c.material not in index:
        raise SceneError(f"scene.clumps.material={c.material!r} is not declared; add it to scene.materials")
    K = len(T.radii)
    R = quat_to_matrix(q)
    off = np.asarray(T.centres, np.float64)
    mpos = (pos[:, None, :] + np.einsum("bij,kj->bki", R, off)).reshape(-1, 3)
    mom = np.tile(np.asarray(T.moments, np.float64), (nb, 1))
    # world angular momentum L = R I R^T ω
    L = np.einsum("bij,bj->bi", R, mom * np.einsum("bji,bj->bi", R, w))
    bvel = (vel[:, None, :] + np.cross(w[:, None, :], mpos.reshape(nb, K, 3) - pos[:, None, :])).reshape(-1, 3)
    members = {"pos": mpos, "r": np.tile(T.radii, nb), "mass": np.full(nb * K, float(T.mass)), "vel": bvel,
               "angvel": np.repeat(w, K, axis=0), "body": np.repeat(np.arange(nb, dtype=np.int64), K)}
    bodies = Bodies3(pos=pos, vel=vel, L=L, angvel=w.copy(), quat=q / norm[:, None], mass=np.full(nb, float(T.mass)),
                     moments=mom, start=first + K * np.arange(nb + 1, dtype=np.int64), offset=np.tile(off, (nb, 1)))
    return bodies, members


def _law_family(scene, mats, names, index, walls):
    """The law family of every pair of materials that can meet (particles of ``mats``, the walls):
    (family, compiled params, 3D history width)."""
    plane_mats = [p.material for p in walls]
    used = sorted(set(mats), key=names.index)
    pairs = {}
    count = {m: mats.count(m) for m in used}
    for a in used:
        for b in used:  # sphere pairs that exist (a lone sphere of a material never meets its own kind)
            if names.index(b) < names.index(a) or (a == b and count[a] < 2):
                continue
            pairs[(a, b)] = scene.law_for(a, b)
        for b in plane_mats:
            if (a, b) not in pairs and (b, a) not in pairs:
                pairs[(a, b)] = scene.law_for(a, b)
    if not pairs:  # nothing can touch (a lone particle, no wall): the laws declared between its materials decide
        pairs = {k: law for k, law in scene.laws.items() if k[0] in index and k[1] in index}
        if not pairs:
            raise SceneError(f"scene {scene.name!r}: no particle can touch another or a wall, and scene.laws declares "
                             f"no law between its materials ({', '.join(map(repr, used))}), so the run has no contact "
                             f"law family; declare one, e.g. laws[({used[0]!r}, {used[0]!r})] = HertzMindlinLaw(...)")
    fams = {f for f in FAMILIES_3D for law in pairs.values() if f.accepts(law)}
    if len(fams) != 1:
        raise SceneError(f"scene {scene.name!r} mixes contact-law families ({sorted(f.name for f in fams)}) or has "
                         "a law no 3D family implements; give every pair a LinearLaw or every pair a "
                         "HertzMindlinLaw")
    family = fams.pop()(scene, pairs, index)
    params = family.params()
    width = family.history_width(3)

    return family, params, width


def _walls(scene, walls, index):
    """Planes3 (planes, then meshes), Triangles3 and Loading3 of the scene's wall bodies."""
    plane_mats = [p.material for p in walls]
    # wall bodies: planes (point, unit normal), then meshes (reference point = first vertex)
    npl = len(walls)
    point = np.array([p.point if not hasattr(p, "triangles") else np.asarray(p.vertices, np.float64)[0]
                      for p in walls], np.float64).reshape(npl, 3)
    normal = np.array([p.normal if not hasattr(p, "triangles") else (0.0, 0.0, 0.0) for p in walls],
                      np.float64).reshape(npl, 3)
    is_mesh = np.array([hasattr(p, "triangles") for p in walls], np.int8)
    for q in range(npl):
        if not is_mesh[q]:
            normal[q] /= np.linalg.norm(normal[q])
    planes = Planes3(point=point, normal=normal, vel=np.zeros((npl, 3)),
                     mat=np.array([index[m] for m in plane_mats], np.int64), force=np.zeros((npl, 3)),
                     ref=point.copy(), is_mesh=is_mesh)
    tv, tw, ti = [], [], []
    periodic = scene.box.periodic_x is not None or scene.box.periodic_y is not None
    for q, w in enumerate(walls):
        if is_mesh[q]:
            v = np.asarray(w.vertices, np.float64)
            t = np.asarray(w.triangles, np.int64)
            tv.append(np.concatenate([v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]], axis=1))
            tw.append(np.full(len(t), q, np.int64))
            ti.append(np.full(len(t), 1 if (periodic and w.periodic_images) else 0, np.int8))
    tris = Triangles3(v=np.concatenate(tv) if tv else np.zeros((0, 9)),
                      wall=np.concatenate(tw) if tw else np.zeros(0, np.int64),
                      imaged=np.concatenate(ti) if ti else np.zeros(0, np.int8))
    K = max([len(p.phases) for p in walls] + [1])
    ps = np.zeros((npl, K), np.int64)
    pe = np.zeros((npl, K), np.int64)
    pv = np.zeros((npl, K, 3))
    for q, p in enumerate(walls):
        t = 0
        for k, ph in enumerate(p.phases):
            ps[q, k] = t
            t += int(ph.cycles)
            pe[q, k] = t
            pv[q, k] = ph.velocity
    servo = [getattr(p, "servo", None) for p in walls]
    loading = Loading3(phase_start=ps, phase_end=pe, phase_v=pv,
                       servo_on=np.array([sv is not None for sv in servo], np.int8),
                       servo_start=np.array([sv.start if sv else 0 for sv in servo], np.int64),
                       servo_F=np.array([sv.force if sv else 1.0 for sv in servo]),
                       servo_G=np.array([sv.gain if sv else 0.0 for sv in servo]),
                       servo_vmax=np.array([sv.v_max if sv else 0.0 for sv in servo]))

    return planes, tris, loading


def particle_materials(scene, field: str, one: str, material, n: int) -> list[str]:
    """The material name of each of the n particles of ``scene.<field>`` (``one``: what one of them is
    called in a message), from one name for all or one per particle; each must be declared in
    scene.materials.  Errors name the field, the entry, the rule and the fix."""
    if isinstance(material, str):
        mats = [material] * n
    elif isinstance(material, (list, tuple, np.ndarray)):
        mats = list(material)
    else:
        raise SceneError(f"scene.{field}.material={material!r} is {type_phrase(material)}; give a material "
                         f"name or one per {one}")
    if len(mats) != n:
        raise SceneError(f"scene.{field}.material has {len(mats)} entries for {n} {field}; give one per {one} "
                         "or one name for all")
    for k, m in enumerate(mats):
        if not isinstance(m, str) or m not in scene.materials:
            raise SceneError(f"scene.{field}.material[{k}]={m!r} is not declared; add it to scene.materials")
    return mats


def time_step_laws(scene, family, mats, mat, index, walls, size, m_dash, call) -> tuple[dict, dict]:
    """The laws of the safe critical time step (:func:`demflow.integrate.safe_time_step`'s ``disc_laws`` and
    ``wall_laws``) for the particle materials ``mats`` (names; ``mat`` their indices): the constants of a linear
    law, or for a Hertzian law a function of a particle mask, ``call(f, sel)`` applying
    :meth:`demflow.laws.hertz_mindlin.HertzMindlin.time_step_law`'s ``f`` to the masked particles, against
    partners of the largest ``size`` and dashpot mass ``m_dash`` of their material (a wall: infinite)."""
    used = sorted(set(mats))
    big = {a: (float(size[mat == index[a]].max()), float(m_dash[mat == index[a]].max())) for a in used}

    def constants(law, a, b, wall=False):
        if isinstance(family, HertzMindlin):
            r_b, m_b = (math.inf, math.inf) if wall else big[b]
            f = family.time_step_law(law, a, b, float(scene.max_overlap), r_b, m_b)
            return lambda sel: call(f, sel)
        return family.time_step_constants(law)

    pair_laws = {}
    for (a, b), law in family.laws_by_pair.items():
        if a in used and b in used:
            pair_laws[(index[a], index[b])] = constants(law, a, b)
            pair_laws[(index[b], index[a])] = constants(law, b, a)
    wall_laws = {}
    for a in used:
        for w in walls:
            wall_laws.setdefault(index[a], []).append(constants(scene.law_for(a, w.material), a, w.material, True))
    return pair_laws, wall_laws


def _safe_step(scene, family, r, mass, mats, mat, index, walls, body, bodies) -> float:
    """The packing's safe critical time step (:func:`demflow.integrate.safe_time_step_3d`) [time], for the
    sphere pairs that can meet and every sphere against every wall.  A clump member moves with its clump:
    at its surface a unit force meets the mobility 1/M + ρ²/I of the rigid body (ρ its distance from the
    body's centre, here bounded by |offset| + R, I the smallest principal moment), in every direction, so
    it counts with mass 1/(1/M + ρ²/I_min) and no rotation of its own."""
    from .integrate import safe_time_step_3d

    m_dash = mass  # the masses the contact dashpots use (a member: its clump's)
    mass = mass.astype(np.float64, copy=True)
    inertia = 0.4 * mass * r * r
    members = body >= 0
    if np.any(members):
        b = body[members]
        rho = np.linalg.norm(bodies.offset, axis=1) + r[members]
        mass[members] = 1.0 / (1.0 / bodies.mass[b] + rho ** 2 / bodies.moments[b].min(axis=1))
        inertia[members] = np.inf

    pair_laws, wall_laws = time_step_laws(scene, family, mats, mat, index, walls, r, m_dash,
                                          lambda f, sel: f(r[sel], m_dash[sel]))
    # the spheres and walls each can meet: every sphere but itself and its own clump's members
    own = np.ones(len(r))
    if np.any(members):
        _, inv, counts = np.unique(body[members], return_inverse=True, return_counts=True)
        own[members] = counts[inv]
    partners = len(r) - own + len(walls)
    if scene.max_contacts is not None:
        partners = np.minimum(partners, scene.max_contacts)
    return float(safe_time_step_3d(r, mass, mat, pair_laws, wall_laws, partners=partners, inertia=inertia)["dt"])


SPHERES_ESTIMATE = ("spheres (demflow.integrate.safe_time_step_3d: every sphere with as many neighbours as can "
                    "touch it, rotations coupled by the tangential springs, dashpots, Hertzian stiffness at overlaps "
                    "up to scene.max_overlap={max_overlap:g} of the smaller radius)")


def critical_estimate(scene, family, mats, particle: str, radius, m_rho, mass, radius_name: str) -> tuple[float, str]:
    """The critical time-step estimate [time] that ``scene.dt_fraction`` scales, and how it was formed: for a
    Hertzian law the Rayleigh-wave time of radius ``radius`` (named ``radius_name`` in the description) and
    mass ``m_rho`` (:func:`rayleigh_time_step`), refusing a particle material with an infinite Young's
    modulus; for a linear law 2√(m_min/k_max) with the particles' ``mass``.  ``particle`` names the particles
    in the refusal ("sphere", "ellipsoid")."""
    if isinstance(family, HertzMindlin):
        E = np.array([scene.materials[m].young for m in mats], np.float64)
        nu = np.array([scene.materials[m].poisson for m in mats], np.float64)
        if not np.all(np.isfinite(E)):
            k = int(np.argmax(~np.isfinite(E)))
            raise SceneError(f"{particle} {k} has material {mats[k]!r} with young={E[k]}: only a plane can be rigid; "
                             f"give the {particle}s' material a finite Young's modulus")
        return (rayleigh_time_step(radius, m_rho, E, nu),
                f"the Rayleigh-wave time π{radius_name}√(ρ/G)/(0.1631ν + 0.8766)")
    kmax = max(max(law.kn, law.ks) for law in family.laws_by_pair.values())
    return 2.0 * math.sqrt(float(mass.min()) / kmax), "2√(m_min/k_max)"


def _chosen_step(scene, dt_crit: float, how: str) -> float:
    """The time step: ``scene.dt_fraction`` × the critical estimate ``dt_crit`` (``how`` names it), or
    ``scene.dt``, refused above the estimate unless ``scene.allow_supercritical``."""
    if scene.dt is None:
        return scene.dt_fraction * dt_crit
    dt = float(scene.dt)
    if dt > dt_crit and not scene.allow_supercritical:
        raise SceneError(f"scene.dt={dt:.6g} exceeds the critical estimate {dt_crit:.6g} ({how}); give a "
                         "smaller dt, leave dt=None for dt_fraction × the estimate, or set "
                         "allow_supercritical=True")
    return dt


def _check_safe_step(scene, dt: float, dt_safe: float, estimate: str = SPHERES_ESTIMATE) -> None:
    """Refuse a step above the safe estimate (warn with allow_unsafe_dt; allow_supercritical accepts it).
    ``estimate`` says what the estimate assumes ("{max_overlap}" is filled in)."""
    if dt <= dt_safe or scene.allow_supercritical:
        return
    field = f"scene.dt={dt:.6g}" if scene.dt is not None else (f"scene.dt_fraction={scene.dt_fraction:g} gives "
                                                               f"dt={dt:.6g}, which")
    what = (f"{field} is above the safe critical time step {dt_safe:.6g} of a packing of these "
            + estimate.format(max_overlap=scene.max_overlap))
    if scene.allow_unsafe_dt:
        import warnings

        from .scene import UnsafeTimeStepWarning

        warnings.warn(f"scene {scene.name!r}: {what}; run anyway (allow_unsafe_dt=True)", UnsafeTimeStepWarning,
                      stacklevel=3)
        return
    raise SceneError(f"{what}; give dt <= {dt_safe:.6g} (or a smaller dt_fraction), declare a smaller "
                     "scene.max_overlap if the contacts stay shallower, or set allow_unsafe_dt=True to run it "
                     "with a warning")


def _skin_and_box(scene, r):
    """The neighbour-list skin and the Box3, refusing periods shorter than twice the reach (``r``:
    the particles' (bounding) radii)."""
    skin = float(scene.skin) if scene.skin is not None else 0.2 * float(r.mean())
    b = scene.box
    lx = (b.periodic_x[1] - b.periodic_x[0]) if b.periodic_x else 0.0
    ly = (b.periodic_y[1] - b.periodic_y[0]) if b.periodic_y else 0.0
    box = Box3(periodic_x=b.periodic_x is not None, periodic_y=b.periodic_y is not None,
               x0=b.periodic_x[0] if b.periodic_x else 0.0, y0=b.periodic_y[0] if b.periodic_y else 0.0,
               lx=float(lx), ly=float(ly))
    reach = 2.0 * float(r.max()) + skin
    for axis, length in (("x", lx), ("y", ly)):
        if length and length <= 2.0 * reach:
            raise SceneError(f"scene.box.periodic_{axis}: the period {length:.6g} must exceed twice the reach "
                             f"2·(2·r_max + skin) = {2.0 * reach:.6g} (minimum image); widen the box to more than "
                             f"{2.0 * reach:.6g} or reduce the skin")
    _check_periodic_meshes(scene, float(r.max()) + skin)
    return skin, box


def _check_periodic_meshes(scene, reach: float) -> None:
    """Meshes in a periodic box.  With ``periodic_images`` (the default) a particle meets each triangle
    through its nearest image, which is the only one within its reach when every triangle is narrower than
    period − 2·reach (``reach`` = r_max + skin): a wider triangle is refused.  Without, warn
    (PeriodicMeshWarning) for each mesh whose vertices lie within ``reach`` of a periodic boundary or beyond
    it: there the contacts are not those of a periodic mesh (measured: an ellipsoid wrapped from a ramp's
    low end at x = 0 to its high end at x = L started 0.17 of its thinnest semi-axis deep and was launched).
    Phases that move a mesh later are not followed by the warning."""
    import warnings

    from .scene import PeriodicMeshWarning

    for mesh in scene.meshes:
        v = np.asarray(mesh.vertices, float)
        for axis, a, per in (("x", 0, scene.box.periodic_x), ("y", 1, scene.box.periodic_y)):
            if per is None or v.size == 0:
                continue
            lo, hi = float(per[0]), float(per[1])
            if mesh.periodic_images:
                t = np.asarray(mesh.triangles, np.int64)
                width = v[t, a].max(axis=1) - v[t, a].min(axis=1)
                widest = int(np.argmax(width))
                limit = (hi - lo) - 2.0 * reach
                if width[widest] >= limit:
                    raise SceneError(
                        f"mesh {mesh.name!r}: triangle {widest} is {width[widest]:.6g} wide along {axis}; with "
                        f"periodic_images every triangle must be narrower than the period {hi - lo:.6g} minus "
                        f"2·(r_max + skin) = {limit:.6g}, or a particle could reach two images of it. Split it into "
                        "narrower triangles (or set periodic_images=False: no images)")
                continue
            margin = min(float(v[:, a].min()) - lo, hi - float(v[:, a].max()))
            if margin < reach:
                warnings.warn(f"scene {scene.name!r}: mesh {mesh.name!r} comes to {margin:.4g} of the periodic boundary "
                              f"along {axis} (scene.box.periodic_{axis}={tuple(per)}), less than a particle's reach "
                              f"r_max + skin = {reach:.4g}; the mesh has periodic_images=False, so a particle wrapped "
                              "across that boundary meets the mesh's other end. Set periodic_images=True, or keep the "
                              "mesh at least that far inside the period", PeriodicMeshWarning,
                              stacklevel=_stacklevel_outside_package())


def _stacklevel_outside_package() -> int:
    """``warnings.warn``'s stacklevel, for a warning issued by this function's caller, that points at the
    first frame outside the demflow package (the user's call of ``build``)."""
    import inspect
    import os

    pkg = os.path.dirname(os.path.abspath(__file__)) + os.sep
    frame = inspect.currentframe().f_back
    level = 1
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(pkg):
        frame = frame.f_back
        level += 1
    return level


def build3d(scene: Scene3D) -> Simulation3D:
    """Check ``scene`` and return a :class:`Simulation3D` ready to run."""
    check_scene3d(scene)
    if scene.ellipsoids is not None:
        from .ellipsoids3d import build_ellipsoids

        return build_ellipsoids(scene)
    s = scene.spheres if scene.spheres is not None else Spheres(x=[], y=[], z=[], radius=[], material=[])
    n = _common_length("scene.spheres", s, ("x", "y", "z", "radius"))
    if n == 0 and (scene.clumps is None or len(scene.clumps) == 0):
        raise SceneError("scene.spheres is empty and there are no clumps; give at least one sphere or clump")
    x = _array("scene.spheres.x", s.x, n)
    y = _array("scene.spheres.y", s.y, n)
    z = _array("scene.spheres.z", s.z, n)
    r = _array("scene.spheres.radius", s.radius, n)
    if np.any(r <= 0):
        k = int(np.argmax(r <= 0))
        raise SceneError(f"scene.spheres.radius[{k}]={float(r[k])!r} must be > 0; give positive radii")
    mats = particle_materials(scene, "spheres", "sphere", s.material, n)
    names = list(scene.materials)
    index = {m: k for k, m in enumerate(names)}
    mat = np.array([index[m] for m in mats], np.int64)
    if s.mass is not None:
        mass = _array("scene.spheres.mass", s.mass, n)
    else:
        rho = np.array([scene.materials[m].density for m in mats])
        mass = rho * 4.0 / 3.0 * math.pi * libm.cube(r)
    if np.any(mass <= 0):
        k = int(np.argmax(mass <= 0))
        where = (f"scene.spheres.mass[{k}]" if s.mass is not None
                 else f"scene.materials[{mats[k]!r}].density (sphere {k})")
        raise SceneError(f"{where}: sphere {k} has mass {float(mass[k])!r}; a mass must be > 0: give a positive density "
                         "or mass")
    vel = np.zeros((n, 3)) if s.velocity is None else _array("scene.spheres.velocity", s.velocity, n, (3,))
    angvel = (np.zeros((n, 3)) if s.angular_velocity is None
              else _array("scene.spheres.angular_velocity", s.angular_velocity, n, (3,)))
    fixed = np.zeros(n, np.int8) if s.fixed is None else _array("scene.spheres.fixed", s.fixed, n,
                                                                    dtype=bool).astype(np.int8)
    body = np.full(n, -1, np.int64)
    bodies = _no_bodies()
    if scene.clumps is not None and len(scene.clumps):
        bodies, members = _clumps(scene.clumps, index, n)
        x, y, z = (np.concatenate([x, members["pos"][:, a]]) for a in range(3))
        r = np.concatenate([r, members["r"]])
        mats = mats + [scene.clumps.material] * len(members["r"])
        mat = np.concatenate([mat, np.full(len(members["r"]), index[scene.clumps.material], np.int64)])
        mass = np.concatenate([mass, members["mass"]])
        vel = np.concatenate([vel, members["vel"]])
        angvel = np.concatenate([angvel, members["angvel"]])
        fixed = np.concatenate([fixed, np.full(len(members["r"]), 2, np.int8)])
        body = np.concatenate([body, members["body"]])
        n = len(r)
    quat = np.zeros((n, 4))
    quat[:, 0] = 1.0

    walls = list(scene.planes) + list(scene.meshes)  # wall bodies: planes, then meshes
    family, params, width = _law_family(scene, mats, names, index, walls)
    planes, tris, loading = _walls(scene, walls, index)
    skin, box = _skin_and_box(scene, r)

    # the critical time step
    inertia = 0.4 * mass * r ** 2
    # members carry their clump's mass (for the dashpots): their density is the material's
    dens = np.array([scene.materials[m].density for m in mats], np.float64)
    m_rho = np.where((fixed == 2) & (dens > 0), dens * 4.0 / 3.0 * math.pi * libm.cube(r), mass)
    dt_crit, how = critical_estimate(scene, family, mats, "sphere", r, m_rho, mass, "R")
    dt = _chosen_step(scene, dt_crit, how)
    dt_safe = _safe_step(scene, family, r, mass, mats, mat, index, walls, body, bodies)
    _check_safe_step(scene, dt, dt_safe)
    d = scene.damping
    refuse_rotational_dashpot(scene, bodies, "clumps")
    # the row layout is measured: with the radius moved beside the position (the distance test then reads one cache
    # line of the other sphere's row, not two) the step at 1e5 spheres took 10 % longer: that test, a loop without
    # branches, brings in the second line the touching pairs' stages then read
    # (benchmarks/results/speed_experiments_session38.md)
    P = np.zeros((n, 16))
    P[:, 9] = r
    P[:, 10] = mass
    P[:, 11] = mat
    P[:, 12] = fixed == 1  # immovable (a clump member moves: its mass column is the clump's)
    sp = Spheres3(pos=np.stack([x, y, z], axis=1), vel=vel, angvel=angvel, quat=quat, r=r, mass=mass,
                  inertia=inertia, inv_r2=1.0 / r ** 2, mat=mat, fixed=fixed, body=body, FM=np.zeros((n, 6)), P=P,
                  ref=np.zeros((n, 3)), img=np.zeros((n, 2), np.int64))
    sim = Simulation3D(scene=scene, spheres=sp, bodies=bodies, planes=planes, tris=tris, loading=loading, law=family, law_params=params,
                        box=box, dt=dt, dt_crit=dt_crit, dt_safe=dt_safe, skin=skin, gravity=scene.gravity, width=width,
                        damping=Damping3(alpha=float(d.alpha), c_abs=float(d.C), c_rot_abs=float(d.C_rot),
                                         local=float(scene.local_damping), adaptive=bool(scene.adaptive_damping),
                                         alpha_now=np.zeros(1), prev_r=np.zeros((n if scene.adaptive_damping else 0, 3)),
                                         prev_dx=np.zeros((n if scene.adaptive_damping else 0, 3))))
    _refuse_initial_overlaps(sim)
    return sim


def refuse_rotational_dashpot(scene, bodies, family: str) -> None:
    """The absolute rotational dashpot C_rot (``GlobalDamping.C_rot``) acts on bodies that turn as a sphere
    (equal principal moments); an aspherical body's rotation (the angular-momentum leapfrog of
    :func:`demflow.stepping3d.body_step`) has mass-proportional damping only.  Refuse the pair instead of
    ignoring C_rot."""
    c_rot = float(scene.damping.C_rot)
    if c_rot == 0.0 or bodies.pos.shape[0] == 0:
        return
    m = bodies.moments
    aspherical = np.flatnonzero((m[:, 0] != m[:, 1]) | (m[:, 1] != m[:, 2]))
    if aspherical.size:
        raise SceneError(f"scene.damping.C_rot={c_rot:g} with aspherical {family} ({aspherical.size} of "
                         f"{m.shape[0]} bodies have unequal principal moments, first body {int(aspherical[0])}): the "
                         "rotational dashpot C_rot is applied to spheres and to bodies with equal principal moments "
                         "only; give C_rot=0 and damp rotation with GlobalDamping.alpha (mass-proportional, it acts "
                         "on the angular momentum) or with local_damping")


def _refuse_initial_overlaps(sim: Simulation3D) -> None:
    """An overlap beyond the blow-up limit at step 0 is bad input, not a blow-up: name the pair."""
    from .contacts.spheres import pack_rows, sphere_forces
    from .stepping3d import MAX_OVERLAP_RATIO

    hist = sim.pairs.hist.copy()
    pack_rows(sim.spheres)
    status, _, _ = sphere_forces(sim.spheres, sim.pairs, sim.planes, sim.tris, sim.law_params, sim.dt, True,
                                 MAX_OVERLAP_RATIO)
    sim.pairs.hist[:] = hist
    sim.spheres.FM[:] = 0.0
    sim.planes.force[:] = 0.0
    if status:
        p = sim.pairs
        r = sim.spheres.r
        n, nw = sim.n, sim.n_planes
        rmin = np.where(p.j < n, np.minimum(r[p.i], r[np.minimum(p.j, n - 1)]), r[p.i])
        k = int(np.argmax(p.ovl / rmin))
        j = int(p.j[k])
        names = [pl.name for pl in sim.scene.planes] + [m.name for m in sim.scene.meshes]
        other = (f"sphere {j}" if j < n else f"wall {names[j - n]!r}" if j < n + nw
                 else f"mesh {names[int(sim.tris.wall[j - n - nw])]!r} (triangle {j - n - nw})")
        raise SceneError(f"sphere {int(p.i[k])} overlaps {other} by {p.ovl[k]:.4g} at the start, more than "
                         f"{MAX_OVERLAP_RATIO:.0%} of the smaller radius ({rmin[k]:.4g}); move them apart")
