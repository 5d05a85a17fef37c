"""stability-matrix: every extreme either stable or a clear error, never silent garbage (issue 17 item 2).

Each cell is a small scene pushed to one extreme — a time step near and above the true critical
step of a frictional packing (its rotational mode), shear-to-normal stiffness ratios 1e-3 and 1e3,
discs 100:1 in radius, no friction and a friction coefficient of 1e6, a BEM gap shrunk towards
zero, pore-fluid viscosities 1e-3 to 1e3, a 1e6-step run of a conservative packing, and in 3D a
Hertz-Mindlin sphere packing near and above its measured critical step and at zero and huge
friction — with the outcome it must have declared up front:

- ``stable``: the run completes, and an observer that does not use demflow's own blow-up detectors
  finds the state finite, no overlap beyond half the smaller radius, and the energy not grown: the
  kinetic + gravitational (net of buoyancy) + elastic energy at the end is at most
  GARBAGE_GROWTH × the larger of its start and its largest value in the first chunk (nothing in a
  cell's scene supplies energy: no driven wall, no applied load);
- ``refused``: ``build`` raises :class:`~demflow.scene.SceneError` whose message names the field and
  the fix;
- ``stopped``: the run raises :class:`~demflow.simulation.BlowUpError` and the last good state it
  saved loads and is finite.

Any other outcome — a run that completes with the observer seeing a grown energy, a non-finite value
or a deep overlap — is ``garbage``, and the cell's check fails.  The negative control
(:func:`garbage_control`) runs an unstable cell with the energy check set to "warn" (the detector
silenced): the observer must call it garbage, so the observer can fail.

Assumptions (stated on the report): the "true critical step" of the hexagonal frictional packing is
the analytic 2/√24 √(m/kN) of its all-discs-spinning mode (measured to 1 % by
tests/test_time_step.py); the 100:1 cell is one disc of radius 1 resting on three layers of discs
of radius 0.01 in a box; the fluid cells are the §5.1 falling disc (CGS units, a 5 cm channel)
with the viscosity or the BEM gap changed; "gaps → 0" is the Fluid.min_gap of a disc started
touching a side wall, down to 1e-4 × its radius; the 3D cells are the face-centred cubic Hertz packing
of :func:`fcc`, whose true critical step is FCC_CRITICAL × its safe estimate (measured by bisection in
tests/test_time_step3d.py, which never reads the estimate).
"""
from __future__ import annotations

import math
import os
import time
import warnings
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from ..laws.hertz_mindlin import HertzMindlinLaw
from ..scene import Box, ContactModel, Discs, LinearLaw, Material, Outputs, Scene, SceneError, Wall
from ..scene3d import Outputs3D, Plane, Scene3D, Spheres
from ..tolerances import tol
from .base import Case, CaseRun, Check

SRC = "issue 17 item 2 (stability at the extremes)"
# the observer's bounds and the drift bound, justified in demflow/tolerances.py
GARBAGE_GROWTH = tol("stability.energy-growth").value
KINETIC_GROWTH = tol("stability.kinetic-growth").value
KN = 1e5
DENSITY = 1.0
PERTURBATION = 1e-4  # velocity scale of the packings' random excitation [length/time]
SPIN_LIMIT = 2.0 / math.sqrt(24.0)  # the hexagonal frictional packing's critical Δt / √(m/kN)
DRIFT_TOL_PER_STEP = tol("stability.drift-per-step").value
OUTCOMES = ("stable", "refused", "stopped")
# the drift cell's velocity scale: displacements ~5e-4 R, far inside the 1e-2 R pre-compression (no contact opens: the
# system is exactly linear), kinetic energy ~0.5 % of the stored elastic energy
DRIFT_PERTURBATION = 0.1
# the 3D packing (fcc): glass-like spheres of 1 cm, Hertz-Mindlin, every contact pre-compressed to 1 % of R
FCC_R = 0.01
FCC_E, FCC_NU, FCC_RHO = 7e10, 0.2, 2650.0
FCC_PERTURBATION = 1e-6  # [length/time]: displacements far below the pre-compression
# its true critical step over its safe estimate (elastic, μ = 0.5): 1.62, measured by bisection to 2 % and asserted
# by tests/test_time_step3d.py; the cells above it use 1.1 × this
FCC_CRITICAL = 1.62
# the ellipsoid lattice (ellipsoid_lattice): aligned ellipsoids of semi-axes 3 × 2 × 1.2 cm, the glass above, every
# contact pre-compressed to 1 % of c; its true critical step over the ellipsoids' safe estimate (elastic, μ = 0.5):
# 3.81, measured by bisection to 2 % and asserted by tests/test_ellipsoid_time_step.py
ELL_AXES = (0.03, 0.02, 0.012)
ELL_CRITICAL = 3.81


