"""Scene → Simulation: check a scene and allocate only what its physics needs.

Everything a user can get wrong is checked here, before any step runs, and refused with
a message that names the value, the constraint and the fix.
"""
from __future__ import annotations

import math
import warnings

import numpy as np

from .contacts.neighbours import point_segment_distance
from .integrate import critical_time_step, safe_time_step
from .laws import FAMILIES
from .scene import Scene, SceneError, Superquadrics, UnsafeTimeStepWarning, check_vector, is_number, type_phrase
from .space import open_box, periodic_box, wrap
from .state import PeriodicBox
from .validate import check_scene

# Coordinates and radii are kept below this magnitude [length]: squared distances (the contact
# geometry's dx² + dy², R²) of larger values overflow a float64 (1.8e308).
MAX_LENGTH = 1e150


def _as_array(name, v, n=None):
    """discs.<name> as a 1-D float64 array of finite numbers (``n`` entries when given), refused with
    the path of the first bad entry (a bool, a string, None, a non-finite number)."""
    path = f"scene.discs.{name}"
    if isinstance(v, np.ndarray):
        if v.ndim != 1 or v.dtype.kind not in "iuf":
            raise SceneError(f"{path} is an array of shape {v.shape} and dtype {v.dtype}; give a 1-D array "
                             "of numbers, one per disc")
        a = v.astype(np.float64)
    elif isinstance(v, (list, tuple)):
        k = next((k for k, e in enumerate(v) if type(e) is not float and not is_number(e)), None)
        if k is not None:
            raise SceneError(f"{path}[{k}]={v[k]!r} is {type_phrase(v[k])}, not a number; give a finite number")
        a = np.array(v, dtype=np.float64)
    else:
        raise SceneError(f"{path}={v!r} is {type_phrase(v)}; give a list or 1-D array of numbers, one per disc")
    if n is not None and a.shape[0] != n:
        raise SceneError(f"{path} has {a.shape[0]} entries for {n} discs (len(scene.discs.x)); give one per disc")
    if not np.all(np.isfinite(a)):
        k = int(np.flatnonzero(~np.isfinite(a))[0])
        raise SceneError(f"{path}[{k}]={a[k]} is not finite; give a finite number")
    return a


def _check_length_scale(path, a):
    big = np.flatnonzero(np.abs(a) > MAX_LENGTH)
    if big.size:
        k = int(big[0])
        raise SceneError(f"{path}[{k}]={a[k]:g} is beyond ±{MAX_LENGTH:g}, where squared distances overflow; "
                         "rescale the scene's length unit")


def _check_discs(scene: Scene):
    d = scene.discs
    x = _as_array("x", d.x)
    n = x.shape[0]
    y = _as_array("y", d.y, n)
    r = _as_array("radius", d.radius, n)
    bad = np.flatnonzero(r <= 0)
    if bad.size:
        k = int(bad[0])
        raise SceneError(f"scene.discs.radius[{k}]={r[k]}: disc {k} has radius {r[k]}; a radius must be > 0")
    for name, a in (("x", x), ("y", y), ("radius", r)):
        _check_length_scale(f"scene.discs.{name}", a)
    if isinstance(d.material, str):
        mats = [d.material] * n
        paths = ["scene.discs.material"] * n
    else:
        if not isinstance(d.material, (list, tuple, np.ndarray)):
            raise SceneError(f"scene.discs.material={d.material!r} is {type_phrase(d.material)}; give one "
                             "material name or a list of names, one per disc")
        mats = list(d.material)
        paths = [f"scene.discs.material[{k}]" for k in range(len(mats))]
        if len(mats) != n:
            raise SceneError(f"scene.discs.material has {len(mats)} entries for {n} discs; give one per disc or "
                             "one name")
    for k, m in enumerate(mats):
        if not (isinstance(m, str) and m in scene.materials):
            raise SceneError(
                f"{paths[k]}={m!r}: disc {k} uses material {m!r}, which the scene does not declare; "
                f"add it to scene.materials (declared: {sorted(scene.materials)})"
            )
    if d.mass is not None:
        mass = _as_array("mass", d.mass, n)
        bad = np.flatnonzero(mass <= 0)
        if bad.size:
            k = int(bad[0])
            raise SceneError(f"scene.discs.mass[{k}]={mass[k]}: disc {k} has mass {mass[k]}; a mass must be > 0")
    else:
        rho = np.array([float(scene.materials[m].density) for m in mats], dtype=np.float64)
        with np.errstate(over="ignore"):
            mass = rho * np.pi * r * r
        bad = np.flatnonzero(mass <= 0)
        if bad.size:
            k = int(bad[0])
            raise SceneError(
                f"scene.materials[{mats[k]!r}].density={scene.materials[mats[k]].density!r} gives disc {k} the "
                f"mass {mass[k]} (ρπR²); a disc's mass must be > 0: give the material a density > 0 or give "
                "scene.discs.mass"
            )
    with np.errstate(over="ignore"):
        inertia = 0.5 * mass * r * r
    bad = np.flatnonzero(~(np.isfinite(mass) & np.isfinite(inertia)))
    if bad.size:
        k = int(bad[0])
        raise SceneError(f"scene.discs.radius[{k}]={r[k]:g}: disc {k}'s mass {mass[k]:g} or moment of inertia "
                         f"½mR² = {inertia[k]:g} is not finite; give a smaller radius, density or mass (or rescale "
                         "the units)")
    v = np.zeros((n, 2))
    if d.velocity is not None:
        v = _velocities(d.velocity, n)
    om = np.zeros(n)
    if d.angular_velocity is not None:
        om = _as_array("angular_velocity", d.angular_velocity, n)
    return x, y, r, mats, mass, inertia, v, om


