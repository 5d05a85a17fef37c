"""The user's path (issue 18 item 6): VTK output read back by an independent reader (meshio),
progress bars, and a help text for every command and option."""
from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import golden3d_scenes as g3
import golden_scenes as g2
from demflow import build, progress
from demflow.cli import build_parser
from demflow.results import Results
from demflow.vtk import write_results_vtk, write_simulation3d_vtk

meshio = pytest.importorskip("meshio")


@pytest.fixture(scope="module")
def run2d():
    sim = build(g2.frictional_box())
    sim.run(1500)
    return sim, Results.from_simulation(sim)


def test_2d_snapshots_read_back_in_vtk_with_the_tables_values(run2d, tmp_path):
    sim, res = run2d
    files = write_results_vtk(res, tmp_path, prefix="box")
    assert (tmp_path / "box.pvd").exists() and len(files) == 3  # one snapshot (1500): particles, contacts, pvd
    assert not [f for f in tmp_path.iterdir() if f.name.startswith(".") or f.suffix == ".tmp"]  # no leftovers
    p = res.particles[res.particles.step == 1500].sort_values("id")
    m = meshio.read(tmp_path / "box_particles_000001500.vtu")
    np.testing.assert_array_equal(m.points[:, :2], np.c_[p.x, p.y])
    np.testing.assert_array_equal(m.point_data["radius"].ravel(), p.radius)
    np.testing.assert_array_equal(m.point_data["velocity"][:, :2], np.c_[p.vx, p.vy])
    c = res.contacts[res.contacts.step == 1500]
    lines = meshio.read(tmp_path / "box_contacts_000001500.vtu")
    assert lines.cells[0].type == "line" and len(lines.cells[0].data) == len(c) > 0
    np.testing.assert_array_equal(lines.cell_data["fn"][0].ravel(), c.fn)
    ends = lines.points[lines.cells[0].data]  # (contacts, 2, 3)
    xy = np.c_[p.x, p.y]
    np.testing.assert_allclose(ends[:, 0, :2], xy[c.i.to_numpy()], rtol=0, atol=0)  # starts at centre i
    disc = c.j.to_numpy() >= 0  # a disc-disc line ends at j's centre, up to the overlap (no periodic axis here)
    gap = np.linalg.norm(ends[disc, 1, :2] - xy[c.j.to_numpy()[disc]], axis=1)
    assert np.all(gap <= c.overlap.to_numpy()[disc] + 1e-12), gap.max()
    wall = ~disc  # a wall contact ends at the contact point
    np.testing.assert_allclose(ends[wall, 1, :2], np.c_[c.px, c.py][wall], rtol=1e-12, atol=1e-12)


def test_3d_state_reads_back_in_vtk(tmp_path):
    sim = build(g3.settling_bed())
    sim.run(1500)
    write_simulation3d_vtk(sim, tmp_path)
    m = meshio.read(tmp_path / "run_particles_000001500.vtu")
    np.testing.assert_array_equal(m.points, sim.spheres.pos)
    np.testing.assert_array_equal(m.point_data["radius"].ravel(), sim.spheres.r)
    lines = meshio.read(tmp_path / "run_contacts_000001500.vtu")
    on = sim.pairs.ovl > 0
    assert len(lines.cells[0].data) == on.sum() > 0
    np.testing.assert_array_equal(lines.cell_data["fn"][0].ravel(), sim.pairs.fn[on])
    ends = lines.points[lines.cells[0].data]
    length = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    # sphere-sphere: centre to (image of) centre = r_i + r_j - overlap; walls: centre to surface = r_i - overlap
    i, j = sim.pairs.i[on], sim.pairs.j[on]
    rj = np.where(j < sim.n, sim.spheres.r[np.minimum(j, sim.n - 1)], 0.0)
    # (the overlap is the last force evaluation's, one position update ago: each end moved at most |v| dt)
    moved = 2 * np.abs(sim.spheres.vel).max() * np.sqrt(3) * sim.dt
    np.testing.assert_allclose(length, sim.spheres.r[i] + rj - sim.pairs.ovl[on], rtol=0, atol=moved)
    assert moved < 0.05 * sim.spheres.r.min()  # small enough to catch a line to the wrong sphere or a wrong image


def _assert_empty_grid(path):
    """``path`` is a VTK XML unstructured grid with no point and no cell and the contact arrays (read with the
    standard library: meshio 5 cannot read a grid without cells; ParaView and VTK can)."""
    import xml.etree.ElementTree as ET

    root = ET.parse(path).getroot()
    assert root.get("type") == "UnstructuredGrid"
    piece = root.find("UnstructuredGrid/Piece")
    assert piece.get("NumberOfPoints") == "0" and piece.get("NumberOfCells") == "0"
    assert [a.get("Name") for a in piece.find("CellData")] == ["fn", "fs", "overlap", "sliding"]
    assert all(not (a.text or "").strip() for a in piece.iter("DataArray"))


