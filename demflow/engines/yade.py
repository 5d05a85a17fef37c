"""YADE (Debian package ``yade``, 2023.02a): deck writer, runner and reader.

How a demflow scene is expressed (see :mod:`demflow.engines.capabilities`, which the deck writer
consults to refuse what YADE cannot express):
discs are spheres with ``blockedDOFs = 'zXY'`` given the disc mass ρπR² and inertia ½mR²;
contact values per material pair are split into per-material ``ViscElMat`` values that YADE
combines in series (k = k₁k₂/(k₁+k₂)) and friction angles it combines by the minimum;
walls are fixed boxes moved kinematically; global damping is applied as the extra force that
turns YADE's explicit update into thesis eq 2.27.  The normal force is kN × overlap
(demflow ``ContactModel(normal="overlap")``) and sliding follows the C&S rule.
"""
from __future__ import annotations

import json
import math
import subprocess
from importlib import resources
from pathlib import Path

import numpy as np

from .base import Engine, EngineOutputError, EngineUnsupported, atomic_json, scene_numbers
from .capabilities import refuse_inexpressible
from .tables import results_from_records


def split_in_series(pairs: dict, disc_mats: list, wall_mats: list, key: str) -> dict:
    """Per-material values v_m such that v_a v_b / (v_a + v_b) equals each pair's value.

    Disc materials get twice their self-contact value; each wall material is solved from its
    contact with the first disc material and every other pair is checked.
    """
    vals = {}
    for d in disc_mats:
        vals[d] = 2.0 * pairs[(d, d)][key] if (d, d) in pairs else None
    ref = next((d for d in disc_mats if vals[d] is not None), None)
    for d in disc_mats:
        if vals[d] is None:  # a disc material with no self contact: fit it to the reference disc material
            pv = pairs[(ref, d)][key]
            vals[d] = 0.0 if pv == 0 else _partner(vals[ref], pv, key)
    for w in wall_mats:
        d = disc_mats[0]
        pv = pairs[(d, w)][key]
        vals[w] = 0.0 if pv == 0 else _partner(vals[d], pv, key)
    for (a, b), law in pairs.items():
        va, vb = vals[a], vals[b]
        got = 0.0 if va == 0 or vb == 0 else va * vb / (va + vb)
        if not math.isclose(got, law[key], rel_tol=1e-12, abs_tol=0.0):
            raise EngineUnsupported(
                f"YADE combines {key} in series per material; no per-material values reproduce pair "
                f"({a}, {b}) {key}={law[key]} together with the other pairs (capabilities feature "
                f"'pair-stiffness'); give the pairs values of the form v_a v_b/(v_a + v_b), or run LIGGGHTS, "
                f"which takes a table per type pair")
    return vals


def _materials_in_series(pairs: dict, disc_mats: list, wall_mats: list) -> dict:
    """Per-material ViscElMat values (kn, ks, cn, cs, friction angle φ) that YADE's rules (values in series,
    the smaller angle) turn into every pair's law; EngineUnsupported where none do."""
    ym = {m: {} for m in disc_mats + wall_mats}
    for key in ("kn", "ks", "cn", "cs"):
        vals = split_in_series(pairs, disc_mats, wall_mats, key)
        for m in ym:
            ym[m][key] = vals[m]
    # friction: the pair uses the smaller of the two angles.  A material with a law against
    # itself takes that angle; any other the smallest angle of its pairs (then checked)
    for m in ym:
        ym[m]["phi"] = math.atan(pairs[(m, m)]["mu"]) if (m, m) in pairs else math.pi / 2
    for (a, b), law in pairs.items():
        phi = math.atan(law["mu"])
        for m in (a, b):
            if (m, m) not in pairs:
                ym[m]["phi"] = min(ym[m]["phi"], phi)
    for (a, b), law in pairs.items():
        if not math.isclose(math.tan(min(ym[a]["phi"], ym[b]["phi"])), law["mu"], rel_tol=1e-12, abs_tol=1e-15):
            raise EngineUnsupported(f"YADE takes the smaller friction angle of two materials; pair ({a}, {b}) "
                                    f"tan φ = {law['mu']} cannot be expressed with the other pairs "
                                    f"(capabilities feature 'pair-friction'); make disc-wall friction at most "
                                    f"the disc-disc friction, or run LIGGGHTS (a table per type pair)")
    return ym


