"""2D superquadric particles: build, compiled cycle and the Python-side simulation (Miyata §2.3).

A scene whose ``discs`` is a :class:`~demflow.scene.Superquadrics` is built here by
:func:`build_superquadrics` (called from :func:`demflow.build.build`).  This is a path of its own
beside the disc cycle (:mod:`demflow.stepping`), not a branch in it: the disc kernels are unchanged
to the bit.  It reuses the disc path's pieces:

- the neighbour search (:func:`~demflow.contacts.neighbours.pairs_cell_search` on the bounding
  radii, keyed pairs, :func:`~demflow.contacts.neighbours.transfer_history`);
- the linear law's per-contact kernel (:func:`~demflow.laws.linear.linear_contact`, thesis eqs
  2.7-2.20) with the scene's :class:`~demflow.scene.LinearLaw` tables and contact model;
- the walls (segments, prescribed phases, servo control: :mod:`demflow.walls`);
- the central-difference update with global damping (thesis eqs 2.27-2.30, as
  :mod:`demflow.integrate`), with the polar moment of inertia of the superquadric.

The pair geometry is :func:`demflow.shapes.superquadric.pair_contact` (Brent minimisation of the
geometric potential, warm-started from the last step's surface parameters, which are kept in the
contact's history row with the law's springs) and
:func:`~demflow.shapes.superquadric.segment_contact` for walls.  The contact reduces to two discs,
the circles of curvature (eqs 38-42), so the contact kinematics are the disc code's with lever arms
Q - x (see :mod:`demflow.shapes.superquadric`).  Miyata's restitution dashpot (eq 17) is added per
contact from the pair's effective mass when ``Superquadrics.restitution`` is given.

A box periodic along x and/or y (:class:`~demflow.scene.Box`) is handled as on the disc path
(:mod:`demflow.space`, :mod:`demflow.contacts.periodic`): centroids are wrapped into the box at every
neighbour-list build (image counters ``sim.ix``, ``sim.iy`` keep unwrapped positions), pairs are
listed by minimum image on the bounding circles, and each pair carries the shift (sx, sy) of its
other particle's image, added to the centre difference before the pair geometry.

Not (yet) supported on this path, and refused by the build: a pore fluid, tracked pairs and
snapshots.  The cycle is serial (deterministic: pairs and particles in a fixed order).

History row of a pair (5 columns): N, S (the linear law's springs), α_i, α_j (the last minimisers
on the finder's and the other's surface; α_i only for a wall pair) and a flag (1: α valid).
"""
from __future__ import annotations

import math
from collections import namedtuple
from pathlib import Path

import numpy as np

from .checkpoint_scene import check_same_scene, last_good_path, read_checkpoint, scene_digest, write_checkpoint
from .contacts.neighbours import pairs_cell_search, transfer_history
from .integrate import critical_time_step
from .jit import njit
from .laws.linear import linear_contact
from .scene import SceneError, type_phrase
from .shapes import superquadric as sq
from .walls import move_walls, set_wall_velocities

DONE = 0
REBUILD = 1
BLOWUP = 2
HIST = 5  # N, S, α_i, α_j, valid
MAX_OVERLAP_RATIO = 0.5  # default: an overlap beyond this fraction of the smaller semi-axis is a blow-up (as the disc
# cycle); Superquadrics.max_overlap changes it per scene (knobs.max_overlap)
MAX_STEP_RATIO = 0.5  # a particle moving more than this fraction of its smaller semi-axis in one step: blow-up

SQBodies = namedtuple("SQBodies", [
    "x", "y", "th",          # centroid [length], orientation of the body x axis [rad]
    "vx", "vy", "om",        # velocity at the half step [length/time], spin [1/time]
    "a", "b", "n", "rb",     # semi-axes [length], exponent, bounding radius [length]
    "mass", "inertia",       # [mass], polar moment about the centroid [mass·length²]
    "C", "Cr",               # global dashpots (thesis eqs 2.27-2.28)
    "mat",                   # material index (int64)
    "xref", "yref",          # centroid at the last neighbour-list build [length]
    "Fx", "Fy", "M",         # contact force and moment sums of the last step
])

# the dynamic state of the bodies and walls (checkpoints, the last good state)
_SQ_STATE = ("x", "y", "th", "vx", "vy", "om", "xref", "yref", "Fx", "Fy", "M")
_SQ_WALL_STATE = ("px", "py", "ex", "ey", "vx", "vy", "om", "cx", "cy", "force")

SQPairOut = namedtuple("SQPairOut", [
    "ovl",         # overlap δ [length] (eq 42; <= 0 apart)
    "fn", "fs",    # total normal and shear force [force]
    "nx", "ny",    # unit normal from the finder to the other (C_i → C_j)
    "cpx", "cpy",  # contact point [length]
])

