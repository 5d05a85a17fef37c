"""miyata-uniaxial-3d in LIGGGHTS (demflow.engines.liggghts_uniaxial3d): a reduced protocol (8 clumps in a
1 × 1 m periodic box, trimmed at 0.55 m, loaded to 400 kPa, two snapshot levels both at 400 kPa) run once for the module (about
half a minute), then the settled bed, the bodies LIGGGHTS integrated, the curve's consistency, and the reader's
refusals of damaged output."""
import math
import shutil
import warnings

import numpy as np
import pytest

pytestmark = [pytest.mark.engines,
              pytest.mark.skipif(shutil.which("liggghts") is None, reason="LIGGGHTS (liggghts) is not on PATH")]

P = dict(box=1.0, n_insert=8, trim=0.55, stress_max=400e3, snapshots=2, settle_max=300000)  # two levels, both 400 kPa


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    from demflow.cases.miyata_uniaxial3d import MiyataUniaxial3D
    from demflow.cases.miyata_uniaxial3d_protocol import insertion_scene
    from demflow.engines.liggghts_uniaxial3d import LiggghtsUniaxial3DEngine

    p = dict(MiyataUniaxial3D.params, **P)
    out = tmp_path_factory.mktemp("lig_uniaxial")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run, info = LiggghtsUniaxial3DEngine(p).run(insertion_scene(p), out, timeout=600)
    return p, run, out


def _reread(p, src, dst):
    from demflow.engines.liggghts_uniaxial3d import LiggghtsUniaxial3DEngine

    shutil.copytree(src, dst)
    for f in ("uniaxial_out.json", "curve.csv", "snapshots.csv"):  # the reader writes these again
        (dst / f).unlink()
    return LiggghtsUniaxial3DEngine(p), dst


def _heavier_first_body(text):
    lines = text.splitlines()
    k = lines.index(next(ln for ln in lines if ln.startswith("ITEM: ENTRIES"))) + 1
    w = lines[k].split()
    w[3] = repr(float(w[3]) * 1.001)
    lines[k] = " ".join(w)
    return "\n".join(lines) + "\n"


def test_the_run_completes_with_every_output_key(ran):
    from demflow.engines.uniaxial3d import OUT_KEYS

    p, run, _ = ran
    m = run.meta
    assert all(k in m for k in OUT_KEYS + ("area",))
    assert m["n_inserted"] == p["n_insert"]
    assert 0 < m["n_particles"] <= m["n_inserted"]
    assert all(s > 0 for s in m["settle_steps"])
    assert m["area"] == p["box"] ** 2


def test_a_liggghts_body_has_the_templates_mass_and_moments(ran):
    """use_density + mass + inertia_tensor: LIGGGHTS takes the template's mass and (diagonal) inertia as given
    (no Monte Carlo); its Jacobi eigen-solution of a diagonal tensor is exact, and the dump prints 17 digits:
    equal to 1e-12."""
    p, run, _ = ran
    from demflow.shapes.clump import MIYATA_AXES, MIYATA_MASS, ClumpTemplate

    T = ClumpTemplate.ellipsoid_like(int(p["K"]), MIYATA_AXES, MIYATA_MASS)
    assert math.isclose(run.meta["clump_mass"], float(T.mass), rel_tol=1e-12)
    np.testing.assert_allclose(run.meta["clump_inertia"], np.asarray(T.moments, float), rtol=1e-12)


def test_the_settled_floor_carries_the_beds_weight(ran):
    _, run, _ = ran
    m = run.meta
    assert m["weight"] == pytest.approx(m["n_particles"] * 191.0 * 9.81, rel=1e-12)
    assert abs(m["floor_settled"] / m["weight"] - 1.0) < 0.005


