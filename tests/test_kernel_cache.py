"""The on-disk kernel cache is stamped with the whole package (demflow.jit.PackageStampedLocator).

Numba alone stamps a cached kernel with its own file: a kernel that inlines a helper of another module ran
the helper's old code after the helper changed (found 2026-11-27: the ellipsoid cycle kept the body step of
stepping3d.py from before an edit, and its golden test passed on the stale kernel)."""
from __future__ import annotations

from pathlib import Path

import demflow  # noqa: F401  (the locator is installed on import)
import demflow.jit as jit


def test_tree_digest_changes_with_any_file_of_the_tree(tmp_path: Path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "sub" / "b.py").write_text("y = 2\n")
    d0 = jit.tree_digest(tmp_path)
    assert jit.tree_digest(tmp_path) == d0
    (tmp_path / "sub" / "b.py").write_text("y = 3\n")  # another module than the kernel's
    d1 = jit.tree_digest(tmp_path)
    assert d1 != d0
    (tmp_path / "sub" / "b.py").rename(tmp_path / "b.py")  # same content, another path
    assert jit.tree_digest(tmp_path) not in (d0, d1)
    (tmp_path / "notes.txt").write_text("not source")
    assert jit.tree_digest(tmp_path) == jit.tree_digest(tmp_path)


def test_demflow_kernels_carry_the_package_stamp():
    from demflow.stepping3d import body_step
    from demflow.stepping_ellipsoids import run_steps_ellipsoids

    for kernel in (run_steps_ellipsoids, body_step):
        loc = kernel._cache._impl.locator
        assert isinstance(loc, jit.PackageStampedLocator)
        own, package = loc.get_source_stamp()
        assert package == jit.package_digest() == jit.tree_digest(Path(jit.__file__).resolve().parent)
        assert Path(loc.get_cache_path()).is_dir()


def test_a_kernel_numba_cannot_cache_gets_numbas_warning_not_an_attribute_error():
    """Numba's warning that a kernel cannot be cached (it uses dynamic globals, e.g. ``numba.get_num_threads()``
    inside the kernel) names the kernel's file through its locator's ``_py_file``: the stamped locator had none,
    and the warning's path raised AttributeError instead (found 2026-12-03 with such a kernel in demflow/)."""
    import demflow.stepping3d
    from demflow.stepping3d import body_step

    loc = body_step._cache._impl.locator
    assert isinstance(loc, jit.PackageStampedLocator)
    assert Path(loc._py_file).resolve() == Path(demflow.stepping3d.__file__).resolve()


def test_other_kernels_keep_numbas_locator(tmp_path: Path):
    """A user's kernel outside demflow's tree keeps Numba's own stamp."""
    import importlib.util

    src = tmp_path / "userkernel.py"
    src.write_text("import numba\n@numba.njit(cache=True)\ndef f(x):\n    return x + 1\n")
    spec = importlib.util.spec_from_file_location("userkernel", src)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.f(1) == 2
    assert not isinstance(mod.f._cache._impl.locator, jit.PackageStampedLocator)


def test_the_stamp_survives_numba_rereading_its_settings(monkeypatch):
    """Numba re-reads its settings when a NUMBA_* variable changes (and resets the locator setting then); every
    demflow decorator puts the locator back."""
    import numba

    monkeypatch.setenv("NUMBA_DEBUG_CACHE", "0")
    numba.core.config.reload_config()
    assert "PackageStampedLocator" not in (numba.config.CACHE_LOCATOR_CLASSES or "")

    def add_one(x):
        return x + 1

    kernel = jit.njit(add_one)
    assert kernel(1) == 2
    assert isinstance(kernel._cache._impl.locator, jit.PackageStampedLocator)


def _unreadable_index() -> bytes:
    """An index as Numba writes it (its version, then the pickled stamp and signatures) whose signatures name a type
    the source no longer defines: unpickling it raises AttributeError."""
    import pickle

    import numba

    return pickle.dumps(numba.__version__, protocol=-1) + b"cdemflow.jit\nNoSuchStructure\n."


def test_an_index_written_for_another_source_is_never_read():
    """Numba unpickles an index before it compares its stamp: an index whose signatures name a type that is gone
    stopped every call of the kernel with AttributeError (found 2026-11-28 with run_steps3).  The stamp is in the
    cache files' names now: the kernel compiles anew, and its files written for other sources are removed."""
    import sys

    def add_two(x):
        return x + 2

    kernel = jit.njit(add_two)
    loc = kernel._cache._impl.locator
    assert isinstance(loc, jit.PackageStampedLocator)
    cache = Path(loc.get_cache_path())
    cache.mkdir(parents=True, exist_ok=True)
    base = f"{loc._name}-{loc._base.get_disambiguator()}"
    py = f".py{sys.version_info[0]}{sys.version_info[1]}{getattr(sys, 'abiflags', '')}"
    current = f"{loc._name}-{loc.get_disambiguator()}{py}"
    assert current.startswith(base + "-") and current != base + py
    for f in cache.glob(current + "*"):  # compile and save anew in this test
        f.unlink()
    stale = [cache / f"{base}{py}.nbi", cache / f"{base}{py}.1.nbc",  # the names Numba gave before
             cache / f"{base}-000000000000{py}.nbi"]  # another stamp
    for f in stale:
        f.write_bytes(_unreadable_index())
    other = cache / f"{base}0{py}.nbi"  # another kernel's (line number 10x): kept
    other.write_bytes(b"")
    try:
        assert kernel(1) == 3
        assert (cache / f"{current}.nbi").is_file()
        assert [f for f in stale if f.exists()] == []
        assert other.exists()
    finally:
        for f in stale + [other]:
            f.unlink(missing_ok=True)