def _velocities(vel, n):
    """scene.discs.velocity as an (n, 2) array of finite numbers."""
    path = "scene.discs.velocity"
    if isinstance(vel, np.ndarray) and vel.dtype.kind in "iuf":
        if vel.shape != (n, 2):
            raise SceneError(f"{path} has shape {vel.shape} for {n} discs; give an (n, 2) array (vx, vy) per disc")
        rows = vel
    elif isinstance(vel, (list, tuple, np.ndarray)):
        if len(vel) != n:
            raise SceneError(f"{path} has {len(vel)} entries for {n} discs; give one (vx, vy) per disc")
        rows = vel
    else:
        raise SceneError(f"{path}={vel!r} is {type_phrase(vel)}; give one (vx, vy) per disc")
    if not (isinstance(rows, np.ndarray) and rows.dtype.kind in "iuf" and np.all(np.isfinite(rows))):
        for k, row in enumerate(rows):
            check_vector(f"{path}[{k}]", row, 2, unit="length/time")
    return np.array(rows, dtype=np.float64).reshape(n, 2)


def _check_overlaps(x, y, r, walls, tol, box):
    """Refuse initial disc-disc or disc-wall overlaps beyond tol × the smaller radius (across the
    boundary too in a periodic box)."""
    from .contacts.neighbours import pairs_cell_search
    from .contacts.periodic import pairs_periodic

    n = x.shape[0]
    if n == 0:
        return
    ax = np.array([w[0] for w in walls], dtype=np.float64)
    ay = np.array([w[1] for w in walls], dtype=np.float64)
    bx = np.array([w[2] for w in walls], dtype=np.float64)
    by = np.array([w[3] for w in walls], dtype=np.float64)
    if isinstance(box, PeriodicBox):
        x, y = x.copy(), y.copy()
        wrap(box, x, y, np.zeros(n, np.int64), np.zeros(n, np.int64))
        fi, ot, sx, sy = pairs_periodic(x, y, r, 0.0, ax, ay, bx, by, box)
    else:
        fi, ot = pairs_cell_search(x, y, r, 0.0, ax, ay, bx, by)
        sx = sy = np.zeros(fi.shape[0])
    for i, j, dx0, dy0 in zip(fi, ot, sx, sy):
        if j < n:
            dist = math.hypot(x[j] + dx0 - x[i], y[j] + dy0 - y[i])
            ov = r[i] + r[j] - dist
            lim = tol * min(r[i], r[j])
            what = f"discs {min(i, j)} and {max(i, j)}"
        else:
            _, _, dist = point_segment_distance(x[i], y[i], ax[j - n], ay[j - n], bx[j - n], by[j - n])
            ov = r[i] - dist
            lim = tol * r[i]
            what = f"disc {i} and wall {j - n}"
        if ov > lim:
            where = "scene.discs" if j < n else f"scene.discs and scene.walls[{j - n}]"
            raise SceneError(
                f"{where}: {what} overlap by {ov:.6g} at the start, more than the tolerance {lim:.6g} "
                f"(overlap_tolerance={tol} × radius); move them apart or raise scene.overlap_tolerance"
            )


