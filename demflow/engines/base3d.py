"""What the 3D engine harness shares: the scene as validated numbers, the trajectory tables every
engine returns, and demflow itself behind the same interface.

A :class:`~demflow.scene3d.Scene3D` reaches an engine deck only as :func:`scene3d_numbers`: numbers
(finite floats, checked) and identifiers (checked), taken from the *built* simulation so that the
engines get the masses, inertias, effective moduli, damping ratios and time step demflow uses.

Every engine returns a :class:`Trajectory3D`, one convention for all three:

- ``spheres``: step, id, x, y, z, vx, vy, vz, wx, wy, wz — after ``step`` steps: the centre x_n
  (unwrapped across periodic boundaries), the velocity and angular velocity of the last half step
  v_{n-1/2}, ω_{n-1/2} (at step 0 the initial v(-Δt/2) demflow is given);
- ``planes``: step, plane, fx, fy, fz — the force of the spheres on each plane evaluated at the
  positions x_step (during step ``step``).

demflow, YADE (``NewtonIntegrator``) and LIGGGHTS (velocity Verlet, whose on-step v_n the reader
turns back into v_{n-1/2} = v_n − Δt f_n / 2m with the force it dumped) hold these same numbers.
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..scene import SceneError, check_identifier
from . import DemflowEngine
from .base import EngineRun, EngineUnsupported

SPHERE_COLUMNS = ("step", "id", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz")
PLANE_COLUMNS = ("step", "plane", "fx", "fy", "fz")


def _num(v, what) -> float:
    f = float(v)
    if not math.isfinite(f):
        raise SceneError(f"{what}={v!r} is not a finite number; engine decks take finite numbers only")
    return f


def _nums(a, what) -> list:
    a = np.asarray(a, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise SceneError(f"{what} holds a non-finite number; engine decks take finite numbers only")
    return a.tolist()


def scene3d_numbers(scene, sim) -> dict:
    """The 3D scene as plain numbers and identifiers (validated), from its built simulation ``sim``.

    Material pairs that can meet carry the law's compiled tables (E*, G*, μ, ζ_n, ζ_t and the modes);
    a rigid plane material (E = ∞) is kept as ``rigid`` with no modulus (each deck says how it
    expresses it).
    """
    from ..laws.hertz_mindlin import CAP_TOTAL, HERTZ_PARAMS_TYPES, SHEAR_TOTAL, TANGENTIAL_MD, TANGENTIAL_MINDLIN

    check_identifier("scene", scene.name)
    if getattr(scene, "ellipsoids", None) is not None:
        raise EngineUnsupported(
            f"scene {scene.name!r} has ellipsoids; the 3D engine decks write spheres only (neither deck expresses "
            "the Lin & Ng ellipsoid contact): run it in demflow")
    if getattr(scene, "meshes", None):
        raise EngineUnsupported(
            f"scene {scene.name!r} has triangle meshes ({', '.join(repr(m.name) for m in scene.meshes)}); the 3D "
            "engine decks write spheres, clumps and planes only (a mesh would be left out of the deck): run it in "
            "demflow, or give the walls as planes")
    names = [check_identifier("material", m) for m in scene.materials]
    law = sim.law_params
    if not isinstance(law, HERTZ_PARAMS_TYPES):
        raise EngineUnsupported(
            f"scene {scene.name!r} uses the linear law in 3D; the 3D engine decks express the Hertz-Mindlin law "
            "only (capabilities feature 'linear-law-3d'): give every pair a HertzMindlinLaw")
    sp = sim.spheres
    mats = [names[int(m)] for m in sp.mat]
    used = sorted(set(mats), key=names.index)
    plane_mats = [names[int(m)] for m in sim.planes.mat]
    materials = {}
    for m in sorted(set(used) | set(plane_mats), key=names.index):
        mt = scene.materials[m]
        rigid = mt.young == math.inf
        materials[m] = dict(rigid=rigid, young=None if rigid else _num(mt.young, f"material {m} young"),
                            poisson=_num(mt.poisson, f"material {m} poisson"),
                            density=_num(mt.density, f"material {m} density"))
    tmode = {TANGENTIAL_MINDLIN: "mindlin", TANGENTIAL_MD: "mindlin-deresiewicz"}

    def pair(a, b):
        ia, ib = names.index(a), names.index(b)
        return dict(a=a, b=b, Estar=_num(law.Estar[ia, ib], "E*"), Gstar=_num(law.Gstar[ia, ib], "G*"),
                    mu=_num(law.mu[ia, ib], "friction"), zn=_num(law.zn[ia, ib], "zeta_n"),
                    zt=_num(law.zt[ia, ib], "zeta_t"), tangential=tmode.get(int(law.tangential[ia, ib]), "none"))

    # sphere-sphere pairs that can meet (a lone sphere of a material never meets its own kind), then
    # sphere-plane pairs (b a plane's material)
    sphere_pairs = [pair(a, b) for k, a in enumerate(used) for b in used[k:] if a != b or mats.count(a) > 1]
    plane_pairs = [pair(a, b) for a in used for b in sorted(set(plane_mats), key=names.index)]
    planes = []
    for q, p in enumerate(scene.planes):
        phases = [dict(cycles=int(ph.cycles), v=_nums(ph.velocity, f"plane {p.name} phase velocity"))
                  for ph in p.phases]
        planes.append(dict(name=check_identifier("plane", p.name), point=_nums(sim.planes.point[q], "plane point"),
                           normal=_nums(sim.planes.normal[q], "plane normal"), material=plane_mats[q],
                           phases=phases, servo=p.servo is not None))
    b = scene.box
    box = dict(periodic_x=b.periodic_x is not None, periodic_y=b.periodic_y is not None,
               x0=_num(sim.box.x0, "box x0"), y0=_num(sim.box.y0, "box y0"),
               lx=_num(sim.box.lx, "box lx"), ly=_num(sim.box.ly, "box ly"))
    d = scene.damping
    return dict(
        name=scene.name, dim=3, dt=_num(sim.dt, "dt"), n_steps=int(scene.n_steps),
        every=max(int(scene.outputs.every), 1), gravity=_nums(sim.g, "gravity"),
        local_damping=_num(scene.local_damping, "local damping"),
        global_damping=bool(d.C > 0 or d.C_rot > 0 or d.alpha > 0),
        skin=_num(sim.skin, "skin"), n_spheres=int(sim.n),
        spheres=dict(x=_nums(sp.pos[:, 0], "x"), y=_nums(sp.pos[:, 1], "y"), z=_nums(sp.pos[:, 2], "z"),
                     r=_nums(sp.r, "radius"), mass=_nums(sp.mass, "mass"), inertia=_nums(sp.inertia, "inertia"),
                     vx=_nums(sp.vel[:, 0], "vx"), vy=_nums(sp.vel[:, 1], "vy"), vz=_nums(sp.vel[:, 2], "vz"),
                     wx=_nums(sp.angvel[:, 0], "wx"), wy=_nums(sp.angvel[:, 1], "wy"),
                     wz=_nums(sp.angvel[:, 2], "wz"), material=mats, fixed=[int(f) for f in sp.fixed]),
        materials=materials, sphere_pairs=sphere_pairs, plane_pairs=plane_pairs, planes=planes, box=box,
        shear_spring="total" if law.shear_spring == SHEAR_TOTAL else "incremental",
        friction_cap="total" if law.cap == CAP_TOTAL else "elastic",
    )


def touching_at_start(sim) -> bool:
    """Whether any contact carries force at t = 0 (then v(0) and v(-Δt/2) differ by that force):
    the pairs the neighbour search lists with no skin (centres closer than r_i + r_j, or a plane
    closer than r)."""
    from ..contacts.spheres import sphere_pairs

    i, _, _ = sphere_pairs(sim.spheres.pos, sim.spheres.r, 0.0, sim.box, sim.planes.point, sim.planes.normal)
    return bool(i.size)


@dataclass
class Trajectory3D:
    """The trajectory tables of one 3D run (module docstring) plus its metadata."""

    spheres: pd.DataFrame
    planes: pd.DataFrame
    meta: dict = field(default_factory=dict)

    def sphere_array(self, columns=("x", "y", "z")) -> tuple[np.ndarray, np.ndarray]:
        """(steps (R,), values (R, n, len(columns))) of every recorded sphere row, by step then id."""
        df = self.spheres.sort_values(["step", "id"])
        steps = np.unique(df.step.to_numpy())
        n = df.id.nunique()
        return steps, df[list(columns)].to_numpy().reshape(len(steps), n, len(columns))

    def plane_array(self) -> tuple[np.ndarray, np.ndarray]:
        """(steps (R,), forces (R, n_planes, 3)) in the order the planes were declared."""
        names = self.meta.get("planes", sorted(self.planes.plane.unique()))
        if not names:
            return np.zeros(0, np.int64), np.zeros((0, 0, 3))
        df = self.planes.copy()
        df["k"] = df.plane.map({p: k for k, p in enumerate(names)})
        df = df.sort_values(["step", "k"])
        steps = np.unique(df.step.to_numpy())
        return steps, df[["fx", "fy", "fz"]].to_numpy().reshape(len(steps), len(names), 3)

    def save(self, out) -> Path:
        """Parquet tables + meta.json into directory ``out`` (each file written atomically)."""
        from ..results import save_tables

        return save_tables(out, {"spheres": self.spheres, "planes": self.planes}, "meta.json", self.meta)

    @classmethod
    def load(cls, out) -> "Trajectory3D":
        """Read tables written by :meth:`save`, or a stored reference (whose meta.json holds the run's own
        meta under ``results_meta``, merged here with the provenance)."""
        out = Path(out)
        m = json.loads((out / "meta.json").read_text())
        meta = dict(m.get("results_meta") or {}, **{k: v for k, v in m.items() if k != "results_meta"})
        return cls(spheres=pd.read_parquet(out / "spheres.parquet"), planes=pd.read_parquet(out / "planes.parquet"),
                   meta=meta)


def trajectory_from_arrays(sim, engine: str, sphere_steps, sphere_rows, plane_steps, plane_rows) -> Trajectory3D:
    """Build the tables from arrays: sphere_rows (R, n, 9) = x, y, z, vx, vy, vz, wx, wy, wz;
    plane_rows (Q, n_planes, 3)."""
    sphere_steps = np.asarray(sphere_steps, np.int64)
    rows = np.asarray(sphere_rows, np.float64).reshape(len(sphere_steps), sim.n, 9)
    n = sim.n
    sph = pd.DataFrame({"step": np.repeat(sphere_steps, n), "id": np.tile(np.arange(n), len(sphere_steps))})
    for k, c in enumerate(SPHERE_COLUMNS[2:]):
        sph[c] = rows[:, :, k].reshape(-1)
    names = [p.name for p in sim.scene.planes]
    plane_steps = np.asarray(plane_steps, np.int64)
    pr = np.asarray(plane_rows, np.float64).reshape(len(plane_steps), len(names), 3)
    pl = pd.DataFrame({"step": np.repeat(plane_steps, len(names)),
                       "plane": np.tile(np.array(names, dtype=object), len(plane_steps))})
    for k, c in enumerate(("fx", "fy", "fz")):
        pl[c] = pr[:, :, k].reshape(-1)
    meta = dict(engine=engine, scene=sim.scene.name, dt=sim.dt, steps=int(sim.scene.n_steps), n_spheres=n,
                planes=names, dim=3, r_min=float(np.min(sim.spheres.r)))
    return Trajectory3D(spheres=sph, planes=pl, meta=meta)


def demflow_trajectory(sim) -> Trajectory3D:
    """Run a built 3D simulation to its scene's n_steps, recording the trajectory tables every
    ``outputs.every`` steps (the state after each step, read from the simulation)."""
    every = max(int(sim.scene.outputs.every), 1)
    total = int(sim.scene.n_steps)
    s_steps, s_rows, p_steps, p_rows = [], [], [], []

    def state():
        sp = sim.spheres
        return np.concatenate([sim.unwrapped_positions(), sp.vel, sp.angvel], axis=1).copy()

    while True:
        step = sim.step
        if step % every == 0:
            s_steps.append(step)
            s_rows.append(state())
        if step >= total:
            break
        sim.run(1)
        if step % every == 0:  # the plane forces evaluated at x_step
            p_steps.append(step)
            p_rows.append(sim.planes.force.copy())
        nxt = min(total, (step // every + 1) * every)
        if nxt > sim.step:
            sim.run(nxt - sim.step)
    return trajectory_from_arrays(sim, "demflow", s_steps, s_rows, p_steps, p_rows)


def trajectory_difference(ref: Trajectory3D, other: Trajectory3D, until: int | None = None) -> dict:
    """The largest difference of ``other`` from ``ref`` over their common recorded steps (up to step
    ``until`` when given: states after that many steps, plane forces evaluated before it), each part
    made dimensionless by ``ref``'s own scales: positions by the smallest radius R, velocities by the
    largest speed V, angular velocities by V/R, plane forces by the largest plane force.

    Returns dict(position, velocity, angular, plane, max (the largest of the four), steps (the number
    of common steps compared))."""
    cols = ("x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz")
    s0, a0 = ref.sphere_array(cols)
    s1, a1 = other.sphere_array(cols)
    if until is not None:
        s0, a0 = s0[s0 <= until], a0[s0 <= until]
    common, i0, i1 = np.intersect1d(s0, s1, return_indices=True)
    if common.size == 0 or a0.shape[1] != a1.shape[1]:
        raise ValueError(f"trajectories of {ref.meta.get('scene')} share no recorded step or differ in spheres")
    a0, a1 = a0[i0], a1[i1]
    R = float(ref.meta["r_min"])
    V = float(np.max(np.linalg.norm(a0[:, :, 3:6], axis=2)))
    d = np.abs(a1 - a0)
    out = dict(position=float(d[:, :, :3].max() / R), velocity=float(d[:, :, 3:6].max() / V),
               angular=float(d[:, :, 6:].max() * R / V), plane=0.0, steps=int(common.size))
    p0, f0 = ref.plane_array()
    p1, f1 = other.plane_array()
    if until is not None:
        p0, f0 = p0[p0 < until], f0[p0 < until]
    if f0.size and f1.size:
        pc, j0, j1 = np.intersect1d(p0, p1, return_indices=True)
        F = float(np.max(np.abs(f0)))
        if pc.size and F > 0:
            out["plane"] = float(np.max(np.abs(f1[j1] - f0[j0])) / F)
    out["max"] = max(out["position"], out["velocity"], out["angular"], out["plane"])
    return out


class Demflow3DEngine(DemflowEngine):
    """demflow itself on a 3D scene, behind the engines' interface (no subprocess): the trajectory tables."""

    def run(self, scene, workdir=None, *, timeout=None, sim=None):
        from ..build import build

        t0 = time.perf_counter()
        res = demflow_trajectory(sim or build(scene))
        run = EngineRun(engine="demflow", version=self.version(), command=["demflow"],
                        wall_time_s=round(time.perf_counter() - t0, 3), date=time.strftime("%Y-%m-%dT%H:%M:%S"))
        return res, run


