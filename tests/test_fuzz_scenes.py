"""Invalid scenes are refused clearly; non-finite states end in BlowUpError (issue 19).

Scenes: Hypothesis draws, per category of tests/scene_faults.py, a fault and its value (one fault
per scene, derandomized, a bounded number of examples) and asserts a SceneError whose message names
the broken field by its dotted path.  benchmarks/fuzz_scenes.py runs the same catalogue on 400
seeded scenes and writes the counts the robustness page shows.

Run time: NaN or infinity injected after build into gravity, a disc's mass, a law's parameters (so
the law's output), the external force, the fluid solve and a wall's motion each raise BlowUpError,
with the last good state saved and loadable, bit-identical to a run stopped at that step.
"""
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demflow import (BlowUpError, Discs, LinearLaw, Material, Outputs, Scene, SceneError, Wall, build)
from demflow.scene import check_identifier, check_name
from demflow.simulation import Simulation, first_nonfinite, record_bytes, recorded_steps
from demflow.stepping import state_is_finite

import scene_faults as sf

FUZZ = settings(max_examples=12, deadline=None, derandomize=True, database=None,
                suppress_health_check=list(HealthCheck))


# ----------------------------------------------------------------------------- invalid scenes
@pytest.mark.parametrize("category", sf.CATEGORIES)
@FUZZ
@given(data=st.data())
def test_every_invalid_scene_is_refused_naming_its_field(category, data):
    faults = [f for f in sf.FAULTS if f.category == category]
    f = data.draw(st.sampled_from(faults), label="fault")
    scene, path, value = f.make(lambda seq: data.draw(st.sampled_from(list(seq))))
    kind, msg = sf.classify(scene, path)
    assert kind == "clear", (f.name, path, value, kind, msg)


@pytest.mark.parametrize("fault", sf.FAULTS, ids=[f"{f.category}: {f.name}" for f in sf.FAULTS])
def test_every_fault_kind_with_its_first_values(fault):
    """Each fault kind at least once (Hypothesis samples within a category): the first entry of every
    pool it draws from."""
    scene, path, value = fault.make(lambda seq: list(seq)[0])
    kind, msg = sf.classify(scene, path)
    assert kind == "clear", (fault.name, path, value, kind, msg)


@pytest.mark.parametrize("name", list(sf.BASES))
def test_the_base_scenes_are_valid(name):
    """Negative control: without a fault each base scene builds and runs."""
    sim = build(sf.BASES[name]())
    sim.run()
    assert sim.step == sim.scene.n_steps


def test_classify_tells_the_outcomes_apart():
    """Negative control of the classifier: a valid scene is 'accepted', a message without the path is
    'unnamed'."""
    assert sf.classify(sf.base_dry(), "scene.name")[0] == "accepted"
    sc = replace(sf.base_dry(), dt=math.nan)
    assert sf.classify(sc, "scene.dt")[0] == "clear"
    assert sf.classify(sc, "scene.gravity")[0] == "unnamed"


def test_every_field_of_every_scene_object_is_fuzzed():
    """The catalogue breaks every dataclass field of the scene objects (paths drawn over many picks)."""
    import random

    rng = random.Random(0)
    paths = set()
    for f in sf.FAULTS:
        for _ in range(40):
            paths.add(f.make(rng.choice)[1])
    text = "\n".join(paths)
    where = {"Scene": "scene.", "Discs": "scene.discs.", "Material": "].", "LinearLaw": "].", "Wall": "].",
             "Phase": "].", "Servo": "servo.", "Outputs": "outputs.", "Box": "box.", "ContactModel": "contact_model.",
             "GlobalDamping": "damping.", "Fluid": "fluid.", "WallLoad": "].", "Superquadrics": "scene.discs."}
    missing = [fp for fp in sf.field_paths() if where[fp.split(".")[0]] + fp.split(".")[1] not in text]
    assert not missing, missing


@pytest.mark.parametrize("name", ["abc\n", "abc\r\n", "a\nb", "", "1a", "a" * 65, "a b", "é"])
def test_identifiers_are_matched_in_full(name):
    with pytest.raises(SceneError, match="not an identifier"):
        check_identifier("material", name)
    with pytest.raises(SceneError, match=r"scene\.name="):
        check_name("scene.name", name)
    assert check_name("scene.name", "a" * 64) == "a" * 64