SQKnobs = namedtuple("SQKnobs", [
    "tol",     # Brent tolerance on α [rad]
    "window",  # warm-start bracket half-width [rad]
    "max_overlap",  # blow-up: an overlap beyond this fraction of the pair's smaller semi-axis
    "zeta",    # (nm, nm) damping ratio of Miyata eq 17 per material pair (0: none)
])


@njit
def _pair(k, i, j, nb, bd, sx, sy, walls, hist, law, knobs, dt, counters):
    """Geometry and force of pair k (finder i, other j; j >= nb: wall j - nb).  Returns
    (δ, nx, ny, fx, fy, Mi, Mj, Fn, Fs, cpx, cpy): the force (fx, fy) on i, the moments on i and on j
    (or on the wall about its point P), the total normal and shear force and the contact point.
    (sx[k], sy[k]): the shift of j's image in a periodic box (0 in an open box) [length]."""
    xi = bd.x[i]
    yi = bd.y[i]
    warm = hist[k, 4] > 0.0
    if j < nb:
        dx = bd.x[j] + sx[k] - xi
        dy = bd.y[j] + sy[k] - yi
        reach = bd.rb[i] + bd.rb[j]
        if dx * dx + dy * dy >= reach * reach:
            return -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, xi, yi
        delta, ex, ey, Cix, Ciy, rhoi, Cjx, Cjy, rhoj, ali, alj, ev = sq.pair_contact(
            dx, dy, bd.th[i], bd.th[j], bd.a[i], bd.b[i], bd.n[i], bd.rb[i], bd.a[j], bd.b[j], bd.n[j], bd.rb[j],
            hist[k, 2], hist[k, 3], warm, knobs.tol, knobs.window)
        hist[k, 2] = ali
        hist[k, 3] = alj
        hist[k, 4] = 1.0
        counters[0] += ev
        counters[1] += 1
        lix = Cix + rhoi * ex  # lever arms Q - x (module doc of demflow.shapes.superquadric)
        liy = Ciy + rhoi * ey
        ljx = Cjx - rhoj * ex
        ljy = Cjy - rhoj * ey
        rvx = bd.vx[i] - bd.om[i] * liy - (bd.vx[j] - bd.om[j] * ljy)
        rvy = bd.vy[i] + bd.om[i] * lix - (bd.vy[j] + bd.om[j] * ljx)
        mi = bd.mass[i]
        mj = bd.mass[j]
        meff = mi * mj / (mi + mj)
        mb = bd.mat[j]
        cpx = xi + Cix + (rhoi - 0.5 * delta) * ex
        cpy = yi + Ciy + (rhoi - 0.5 * delta) * ey
    else:
        w = j - nb
        ax = walls.px[w] + walls.h1[w] * walls.ex[w]
        ay = walls.py[w] + walls.h1[w] * walls.ey[w]
        bx = walls.px[w] + walls.h2[w] * walls.ex[w]
        by = walls.py[w] + walls.h2[w] * walls.ey[w]
        delta, ex, ey, lix, liy, qx, qy, ali, ev = sq.segment_contact(
            xi, yi, bd.th[i], bd.a[i], bd.b[i], bd.n[i], bd.rb[i], ax, ay, bx, by, hist[k, 2], warm, knobs.tol,
            knobs.window)
        hist[k, 2] = ali
        hist[k, 4] = 1.0 if ev > 0 or warm else 0.0
        counters[0] += ev
        counters[1] += 1
        ljx = qx - walls.px[w]  # lever arm of the wall's force about its point P
        ljy = qy - walls.py[w]
        wvx = walls.vx[w] - walls.om[w] * (qy - walls.cy[w])
        wvy = walls.vy[w] + walls.om[w] * (qx - walls.cx[w])
        rvx = bd.vx[i] - bd.om[i] * liy - wvx
        rvy = bd.vy[i] + bd.om[i] * lix - wvy
        meff = bd.mass[i]
        mb = walls.mat[w]
        cpx = 0.5 * (xi + lix + qx)
        cpy = 0.5 * (yi + liy + qy)
    if delta <= 0.0:
        return delta, ex, ey, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, cpx, cpy
    ma = bd.mat[i]
    tx = ey
    ty = -ex
    ndot = rvx * ex + rvy * ey
    sdot = rvx * tx + rvy * ty
    kn = law.kn[ma, mb]
    cn = law.cn[ma, mb] + 2.0 * knobs.zeta[ma, mb] * math.sqrt(kn * meff)  # Miyata eq 17
    N, S, Fn, Fs, sliding = linear_contact(delta, ndot, sdot, hist[k, 0], hist[k, 1], dt, kn, law.ks[ma, mb], cn,
                                           law.cs[ma, mb], law.mu[ma, mb], law.coh[ma, mb], law.normal_mode,
                                           law.sliding_mode, law.has_shear)
    hist[k, 0] = N
    hist[k, 1] = S
    fx = -Fn * ex - Fs * tx
    fy = -Fn * ey - Fs * ty
    Mi = lix * fy - liy * fx
    Mj = ljy * fx - ljx * fy  # (l_j) × (-f)
    return delta, ex, ey, fx, fy, Mi, Mj, Fn, Fs, cpx, cpy


