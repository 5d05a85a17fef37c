"""The 3D engine output readers (YADE and LIGGGHTS on a Scene3D) refuse corrupted files with
EngineOutputError only, like the 2D ones (tests/test_fuzz_readers.py).

The fixtures are real engine outputs (tests/reader_faults3d.py); every corruption of
tests/reader_faults.py is drawn, seeded, 100 per reader, plus random bytes per file (Hypothesis)
and one named fault per check.
"""
import random
import shutil

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import reader_faults3d as rf
from demflow import build
from demflow.engines import EngineOutputError
from demflow.engines.base3d import Trajectory3D, demflow_trajectory, trajectory_difference

N_PER_READER = 100
ENGINES = list(rf.FILES)


@pytest.fixture(scope="module", params=ENGINES)
def engine_sim(request):
    return request.param, build(rf.fixture_scene(request.param))


def test_the_fixture_outputs_read_into_the_trajectory_demflow_records(engine_sim, tmp_path):
    """Negative control for the refusals below: the uncorrupted outputs are accepted, at the steps
    demflow records, and they follow demflow's trajectory of the same scene (the conformance case's
    claim, here at its own loose scale: 1e-6 of the sphere's radius and speed scales)."""
    engine, sim = engine_sim
    shutil.copytree(rf.FIXTURES / engine, tmp_path / "o")
    res = rf.read(engine, sim, tmp_path / "o")
    assert isinstance(res, Trajectory3D)
    assert sorted(set(res.spheres.step)) == list(range(0, rf.N_STEPS + 1, rf.EVERY))
    assert len(res.planes) == rf.N_STEPS // rf.EVERY * sim.n_planes
    own = demflow_trajectory(build(rf.fixture_scene(engine)))
    d = trajectory_difference(own, res)
    assert d["steps"] == rf.N_STEPS // rf.EVERY + 1
    assert max(d["position"], d["velocity"], d["angular"]) < 1e-6, d


def test_corrupted_outputs_are_refused_with_engine_output_error_only(engine_sim, tmp_path):
    engine, sim = engine_sim
    rng = random.Random(f"test3d-{engine}")
    outcomes = {"refused": 0, "accepted": 0}
    for i in range(N_PER_READER):
        d = tmp_path / f"c{i}"
        name, kind = rf.corrupted_dir(engine, d, rng)
        try:
            res = rf.read(engine, sim, d)
        except EngineOutputError as e:
            assert "rerun the engine" in str(e) or "see" in str(e), str(e)
            outcomes["refused"] += 1
        else:  # the corruption left a well-formed output (a changed digit)
            assert isinstance(res, Trajectory3D) and len(res.spheres) == (rf.N_STEPS // rf.EVERY + 1) * sim.n
            assert np.all(np.isfinite(res.spheres[["x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz"]].to_numpy())), (name, kind)
            outcomes["accepted"] += 1
        shutil.rmtree(d)
    assert outcomes["refused"] >= 0.6 * N_PER_READER, outcomes


@pytest.mark.parametrize("name", [f for files in rf.FILES.values() for f in files])
@settings(max_examples=15, deadline=None, derandomize=True, database=None,
          suppress_health_check=list(HealthCheck))
@given(data=st.binary(max_size=3000))
def test_random_bytes_in_any_file_are_refused(name, data, tmp_path_factory):
    engine = next(e for e, files in rf.FILES.items() if name in files)
    sim = _sim(engine)
    d = tmp_path_factory.mktemp("rnd")
    for f in rf.FILES[engine]:
        shutil.copyfile(rf.FIXTURES / engine / f, d / f)
    (d / name).write_bytes(data + (b"\nDEMFLOW-COMPLETE\n" if name == "log.liggghts" else b""))
    try:
        rf.read(engine, sim, d)
    except EngineOutputError:
        return
    assert name == "log.liggghts"  # the log is read for its completion mark only


_SIMS = {}


def _sim(engine):
    if engine not in _SIMS:
        _SIMS[engine] = build(rf.fixture_scene(engine))
    return _SIMS[engine]


@pytest.mark.parametrize("engine, name, edit, words", [
    ("liggghts3d", "planes.txt", lambda b: b"\n".join(b.split(b"\n")[1:]), "planes.txt: it holds 5 rows"),
    ("liggghts3d", "planes.txt", lambda b: b.replace(b"20 ", b"25 ", 1), "planes.txt: it holds 6 rows"),
    ("liggghts3d", "spheres.txt", lambda b: b[: len(b) // 2], "spheres.txt"),
    ("liggghts3d", "spheres.txt", lambda b: b.replace(b"ITEM: TIMESTEP\n20\n", b"ITEM: TIMESTEP\n5\n"),
     "timestep 5 is repeated or out of order"),
    ("liggghts3d", "spheres.txt", lambda b: b.replace(b"\n1 ", b"\n2 ", 1), "holds an id outside 1..1"),
    ("liggghts3d", "scene.json", lambda b: b.replace(b'"lo"', b'"lox"'), "scene.json is missing or corrupt"),
    ("liggghts3d", "log.liggghts", lambda b: b.replace(b"DEMFLOW-COMPLETE", b"DEMFLOW"), "did not complete"),
    ("yade3d", "yade_out.json", lambda b: b.replace(b'"complete": true', b'"complete": false'), "incomplete"),
    ("yade3d", "yade_out.json", lambda b: b[:-10], "truncated or corrupt"),
    ("yade3d", "yade_out.json", lambda b: b.replace(b'"sphere_steps": [0, 10, ', b'"sphere_steps": [0, 15, '),
     "rec.sphere_steps records steps"),
    ("yade3d", "yade_out.json", lambda b: b.replace(b'"planes": [', b'"planes": [NaN, ', 1),
     "rec.planes is not a regular array"),
    ("yade3d", "yade_out.json", lambda b: b.replace(b'"planes": [', b'"planes": [[[0, 0, 0]], ', 1),
     "rec.planes has shape (7, 1, 3), expected (6, 1, 3)"),
    ("yade3d", "yade_out.json", lambda b: b.replace(b'"spheres": [[[0.0, ', b'"spheres": [[[', 1),
     "rec.spheres is not a regular array"),
])
def test_each_check_names_the_file_and_the_fault(engine, name, edit, words, tmp_path):
    shutil.copytree(rf.FIXTURES / engine, tmp_path / "o")
    f = tmp_path / "o" / name
    before = f.read_bytes()
    f.write_bytes(edit(before))
    assert f.read_bytes() != before, "the edit must change the file"
    with pytest.raises(EngineOutputError, match=words.replace("(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        rf.read(engine, _sim(engine), tmp_path / "o")