def test_a_run_longer_than_can_be_stored_is_refused_up_front_with_the_numbers():
    sc = replace(sf.base_dry(), n_steps=10 ** 12, outputs=Outputs(every=1))
    with pytest.raises(SceneError) as e:
        build(sc)
    msg = str(e.value)
    for w in ("scene.n_steps=1000000000000", "1,000,000,000,000 recorded steps", f"{record_bytes(4, 0)} bytes",
              "GiB", "scene.outputs.every >="):
        assert w in msg, (w, msg)
    # with nothing recorded the same length builds, and run() checks its own argument the same way
    sim = build(replace(sc, outputs=Outputs(every=0)))
    sim.scene.outputs = Outputs(every=1)
    with pytest.raises(SceneError, match=r"run\(n_steps\)=1000000000000"):
        sim.run(10 ** 12)
    with pytest.raises(SceneError, match=r"run\(n_steps\)=-1"):
        sim.run(-1)


def test_records_are_allocated_per_chunk_and_identical(monkeypatch):
    """Records grow with what is recorded: a run in chunks of 7 steps gives the same records, to the bit,
    as one chunk."""
    a = build(sf.base_dry()).run()
    monkeypatch.setattr(Simulation, "CHUNK", 7)
    b = build(sf.base_dry()).run()
    assert len(a.records) == len(b.records) == 1
    for u, v in zip(a.records[0], b.records[0]):
        assert u.shape == v.shape and np.array_equal(u, v)
    assert len(a.records[0][0]) == recorded_steps(0, 100, 2) == 50
    assert recorded_steps(3, 10, 4) == len([s for s in range(3, 13) if s % 4 == 0])


# ----------------------------------------------------------------------------- non-finite states
def _falling(n_steps=400):
    """Two discs: one resting on a floor (contacts), one in free flight (no contact: only the state
    check can see its NaN)."""
    law = LinearLaw(kn=1e5, ks=5e4, cn=10.0, friction=0.3)
    return Scene(name="nonfinite", discs=Discs(x=[0.0, 10.0], y=[1.0, 5.0], radius=[1.0, 1.0], material="g"),
                 materials={"g": Material(density=1.0), "w": Material()},
                 laws={("g", "g"): law, ("g", "w"): law},
                 walls=[Wall("floor", (0.0, 0.0), (1.0, 0.0), -20.0, 20.0, "w")],
                 gravity=(0.0, -1.0), dt=1e-3, n_steps=n_steps, outputs=Outputs(every=10))


def _blows_up(sim, *, match):
    with pytest.raises(BlowUpError, match=match) as e:
        sim.run()
    return e.value


def _last_good_is_loadable(err, scene_fn):
    """The saved state loads into a fresh build of the scene and equals, to the bit, that scene run
    to the same step."""
    assert err.path and "Last good state" in str(err)
    z = np.load(err.path)
    for k in ("x", "y", "vx", "vy", "om", "hist"):
        assert np.all(np.isfinite(z[k])), k
    fresh = build(scene_fn()).load_checkpoint(err.path)
    step = fresh.step
    ref = build(scene_fn()).run(step)
    assert np.array_equal(fresh.x, ref.x) and np.array_equal(fresh.vy, ref.vy) and np.array_equal(fresh.hist, ref.hist)
    fresh.run(5)  # and it runs on
    assert np.all(np.isfinite(fresh.x))


@pytest.fixture(autouse=True)
def _blowup_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))


def test_nan_gravity_and_nan_density_are_refused_by_build():
    with pytest.raises(SceneError, match=r"scene\.gravity\[0\]=nan is not finite"):
        build(replace(_falling(), gravity=(math.nan, 0.0)))
    sc = _falling()
    sc.materials = {"g": Material(density=math.nan), "w": Material()}
    with pytest.raises(SceneError, match=r"scene\.materials\['g'\]\.density=nan is not finite"):
        build(sc)


def test_nan_gravity_at_run_time_is_a_blowup_with_the_last_good_state(monkeypatch):
    monkeypatch.setattr(Simulation, "CHUNK", 100)
    sim = build(_falling())
    sim.run(150)
    sim.gx = math.nan  # e.g. a gravity computed by a user's stage script
    err = _blows_up(sim, match=r"discs\.\w+\[\d\] = nan is not finite")
    assert "gravity (now (nan, -1.0))" in str(err)
    assert build(_falling()).load_checkpoint(err.path).step == 150  # the chunk's start
    _last_good_is_loadable(err, _falling)