@njit
def pair_pass(bd, finder, other, sx, sy, hist, out, walls, law, knobs, dt, counters):
    """Every listed pair once, in key order: forces summed into bd.Fx, bd.Fy, bd.M (and the walls'
    force and moment about P, walls.force), outputs into ``out``.  Returns the number of pairs beyond
    knobs.max_overlap or with a non-finite force, and the elastic energy Σ N²/2kN + S²/2kS."""
    nb = bd.x.shape[0]
    bd.Fx[:] = 0.0
    bd.Fy[:] = 0.0
    bd.M[:] = 0.0
    walls.force[:, :] = 0.0
    nbad = 0
    elastic = 0.0
    for k in range(finder.shape[0]):
        i = finder[k]
        j = other[k]
        delta, ex, ey, fx, fy, Mi, Mj, Fn, Fs, cpx, cpy = _pair(k, i, j, nb, bd, sx, sy, walls, hist, law, knobs,
                                                                dt, counters)
        out.ovl[k] = delta
        out.nx[k] = ex
        out.ny[k] = ey
        out.cpx[k] = cpx
        out.cpy[k] = cpy
        out.fn[k] = Fn
        out.fs[k] = Fs
        if delta <= 0.0:
            hist[k, 0] = 0.0  # contact broken: the springs are cleared, the warm start is kept
            hist[k, 1] = 0.0
            continue
        bd.Fx[i] += fx
        bd.Fy[i] += fy
        bd.M[i] += Mi
        ma = bd.mat[i]
        if j < nb:
            bd.Fx[j] -= fx
            bd.Fy[j] -= fy
            bd.M[j] += Mj
            mb = bd.mat[j]
            smallest = min(min(bd.a[i], bd.b[i]), min(bd.a[j], bd.b[j]))
        else:
            w = j - nb
            walls.force[w, 0] -= fx
            walls.force[w, 1] -= fy
            walls.force[w, 2] += Mj
            mb = walls.mat[w]
            smallest = min(bd.a[i], bd.b[i])
        elastic += 0.5 * hist[k, 0] ** 2 / law.kn[ma, mb]
        if law.has_shear and law.ks[ma, mb] > 0.0:
            elastic += 0.5 * hist[k, 1] ** 2 / law.ks[ma, mb]
        if not (delta <= knobs.max_overlap * smallest and np.isfinite(Fn) and np.isfinite(Fs)):
            nbad += 1
    return nbad, elastic


@njit
def integrate(bd, gx, gy, dt):
    """Central differences with global damping (thesis eqs 2.27-2.30) for every particle.  Returns
    (largest squared displacement since the build, largest squared step over the smaller semi-axis,
    kinetic energy at the full step from the mean of the half-step velocities)."""
    dmax2 = 0.0
    jump2 = 0.0
    ke = 0.0
    for i in range(bd.x.shape[0]):
        m = bd.mass[i]
        inertia = bd.inertia[i]
        a = bd.C[i] * dt / (2.0 * m)
        vx = (bd.vx[i] * (1.0 - a) + (bd.Fx[i] / m + gx) * dt) / (1.0 + a)
        vy = (bd.vy[i] * (1.0 - a) + (bd.Fy[i] / m + gy) * dt) / (1.0 + a)
        b = bd.Cr[i] * dt / (2.0 * inertia)
        om = (bd.om[i] * (1.0 - b) + bd.M[i] * dt / inertia) / (1.0 + b)
        mvx = 0.5 * (vx + bd.vx[i])
        mvy = 0.5 * (vy + bd.vy[i])
        mom = 0.5 * (om + bd.om[i])
        ke += 0.5 * (m * (mvx * mvx + mvy * mvy) + inertia * mom * mom)
        bd.vx[i] = vx
        bd.vy[i] = vy
        bd.om[i] = om
        bd.x[i] += vx * dt
        bd.y[i] += vy * dt
        bd.th[i] += om * dt
        ddx = bd.x[i] - bd.xref[i]
        ddy = bd.y[i] - bd.yref[i]
        dmax2 = max(dmax2, ddx * ddx + ddy * ddy)
        s = min(bd.a[i], bd.b[i])
        jump2 = max(jump2, (vx * vx + vy * vy) * dt * dt / (s * s))
    return dmax2, jump2, ke