# ---------------------------------------------------------------------------------------------- scenes
def hexagonal(nx: int = 6, ny: int = 6, radius: float = 1.0, overlap: float = 0.01):
    """Equal discs on a hexagonal lattice filling a periodic box, each touching six, with contact
    overlap ``overlap`` × R; by symmetry every disc is in equilibrium.  Returns x, y, r, (lx, ly)."""
    d = 2.0 * radius - overlap * radius
    h = d * math.sqrt(3.0) / 2.0
    x, y = [], []
    for j in range(ny):
        for i in range(nx):
            x.append((i + 0.5 * (j % 2) + 0.25) * d)
            y.append((j + 0.5) * h)
    return np.array(x), np.array(y), np.full(nx * ny, radius), (nx * d, ny * h)


def packing_scene(packing, dt, *, ks: float = KN, friction: float = 0.5, cn: float = 0.0, cs: float = 0.0,
                  seed: int = 3, n_steps: int = 3000, name: str = "packing", perturbation: float = PERTURBATION,
                  **scene_kw) -> Scene:
    """The packing with the linear law (kN = KN, kS = ``ks``, overlap normal law so the springs carry
    their force from the first step), perturbed by random velocities and spins of scale PERTURBATION,
    in its periodic box, stepped at ``dt`` (None: the scene's default)."""
    x, y, r, (lx, ly) = packing
    rng = np.random.default_rng(seed)
    v = perturbation * rng.normal(size=(len(x), 2))
    om = perturbation * rng.normal(size=len(x)) / r
    law = LinearLaw(kn=KN, ks=ks, cn=cn, cs=cs, friction=friction)
    kw = dict(overlap_tolerance=0.1, skin=0.2, outputs=Outputs(every=0))
    kw.update(scene_kw)
    return Scene(name=name, discs=Discs(x=x, y=y, radius=r, material="g", velocity=v, angular_velocity=om),
                 materials={"g": Material(density=DENSITY)}, laws={("g", "g"): law},
                 contact_model=ContactModel(normal="overlap"), box=Box(periodic_x=(0.0, lx), periodic_y=(0.0, ly)),
                 dt=dt, n_steps=n_steps, **kw)


def fcc(nx: int = 6, ny: int = 6, layers: int = 3, overlap: float = 0.01, friction: float = 0.5,
        restitution: float = 1.0, dt: float | None = None, seed: int = 3, **kw) -> Scene3D:
    """Face-centred cubic sphere packing: hexagonal (111) layers stacked ABC between two planes, periodic
    along x and y, every contact pre-compressed to the overlap ``overlap`` × R (the planes to the overlap
    whose Hertz force equals the vertical pull of the three contacts a boundary layer lacks), so every
    sphere is in equilibrium by symmetry; tiny random velocities and spins excite every mode."""
    R = FCC_R
    d = 2.0 * R - overlap * R  # centre distance of touching spheres
    h = d * math.sqrt(2.0 / 3.0)  # layer spacing
    lx, ly = nx * d, ny * d * math.sqrt(3.0) / 2.0
    shifts = [(0.0, 0.0), (0.5 * d, d / (2.0 * math.sqrt(3.0))), (d, d / math.sqrt(3.0))]
    pos = []
    for k in range(layers):
        sx, sy = shifts[k % 3]
        for j in range(ny):
            for i in range(nx):
                x = (i + 0.5 * (j % 2)) * d + sx
                y = j * d * math.sqrt(3.0) / 2.0 + sy
                pos.append((x % lx, y % ly, k * h))
    pos = np.array(pos)
    # the plane overlap: 4/3 E* √R δp^1.5 = 3 (h/d) 4/3 E* √(R/2) δ^1.5  →  δp = δ (3 h/d /√2)^(2/3)
    dp = overlap * R * (3.0 * (h / d) / math.sqrt(2.0)) ** (2.0 / 3.0)
    rng = np.random.default_rng(seed)
    n = len(pos)
    law = HertzMindlinLaw(friction=friction, restitution=restitution)
    kw.setdefault("max_overlap", overlap)
    return Scene3D(
        name=kw.pop("name", "fcc"),
        spheres=Spheres(x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], radius=np.full(n, R), material="rock",
                        velocity=FCC_PERTURBATION * rng.normal(size=(n, 3)),
                        angular_velocity=FCC_PERTURBATION / R * rng.normal(size=(n, 3))),
        materials={"rock": Material(density=FCC_RHO, young=FCC_E, poisson=FCC_NU)},
        laws={("rock", "rock"): law},
        planes=[Plane("floor", (0.0, 0.0, -(R - dp)), (0.0, 0.0, 1.0), "rock"),
                Plane("lid", (0.0, 0.0, (layers - 1) * h + (R - dp)), (0.0, 0.0, -1.0), "rock")],
        box=Box(periodic_x=(0.0, lx), periodic_y=(0.0, ly)), dt=dt, outputs=Outputs3D(every=0), **kw)