def test_the_curve_is_consistent(ran):
    from demflow.engines.uniaxial3d import CURVE_COLUMNS, SNAPSHOT_COLUMNS

    p, run, _ = ran
    c = run.curve
    n = run.meta["n_particles"]
    assert tuple(c.columns) == CURVE_COLUMNS and tuple(run.snapshots.columns) == SNAPSHOT_COLUMNS
    xy = run.snapshots[["x", "y"]].to_numpy(float)  # contact points (Fig. 34 maps): inside the periodic box
    assert np.isfinite(xy).all() and (xy >= 0).all() and (xy < p["box"]).all()
    assert np.all(np.diff(c.step) == p["record_every"]) and c.step.iloc[0] == p["record_every"]
    dz = p["plate_speed"] * run.meta["dt"] * p["record_every"]
    np.testing.assert_allclose(-np.diff(c.plate_z), dz, rtol=1e-9)
    assert c.plate_z.iloc[0] == pytest.approx(run.meta["plate_start"] - dz, rel=1e-12)
    for col in ("plate_contacts", "floor_contacts"):
        assert c[col].between(0, n).all()
    assert (c.plate_contacts[c.plate_stress > 0] >= 1).all() and (c.plate_contacts[c.plate_stress == 0] == 0).all()
    first = c.index[c.plate_stress > 0][0]
    np.testing.assert_allclose(c.settlement[first:], c.plate_z[first] - c.plate_z[first:], atol=1e-12)
    assert (c.settlement[:first] == 0).all()
    assert c.plate_stress.iloc[-1] >= p["stress_max"] and (c.plate_stress.iloc[:-1] < p["stress_max"]).all()
    # the snapshot at 400 kPa: one force per touching particle, summing to the plate force (per-contact forces
    # come from compute wall/gran/local, the plate force from the mesh: the same contacts)
    # both levels are reached at the same record: snapshots 0 and 1 hold the same forces
    s = run.snapshots
    assert sorted(s.snapshot.unique()) == [0, 1] and run.meta["n_snapshots"] == 2
    row = c[c.plate_stress >= 400e3].iloc[0]
    for k in (0, 1):
        for wall, col, stress in (("plate", "plate_contacts", row.plate_stress),
                                  ("floor", "floor_contacts", row.floor_stress)):
            f = s[(s.wall == wall) & (s.snapshot == k)].force
            assert len(f) == row[col] and (f > 0).all()
            assert f.sum() == pytest.approx(stress * run.meta["area"], rel=0.02)


def test_the_reader_refuses_damaged_output(ran, tmp_path):
    from demflow.engines.base import EngineOutputError

    p, run, out = ran
    eng, d = _reread(p, out, tmp_path / "ok")
    again = eng.read(None, None, d)  # an undamaged copy reads back the same run
    assert again.curve.equals(run.curve)
    damage = {
        "walls.txt": lambda t: t[: len(t) // 2],  # truncated mid-block
        "curve_raw.txt": lambda t: t[: len(t) // 2],  # records cut: loading no longer reaches its stop
        "log2.liggghts": lambda t: t.replace("DEMFLOW-COMPLETE", ""),  # no completion mark
        "bodies2.txt": _heavier_first_body,  # one body of another mass
        "plate_end_*.stl": lambda t: t.replace("vertex 0 0 ", "vertex 0 0 1", 1),  # the plate not where its steps put it
    }
    for name, f in damage.items():
        eng, d = _reread(p, out, tmp_path / name.replace(".", "_").replace("*", "x"))
        path = next(d.glob(name))
        path.write_text(f(path.read_text()))
        with pytest.raises(EngineOutputError, match=name.split(".")[0]):
            eng.read(None, None, d)
    for name in ("walls.txt", "atoms2.txt", "pass1.json", "plate_end_*.stl"):
        eng, d = _reread(p, out, tmp_path / f"missing_{name.replace('.', '_').replace('*', 'x')}")
        next(d.glob(name)).unlink()
        with pytest.raises(EngineOutputError, match=name.split(".")[0]):
            eng.read(None, None, d)


def test_the_reader_refuses_a_wrong_atom_to_body_map(ran, tmp_path):
    """Two atoms of different bodies swap bodies in atoms2.txt: their bodies' members no longer sit at the
    template's distances."""
    p, _, out = ran
    from demflow.engines.base import EngineOutputError

    eng, d = _reread(p, out, tmp_path / "swapped")
    lines = (d / "atoms2.txt").read_text().splitlines()
    k = lines.index(next(ln for ln in lines if ln.startswith("ITEM: ATOMS"))) + 1
    a, b = lines[k].split(), lines[k + 8].split()  # atom 1 (body 1) and atom 9 (body 2)
    assert a[1] != b[1]
    a[1], b[1] = b[1], a[1]
    lines[k], lines[k + 8] = " ".join(a), " ".join(b)
    (d / "atoms2.txt").write_text("\n".join(lines) + "\n")
    with pytest.raises(EngineOutputError, match="atoms2"):
        eng.read(None, None, d)
