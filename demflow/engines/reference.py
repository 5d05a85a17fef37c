"""Stored reference runs: ``reference_runs/<case>/<variant>/<engine>/``.

Each holds the deck the engine ran, its log, the parsed tables (Parquet) and ``meta.json``
(engine, version, command, wall time, date, sha256 of every input and output file).
:func:`generate` writes one only after the engine succeeded and its output parsed (into a
temporary directory renamed into place), so a failed run leaves nothing behind;
:func:`load` verifies every hash before use.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

from ..results import Results
from .base import EngineError, atomic_json, sha256

README = """# Reference run: {case} / {variant} / {engine}

Produced by `demflow reference {case} --engine {engine} --variant {variant}` with {engine} {version}
on {date} ({wall_time_s} s). The deck (`deck.*`, `scene.json`, meshes) is exactly what the engine
ran; `engine.log` its output; `*.parquet` the parsed tables in demflow's common format.
`meta.json` lists the sha256 of every file: demflow refuses a reference whose files do not
match (regenerate it with the command above; never edit by hand).
"""


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
    dest.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=dest.parent, prefix=f".{engine.name}-") as tmp:
        work = Path(tmp) / "work"
        res, run = engine.run(scene, work, timeout=timeout)
        out = Path(tmp) / "ref"
        out.mkdir()
        for f in work.iterdir():
            if f.name in ("scene.json", "engine.log", "log.liggghts") or f.name.startswith("deck") or f.suffix == ".stl":
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
        if dest.exists():
            old = Path(tmp) / "old"
            dest.rename(old)
        out.rename(dest)
    return dest


def verify(path: Path) -> dict:
    """Check every file of a stored reference against meta.json; return the meta."""
    meta_f = path / "meta.json"
    if not meta_f.exists():
        raise EngineError(f"no stored reference at {path}; generate it with `demflow reference ...`")
    meta = json.loads(meta_f.read_text())
    for name, digest in meta["files"].items():
        f = path / name
        if not f.exists() or sha256(f) != digest:
            raise EngineError(
                f"stored reference {path} fails its hash check at {name} (edited by hand or corrupt); "
                f"regenerate it: demflow reference {meta['case']} --engine {meta['engine']} --variant {meta['variant']}")
    return meta


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