def _check_fluid(scene: Scene, x, y, r, wall_geo):
    """Check a saturated scene's :class:`~demflow.scene.Fluid` and return the
    :class:`~demflow.coupling.FluidSetup` the coupling needs."""
    from .bem.geometry import points_in_polygon, signed_area
    from .coupling import FluidSetup, outer_corners

    f = scene.fluid  # every field already checked on its own (Fluid.check)
    mu, rho = float(f.viscosity), float(f.density)
    n_disc, stride, rec, start = (int(f.elements_per_disc), int(f.stride), int(f.record_every), int(f.start))
    n = r.shape[0]
    r_min = float(r.min()) if n else 1.0
    gap = 0.01 * r_min if f.min_gap is None else float(f.min_gap)
    if gap >= 0.5 * r_min:
        raise SceneError(f"scene.fluid.min_gap={gap} is not small against the smallest radius {r_min}; "
                         "give a gap below half of it (thesis §5.3.3 used 0.01 r)")
    h_max = float(r.mean()) if f.element_length is None else float(f.element_length)
    names = [w.name for w in scene.walls]
    bnames = list(f.boundary) if f.boundary is not None else names
    if len(bnames) < 3:
        raise SceneError(f"scene.fluid.boundary has {len(bnames)} walls; the fluid needs at least 3 walls around it "
                         "(give Fluid.boundary, the walls counter-clockwise around the fluid)")
    for b in bnames:
        if b not in names:
            raise SceneError(f"scene.fluid.boundary names wall {b!r}, which the scene does not have (walls: {names})")
    if len(set(bnames)) != len(bnames):
        raise SceneError(f"scene.fluid.boundary {bnames} names a wall twice; name each wall once")
    widx = np.array([names.index(b) for b in bnames], dtype=np.int64)
    g = np.array(wall_geo, dtype=np.float64).reshape(-1, 8)
    try:
        corners = outer_corners(g[widx, 0:2], g[widx, 6:8])
    except ValueError as e:
        raise SceneError(f"scene.fluid.boundary {bnames}: {e}; list the walls in order around the fluid") from None
    if signed_area(corners) <= 0:
        raise SceneError(f"scene.fluid.boundary {bnames} runs clockwise (or is degenerate); list the walls "
                         "counter-clockwise around the fluid (thesis §4.3.8)")
    if n:
        inside = points_in_polygon(np.column_stack([x, y]), corners)
        if not np.all(inside):
            k = int(np.flatnonzero(~inside)[0])
            raise SceneError(f"scene.discs: disc {k} at ({x[k]:.6g}, {y[k]:.6g}) lies outside the fluid boundary "
                             f"{bnames} (scene.fluid.boundary); move it inside or list the walls around it")
    lw, lf, ld = [], [], []
    for q, ld_ in enumerate(f.loads):
        path = f"scene.fluid.loads[{q}]"
        if ld_.wall not in bnames:
            raise SceneError(f"{path}.wall={ld_.wall!r} is not on the fluid boundary {bnames}; load a boundary wall")
        F = float(ld_.force)
        d = np.asarray(ld_.direction, dtype=float)
        d = d / float(np.hypot(*d))
        w = names.index(ld_.wall)
        ex, ey = g[w, 6], g[w, 7]
        if min(abs(d[0]), abs(d[1])) > 1e-12 or abs(d[0] * ex + d[1] * ey) > 1e-9:
            raise SceneError(f"{path}.direction={ld_.direction!r} on wall {ld_.wall!r}: the direction must be along "
                             "x or y and perpendicular to the wall (the traction replaces one velocity component)")
        lw.append(w)
        lf.append(F)
        ld.append(d)
    return FluidSetup(mu=mu, rho=rho, boundary=widx, n_disc=n_disc, element_length=h_max, gap=gap,
                      stride=stride, adaptive=bool(f.adaptive), safety=float(f.safety), moments=bool(f.moments),
                      load_wall=np.array(lw, dtype=np.int64), load_force=np.array(lf, dtype=float),
                      load_dir=np.array(ld, dtype=float).reshape(-1, 2), record_every=rec,
                      quadrature=int(f.quadrature), start=start)


