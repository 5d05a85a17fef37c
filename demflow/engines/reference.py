"""Stored reference runs: ``reference_runs/<case>/<variant>/<engine>/``.

Each holds the deck the engine ran, its log, the parsed tables (Parquet) and ``meta.json``
(engine, version, command, wall time, date, sha256 of every input and output file), and
``meta.sha256``, the sha256 of ``meta.json`` itself (``sha256sum -c meta.sha256`` checks it), so
that meta.json, which the tables' metadata is loaded from, is covered by the hash check too.
:func:`generate` writes one only after the engine succeeded and its output parsed (into a
temporary directory renamed into place), so a failed run leaves nothing behind;
:func:`load` verifies every hash before use.  :func:`seal` adds ``meta.sha256`` to a reference
stored before it existed, after verifying every other file (``demflow reference CASE --engine E
--seal``).
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

from ..atomic import write_text_atomic
from ..results import Results
from .base import EngineError, atomic_json, sha256

README = """# Reference run: {case} / {variant} / {engine}

Produced by `demflow reference {case} --engine {engine} --variant {variant}` with {engine} {version}
on {date} ({wall_time_s} s). The deck (`deck.*`, `scene.json`, meshes) is exactly what the engine
ran; `engine.log` its output; `*.parquet` the parsed tables in demflow's common format.
`meta.json` lists the sha256 of every file and `meta.sha256` that of `meta.json`: demflow refuses a
reference whose files do not match (regenerate it with the command above; never edit by hand).
"""

SEAL = "meta.sha256"


def root() -> Path:
    """The reference_runs/ directory: $DEMFLOW_REFERENCE_RUNS, ./reference_runs, or the source tree's."""
    env = os.environ.get("DEMFLOW_REFERENCE_RUNS")
    if env:
        return Path(env)
    here = Path.cwd() / "reference_runs"
    if here.is_dir():
        return here
    return Path(__file__).resolve().parents[2] / "reference_runs"


def location(case: str, variant: str, engine: str, base: Path | None = None) -> Path:
    return (base or root()) / case / variant / engine


def generate(case: str, variant: str, engine, scene, *, params: dict | None = None, base: Path | None = None,
             timeout: float = 600.0) -> Path:
    """Run ``engine`` on ``scene`` and store the result; returns the reference directory."""
    dest = location(case, variant, engine.name, base)
    made = [p for p in (dest.parent, dest.parent.parent) if not p.exists()]  # removed again on failure
    dest.parent.mkdir(parents=True, exist_ok=True)
    try:
        _generate(case, variant, engine, scene, params, dest, timeout)
    except BaseException:
        for p in made:
            if p.is_dir() and not any(p.iterdir()):
                p.rmdir()
        raise
    return dest


def _generate(case, variant, engine, scene, params, dest: Path, timeout: float) -> None:
    with tempfile.TemporaryDirectory(dir=dest.parent, prefix=f".{engine.name}-") as tmp:
        work = Path(tmp) / "work"
        res, run = engine.run(scene, work, timeout=timeout)
        out = Path(tmp) / "ref"
        out.mkdir()
        for f in work.iterdir():
            # every input the engine declared, the deck(s), the engine's logs (one per invocation: engine.log or engine1.log, engine2.log, ...;
            # LIGGGHTS's own log.liggghts, log1.liggghts, ...), the numbers and the meshes
            if (f.name == "scene.json" or f.name in run.inputs or f.name.startswith("deck") or f.suffix == ".stl"
                    or (f.name.startswith("engine") and f.suffix == ".log")
                    or (f.name.startswith("log") and f.suffix == ".liggghts")):
                shutil.copy2(f, out / f.name)
        res.meta.update(case=case, variant=variant, params=params)
        res.save(out)
        files = sorted(p.name for p in out.iterdir() if p.name != "meta.json")
        meta = dict(case=case, variant=variant, engine=run.engine, engine_version=run.version, command=run.command,
                    wall_time_s=run.wall_time_s, date=run.date, inputs=run.inputs,
                    files={f: sha256(out / f) for f in files}, results_meta=res.meta)
        (out / "meta.json").unlink(missing_ok=True)
        atomic_json(out / "meta.json", meta)
        (out / "README.md").write_text(README.format(case=case, variant=variant, engine=run.engine, version=run.version,
                                                     date=run.date, wall_time_s=run.wall_time_s))
        meta["files"]["README.md"] = sha256(out / "README.md")
        atomic_json(out / "meta.json", meta)
        _write_seal(out)
        if dest.exists():
            old = Path(tmp) / "old"
            dest.rename(old)
        out.rename(dest)