def test_a_free_flying_disc_with_nan_gravity_is_caught_by_the_state_check():
    """No contact sees it, so only the per-call state check can: the disc without contacts."""
    sc = replace(_falling(), discs=Discs(x=[10.0], y=[5.0], radius=[1.0], material="g"))
    sim = build(sc)
    sim.gy = math.inf
    err = _blows_up(sim, match=r"discs\.(vy|y)\[0\] = (inf|nan) is not finite")
    assert build(sc).load_checkpoint(err.path).step == 0


def test_nan_mass_at_run_time_is_a_blowup():
    sim = build(_falling())
    sim.discs.mass[0] = math.nan  # density NaN with a given dt, as the issue found it accepted
    err = _blows_up(sim, match="blew up")
    _last_good_is_loadable(err, _falling)


def test_nan_in_a_law_output_is_a_blowup():
    sim = build(_falling())
    sim.law_params.cn[:] = math.nan  # every contact's damping force, so the law's Fn, is NaN
    err = _blows_up(sim, match="a force became non-finite")
    _last_good_is_loadable(err, _falling)


def test_nan_external_force_is_a_blowup():
    sim = build(_falling())
    sim.has_external_force = True
    sim.external_force = np.zeros((sim.n, 3))
    sim.external_force[1, 1] = math.nan
    err = _blows_up(sim, match=r"discs\.\w+\[1\] = nan")
    _last_good_is_loadable(err, _falling)


def test_a_wall_driven_to_infinity_is_a_blowup():
    sc = _falling()
    sc.walls = [replace(sc.walls[0], phases=())]
    sim = build(sc)
    sim.loading.phase_end[0, 0] = 10 ** 6
    sim.loading.phase_vx[0, 0] = math.inf
    err = _blows_up(sim, match=r"walls\.(px|vx)\[0\] = (inf|nan)|force became non-finite")
    assert build(sc).load_checkpoint(err.path).step == 0


def test_a_nan_fluid_force_is_a_blowup(monkeypatch):
    from demflow.coupling import FluidCoupler

    solve = FluidCoupler.solve

    def nan_solve(self, sim):
        return np.full_like(solve(self, sim), math.nan)

    monkeypatch.setattr(FluidCoupler, "solve", nan_solve)
    sim = build(sf.base_fluid())
    err = _blows_up(sim, match=r"fluid force and buoyancy \(external_force\)\[0, 0\] = nan is not finite after "
                               r"the fluid solve")
    assert build(sf.base_fluid()).load_checkpoint(err.path).step == 0


def test_first_nonfinite_finds_every_kind_and_no_false_alarm():
    a = np.zeros((1000, 2))
    assert first_nonfinite({"a": a}) is None
    assert first_nonfinite({"big": np.array([1e308, 1e308, -1e308])}) is None  # the sum overflows: exact test
    for bad in (math.nan, math.inf, -math.inf):
        a[731, 1] = bad
        assert first_nonfinite({"ok": np.ones(3), "a": a}) == f"a[731, 1] = {bad}"


def test_the_compiled_state_check_sees_every_quantity():
    """state_is_finite (run at the end of every call of the cycle) is True on a sound state and False
    with a NaN or inf in any one of the quantities it covers; the Python search names the same one."""
    sim = build(_falling()).run(20)
    assert sim._nonfinite_state() is None and sim.pairs.hist.size
    fields = [(sim.discs, f) for f in ("x", "y", "th", "vx", "vy", "om", "Fx", "Fy", "M")]
    fields += [(sim.walls, f) for f in ("px", "py", "ex", "ey", "vx", "vy", "om", "cx", "cy", "force")]
    for struct, f in fields + [(sim.pairs, "hist")]:
        a = getattr(struct, f)
        for bad in (math.nan, -math.inf):
            keep = a.flat[-1]
            a.flat[-1] = bad
            assert not state_is_finite(sim.discs, sim.walls, sim.pairs.hist), f
            assert sim._nonfinite_state().split("[")[0].endswith(f), (f, sim._nonfinite_state())
            a.flat[-1] = keep
    assert state_is_finite(sim.discs, sim.walls, sim.pairs.hist)