@njit
def run_sq_steps(n, step0, skin, disp_walls, bd, finder, other, sx, sy, hist, out, walls, loading, law, knobs, dt,
                 gx, gy, every, rec, rec_count, counters):
    """Run up to n steps from step ``step0``; stop early when the neighbour list is stale (REBUILD: the
    largest displacement since the build plus the walls' exceeds skin/2) or on a blow-up (BLOWUP; the
    step that found it was not applied).  Every ``every``-th step (0: none) writes a row
    (step, kinetic energy at the full step, elastic energy) of ``rec``.  Returns (steps done, status,
    disp_walls, rec_count)."""
    for s in range(n):
        step = step0 + s
        nbad, elastic = pair_pass(bd, finder, other, sx, sy, hist, out, walls, law, knobs, dt, counters)
        if nbad > 0:
            return s, BLOWUP, disp_walls, rec_count
        set_wall_velocities(step, walls, loading)
        dmax2, jump2, ke = integrate(bd, gx, gy, dt)
        if every > 0 and step % every == 0 and rec_count < rec.shape[0]:
            rec[rec_count, 0] = step
            rec[rec_count, 1] = ke
            rec[rec_count, 2] = elastic
            rec_count += 1
        if jump2 > MAX_STEP_RATIO * MAX_STEP_RATIO or not np.isfinite(jump2):
            return s + 1, BLOWUP, disp_walls, rec_count
        disp_walls += move_walls(walls, dt)
        if math.sqrt(dmax2) + disp_walls > 0.5 * skin:
            return s + 1, REBUILD, disp_walls, rec_count
    return n, DONE, disp_walls, rec_count


# ----------------------------------------------------------------------------------------- build
def _refuse_unsupported(scene) -> None:
    if scene.fluid is not None:
        raise SceneError("scene.fluid is set on a scene of Superquadrics; the saturated coupling is for discs only: "
                         "give scene.fluid=None or use Discs")
    for key in ("track_pairs", "snapshots"):
        v = getattr(scene.outputs, key)
        if len(v):
            raise SceneError(f"scene.outputs.{key}={v!r}: {key} are not recorded for Superquadrics yet; give "
                             f"scene.outputs.{key}=() (sim.contacts() gives the contacts at any time)")


def _with_skin(scene, skin):
    import dataclasses

    return dataclasses.replace(scene, skin=skin)


