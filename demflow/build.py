"""Scene → Simulation: check a scene and allocate only what its physics needs.

Everything a user can get wrong is checked here, before any step runs, and refused with
a message that names the value, the constraint and the fix.
"""
from __future__ import annotations

import math

import numpy as np

from .contacts.neighbours import point_segment_distance
from .integrate import critical_time_step
from .laws import FAMILIES
from .scene import Scene, SceneError, check_identifier
from .space import open_box, periodic_box, wrap
from .state import PeriodicBox


def _as_array(name, v, n):
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape[0] != n:
        raise SceneError(f"discs.{name} has {a.shape[0]} entries for {n} discs; give one per disc")
    if not np.all(np.isfinite(a)):
        k = int(np.flatnonzero(~np.isfinite(a))[0])
        raise SceneError(f"discs.{name}[{k}] = {a[k]} is not finite; give a finite number")
    return a


def _check_discs(scene: Scene):
    d = scene.discs
    n = len(d)
    x = _as_array("x", d.x, n)
    y = _as_array("y", d.y, n)
    r = _as_array("radius", d.radius, n)
    bad = np.flatnonzero(r <= 0)
    if bad.size:
        k = int(bad[0])
        raise SceneError(f"disc {k} has radius {r[k]}; a radius must be > 0")
    mats = [d.material] * n if isinstance(d.material, str) else list(d.material)
    if len(mats) != n:
        raise SceneError(f"discs.material has {len(mats)} entries for {n} discs; give one per disc or one name")
    for k, m in enumerate(mats):
        if m not in scene.materials:
            raise SceneError(
                f"disc {k} uses material {m!r}, which the scene does not declare; "
                f"add it to scene.materials (declared: {sorted(scene.materials)})"
            )
    if d.mass is not None:
        mass = _as_array("mass", d.mass, n)
    else:
        rho = np.array([scene.materials[m].density for m in mats], dtype=np.float64)
        mass = rho * np.pi * r * r
    bad = np.flatnonzero(mass <= 0)
    if bad.size:
        k = int(bad[0])
        raise SceneError(
            f"disc {k} has mass {mass[k]} (material {mats[k]!r}, density "
            f"{scene.materials[mats[k]].density}); a mass must be > 0: set a positive density or mass"
        )
    inertia = 0.5 * mass * r * r
    v = np.zeros((n, 2))
    if d.velocity is not None:
        v = np.asarray(d.velocity, dtype=np.float64).reshape(n, 2)
        if not np.all(np.isfinite(v)):
            raise SceneError("discs.velocity has a non-finite entry; give finite velocities")
    om = np.zeros(n)
    if d.angular_velocity is not None:
        om = _as_array("angular_velocity", d.angular_velocity, n)
    return x, y, r, mats, mass, inertia, v, om


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
            raise SceneError(
                f"{what} overlap by {ov:.6g} at the start, more than the tolerance {lim:.6g} "
                f"(overlap_tolerance={tol} × radius); move them apart or raise scene.overlap_tolerance"
            )


