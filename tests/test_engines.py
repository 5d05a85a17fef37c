"""The cross-code harness: stored references, decks, failure handling, and live engines.

Default tests need no engine: they verify the stored references (sha256) and compare fresh
demflow runs with them.  Tests marked ``engines`` run the real YADE and LIGGGHTS
(installed by scripts/install-engines.sh; .ci/run runs them).
"""
import json
import os
import shutil
import stat

import numpy as np
import pytest

from demflow import SceneError, build
from demflow.cases.cs_nine_disc import NineDisc, contact_c_force
from demflow.cases.cs_nine_disc_engines import CASE, NineDiscEngines, engine_scene
from demflow.engines import (EngineFailed, EngineNotFound, EngineOutputError, EngineTimeout, LiggghtsEngine,
                             YadeEngine, get_engine)
from demflow.engines import reference

P = NineDisc().merged()


def test_every_stored_reference_passes_its_hash_check():
    stored = reference.available(CASE)
    assert stored, "reference_runs/cs-nine-disc must hold the engines' runs"
    n = 0
    for variant, engines in stored.items():
        for e in engines:
            meta = reference.verify(reference.location(CASE, variant, e))
            assert meta["engine"] == e and meta["engine_version"]
            n += 1
    assert n >= 16  # 11 YADE variants + 5 LIGGGHTS variants


def test_tampered_reference_is_refused(tmp_path):
    src = reference.location(CASE, "undamped", "yade")
    dst = tmp_path / CASE / "undamped" / "yade"
    shutil.copytree(src, dst)
    reference.load(CASE, "undamped", "yade", base=tmp_path)  # intact copy loads
    f = dst / "tracked.parquet"
    os.chmod(f, 0o644)
    data = bytearray(f.read_bytes())
    data[len(data) // 2] ^= 0xFF
    f.write_bytes(bytes(data))
    with pytest.raises(Exception, match="hash check"):
        reference.load(CASE, "undamped", "yade", base=tmp_path)


def test_fresh_demflow_runs_agree_with_stored_engine_references():
    """Acceptance of issue 5: equivalent variants agree within 1 % at equilibrium and to
    round-off over the history (tolerances.py); every stored variant is compared."""
    case = NineDiscEngines()
    p = case.merged()
    results = case.run(p)
    assert set(results.results) == set(reference.available(CASE))
    checks = case.checks(results, p)
    asserted = [c for c in checks if np.isfinite(c.tolerance)]
    assert len(asserted) >= 2 * 12  # 7 equivalent YADE variants + 5 LIGGGHTS, two checks each
    failed = [(c.name, c.value, c.reference, c.error) for c in checks if not c.passed]
    assert not failed, failed


@pytest.mark.parametrize("bad", ['x"; import os; os.system("echo hacked") #', "a\nb", "name with spaces", "1abc"])
def test_scene_names_that_are_not_identifiers_never_reach_a_deck(bad, tmp_path):
    sc = engine_scene("undamped", P)
    sc.name = bad
    for engine in (YadeEngine(), LiggghtsEngine()):
        with pytest.raises(SceneError, match="not an identifier"):
            engine.write_deck(sc, build(engine_scene("undamped", P)), tmp_path)
    with pytest.raises(SceneError, match="not an identifier"):
        build(sc)


def test_yade_deck_is_the_fixed_program_and_data_is_numbers(tmp_path):
    sc = engine_scene("damped", P)
    YadeEngine().write_deck(sc, build(sc), tmp_path)
    from importlib import resources

    fixed = resources.files("demflow.engines.decks").joinpath("yade_discs2d.py").read_text()
    assert (tmp_path / "deck.py").read_text() == fixed
    data = json.loads((tmp_path / "scene.json").read_text())

    import re

    from helpers import json_leaves
    for v in json_leaves(data):
        assert v is None or isinstance(v, (int, float, bool)) or re.fullmatch(r"[A-Za-z][A-Za-z0-9_\-|]*", v), v


def _fake_engine(tmp_path, name, script):
    d = tmp_path / "bin"
    d.mkdir(exist_ok=True)
    exe = d / name
    exe.write_text("#!/bin/sh\n" + script)
    exe.chmod(exe.stat().st_mode | stat.S_IEXEC)
    return d


@pytest.mark.parametrize("engine_cls", [YadeEngine, LiggghtsEngine])
def test_engine_absent_gives_install_hint_and_writes_nothing(engine_cls, tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))
    e = engine_cls()
    with pytest.raises(EngineNotFound, match=f"apt-get install -y {e.package}"):
        reference.generate(CASE, "undamped", e, engine_scene("undamped", P), base=tmp_path / "refs")
    assert not (tmp_path / "refs" / CASE / "undamped" / e.name).exists()


