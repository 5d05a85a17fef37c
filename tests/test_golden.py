"""Golden tests: today's 2D results, to the bit (the safety net of the core refactor, issue 12).

Each golden scene (``tests/golden_scenes.py``) is run and every array of its final state and of
its result tables is compared bit for bit with the file written before the refactor began
(``tests/golden/*.npz``, the commit is stored in each file).  The frictional box runs at one and
two threads: results must not depend on the thread count.  A second process must load every
kernel from Numba's on-disk cache (compile nothing).  The slow test compares every check value of
``demflow validate`` with the values it gave before the refactor.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import golden_scenes as gs  # noqa: E402

from demflow import schema  # noqa: E402


def _bits(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    if a.dtype.kind == "f":
        return a.view(np.uint64 if a.dtype.itemsize == 8 else np.uint32)
    return a


# Results that go through LAPACK (the BEM's dense LU: the saturated scene) depend in their last bits on the
# kernels OpenBLAS picks for the CPU; those scenes run in a process with the kernels pinned
# (golden_scenes.PINNED_BLAS).  Nothing else in demflow's results goes through BLAS (ζ(e) was made BLAS-free
# on 2026-11-25, tests/test_spheres3d.py); a difference here is a change of the code.
BLAS_HINT = ("scenes through LAPACK run with OpenBLAS's kernels pinned (tests/golden_scenes.py, PINNED_BLAS); "
             "elsewhere a difference is a change of the code")


def assert_same_bits(name: str, got: dict, want) -> None:
    keys = sorted(k for k in want.files if k != "commit")
    missing = sorted(set(keys) - set(got))
    assert not missing, f"{name}: arrays {missing} are gone"
    # columns a later schema version adds (demflow/schema.py) are allowed beside the golden v1 columns
    added = {f"{t}/{c}" for t in gs.TABLES for c in set(schema.columns(t, 2)) - set(schema.columns(t, 1))}
    extra = sorted(set(got) - set(keys) - added)
    assert not extra, f"{name}: arrays {extra} are new and not a schema addition"
    for k in keys:
        a, b = np.asarray(got[k]), want[k]
        assert a.shape == b.shape, f"{name} {k}: shape {a.shape} != golden {b.shape}"
        if a.dtype.kind in "US" or b.dtype.kind in "US":
            assert np.array_equal(a.astype(str), b.astype(str)), f"{name} {k}: values differ"
            continue
        assert a.dtype == b.dtype, f"{name} {k}: dtype {a.dtype} != golden {b.dtype}"
        same = _bits(a) == _bits(b)
        if not np.all(same):
            i = int(np.flatnonzero(~same.reshape(-1))[0])
            raise AssertionError(f"{name} {k}: {int((~same).sum())} entries differ from the golden file, "
                                 f"first at flat index {i}: {a.reshape(-1)[i]!r} != {b.reshape(-1)[i]!r}; "
                                 + BLAS_HINT)


@pytest.mark.parametrize("name, threads", [("box", 1), ("box", 2), ("nine_disc", 1), ("saturated", 1)])
def test_golden_bits(name, threads, tmp_path):
    if name in gs.BLAS_SCENES:
        if not gs.cpu_runs_pinned_blas():
            pytest.skip(f"{name} is checked with OpenBLAS's Haswell kernels, which this CPU cannot run (no AVX2/FMA)")
        gs.run_pinned(name, tmp_path / "got.npz")
        with np.load(tmp_path / "got.npz", allow_pickle=False) as f:
            got = {k: f[k] for k in f.files}
    else:
        got = gs.state_arrays(*gs.run(name, threads=threads))
    with np.load(gs.GOLDEN / f"{name}.npz", allow_pickle=False) as want:
        assert_same_bits(f"{name}@{threads}", got, want)


def test_golden_detects_a_change():
    """Negative control: one bit of the law changed (friction 0.5 → 0.5 + 1 ulp) must fail the box."""
    scene = gs.frictional_box()
    from dataclasses import replace

    from demflow import build

    law = scene.laws[("grain", "grain")]
    law2 = replace(law, friction=float(np.nextafter(law.friction, 1.0)))
    scene = replace(scene, laws={("grain", "grain"): law2, ("grain", "wall"): law})
    sim = build(scene).run()
    with np.load(gs.GOLDEN / "box.npz", allow_pickle=False) as want:
        with pytest.raises(AssertionError):
            assert_same_bits("box-perturbed", gs.state_arrays(sim, sim.results()), want)


def test_result_table_schema_v1():
    """Every column of today's (v1) result tables is still there with its dtype."""
    frozen = json.loads((gs.GOLDEN / "schema_v1.json").read_text())["tables"]
    _, res = gs.run("box")
    now = gs.schema(res)
    for table, cols in frozen.items():
        for c, dtype in cols.items():
            assert c in now[table], f"table {table}: column {c} is gone"
            assert now[table][c] == dtype, f"table {table}: column {c} is {now[table][c]}, was {dtype}"