def ellipsoid_lattice(dt=None, nx: int = 4, ny: int = 4, overlap: float = 0.01, friction: float = 0.5,
                      restitution: float = 1.0, seed: int = 3, **kw) -> Scene3D:
    """One layer of aligned ellipsoids (semi-axes ELL_AXES a > b > c along x, y, z) between a floor and a lid,
    periodic along x and y, every contact (tip to tip along x and y, the c tips on the planes) pre-compressed to
    ``overlap`` × c, so every body is in equilibrium by symmetry; tiny random velocities and spins excite every
    mode.  The stiffest contacts of an ellipsoid, on its flattest face (the c tips), meet the planes."""
    from ..scene3d import Ellipsoids

    a, b, c = ELL_AXES
    d = overlap * c
    lx, ly = nx * (2 * a - d), ny * (2 * b - d)
    g = np.array([((i + 0.5) * lx / nx, (j + 0.5) * ly / ny, 0.0) for j in range(ny) for i in range(nx)])
    n = len(g)
    rng = np.random.default_rng(seed)
    kw.setdefault("max_overlap", overlap)
    return Scene3D(
        name=kw.pop("name", "ellipsoid-lattice"), spheres=None,
        ellipsoids=Ellipsoids(axes=[ELL_AXES] * n, x=g[:, 0], y=g[:, 1], z=g[:, 2], material="rock",
                              velocity=FCC_PERTURBATION * rng.normal(size=(n, 3)),
                              angular_velocity=FCC_PERTURBATION / c * rng.normal(size=(n, 3))),
        materials={"rock": Material(density=FCC_RHO, young=FCC_E, poisson=FCC_NU)},
        laws={("rock", "rock"): HertzMindlinLaw(friction=friction, restitution=restitution)},
        planes=[Plane("floor", (0.0, 0.0, -(c - d)), (0.0, 0.0, 1.0), "rock"),
                Plane("lid", (0.0, 0.0, c - d), (0.0, 0.0, -1.0), "rock")],
        box=Box(periodic_x=(0.0, lx), periodic_y=(0.0, ly)), dt=dt, outputs=Outputs3D(every=0), **kw)


def ellipsoid_lattice_at(fraction: float, **kw) -> Scene3D:
    """:func:`ellipsoid_lattice` stepped at ``fraction`` × the safe critical step build computes for it."""
    return _at_safe_estimate(ellipsoid_lattice, fraction, **kw)


def fcc_at(fraction: float, **kw) -> Scene3D:
    """:func:`fcc` stepped at ``fraction`` × the safe critical step build computes for it."""
    return _at_safe_estimate(fcc, fraction, **kw)


def _at_safe_estimate(make, fraction: float, **kw) -> Scene3D:
    """``make(dt=..., **kw)`` stepped at ``fraction`` × the safe critical step build computes for it."""
    from ..build import build

    probe = make(dt=1e-12, allow_supercritical=True, **{k: v for k, v in kw.items() if k not in (
        "allow_unsafe_dt", "allow_supercritical", "n_steps", "name")})
    return make(dt=fraction * build(probe).dt_safe, **kw)


def unit_time() -> float:
    """√(m/kN) of a unit disc of the packings [time]."""
    return math.sqrt(math.pi * DENSITY / KN)


def radius_ratio_scene(dt: float | None = None, n_steps: int = 3000) -> Scene:
    """One disc of radius 1 on three layers of discs of radius 0.01 (100:1) in a box 2.4 wide, under
    gravity, contact dashpots at 30 % of critical (a settling bed); Δt from the scene's safe default."""
    r_s, r_b, W = 0.01, 1.0, 2.4
    xs, ys = [], []
    per_row = int(W / (2 * r_s)) - 1
    for j in range(3):
        for i in range(per_row):
            xs.append(-W / 2 + r_s * (1.0 + (j % 2)) + 2.0 * r_s * i)
            ys.append(r_s + j * r_s * math.sqrt(3.0))
    xs.append(0.0)
    ys.append(ys[-1] + r_s + r_b + 1e-3)
    r = np.array([r_s] * (len(xs) - 1) + [r_b])
    m_small = math.pi * r_s ** 2 * DENSITY
    c = 2 * 0.3 * math.sqrt(KN * m_small / 2)
    law = LinearLaw(kn=KN, ks=KN, cn=c, cs=c, friction=0.5)
    walls = [Wall("floor", (0.0, 0.0), (1.0, 0.0), -W / 2, W / 2, "w"),
             Wall("left", (-W / 2, 0.0), (0.0, 1.0), 0.0, 4.0, "w"),
             Wall("right", (W / 2, 0.0), (0.0, 1.0), 0.0, 4.0, "w")]
    return Scene(name="stability-radius-100", discs=Discs(np.array(xs), np.array(ys), r, "g"),
                 materials={"g": Material(density=DENSITY), "w": Material()},
                 laws={("g", "g"): law, ("g", "w"): law}, walls=walls, gravity=(0.0, -9.81), dt=dt,
                 n_steps=n_steps, outputs=Outputs(every=0))


