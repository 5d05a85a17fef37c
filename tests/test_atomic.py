"""Atomic writes (demflow.atomic): whole or nothing, no temporary files left, the permissions of an ordinary file.

Before, every writer had its own temporary-file code: reports, checkpoints and VTK collections came out readable
by their owner only (``tempfile.mkstemp`` creates files 0600), and a write that failed half-way left its
temporary file beside the target."""
import os
import stat

import numpy as np
import pytest

import demflow as df
from demflow.atomic import write_atomic, write_json_atomic, write_text_atomic
from demflow.checkpoint_scene import read_checkpoint, write_checkpoint


@pytest.fixture
def umask022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def _mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


def test_a_written_file_has_an_ordinary_files_permissions(tmp_path, umask022):
    ordinary = tmp_path / "ordinary.txt"
    ordinary.write_text("x")
    f = write_text_atomic(tmp_path / "sub" / "a.txt", "Δt × 2\n")  # the parent is created
    assert f.read_text(encoding="utf-8") == "Δt × 2\n"
    assert _mode(f) == _mode(ordinary) == 0o644


def test_a_failed_write_keeps_the_old_file_and_leaves_nothing_behind(tmp_path):
    target = write_text_atomic(tmp_path / "a.json", "old")

    def half_then_fail(tmp):
        with open(tmp, "w") as fh:
            fh.write("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        write_atomic(target, half_then_fail)
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]


def test_json_is_serialised_before_the_file_is_touched(tmp_path):
    target = write_json_atomic(tmp_path / "a.json", {"a": 1})
    with pytest.raises(TypeError):
        write_json_atomic(target, {"a": object()})
    assert target.read_text() == '{"a": 1}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]


def test_checkpoints_round_trip_with_ordinary_permissions(tmp_path, umask022):
    a = np.arange(6.0).reshape(2, 3)
    f = write_checkpoint(tmp_path / "c.npz", {"scene": "s", "step": 3}, {"pos": a})
    meta, state = read_checkpoint(f)
    assert meta == {"scene": "s", "step": 3} and np.array_equal(state["pos"], a)
    assert _mode(f) == 0o644
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.npz"]


def test_a_simulations_checkpoint_and_the_validation_report_are_readable_by_others(tmp_path, umask022):
    sc = df.Scene3D(name="two", spheres=df.Spheres(x=[0.0, 0.1], y=[0.0, 0.0], z=[0.0, 0.0], radius=[0.01, 0.01],
                                                   material="m"),
                    materials={"m": df.Material(density=2650.0, young=7e9, poisson=0.2)},
                    laws={("m", "m"): df.HertzMindlinLaw(friction=0.3, restitution=0.5)}, n_steps=10)
    sim = df.build(sc).run()
    assert _mode(sim.save_checkpoint(tmp_path / "two.npz")) == 0o644
    from demflow.report.validation import run_validation

    run_validation(["ch3-impulse-chain"], outdir=tmp_path / "report")
    for name in ("index.html", "summary.json"):
        assert _mode(tmp_path / "report" / name) == 0o644, name


def test_the_umask_is_read_at_each_write_not_at_import(tmp_path):
    """A process that sets its umask after importing demflow (a server, a shared-group run) gets files with
    that umask; before, the mask of import time was used for every write."""
    old = os.umask(0o077)
    try:
        private = write_text_atomic(tmp_path / "private.txt", "x")
        os.umask(0o002)
        group = write_text_atomic(tmp_path / "group.txt", "x")
    finally:
        os.umask(old)
    assert _mode(private) == 0o600
    assert _mode(group) == 0o664