def _check_fluid(scene: Scene, x, y, r, wall_geo):
    """Check a saturated scene's :class:`~demflow.scene.Fluid` and return the
    :class:`~demflow.coupling.FluidSetup` the coupling needs."""
    from .bem.geometry import points_in_polygon, signed_area
    from .coupling import FluidSetup, outer_corners

    f = scene.fluid

    def positive(key, v, allow_zero=False):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and (v >= 0 if allow_zero else v > 0)):
            raise SceneError(f"fluid {key}={v!r}; give a finite number {'>= 0' if allow_zero else '> 0'}")
        return float(v)

    def whole(key, v, lo):
        if not (isinstance(v, (int, np.integer)) and v >= lo):
            raise SceneError(f"fluid {key}={v!r}; give a whole number >= {lo}")
        return int(v)

    mu = positive("viscosity", f.viscosity)
    rho = positive("density", f.density, allow_zero=True)
    n_disc = whole("elements_per_disc", f.elements_per_disc, 8)
    stride = whole("stride", f.stride, 1)
    rec = whole("record_every", f.record_every, 1)
    start = whole("start", f.start, 0)
    if not (0 < f.safety <= 1):
        raise SceneError(f"fluid safety={f.safety}; give a fraction in (0, 1] of the drag stability limit 2τ")
    n = r.shape[0]
    r_min = float(r.min()) if n else 1.0
    gap = 0.01 * r_min if f.min_gap is None else positive("min_gap", f.min_gap)
    if gap >= 0.5 * r_min:
        raise SceneError(f"fluid min_gap={gap} is not small against the smallest radius {r_min}; "
                         "give a gap below half of it (thesis §5.3.3 used 0.01 r)")
    h_max = float(r.mean()) if f.element_length is None else positive("element_length", f.element_length)
    names = [w.name for w in scene.walls]
    bnames = list(f.boundary) if f.boundary is not None else names
    if len(bnames) < 3:
        raise SceneError(f"fluid boundary has {len(bnames)} walls; the fluid needs at least 3 walls around it "
                         "(give Fluid.boundary, the walls counter-clockwise around the fluid)")
    for b in bnames:
        if b not in names:
            raise SceneError(f"fluid boundary names wall {b!r}, which the scene does not have (walls: {names})")
    if len(set(bnames)) != len(bnames):
        raise SceneError(f"fluid boundary {bnames} names a wall twice")
    widx = np.array([names.index(b) for b in bnames], dtype=np.int64)
    g = np.array(wall_geo, dtype=np.float64).reshape(-1, 8)
    try:
        corners = outer_corners(g[widx, 0:2], g[widx, 6:8])
    except ValueError as e:
        raise SceneError(f"fluid boundary {bnames}: {e}; list the walls in order around the fluid") from None
    if signed_area(corners) <= 0:
        raise SceneError(f"fluid boundary {bnames} runs clockwise (or is degenerate); list the walls "
                         "counter-clockwise around the fluid (thesis §4.3.8)")
    if n:
        inside = points_in_polygon(np.column_stack([x, y]), corners)
        if not np.all(inside):
            k = int(np.flatnonzero(~inside)[0])
            raise SceneError(f"disc {k} at ({x[k]:.6g}, {y[k]:.6g}) lies outside the fluid boundary {bnames}")
    lw, lf, ld = [], [], []
    for ld_ in f.loads:
        if ld_.wall not in bnames:
            raise SceneError(f"fluid load on wall {ld_.wall!r}: the wall is not on the fluid boundary {bnames}")
        F = positive(f"load force on {ld_.wall!r}", ld_.force)
        d = np.asarray(ld_.direction, dtype=float)
        L = float(np.hypot(*d))
        if not L > 0:
            raise SceneError(f"fluid load on wall {ld_.wall!r}: direction {ld_.direction} is zero")
        d = d / L
        w = names.index(ld_.wall)
        ex, ey = g[w, 6], g[w, 7]
        if min(abs(d[0]), abs(d[1])) > 1e-12 or abs(d[0] * ex + d[1] * ey) > 1e-9:
            raise SceneError(f"fluid load on wall {ld_.wall!r}: direction {tuple(d)} must be along x or y and "
                             "perpendicular to the wall (the traction replaces one velocity component)")
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
    b = scene.box
    b.check()
    if not b.periodic:
        return open_box()
    (x0, x1) = b.periodic_x if b.periodic_x is not None else (0.0, math.inf)
    (y0, y1) = b.periodic_y if b.periodic_y is not None else (0.0, math.inf)
    box = periodic_box(float(x0), float(y0), float(x1) - float(x0), float(y1) - float(y0))
    skin = scene.skin if scene.skin is not None else (0.2 * float(r.mean()) if r.size else 1.0)
    from .contacts.periodic import check_period

    try:
        check_period(box, r, skin)
    except ValueError as e:
        raise SceneError(f"box: {e}") from None
    return box