def build_superquadrics(scene):
    """Check a scene of :class:`~demflow.scene.Superquadrics` (its fields are already checked by
    :func:`demflow.validate.check_scene`) and return a ready :class:`SuperquadricSimulation`."""
    from .build import _as_array, _check_length_scale, _velocities, material_laws, wall_geometry
    from .laws.restitution import zeta_linear
    from .simulation import walls_and_loading

    from .simulation import check_run_length

    _refuse_unsupported(scene)
    p = scene.discs
    x = _as_array("x", p.x)
    nb = x.shape[0]
    y = _as_array("y", p.y, nb)
    a = _as_array("a", p.a, nb)
    b = _as_array("b", p.b, nb)
    nexp = _as_array("n", p.n, nb)
    th = _as_array("theta", p.theta, nb) if p.theta is not None else np.zeros(nb)
    for name, arr in (("x", x), ("y", y), ("a", a), ("b", b)):
        _check_length_scale(f"scene.discs.{name}", arr)
    if isinstance(p.material, str):
        mats = [p.material] * nb
    else:
        if not isinstance(p.material, (list, tuple, np.ndarray)):
            raise SceneError(f"scene.discs.material={p.material!r} is {type_phrase(p.material)}; give one material "
                             "name or a list of names, one per particle")
        mats = list(p.material)
        if len(mats) != nb:
            raise SceneError(f"scene.discs.material has {len(mats)} entries for {nb} particles; give one per particle "
                             "or one name")
    for k, m in enumerate(mats):
        if not (isinstance(m, str) and m in scene.materials):
            where = "scene.discs.material" + ("" if isinstance(p.material, str) else f"[{k}]")
            raise SceneError(f"{where}={m!r}: particle {k} uses material {m!r}, which the scene does not declare; "
                             f"add it to scene.materials (declared: {sorted(scene.materials)})")
    rb = np.array([sq.bounding_radius(a[k], b[k], nexp[k]) for k in range(nb)])
    with np.errstate(over="ignore"):  # an overflow is refused below, naming the semi-axes
        props = [sq.mass_properties(a[k], b[k], nexp[k], float(scene.materials[mats[k]].density)) for k in range(nb)]
    mass = np.array([m for m, _ in props], dtype=np.float64)
    inertia = np.array([i for _, i in props], dtype=np.float64)
    if p.mass is not None:
        given = _as_array("mass", p.mass, nb)
        bad = np.flatnonzero(given <= 0)
        if bad.size:
            raise SceneError(f"scene.discs.mass[{bad[0]}]={given[bad[0]]}; a mass must be > 0")
        area = np.array([sq.area(a[k], b[k], nexp[k]) for k in range(nb)])
        j_area = np.array([sum(sq.second_moments(a[k], b[k], nexp[k])) for k in range(nb)])
        mass, inertia = given, given * j_area / area  # the same shape at uniform density
    bad = np.flatnonzero(~(mass > 0))
    if bad.size:
        k = int(bad[0])
        raise SceneError(f"scene.materials[{mats[k]!r}].density gives particle {k} the mass {mass[k]}; give the "
                         "material a density > 0 or give scene.discs.mass")
    bad = np.flatnonzero(~(np.isfinite(mass) & np.isfinite(inertia) & (inertia > 0)))
    if bad.size:
        k = int(bad[0])
        raise SceneError(f"scene.discs.a[{k}]={a[k]:g}, scene.discs.b[{k}]={b[k]:g} (n={nexp[k]:g}) with "
                         f"scene.materials[{mats[k]!r}].density={scene.materials[mats[k]].density!r}: particle {k}'s "
                         f"mass {mass[k]:g} or moment of inertia {inertia[k]:g} is not finite and > 0; give smaller "
                         "semi-axes, density or mass (or rescale the units)")
    v = _velocities(p.velocity, nb) if p.velocity is not None else np.zeros((nb, 2))
    om = _as_array("angular_velocity", p.angular_velocity, nb) if p.angular_velocity is not None else np.zeros(nb)

    wall_geo = wall_geometry(scene)
    check_run_length("scene.n_steps", int(scene.n_steps), scene, nb, len(scene.walls), 0)
    mat_names, mid, used, law, k_max = material_laws(scene, mats)
    if law.name != "linear":
        raise SceneError(f"scene.laws: the {law.name} law is not available for Superquadrics yet; give LinearLaw "
                         "(Miyata §2.3 uses the linear law with restitution damping, eq 17)")
    zeta = np.zeros((len(mat_names), len(mat_names)))
    if p.restitution is not None:
        zeta[:, :] = zeta_linear(float(p.restitution))
    dt_crit = critical_time_step(mass, k_max)
    if scene.dt is None:
        dt = float(scene.dt_fraction) * dt_crit
        if not (math.isfinite(dt) and dt > 0):
            raise SceneError("scene.dt=None: no contact law with stiffness applies; give scene.dt")
    else:
        dt = float(scene.dt)
        if dt > dt_crit and not scene.allow_supercritical:
            raise SceneError(f"scene.dt: dt={dt:.6g} is above the critical time step 2√(m_min/k_max) = {dt_crit:.6g}; "
                             f"use dt <= {0.1 * dt_crit:.6g} (10 % of critical, thesis §2.2.4.4) or set "
                             "allow_supercritical=True")
    d = scene.damping
    C = d.alpha * mass if d.alpha > 0 else np.full(nb, float(d.C))
    Cr = d.alpha * inertia if d.alpha > 0 else np.full(nb, float(d.C_rot))
    skin = float(scene.skin) if scene.skin is not None else (0.2 * float(rb.mean()) if nb else 1.0)
    bodies = SQBodies(x=x.copy(), y=y.copy(), th=th.copy(), vx=v[:, 0].copy(), vy=v[:, 1].copy(), om=om.copy(),
                      a=a, b=b, n=nexp, rb=rb, mass=mass, inertia=inertia, C=C, Cr=Cr,
                      mat=np.array([mid[m] for m in mats], dtype=np.int64), xref=x.copy(), yref=y.copy(),
                      Fx=np.zeros(nb), Fy=np.zeros(nb), M=np.zeros(nb))
    walls, loading = walls_and_loading(scene, wall_geo, np.array([mid[w.material] for w in scene.walls],
                                                                 dtype=np.int64))
    knobs = SQKnobs(tol=float(p.tolerance), window=float(p.window), max_overlap=float(p.max_overlap), zeta=zeta)
    from .build import _check_box

    # the disc path's check on the bounding radii (period >= twice 2·r_max + skin); open: None
    box = _check_box(scene if scene.skin is not None else _with_skin(scene, skin), rb, x, y) if scene.box.periodic \
        else None
    sim = SuperquadricSimulation(scene, bodies, walls, loading, law.params(), knobs, dt, dt_crit, skin,
                                 tuple(map(float, scene.gravity)), mat_names, box)
    sim.check_initial_overlaps(float(scene.overlap_tolerance))
    return sim