class BenchmarkSummary(dict):
    """What a benchmark deck reports after its run (steps, sphere_contacts, kinetic, ...), with the ``meta``
    dict the engines' ``run`` fills in (engine, version)."""

    def __init__(self, *a, **k):
        super().__init__(*a, **k)
        self.meta = {}


def read_json_output(path: Path, engine: str) -> dict:
    """A deck's JSON output, refusing a missing, truncated or incomplete file."""
    from .base import EngineOutputError

    if not path.exists():
        raise EngineOutputError(f"{engine} wrote no output ({path} missing); see {path.parent / 'engine.log'}")
    try:
        out = json.loads(path.read_text())
    except (OSError, ValueError, RecursionError) as e:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        raise EngineOutputError(f"{engine} output {path} is truncated or corrupt ({e}); rerun the engine") from None
    if not (isinstance(out, dict) and out.get("complete") is True):
        raise EngineOutputError(f"{engine} output {path} is incomplete; rerun the engine")
    return out


def recorded_steps(sim) -> tuple[np.ndarray, np.ndarray]:
    """The steps a trajectory records (as :func:`demflow_trajectory` and the decks write them): sphere
    states at 0, every, 2·every, ... up to n_steps; plane forces at 0, every, ... below n_steps."""
    every = max(int(sim.scene.outputs.every), 1)
    total = int(sim.scene.n_steps)
    return np.arange(0, total + 1, every, dtype=np.int64), np.arange(0, total, every, dtype=np.int64)

