"""Engine output readers refuse corrupted files with EngineOutputError only; stored references are
hash-checked including meta.json (issue 19).

The fixtures are real YADE and LIGGGHTS outputs (tests/fixtures/engine_outputs/, see
tests/reader_faults.py).  Default tests corrupt 100 copies per reader (seeded) and feed each file
random bytes (Hypothesis, derandomized); benchmarks/fuzz_readers.py runs 1000 per reader.
"""
import json
import random
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demflow import build
from demflow.engines import EngineError, EngineOutputError
from demflow.engines import reference
from demflow.results import Results

import reader_faults as rf

N_PER_READER = 100
REFS = Path(__file__).resolve().parents[1] / "reference_runs"


@pytest.fixture(scope="module")
def sim():
    return build(rf.fixture_scene())


@pytest.fixture(scope="module")
def refs_before():
    return rf.fingerprint(REFS)


@pytest.mark.parametrize("engine", list(rf.FILES))
def test_the_fixture_outputs_read_into_tables(engine, sim, tmp_path):
    """Negative control: the uncorrupted outputs are accepted, with the tables the scene asks for."""
    d = tmp_path / engine
    shutil.copytree(rf.FIXTURES / engine, d)
    res = rf.read(engine, sim, d)
    assert isinstance(res, Results)
    n_rec = 100 // 10
    assert len(res.wall_forces) == n_rec * sim.nw and len(res.tracked) == n_rec * len(sim.track)
    assert sorted(set(res.particles.step)) == [40, 100] and len(res.particles) == 2 * sim.n
    assert np.all(np.isfinite(res.wall_forces.fy)) and res.contacts.fn.max() > 0


@pytest.mark.parametrize("engine", list(rf.FILES))
def test_corrupted_outputs_are_refused_with_engine_output_error_only(engine, sim, tmp_path, refs_before):
    rng = random.Random(f"test-{engine}")
    outcomes = {"refused": 0, "accepted": 0}
    for i in range(N_PER_READER):
        d = tmp_path / f"c{i}"
        name, kind = rf.corrupted_dir(engine, d, rng)
        try:
            res = rf.read(engine, sim, d)
        except EngineOutputError as e:
            assert "rerun the engine" in str(e) or "see" in str(e), str(e)
            outcomes["refused"] += 1
        else:  # the corruption left a well-formed output (a changed digit, rows of one block reordered)
            assert isinstance(res, Results) and len(res.wall_forces) == 10 * sim.nw, (name, kind)
            outcomes["accepted"] += 1
        shutil.rmtree(d)
    assert outcomes["refused"] >= 0.6 * N_PER_READER, outcomes
    assert rf.fingerprint(REFS) == refs_before


@pytest.mark.parametrize("engine, name", [(e, f) for e, files in rf.FILES.items() for f in files])
@settings(max_examples=15, deadline=None, derandomize=True, database=None,
          suppress_health_check=list(HealthCheck))
@given(data=st.binary(max_size=3000))
def test_random_bytes_in_any_file_are_refused(engine, name, data, sim, tmp_path_factory):
    d = tmp_path_factory.mktemp("rnd")
    for f in rf.FILES[engine]:
        shutil.copyfile(rf.FIXTURES / engine / f, d / f)
    (d / name).write_bytes(data + (b"\nDEMFLOW-COMPLETE\n" if name == "log.liggghts" else b""))
    try:
        rf.read(engine, sim, d)
    except EngineOutputError:
        return
    assert name == "log.liggghts"  # only the log may hold anything (the completion mark is all it is read for)


