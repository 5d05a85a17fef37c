"""Non-finite states of the shape families end in BlowUpError with the last good state (issue 19 item 2,
for the 2D superquadrics of issue 15 and the 3D ellipsoids).

As tests/test_fuzz_scenes.py does for discs: a NaN gravity or density is refused by ``build`` (a
SceneError naming the field); injected after the build into the simulation's gravity, a body's mass,
a law's parameters (so the law's output) or a wall's motion it raises BlowUpError, and the state saved
with it loads into a fresh build of the scene, is finite, equals that scene run to the same step and
runs on.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from demflow import (BlowUpError, Ellipsoids, HertzMindlinLaw, LinearLaw, Material, Outputs, Outputs3D, Plane,
                     Scene, Scene3D, SceneError, Superquadrics, Wall, build)


@pytest.fixture(autouse=True)
def _blowup_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))


def _blows_up(sim, *, match):
    with pytest.raises(BlowUpError, match=match) as e:
        sim.run()
    assert e.value.path and "Last good state" in str(e.value)
    return e.value


# ----------------------------------------------------------------------------- 2D superquadrics
def _superquadrics(n_steps=400):
    """An n = 4 superquadric resting on a floor (a contact from the first steps) and an n = 2.5 one in free
    flight (no contact: only the state check sees its NaN)."""
    law = LinearLaw(kn=1e5, ks=5e4, cn=10.0, friction=0.3)
    return Scene(name="nonfinite-sq",
                 discs=Superquadrics(x=[0.0, 10.0], y=[0.5, 5.0], a=[1.0, 1.0], b=[0.5, 0.7], n=[4.0, 2.5],
                                     material="g", theta=[0.0, 0.4]),
                 materials={"g": Material(density=1.0), "w": Material()}, laws={("g", "g"): law, ("g", "w"): law},
                 walls=[Wall("floor", (0.0, 0.0), (1.0, 0.0), -20.0, 20.0, "w")], gravity=(0.0, -1.0), dt=1e-3,
                 n_steps=n_steps, outputs=Outputs(every=10))


def _sq_last_good_is_loadable(err, scene_fn=_superquadrics):
    z = np.load(err.path)
    for k in ("x", "y", "th", "vx", "vy", "om", "hist", "wall_px"):
        assert np.all(np.isfinite(z[k])), k
    fresh = build(scene_fn()).load_checkpoint(err.path)
    step = fresh.step
    ref = build(scene_fn()).run(step)
    for k in ("x", "y", "th", "vx", "vy", "om"):
        assert np.array_equal(getattr(fresh.bodies, k), getattr(ref.bodies, k)), k
    assert np.array_equal(fresh.hist, ref.hist) and np.array_equal(fresh.finder, ref.finder)
    fresh.run(5)  # and it runs on, as the uninterrupted run does
    ref.run(5)
    assert np.all(np.isfinite(fresh.bodies.x)) and np.array_equal(fresh.bodies.y, ref.bodies.y)
    return step


def test_sq_nan_gravity_and_nan_density_are_refused_by_build():
    with pytest.raises(SceneError, match=r"scene\.gravity\[0\]=nan is not finite"):
        build(replace(_superquadrics(), gravity=(math.nan, -1.0)))
    sc = _superquadrics()
    sc.materials = {"g": Material(density=math.nan), "w": Material()}
    with pytest.raises(SceneError, match=r"scene\.materials\['g'\]\.density=nan is not finite"):
        build(sc)


def test_sq_nan_gravity_at_run_time_is_a_blowup_with_the_last_good_state(monkeypatch):
    from demflow.simulation_sq2d import SuperquadricSimulation

    monkeypatch.setattr(SuperquadricSimulation, "CHUNK", 100)
    sim = build(_superquadrics())
    sim.run(150)
    assert sim.hist.shape[0] and np.any(sim.out.ovl > 0)  # the resting body touches the floor
    sim.gx = math.nan
    err = _blows_up(sim, match=r"bodies\.\w+\[\d\] = nan is not finite")
    assert "gravity (now (nan, -1.0))" in str(err)
    assert _sq_last_good_is_loadable(err) == 150  # the start of the chunk (this run call's first)


def test_sq_free_flying_body_with_inf_gravity_is_caught_by_the_state_check():
    sc = replace(_superquadrics(), discs=Superquadrics(x=[10.0], y=[5.0], a=[1.0], b=[0.7], n=[2.5], material="g"))
    sim = build(sc)
    sim.gy = math.inf
    err = _blows_up(sim, match=r"bodies\.(vy|y)\[0\] = (inf|nan) is not finite")
    assert build(sc).load_checkpoint(err.path).step == 0


def test_sq_nan_mass_at_run_time_is_a_blowup():
    sim = build(_superquadrics())
    sim.bodies.mass[0] = math.nan  # a density NaN that got past the build
    err = _blows_up(sim, match="blew up")
    assert _sq_last_good_is_loadable(err) == 0


def test_sq_nan_in_a_law_output_is_a_blowup(monkeypatch):
    from demflow.simulation_sq2d import SuperquadricSimulation

    monkeypatch.setattr(SuperquadricSimulation, "CHUNK", 50)
    sim = build(_superquadrics())
    sim.run(60)
    sim.law_params.cn[:] = math.nan  # every contact's damping force, so the law's Fn, is NaN
    err = _blows_up(sim, match=r"bodies\.(Fx|Fy|M)\[0\] = nan is not finite")
    assert _sq_last_good_is_loadable(err) == 60
    assert np.all(np.isfinite(sim.bodies.x)) and sim.step == 60  # the simulation itself is back at the good state


def test_sq_wall_driven_to_infinity_is_a_blowup():
    sc = _superquadrics()
    sc.discs = replace(sc.discs, x=[10.0], y=[5.0], a=[1.0], b=[0.7], n=[2.5], theta=None)  # no contact
    sim = build(sc)
    sim.loading.phase_end[0, 0] = 10 ** 6
    sim.loading.phase_vx[0, 0] = math.inf
    err = _blows_up(sim, match=r"walls\.(px|vx)\[0\] = (inf|nan)")
    assert build(sc).load_checkpoint(err.path).step == 0


def test_sq_checkpoint_is_refused_by_another_scene(tmp_path):
    sim = build(_superquadrics()).run(20)
    path = sim.save_checkpoint(tmp_path / "sq.npz")
    other = replace(_superquadrics(), discs=Superquadrics(x=[10.0], y=[5.0], a=[1.0], b=[0.7], n=[2.5], material="g"))
    with pytest.raises(ValueError, match="build the same scene"):
        build(other).load_checkpoint(path)


# ----------------------------------------------------------------------------- 3D ellipsoids
def _ellipsoids():
    """An ellipsoid resting on a floor (a contact from the first steps) and one in free flight."""
    return Scene3D(
        name="nonfinite-ell", spheres=None,
        ellipsoids=Ellipsoids(axes=[[0.012, 0.01, 0.008], [0.01, 0.008, 0.006]], x=[0.0, 0.1], y=[0.0, 0.0],
                              z=[0.008, 0.05], material="g"),
        materials={"g": Material(density=2500.0, young=1e8, poisson=0.3), "w": Material(young=math.inf, poisson=0.25)},
        laws={("g", "g"): HertzMindlinLaw(friction=0.4, restitution=0.7),
              ("g", "w"): HertzMindlinLaw(friction=0.4, restitution=0.7)},
        planes=[Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "w")], gravity=(0.0, 0.0, -9.81), n_steps=400,
        outputs=Outputs3D(every=10))


def _ell_last_good_is_loadable(err, scene_fn=_ellipsoids):
    z = np.load(err.path)
    for k in ("pos", "vel", "angvel", "body_pos", "body_vel", "body_L", "body_quat", "hist", "plane_point"):
        assert np.all(np.isfinite(z[k])), k
    fresh = build(scene_fn()).load_checkpoint(err.path)
    step = fresh.step
    ref = build(scene_fn()).run(step)
    for k in ("pos", "vel", "L", "quat"):
        assert np.array_equal(getattr(fresh.bodies, k), getattr(ref.bodies, k)), k
    fresh.run(5)
    assert np.all(np.isfinite(fresh.bodies.pos)) and np.all(np.isfinite(fresh.spheres.FM))
    return step


def test_ell_nan_gravity_and_nan_density_are_refused_by_build():
    with pytest.raises(SceneError, match=r"scene\.gravity"):
        build(replace(_ellipsoids(), gravity=(0.0, math.nan, -9.81)))
    sc = _ellipsoids()
    sc.materials = dict(sc.materials, g=Material(density=math.nan, young=1e8, poisson=0.3))
    with pytest.raises(SceneError, match=r"scene\.materials\['g'\]\.density"):
        build(sc)


def test_ell_nan_gravity_at_run_time_is_a_blowup_with_the_last_good_state(monkeypatch):
    from demflow.simulation3d import Simulation3D

    monkeypatch.setattr(Simulation3D, "CHUNK", 100)
    sim = build(_ellipsoids())
    sim.run(150)
    assert np.any(sim.pairs.ovl > 0)  # the resting ellipsoid touches the floor
    sim.g[0] = math.nan
    err = _blows_up(sim, match=r"(bodies|spheres)\.\w+\[\d(, \d)?\] = nan is not finite")
    assert "gravity (now (nan, 0.0, -9.81))" in str(err)
    assert _ell_last_good_is_loadable(err) == 150


def test_ell_nan_mass_at_run_time_is_a_blowup():
    sim = build(_ellipsoids())
    sim.bodies.mass[0] = math.nan  # a density NaN that got past the build
    sim.spheres.mass[0] = math.nan
    err = _blows_up(sim, match="blew up")
    assert _ell_last_good_is_loadable(err) == 0


def test_ell_nan_in_a_law_output_is_a_blowup(monkeypatch):
    from demflow.simulation3d import Simulation3D

    monkeypatch.setattr(Simulation3D, "CHUNK", 50)
    sim = build(_ellipsoids())
    sim.run(60)
    # every contact's effective modulus, so the law's normal force, is NaN (a NaN zn would not do: the law
    # adds its dashpot only where zn > 0)
    sim.law_params.Estar[:] = math.nan
    err = _blows_up(sim, match=r"blew up at step 61: (spheres|bodies)\.\w+\[0, \d\] = nan is not finite")
    assert _ell_last_good_is_loadable(err) == 60


# ---------------------------------------------------------------------------- 3D spheres (the same guarantees)
def _spheres():
    """A sphere resting on a floor (a contact from the first steps) and one in free flight."""
    from demflow import Spheres

    return Scene3D(
        name="nonfinite-sph", spheres=Spheres(x=[0.0, 0.1], y=[0.0, 0.0], z=[0.01, 0.05], radius=[0.01, 0.01],
                                             material="g"),
        materials={"g": Material(density=2500.0, young=1e8, poisson=0.3), "w": Material(young=math.inf, poisson=0.25)},
        laws={("g", "g"): HertzMindlinLaw(friction=0.4, restitution=0.7),
              ("g", "w"): HertzMindlinLaw(friction=0.4, restitution=0.7)},
        planes=[Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "w")], gravity=(0.0, 0.0, -9.81), n_steps=400,
        outputs=Outputs3D(every=10))


def _sph_last_good_is_loadable(err):
    z = np.load(err.path)
    for k in ("pos", "vel", "angvel", "hist", "plane_point"):
        assert np.all(np.isfinite(z[k])), k
    fresh = build(_spheres()).load_checkpoint(err.path)
    ref = build(_spheres()).run(fresh.step)
    assert np.array_equal(fresh.spheres.pos, ref.spheres.pos) and np.array_equal(fresh.spheres.vel, ref.spheres.vel)
    return fresh.step


def test_sph_nan_gravity_at_run_time_is_a_blowup_with_the_last_good_state(monkeypatch):
    from demflow.simulation3d import Simulation3D

    monkeypatch.setattr(Simulation3D, "CHUNK", 100)
    sim = build(_spheres())
    sim.run(150)
    sim.g[0] = math.nan
    err = _blows_up(sim, match="blew up")
    assert _sph_last_good_is_loadable(err) == 150


def test_sph_nan_mass_and_nan_law_output_are_blowups(monkeypatch):
    from demflow.simulation3d import Simulation3D

    sim = build(_spheres())
    sim.spheres.mass[1] = math.nan  # a density NaN that got past the build (the sphere in free flight)
    assert _sph_last_good_is_loadable(_blows_up(sim, match="blew up")) == 0
    monkeypatch.setattr(Simulation3D, "CHUNK", 50)
    sim = build(_spheres())
    sim.run(60)
    sim.law_params.Estar[:] = math.nan
    assert _sph_last_good_is_loadable(_blows_up(sim, match="blew up")) == 60
