"""YADE (Debian ``yade``, 2023.02a) on miyata-uniaxial-3d: the whole uniaxial protocol in one fixed deck.

What is expressed how (ENGINES.md "3D clumps and Hertz", the capabilities table):

- clumps by ``appendClumped`` of demflow's member spheres at demflow's insertion positions and
  orientations (the same lattice and seed: only the chaos of settling separates the beds), mass and
  principal moments set to demflow's template (YADE integrates the union's inertia itself; the deck
  gives each of YADE's principal axes the moment of demflow's axis parallel to it and records the
  worst alignment, |cos| ≥ 0.99 checked here);
- Hertz-Mindlin: ``Ip2_FrictMat_FrictMat_MindlinPhys`` with demflow's E*, G* (the pair stiffness is
  checked as :mod:`demflow.engines.yade3d` does), ``betan = ζ_n``, ``betas = ζ_t``, ``frictAngle = atan μ``;
  every member sphere's mass is set to its clump's so YADE's dashpots use the body masses as demflow's
  do; ``Law2_ScGeom_MindlinPhys_Mindlin`` (incremental shear spring, demflow's default);
- floor and plate: boxes much wider than the period with the compensated wall material of
  :func:`demflow.engines.yade3d.wall_material` (YADE's box-sphere contact uses R/2);
- NewtonIntegrator local damping = demflow's Cundall local damping (ENGINES.md: same definition),
  ``exactAsphericalRot=True``;
- trimming deletes clumps (``deleteClumpBody``) and then installs a fresh collider (the 2023.02a
  periodic-deletion hang).
"""
from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np

from .base import EngineOutputError, EngineUnsupported, atomic_json
from .uniaxial3d import protocol_numbers, read_uniaxial_output
from .yade import YadeEngine
from .yade3d import sphere_pair_stiffness, wall_material

DISCRETIZATION = 15  # appendClumped's voxels per smallest member diameter (ENGINES.md)
WATCH_EVERY = 10  # steps between the deck's checks for wall contacts YADE's collider missed (≤ 5 µm of plate travel)
AXIS_ALIGNMENT_MIN = 0.99  # |cos| between YADE's and demflow's principal axes below which the run is refused


class YadeUniaxial3DEngine(YadeEngine):
    """YADE running the uniaxial protocol of case parameters ``params`` (module docstring)."""

    deck = "yade_uniaxial3d.py"

    def __init__(self, params: dict, benchmark: bool = False):
        self.params = dict(params)
        self.benchmark = benchmark  # speed runs: the first settling stage only, timed in the deck (bench.json)

    def write_deck(self, scene, sim, deckdir: Path):
        from ..build3d import quat_to_matrix

        S = protocol_numbers(scene, sim, self.params)
        M = S["materials"]
        rock, wall = S["particle_material"], S["plane_material"]
        pp = next(p for p in S["sphere_pairs"] if p["a"] == rock and p["b"] == rock)
        sphere_pair_stiffness(pp, M)
        pw = next(p for p in S["plane_pairs"] if p["a"] == rock and p["b"] == wall)
        Ew, nuw = wall_material(M[rock]["young"], M[rock]["poisson"], pw["Estar"], pw["Gstar"])
        if S["shear_spring"] != "incremental" or S["friction_cap"] != "total":
            raise EngineUnsupported("YADE's Mindlin law stores the shear force incrementally and caps it with the "
                                    "total normal force; the scene asks for shear_spring="
                                    f"{S['shear_spring']!r}, friction_cap={S['friction_cap']!r}")
        S["yade_materials"] = {"particle": dict(young=M[rock]["young"], poisson=M[rock]["poisson"]),
                               "wall": dict(young=Ew, poisson=nuw)}
        S["yade_pairs"] = [dict(a="particle", b="particle", betan=pp["zn"], betas=pp["zt"], phi=math.atan(pp["mu"])),
                           dict(a="particle", b="wall", betan=pw["zn"], betas=pw["zt"], phi=math.atan(pw["mu"])),
                           dict(a="wall", b="wall", betan=0.0, betas=0.0, phi=0.0)]
        c = np.asarray(S["template"]["centres"])
        pos = np.asarray(S["bodies"]["pos"])
        R = quat_to_matrix(np.asarray(S["bodies"]["quat"]))  # (nb, 3, 3) body → world
        S["members"] = (pos[:, None, :] + np.einsum("bij,kj->bki", R, c)).tolist()
        S["body_axes"] = np.transpose(R, (0, 2, 1)).tolist()  # row k: body axis k in the world
        rmax = float(np.max(S["template"]["radii"]))
        top = float(pos[:, 2].max()) + float(np.max(np.linalg.norm(c, axis=1))) + rmax
        S["cell_height"] = 100.0 * top
        S["wall_thickness"] = 4.0 * rmax
        S["wall_half_size"] = 100.0 * S["protocol"]["box"]
        S["discretization"] = DISCRETIZATION
        S["watch_every"] = WATCH_EVERY
        S["benchmark"] = bool(self.benchmark)
        atomic_json(deckdir / "scene.json", S)
        deck = deckdir / "deck.py"
        deck.write_text(resources.files("demflow.engines.decks").joinpath(self.deck).read_text())
        return [deck, deckdir / "scene.json"]

    def read(self, scene, sim, outdir: Path):
        if self.benchmark:
            from .base3d import BenchmarkSummary, read_json_output

            return BenchmarkSummary(read_json_output(Path(outdir) / "bench.json", "YADE"))
        run = read_uniaxial_output(outdir, "yade", float(self.params["box"]) ** 2)
        a = float(run.meta.get("principal_axis_alignment", math.nan))
        if not a >= AXIS_ALIGNMENT_MIN:
            raise EngineOutputError(f"YADE's principal axes of a clump deviate from demflow's (|cos| = {a:.4g} < "
                                    f"{AXIS_ALIGNMENT_MIN}): its moments cannot be matched axis by axis")
        return run
