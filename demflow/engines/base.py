"""The interface every engine (demflow, YADE, LIGGGHTS) implements.

``engine.run(scene, workdir)`` writes the deck(s) for a scene, runs the engine (subprocess,
timeout, captured log, exit status checked, version recorded) and reads its outputs into
the same :class:`~demflow.results.Results` tables demflow produces, so analysis never
knows which engine produced a table.

Decks are fixed programs; the scene reaches them only as ``scene.json``, numbers and
identifiers that :func:`scene_numbers` has validated.  A scene name or label is never
pasted into a deck's code.
"""
from __future__ import annotations

import hashlib
import math
import os
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path


from ..atomic import write_json_atomic
from ..scene import Scene, SceneError, check_identifier


class EngineError(RuntimeError):
    """An engine could not produce a result; the message says why and what to do."""


class EngineNotFound(EngineError):
    pass


class EngineTimeout(EngineError):
    pass


class EngineFailed(EngineError):
    pass


class EngineOutputError(EngineError):
    pass


class EngineUnsupported(EngineError):
    """The scene uses something this engine cannot express (see :mod:`demflow.engines.capabilities`)."""


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _num(v, what):
    f = float(v)
    if not math.isfinite(f):
        raise SceneError(f"{what}={v!r} is not a finite number; engine decks take finite numbers only")
    return f


def scene_numbers(scene: Scene, sim) -> dict:
    """The scene as plain numbers and identifiers (validated), from a built simulation.

    ``sim`` is ``demflow.build(scene)``: the engines get the same masses, inertias, laws per
    material pair, time step and wall kinematics demflow uses.
    """
    check_identifier("scene", scene.name)
    mats = [check_identifier("material", m) for m in sim.material_names]
    walls = []
    for w, wall in enumerate(scene.walls):
        if wall.servo is not None:
            raise EngineUnsupported(f"wall {wall.name!r} is a servo wall; engine decks support prescribed motion only")
        phases = []
        for ph in wall.phases:
            phases.append(dict(cycles=int(ph.cycles), vx=_num(ph.velocity[0], "phase vx"),
                               vy=_num(ph.velocity[1], "phase vy"), omega=_num(ph.omega, "phase omega"),
                               pivot=None if ph.pivot is None else [_num(ph.pivot[0], "pivot"), _num(ph.pivot[1], "pivot")]))
        walls.append(dict(name=check_identifier("wall", wall.name), px=float(sim.wpx[w]), py=float(sim.wpy[w]),
                          ex=float(sim.wex[w]), ey=float(sim.wey[w]), h1=float(sim.wh1[w]), h2=float(sim.wh2[w]),
                          material=mats[int(sim.wmat[w])], phases=phases))
    t = sim.t
    laws = {}
    for a in range(len(mats)):
        for b in range(a, len(mats)):
            if t["kn"][a, b] > 0:
                laws[f"{mats[a]}|{mats[b]}"] = {k: float(t[k][a, b]) for k in ("kn", "ks", "cn", "cs", "mu", "coh")}
    return dict(
        name=scene.name, dt=float(sim.dt), n_steps=int(scene.n_steps), gravity=[float(sim.gx), float(sim.gy)],
        every=int(scene.outputs.every), snapshots=[int(s) for s in scene.outputs.snapshots],
        track=[[int(a), int(b)] for a, b in sim.track], n_discs=int(sim.n),
        discs=dict(x=sim.x.tolist(), y=sim.y.tolist(), r=sim.r.tolist(), mass=sim.mass.tolist(),
                   inertia=sim.inertia.tolist(), vx=sim.vx.tolist(), vy=sim.vy.tolist(), omega=sim.om.tolist(),
                   material=[mats[int(m)] for m in sim.mat]),
        damping=dict(C=sim.C.tolist(), Cr=sim.Cr.tolist()),
        materials=mats, laws=laws, walls=walls,
        normal=scene.contact_model.normal, sliding=scene.contact_model.sliding,
    )


@dataclass
class EngineRun:
    """What one engine run did: for meta.json."""

    engine: str
    version: str
    command: list
    wall_time_s: float
    date: str
    inputs: dict = field(default_factory=dict)
    outputs: dict = field(default_factory=dict)


class Engine:
    """Base class: subclasses set ``name``, ``executable``, ``package`` and implement
    ``write_deck``, ``command``, ``read`` and ``version``."""

    name = ""
    executable = ""
    package = ""

    def path(self) -> str:
        exe = shutil.which(self.executable)
        if exe is None:
            raise EngineNotFound(
                f"{self.name} is not installed: no {self.executable!r} on PATH. Install it with "
                f"`apt-get install -y {self.package}` (as root), or run scripts/install-engines.sh"
            )
        return exe

    def available(self) -> bool:
        return shutil.which(self.executable) is not None

    def version(self) -> str:
        raise NotImplementedError

    def write_deck(self, scene: Scene, sim, deckdir: Path) -> list[Path]:
        raise NotImplementedError

    def command(self, deckdir: Path) -> list[str]:
        raise NotImplementedError

    def read(self, scene: Scene, sim, outdir: Path):
        raise NotImplementedError

    def run(self, scene: Scene, workdir: str | os.PathLike, *, timeout: float = 600.0, sim=None):
        """Write the deck into ``workdir``, run the engine there, return (Results, EngineRun).

        Raises EngineNotFound, EngineTimeout, EngineFailed (non-zero exit, log tail quoted)
        or EngineOutputError (missing or truncated output).
        """
        from ..build import build

        self.path()
        sim = sim or build(scene)
        workdir = Path(workdir)
        workdir.mkdir(parents=True, exist_ok=True)
        inputs = self.write_deck(scene, sim, workdir)
        cmd = self.command(workdir)
        log = workdir / "engine.log"
        t0 = time.perf_counter()
        env = dict(os.environ, OMP_NUM_THREADS="1")
        try:
            with open(log, "w") as fh:
                proc = subprocess.run(cmd, cwd=workdir, stdout=fh, stderr=subprocess.STDOUT, timeout=timeout,
                                      stdin=subprocess.DEVNULL, env=env)
        except subprocess.TimeoutExpired:
            raise EngineTimeout(f"{self.name} did not finish scene {scene.name!r} within {timeout} s "
                                f"(log: {log}); raise the timeout or shorten the run") from None
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            tail = log.read_text(errors="replace")[-2000:]
            raise EngineFailed(f"{self.name} exited with status {proc.returncode} on scene {scene.name!r}; "
                               f"last lines of {log}:\n{tail}")
        res = self.read(scene, sim, workdir)
        run = EngineRun(engine=self.name, version=self.version(), command=cmd, wall_time_s=round(wall, 3),
                        date=time.strftime("%Y-%m-%dT%H:%M:%S"),
                        inputs={p.name: sha256(p) for p in inputs})
        res.meta.update(engine=self.name, engine_version=run.version)
        return res, run


def atomic_json(path: Path, obj) -> None:
    """An engine file's JSON (decks' scene numbers, engine outputs; indent 1), written atomically."""
    write_json_atomic(path, obj, indent=1)