def _partner(v_known, v_pair, key):
    if v_known is None or v_known <= v_pair:
        raise EngineUnsupported(
            f"YADE cannot express pair {key}={v_pair} against a material value {v_known}: values combine in series "
            f"(capabilities feature 'pair-stiffness'), so the pair value must be below the disc material's "
            f"(2 × the disc-disc value); lower the disc-wall {key} or run LIGGGHTS")
    return v_known * v_pair / (v_known - v_pair)


class YadeEngine(Engine):
    name = "yade"
    executable = "yade"
    package = "yade"

    def version(self) -> str:
        out = subprocess.run([self.path(), "--version"], capture_output=True, text=True, timeout=60)
        for line in out.stdout.splitlines():
            if "version" in line.lower() or line.strip()[:1].isdigit():
                return line.strip()
        return out.stdout.strip()[:80]

    def write_deck(self, scene, sim, deckdir: Path):
        refuse_inexpressible(self.name, scene)
        S = scene_numbers(scene, sim)
        pairs = {}
        for key, law in S["laws"].items():
            a, b = key.split("|")
            pairs[(a, b)] = law
            pairs[(b, a)] = law
        disc_mats = sorted(set(S["discs"]["material"]))
        wall_mats = sorted({w["material"] for w in S["walls"]} - set(disc_mats))
        try:
            ym = _materials_in_series(pairs, disc_mats, wall_mats)
        except EngineUnsupported:
            if not wall_mats:
                raise
            # the disc-wall pairs cannot come from YADE's series rule (e.g. a wall stiffer than twice the
            # disc-disc value, Miyata Table 2): the deck sets each disc-wall interaction's ViscElPhys to the
            # pair's law itself when the contact forms (capabilities feature 'pair-stiffness')
            ym = _materials_in_series({k: v for k, v in pairs.items() if k[0] in disc_mats and k[1] in disc_mats},
                                      disc_mats, [])
            for w in wall_mats:
                ym[w] = dict(ym[disc_mats[0]])
            S["wall_phys"] = {w: {d: pairs[(d, w)] for d in disc_mats if (d, w) in pairs} for w in wall_mats}
        for m in S["materials"]:
            ym.setdefault(m, dict(kn=0.0, ks=0.0, cn=0.0, cs=0.0, phi=0.0))
        S["yade_materials"] = ym
        if scene.box.periodic_x is not None:
            S["periodic_x"] = [float(v) for v in scene.box.periodic_x]
        # walls: which side are the discs on? (the box is put on the other side)
        x = np.asarray(S["discs"]["x"])
        y = np.asarray(S["discs"]["y"])
        for w in S["walls"]:
            nx, ny = -w["ey"], w["ex"]
            side = np.sign(np.mean((x - w["px"]) * nx + (y - w["py"]) * ny)) or 1.0
            w["nx_in"], w["ny_in"] = float(side * nx), float(side * ny)
        S["wall_thickness"] = float(np.mean(S["discs"]["r"]))
        atomic_json(deckdir / "scene.json", S)
        deck = deckdir / "deck.py"
        deck.write_text(resources.files("demflow.engines.decks").joinpath("yade_discs2d.py").read_text())
        return [deck, deckdir / "scene.json"]

    def command(self, deckdir: Path):
        return [self.path(), "-n", "-j1", "-x", "deck.py"]

    def read(self, scene, sim, outdir: Path):
        """The result tables of a YADE run in ``outdir`` (``yade_out.json``, written by the deck).  Its
        structure is checked before use (the keys, the shape of every array, finite numbers, the recorded
        steps the deck asked for, snapshot steps and body ids in range); anything else raises
        EngineOutputError naming the file and the entry."""
        f = Path(outdir) / "yade_out.json"
        if not f.exists():
            raise EngineOutputError(f"YADE wrote no output ({f} missing); see {Path(outdir) / 'engine.log'}")
        try:
            out = json.loads(f.read_text())
        except (OSError, ValueError) as e:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
            raise EngineOutputError(f"YADE output {f} is truncated or corrupt ({e}); rerun the engine") from None
        if not (isinstance(out, dict) and out.get("complete") is True):
            raise EngineOutputError(f"YADE output {f} is incomplete; rerun the engine")
        n, nw, nt = sim.n, sim.nw, len(sim.track)
        rec = _entry(f, out, "rec", dict)
        steps = _array(f, "rec.step", _entry(f, rec, "step", list), (-1,))
        R = steps.shape[0]
        every = int(scene.outputs.every)
        want = np.arange(0, int(scene.n_steps), every) if every > 0 else np.zeros(0)
        if not np.array_equal(steps, want):
            raise _bad(f, "rec.step", f"records steps {steps[:4].tolist()}... ({R}), the deck records every {every} "
                                      f"steps from 0 to {int(scene.n_steps) - 1} ({want.shape[0]})")
        wall = _array(f, "rec.wall", _entry(f, rec, "wall", list), (R, nw, 3))
        wallpos = _array(f, "rec.wallpos", _entry(f, rec, "wallpos", list), (R, nw, 2))
        track = _array(f, "rec.track", _entry(f, rec, "track", list), (R, nt, 2))
        kinetic = _array(f, "rec.kinetic", _entry(f, rec, "kinetic", list), (R,))
        snaps = []
        last = -1
        for q, sn in enumerate(_entry(f, out, "snapshots", list)):
            where = f"snapshots[{q}]"
            if not isinstance(sn, dict):
                raise _bad(f, where, "is not an object")
            st = _entry(f, sn, "step", int, where)
            if st not in scene.outputs.snapshots or st <= last:
                raise _bad(f, f"{where}.step", f"{st!r} is not one of the scene's snapshot steps, in order")
            last = st
            parts = _array(f, f"{where}.particles", _entry(f, sn, "particles", list, where), (n, 7))
            cons = _array(f, f"{where}.contacts", _entry(f, sn, "contacts", list, where), (-1, 9))
            ids = cons[:, :2]
            if not (np.all(ids == np.round(ids)) and np.all(ids >= 0) and np.all(cons[:, 0] < n)
                    and np.all(cons[:, 1] < n + nw)):
                raise _bad(f, f"{where}.contacts", f"a body id is outside 0..{n - 1} (discs) or {n}..{n + nw - 1} "
                                                   "(walls)")
            geo = _array(f, f"{where}.walls", _entry(f, sn, "walls", list, where), (nw, 4))
            snaps.append(dict(step=st, particles=parts, contacts=cons, walls=geo))
        return results_from_records(sim, engine="yade", steps=steps.astype(np.int64), wall=wall, wallpos=wallpos,
                                    track=track, kinetic=kinetic, snapshots=snaps)