def falling_disc_scene(*, mu=None, dt=None, allow=False, min_gap=None, at_wall=False, n_steps=200, name="fd"):
    """The thesis §5.1 falling disc (CGS, 16 elements on the disc) with its viscosity, time step (None: the
    thesis's; "auto": the default rule) or BEM gap changed; ``at_wall`` starts the disc touching the right
    wall (the fluid gap is then the min_gap the BEM leaves)."""
    from .thesis_falling_disc import FallingDisc

    case = FallingDisc()
    p = case.merged(dict(elements=16))
    if min_gap is not None:
        p["min_gap"] = min_gap
    sc = case.scene(p, mu=mu, dt=None if dt == "auto" else dt, allow=allow, name=name)
    if dt == "auto":  # the default step: 0.1 × 2√(m/k) capped at the fluid drag limit
        sc = replace(sc, dt=None)
    if at_wall:
        x = p["b"] - p["r"]
        sc = replace(sc, discs=replace(sc.discs, x=np.array([x]), y=np.array([0.0])))
    return replace(sc, n_steps=n_steps)


# ---------------------------------------------------------------------------------------------- observer
def _is3d(sim) -> bool:
    return hasattr(sim, "spheres")


def observed_energy(sim) -> float:
    """Kinetic + gravitational (net of buoyancy) + elastic energy [force·length], from the state alone
    (the springs' energy from the simulation's contact evaluation)."""
    if _is3d(sim):
        return kinetic_energy(sim) + _potential3d(sim) + _elastic(sim)
    e = kinetic_energy(sim)
    gx, gy = sim.gx, sim.gy
    m_net = sim.mass.copy()
    if sim.fluid is not None:
        m_net = m_net - float(sim.scene.fluid.density) * math.pi * sim.r ** 2
    e -= float(np.sum(m_net * (gx * sim.x + gy * sim.y)))
    return e + float(sim.mechanical_energy()["elastic"])


def _free3d(sim):
    """The 3D particles that move on their own: not fixed, not a clump member (a clump: its body)."""
    return sim.spheres.fixed == 0


def _potential3d(sim) -> float:
    sp, b = sim.spheres, sim.bodies
    free = _free3d(sim)
    e = -float(np.sum(sp.mass[free] * (sim.unwrapped_positions()[free] @ sim.g)))
    return e - float(np.sum(b.mass * (b.pos @ sim.g)))  # (no gravity across periodic axes in these cells)


def kinetic_energy(sim) -> float:
    if _is3d(sim):
        sp, b = sim.spheres, sim.bodies
        free = _free3d(sim)
        e = 0.5 * np.sum(sp.mass[free] * np.sum(sp.vel[free] ** 2, 1) + sp.inertia[free] * np.sum(sp.angvel[free] ** 2, 1))
        return float(e + 0.5 * np.sum(b.mass * np.sum(b.vel ** 2, 1)) + 0.5 * np.sum(b.angvel * b.L))
    return float(0.5 * np.sum(sim.mass * (sim.vx ** 2 + sim.vy ** 2) + sim.inertia * sim.om ** 2))


def lift_work(sim) -> float:
    """Σ |m_net| |g| R: the work of lifting every disc by its radius against gravity net of buoyancy."""
    if _is3d(sim):
        sp = sim.spheres
        return float(np.sum(sp.mass * np.linalg.norm(sim.g) * sp.r))
    m_net = sim.mass.copy()
    if sim.fluid is not None:
        m_net = m_net - float(sim.scene.fluid.density) * math.pi * sim.r ** 2
    return float(np.sum(np.abs(m_net) * math.hypot(sim.gx, sim.gy) * sim.r))


def _elastic(sim) -> float:
    return float(sim.mechanical_energy()["elastic"])


def _conserved(sim) -> float:
    """Kinetic + elastic as the simulation's energy balance counts them (the drift cell's series)."""
    m = sim.mechanical_energy()
    return float(m["kinetic"] + m["elastic"])


def _state(sim) -> np.ndarray:
    if _is3d(sim):
        sp = sim.spheres
        return np.concatenate([sp.pos.ravel(), sp.vel.ravel(), sp.angvel.ravel()])
    return np.concatenate([sim.x, sim.y, sim.vx, sim.vy, sim.om])


def energy_scale(sim) -> float:
    """The scale an energy growth is measured against [force·length]: the largest of |E|, the kinetic +
    elastic energy, and the work of lifting every disc by its radius against gravity net of buoyancy (so a
    disc starting at rest at the height origin still has a finite scale)."""
    kin = kinetic_energy(sim)
    return max(abs(observed_energy(sim)), kin + _elastic(sim), lift_work(sim))


