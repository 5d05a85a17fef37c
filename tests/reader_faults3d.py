"""Engine outputs of the 3D readers for the reader fuzz suite (issue 19, 3D half).

The fixtures in tests/fixtures/engine_outputs/{yade3d,liggghts3d}/ are the raw outputs of real YADE
and LIGGGHTS runs of :func:`fixture_scene` (the conformance-3d oblique-plane scene: a sphere sliding
on an inclined plane, 60 steps, recorded every 10; YADE in its incremental shear-spring mode,
LIGGGHTS in its total one), written by :func:`regenerate` (``python tests/reader_faults3d.py``;
needs both engines).  They are corrupted by :func:`reader_faults.corrupt` exactly like the 2D ones.
"""
from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "engine_outputs"
FILES = {"yade3d": ("yade_out.json",),
         "liggghts3d": ("log.liggghts", "scene.json", "spheres.txt", "planes.txt")}
VARIANT = {"yade3d": "oblique-plane", "liggghts3d": "oblique-plane-total"}
N_STEPS, EVERY = 60, 10


def fixture_scene(engine: str):
    from demflow.cases.conformance_3d import PARAMS, scene

    sc = scene(VARIANT[engine], PARAMS)
    sc.name = "reader-fixture-3d"
    sc.n_steps = N_STEPS
    sc.outputs = dataclasses.replace(sc.outputs, every=EVERY)
    return sc


def engine_of(engine: str):
    from demflow.engines.liggghts3d import Liggghts3DEngine
    from demflow.engines.yade3d import Yade3DEngine

    return {"yade3d": Yade3DEngine, "liggghts3d": Liggghts3DEngine}[engine]()


def read(engine: str, sim, outdir: Path):
    return engine_of(engine).read(sim.scene, sim, outdir)


def corrupted_dir(engine: str, dest: Path, rng) -> tuple[str, str]:
    """Copy the fixture outputs into ``dest`` with one file corrupted; returns (file, kind)."""
    from reader_faults import corrupted_copy

    return corrupted_copy(FIXTURES / engine, FILES[engine], dest, rng)


def regenerate(dest: Path = FIXTURES) -> None:
    """Run YADE and LIGGGHTS on :func:`fixture_scene` and keep their raw outputs as the fixtures."""
    import tempfile

    for engine in FILES:
        with tempfile.TemporaryDirectory() as tmp:
            engine_of(engine).run(fixture_scene(engine), Path(tmp), timeout=600)
            out = dest / engine
            out.mkdir(parents=True, exist_ok=True)
            for name in FILES[engine]:
                shutil.copy2(Path(tmp) / name, out / name)


if __name__ == "__main__":
    regenerate()
