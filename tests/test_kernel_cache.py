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