def deepest_overlap(sim) -> float:
    """The largest overlap of a contact as a fraction of the smaller radius (a wall's: the disc's)."""
    if _is3d(sim):
        return sim.deepest_overlap_now()
    t = sim.contact_table_arrays()
    if t["overlap"].size == 0:
        return 0.0
    i, j = t["finder"], t["other"]
    r = sim.r
    rb = np.where(j < sim.n, r[np.minimum(j, sim.n - 1)], np.inf)
    return float(np.max(t["overlap"] / np.minimum(r[i], rb)))


@dataclass
class Cell:
    """One cell: its row (the extreme), its setting, the outcome it must have, its scene and run length."""

    row: str
    setting: str
    expect: str
    scene: Callable[[], Scene]
    steps: int
    chunk: int = 500
    field: str = ""  # a refusal must name this field (e.g. "scene.dt"), so it is refused for the right reason


@dataclass
class Outcome:
    cell: Cell
    outcome: str  # stable / refused / stopped / garbage
    detail: str
    growth: float = math.nan
    wall_s: float = 0.0
    drift: np.ndarray | None = None  # kinetic + elastic (Simulation.mechanical_energy) at the start and every chunk

def run_cell(cell: Cell, *, energy_check: str | None = None) -> Outcome:
    """Build and run ``cell``; classify what happened (module docstring).  ``energy_check`` overrides
    the scene's (the negative control silences the detector with "warn")."""
    from ..build import build
    from ..scene import EnergyBalanceWarning, UnsafeTimeStepWarning
    from ..simulation import BlowUpError

    t0 = time.perf_counter()
    sc = cell.scene()
    if energy_check is not None:
        sc = replace(sc, energy_check=energy_check)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnsafeTimeStepWarning)
        warnings.simplefilter("ignore", EnergyBalanceWarning)
        try:
            sim = build(sc)
        except SceneError as e:
            msg = str(e)
            clear = (cell.field or "scene.") in msg and any(w in msg for w in ("give", "Use", "use", "set", "educe"))
            return Outcome(cell, "refused" if clear else "garbage",
                           msg if clear else f"unclear refusal: {msg}", wall_s=time.perf_counter() - t0)
        e0 = observed_energy(sim)
        ref = energy_scale(sim)
        k_ref = kinetic_energy(sim) + lift_work(sim)
        conserved0 = _conserved(sim)
        k_max = 0.0
        series = [conserved0]
        done = 0
        try:
            while done < cell.steps:
                n = min(cell.chunk, cell.steps - done)
                sim.run(n, progress=False)
                done += n
                e = observed_energy(sim)
                k_max = max(k_max, kinetic_energy(sim))
                series.append(_conserved(sim))
                if not math.isfinite(e):
                    break
        except BlowUpError as err:
            ok = err.path is not None and os.path.exists(err.path)
            if ok:
                z = np.load(err.path)
                ok = all(np.all(np.isfinite(z[k])) for k in z.files if z[k].dtype.kind == "f")
            return Outcome(cell, "stopped" if ok else "garbage",
                           str(err).split(". Last good")[0] + ("" if ok else " (last good state missing or not finite)"),
                           wall_s=time.perf_counter() - t0)
    state = _state(sim)
    e1 = observed_energy(sim)
    growth = (e1 - e0) / ref if ref > 0 else (0.0 if e1 == e0 else math.inf)  # relative to the scale
    deep = deepest_overlap(sim)
    bad = []
    if not np.all(np.isfinite(state)) or not math.isfinite(e1):
        bad.append("non-finite state")
    if e1 > e0 + (GARBAGE_GROWTH - 1.0) * ref:
        bad.append(f"energy grew from {e0:.4g} to {e1:.4g} with no source")
    if deep > 0.5:
        bad.append(f"an overlap of {deep:.3g} × the smaller radius")
    if not k_max <= KINETIC_GROWTH * k_ref:
        bad.append(f"the kinetic energy reached {k_max:.4g}, {k_max / k_ref if k_ref > 0 else math.inf:.3g} × its start "
                   f"plus the lift work, with no source")
    drift = np.array(series)
    wall = time.perf_counter() - t0
    if bad:
        return Outcome(cell, "garbage", "; ".join(bad), growth, wall, drift)
    return Outcome(cell, "stable", f"{done} steps, Δt = {sim.dt:.4g}, energy change {growth:+.3g} × its scale, "
                                   f"largest kinetic energy {k_max / k_ref if k_ref > 0 else 0.0:.3g} × start plus lift "
                                   f"work, deepest overlap {deep:.3g} R", growth, wall, drift)


