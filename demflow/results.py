"""Result tables: the one format every engine (demflow, YADE, LIGGGHTS) produces.

Tables (pandas DataFrames, long format, saved as Parquet):

- ``wall_forces``: step, time, wall, fx, fy, moment, px, py — force of the discs on each
  wall [force], its moment about the wall point P [force·length], P's position [length]
- ``tracked``: step, time, a, b, fn, fs — total normal and shear force of tracked pairs
- ``energy``: step, time, kinetic, elastic [force·length]
- ``particles``: step, time, id, x, y, theta, vx, vy, omega, radius (at snapshots)
- ``contacts``: step, time, i, j, wall, px, py, nx, ny, fn, fs, sliding, overlap, fx, fy
  (at snapshots; j = -1 and wall = name for disc-wall contacts; n from i to j/the wall; fn, fs
  the total normal and shear force [force]; fx, fy the force on i, −fn·n − fs·τ with
  τ = (n_y, −n_x) [force], schema v2)

Saturated scenes (thesis §3.4) add, at every recorded fluid solve:

- ``fluid_forces``: step, time, id, fx, fy, moment, vx, vy, omega — the force and moment of the
  fluid on each disc (BEM, without buoyancy) [force], [force·length], and the disc velocity the
  solve prescribed (v_{i−1/2} at step i: the half-step lag of thesis §3.4) and its position x, y
- ``fluid_walls``: step, time, wall, fx, fy — the force of the fluid on each boundary wall
- ``pore_pressure``: step, time, wall, x, y, s, p — pressure at the BEM nodes along each wall
  (s: distance from the wall's first corner) [force/length²]

``meta`` holds ``schema_version`` (2) and ``dim`` (2).  Columns and dtypes of every table, per
schema version, are frozen in :mod:`demflow.schema`; :meth:`Results.load` upgrades older tables
(the stored v1 reference runs) to the current version.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from . import schema
from .atomic import write_atomic

TABLES = ("wall_forces", "tracked", "energy", "particles", "contacts")
FLUID_TABLES = ("fluid_forces", "fluid_walls", "pore_pressure")


def save_tables(out, tables: dict, meta_name: str, meta: dict, indent: int = 2) -> Path:
    """Each DataFrame of ``tables`` as ``<name>.parquet`` and ``meta`` as JSON ``meta_name`` into directory
    ``out``, every file written atomically (the 3D trajectory and uniaxial run objects)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for name, df in tables.items():
        write_atomic(out / f"{name}.parquet", lambda p, df=df: df.to_parquet(p, index=False))
    write_atomic(out / meta_name, lambda p: Path(p).write_text(json.dumps(meta, indent=indent, default=str)))
    return out