# ----------------------------------------------------------------------------------------- simulation
class SuperquadricSimulation:
    """State and stepping of one 2D superquadric scene (built by :func:`build_superquadrics`).

    ``bodies`` (:data:`SQBodies`), ``walls``/``loading`` (:mod:`demflow.state`), the pair list
    ``finder``, ``other`` with its ``hist`` (key order, 5 columns: see the module doc) and ``out``
    (:data:`SQPairOut`), the law's tables ``law_params`` and the contact ``knobs``.
    ``energy_records`` holds rows (step, kinetic, elastic) every ``scene.outputs.every`` steps;
    ``counters`` = (potential evaluations, pair geometries computed) since the build.
    """

    def __init__(self, scene, bodies, walls, loading, law_params, knobs, dt, dt_crit, skin, gravity, material_names,
                 box=None):
        self.scene = scene
        self.bodies = bodies
        self.walls = walls
        self.loading = loading
        self.law_params = law_params
        self.knobs = knobs
        self.dt = dt
        self.dt_crit = dt_crit
        self.skin = skin
        self.gx, self.gy = gravity
        self.material_names = material_names
        self.n = bodies.x.shape[0]
        self.nw = walls.px.shape[0]
        self.step = 0
        self.disp_walls = 0.0
        self.rebuilds = 0
        self.counters = np.zeros(2, np.int64)
        self.box = box  # a PeriodicBox, or None (open)
        self.ix = np.zeros(self.n, np.int64)  # periods crossed (unwrapped x = x + ix·lx)
        self.iy = np.zeros(self.n, np.int64)
        self.finder = np.empty(0, np.int64)
        self.other = np.empty(0, np.int64)
        self.sx = np.empty(0)
        self.sy = np.empty(0)
        self.hist = np.zeros((0, HIST))
        self.out = self._outputs(0)
        self.energy_records = np.zeros((0, 3))
        self._scene_digest = scene_digest(self.fixed_parts())  # as built (demflow.checkpoint_scene)

    def fixed_parts(self) -> dict:
        """What the scene fixes and a run does not change, by name (:mod:`demflow.checkpoint_scene`)."""
        bd, w = self.bodies, self.walls
        return {"particles (semi-axes, exponent, mass, inertia, damping, material)": (
                    bd.a, bd.b, bd.n, bd.mass, bd.inertia, bd.C, bd.Cr, bd.mat),
                "walls (extent, material)": (w.h1, w.h2, w.mat), "time step": self.dt, "gravity": (self.gx, self.gy),
                "contact law": self.law_params, "knobs": self.knobs, "box": repr(self.box)}

    @staticmethod
    def _outputs(m):
        return SQPairOut(*[np.zeros(m) for _ in SQPairOut._fields])

    def wall_endpoints(self):
        w = self.walls
        return w.px + w.h1 * w.ex, w.py + w.h1 * w.ey, w.px + w.h2 * w.ex, w.py + w.h2 * w.ey

    def rebuild(self) -> None:
        """Rebuild the neighbour list on the bounding circles, carrying each pair's history (springs and
        warm-start parameters) by key."""
        bd = self.bodies
        ax, ay, bx, by = self.wall_endpoints()
        if self.box is None:
            finder, other = pairs_cell_search(bd.x, bd.y, bd.rb, self.skin, ax, ay, bx, by)
            sx = np.zeros(finder.shape[0])
            sy = np.zeros(finder.shape[0])
        else:
            from .contacts.periodic import pairs_periodic
            from .space import wrap

            wrap(self.box, bd.x, bd.y, self.ix, self.iy)
            finder, other, sx, sy = pairs_periodic(bd.x, bd.y, bd.rb, self.skin, ax, ay, bx, by, self.box)
        self.hist = transfer_history(self.finder, self.other, self.hist, finder, other, self.n + self.nw)
        self.finder, self.other, self.sx, self.sy = finder, other, sx, sy
        self.out = self._outputs(finder.shape[0])
        bd.xref[:] = bd.x
        bd.yref[:] = bd.y
        self.disp_walls = 0.0
        self.rebuilds += 1

    def check_initial_overlaps(self, tol: float) -> None:
        """Refuse overlaps at the start beyond tol × the smaller semi-axis of the pair."""
        if self.n == 0:
            return
        self.rebuild()
        hist = self.hist.copy()
        counters = np.zeros(2, np.int64)
        bd = self.bodies
        pair_pass(bd, self.finder, self.other, self.sx, self.sy, hist, self.out, self.walls, self.law_params, self.knobs,
                  self.dt, counters)
        bd.Fx[:] = 0.0
        bd.Fy[:] = 0.0
        bd.M[:] = 0.0
        self.walls.force[:] = 0.0
        small = np.minimum(bd.a, bd.b)
        for k in np.flatnonzero(self.out.ovl > 0):
            i, j = int(self.finder[k]), int(self.other[k])
            lim = tol * (min(small[i], small[j]) if j < self.n else small[i])
            if self.out.ovl[k] > lim:
                what = f"particles {min(i, j)} and {max(i, j)}" if j < self.n else f"particle {i} and wall {j - self.n}"
                raise SceneError(f"scene.discs: {what} overlap by {self.out.ovl[k]:.6g} at the start, more than "
                                 f"{lim:.6g} (overlap_tolerance={tol} × the smaller semi-axis); move them apart or "
                                 "raise scene.overlap_tolerance")
        self.hist[:, 2:] = hist[:, 2:]  # keep the warm starts found

    CHUNK = 20000  # steps between last-good-state copies (as the disc cycle)

    def run(self, n_steps: int | None = None) -> "SuperquadricSimulation":
        """Advance ``n_steps`` (default scene.n_steps) steps.  A blow-up (an overlap or a step beyond
        half the smaller semi-axis, a non-finite force, or any non-finite body or wall quantity on return
        from the compiled cycle: a NaN gravity, mass or law output, a wall driven to infinity) raises
        :class:`~demflow.simulation.BlowUpError` after restoring and saving the last good state (the
        start of the chunk, at most ``CHUNK`` steps back; :meth:`load_checkpoint` reads it)."""
        from .scene import check_whole

        from .simulation import check_run_length

        n_steps = check_whole("run(n_steps)", self.scene.n_steps if n_steps is None else n_steps)
        check_run_length("run(n_steps)", n_steps, self.scene, self.n, self.nw, 0, self.step)  # records fit
        every = int(self.scene.outputs.every)
        rows = (self.step + n_steps - 1) // every - (self.step - 1) // every if every > 0 and n_steps > 0 else 0
        rec = np.zeros((rows, 3))
        rec_count = 0
        if self.n and self.finder.shape[0] == 0 and self.rebuilds == 0:
            self.rebuild()
        target = self.step + n_steps
        changes = sorted({int(st) for w in self.scene.walls if w.servo is not None for st, _ in w.servo.schedule})
        while self.step < target:
            self._set_servo_targets()
            nxt = [c for c in changes if c > self.step]
            stop = min(target, self.step + self.CHUNK, nxt[0] if nxt else target)
            good = self._copy_state()
            while self.step < stop:
                done, status, self.disp_walls, rec_count = run_sq_steps(
                    stop - self.step, self.step, self.skin, self.disp_walls, self.bodies, self.finder, self.other,
                    self.sx, self.sy, self.hist, self.out, self.walls, self.loading, self.law_params, self.knobs, self.dt, self.gx,
                    self.gy, every, rec, rec_count, self.counters)
                self.step += done
                # the cycle's own tests see overlaps, steps and forces; one O(n) pass per call sees a NaN or
                # inf no contact met (a body in free flight under a NaN gravity, a wall driven to infinity)
                bad = self._nonfinite_state()
                if status == BLOWUP or bad is not None:
                    self.energy_records = np.vstack([self.energy_records, rec[:rec_count]])
                    self._blow_up(good, bad)
                if status == REBUILD:
                    self.rebuild()
        self.energy_records = np.vstack([self.energy_records, rec[:rec_count]])
        return self

    def _set_servo_targets(self) -> None:
        """Servo targets in effect at the current step (Servo.schedule), as the disc cycle."""
        for w, wall in enumerate(self.scene.walls):
            if wall.servo is not None:
                self.loading.servo_F[w] = wall.servo.force_at(self.step)

    def _nonfinite_state(self) -> str | None:
        """The first non-finite quantity of the bodies, the walls or the contact history, or None."""
        from .simulation import first_nonfinite

        bd, w = self.bodies, self.walls
        return first_nonfinite({
            **{f"bodies.{k}": getattr(bd, k) for k in ("x", "y", "th", "vx", "vy", "om", "Fx", "Fy", "M")},
            **{f"walls.{k}": getattr(w, k) for k in ("px", "py", "ex", "ey", "vx", "vy", "om", "cx", "cy", "force")},
            "pairs.hist": self.hist})

    def _blow_up(self, good: dict, bad: str | None):
        """Restore the last good state ``good``, save it and raise BlowUpError naming the non-finite
        quantity ``bad`` (None: the cycle's overlap, step or force test stopped it)."""
        from .simulation import BlowUpError

        bad_step = self.step
        if bad is not None:
            why = (f"{bad} is not finite (its origin may be gravity (now ({self.gx}, {self.gy})), a mass, a contact "
                   f"law or a wall's motion). Check those for NaN or infinite values, then reduce dt (now "
                   f"{self.dt:.4g}, critical estimate {self.dt_crit:.4g}) or the loading rate")
        else:
            why = (f"an overlap beyond {self.knobs.max_overlap:.0%} of a semi-axis, a non-finite force or a step beyond "
                   f"{MAX_STEP_RATIO:.0%} of a semi-axis. Reduce dt (now {self.dt:.4g}, critical estimate "
                   f"{self.dt_crit:.4g}) or the loading rate")
        self._restore_state(good)
        path = self._save_last_good()
        raise BlowUpError(f"scene {self.scene.name!r} (superquadrics) blew up at step {bad_step}: {why}. Last good "
                          f"state (step {self.step}) saved to {path}", path)

    # ------------------------------------------------------------------ state I/O
    def _state_arrays(self) -> dict:
        """The dynamic state by name (the arrays themselves): bodies, walls, the pair list with its history
        (kept as it is, so that a run resumed from it is the uninterrupted run to the bit)."""
        bd, w = self.bodies, self.walls
        out = {k: getattr(bd, k) for k in _SQ_STATE}
        out.update({f"wall_{k}": getattr(w, k) for k in _SQ_WALL_STATE})
        out.update(finder=self.finder, other=self.other, sx=self.sx, sy=self.sy, ix=self.ix, iy=self.iy, hist=self.hist,
                   scalars=np.array([self.disp_walls, float(self.rebuilds)]))
        return out

    def _set_state(self, s: dict) -> None:
        bd, w = self.bodies, self.walls
        for k in _SQ_STATE:
            getattr(bd, k)[:] = s[k]
        for k in _SQ_WALL_STATE:
            getattr(w, k)[:] = s[f"wall_{k}"]
        self.finder = np.array(s["finder"], np.int64)
        self.other = np.array(s["other"], np.int64)
        m = self.finder.shape[0]
        self.sx = np.array(s.get("sx", np.zeros(m)), np.float64)  # periodic image shifts (older checkpoints: open box)
        self.sy = np.array(s.get("sy", np.zeros(m)), np.float64)
        self.ix = np.array(s.get("ix", np.zeros(self.n)), np.int64)
        self.iy = np.array(s.get("iy", np.zeros(self.n)), np.int64)
        self.hist = np.array(s["hist"], np.float64).reshape(-1, HIST)
        self.out = self._outputs(self.finder.shape[0])
        self.disp_walls = float(s["scalars"][0])
        self.rebuilds = int(s["scalars"][1])

    def _copy_state(self) -> dict:
        return {k: np.array(v, copy=True) for k, v in self._state_arrays().items()} | {"step": self.step}

    def _restore_state(self, s: dict) -> None:
        self.step = s["step"]
        self._set_state(s)

    def _save_last_good(self) -> str:
        path = last_good_path(self.scene.name, self.step)
        self.save_checkpoint(path)
        return str(path)

    def save_checkpoint(self, path) -> Path:
        """Write the dynamic state to ``path`` (.npz) atomically (temporary file + rename)."""

        meta = dict(scene=self.scene.name, family="superquadrics", step=self.step, n=self.n, nw=self.nw, dt=self.dt,
                    static=self._scene_digest)
        return write_checkpoint(Path(path), meta, self._state_arrays())

    def load_checkpoint(self, path) -> "SuperquadricSimulation":
        """Restore a state written by :meth:`save_checkpoint` (or saved on a blow-up) for the same scene."""
        meta, state = read_checkpoint(path)
        if (meta.get("family") != "superquadrics" or meta["scene"] != self.scene.name or meta["n"] != self.n
                or meta["nw"] != self.nw):
            raise ValueError(f"checkpoint {path} is for scene {meta['scene']!r} ({meta.get('family', 'discs')}, "
                             f"{meta['n']} particles, {meta['nw']} walls), not {self.scene.name!r} (superquadrics, "
                             f"{self.n}, {self.nw}); build the same scene")
        check_same_scene(path, meta, self._scene_digest)
        self.step = int(meta["step"])
        self._set_state(state)
        return self

    def unwrapped_positions(self):
        """(x, y) of the centroids with the periods crossed added back [length] (as the disc path)."""
        bd = self.bodies
        if self.box is None:
            return bd.x.copy(), bd.y.copy()
        ux = bd.x + (self.ix * self.box.lx if self.box.periodic_x else 0.0)
        uy = bd.y + (self.iy * self.box.ly if self.box.periodic_y else 0.0)
        return ux, uy

    def kinetic_energy(self) -> float:
        """½Σ(m v² + I ω²) at the half-step velocities [force·length]."""
        bd = self.bodies
        return float(0.5 * np.sum(bd.mass * (bd.vx ** 2 + bd.vy ** 2) + bd.inertia * bd.om ** 2))

    def contacts(self) -> dict:
        """The touching pairs of the last step evaluated: finder i, other j (>= n: wall j - n), overlap,
        normal (i → j), contact point, normal and shear force."""
        k = np.flatnonzero(self.out.ovl > 0)
        o = self.out
        return dict(i=self.finder[k], j=self.other[k], overlap=o.ovl[k], nx=o.nx[k], ny=o.ny[k], cpx=o.cpx[k],
                    cpy=o.cpy[k], fn=o.fn[k], fs=o.fs[k])