def build(scene: Scene):
    """Check ``scene`` and return a ready :class:`~demflow.simulation.Simulation` (a 3D
    :class:`~demflow.scene3d.Scene3D`: a :class:`~demflow.simulation3d.Simulation3D`)."""
    from .scene3d import Scene3D
    from .simulation import Simulation

    if isinstance(scene, Scene3D):
        from .build3d import build3d

        return build3d(scene)

    check_identifier("scene", scene.name)
    for m in scene.materials:
        check_identifier("material", m)
    scene.contact_model.check()
    scene.damping.check()
    x, y, r, mats, mass, inertia, v, om = _check_discs(scene)
    n = x.shape[0]

    # walls
    names = set()
    wall_geo = []
    for w in scene.walls:
        check_identifier("wall", w.name)
        if w.name in names:
            raise SceneError(f"two walls are named {w.name!r}; wall names must be unique")
        names.add(w.name)
        if w.material not in scene.materials:
            raise SceneError(f"wall {w.name!r} uses undeclared material {w.material!r}; add it to scene.materials")
        ex, ey = map(float, w.direction)
        L = math.hypot(ex, ey)
        if not (L > 0 and math.isfinite(L)):
            raise SceneError(f"wall {w.name!r} has direction {w.direction}; give a non-zero finite vector")
        if not (math.isfinite(w.h1) and math.isfinite(w.h2) and w.h1 < w.h2):
            raise SceneError(f"wall {w.name!r} has h1={w.h1}, h2={w.h2}; need finite h1 < h2 (endpoints P+h1·e, P+h2·e)")
        ex, ey = ex / L, ey / L
        px, py = map(float, w.point)
        wall_geo.append((px + w.h1 * ex, py + w.h1 * ey, px + w.h2 * ex, py + w.h2 * ey, px, py, ex, ey))
        for ph in w.phases:
            if int(ph.cycles) != ph.cycles or ph.cycles < 0:
                raise SceneError(f"wall {w.name!r}: phase cycles={ph.cycles}; give a whole number >= 0")
            if not all(math.isfinite(float(c)) for c in (*ph.velocity, ph.omega)):
                raise SceneError(f"wall {w.name!r}: a phase has a non-finite velocity or omega")
        if w.servo is not None:
            s = w.servo
            if not (s.force > 0 and s.gain > 0 and s.v_max > 0):
                raise SceneError(
                    f"wall {w.name!r}: servo force={s.force}, gain={s.gain}, v_max={s.v_max}; all must be > 0"
                )
            for step, force in s.schedule:
                if int(step) != step or step < 0 or not (math.isfinite(force) and force > 0):
                    raise SceneError(f"wall {w.name!r}: servo schedule entry (step={step}, force={force}); "
                                     "give a whole step >= 0 and a force > 0")
            if math.hypot(*s.direction) == 0:
                raise SceneError(f"wall {w.name!r}: servo direction is zero; give the unit load direction")

    # laws for every material pair that can meet, and the one law family that implements them
    mat_names = sorted(scene.materials)
    mid = {m: k for k, m in enumerate(mat_names)}
    disc_mats = sorted(set(mats))
    wall_mats = sorted({w.material for w in scene.walls})
    count = {m: mats.count(m) for m in disc_mats}
    needed = [(a, b) for ia, a in enumerate(disc_mats) for b in disc_mats[ia:]
              if (a != b or count[a] >= 2)]
    needed += [(a, b) for a in disc_mats for b in wall_mats]
    used = {}
    for a, b in needed:
        law = scene.law_for(a, b)
        law.check((a, b))
        used[(a, b)] = law
    family = _law_family(used)
    law = family(scene, used, mid)
    k_max = max([law.stiffness_bound(lw) for lw in used.values()], default=0.0)

    # time step
    dt_crit = critical_time_step(mass, k_max)
    if scene.dt is None:
        if not (0 < scene.dt_fraction <= 1):
            raise SceneError(f"dt_fraction={scene.dt_fraction}; give a fraction in (0, 1] of the critical time step")
        dt = scene.dt_fraction * dt_crit
        if not math.isfinite(dt):
            raise SceneError("no contact law with stiffness applies, so no critical time step exists; give scene.dt")
    else:
        dt = float(scene.dt)
        if not (dt > 0 and math.isfinite(dt)):
            raise SceneError(f"dt={scene.dt}; give a finite time step > 0")
        if dt > dt_crit and not scene.allow_supercritical:
            raise SceneError(
                f"dt={dt:.6g} is above the critical time step 2√(m_min/k_max) = {dt_crit:.6g} "
                f"(m_min={mass.min():.6g}, k_max={k_max:.6g}); use dt <= {0.1 * dt_crit:.6g} "
                "(10 % of critical, thesis §2.2.4.4) or set allow_supercritical=True"
            )

    box = _check_box(scene, r, x, y)
    if n:
        _check_overlaps(x, y, r, wall_geo, scene.overlap_tolerance, box)

    # damping per disc
    d = scene.damping
    if d.alpha > 0:
        C = d.alpha * mass
        Cr = d.alpha * inertia
    else:
        C = np.full(n, d.C)
        Cr = np.full(n, d.C_rot)

    if scene.outputs.every < 0:
        raise SceneError(f"outputs.every={scene.outputs.every}; give 0 (no records) or a positive step count")
    skin = scene.skin if scene.skin is not None else (0.2 * float(r.mean()) if n else 1.0)
    if not (skin > 0 and math.isfinite(skin)):
        raise SceneError(f"skin={skin}; give a positive neighbour-list margin")

    wall_index = {w.name: k for k, w in enumerate(scene.walls)}

    def body(b):
        if isinstance(b, str) and b.startswith("wall:"):
            nm_ = b[5:]
            if nm_ not in wall_index:
                raise SceneError(f"tracked pair names wall {nm_!r}, which the scene does not have")
            return n + wall_index[nm_]
        b = int(b)
        if not 0 <= b < n:
            raise SceneError(f"tracked pair names disc {b}; discs are numbered 0..{n - 1}")
        return b

    track = []
    for a, b in scene.outputs.track_pairs:
        ia, ib = body(a), body(b)
        if ia >= n and ib >= n:
            raise SceneError(f"tracked pair ({a}, {b}) joins two walls; walls do not touch each other")
        if ia >= n or (ib < n and not (r[ia] > r[ib] or (r[ia] == r[ib] and ia < ib))):
            ia, ib = ib, ia
        track.append((ia, ib))

    fluid = _check_fluid(scene, x, y, r, wall_geo) if scene.fluid is not None else None

    sim = Simulation(
        scene=scene, x=x, y=y, r=r, mass=mass, inertia=inertia, v=v, om=om,
        mat=np.array([mid[m] for m in mats], dtype=np.int64),
        wall_geo=wall_geo, wall_mat=np.array([mid[w.material] for w in scene.walls], dtype=np.int64),
        law=law, dt=dt, dt_crit=dt_crit, C=C, Cr=Cr, skin=skin,
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
                f"dt={dt:.6g} is above the fluid drag limit {bound:.6g} = safety·2m/K (m the disc mass, K its "
                f"self-resistance with a wall at the minimum gap {fluid.gap:.4g}; demflow.coupling): the lagged "
                f"explicit drag would oscillate and grow. Use dt <= {bound:.6g}, a larger Fluid.min_gap, or set "
                "allow_supercritical=True")
    return sim
