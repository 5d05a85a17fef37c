"""The frozen schema of the result tables, per version, and the upgrade of older tables on load.

Every engine (demflow, YADE, LIGGGHTS) produces the same tables (:mod:`demflow.results`); this
module says, as data, which columns and dtypes each table has in each schema version.  A version,
once written here, never changes: a new column makes a new version, and :func:`upgrade` turns
tables of every older version into the current one when they are loaded.

Versions
- 1: 2D discs (the stored reference runs in ``reference_runs/`` are v1 and stay so: they are
  hash-checked, never rewritten).
- 2: v1 plus the contact force vector on disc i, ``fx``, ``fy`` [force], on every contact row;
  ``meta`` carries ``schema_version`` and ``dim`` (2).  A v1 table loaded is upgraded in memory
  (``fx``, ``fy`` computed by :func:`contact_force_on_i`, ``dim = 2``) and its meta records the
  version it came from as ``schema_origin``.

Sign convention of the contacts table (demflow.laws.linear, thesis §2.2.4.1, C&S Fig. 3): n is the
unit vector from disc i to j (or to the wall), τ = (n_y, −n_x) its clockwise perpendicular, fn
and fs the total normal and shear force (dashpots included); the force on i is
F_i = −fn·n − fs·τ, the force on j (or the wall) −F_i.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

SCHEMA_VERSION = 2
DIM = 2

_WALL_FORCES = (("step", "int64"), ("time", "float64"), ("wall", "str"), ("fx", "float64"), ("fy", "float64"),
                ("moment", "float64"), ("px", "float64"), ("py", "float64"))
_TRACKED = (("step", "int64"), ("time", "float64"), ("a", "str"), ("b", "str"), ("fn", "float64"),
            ("fs", "float64"))
_ENERGY = (("step", "int64"), ("time", "float64"), ("kinetic", "float64"), ("elastic", "float64"))
_PARTICLES = (("step", "int64"), ("time", "float64"), ("id", "int64"), ("x", "float64"), ("y", "float64"),
              ("theta", "float64"), ("vx", "float64"), ("vy", "float64"), ("omega", "float64"),
              ("radius", "float64"))
_CONTACTS_V1 = (("step", "int64"), ("time", "float64"), ("i", "int64"), ("j", "int64"), ("wall", "str"),
                ("px", "float64"), ("py", "float64"), ("nx", "float64"), ("ny", "float64"), ("fn", "float64"),
                ("fs", "float64"), ("sliding", "bool"), ("overlap", "float64"))
_WALL_GEOMETRY = (("step", "int64"), ("wall", "str"), ("px", "float64"), ("py", "float64"), ("ex", "float64"),
                  ("ey", "float64"), ("h1", "float64"), ("h2", "float64"))
_FLUID_FORCES = (("step", "int64"), ("time", "float64"), ("id", "int64"), ("fx", "float64"), ("fy", "float64"),
                 ("moment", "float64"), ("vx", "float64"), ("vy", "float64"), ("omega", "float64"),
                 ("x", "float64"), ("y", "float64"))
_FLUID_WALLS = (("step", "int64"), ("time", "float64"), ("wall", "str"), ("fx", "float64"), ("fy", "float64"))
_PORE_PRESSURE = (("step", "int64"), ("time", "float64"), ("wall", "str"), ("x", "float64"), ("y", "float64"),
                  ("s", "float64"), ("p", "float64"))

# version -> table -> ((column, dtype), ...).  Frozen: never edit a version that has been released.
# ``wall_geometry`` is stored as wall_geometry.parquet and held in ``Results.walls["geometry"]``.
SCHEMAS: dict[int, dict[str, tuple[tuple[str, str], ...]]] = {
    1: dict(wall_forces=_WALL_FORCES, tracked=_TRACKED, energy=_ENERGY, particles=_PARTICLES,
            contacts=_CONTACTS_V1, wall_geometry=_WALL_GEOMETRY, fluid_forces=_FLUID_FORCES,
            fluid_walls=_FLUID_WALLS, pore_pressure=_PORE_PRESSURE),
    2: dict(wall_forces=_WALL_FORCES, tracked=_TRACKED, energy=_ENERGY, particles=_PARTICLES,
            contacts=_CONTACTS_V1 + (("fx", "float64"), ("fy", "float64")), wall_geometry=_WALL_GEOMETRY,
            fluid_forces=_FLUID_FORCES, fluid_walls=_FLUID_WALLS, pore_pressure=_PORE_PRESSURE),
}


class SchemaError(ValueError):
    """A result table does not match its schema; the message names the table, column and fix."""


def columns(table: str, version: int = SCHEMA_VERSION) -> list[str]:
    """Column names of ``table`` in schema ``version``, in order."""
    return [c for c, _ in _table(table, version)]


def _table(table, version):
    if version not in SCHEMAS:
        raise SchemaError(f"schema_version={version!r} is unknown; known versions are {sorted(SCHEMAS)} "
                          "(a newer demflow wrote these tables: upgrade demflow)")
    if table not in SCHEMAS[version]:
        raise SchemaError(f"table {table!r} is not in result schema v{version}; its tables are "
                          f"{', '.join(SCHEMAS[version])}")
    return SCHEMAS[version][table]


def empty(table: str, version: int = SCHEMA_VERSION) -> pd.DataFrame:
    """An empty table with the columns and dtypes of ``table`` in schema ``version``."""
    return pd.DataFrame({c: pd.Series(dtype=d) for c, d in _table(table, version)})


def conform(df: pd.DataFrame, table: str, version: int = SCHEMA_VERSION) -> pd.DataFrame:
    """``df`` with exactly the schema's columns, in order, cast to the schema's dtypes.

    Casting changes no value of a table that already has its dtypes (the engines' and demflow's
    tables); it gives empty tables (built from column lists) their dtypes.  Raises SchemaError
    naming the missing columns.
    """
    spec = _table(table, version)
    missing = [c for c, _ in spec if c not in df.columns]
    if missing:
        raise SchemaError(f"table {table!r} lacks column(s) {missing} of result schema v{version}; "
                          f"it has {list(df.columns)}. Produce it with demflow.results or upgrade it on load")
    out = df.loc[:, [c for c, _ in spec]]
    return out.astype({c: d for c, d in spec if str(out[c].dtype) != d})


def dtypes(df: pd.DataFrame) -> tuple[tuple[str, str], ...]:
    """((column, dtype), ...) of a table, in the form of :data:`SCHEMAS` (to compare with it)."""
    return tuple((c, str(t)) for c, t in df.dtypes.items())


def contact_force_on_i(nx, ny, fn, fs):
    """Force on disc i of each contact row, (fx, fy) [force]: F_i = −fn·n − fs·τ, τ = (n_y, −n_x).

    n from i to j (or the wall), fn, fs the total normal and shear force [force] (demflow.laws.linear,
    thesis §2.2.4.1: the force on the finder α is −(N + D_N)ε − (S + D_S)τ).
    """
    nx, ny, fn, fs = (np.asarray(a, dtype=np.float64) for a in (nx, ny, fn, fs))
    return -(fn * nx + fs * ny), -(fn * ny - fs * nx)


def with_force_vectors(contacts: pd.DataFrame) -> pd.DataFrame:
    """The contacts table with ``fx``, ``fy`` (force on i, :func:`contact_force_on_i`) added."""
    fx, fy = contact_force_on_i(contacts["nx"], contacts["ny"], contacts["fn"], contacts["fs"])
    return contacts.assign(fx=fx, fy=fy)


def version_of(meta: dict) -> int:
    """Schema version of stored tables from their meta.json (top level, or ``results_meta`` of a
    stored reference run); no version recorded means v1 (tables written before versions existed)."""
    for m in (meta, meta.get("results_meta") or {}):
        if "schema_version" in m:
            return int(m["schema_version"])
    return 1


def upgrade(tables: dict[str, pd.DataFrame], meta: dict) -> tuple[dict[str, pd.DataFrame], dict]:
    """Tables and meta of any known version, upgraded to :data:`SCHEMA_VERSION` (new objects).

    v1 → v2: contacts gain ``fx``, ``fy``; meta gains ``dim = 2``, ``schema_version = 2`` and
    ``schema_origin = 1``.  Every table is then conformed to the current schema.
    """
    origin = version_of(meta)
    _table("contacts", origin)  # raises for an unknown version
    tables = dict(tables)
    if origin < 2 and "contacts" in tables and not {"fx", "fy"} <= set(tables["contacts"].columns):
        tables["contacts"] = with_force_vectors(tables["contacts"])
    meta = dict(meta)
    meta.setdefault("dim", DIM)
    meta["schema_version"] = SCHEMA_VERSION
    if origin != SCHEMA_VERSION:
        meta["schema_origin"] = origin
    return {name: conform(df, name) for name, df in tables.items()}, meta