_SECOND_PROCESS = textwrap.dedent("""
    import sys
    from numba.core import event
    sys.path.insert(0, {tests!r})
    import golden_scenes as gs
    with event.install_recorder("numba:compile") as rec:
        for name in ("box", "nine_disc"):
            gs.run(name)
    compiled = sorted({{ev.data["dispatcher"].py_func.__module__ + "." + ev.data["dispatcher"].py_func.__qualname__
                       for _, ev in rec.buffer if ev.is_start}})
    print(len(compiled))
    for c in compiled:
        print(c)
""")


def _compiled_in_fresh_processes(times: int, **env_extra) -> list[str]:
    """Run the dry golden scenes in ``times`` fresh processes one after the other; the last one's
    count and names of functions Numba compiled (read from its "numba:compile" events)."""
    code = _SECOND_PROCESS.format(tests=str(Path(__file__).parent))
    env = dict(os.environ, **env_extra)
    for _ in range(times):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=900)
        assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout.strip().splitlines()


def test_second_process_compiles_nothing():
    """Numba's on-disk cache survives: a second process running the dry golden scenes compiles no
    demflow kernel (the first one may, if the cache is cold)."""
    lines = _compiled_in_fresh_processes(2)
    n = int(lines[0])
    assert n == 0, f"the second process compiled {n} functions: {lines[1:]}"


@pytest.mark.slow
def test_validate_check_values_unchanged(tmp_path):
    """Every check value of `demflow validate` (fast cases) equals the value it had before the refactor
    (timings excluded).  The values were recorded where OpenBLAS runs its SkylakeX kernels, and the BEM
    cases' go through LAPACK (tests/golden_scenes.py): validate runs in a process with those kernels pinned,
    which needs a CPU with AVX-512."""
    from blas_kernels import can_run, run_under

    if not can_run("SkylakeX"):
        pytest.skip("the values were recorded with OpenBLAS's SkylakeX kernels, which need AVX-512")
    golden = json.loads((gs.GOLDEN / "validate_checks.json").read_text())["cases"]
    code = textwrap.dedent("""
        import json, sys
        from demflow.report import run_validation
        s = run_validation(json.loads(sys.argv[1]), sys.argv[2])
        json.dump({c: {k["name"]: k["value"] for k in s["cases"][c]["checks"]} for c in json.loads(sys.argv[1])},
                  open(sys.argv[3], "w"))
    """)
    out = tmp_path / "values.json"
    done = run_under("SkylakeX", ["-c", code, json.dumps(sorted(golden)), str(tmp_path / "validation"), str(out)])
    assert done.returncode == 0, done.stderr[-3000:]
    values_now = json.loads(out.read_text())
    diffs = []
    for case, values in golden.items():
        got = values_now[case]
        for name, v in values.items():
            if name not in got:
                diffs.append(f"{case}: check {name!r} is gone")
            elif got[name] != v and not (got[name] != got[name] and v != v):
                diffs.append(f"{case}: {name!r} = {got[name]!r}, was {v!r}")
    assert not diffs, "\n".join(diffs)


@pytest.mark.slow
def test_compile_detector_sees_a_cold_cache(tmp_path):
    """Negative control of the test above: with an empty cache directory the detector counts the
    kernels compiled (measured: 106 functions)."""
    lines = _compiled_in_fresh_processes(1, NUMBA_CACHE_DIR=str(tmp_path))
    assert int(lines[0]) > 10