def _law_family(used: dict):
    """The one law family implementing every declared law that applies (demflow.laws.FAMILIES)."""
    found = set()
    for pair, law in used.items():
        fam = next((f for f in FAMILIES if f.accepts(law)), None)
        if fam is None:
            raise SceneError(f"law {pair} is a {type(law).__name__}, which no law family implements; "
                             f"use one of {[f.name for f in FAMILIES]}")
        found.add(fam)
    if len(found) > 1:
        raise SceneError(f"the scene mixes law families {sorted(f.name for f in found)}; "
                         "declare every material pair's law in one family")
    return found.pop() if found else FAMILIES[0]


def _check_box(scene: Scene, r, x, y):
    """The compiled box of ``scene.box``: open, or periodic (period >= twice the neighbour reach)."""
    b = scene.box  # bounds checked by Box.check
    if not b.periodic:
        return open_box()
    (x0, x1) = b.periodic_x if b.periodic_x is not None else (0.0, math.inf)
    (y0, y1) = b.periodic_y if b.periodic_y is not None else (0.0, math.inf)
    box = periodic_box(float(x0), float(y0), float(x1) - float(x0), float(y1) - float(y0))
    skin = scene.skin if scene.skin is not None else (0.2 * float(r.mean()) if r.size else 1.0)
    from .contacts.periodic import check_period

    for axis, bounds in (("x", b.periodic_x), ("y", b.periodic_y)):
        if bounds is not None:
            _check_length_scale(f"scene.box.periodic_{axis}", np.asarray(bounds, dtype=np.float64))
    try:
        check_period(box, r, skin)
    except ValueError as e:
        axis = "x" if "along x" in str(e) else "y"
        raise SceneError(f"scene.box.periodic_{axis}: {e}") from None
    return box


def _tracked_pairs(scene: Scene, r):
    """scene.outputs.track_pairs as (finder, other) keys (a disc index, or n + wall index)."""
    n = r.shape[0]
    wall_index = {w.name: k for k, w in enumerate(scene.walls)}

    def body(path, b):
        if isinstance(b, str) and b.startswith("wall:"):
            if b[5:] not in wall_index:
                raise SceneError(f"{path} names wall {b[5:]!r}, which the scene does not have "
                                 f"(walls: {list(wall_index)}); give 'wall:NAME' of one of them")
            return n + wall_index[b[5:]]
        if not (is_number(b) and float(b).is_integer() and 0 <= b < n):
            raise SceneError(f"{path}={b!r} is not a disc index 0..{n - 1} or 'wall:NAME'; give one of those")
        return int(b)

    track = []
    for k, (a, b) in enumerate(scene.outputs.track_pairs):
        path = f"scene.outputs.track_pairs[{k}]"
        ia, ib = body(path, a), body(path, b)
        if ia >= n and ib >= n:
            raise SceneError(f"{path}=({a!r}, {b!r}) joins two walls; walls do not touch each other, track a disc")
        if ia == ib:
            raise SceneError(f"{path}=({a!r}, {b!r}) joins disc {ia} with itself; a contact joins two bodies, give "
                             "two different discs (or a disc and 'wall:NAME')")
        if ia >= n or (ib < n and not (r[ia] > r[ib] or (r[ia] == r[ib] and ia < ib))):
            ia, ib = ib, ia
        track.append((ia, ib))
    return track


def material_laws(scene, mats: list):
    """The laws of every material pair that can meet (particle materials ``mats``, one per particle, and
    the walls'), and the one law family that implements them.  Returns (material names sorted, their
    index, {pair: law}, the law family instance, the largest stiffness bound)."""
    mat_names = sorted(scene.materials)
    mid = {m: k for k, m in enumerate(mat_names)}
    disc_mats = sorted(set(mats))
    wall_mats = sorted({w.material for w in scene.walls})
    count = {m: mats.count(m) for m in disc_mats}
    needed = [(a, b) for ia, a in enumerate(disc_mats) for b in disc_mats[ia:]
              if (a != b or count[a] >= 2)]
    needed += [(a, b) for a in disc_mats for b in wall_mats]
    used = {(a, b): scene.law_for(a, b) for a, b in needed}  # each checked by its key (demflow.validate)
    family = _law_family(used)
    law = family(scene, used, mid)
    k_max = max([law.stiffness_bound(lw) for lw in used.values()], default=0.0)
    return mat_names, mid, used, law, k_max


