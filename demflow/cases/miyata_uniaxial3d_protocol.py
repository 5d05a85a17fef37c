"""The uniaxial-compression protocol of Miyata §3.3 as demflow runs it (one seed, any variant of the
miyata-uniaxial-3d cases): the scenes of its stages, settling, trimming, the plate's loading with its records and
snapshots, and resumable checkpoints (:class:`ProtocolCheckpoints`).

The seed's protocol: particles inserted in a box periodic in x and y, settled under gravity, those
with centres above 2.0 m removed, settled again, a plate placed at the top and lowered at 2 cm/s;
Hertz E = 70 GPa, ν = 0.2 (particles and plate), μ = 0.6; particles 191 kg with semi-axes 37.1,
26.0 and 18.2 cm.

Assumptions (stated on the report): particles are K-sphere clumps of the ellipsoid (the greedy
cover of :mod:`demflow.shapes.clump`, scaled to 191 kg; K = 8 by default: 69 % of the ellipsoid's
volume, the rest of the mass spread over it) or the ellipsoid itself; inserted on a loose lattice with random
orientations (seeded); Cundall local damping 0.3 throughout (the seed does not say which damping its run used;
YADE's recipe of ENGINES.md); dashpots from e = 0.3 (LIGGGHTS-like body-mass dashpots); the
settled state is "at rest" when the kinetic energy is below 1e-9 × the bed's weight × 1 m.
Contacts on the plate and the floor are counted per particle (a clump touching with several
members counts once) and a particle's force is the sum over its members.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..scene import Box, Material
from ..scene3d import Clumps, Ellipsoids, Outputs3D, Plane, PlanePhase, Scene3D
from ..shapes.clump import MIYATA_AXES, MIYATA_MASS, ClumpTemplate
from ..shapes.clump import bounding_radius as clump_bounding_radius
from ..laws.hertz_mindlin import HertzMindlinLaw


G = 9.81


# the seed's own particle as a true ellipsoid (issue 16 item 2): the density that gives it 191 kg
ELLIPSOID_DENSITY = MIYATA_MASS / (4.0 / 3.0 * math.pi * MIYATA_AXES[0] * MIYATA_AXES[1] * MIYATA_AXES[2])


def _materials(young=7e10, shape="clumps"):
    rho = ELLIPSOID_DENSITY if shape == "ellipsoids" else 2650.0  # (a clump template carries its own 191 kg)
    return {"rock": Material(density=rho, young=young, poisson=0.2),
            "steel": Material(density=7800.0, young=young, poisson=0.2)}


def _particles(p, pos, q) -> dict:
    """The Scene3D fields of the particles: K-sphere clumps of the ellipsoid (``shape`` "clumps") or the
    ellipsoid itself ("ellipsoids", :class:`demflow.scene3d.Ellipsoids`), at ``pos`` with orientations ``q``."""
    if p.get("shape", "clumps") == "ellipsoids":
        return dict(spheres=None, ellipsoids=Ellipsoids(axes=[MIYATA_AXES] * len(pos), x=pos[:, 0], y=pos[:, 1],
                                                        z=pos[:, 2], material="rock", orientation=q))
    T = ClumpTemplate.ellipsoid_like(int(p["K"]), MIYATA_AXES, MIYATA_MASS)
    return dict(spheres=None, clumps=Clumps(T, x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], material="rock",
                                            orientation=q))


def particle_tops(sim) -> np.ndarray:
    """The highest point of each particle [length]: a clump's members' tops, an ellipsoid's
    z + √Σ_k (R_zk a_k)² (its support along z)."""
    if hasattr(sim, "ell"):
        rz = sim.ell.rot[:, 6:9] * sim.ell.axes
        return sim.spheres.pos[:, 2] + np.sqrt(np.sum(rz * rz, axis=1))
    return sim.spheres.pos[:, 2] + sim.spheres.r


def _laws(p=None):
    """Hertz-Mindlin, μ = 0.6, dashpots of e = 0.3; the Mindlin spring stored incrementally (YADE's, demflow's
    default) unless ``p["shear_spring"]`` is "total" (LIGGGHTS's; capabilities row shear-spring-uniaxial)."""
    law = HertzMindlinLaw(friction=0.6, restitution=0.3, shear_spring=(p or {}).get("shear_spring", "incremental"))
    return {("rock", "rock"): law, ("rock", "steel"): law}


def bounding_radius(p) -> float:
    """The radius of the particle's bounding sphere about its centre of mass [length]: the clump template's
    max |c_k| + r_k, or the ellipsoid's largest semi-axis."""
    if p.get("shape", "clumps") == "ellipsoids":
        return float(max(MIYATA_AXES))
    T = ClumpTemplate.ellipsoid_like(int(p["K"]), MIYATA_AXES, MIYATA_MASS)
    return clump_bounding_radius(T.centres, T.radii)


def random_insertion(n: int, L: float, rb: float, rng, packing: float | None = None,
                     max_tries: int = 1000) -> np.ndarray:
    """(n, 3) centres placed the way the LIGGGHTS deck's ``fix insert/pack ... all_in yes`` places bodies
    (:mod:`demflow.engines.liggghts_uniaxial3d`, capabilities row clumps-3d): one by one at uniform random points
    of the region [0, L]² × [0.05, 0.05 + H + 2 rb], H = n (4/3 π rb³) / (packing L²) + 2 rb (packing the deck's
    bounding-sphere volume fraction, 0.2), each bounding sphere (radius ``rb``) wholly inside the region and
    overlapping none placed before (so none across the period either); a rejected point is redrawn, up to
    ``max_tries`` times a body, else a clear error."""
    from ..engines.liggghts_uniaxial3d import PACKING

    packing = PACKING if packing is None else packing
    H = n * (4.0 / 3.0 * math.pi * rb ** 3) / (packing * L * L) + 2.0 * rb
    lo = np.array([rb, rb, 0.05 + rb])
    hi = np.array([L - rb, L - rb, 0.05 + rb + H])
    if np.any(hi < lo):
        raise ValueError(f"random_insertion: a box of side L={L:g} cannot hold a bounding sphere of radius {rb:g} "
                         "wholly inside it; widen the box")
    pos = np.zeros((n, 3))
    for k in range(n):
        for _ in range(max_tries):
            x = lo + (hi - lo) * rng.random(3)
            if k == 0 or np.min(np.sum((pos[:k] - x) ** 2, axis=1)) >= (2.0 * rb) ** 2:
                pos[k] = x
                break
        else:
            raise ValueError(f"random_insertion: no room for body {k} of {n} after {max_tries} tries (bounding radius "
                             f"{rb:g}, packing {packing:g}); lower the packing or the count")
    return pos


def insertion_scene(p) -> Scene3D:
    """Clumps on a loose lattice (spacing 0.78 m, above one another) with random orientations; with
    ``p["insertion"] == "random"`` at the random points of :func:`random_insertion` instead (LIGGGHTS's rule)."""
    rng = np.random.default_rng(p["seed"])
    L = p["box"]
    insertion = p.get("insertion", "lattice")
    if insertion not in ("lattice", "random"):
        from ..scene import SceneError

        raise SceneError(f"miyata-uniaxial-3d: insertion={insertion!r} is not an insertion of this protocol; give "
                         "'lattice' (demflow's loose lattice) or 'random' (the LIGGGHTS deck's insert/pack rule)")
    if insertion == "random":
        pos = random_insertion(int(p["n_insert"]), L, bounding_radius(p), rng)
    else:
        nx = max(1, int(L // 0.78))
        pos = []
        z = 0.45
        while len(pos) < p["n_insert"]:
            for i in range(nx):
                for j in range(nx):
                    if len(pos) < p["n_insert"]:
                        pos.append(((i + 0.5) * L / nx, (j + 0.5) * L / nx, z))
            z += 0.78
        pos = np.array(pos)
    q = rng.normal(size=(len(pos), 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    return Scene3D(name="miyata-uniaxial-3d-settle", materials=_materials(p.get("young", 7e10), p.get("shape", "clumps")),
                   laws=_laws(p), **_particles(p, pos, q),
                   planes=[Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "steel")], gravity=(0.0, 0.0, -G),
                   local_damping=p["local_damping"], box=Box(periodic_x=(0.0, L), periodic_y=(0.0, L)),
                   dt_fraction=p["dt_fraction"], outputs=Outputs3D(every=1000), allow_unsafe_dt=True)


SETTLE_CHUNK = 5000  # steps between the settling tests
CHECKPOINT_STEPS = 50000  # a resumable state at least this often (about a minute of the full variant)
PROTOCOL_VERSION = 3  # raise when protocol_run's stages, records or inputs change: old checkpoints are then not resumed
# (3: the clump template's principal frame without BLAS, 2026-11-25, which moved its last bits)
# the parameters that make a protocol run what it is: its checkpoints are kept under a hash of them
PROTOCOL_KEYS = ("shape", "box", "n_insert", "K", "seed", "trim", "plate_speed", "stress_max", "dt_fraction",
                 "local_damping", "young", "record_every", "settle_max", "snapshots", "plate_z_min")


class ProtocolCheckpoints:
    """Where one protocol run (one seed's parameters) keeps its resumable state: ``root``/seed<N>-<hash of
    :data:`PROTOCOL_KEYS` and :data:`PROTOCOL_VERSION`>/ (a run with other parameters never resumes from it).
    Every file is written atomically.  A completed run keeps its final state: run again, it returns the same
    result in seconds (the report re-rendered); delete the directory to run it afresh."""

    def __init__(self, root, p):
        import hashlib
        import json
        from pathlib import Path

        keys = {k: p.get(k) for k in PROTOCOL_KEYS}
        for k, default in (("insertion", "lattice"), ("shear_spring", "incremental")):
            if p.get(k, default) != default:  # the default runs keep the keys (and checkpoints) they had
                keys[k] = p[k]
        key = hashlib.sha256(json.dumps(keys | {"version": PROTOCOL_VERSION}, sort_keys=True,
                                        default=str).encode()).hexdigest()[:12]
        self.dir = Path(root) / f"seed{int(p['seed'])}-{key}"
        self._t0 = time.perf_counter()
        self._base_s = float(self.load("compute_s") or 0.0)  # compute time of earlier sessions of this run
        self._computing = False  # whether this session advanced the run (a finished run reloaded did not)

    def compute_s(self) -> float:
        """Seconds this run has computed, over every session up to its last checkpoint and this one's now.  A
        session that only reloads a finished run adds nothing: the time a report spends re-rendering a page is
        not the run's cost."""
        return self._base_s + (time.perf_counter() - self._t0 if self._computing else 0.0)

    def mark_time(self) -> None:
        """Store the compute time at a checkpoint (called once this session has advanced the run)."""
        self._computing = True
        self.save("compute_s", self.compute_s())

    def finish(self) -> float:
        """The run's compute time as its result states it, stored with the finished run when this session advanced
        it: reloading the finished run then gives the same number to the bit (the last checkpoint's time was taken
        before the run's final bookkeeping, so a report re-rendered from the checkpoints showed compute times
        1e-4 apart from the run that computed them)."""
        s = self.compute_s()
        if self._computing:
            self.save("compute_s", s)
        return s

    def path(self, name: str):
        return self.dir / name

    def save(self, name: str, obj) -> None:
        import pickle

        from ..atomic import write_bytes_atomic

        write_bytes_atomic(self.dir / name, pickle.dumps(obj))

    def load(self, name: str):
        import pickle

        f = self.dir / name
        return pickle.loads(f.read_bytes()) if f.exists() else None


def settle(sim, p, max_steps: int, ck: ProtocolCheckpoints | None = None, stage: str = "settle", bar=None) -> int:
    """Run until the kinetic energy is below 1e-9 × weight × 1 m (checked every :data:`SETTLE_CHUNK` steps);
    the steps run, negative when ``max_steps`` ran out first.  With ``ck``, resumable: the state is saved
    every :data:`CHECKPOINT_STEPS` steps and at the end (``<stage>.npz``, ``<stage>.done``), and a saved
    state is continued (to the bit: the same chunks from the same state)."""
    W = float(sim.bodies.mass.sum()) * G
    if ck is not None:
        finished = ck.load(f"{stage}.done")
        if ck.path(f"{stage}.npz").exists():
            sim.load_checkpoint(ck.path(f"{stage}.npz"))
        if finished is not None:
            if bar is not None:
                bar.update(abs(finished))
            return finished
    done = sim.step
    if bar is not None:
        bar.update(done)
    result = None
    while done < max_steps:
        sim.run(SETTLE_CHUNK, progress=False if bar is not None else None)
        done += SETTLE_CHUNK
        if bar is not None:
            bar.update(SETTLE_CHUNK)
        r = sim.tables(include_records=True)["records"].iloc[-1]
        if r.kinetic_translation + r.kinetic_rotation < 1e-9 * W * 1.0:
            result = done
            break
        if ck is not None and done % CHECKPOINT_STEPS == 0:
            sim.save_checkpoint(ck.path(f"{stage}.npz"))
            ck.mark_time()
    if result is None:
        result = -done
    if ck is not None:
        sim.save_checkpoint(ck.path(f"{stage}.npz"))
        ck.save(f"{stage}.done", result)
        ck.mark_time()
    return result


def next_stage(sim, p, name: str, keep=None, plate_z: float | None = None) -> Scene3D:
    """A scene continuing from ``sim``'s clumps (those in ``keep``), at rest, optionally with a plate
    at height ``plate_z`` moving down at the plate speed."""
    b = sim.bodies
    keep = np.arange(len(b.mass)) if keep is None else keep
    pos = b.pos[keep].copy()
    sc = insertion_scene(p)
    planes = list(sc.planes)
    if plate_z is not None:
        planes.append(Plane("plate", (0.0, 0.0, plate_z), (0.0, 0.0, -1.0), "steel",
                            phases=(PlanePhase(cycles=10 ** 9, velocity=(0.0, 0.0, -p["plate_speed"])),)))
    return Scene3D(name=name, materials=_materials(p.get("young", 7e10), p.get("shape", "clumps")), laws=_laws(p),
                   **_particles(p, pos, b.quat[keep]), planes=planes, gravity=(0.0, 0.0, -G), local_damping=p["local_damping"],
                   box=Box(periodic_x=(0.0, p["box"]), periodic_y=(0.0, p["box"])), dt_fraction=p["dt_fraction"],
                   allow_unsafe_dt=True,
                   outputs=Outputs3D(every=p["record_every"]))


def plate_touching(sim, wall: int) -> np.ndarray:
    """The bodies touching wall ``wall`` (index among the planes) with a positive normal force, in the
    order of :func:`per_particle_forces`'s values (ascending body index)."""
    pr = sim.pairs
    on = (pr.j == sim.n + wall) & (pr.fn > 0)
    return np.unique(sim.spheres.body[pr.i[on]])


def per_particle_forces(sim, wall: int) -> np.ndarray:
    """Force each particle (clump) exerts on wall ``wall`` (index among the planes): the sum of its
    members' normal forces there; particles not touching are left out."""
    pr = sim.pairs
    on = (pr.j == sim.n + wall) & (pr.fn > 0)
    body = sim.spheres.body[pr.i[on]]
    f = np.bincount(body, weights=pr.fn[on], minlength=len(sim.bodies.mass))
    return f[f > 0]


def wall_contact_points(sim, wall: int, box: float) -> np.ndarray:
    """Where each particle touching wall ``wall`` touches it, seen from above: the normal-force-weighted mean
    (x, y) of its member spheres' centres on that wall (periodic: relative to its first touching member by the
    minimum image), wrapped into [0, box); rows in the order of :func:`per_particle_forces` (ascending body).
    The point every engine's force map draws (Miyata Fig. 34: the force at each contact point)."""
    from ..engines.uniaxial3d import per_particle_contacts

    pr = sim.pairs
    on = (pr.j == sim.n + wall) & (pr.fn > 0)
    i = pr.i[on]
    return per_particle_contacts(sim.spheres.body[i], pr.fn[on], sim.spheres.pos[i, :2], box)[1]


def _loading_row(s3, A, touched, weight):
    """One record of the loading stage: the plate and floor stresses and contacts, and the bed's
    coordination, fabric and average stress (:func:`demflow.analysis.micro3d.micro_state`)."""
    from ..analysis.micro3d import micro_state, statics_stress_zz

    plate = float(s3.planes.force[1, 2]) / A
    zp = float(s3.planes.point[1, 2])
    fp = per_particle_forces(s3, 1)
    ff = per_particle_forces(s3, 0)
    m = micro_state(s3, A * zp)
    f, sg = m["fabric"], m["stress"]
    row = {"step": s3.step, "plate_z": zp, "settlement": (touched - zp) if touched is not None else 0.0,
           "plate_stress": plate, "floor_stress": -float(s3.planes.force[0, 2]) / A, "plate_contacts": fp.size,
           "floor_contacts": ff.size, "coordination": m["coordination"], "coordination_walls": m["coordination_walls"],
           "fabric_xx": f[0, 0], "fabric_yy": f[1, 1], "fabric_zz": f[2, 2],
           "stress_xx": sg[0, 0], "stress_yy": sg[1, 1], "stress_zz": sg[2, 2],
           "stress_xz": 0.5 * (sg[0, 2] + sg[2, 0]), "stress_yz": 0.5 * (sg[1, 2] + sg[2, 1]), "com_z": m["com_z"],
           "stress_zz_statics": statics_stress_zz(plate, weight, A, m["com_z"], zp)}
    return row, fp, ff, m


def protocol_run(p) -> dict:
    """demflow's run of the protocol for parameters ``p`` (one seed): the loading curve, the snapshots and
    the settled bed's numbers (the keys :meth:`demflow.engines.uniaxial3d.UniaxialRun.from_case` reads).

    ``p["checkpoint_dir"]`` (optional): resumable (:class:`ProtocolCheckpoints`; an interrupted run given the
    same parameters continues where its last checkpoint was, to the bit; a completed one returns its result).  ``p["progress"]``: progress bars
    per stage (True / False / None: on a terminal)."""
    import pandas as pd

    from .. import progress
    from ..build import build

    t_start = time.perf_counter()
    root = p.get("checkpoint_dir") or ""
    ck = ProtocolCheckpoints(root, p) if root else None
    show = p.get("progress")
    seed = int(p["seed"])
    A = p["box"] ** 2
    s1 = build(insertion_scene(p))
    with progress.bar(p["settle_max"], f"seed {seed}: settle the inserted bed", show=show) as bar:
        steps1 = settle(s1, p, p["settle_max"], ck, "settle1", bar)
    keep = np.nonzero(s1.bodies.pos[:, 2] <= p["trim"])[0]
    s2 = build(next_stage(s1, p, "miyata-uniaxial-3d-trimmed", keep))
    with progress.bar(p["settle_max"], f"seed {seed}: settle the trimmed bed", show=show) as bar:
        steps2 = settle(s2, p, p["settle_max"], ck, "settle2", bar)
    weight = float(s2.bodies.mass.sum()) * G
    floor_settled = -float(s2.planes.force[0, 2])
    n_particles = len(s2.bodies.mass)
    top = float(particle_tops(s2).max())
    s3 = build(next_stage(s2, p, "miyata-uniaxial-3d-loading", plate_z=top + 0.005))
    z0 = top + 0.005
    st = {"rows": [], "snaps": [], "levels": list(np.linspace(400e3, p["stress_max"], p["snapshots"])),
          "touched": None, "finished": False}
    if ck is not None and ck.path("loading.npz").exists():
        s3.load_checkpoint(ck.path("loading.npz"))
        st = ck.load(f"loading-{s3.step}.pkl")
        if st is None:
            raise FileNotFoundError(f"{ck.dir}: loading.npz is at step {s3.step} but loading-{s3.step}.pkl is missing; "
                                    f"remove {ck.dir} to start this run afresh")
    last_ckpt = s3.step
    every_ckpt = max(1, CHECKPOINT_STEPS // int(p["record_every"])) * int(p["record_every"])
    with progress.bar(int(round(p["stress_max"] / 1e3)), f"seed {seed}: load the plate", unit="kPa", show=show) as bar:
        shown = 0
        while not st["finished"]:
            s3.run(p["record_every"], progress=False if show is not None else None)
            plate = float(s3.planes.force[1, 2]) / A
            zp = float(s3.planes.point[1, 2])
            if st["touched"] is None and plate > 0:
                st["touched"] = zp
            row, fp, ff, m = _loading_row(s3, A, st["touched"], weight)
            st["rows"].append(row)
            while st["levels"] and plate >= st["levels"][0]:
                snap = {"stress": plate, "plate": fp, "floor": ff, "fabric": m["fabric"], "stress_tensor": m["stress"],
                        "coordination": m["coordination"]}
                for wall, k in (("plate", 1), ("floor", 0)):
                    ids = plate_touching(s3, k)
                    snap.update({f"{wall}_ids": ids, f"{wall}_xy": s3.bodies.pos[ids, :2].copy(),
                                 f"{wall}_cxy": wall_contact_points(s3, k, p["box"])})
                st["snaps"].append(snap)
                st["levels"].pop(0)
            st["finished"] = bool(plate >= p["stress_max"] or zp < p["plate_z_min"])
            now = max(0, min(int(plate / 1e3), int(round(p["stress_max"] / 1e3))))
            if now > shown:
                bar.update(now - shown)
                shown = now
            if ck is not None and (s3.step - last_ckpt >= every_ckpt or st["finished"]):
                ck.save(f"loading-{s3.step}.pkl", st)
                s3.save_checkpoint(ck.path("loading.npz"))
                for old in ck.dir.glob("loading-*.pkl"):
                    if old.name != f"loading-{s3.step}.pkl":
                        old.unlink()
                last_ckpt = s3.step
                ck.mark_time()
    sp = s3.spheres
    # the work done: particles (clumps or ellipsoids) × steps, over the three stages (the trimmed bed has fewer)
    particle_steps = len(s1.bodies.mass) * s1.step + n_particles * (s2.step + s3.step)
    bed = {"pos": sp.pos.copy(), "r": sp.r.copy(), "body": sp.body.copy(), "plate_z": float(s3.planes.point[1, 2]),
           "box": float(p["box"])}
    out = {"curve": pd.DataFrame(st["rows"]), "snapshots": st["snaps"], "weight": weight,
           "floor_settled": floor_settled, "n_particles": n_particles, "area": A, "settle_steps": (steps1, steps2),
           "dt": s3.dt, "plate_start": z0, "seed": seed, "bed": bed, "particle_steps": int(particle_steps),
           "compute_s": ck.finish() if ck is not None else time.perf_counter() - t_start}
    return out