# ---------------------------------------------------------------------------------------------- the matrix
def cells(drift_steps: int = 1_000_000) -> list[Cell]:
    """The matrix, row by row (issue 17 item 2)."""
    u = unit_time()
    hexp = hexagonal()
    hx = lambda dt, **kw: (lambda: packing_scene(hexp, dt, **kw))  # noqa: E731
    out = [
        Cell("time step", "0.9 × the safe estimate (default Δt rule)", "stable",
             lambda: _at_safe_fraction(hexp, 0.9), 3000),
        Cell("time step", "1.05 × the true critical step (spinning mode)", "refused",
             hx(1.05 * SPIN_LIMIT * u, name="dt-1p05"), 3000, field="scene.dt="),
        Cell("time step", "1.05 × the true critical step, allow_unsafe_dt", "stopped",
             hx(1.05 * SPIN_LIMIT * u, name="dt-1p05-forced", allow_unsafe_dt=True), 20000),
        Cell("time step", "3 × the true critical step, allow_supercritical", "stopped",
             hx(3.0 * SPIN_LIMIT * u, name="dt-3-forced", allow_supercritical=True), 3000),
        Cell("stiffness ratio", "kS/kN = 1e-3 (default Δt)", "stable", hx(None, ks=1e-3 * KN, name="ks-1e-3"), 3000),
        Cell("stiffness ratio", "kS/kN = 1e3 (default Δt)", "stable", hx(None, ks=1e3 * KN, name="ks-1e3"), 3000),
        Cell("stiffness ratio", "kS/kN = 1e3 at the kS = kN safe step", "refused",
             hx(0.9 * 0.333 * u, ks=1e3 * KN, name="ks-1e3-dt"), 3000, field="scene.dt"),
        Cell("radius ratio", "100:1 (one disc on a bed of small ones), default Δt rule", "refused", radius_ratio_scene,
             3000, field="scene.dt_fraction"),
        Cell("radius ratio", "100:1, 0.9 × the safe step (the refusal's fix)", "stable",
             lambda: at_safe_fraction(radius_ratio_scene, 0.9), 3000),
        Cell("friction", "μ = 0", "stable", hx(None, friction=0.0, name="mu-0"), 3000),
        Cell("friction", "μ = 1e6", "stable", hx(None, friction=1e6, name="mu-1e6"), 3000),
        Cell("BEM gap", "min_gap = 1e-2 r, disc touching a wall, thesis Δt", "refused",
             lambda: falling_disc_scene(min_gap=5e-3, at_wall=True, name="gap-1e-2"), 40, chunk=20,
             field="scene.dt="),
        Cell("BEM gap", "min_gap = 1e-4 r, disc touching a wall, thesis Δt", "refused",
             lambda: falling_disc_scene(min_gap=5e-5, at_wall=True, name="gap-1e-4"), 40, chunk=20,
             field="scene.dt="),
        Cell("BEM gap", "min_gap = 1e-4 r, disc touching a wall, thesis Δt forced", "stopped",
             lambda: falling_disc_scene(min_gap=5e-5, at_wall=True, allow=True, name="gap-1e-4-forced"), 40,
             chunk=20),
        Cell("BEM gap", "min_gap = 1e-4 r, disc touching a wall, default Δt (capped at the drag limit)", "stable",
             lambda: falling_disc_scene(min_gap=5e-5, at_wall=True, dt="auto", name="gap-1e-4-auto"), 40, chunk=20),
        Cell("viscosity", "μ_f = 1e-3, thesis Δt", "stable", lambda: falling_disc_scene(mu=1e-3, name="visc-1e-3"),
             40, chunk=20),
        Cell("viscosity", "μ_f = 1e3, thesis Δt", "refused", lambda: falling_disc_scene(mu=1e3, name="visc-1e3"),
             40, chunk=20, field="scene.dt="),
        Cell("viscosity", "μ_f = 1e3, thesis Δt forced, disc at a wall (the limit's configuration)", "stopped",
             lambda: falling_disc_scene(mu=1e3, allow=True, at_wall=True, name="visc-1e3-forced"), 40, chunk=20),
        Cell("viscosity", "μ_f = 1e3, default Δt (capped at the drag limit), disc at a wall", "stable",
             lambda: falling_disc_scene(mu=1e3, dt="auto", at_wall=True, name="visc-1e3-auto"), 40, chunk=20),
        Cell("energy drift", f"{drift_steps:.0e} steps, frictionless hexagonal packing, no damping", "stable",
             hx(None, friction=0.0, name="drift", n_steps=drift_steps, perturbation=DRIFT_PERTURBATION), drift_steps,
             chunk=max(drift_steps // 100, 1)),
        # 3D: the Hertz-Mindlin FCC packing (its spinning modes, as the 2D packing's)
        Cell("3D time step", "0.9 × the safe estimate (Hertz FCC packing)", "stable",
             lambda: fcc_at(0.9, name="fcc-0p9"), 5000),
        Cell("3D time step", "1.1 × the true critical step", "refused",
             lambda: fcc_at(1.1 * FCC_CRITICAL, name="fcc-1p1"), 5000, field="scene.dt="),
        Cell("3D time step", "1.1 × the true critical step, allow_unsafe_dt", "stopped",
             lambda: fcc_at(1.1 * FCC_CRITICAL, name="fcc-1p1-forced", allow_unsafe_dt=True), 5000),
        Cell("3D time step", "3 × the true critical step, allow_supercritical", "stopped",
             lambda: fcc_at(3.0 * FCC_CRITICAL, name="fcc-3-forced", allow_supercritical=True), 5000),
        Cell("3D friction", "μ = 0, 0.9 × the safe estimate", "stable",
             lambda: fcc_at(0.9, friction=0.0, name="fcc-mu-0"), 5000),
        Cell("3D friction", "μ = 1e6, 0.9 × the safe estimate", "stable",
             lambda: fcc_at(0.9, friction=1e6, name="fcc-mu-1e6"), 5000),
        # ellipsoids: the pre-compressed lattice (its limit is above the Rayleigh step, so forcing it takes
        # allow_supercritical)
        Cell("ellipsoid time step", "0.9 × the safe estimate (Hertz ellipsoid lattice)", "stable",
             lambda: ellipsoid_lattice_at(0.9, name="ell-0p9"), 3000),
        Cell("ellipsoid time step", "1.1 × the true critical step", "refused",
             lambda: ellipsoid_lattice_at(1.1 * ELL_CRITICAL, name="ell-1p1"), 3000, field="scene.dt="),
        Cell("ellipsoid time step", "1.1 × the true critical step, allow_supercritical", "stopped",
             lambda: ellipsoid_lattice_at(1.1 * ELL_CRITICAL, name="ell-1p1-forced", allow_supercritical=True), 3000),
    ]
    return out


def _at_safe_fraction(packing, fraction: float) -> Scene:
    """The packing at ``fraction`` × the safe critical step build computes for it."""
    return at_safe_fraction(lambda dt: packing_scene(packing, dt, name="dt-safe-fraction"), fraction)


def at_safe_fraction(make: Callable[[float | None], Scene], fraction: float) -> Scene:
    """``make(dt)`` at ``fraction`` × the safe critical step build computes for ``make(None)``'s discs (the
    fix the refusal of a too-large default step names)."""
    from ..build import build

    probe = replace(make(None), dt=1e-12, allow_supercritical=True)
    return make(fraction * build(probe).dt_safe)


def garbage_control() -> Outcome:
    """The negative control: the 1.05 × critical cell with the energy detector silenced ("warn") must be
    classified garbage by the observer."""
    u = unit_time()
    cell = Cell("control", "1.05 × critical, energy_check='warn'", "garbage",
                lambda: packing_scene(hexagonal(), 1.05 * SPIN_LIMIT * u, name="control", allow_unsafe_dt=True),
                20000)
    return run_cell(cell, energy_check="warn")


def garbage_control3d() -> Outcome:
    """The 3D negative control: the 1.1 × critical FCC cell with the energy detector silenced must be garbage."""
    cell = Cell("control", "3D, 1.1 × critical, energy_check='warn'", "garbage",
                lambda: fcc_at(1.1 * FCC_CRITICAL, name="control-3d", allow_unsafe_dt=True), 5000)
    return run_cell(cell, energy_check="warn")


def drift_control(steps: int = 100_000) -> Outcome:
    """Negative control of the drift check: the drift cell with contact dashpots at 1e-6 of critical (energy
    leaves the system) must exceed the round-off bound."""
    c = 2e-6 * math.sqrt(KN * math.pi * DENSITY / 2)
    cell = Cell("control", f"drift cell with dashpots (ζ = 1e-6), {steps:.0e} steps", "drift beyond the bound",
                lambda: packing_scene(hexagonal(), None, friction=0.0, cn=c, name="drift-control", n_steps=steps,
                                      perturbation=DRIFT_PERTURBATION), steps, chunk=max(steps // 100, 1))
    return run_cell(cell)


def drift_check(out: Outcome, window: float = 0.2) -> tuple[float, float]:
    """(secular drift, what is allowed) of the conserved energy E = kinetic + elastic sampled at every chunk:
    drift = |mean of the last ``window`` of the samples − mean of the first|; allowed = the spread (max − min)
    of the first window (the bounded oscillation of central differences: the energy error must not grow
    beyond it) + the round-off bound DRIFT_TOL_PER_STEP × steps × |E_0|.  Both relative to |E_0|."""
    e = np.asarray(out.drift, dtype=float)
    e0 = abs(e[0])
    w = max(int(round(window * len(e))), 2)
    first, last = e[:w], e[-w:]
    drift = abs(last.mean() - first.mean()) / e0
    allowed = (first.max() - first.min()) / e0 + DRIFT_TOL_PER_STEP * out.cell.steps
    return float(drift), float(allowed)


class StabilityMatrix(Case):
    name = "stability-matrix"
    title = "Stability at the extremes: every cell stable or a clear error"
    source = SRC
    assumptions = (
        "The observer that calls a run 'stable' uses none of demflow's blow-up detectors: finite state, no overlap "
        "beyond 0.5 R, energy (kinetic + gravitational net of buoyancy + springs) not above 2 × its start; no cell "
        "has an energy source.",
        "The hexagonal frictional packing's true critical step is the analytic 2/√24 √(m/kN) of its spinning mode "
        "(measured to 1 % by tests/test_time_step.py).",
        "The 100:1 cell is one disc of radius 1 resting on three layers of radius-0.01 discs in a box.",
        "The fluid cells are the thesis §5.1 falling disc (CGS units) with its viscosity, Δt or BEM gap changed; "
        "'gaps → 0' is Fluid.min_gap for a disc started touching a side wall.",
        "The energy-drift cell runs the default 1e6 steps; the default test run uses 1e5 (the case's drift_steps).",
        "The 3D cells are a face-centred cubic packing of 108 Hertz-Mindlin spheres (R = 1 cm, E = 70 GPa, ν = 0.2, "
        "μ = 0.5, 1 % pre-compression) between two planes, periodic in x and y; its true critical step is 1.62 × its "
        "safe estimate (measured by bisection to 2 % in tests/test_time_step3d.py), so '1.1 × critical' is at "
        "least 1.08 × the true limit.",
        "The ellipsoid cells are one layer of 16 aligned ellipsoids (semi-axes 3 × 2 × 1.2 cm, the same glass, "
        "μ = 0.5, 1 % pre-compression of c) between two planes, periodic in x and y; its true critical step is 3.81 × "
        "the ellipsoids' safe estimate (measured by bisection to 2 % in tests/test_ellipsoid_time_step.py).",
    )
    params = dict(drift_steps=1_000_000)

    def run(self, p) -> CaseRun:
        outs = [run_cell(c) for c in cells(int(p["drift_steps"]))]
        return CaseRun(extras={"outcomes": outs, "control": garbage_control(), "control-3d": garbage_control3d(),
                               "drift-control": drift_control()})

    def checks(self, run, p):
        out = []
        for o in run.extras["outcomes"]:
            c = o.cell
            ok = o.outcome == c.expect
            out.append(Check.condition(
                f"{c.row}: {c.setting} → {o.outcome} (expected {c.expect})", ok, 1.0 if ok else 0.0, SRC,
                "Each cell's outcome is declared before the run: stable (checked by an independent observer), or a "
                "clear error (SceneError naming the field and the fix, or BlowUpError with the last good state "
                "saved and finite); anything else is silent garbage.", kind="self-consistency"))
            if c.row == "energy drift" and o.outcome == "stable":
                drift, bound = drift_check(o)
                out.append(Check.condition(
                    f"no energy drift over {c.steps:.0e} conservative steps: |mean E, last fifth − first fifth|/E = "
                    f"{drift:.3g} ≤ {bound:.3g} (the first fifth's spread + round-off)", drift <= bound, drift, SRC,
                    "Central differences keep the energy error of a conservative system bounded (it oscillates, it "
                    "does not grow): the mean energy of the run's last fifth must lie within the spread of its first "
                    "fifth, plus a round-off allowance (tolerance 'stability.drift-per-step').", kind="self-consistency"))
        dc = run.extras["drift-control"]
        d, bound = drift_check(dc)
        out.append(Check.condition(
            f"negative control: the drift check fails for a run with dashpots at ζ = 1e-6 (drift {d:.3g} > {bound:.3g})",
            d > bound, d, SRC, "The drift bound must be able to fail: energy leaving through dashpots is seen.",
            kind="self-consistency"))
        for key, what in (("control", "the 1.05 × critical run"), ("control-3d", "the 3D 1.1 × critical run")):
            ctl = run.extras[key]
            out.append(Check.condition(
                f"negative control: the observer calls {what} with the energy detector silenced {ctl.outcome!r}",
                ctl.outcome == "garbage", 1.0 if ctl.outcome == "garbage" else 0.0, SRC,
                "The observer must be able to fail: an unstable run the detectors do not stop is garbage.",
                kind="self-consistency"))
        return out

    def tables(self, run, p):
        import pandas as pd

        rows = [dict(row=o.cell.row, setting=o.cell.setting, expected=o.cell.expect, outcome=o.outcome,
                     detail=o.detail[:300], wall_s=round(o.wall_s, 2)) for o in run.extras["outcomes"]]
        for key in ("control", "control-3d"):
            ctl = run.extras[key]
            rows.append(dict(row="control", setting=ctl.cell.setting, expected="garbage", outcome=ctl.outcome,
                             detail=ctl.detail[:300], wall_s=round(ctl.wall_s, 2)))
        return [("The matrix: each cell's expected and observed outcome", pd.DataFrame(rows))]


__all__ = ["StabilityMatrix", "cells", "run_cell", "garbage_control", "garbage_control3d", "hexagonal", "packing_scene", "fcc", "fcc_at"]