@pytest.mark.parametrize("script, error, timeout", [
    ("sleep 30\n", EngineTimeout, 0.5),
    ("echo 'segfault in the engine' >&2; exit 3\n", EngineFailed, 30),
    ("printf '{\"rec\": {\"step\": [0, 1' > yade_out.json; exit 0\n", EngineOutputError, 30),
    ("exit 0\n", EngineOutputError, 30),
], ids=["timeout", "nonzero-exit", "truncated-output", "no-output"])
def test_engine_failures_are_clear_and_write_nothing(script, error, timeout, tmp_path, monkeypatch):
    """A program standing in for the yade executable times out, fails or truncates its output:
    the harness reports it and leaves reference_runs untouched."""
    monkeypatch.setenv("PATH", str(_fake_engine(tmp_path, "yade", script)) + os.pathsep + os.environ["PATH"])
    base = tmp_path / "refs"
    with pytest.raises(error) as e:
        reference.generate(CASE, "undamped", YadeEngine(), engine_scene("undamped", P), base=base, timeout=timeout)
    assert "yade" in str(e.value)
    assert not (base / CASE / "undamped" / "yade").exists()
    assert not any(p.name == "meta.json" for p in base.rglob("*")) if base.exists() else True


def test_liggghts_without_completion_mark_is_truncated(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(_fake_engine(tmp_path, "liggghts", "echo 'LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0)' > log.liggghts\n"))
                       + os.pathsep + os.environ["PATH"])
    with pytest.raises(EngineOutputError, match="truncated"):
        LiggghtsEngine().run(engine_scene("undamped", P), tmp_path / "w", timeout=30)


# ---------------------------------------------------------------- live engines
@pytest.mark.engines
@pytest.mark.parametrize("engine, variant", [("yade", "undamped"), ("yade", "damped"), ("liggghts", "undamped"),
                                             ("liggghts", "speed-0.36-kn1.5e8")])
def test_live_engine_reproduces_its_stored_reference(engine, variant, tmp_path):
    """Regenerate the deck, run the real engine, compare with the stored reference."""
    e = get_engine(engine)
    stored_dir = reference.location(CASE, variant, engine)
    stored = reference.load(CASE, variant, engine)
    res, run = e.run(engine_scene(variant, P), tmp_path, timeout=600)
    for deck in ("deck.py", "deck.in", "scene.json"):
        if (stored_dir / deck).exists():
            assert (tmp_path / deck).read_text() == (stored_dir / deck).read_text(), f"{deck} changed"
    s0, f0, g0 = contact_c_force(stored)
    s1, f1, g1 = contact_c_force(res)
    assert np.array_equal(s0, s1)
    assert np.max(np.abs(f1 - f0)) <= 1e-9 * np.max(np.abs(f0))
    w0 = stored.wall_forces
    w1 = res.wall_forces
    assert np.max(np.abs(w1.fx.to_numpy() - w0.fx.to_numpy())) <= 1e-9 * np.max(np.abs(w0.fx.to_numpy()))


@pytest.mark.engines
def test_live_comparison_of_all_three_engines(tmp_path):
    case = NineDiscEngines()
    case.live = True
    p = case.merged()
    res = case.run(p)
    checks = case.checks(res, p)
    assert all(c.passed for c in checks), [(c.name, c.error) for c in checks if not c.passed]