def _safe_time_step(scene: Scene, family, used: dict, r, mass, inertia, mats, mid) -> dict:
    """:func:`demflow.integrate.safe_time_step` of the scene: its laws' springs and dashpots by
    disc material pair and against the walls (each wall by its own law)."""
    disc_mat = np.array([mid[m] for m in mats], dtype=np.int64)
    present = set(mats)
    count = {m: mats.count(m) for m in present}
    disc_laws = {}
    for a in present:
        for b in present:
            if a != b or count[a] >= 2:
                disc_laws[(mid[a], mid[b])] = family.time_step_constants(scene.law_for(a, b))
    wall_laws = {}
    for a in present:
        wall_laws[mid[a]] = [family.time_step_constants(scene.law_for(a, w.material)) for w in scene.walls]
    return safe_time_step(r, mass, inertia, disc_mat, disc_laws, wall_laws)


def _unsafe_dt(scene: Scene, dt: float, dt_crit: float, safe: dict, mass, r) -> None:
    """Refuse (or, with allow_unsafe_dt or allow_supercritical, warn about) a step above the safe critical
    time step."""
    i = safe["disc"]
    how = (f"the highest mode of a packing, translations and rotations coupled through the shear springs: "
           f"ω_max² <= {safe['omega2']:.6g} (disc {i}, mass {mass[i]:.6g}, radius {r[i]:.6g}, up to "
           f"{safe['contacts']} contacts), dashpot rate <= {safe['gamma']:.6g}; demflow.integrate.safe_time_step")
    where = (f"scene.dt={dt:.6g}" if scene.dt is not None else
             f"scene.dt_fraction={scene.dt_fraction!r} gives dt={dt:.6g} ({scene.dt_fraction!r} × 2√(m_min/k_max), "
             f"{dt_crit:.6g}), which")
    if scene.allow_supercritical or scene.allow_unsafe_dt:
        flag = "allow_supercritical" if scene.allow_supercritical else "allow_unsafe_dt"
        warnings.warn(f"scene {scene.name!r}: {where} is above the safe critical time step {safe['dt']:.6g} ({how}); "
                      f"allowed by {flag}=True: the run may grow unstable (the energy check raises BlowUpError)",
                      UnsafeTimeStepWarning, stacklevel=3)
        return
    fix = (f"give dt <= {safe['dt']:.6g}" if scene.dt is not None else
           f"give dt_fraction <= {safe['dt'] / dt_crit:.4g}")
    raise SceneError(f"{where} is above the safe critical time step {safe['dt']:.6g} ({how}); {fix} "
                     f"(e.g. half of it), or set allow_unsafe_dt=True to run it anyway (a packing looser than the worst case "
                     "the estimate assumes can be stable above it)")



def wall_geometry(scene) -> list:
    """Per wall of ``scene.walls`` (fields checked by Wall.check): (ax, ay, bx, by, px, py, ex, ey), the
    endpoints A = P + h1·e, B = P + h2·e, the point P and the unit direction e, with every endpoint
    within MAX_LENGTH."""
    wall_geo = []
    for i, w in enumerate(scene.walls):
        ex, ey = map(float, w.direction)
        L = math.hypot(ex, ey)
        ex, ey = ex / L, ey / L
        px, py = map(float, w.point)
        h1, h2 = float(w.h1), float(w.h2)
        geo = (px + h1 * ex, py + h1 * ey, px + h2 * ex, py + h2 * ey, px, py, ex, ey)
        if not all(abs(c) <= MAX_LENGTH for c in geo):
            p = f"scene.walls[{i}]"
            raise SceneError(f"{p}.point={w.point!r}, {p}.h1={w.h1!r} and {p}.h2={w.h2!r} (wall {w.name!r}) put an "
                             f"endpoint beyond ±{MAX_LENGTH:g}, where squared distances overflow; give a wall "
                             "within that range (or rescale the length unit)")
        wall_geo.append(geo)
    return wall_geo


