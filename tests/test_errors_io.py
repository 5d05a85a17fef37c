"""Bad input is refused with a clear message; outputs, checkpoints and blow-ups behave."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from demflow import (BlowUpError, Discs, LinearLaw, Material, Outputs, Results, Scene, SceneError, Wall, build)

from helpers import box_walls, gas_scene, random_packing


def two(**kw):
    base = dict(name="two", discs=Discs(x=[0.0, 3.0], y=[0.0, 0.0], radius=[1.0, 1.0], material="g"),
                materials={"g": Material(density=1.0)}, laws={("g", "g"): LinearLaw(kn=1e5)})
    base.update(kw)
    return Scene(**base)


@pytest.mark.parametrize("scene, words", [
    (two(discs=Discs(x=[0.0, 3.0], y=[0, 0], radius=[1.0, -1.0], material="g")), ["disc 1", "radius -1.0", "> 0"]),
    (two(discs=Discs(x=[0.0, 3.0], y=[0, 0], radius=[1.0, 1.0], material="g", mass=[1.0, 0.0])), ["disc 1", "mass 0.0"]),
    (two(discs=Discs(x=[0.0, 1.5], y=[0, 0], radius=[1.0, 1.0], material="g")), ["discs 0 and 1", "overlap by 0.5", "overlap_tolerance"]),
    (two(dt=1.0), ["dt=1", "critical time step", "allow_supercritical"]),
    (two(laws={}), ["no contact law", "('g', 'g')", "LinearLaw"]),
    (two(discs=Discs(x=[0.0, 3.0], y=[0, 0], radius=[1.0, 1.0], material="sand")), ["material 'sand'", "scene.materials"]),
    (two(name='x"; import os'), ["is not an identifier"]),
    (two(laws={("g", "g"): LinearLaw(kn=1e5, friction=-1.0)}), ["friction=-1.0", ">= 0"]),
])
def test_bad_input_refused_with_message(scene, words):
    with pytest.raises(SceneError) as e:
        build(scene)
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_supercritical_dt_allowed_when_asked():
    sim = build(two(dt=1.0, allow_supercritical=True))
    assert sim.dt == 1.0 and sim.dt > sim.dt_crit


def test_default_dt_is_a_tenth_of_critical():
    sim = build(two())
    assert sim.dt == pytest.approx(0.1 * 2 * np.sqrt(np.pi / 1e5))


def test_frictionless_scene_keeps_no_shear_history():
    assert build(two()).hist.shape[1] == 1
    assert build(two(laws={("g", "g"): LinearLaw(kn=1e5, ks=1e5, friction=0.5)})).hist.shape[1] == 2


def test_blowup_detected_and_last_good_state_saved(tmp_path, monkeypatch):
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))
    # a disc held between two walls, stepped at 4.5× the critical Δt: the explicit scheme is unstable
    sc = two(discs=Discs(x=[0.0], y=[0.0], radius=[1.0], material="g", velocity=[[1.0, 0.0]]),
             materials={"g": Material(density=1.0), "w": Material()}, laws={("g", "w"): LinearLaw(kn=1e5)},
             walls=[Wall("left", (-1.0, 0.0), (0.0, 1.0), -2.0, 2.0, "w"),
                    Wall("right", (1.0, 0.0), (0.0, 1.0), -2.0, 2.0, "w")],
             dt=0.05, allow_supercritical=True, n_steps=1000)
    with pytest.raises(BlowUpError) as e:
        build(sc).run()
    assert "blew up" in str(e.value) and Path(e.value.path).exists()
    z = np.load(e.value.path)
    assert np.all(np.isfinite(z["x"]))


def _frictional_box(n_steps):
    x, y, r, box = random_packing(40, 7, box=14.0)
    rng = np.random.default_rng(8)
    sc = gas_scene(x, y, r, rng.normal(0, 2.0, (len(x), 2)), ks=8e4, mu=0.4, cn=2.0, walls=box_walls(14.0),
                   n_steps=n_steps, every=10)
    sc.gravity = (0.0, -9.81)
    return sc


def test_determinism_same_scene_same_results():
    a = build(_frictional_box(2000)).run()
    b = build(_frictional_box(2000)).run()
    assert np.array_equal(a.x, b.x) and np.array_equal(a.hist, b.hist)


def test_checkpoint_resume_equals_continuous_run(tmp_path):
    full = build(_frictional_box(2000)).run()
    build(_frictional_box(2000)).run(1000, checkpoint=tmp_path / "c.npz")
    resumed = build(_frictional_box(2000)).load_checkpoint(tmp_path / "c.npz").run(1000)
    assert resumed.step == 2000
    assert np.array_equal(full.x, resumed.x) and np.array_equal(full.om, resumed.om)


@pytest.mark.parametrize("change,part", [(dict(radius=0.45), "discs"), (dict(dt=1e-4), "time step"),
                                         (dict(kn=2e7), "contact law")])
def test_a_checkpoint_of_another_scene_with_the_same_name_is_refused(tmp_path, change, part):
    """load_checkpoint compares what the scene fixes (radii, masses, dt, walls, law, box, gravity), not only its
    name and counts: a checkpoint written with radius 0.5 loaded into a radius-0.45 scene before without a word."""
    def scene(radius=0.5, dt=2e-4, kn=1e7):
        return Scene(name="same-name", discs=Discs(x=[0.5, 1.5], y=[0.5, 0.6], radius=[radius] * 2, material="d"),
                     materials={"d": Material(density=2000.0), "w": Material()},
                     laws={("d", "d"): LinearLaw(kn=kn, cn=1e4), ("d", "w"): LinearLaw(kn=kn, cn=1e4)},
                     walls=[Wall("floor", point=(0, 0), direction=(1, 0), h1=-1, h2=3, material="w")], dt=dt,
                     gravity=(0, -10), n_steps=100, outputs=Outputs(every=10))
    build(scene()).run(50, checkpoint=tmp_path / "c.npz")
    assert build(scene()).load_checkpoint(tmp_path / "c.npz").step == 50
    with pytest.raises(ValueError, match=f"these parts differ from this scene's: {part}"):
        build(scene(**change)).load_checkpoint(tmp_path / "c.npz")


def test_a_3d_checkpoint_of_another_scene_with_the_same_name_is_refused(tmp_path):
    import demflow as df

    def scene(radius=0.1, young=7e8):
        return df.Scene3D(name="same-name", spheres=df.Spheres(x=[0.0, 0.3], y=[0.0, 0.0], z=[0.2, 0.2],
                                                              radius=[radius] * 2, material="rock"),
                          materials={"rock": df.Material(density=2650.0, young=young, poisson=0.2)},
                          laws={("rock", "rock"): df.HertzMindlinLaw(friction=0.4)}, gravity=(0.0, 0.0, -9.81),
                          dt_fraction=0.1, outputs=df.Outputs3D(every=0))
    a = build(scene())
    a.run(20)
    a.save_checkpoint(tmp_path / "c.npz")
    assert build(scene()).load_checkpoint(tmp_path / "c.npz").step == 20
    with pytest.raises(ValueError, match="particles"):
        build(scene(radius=0.11)).load_checkpoint(tmp_path / "c.npz")
    with pytest.raises(ValueError, match="contact law"):  # and the time step, which follows the stiffness
        build(scene(young=7e9)).load_checkpoint(tmp_path / "c.npz")


def test_tables_roundtrip_parquet(tmp_path):
    sc = _frictional_box(500)
    sc.outputs = Outputs(every=10, snapshots=(0, 500))
    res = build(sc).run().results()
    res.save(tmp_path / "out")
    back = Results.load(tmp_path / "out")
    assert set(back.wall_forces.wall) == {"bottom", "right", "top", "left"}
    assert len(back.particles) == 2 * 40 and {"fn", "fs", "nx", "sliding"} <= set(back.contacts.columns)
    assert np.allclose(back.wall_forces.fy, res.wall_forces.fy)


def test_gravity_settled_bed_wall_reactions_balance_weight():
    sc = _frictional_box(20000)
    sc.damping = type(sc.damping)(alpha=2.0)  # terminal speed g/α ≈ 5 m/s, decay time 0.5 s ≪ 11 s
    sim = build(sc).run()
    wf = sim.results().wall_forces
    last = wf[wf.step == wf.step.max()]
    assert -last.fy.sum() == pytest.approx(sim.mass.sum() * 9.81, rel=1e-3)


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "demflow.cli", *args], cwd=cwd, capture_output=True, text=True)


def test_cli_cases_run_and_validate(tmp_path):
    out = _cli("cases", cwd=tmp_path)
    assert out.returncode == 0 and "cs-nine-disc" in out.stdout and "thesis-impact" in out.stdout
    out = _cli("run", "thesis-impact", "--out", str(tmp_path / "imp"), "--set", "dt=2e-5", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "imp" / "thesis" / "particles.parquet").exists()
    assert json.loads((tmp_path / "imp" / "thesis" / "meta.json").read_text())["params"]["dt"] == 2e-5
    out = _cli("run", "no-such-case", cwd=tmp_path)
    assert out.returncode == 2 and "unknown case" in out.stderr
    out = _cli("validate", "--case", "thesis-one-disc", "--out", str(tmp_path / "rep"), cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    s = json.loads((tmp_path / "rep" / "summary.json").read_text())
    assert s["cases"]["thesis-one-disc"]["passed"]
    assert (tmp_path / "rep" / "thesis-one-disc" / "plate_force.png").exists()


def test_loading_a_file_that_is_no_checkpoint_says_so(tmp_path):
    (tmp_path / "notes.npz").write_text("not an archive")
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    for f in ("notes.npz", "other.npz"):
        with pytest.raises(ValueError, match="is not a demflow checkpoint"):
            build(_frictional_box(100)).load_checkpoint(tmp_path / f)


@pytest.mark.parametrize("kw,words", [(dict(threads=0), "run\\(threads\\)=0 is not a number of threads"),
                                      (dict(threads="2"), "run\\(threads\\)='2' is not a number of threads"),
                                      (dict(checkpoint_every=-5), "run\\(checkpoint_every\\)=-5")])
def test_run_refuses_a_bad_thread_count_or_checkpoint_interval(kw, words):
    """threads=0 ran with the default, threads=-1 gave Numba's raw error, checkpoint_every=-5 was accepted."""
    with pytest.raises(ValueError, match=words):
        build(_frictional_box(100)).run(10, **kw)
