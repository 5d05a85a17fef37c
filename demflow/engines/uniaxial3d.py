"""miyata-uniaxial-3d in the real engines: the protocol as numbers, the output every engine writes,
and the run object all three engines (demflow, YADE, LIGGGHTS) return.

The uniaxial case is a *protocol*, not one scene (insert, settle, trim, settle, place the plate,
load), and the engines cannot share a bed: LIGGGHTS makes bodies only through its insertion fixes,
and a settled bed is chaotic anyway.  So each engine's deck runs the whole protocol itself from the
same numbers (:func:`protocol_numbers`: demflow's clump template, masses, inertias, moduli, damping
ratios, Δt, box, trim height, plate speed and stress levels, all validated finite numbers) and the
engines are compared statistically (demflow's seed band, issue 14 item 4).

What every engine deck writes into its working directory (read by :func:`read_uniaxial_output`):

- ``uniaxial_out.json``: ``n_inserted``, ``n_particles`` (after trimming), ``weight`` (the trimmed
  bed's weight [N]), ``floor_settled`` (the floor's normal force after the second settling [N]),
  ``settle_steps`` ([first, second], steps), ``dt`` [s], ``plate_start`` (the plate's height when
  loading starts [m]), ``clump_mass`` [kg], ``clump_inertia`` (principal moments [kg m²]);
- ``curve.csv``: one row every ``record_every`` loading steps with the columns of
  :data:`CURVE_COLUMNS`: step (since loading began), plate_z [m], settlement (plate travel since
  its force first became positive [m]), plate_stress, floor_stress (normal force / box area [Pa]),
  plate_contacts, floor_contacts (particles, not member spheres, touching);
- ``snapshots.csv``: :data:`SNAPSHOT_COLUMNS`: snapshot (0, 1, ...), stress (the plate stress when
  it was taken [Pa]), wall ("plate" or "floor"), force (one particle's normal force on that wall,
  the sum over its member spheres [N]), x, y (where the particle touches the wall: the normal-force-
  weighted mean of its touching members' centres, periodic minimum image, wrapped into the box [m];
  :func:`demflow.cases.miyata_uniaxial3d_protocol.wall_contact_points`); one snapshot when the plate stress first
  reaches each of ``snapshot_levels``.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .base import EngineOutputError

CURVE_COLUMNS = ("step", "plate_z", "settlement", "plate_stress", "floor_stress", "plate_contacts", "floor_contacts")
SNAPSHOT_COLUMNS = ("snapshot", "stress", "wall", "force", "x", "y")
OUT_KEYS = ("n_inserted", "n_particles", "weight", "floor_settled", "settle_steps", "dt", "plate_start", "clump_mass",
            "clump_inertia")
SETTLE_CHECK_EVERY = 5000  # steps between at-rest checks (demflow.cases.miyata_uniaxial3d_protocol.settle)
SETTLE_KE_FRACTION = 1e-9  # at rest: kinetic energy < this × the bed's weight × 1 m
PLATE_GAP = 0.005  # the plate starts this far above the highest particle point [m]


def _finite(v, what) -> float:
    f = float(v)
    if not math.isfinite(f):
        raise EngineOutputError(f"{what}={v!r} is not a finite number")
    return f


def per_particle_contacts(body: np.ndarray, fn: np.ndarray, xy: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
    """Per particle (ascending body id) touching a wall, from its member contacts (``body`` of each, normal force
    ``fn``, member centre ``xy``): the forces summed, and where it touches: the force-weighted mean of its touching
    members' centres (minimum image from its first one, wrapped into [0, L)); what the snapshots' force, x and y
    are in every engine."""
    if body.size == 0:
        return np.zeros(0), np.zeros((0, 2))
    _, first, inv = np.unique(body, return_index=True, return_inverse=True)
    ref = xy[first]
    d = xy - ref[inv]
    d -= L * np.round(d / L)
    f = np.bincount(inv, weights=fn)
    mean = np.column_stack([np.bincount(inv, weights=fn * d[:, k]) for k in range(2)]) / f[:, None]
    return f, np.mod(ref + mean, L)


def protocol_numbers(scene, sim, p: dict) -> dict:
    """The uniaxial protocol of case parameters ``p`` as plain validated numbers, from the insertion
    scene ``scene`` (clumps on demflow's lattice with its seeded orientations) and its built ``sim``.

    Keys: the sphere/plane material pairs of :func:`demflow.engines.base3d.scene3d_numbers` (E*, G*, μ,
    ζ_n, ζ_t), ``template`` (member centres in the principal frame [m], radii [m], mass [kg], principal
    moments [kg m²]), ``bodies`` (centres of mass [m], quaternions w, x, y, z body → world),
    ``protocol`` (box side, trim height, plate speed, stress_max, snapshot levels, record_every,
    settle_max, the at-rest rule), ``dt``, ``gravity``, ``local_damping``, ``skin`` (demflow's neighbour
    margin [m], which LIGGGHTS's deck uses as its ``neighbor`` skin).
    """
    from .base import EngineUnsupported
    from .base3d import _nums, scene3d_numbers

    if scene.clumps is None:
        raise EngineUnsupported(f"scene {scene.name!r} has no clumps: the uniaxial engine decks build clump beds "
                                "(shape='clumps'); the ellipsoid variant runs in demflow only")
    S = scene3d_numbers(scene, sim)
    T = scene.clumps.template
    c = scene.clumps
    pos = np.column_stack([np.asarray(c.x, float), np.asarray(c.y, float), np.asarray(c.z, float)])
    levels = np.linspace(400e3, float(p["stress_max"]), int(p["snapshots"]))
    mats = sorted({m for m in S["spheres"]["material"]})
    if len(mats) != 1:
        raise EngineUnsupported("the uniaxial decks take clumps of one material")
    out = dict(
        name=S["name"], dt=S["dt"], gravity=S["gravity"], local_damping=S["local_damping"], skin=S["skin"],
        materials=S["materials"], sphere_pairs=S["sphere_pairs"], plane_pairs=S["plane_pairs"],
        shear_spring=S["shear_spring"], friction_cap=S["friction_cap"], particle_material=mats[0], plane_material=S["planes"][0]["material"],
        template=dict(centres=_nums(T.centres, "template centres"), radii=_nums(T.radii, "template radii"),
                      mass=_finite(T.mass, "template mass"), moments=_nums(T.moments, "template moments")),
        bodies=dict(pos=_nums(pos, "clump centres"), quat=_nums(np.asarray(c.orientation, float), "clump orientations")),
        protocol=dict(box=_finite(p["box"], "box"), n_insert=int(p["n_insert"]), trim=_finite(p["trim"], "trim"),
                      plate_speed=_finite(p["plate_speed"], "plate speed"),
                      stress_max=_finite(p["stress_max"], "stress_max"), snapshot_levels=_nums(levels, "levels"),
                      record_every=int(p["record_every"]), settle_max=int(p["settle_max"]),
                      settle_check_every=SETTLE_CHECK_EVERY, settle_ke_fraction=SETTLE_KE_FRACTION,
                      plate_gap=PLATE_GAP, plate_z_min=_finite(p.get("plate_z_min", 0.5), "plate_z_min")),
    )
    if len(out["bodies"]["pos"]) != out["protocol"]["n_insert"]:
        raise EngineUnsupported(f"the insertion scene has {len(pos)} clumps, the protocol {p['n_insert']}")
    return out


@dataclass
class UniaxialRun:
    """One engine's run of the uniaxial protocol: the loading curve, the force snapshots, and the
    settled bed's numbers (``meta``: the keys of :data:`OUT_KEYS` plus provenance)."""

    curve: pd.DataFrame
    snapshots: pd.DataFrame
    meta: dict = field(default_factory=dict)

    def snapshot_points(self, wall: str, snapshot: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """(forces, (x, y) contact points) of the particles on ``wall`` in snapshot ``snapshot`` (Fig. 34)."""
        s = self.snapshots[(self.snapshots.wall == wall) & (self.snapshots.snapshot == snapshot)]
        return s.force.to_numpy(), s[["x", "y"]].to_numpy(float)

    def snapshot_forces(self, wall: str) -> list[np.ndarray]:
        """Per-particle normal forces on ``wall`` ("plate" or "floor"), one array per snapshot."""
        s = self.snapshots[self.snapshots.wall == wall]
        return [g.force.to_numpy() for _, g in s.groupby("snapshot", sort=True)]

    def save(self, out) -> Path:
        """curve.parquet, snapshots.parquet and uniaxial.json into ``out`` (each written atomically)."""
        from ..results import save_tables

        return save_tables(out, {"curve": self.curve, "snapshots": self.snapshots}, "uniaxial.json", self.meta, indent=1)

    @classmethod
    def load(cls, out) -> "UniaxialRun":
        """Read what :meth:`save` wrote (a stored reference adds its provenance from meta.json)."""
        out = Path(out)
        meta = json.loads((out / "uniaxial.json").read_text())
        if (out / "meta.json").exists():
            m = json.loads((out / "meta.json").read_text())
            meta.update({k: v for k, v in m.items() if k not in ("results_meta", "files")})
        return cls(curve=pd.read_parquet(out / "curve.parquet"), snapshots=pd.read_parquet(out / "snapshots.parquet"),
                   meta=meta)

    @classmethod
    def from_case(cls, extras: dict, engine: str = "demflow") -> "UniaxialRun":
        """demflow's own run (the extras of :class:`demflow.cases.miyata_uniaxial3d.MiyataUniaxial3D`)."""
        rows = []
        for k, s in enumerate(extras["snapshots"]):
            for wall in ("plate", "floor"):
                xy = s.get(f"{wall}_cxy")  # (runs checkpointed before the contact points were kept: nan)
                xy = np.full((len(s[wall]), 2), np.nan) if xy is None else xy
                rows += [(k, float(s["stress"]), wall, float(f), float(x), float(y)) for f, (x, y) in zip(s[wall], xy)]
        snaps = pd.DataFrame(rows, columns=list(SNAPSHOT_COLUMNS))
        meta = dict(engine=engine, n_particles=int(extras["n_particles"]), weight=float(extras["weight"]),
                    floor_settled=float(extras["floor_settled"]), settle_steps=[int(s) for s in extras["settle_steps"]],
                    dt=float(extras["dt"]), plate_start=float(extras["plate_start"]), area=float(extras["area"]))
        return cls(curve=extras["curve"][list(CURVE_COLUMNS)].copy(), snapshots=snaps, meta=meta)


def read_uniaxial_output(outdir, engine: str, area: float) -> UniaxialRun:
    """An engine deck's output (module docstring), refusing a missing, truncated or non-finite file with
    a message naming the file and what is wrong."""
    outdir = Path(outdir)
    f = outdir / "uniaxial_out.json"
    if not f.exists():
        raise EngineOutputError(f"{engine} wrote no {f.name} in {outdir}: the run stopped before the protocol ended "
                                "(see engine.log)")
    try:
        meta = json.loads(f.read_text())
    except ValueError as e:
        raise EngineOutputError(f"{f} is not valid JSON ({e}): truncated?") from None
    missing = [k for k in OUT_KEYS if k not in meta]
    if missing:
        raise EngineOutputError(f"{f} lacks {missing}: the deck and demflow disagree on the output format")
    for k in ("weight", "floor_settled", "dt", "plate_start", "clump_mass"):
        meta[k] = _finite(meta[k], f"{f.name} {k}")
    tables = {}
    for name, cols in (("curve", CURVE_COLUMNS), ("snapshots", SNAPSHOT_COLUMNS)):
        path = outdir / f"{name}.csv"
        if not path.exists():
            raise EngineOutputError(f"{engine} wrote no {path.name} in {outdir} (see engine.log)")
        df = pd.read_csv(path)
        if tuple(df.columns) != cols:
            raise EngineOutputError(f"{path} has columns {list(df.columns)}, expected {list(cols)}")
        num = df.drop(columns=["wall"]) if name == "snapshots" else df
        if len(df) and not np.all(np.isfinite(num.to_numpy(dtype=float))):
            raise EngineOutputError(f"{path} holds a non-finite number")
        tables[name] = df
    if tables["curve"].empty:
        raise EngineOutputError(f"{outdir / 'curve.csv'} has no rows: the plate never moved")
    if meta["settle_steps"][0] < 0 or meta["settle_steps"][1] < 0:
        raise EngineOutputError(f"{engine}'s bed did not come to rest within the settle budget (settle_steps "
                                f"{meta['settle_steps']}); raise settle_max")
    meta.update(engine=engine, area=float(area))
    return UniaxialRun(curve=tables["curve"], snapshots=tables["snapshots"], meta=meta)