# ----------------------------------------------------------------------------- the script and the report page
def test_the_400_scene_script_refuses_all_and_matches_the_committed_results(tmp_path):
    """benchmarks/fuzz_scenes.py (seeded) run now gives 100 % clear refusals and the very counts the
    robustness page shows (benchmarks/results/fuzz_scenes.json)."""
    import importlib.util
    import json
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location("fuzz_scenes_script", root / "benchmarks" / "fuzz_scenes.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    assert script.main(["--n", "400", "--out", str(tmp_path / "f.json")]) == 0
    now = json.loads((tmp_path / "f.json").read_text())
    committed = json.loads((root / "benchmarks" / "results" / "fuzz_scenes.json").read_text())
    assert now["outcomes"] == {"clear": 400}
    assert (now["faults"], now["catalogue"]) == (committed["faults"], committed["catalogue"])


def test_the_400_scene_script_refuses_all_3d_scenes_and_matches_the_committed_results(tmp_path):
    """The same script with --3d (tests/scene_faults3d.py: spheres, walls, meshes, clumps, ellipsoids) gives
    100 % clear refusals and the counts committed in benchmarks/results/fuzz_scenes3d.json."""
    import importlib.util
    import json
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location("fuzz_scenes_script", root / "benchmarks" / "fuzz_scenes.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    assert script.main(["--3d", "--n", "400", "--out", str(tmp_path / "f3.json")]) == 0
    now = json.loads((tmp_path / "f3.json").read_text())
    committed = json.loads((root / "benchmarks" / "results" / "fuzz_scenes3d.json").read_text())
    assert now["outcomes"] == {"clear": 400} and now["kind"] == "scenes3d"
    assert (now["faults"], now["catalogue"]) == (committed["faults"], committed["catalogue"])


def test_the_robustness_page_is_rendered_from_the_fuzz_results(tmp_path):
    from pathlib import Path

    from demflow.report.robustness import render, summary_line

    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    page = render(root)
    assert "400/400 (100.0 %) refused by a SceneError naming the broken field" in page
    assert "radii: disc radius" in page and "scene.discs.radius[" in page
    assert "Corrupted engine outputs" in page and "liggghts" in page and "yade_out.json" in page
    assert "Invalid 3D scenes" in page and "scene.ellipsoids." in page  # benchmarks/fuzz_scenes.py --3d
    assert "superquadrics: superquadric entry" in page
    assert "0 unhandled" in summary_line(root) and "400/400 invalid 3D scenes" in summary_line(root)
    assert render(tmp_path) is None and summary_line(tmp_path) == ""  # nothing run: no page


# ----------------------------------------------------------------------------- 3D scenes (spheres, planes,
# plates, meshes, clumps, the Hertz-Mindlin law): the same protocol, tests/scene_faults3d.py
import scene_faults3d as sf3  # noqa: E402


@pytest.mark.parametrize("category", sf3.CATEGORIES3D)
@FUZZ
@given(data=st.data())
def test_every_invalid_3d_scene_is_refused_naming_its_field(category, data):
    faults = [f for f in sf3.FAULTS3D if f.category == category]
    f = data.draw(st.sampled_from(faults), label="fault")
    scene, path, value = f.make(lambda seq: data.draw(st.sampled_from(list(seq))))
    kind, msg = sf.classify(scene, path)
    assert kind == "clear", (f.name, path, value, kind, msg)


def test_the_3d_base_scene_is_valid():
    """Negative control: without a fault the 3D base scenes (spheres and clumps; ellipsoids) build and run."""
    for scene in (sf3.base3d(), sf3.base3d_ellipsoids()):
        sim = build(scene)
        sim.run()
        assert sim.step == sim.scene.n_steps


def test_every_field_of_every_3d_scene_object_is_fuzzed_or_derived():
    """The 3D catalogue breaks every field of the 3D scene objects, except the few listed with the reason."""
    import random

    rng = random.Random(0)
    paths = set()
    for f in sf3.FAULTS3D:
        for _ in range(60):
            paths.add(f.make(rng.choice)[1])
    text = "\n".join(paths)
    where = {"Scene3D": "scene.", "Spheres": "scene.spheres.", "Plane": "].", "PlanePhase": "].", "PlateServo": "servo.",
             "TriangleMesh": "].", "Clumps": "clumps.", "Ellipsoids": "ellipsoids.", "Outputs3D": "outputs.",
             "HertzMindlinLaw": "]."}
    derived = {
        "Scene3D.damping", "Scene3D.contact_model",  # GlobalDamping and ContactModel: the 2D objects, fuzzed
        # by tests/scene_faults.py and checked by the same methods
        "Scene3D.description",  # free text, never used in a deck
        "Clumps.y", "Clumps.z",  # the same per-entry and length check as Clumps.x (build3d._array)
    }
    missing = [fp for fp in sf3.field_paths3d()
               if fp not in derived and where[fp.split(".")[0]] + fp.split(".")[1] not in text]
    assert not missing, missing