@dataclass
class Results:
    """The tables of one run plus its metadata (engine, scene, dt, ...)."""

    wall_forces: pd.DataFrame
    tracked: pd.DataFrame
    energy: pd.DataFrame
    particles: pd.DataFrame
    contacts: pd.DataFrame
    meta: dict = field(default_factory=dict)
    walls: dict = field(default_factory=dict)  # wall name -> geometry at each snapshot
    fluid_forces: pd.DataFrame = field(default_factory=lambda: schema.empty("fluid_forces"))
    fluid_walls: pd.DataFrame = field(default_factory=lambda: schema.empty("fluid_walls"))
    pore_pressure: pd.DataFrame = field(default_factory=lambda: schema.empty("pore_pressure"))

    @classmethod
    def from_simulation(cls, sim) -> "Results":
        """The tables of a run simulation (schema v2), from its public ``records``, ``snapshots``
        and attributes only."""
        dt = sim.dt
        wf, tr, en = [], [], []
        for steps, wall, wpos, track, energy in sim.records:
            t = steps * dt
            for w, name in enumerate(sim.wall_names):
                wf.append(pd.DataFrame(dict(step=steps, time=t, wall=name, fx=wall[:, w, 0], fy=wall[:, w, 1],
                                            moment=wall[:, w, 2], px=wpos[:, w, 0], py=wpos[:, w, 1])))
            for k, (a, b) in enumerate(sim.track):
                tr.append(pd.DataFrame(dict(step=steps, time=t, a=_body_name(sim, a), b=_body_name(sim, b),
                                            fn=track[:, k, 0], fs=track[:, k, 1])))
            en.append(pd.DataFrame(dict(step=steps, time=t, kinetic=energy[:, 0], elastic=energy[:, 1])))
        parts, cons, walls = [], [], []
        for s in sim.snapshots:
            p = s["particles"]
            parts.append(pd.DataFrame(dict(step=s["step"], time=s["time"], id=np.arange(sim.n), **p)))
            c = s["contacts"]
            is_wall = c["other"] >= sim.n
            wall_name = np.array([sim.wall_names[o - sim.n] if o >= sim.n else "" for o in c["other"]], dtype=object)
            cons.append(pd.DataFrame(dict(
                step=s["step"], time=s["time"], i=c["finder"], j=np.where(is_wall, -1, c["other"]),
                wall=wall_name, px=c["px"], py=c["py"], nx=c["nx"], ny=c["ny"], fn=c["fn"], fs=c["fs"],
                sliding=c["sliding"], overlap=c["overlap"])))
            w = s["walls"]
            walls.append(pd.DataFrame(dict(step=s["step"], wall=sim.wall_names, **w)))
        from .manifest import physics_manifest

        meta = dict(engine="demflow", scene=sim.scene.name, dt=dt, dt_crit=sim.dt_crit, steps=sim.step,
                    n_discs=sim.n, walls=sim.wall_names, rebuilds=sim.rebuilds, physics=physics_manifest(sim), dem_s=float(sim.dem_s))
        fluid = {}
        if sim.fluid is not None:
            fc = sim.fluid
            ff, fw, pp = [], [], []
            for step, out, wfl, vel in fc.records:
                ff.append(pd.DataFrame(dict(step=step, time=step * dt, id=np.arange(sim.n), fx=out[:, 0],
                                            fy=out[:, 1], moment=out[:, 2], vx=vel[:, 0], vy=vel[:, 1],
                                            omega=vel[:, 2], x=vel[:, 3], y=vel[:, 4])))
                fw.append(pd.DataFrame(dict(step=step, time=step * dt, wall=fc.names, fx=wfl[:, 0], fy=wfl[:, 1])))
            for step, name, x, y, s_, p in fc.pressure:
                pp.append(pd.DataFrame(dict(step=step, time=step * dt, wall=name, x=x, y=y, s=s_, p=p)))
            fluid = dict(fluid_forces=concat(ff, "fluid_forces"), fluid_walls=concat(fw, "fluid_walls"),
                         pore_pressure=concat(pp, "pore_pressure"))
            ks = [int(k) for _, k in fc.strides] or [0]
            meta.update(fluid_solves=fc.solves, bem_seconds=fc.bem_s, dem_seconds=sim.dem_s,
                        fluid_stride_min=min(ks), fluid_stride_max=max(ks))
        return versioned(cls(wall_forces=concat(wf, "wall_forces"), tracked=concat(tr, "tracked"),
                             energy=concat(en, "energy"), particles=concat(parts, "particles"),
                             contacts=concat(cons, "contacts"), meta=meta,
                             walls={"geometry": concat(walls, "wall_geometry")}, **fluid))

    def wall(self, name: str) -> pd.DataFrame:
        """Force history of one wall."""
        return self.wall_forces[self.wall_forces.wall == name].reset_index(drop=True)

    def pair(self, a, b) -> pd.DataFrame:
        """Force history of one tracked pair (names as in the table: '3', 'wall:floor')."""
        a, b = str(a), str(b)
        t = self.tracked
        sel = ((t.a == a) & (t.b == b)) | ((t.a == b) & (t.b == a))
        return t[sel].reset_index(drop=True)

    def save(self, out: str | os.PathLike) -> Path:
        """Write every table as Parquet plus meta.json into directory ``out`` (each file atomically).  The optional
        tables (a saturated run's fluid tables, the walls' geometry) that this result does not have are removed from
        ``out``, so that saving over an earlier result and loading gives this result, not a mix of the two."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        names = TABLES + tuple(t for t in FLUID_TABLES if len(getattr(self, t)))
        for name in names:
            df = getattr(self, name)
            write_atomic(out / f"{name}.parquet", lambda p, df=df: df.to_parquet(p, index=False))
        geo = self.walls.get("geometry")
        if geo is not None:
            write_atomic(out / "wall_geometry.parquet", lambda p: geo.to_parquet(p, index=False))
        stale = [t for t in FLUID_TABLES if t not in names] + ([] if geo is not None else ["wall_geometry"])
        for name in stale:
            (out / f"{name}.parquet").unlink(missing_ok=True)
        write_atomic(out / "meta.json", lambda p: Path(p).write_text(json.dumps(self.meta, indent=2, default=str)))
        return out

    @classmethod
    def load(cls, out: str | os.PathLike) -> "Results":
        """Read tables written by :meth:`save` (or a stored reference run), upgraded to the current
        schema (:func:`demflow.schema.upgrade`: v1 contacts gain fx, fy; meta records
        ``schema_origin``).  The files are not changed."""
        out = Path(out)
        tables = {name: pd.read_parquet(out / f"{name}.parquet") for name in TABLES}
        tables.update({name: pd.read_parquet(out / f"{name}.parquet") for name in FLUID_TABLES
                       if (out / f"{name}.parquet").exists()})
        if (out / "wall_geometry.parquet").exists():
            tables["wall_geometry"] = pd.read_parquet(out / "wall_geometry.parquet")
        tables, meta = schema.upgrade(tables, json.loads((out / "meta.json").read_text()))
        geometry = tables.pop("wall_geometry", None)
        return cls(**tables, meta=meta, walls={} if geometry is None else {"geometry": geometry})


def _body_name(sim, b):
    return f"wall:{sim.wall_names[b - sim.n]}" if b >= sim.n else str(b)


def concat(frames: list, table: str) -> pd.DataFrame:
    """The frames of one table joined (or the empty table), with the current schema's columns and
    dtypes; contacts gain their force vectors fx, fy (:func:`demflow.schema.with_force_vectors`)."""
    df = pd.concat(frames, ignore_index=True) if frames else schema.empty(table)
    if table == "contacts":
        df = schema.with_force_vectors(df)
    return schema.conform(df, table)


def versioned(res: Results) -> Results:
    """``res`` with ``schema_version`` and ``dim`` in its meta (tables built by this version)."""
    res.meta.update(schema_version=schema.SCHEMA_VERSION, dim=schema.DIM)
    return res