def test_a_snapshot_without_contacts_writes_an_empty_contact_file(tmp_path):
    """A snapshot where nothing touches (a disc in the air, spheres apart) writes an empty contact grid with the same
    cell arrays beside the particles (pyevtk refuses an empty piece: it raised a bare AssertionError before)."""
    import demflow as df

    scene = df.Scene(name="one-disc", discs=df.Discs(x=[0.0], y=[1.5], radius=[1.0], material="disc"),
                     materials={"disc": df.Material(density=2400.0), "plate": df.Material()},
                     laws={("disc", "plate"): df.LinearLaw(kn=1e7, cn=1e5)},
                     walls=[df.Wall("plate", point=(0, 0), direction=(1, 0), h1=-5, h2=5, material="plate")],
                     damping=df.GlobalDamping(C=0.0), gravity=(0, -10), dt=1e-3, n_steps=10,
                     outputs=df.Outputs(every=1, snapshots=(0,)))
    res = build(scene).run().results()
    assert len(res.contacts[res.contacts.step == 0]) == 0
    files = write_results_vtk(res, tmp_path / "2d")
    assert len(files) == 3
    _assert_empty_grid(tmp_path / "2d" / "run_contacts_000000000.vtu")
    assert len(meshio.read(tmp_path / "2d" / "run_particles_000000000.vtu").points) == 1
    sim = build(df.Scene3D(name="apart", spheres=df.Spheres(x=[0.0, 1.0], y=[0.0, 0.0], z=[1.0, 1.0], radius=[0.1, 0.1],
                                                            material="rock"),
                           materials={"rock": df.Material(density=2650.0, young=7e8, poisson=0.2)},
                           laws={("rock", "rock"): df.HertzMindlinLaw(friction=0.4)}, gravity=(0.0, 0.0, 0.0),
                           outputs=df.Outputs3D(every=0)))
    sim.run(5)
    write_simulation3d_vtk(sim, tmp_path / "3d")
    _assert_empty_grid(tmp_path / "3d" / "run_contacts_000000005.vtu")
    assert not [f for f in (tmp_path / "3d").iterdir() if f.name.startswith(".") or f.suffix == ".tmp"]


def test_a_run_shows_a_progress_bar_when_asked_and_none_in_a_pipe(capsys, monkeypatch):
    monkeypatch.setattr(progress, "DELAY_S", 0.0)
    sim = build(dataclasses.replace(g2.frictional_box(), n_steps=300))
    sim.run(300, progress=True)
    err = capsys.readouterr().err
    assert "golden-box" in err and "/300 [" in err and sim.step == 300, err
    sim.run(100)  # default: tqdm's rule, off when standard error is not a terminal (pytest captures it)
    assert capsys.readouterr().err == ""
    progress.enable(False)
    try:
        sim.run(100, progress=None)
        assert capsys.readouterr().err == ""
    finally:
        progress.enable(None)


def test_every_command_and_option_has_a_help_text():
    ap = build_parser()
    subs = next(a for a in ap._actions if isinstance(a, argparse._SubParsersAction))
    assert set(subs.choices) == {"cases", "run", "validate", "reference", "compare", "sweep", "tradeoff"}
    helps = {c.dest: c.help for c in subs._choices_actions}
    for name, parser in subs.choices.items():
        assert helps.get(name), f"command {name} has no help line"
        assert parser.description and len(parser.description) > 40, f"command {name} has no description"
        for a in parser._actions:
            if not isinstance(a, argparse._HelpAction):
                assert a.help and len(a.help) > 10, f"demflow {name}: {a.option_strings or a.dest} has no help"
    for a in ap._actions:
        if not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction)):
            assert a.help, a


@pytest.mark.parametrize("cmd", [[], ["run"], ["validate"], ["reference"], ["compare"], ["cases"], ["sweep"], ["tradeoff"]])
def test_help_runs_from_the_command_line(cmd):
    out = subprocess.run([sys.executable, "-m", "demflow.cli", *cmd, "--help"], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0 and "usage: demflow" in out.stdout, out.stderr


def test_run_of_a_case_without_result_tables_creates_its_output_folder(tmp_path):
    """`demflow run` draws the figures of a case whose run keeps no result tables (ch3-impulse-chain: records
    only) into a folder that does not exist yet (it used to fail there, after the whole run)."""
    from demflow.cli import main

    out = tmp_path / "new" / "chain"
    assert main(["--no-progress", "run", "ch3-impulse-chain", "--out", str(out)]) == 0
    assert any(out.glob("*.png"))
