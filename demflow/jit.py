"""The one set of JIT flags every demflow kernel is compiled with.

All kernels are compiled by :func:`njit` (serial), :func:`njit_parallel`
(``prange`` loops) or :func:`njit_inline` (helpers inlined into their caller).  ``cache=True`` keeps compiled code between processes;
``fastmath`` stays off so results are bit-reproducible across runs (determinism:
same scene, same seed, same results).
"""
from __future__ import annotations

import functools
import hashlib
import os
import warnings
from pathlib import Path

import numba
from numba.core import caching as _caching

# Numba vectorises loops of math calls through Intel's SVML when it finds the library (intel-cmplr-lib-rt), and SVML
# rounds differently from libm and per CPU (demflow.libm); demflow/__init__.py asks it off before Numba is imported.
if getattr(numba.config, "USING_SVML", False):
    warnings.warn("Numba was imported before demflow with Intel's SVML in use: results may then differ between CPUs "
                  "in the last bits; set NUMBA_DISABLE_INTEL_SVML=1 before importing numba", RuntimeWarning,
                  stacklevel=2)

JIT_FLAGS = dict(cache=True, nogil=True, fastmath=False, error_model="numpy")


# Numba stamps a cached kernel with the content of the file that defines it, and nothing else: a kernel that
# calls (or inlines) a helper of another module kept its old compiled code after that helper changed (found
# 2026-11-27: run_steps_ellipsoids loaded from the cache still ran the body step of the stepping3d.py before an
# edit).  Every kernel of demflow, and of its tests and benchmarks beside it, is therefore stamped with the
# content of the whole package as well: any change to a demflow source recompiles every kernel once.
_PACKAGE = Path(__file__).resolve().parent
_STAMPED_TREES = (_PACKAGE, _PACKAGE.parent / "tests", _PACKAGE.parent / "benchmarks")


def tree_digest(root: Path) -> str:
    """SHA-256 of the paths (relative to ``root``) and contents of every ``*.py`` file under ``root``."""
    h = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        h.update(f.relative_to(root).as_posix().encode() + b"\0")
        h.update(f.read_bytes() + b"\0")
    return h.hexdigest()


@functools.lru_cache(maxsize=None)
def package_digest() -> str:
    """:func:`tree_digest` of the demflow package (once per process)."""
    return tree_digest(_PACKAGE)


# Numba's own locators, in its order (numba.core.caching); the first that takes a file gives its cache directory
_NUMBA_LOCATORS = [name for name in ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator",
                                     "IPythonCacheLocator", "ZipCacheLocator") if hasattr(_caching, name)]


class PackageStampedLocator:
    """Numba's own locator for a demflow kernel (same cache directory), with the source stamp (own file, whole
    package) instead of the own file only, and a digest of that stamp in the cache files' names.  Installed through
    Numba's public setting ``numba.config.CACHE_LOCATOR_CLASSES`` (``NUMBA_CACHE_LOCATOR_CLASSES``), ahead of the
    locators it names.

    Why the stamp is in the names: Numba unpickles a kernel's whole index, the stamp and the signatures it holds,
    before it compares the stamp, and a signature naming a type that the source no longer defines fails there
    (``AttributeError: Can't get attribute ...``) instead of being discarded as stale: found 2026-11-28, when a
    structure added to demflow.contacts.spheres and removed again left the index of ``run_steps3`` unreadable,
    and every run of a 3D scene stopped with that error until the cache was deleted by hand; an upgrade over an
    installed demflow leaves its cache files behind the same way.  An index is now read only by the source it
    was written for; the files of this kernel written for other sources are removed when it saves anew."""

    def __init__(self, base, name, py_file=None):
        self._base = base
        self._name = name  # Numba's file-name prefix of the kernel, module.qualname
        # the kernel's source file, under the name Numba's locators give it: Numba's warning that a kernel cannot be
        # cached reads it (numba.core.caching.CacheImpl.check_cachable)
        self._py_file = py_file

    def ensure_cache_path(self):
        self._base.ensure_cache_path()
        self._remove_stale()

    def get_cache_path(self):
        return self._base.get_cache_path()

    def get_source_stamp(self):
        return (self._base.get_source_stamp(), package_digest())

    def get_disambiguator(self):
        stamp = hashlib.sha256(repr(self.get_source_stamp()).encode()).hexdigest()[:12]
        return f"{self._base.get_disambiguator()}-{stamp}"

    def _remove_stale(self):
        """Remove this kernel's index and data files written for another source (another stamp in the name)."""
        before = f"{self._name}-{self._base.get_disambiguator()}"  # then "-<stamp>." now, "." before 2026-11-28
        current = f"{self._name}-{self.get_disambiguator()}."
        try:
            entries = list(os.scandir(self.get_cache_path()))
        except OSError:
            return
        for e in entries:
            if e.name.startswith((before + "-", before + ".")) and not e.name.startswith(current) \
                    and e.name.endswith((".nbi", ".nbc")):
                try:
                    os.unlink(e.path)
                except OSError:  # another process removed it, or the directory is read-only
                    pass

    @classmethod
    def from_function(cls, py_func, py_file):
        path = Path(py_file).resolve()
        if not any(path.is_relative_to(t) for t in _STAMPED_TREES):
            return None
        # Numba's own prefix of the kernel's files (numba.core.caching's _CacheImpl.get_filename_base)
        name = f"{os.path.splitext(os.path.basename(py_file))[0]}.{py_func.__qualname__}"
        name = name.replace("<", "").replace(">", "")
        for locator in _base_locators():
            base = _locator_class(locator).from_function(py_func, py_file)
            if base is not None:
                return cls(base, name, py_file)
        return None