@pytest.mark.parametrize("engine, name, edit, words", [
    ("liggghts", "walls.txt", lambda b: b"\n".join(b.split(b"\n")[1:]), "walls.txt has 9 rows, expected 10"),
    ("liggghts", "contacts.txt", lambda b: b[: len(b) // 2], "contacts.txt"),
    ("liggghts", "particles.txt", lambda b: b.replace(b"\n5 ", b"\n3 ", 1), "does not list atoms 1..9 once each"),
    ("liggghts", "wallcontacts.txt", lambda b: b.replace(b"ITEM: TIMESTEP\n20\n", b"ITEM: TIMESTEP\n5\n"),
     "timestep 5 is repeated or out of order"),
    ("liggghts", "contacts.txt", lambda b: b.replace(b" 1 2 ", b" 1 20 ", 1), "holds an id outside 1..9"),
    ("liggghts", "walls.txt", lambda b: b"nan" + b[b.index(b" "):], "non-finite"),
    ("yade", "yade_out.json", lambda b: b.replace(b'"complete": true', b'"complete": false'), "incomplete"),
    ("yade", "yade_out.json", lambda b: b[:-10], "truncated or corrupt"),
    ("yade", "yade_out.json", lambda b: b.replace(b'"step": [0, 10, ', b'"step": [0, 15, '), "rec.step records steps"),
    ("yade", "yade_out.json", lambda b: b.replace(b'"kinetic": [', b'"kinetic": [NaN, ', 1), "rec.kinetic has shape"),
])
def test_each_check_names_the_file_and_the_fault(engine, name, edit, words, sim, tmp_path):
    shutil.copytree(rf.FIXTURES / engine, tmp_path / "o")
    f = tmp_path / "o" / name
    before = f.read_bytes()
    f.write_bytes(edit(before))
    assert f.read_bytes() != before, "the edit must change the file"
    with pytest.raises(EngineOutputError, match=words.replace("(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        rf.read(engine, sim, tmp_path / "o")


@pytest.mark.parametrize("engine", list(rf.FILES))
def test_a_refused_output_writes_nothing_through_reference_generate(engine, sim, tmp_path, refs_before):
    """The whole path: an engine (replaying corrupted files) runs, its output is refused, and the reference
    directory gets nothing, not even the case and variant folders."""
    rng = random.Random(f"generate-{engine}")
    base = tmp_path / "refs"
    base.mkdir()
    n = 0
    while n < 3:
        d = tmp_path / f"c{n}-{rng.random()}"
        rf.corrupted_dir(engine, d, rng)
        try:
            rf.read(engine, sim, d)
            continue  # a well-formed corruption: not this test's subject
        except EngineOutputError:
            pass
        with pytest.raises(EngineOutputError):
            reference.generate("reader-fixture", "fuzz", rf.replay_engine(engine, d), sim.scene, base=base)
        assert not any(base.iterdir()), list(base.rglob("*"))
        n += 1
    assert rf.fingerprint(REFS) == refs_before


# ----------------------------------------------------------------------------- meta.json in the hash check
def _copy_ref(tmp_path, engine="yade", variant="undamped"):
    from demflow.cases.cs_nine_disc_engines import CASE

    dst = tmp_path / CASE / variant / engine
    shutil.copytree(reference.location(CASE, variant, engine), dst)
    for f in dst.iterdir():
        f.chmod(0o644)
    return CASE, variant, engine, dst


def test_every_stored_reference_is_sealed_and_its_meta_json_checked():
    n = 0
    for case in ("cs-nine-disc", "cs-photoelastic"):
        for variant, engines in reference.available(case).items():
            for e in engines:
                path = reference.location(case, variant, e)
                assert (path / reference.SEAL).exists(), path
                reference.verify(path)
                n += 1
    assert n >= 18


def test_an_edited_meta_json_is_refused(tmp_path):
    case, variant, engine, dst = _copy_ref(tmp_path)
    reference.load(case, variant, engine, base=tmp_path)  # intact copy loads
    meta = json.loads((dst / "meta.json").read_text())
    meta["results_meta"]["dt"] *= 2  # what Results.load would hand on as the run's time step
    (dst / "meta.json").write_text(json.dumps(meta, indent=1))
    with pytest.raises(EngineError, match="fails its hash check at meta.json"):
        reference.load(case, variant, engine, base=tmp_path)
    with pytest.raises(EngineError, match="fails its hash check at meta.json"):
        reference.seal(dst)  # a seal that no longer matches is never rewritten


def test_an_unsealed_reference_is_refused_until_sealed(tmp_path):
    case, variant, engine, dst = _copy_ref(tmp_path)
    (dst / reference.SEAL).unlink()
    with pytest.raises(EngineError, match="has no meta.sha256.*--seal"):
        reference.load(case, variant, engine, base=tmp_path)
    assert reference.seal(dst) is True and reference.seal(dst) is False
    reference.load(case, variant, engine, base=tmp_path)
    # sealing verifies every file first: a tampered table is not sealed over
    (dst / reference.SEAL).unlink()
    f = dst / "tracked.parquet"
    data = bytearray(f.read_bytes())
    data[len(data) // 2] ^= 0xFF
    f.write_bytes(bytes(data))
    with pytest.raises(EngineError, match="hash check at tracked.parquet"):
        reference.seal(dst)
    assert not (dst / reference.SEAL).exists()
