"""Result tables v2 (demflow.schema): frozen schema, v1 references upgraded on load, round trip,
and the sign of the contact force vectors."""
import json

import numpy as np
import pandas as pd
import pytest

from demflow import Discs, GlobalDamping, LinearLaw, Material, Outputs, Results, Scene, Wall, build, schema
from demflow.cases.cs_nine_disc_engines import CASE
from demflow.engines import reference

G = 9.81


def _tables(res):
    out = {t: getattr(res, t) for t in ("wall_forces", "tracked", "energy", "particles", "contacts", "fluid_forces",
                                        "fluid_walls", "pore_pressure")}
    out["wall_geometry"] = res.walls["geometry"]
    return out


def _assert_schema(res, version=schema.SCHEMA_VERSION):
    for name, df in _tables(res).items():
        assert schema.dtypes(df) == schema.SCHEMAS[version][name], name


def test_frozen_v1_schema_is_what_the_stored_references_hold():
    """v1 as frozen in demflow.schema equals the files of a stored (v1) reference, read raw."""
    path = reference.location(CASE, "undamped", "liggghts")  # (the YADE ones were re-made in v2 on 2026-11-25)
    for name in ("wall_forces", "tracked", "energy", "particles", "contacts", "wall_geometry"):
        raw = pd.read_parquet(path / f"{name}.parquet")
        assert schema.dtypes(raw) == schema.SCHEMAS[1][name], name


@pytest.mark.parametrize("case, variant, engine", [(CASE, "undamped", "liggghts"), ("cs-photoelastic", "seed1", "liggghts")])
def test_v1_reference_loads_verified_and_gains_force_vectors(case, variant, engine):
    before = {p.name: p.read_bytes() for p in reference.location(case, variant, engine).iterdir()}
    res = reference.load(case, variant, engine)  # verifies every sha256 first
    assert res.meta["schema_version"] == 2 and res.meta["schema_origin"] == 1 and res.meta["dim"] == 2
    _assert_schema(res)
    c = res.contacts
    assert len(c) > 0
    fx, fy = schema.contact_force_on_i(c.nx, c.ny, c.fn, c.fs)
    assert np.array_equal(c.fx.to_numpy(), fx) and np.array_equal(c.fy.to_numpy(), fy)
    # |F| = sqrt(fn² + fs²): n and τ are orthonormal
    assert np.allclose(np.hypot(c.fx, c.fy), np.hypot(c.fn, c.fs), rtol=1e-9)
    after = {p.name: p.read_bytes() for p in reference.location(case, variant, engine).iterdir()}
    assert after == before  # loading never rewrites a stored reference
    reference.verify(reference.location(case, variant, engine))


def _disc_on_floor(n_discs=1, steps=4000):
    """n discs of radius 1 stacked on a floor (y = 0) under gravity, damped to rest."""
    law = LinearLaw(kn=1e5, ks=5e4, cn=20.0, friction=0.5)
    return Scene(name="rest", discs=Discs(x=[0.0] * n_discs,
                                          y=[1.0 + 2.0 * k for k in range(n_discs)], radius=[1.0] * n_discs,
                                          material="g"),
                 materials={"g": Material(density=1.0), "wall": Material()},
                 laws={("g", "g"): law, ("g", "wall"): law},
                 walls=[Wall("floor", (0.0, 0.0), (1.0, 0.0), -5.0, 5.0, "wall")], gravity=(0.0, -G),
                 damping=GlobalDamping(alpha=2.0), n_steps=steps, outputs=Outputs(every=100, snapshots=(steps,)))


def test_force_on_a_disc_resting_on_a_floor_points_up():
    sim = build(_disc_on_floor()).run()
    c = sim.results().contacts
    row = c[c.wall == "floor"]
    assert len(row) == 1 and int(row.i.iloc[0]) == 0 and int(row.j.iloc[0]) == -1
    weight = sim.mass[0] * G
    assert row.fy.iloc[0] == pytest.approx(weight, rel=1e-3)  # force of the floor on the disc: up
    assert abs(row.fx.iloc[0]) < 1e-6 * weight


def test_force_vectors_balance_weight_of_every_disc_in_a_resting_stack():
    """Each disc of a resting column: Σ (force on i over its rows as i) − Σ (over its rows as j)
    equals its weight upwards (disc-disc rows included: the force on j is −(fx, fy))."""
    sim = build(_disc_on_floor(3)).run()
    c = sim.results().contacts
    for k in range(3):
        f = (c.loc[c.i == k, ["fx", "fy"]].sum().to_numpy() - c.loc[c.j == k, ["fx", "fy"]].sum().to_numpy())
        assert f[0] == pytest.approx(0.0, abs=1e-6 * sim.mass[k] * G)
        assert f[1] == pytest.approx(sim.mass[k] * G, rel=1e-3)


