"""Engines that run a demflow scene: demflow itself, YADE and LIGGGHTS (same result tables)."""
from __future__ import annotations

import time

from .base import (Engine, EngineError, EngineFailed, EngineNotFound, EngineOutputError, EngineRun, EngineTimeout,
                   EngineUnsupported)
from .liggghts import LiggghtsEngine
from .yade import YadeEngine


class DemflowEngine(Engine):
    """demflow itself, behind the same interface (no subprocess)."""

    name = "demflow"

    def path(self):
        return "demflow"

    def available(self):
        return True

    def version(self):
        from .. import __version__

        return __version__

    def run(self, scene, workdir=None, *, timeout=None, sim=None):
        from ..build import build

        t0 = time.perf_counter()
        res = (sim or build(scene)).run().results()
        run = EngineRun(engine="demflow", version=self.version(), command=["demflow"],
                        wall_time_s=round(time.perf_counter() - t0, 3), date=time.strftime("%Y-%m-%dT%H:%M:%S"))
        return res, run


ENGINES: dict[str, Engine] = {"demflow": DemflowEngine(), "yade": YadeEngine(), "liggghts": LiggghtsEngine()}


def get_engine3d(name: str, **options) -> Engine:
    """The engine that runs 3D sphere scenes (:class:`~demflow.scene3d.Scene3D`): demflow, YADE or LIGGGHTS;
    ``options`` go to its constructor (YADE: ``compensate_walls``, ``avoid_ratcheting``)."""
    from .base3d import Demflow3DEngine
    from .liggghts3d import Liggghts3DEngine
    from .yade3d import Yade3DEngine

    classes = {"demflow": Demflow3DEngine, "yade": Yade3DEngine, "liggghts": Liggghts3DEngine}
    if name not in classes:
        raise EngineError(f"unknown engine {name!r}; choose one of {', '.join(classes)}")
    return classes[name](**options)


def get_engine(name: str) -> Engine:
    if name not in ENGINES:
        raise EngineError(f"unknown engine {name!r}; choose one of {', '.join(ENGINES)}")
    return ENGINES[name]


__all__ = ["ENGINES", "get_engine", "get_engine3d", "Engine", "EngineError", "EngineFailed", "EngineNotFound", "EngineOutputError",
           "EngineTimeout", "EngineUnsupported", "DemflowEngine", "YadeEngine", "LiggghtsEngine"]