def _bad(f: Path, where: str, what: str) -> EngineOutputError:
    return EngineOutputError(f"YADE output {f}: {where} {what}; the output is truncated or corrupt; rerun the engine")


def _entry(f: Path, obj: dict, key: str, kind, where: str = ""):
    """``obj[key]``, of type ``kind`` (an int is never a bool)."""
    path = f"{where}.{key}" if where else key
    if key not in obj:
        raise _bad(f, path, "is missing")
    v = obj[key]
    if not isinstance(v, kind) or (kind is int and isinstance(v, bool)):
        raise _bad(f, path, f"is a {type(v).__name__}, not a {kind.__name__}")
    return v


def _array(f: Path, where: str, v, shape) -> np.ndarray:
    """``v`` as a float array of ``shape`` (-1: any length) holding finite numbers only."""
    if any(isinstance(x, (bool, str)) or x is None for x in _leaves(v)):
        raise _bad(f, where, "holds a value that is not a number")
    try:
        a = np.array(v, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise _bad(f, where, "is not a regular array of numbers") from None
    if a.size == 0 and a.ndim < len(shape) and -1 not in shape[a.ndim:] \
            and all(s in (-1, t) for s, t in zip(shape, a.shape)):
        # an empty list nests no deeper than its first empty level: [] for (0, 3), [[], ...] for (R, 0, 2)
        a = a.reshape(*a.shape, *shape[a.ndim:])
    if a.ndim != len(shape) or any(s not in (-1, t) for s, t in zip(shape, a.shape)):
        raise _bad(f, where, f"has shape {a.shape}, expected {tuple('any' if s == -1 else s for s in shape)}")
    if not np.all(np.isfinite(a)):
        raise _bad(f, where, "holds a non-finite value")
    return a


def _leaves(v):
    if isinstance(v, list):
        for x in v:
            yield from _leaves(x)
    else:
        yield v