def build(scene: Scene):
    """Check ``scene`` and return a ready :class:`~demflow.simulation.Simulation` (a 3D
    :class:`~demflow.scene3d.Scene3D`: a :class:`~demflow.simulation3d.Simulation3D`)."""
    from .scene3d import Scene3D
    from .simulation import Simulation, check_run_length

    if isinstance(scene, Scene3D):
        from .build3d import build3d

        return build3d(scene)

    check_scene(scene)  # every field on its own and the references between objects (demflow.validate)
    if isinstance(scene.discs, Superquadrics):
        from .simulation_sq2d import build_superquadrics

        return build_superquadrics(scene)
    x, y, r, mats, mass, inertia, v, om = _check_discs(scene)
    n = x.shape[0]

    wall_geo = wall_geometry(scene)

    mat_names, mid, used, law, k_max = material_laws(scene, mats)

    # time step: dt_fraction is a fraction of the single-spring estimate (so that derived steps stay what
    # they were); the step is refused above the safe estimate of the packing's highest mode
    dt_crit = critical_time_step(mass, k_max)
    safe = _safe_time_step(scene, law, used, r, mass, inertia, mats, mid)
    dt_safe = safe["dt"]
    if scene.dt is None:
        dt = float(scene.dt_fraction) * dt_crit
        if not (math.isfinite(dt) and dt > 0):
            raise SceneError("scene.dt=None: no contact law with stiffness applies (critical time step "
                             f"{dt_crit:g}), so no time step can be derived; give scene.dt")
    else:
        dt = float(scene.dt)
        if dt > dt_crit and not scene.allow_supercritical:
            raise SceneError(
                f"scene.dt: dt={dt:.6g} is above the critical time step 2√(m_min/k_max) = {dt_crit:.6g} "
                f"(m_min={mass.min():.6g}, k_max={k_max:.6g}); use dt <= {0.1 * dt_crit:.6g} "
                "(10 % of critical, thesis §2.2.4.4) or set allow_supercritical=True"
            )
    if dt > dt_safe:
        _unsafe_dt(scene, dt, dt_crit, safe, mass, r)

    box = _check_box(scene, r, x, y)
    if n:
        _check_overlaps(x, y, r, wall_geo, scene.overlap_tolerance, box)

    # damping per disc
    d = scene.damping
    if d.alpha > 0:
        C = d.alpha * mass
        Cr = d.alpha * inertia
    else:
        C = np.full(n, float(d.C))
        Cr = np.full(n, float(d.C_rot))
    if not (np.all(np.isfinite(C)) and np.all(np.isfinite(Cr))):
        raise SceneError(f"scene.damping.alpha={d.alpha!r} times a disc's mass or inertia is not finite; give a "
                         "smaller alpha")
    skin = float(scene.skin) if scene.skin is not None else (0.2 * float(r.mean()) if n else 1.0)
    track = _tracked_pairs(scene, r)
    check_run_length("scene.n_steps", int(scene.n_steps), scene, n, len(scene.walls), len(track))

    fluid = _check_fluid(scene, x, y, r, wall_geo) if scene.fluid is not None else None

    sim = Simulation(
        scene=scene, x=x, y=y, r=r, mass=mass, inertia=inertia, v=v, om=om,
        mat=np.array([mid[m] for m in mats], dtype=np.int64),
        wall_geo=wall_geo, wall_mat=np.array([mid[w.material] for w in scene.walls], dtype=np.int64),
        law=law, dt=dt, dt_crit=dt_crit, dt_safe=dt_safe, C=C, Cr=Cr, skin=skin,
        gravity=tuple(map(float, scene.gravity)), track=track, material_names=mat_names, fluid=fluid, box=box,
    )
    if fluid is not None:
        # the fluid's own stability limit (explicit lagged drag, see demflow.coupling)
        bound = sim.fluid.time_step_bound(sim)
        sim.dt_fluid = bound
        if scene.dt is None:
            sim.dt = min(sim.dt, bound)
        elif dt > bound and not scene.allow_supercritical:
            raise SceneError(
                f"scene.dt={dt:.6g} is above the fluid drag limit {bound:.6g} = safety·2m/K (m the disc mass, K its "
                f"self-resistance with a wall at the minimum gap {fluid.gap:.4g}; demflow.coupling): the lagged "
                f"explicit drag would oscillate and grow. Use dt <= {bound:.6g} (or dt=None: the default step "
                "is capped at this limit), a larger Fluid.min_gap, or set allow_supercritical=True")
    return sim