def _write_seal(path: Path) -> None:
    """meta.sha256: the sha256 of meta.json, in sha256sum's format, written atomically."""
    write_text_atomic(path / SEAL, f"{sha256(path / 'meta.json')}  meta.json\n")


def _verify_files(path: Path) -> dict:
    """Check every file meta.json lists against its sha256; return the meta."""
    meta_f = path / "meta.json"
    if not meta_f.exists():
        raise EngineError(f"no stored reference at {path}; generate it with `demflow reference ...`")
    try:
        meta = json.loads(meta_f.read_text())
        files = dict(meta["files"])
        how = f"demflow reference {meta['case']} --engine {meta['engine']} --variant {meta['variant']}"
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise EngineError(f"stored reference {path} fails its hash check at meta.json (unreadable: {e}); regenerate "
                          "it with `demflow reference CASE --engine ENGINE --variant VARIANT`") from None
    for name, digest in files.items():
        f = path / name
        if not f.exists() or sha256(f) != digest:
            raise EngineError(
                f"stored reference {path} fails its hash check at {name} (edited by hand or corrupt); "
                f"regenerate it: {how}")
    return meta


def verify(path: Path) -> dict:
    """Check every file of a stored reference against meta.json, and meta.json against meta.sha256;
    return the meta."""
    seal_f = path / SEAL
    if (path / "meta.json").exists() and not seal_f.exists():
        raise EngineError(f"stored reference {path} has no {SEAL}, so its meta.json is not covered by a hash (stored "
                          "before issue 19); seal it, which verifies every other file first: demflow reference CASE "
                          "--engine ENGINE --variant VARIANT --seal (or regenerate it)")
    if seal_f.exists():
        digest = seal_f.read_text().split()[:1]
        if not (path / "meta.json").exists() or digest != [sha256(path / "meta.json")]:
            raise EngineError(f"stored reference {path} fails its hash check at meta.json (edited by hand or corrupt; "
                              f"{SEAL} does not match); regenerate it with `demflow reference`")
    return _verify_files(path)


def seal(path: Path) -> bool:
    """Write meta.sha256 for a reference stored without it, after every file meta.json lists passes its
    hash check; True if written, False if the reference was sealed already (and the seal matches)."""
    if (path / SEAL).exists():
        verify(path)
        return False
    _verify_files(path)
    _write_seal(path)
    return True


def load(case: str, variant: str, engine: str, base: Path | None = None, loader=None) -> Results:
    """The verified tables of a stored reference (``loader(path)`` reads them: default
    :meth:`Results.load`; 3D trajectories: :meth:`demflow.engines.base3d.Trajectory3D.load`)."""
    path = location(case, variant, engine, base)
    meta = verify(path)
    res = (loader or Results.load)(path)
    res.meta.update(reference=str(path), engine_version=meta["engine_version"], reference_date=meta["date"])
    return res


def available(case: str, base: Path | None = None) -> dict:
    """{variant: [engines]} of the references stored for ``case``."""
    out = {}
    d = (base or root()) / case
    if d.is_dir():
        for v in sorted(p for p in d.iterdir() if p.is_dir()):
            engines = sorted(e.name for e in v.iterdir() if (e / "meta.json").exists())
            if engines:
                out[v.name] = engines
    return out