def _locator_class(name: str):
    """A locator named as Numba's setting names it: ``package.module.Klass`` or a class of numba.core.caching."""
    if "." in name:
        import importlib

        module, klass = name.rsplit(".", 1)
        return getattr(importlib.import_module(module), klass)
    return getattr(_caching, name)


_SELF = f"{__name__}.PackageStampedLocator"


def _base_locators() -> list[str]:
    """The locators after ours in the setting (a user's own list, or Numba's)."""
    return [n.strip() for n in (numba.config.CACHE_LOCATOR_CLASSES or "").split(",") if n.strip() and n.strip() != _SELF]


def _install_locator() -> None:
    """Put :class:`PackageStampedLocator` first in Numba's setting (not in the environment, which child
    processes inherit); every decorator of this module calls it, as Numba re-reads its settings from the
    environment when that changes."""
    user = [n.strip() for n in (numba.config.CACHE_LOCATOR_CLASSES or "").split(",") if n.strip()]
    if user and user[0] == _SELF:
        return
    numba.config.CACHE_LOCATOR_CLASSES = ",".join([_SELF] + [n for n in (user or _NUMBA_LOCATORS) if n != _SELF])


_install_locator()

def njit(func):
    """Compile ``func`` (serial) with :data:`JIT_FLAGS`, its cache stamped with the package."""
    _install_locator()  # (the locator is chosen here, when caching is enabled)
    return numba.njit(**JIT_FLAGS)(func)


# Per-pair and per-disc helpers that take arrays are inlined at the Numba IR level: a compiled call
# with array arguments updates reference counts (atomic, serialising threads) on every call.
def njit_inline(func):
    """As :func:`njit`, inlined into its callers."""
    _install_locator()
    return numba.njit(inline="always", **JIT_FLAGS)(func)


# Parallel kernels and namedtuples of arrays (demflow.state): Numba 0.68 silently drops writes made
# as ``struct.field[i] = v`` inside a prange body, and in the pair kernel even writes through
# fields read into local names before the loop were lost (measured; the golden tests catch it).
# So the arrays a prange loop writes are passed to it as plain arguments; structures are read only.
def njit_parallel(func):
    """Compile ``func`` with ``parallel=True`` (its ``prange`` loops run on threads)."""
    _install_locator()
    return numba.njit(parallel=True, **JIT_FLAGS)(func)


def check_thread_count(name: str, n) -> int:
    """``n`` as a thread count: a whole number >= 1 (ValueError naming ``name`` otherwise)."""
    import numbers

    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
        raise ValueError(f"{name}={n!r} is not a number of threads; give a whole number >= 1 (at most "
                         f"{numba.config.NUMBA_NUM_THREADS} here), or None for the default")
    return int(n)


def set_threads(n: int | None) -> int:
    """Set the number of threads parallel kernels use; ``None`` keeps the default.

    Returns the number now in force.  The default is ``DEMFLOW_THREADS`` or all cores.
    """
    if n is None:
        env = os.environ.get("DEMFLOW_THREADS")
        if env:
            try:
                n = int(env)
            except ValueError:
                raise ValueError(f"DEMFLOW_THREADS={env!r} is not a whole number; set it to a number of threads "
                                 f"in 1..{numba.config.NUMBA_NUM_THREADS}, or unset it") from None
    if n is not None:
        check_thread_count("threads", n)
        if n > numba.config.NUMBA_NUM_THREADS:
            raise ValueError(
                f"threads={n} is outside 1..{numba.config.NUMBA_NUM_THREADS}; "
                "give a number of threads this machine has"
            )
        numba.set_num_threads(n)
    return numba.get_num_threads()