def test_v2_round_trip(tmp_path):
    sim = build(_disc_on_floor(3, steps=500)).run()
    res = sim.results()
    assert res.meta["schema_version"] == 2 and res.meta["dim"] == 2 and "schema_origin" not in res.meta
    _assert_schema(res)
    res.save(tmp_path / "out")
    assert json.loads((tmp_path / "out" / "meta.json").read_text())["schema_version"] == 2
    back = Results.load(tmp_path / "out")
    _assert_schema(back)
    assert back.meta == json.loads(json.dumps(res.meta, default=str))
    for name, df in _tables(res).items():
        if len(df) or name in ("wall_forces", "contacts"):
            pd.testing.assert_frame_equal(_tables(back)[name], df, check_exact=True, obj=name)


def test_saving_over_an_earlier_result_leaves_no_table_of_it(tmp_path):
    """A dry result saved where a saturated one (fluid tables) was loads as the dry one: the optional tables it does
    not have are removed (they were left there and loaded with it before)."""
    def result(wet):
        r = Results(**{t: schema.empty(t) for t in ("wall_forces", "tracked", "energy", "particles", "contacts")},
                    meta={"scene": "a"})
        if wet:
            ff = schema.empty("fluid_forces")
            r.fluid_forces = schema.conform(pd.concat([ff, pd.DataFrame({c: [1] for c in ff.columns})],
                                                      ignore_index=True), "fluid_forces")
            r.walls = {"geometry": schema.conform(pd.DataFrame({c: [0] for c in schema.empty("wall_geometry").columns}),
                                                  "wall_geometry")}
        return r

    result(True).save(tmp_path)
    assert len(Results.load(tmp_path).fluid_forces) == 1 and "geometry" in Results.load(tmp_path).walls
    result(False).save(tmp_path)
    back = Results.load(tmp_path)
    assert len(back.fluid_forces) == 0
    assert back.walls == {}
    assert not (tmp_path / "fluid_forces.parquet").exists() and not (tmp_path / "wall_geometry.parquet").exists()


def test_v1_tables_written_then_loaded_are_upgraded(tmp_path):
    """A v1 directory (no schema_version, no fx/fy) loads as v2 with schema_origin 1."""
    res = build(_disc_on_floor(2, steps=500)).run().results()
    res.contacts = res.contacts.drop(columns=["fx", "fy"])
    res.meta = {k: v for k, v in res.meta.items() if k not in ("schema_version", "dim")}
    res.save(tmp_path / "v1")
    back = Results.load(tmp_path / "v1")
    assert back.meta["schema_origin"] == 1 and back.meta["schema_version"] == 2 and back.meta["dim"] == 2
    _assert_schema(back)
    c = back.contacts
    assert len(c) > 0 and np.array_equal(np.c_[c.fx, c.fy], np.c_[schema.contact_force_on_i(c.nx, c.ny, c.fn, c.fs)])


def test_unknown_schema_version_is_refused(tmp_path):
    res = build(_disc_on_floor(1, steps=10)).run().results()
    res.meta["schema_version"] = 99
    res.save(tmp_path / "new")
    with pytest.raises(schema.SchemaError, match="schema_version=99.*upgrade demflow"):
        Results.load(tmp_path / "new")


def test_engine_reader_tables_are_v2():
    """results_from_records (where the YADE and LIGGGHTS readers end) builds v2 tables."""
    from demflow.engines.tables import results_from_records

    sim = build(_disc_on_floor(1, steps=10))
    steps = np.array([0, 5])
    res = results_from_records(
        sim, engine="yade", steps=steps, wall=np.zeros((2, 1, 3)), wallpos=np.zeros((2, 1, 2)),
        track=np.zeros((2, 0, 2)), kinetic=np.zeros(2),
        snapshots=[dict(step=5, particles=[[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]],
                        contacts=[[0, 1, 0.0, 0.0, 0.0, -1.0, 3.0, 0.5, 1e-4]], walls=[[0.0, 0.0, 1.0, 0.0]])])
    assert res.meta["schema_version"] == 2 and res.meta["dim"] == 2
    _assert_schema(res)
    c = res.contacts.iloc[0]  # n = (0, -1) from the disc to the floor: the floor pushes up, fs along -τ = (1, 0)
    assert (c.fx, c.fy) == (0.5, 3.0)
