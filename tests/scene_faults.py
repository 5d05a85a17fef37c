"""A catalogue of invalid scenes, one fault each, for the scene fuzz suite (issue 19).

Each :class:`Fault` takes a valid base scene (:func:`base_dry`, :func:`base_periodic`,
:func:`base_fluid`) and breaks exactly one field with a value drawn by ``pick`` (a function that
chooses one element of a sequence: Hypothesis's ``data.draw(sampled_from(...))`` in
tests/test_fuzz_scenes.py, a seeded ``random.Random.choice`` in benchmarks/fuzz_scenes.py).  It
returns the broken scene and the dotted path of the broken field (``scene.walls[1].servo.v_max``);
the acceptance is a :class:`~demflow.scene.SceneError` whose message contains that path.

:func:`classify` runs ``build`` on one scene and says what happened: ``clear`` (SceneError naming
the field), ``unnamed`` (SceneError not naming it), ``accepted`` (no error) or ``other`` (any other
exception, with its type).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from demflow import (Box, ContactModel, Discs, GlobalDamping, LinearLaw, Material, Outputs, Phase, Scene,
                     SceneError, Servo, Wall, build)
from demflow.scene import Fluid, Superquadrics, WallLoad

NAN, INF = math.nan, math.inf

# ----------------------------------------------------------------------------- value pools
NOT_NUMBERS = [True, False, "1.0", None, 1j, [1.0], {"v": 1.0}, b"1"]
NON_FINITE = [NAN, INF, -INF]
BAD_POSITIVE = NON_FINITE + [-1.0, 0.0, -1e-300] + NOT_NUMBERS           # fields that must be > 0
BAD_NONNEG = NON_FINITE + [-1.0, -1e-12] + NOT_NUMBERS                     # fields that must be >= 0
BAD_FINITE = NON_FINITE + NOT_NUMBERS                                      # any finite number
BAD_WHOLE = [1.5, -1, -3, 0.5, NAN, INF, True, False, "3", None, 2 ** 70, [2]]  # whole numbers >= 0
BAD_VECTOR = [(NAN, 0.0), (0.0, INF), (-INF, 1.0), (1.0,), (1.0, 2.0, 3.0), "ab", None, (True, 0.0),
              ("1", 0.0), 5.0, ((0.0, 0.0), (0.0, 0.0)), (None, 1.0), (1j, 0.0), ()]
BAD_DIRECTION = BAD_VECTOR + [(0.0, 0.0), (1.7e308, 1.7e308)]
BAD_IDENT = ["abc\n", "", " a", "a b", "1abc", "a" * 65, 'x"; import os', None, 5, "é", "a\tb", "abc\x00", "-a",
             b"abc", "abc\r\n", "ab.c"]
BAD_FLAG = ["yes", 1, 0, None, 1.0, "True", [True]]
BAD_ENTRY = [NAN, INF, -INF, "1.0", None, True, 1j, [1.0]]                # one entry of a disc array


# ----------------------------------------------------------------------------- base scenes
def base_dry() -> Scene:
    """Three discs of two materials in a box of four walls: one wall with phases (a translation,
    then a rotation about a pivot), one servo wall with a schedule; damping, gravity, a given dt,
    records, snapshots and tracked pairs."""
    law = LinearLaw(kn=1e5, ks=5e4, cn=1.0, cs=0.5, friction=0.3, cohesion=0.0)
    walls = [Wall("bottom", (3.0, 0.0), (1.0, 0.0), -5.0, 5.0, "w",
                  phases=(Phase(10, (0.0, 0.1)), Phase(5, omega=0.01, pivot=(3.0, 0.0)))),
             Wall("right", (8.0, 3.0), (0.0, 1.0), -3.0, 3.0, "w"),
             Wall("top", (3.0, 6.0), (-1.0, 0.0), -5.0, 5.0, "w",
                  servo=Servo(force=10.0, direction=(0.0, -1.0), gain=0.1, v_max=0.5, start=5,
                              schedule=((20, 12.0),))),
             Wall("left", (-2.0, 3.0), (0.0, -1.0), -3.0, 3.0, "w")]
    return Scene(name="fuzz-dry", discs=Discs(x=[0.0, 2.5, 5.0], y=[2.0, 2.0, 2.0], radius=[1.0, 1.0, 0.8],
                                              material=["g", "g", "h"], velocity=[[0.1, 0.0], [0.0, 0.0], [0.0, 0.1]],
                                              angular_velocity=[0.0, 0.1, 0.0]),
                 materials={"g": Material(density=2.0), "h": Material(density=3.0), "w": Material()},
                 laws={("g", "g"): law, ("g", "h"): law, ("g", "w"): law, ("h", "w"): law},
                 walls=walls, damping=GlobalDamping(C=0.1, C_rot=0.1), gravity=(0.0, -9.81), dt=1e-4,
                 n_steps=100, outputs=Outputs(every=2, snapshots=(0, 50), track_pairs=((0, 1), (0, "wall:bottom"))))


def base_periodic() -> Scene:
    """Two discs in a box periodic along x over a floor that spans it."""
    law = LinearLaw(kn=1e5, ks=5e4, friction=0.5)
    return Scene(name="fuzz-periodic", discs=Discs(x=[1.0, 5.0], y=[1.0, 1.5], radius=[1.0, 0.7], material="g"),
                 materials={"g": Material(density=1.0), "w": Material()},
                 laws={("g", "g"): law, ("g", "w"): law},
                 walls=[Wall("floor", (10.0, 0.0), (1.0, 0.0), -10.0, 10.0, "w")],
                 gravity=(0.0, -1.0), n_steps=50, box=Box(periodic_x=(0.0, 20.0)))


def base_fluid() -> Scene:
    """One disc in a saturated box of four walls with an applied load on the top wall."""
    w, h = 5.0, 10.0
    walls = [Wall("bottom", (0, -h / 2), (1, 0), -w / 2, w / 2, "w"), Wall("right", (w / 2, 0), (0, 1), -h / 2, h / 2, "w"),
             Wall("top", (0, h / 2), (-1, 0), -w / 2, w / 2, "w"), Wall("left", (-w / 2, 0), (0, -1), -h / 2, h / 2, "w")]
    return Scene(name="fuzz-fluid", discs=Discs([0.0], [0.0], [0.5], "disc"),
                 materials={"disc": Material(2.0), "w": Material()},
                 laws={("disc", "w"): LinearLaw(kn=1e5), ("disc", "disc"): LinearLaw(kn=1e5)},
                 walls=walls, gravity=(0.0, -980.0), dt=1e-4, allow_supercritical=True, n_steps=10,
                 outputs=Outputs(every=1),
                 fluid=Fluid(viscosity=1.0, density=1.0, boundary=("bottom", "right", "top", "left"),
                             elements_per_disc=16, loads=(WallLoad("top", 1.0, (0.0, -1.0)),)))


BASES = {"dry": base_dry, "periodic": base_periodic, "fluid": base_fluid}


# ----------------------------------------------------------------------------- faults
@dataclass(frozen=True)
class Fault:
    """One kind of fault: ``make(pick)`` returns (scene, path of the broken field, value used)."""

    category: str
    name: str
    make: Callable


FAULTS: list[Fault] = []


def fault(category, name):
    def deco(fn):
        FAULTS.append(Fault(category, name, fn))
        return fn
    return deco


def _set(obj, **kw):
    """A copy of a dataclass (frozen or not) with fields replaced."""
    return replace(obj, **kw)


def _wall(sc, i, **kw):
    walls = list(sc.walls)
    walls[i] = _set(walls[i], **kw)
    sc.walls = walls
    return sc


def _entry(seq, k, v):
    out = list(seq)
    out[k] = v
    return out


# scene-level scalars -------------------------------------------------------------------
@fault("names", "scene name")
def _(pick):
    v = pick(BAD_IDENT)
    return _set(base_dry(), name=v), "scene.name", v


@fault("gravity", "gravity vector")
def _(pick):
    v = pick(BAD_VECTOR)
    return _set(pick([base_dry, base_periodic])(), gravity=v), "scene.gravity", v


@fault("time step", "dt")
def _(pick):
    v = pick([b for b in BAD_POSITIVE if b is not None])  # None is valid: dt from dt_fraction
    return _set(pick([base_dry, base_fluid])(), dt=v), "scene.dt", v


@fault("time step", "dt above critical")
def _(pick):
    v = pick([1.0, 0.5, 10.0])
    return _set(base_dry(), dt=v), "scene.dt", v


@fault("time step", "dt_fraction")
def _(pick):
    v = pick(BAD_POSITIVE + [1.5, 2.0])
    return _set(base_periodic(), dt=None, dt_fraction=v), "scene.dt_fraction", v


@fault("run length", "n_steps")
def _(pick):
    v = pick(BAD_WHOLE)
    return _set(base_dry(), n_steps=v), "scene.n_steps", v


@fault("run length", "n_steps beyond what can be stored")
def _(pick):
    v = pick([10 ** 12, 1e12, 10 ** 15, 2 ** 62])
    sc = base_dry()
    sc.outputs = _set(sc.outputs, every=1)
    return _set(sc, n_steps=v), "scene.n_steps", v


# The run-time-step flags and the energy check share one fault (one pick from a list as long as BAD_FLAG,
# so that the seeded catalogue draws what it drew before they were added): each bad value goes to one field.
_FLAG_FIELDS = ("allow_supercritical", "allow_unsafe_dt", "energy_check")
_FLAG_FAULTS = [(_FLAG_FIELDS[k % 3], v) for k, v in enumerate(BAD_FLAG)]


@fault("flags", "allow_supercritical")
def _(pick):
    key, v = pick(_FLAG_FAULTS)
    return _set(base_dry(), **{key: v}), f"scene.{key}", v


@fault("neighbour list", "skin")
def _(pick):
    v = pick([b for b in BAD_POSITIVE if b is not None])  # None is valid: 0.2 × the mean radius
    return _set(pick([base_dry, base_periodic])(), skin=v), "scene.skin", v


@fault("neighbour list", "overlap_tolerance")
def _(pick):
    v = pick(BAD_NONNEG)
    return _set(base_dry(), overlap_tolerance=v), "scene.overlap_tolerance", v


@fault("names", "description")
def _(pick):
    v = pick([5, None, b"text", ["a"]])
    return _set(base_dry(), description=v), "scene.description", v


@fault("types", "scene object of the wrong type")
def _(pick):
    key, v = pick([("discs", {"x": [0.0]}), ("discs", None), ("materials", [Material(1.0)]), ("materials", None),
                   ("laws", [LinearLaw(kn=1.0)]), ("laws", None), ("walls", Wall("a", (0, 0), (1, 0), -1, 1, "w")),
                   ("walls", None), ("outputs", {"every": 1}), ("outputs", 1), ("box", (0.0, 1.0)),
                   ("box", None), ("contact_model", "overlap"), ("damping", 0.1), ("damping", None),
                   ("fluid", 1.0), ("contact_model", None)])
    return _set(base_dry(), **{key: v}), f"scene.{key}", v


# materials --------------------------------------------------------------------------------
@fault("densities", "material density")
def _(pick):
    v = pick(BAD_NONNEG)
    sc = pick([base_dry, base_periodic])()
    m = pick(sorted(sc.materials))
    sc.materials = dict(sc.materials, **{m: Material(density=v)})
    return sc, f"scene.materials[{m!r}].density", v


@fault("densities", "material Young's modulus")
def _(pick):
    v = pick([NAN, -INF, -1.0, 0.0] + [x for x in NOT_NUMBERS if x is not None])  # inf: a rigid wall; None: unused
    sc = pick([base_dry, base_periodic])()
    m = pick(sorted(sc.materials))
    sc.materials = dict(sc.materials, **{m: Material(density=sc.materials[m].density, young=v)})
    return sc, f"scene.materials[{m!r}].young", v


@fault("densities", "material Poisson's ratio")
def _(pick):
    v = pick(NON_FINITE + [0.5, 0.7, -1.0, -2.0] + [x for x in NOT_NUMBERS if x is not None])
    sc = pick([base_dry, base_periodic])()
    m = pick(sorted(sc.materials))
    sc.materials = dict(sc.materials, **{m: Material(density=sc.materials[m].density, young=1e9, poisson=v)})
    return sc, f"scene.materials[{m!r}].poisson", v


@fault("densities", "disc material with zero density")
def _(pick):
    sc = base_dry()
    m = pick(["g", "h"])
    sc.materials = dict(sc.materials, **{m: Material(density=0.0)})
    return sc, f"scene.materials[{m!r}].density", 0.0


@fault("names", "material name")
def _(pick):
    v = pick([s for s in BAD_IDENT if isinstance(s, str)])
    sc = base_dry()
    sc.materials = dict(sc.materials, **{v: Material(1.0)})
    return sc, f"scene.materials[{v!r}]", v


@fault("types", "material of the wrong type")
def _(pick):
    v = pick([1.0, None, {"density": 1.0}, "g", LinearLaw(kn=1.0)])
    sc = base_dry()
    sc.materials = dict(sc.materials, h=v)
    return sc, "scene.materials['h']", v


# discs -------------------------------------------------------------------------------------
def _disc_entry_fault(category, name, key, values, start=None):
    """One entry k of the per-disc list ``key`` of base_dry (or of ``start``) set to a drawn bad value."""
    @fault(category, name)
    def make(pick):
        v = pick(values)
        sc = base_dry()
        k = pick([0, 1, 2])
        sc.discs = _set(sc.discs, **{key: _entry(getattr(sc.discs, key) if start is None else start, k, v)})
        return sc, f"scene.discs.{key}[{k}]", v
    return make


_disc_entry_fault("radii", "disc radius", "radius", BAD_POSITIVE[:6] + BAD_ENTRY)
_disc_entry_fault("masses", "disc mass", "mass", BAD_POSITIVE[:6] + BAD_ENTRY, start=[1.0, 2.0, 3.0])
_disc_entry_fault("velocities", "disc angular velocity", "angular_velocity", BAD_ENTRY)
_disc_entry_fault("materials", "disc material undeclared or not a name", "material", ["sand", "G", "g\n", None, 3, ""])


@fault("radii", "disc radius overflowing the mass")
def _(pick):
    v = pick([1e160, 1e200, 1e300])
    sc = base_periodic()
    sc.box = Box()
    sc.discs = _set(sc.discs, radius=[1.0, v], x=[1.0, 3.0 * v])
    return sc, "scene.discs", v


@fault("positions", "disc position")
def _(pick):
    v = pick(BAD_ENTRY)
    key = pick(["x", "y"])
    sc = pick([base_dry, base_periodic])()
    k = pick([0, 1])
    sc.discs = _set(sc.discs, **{key: _entry(getattr(sc.discs, key), k, v)})
    return sc, f"scene.discs.{key}[{k}]", v


@fault("velocities", "disc velocity")
def _(pick):
    sc = base_dry()
    kind = pick(["entry", "shape"])
    if kind == "entry":
        k, c = pick([0, 1, 2]), pick([0, 1])
        v = pick(BAD_ENTRY)
        vel = [list(r) for r in sc.discs.velocity]
        vel[k][c] = v
        path = f"scene.discs.velocity[{k}]"
    else:
        v = vel = pick([[[0.0, 0.0]] * 2, [[0.0, 0.0, 0.0]] * 3, [0.0, 0.0, 0.0], "fast", 1.0, [[0.0], [0.0], [0.0]]])
        path = "scene.discs.velocity"
    sc.discs = _set(sc.discs, velocity=vel)
    return sc, path, v


@fault("array lengths", "disc array of the wrong length")
def _(pick):
    key = pick(["y", "radius", "mass", "angular_velocity", "material"])
    n = pick([2, 4, 0])
    sc = base_dry()
    full = {"y": [2.0] * 5, "radius": [1.0, 1.0, 0.8, 0.5, 0.5], "mass": [1.0] * 5, "angular_velocity": [0.0] * 5,
            "material": ["g", "g", "h", "g", "g"]}[key]
    sc.discs = _set(sc.discs, **{key: full[:n]})
    return sc, f"scene.discs.{key}", n


@fault("array lengths", "disc array of the wrong shape")
def _(pick):
    key = pick(["x", "y", "radius"])
    v = pick([[[0.0, 2.5, 5.0]], 5.0, None, "abc", np.zeros((3, 1))])
    sc = base_dry()
    sc.discs = _set(sc.discs, **{key: v})
    return sc, f"scene.discs.{key}", v


@fault("positions", "initial overlap")
def _(pick):
    d = pick([0.5, 1.0, 1.9])
    sc = base_dry()
    sc.discs = _set(sc.discs, x=[0.0, d, 5.0])
    return sc, "scene.discs", d


# laws --------------------------------------------------------------------------------------
@fault("laws", "law parameter")
def _(pick):
    key = pick(["kn", "ks", "cn", "cs", "friction", "cohesion"])
    v = pick(BAD_POSITIVE if key == "kn" else BAD_NONNEG)
    sc = pick([base_dry, base_periodic, base_fluid])()
    pair = pick(sorted(sc.laws))
    sc.laws = dict(sc.laws, **{}) | {pair: _set(sc.laws[pair], **{key: v})}
    return sc, f"scene.laws[{pair!r}].{key}", v


@fault("laws", "law key")
def _(pick):
    key = pick([("g",), "g", ("g", "g", "g"), ("g", "sand"), ("sand", "w"), (1, 2), ("g", None)])
    sc = base_dry()
    sc.laws = dict(sc.laws) | {key: LinearLaw(kn=1e5)}
    return sc, f"scene.laws[{key!r}]", key


@fault("laws", "law declared twice")
def _(pick):
    sc = base_dry()
    pair = pick([("h", "g"), ("w", "g"), ("w", "h")])
    sc.laws = dict(sc.laws) | {pair: LinearLaw(kn=2e5)}
    return sc, f"scene.laws[{pair!r}]", pair


@fault("laws", "law missing")
def _(pick):
    sc = base_dry()
    pair = pick(sorted(sc.laws))
    sc.laws = {k: v for k, v in sc.laws.items() if k != pair}
    return sc, "scene.laws", pair


@fault("types", "law of the wrong type")
def _(pick):
    v = pick([1e5, None, {"kn": 1e5}, Material(1.0), "linear"])
    sc = base_dry()
    sc.laws = dict(sc.laws) | {("g", "g"): v}
    return sc, "scene.laws[('g', 'g')]", v


@fault("contact model", "contact model choice")
def _(pick):
    key = pick(["normal", "sliding"])
    v = pick(["Incremental", "overlap\n", None, 1, "", "thesis " if key == "sliding" else "cs"])
    sc = base_dry()
    sc.contact_model = _set(sc.contact_model, **{key: v})
    return sc, f"scene.contact_model.{key}", v


@fault("damping", "global damping")
def _(pick):
    key = pick(["C", "C_rot", "alpha"])
    v = pick(BAD_NONNEG)
    sc = base_dry()
    kw = dict(C=0.0, C_rot=0.0, alpha=0.0) | {key: v}
    sc.damping = GlobalDamping(**kw)
    return sc, f"scene.damping.{key}", v


@fault("damping", "both damping forms")
def _(pick):
    sc = base_dry()
    sc.damping = GlobalDamping(C=pick([0.1, 0.0]), C_rot=0.1, alpha=pick([1.0, 0.5]))
    return sc, "scene.damping", None


# walls ------------------------------------------------------------------------------------
@fault("names", "wall name")
def _(pick):
    v = pick(BAD_IDENT + ["left"])
    i = pick([0, 1, 2])
    return _wall(base_dry(), i, name=v), f"scene.walls[{i}].name", v


@fault("walls", "wall point")
def _(pick):
    v = pick(BAD_VECTOR + [(1e308, 0.0)])
    i = pick([0, 1, 2, 3])
    return _wall(base_dry(), i, point=v), f"scene.walls[{i}].point", v


@fault("walls", "wall direction")
def _(pick):
    v = pick(BAD_DIRECTION)
    i = pick([0, 1, 2, 3])
    return _wall(base_dry(), i, direction=v), f"scene.walls[{i}].direction", v


@fault("walls", "wall extent h1, h2")
def _(pick):
    key = pick(["h1", "h2"])
    v = pick(BAD_FINITE + [5.0 if key == "h1" else -5.0, 1e308 if key == "h2" else -1e308])
    i = pick([0, 2])
    return _wall(base_dry(), i, **{key: v}), f"scene.walls[{i}].{key}", v


@fault("walls", "wall material")
def _(pick):
    v = pick(["steel", None, 1, "w\n"])
    i = pick([0, 1, 2, 3])
    return _wall(base_dry(), i, material=v), f"scene.walls[{i}].material", v


@fault("types", "wall of the wrong type")
def _(pick):
    v = pick([None, 1.0, ("bottom", (0, 0), (1, 0), -1, 1, "w"), {"name": "a"}])
    sc = base_dry()
    sc.walls = _entry(sc.walls, 1, v)
    return sc, "scene.walls[1]", v


# phases -----------------------------------------------------------------------------------
@fault("phases", "phase cycles")
def _(pick):
    v = pick(BAD_WHOLE)
    k = pick([0, 1])
    sc = base_dry()
    ph = list(sc.walls[0].phases)
    ph[k] = _set(ph[k], cycles=v)
    return _wall(sc, 0, phases=tuple(ph)), f"scene.walls[0].phases[{k}].cycles", v


@fault("phases", "phase velocity")
def _(pick):
    v = pick(BAD_VECTOR)
    sc = base_dry()
    return _wall(sc, 0, phases=(_set(sc.walls[0].phases[0], velocity=v), sc.walls[0].phases[1])), \
        "scene.walls[0].phases[0].velocity", v


@fault("phases", "phase omega")
def _(pick):
    v = pick(BAD_FINITE)
    sc = base_dry()
    return _wall(sc, 0, phases=(sc.walls[0].phases[0], _set(sc.walls[0].phases[1], omega=v))), \
        "scene.walls[0].phases[1].omega", v


@fault("phases", "phase pivot")
def _(pick):
    v = pick([p for p in BAD_VECTOR if p is not None] + [(1e308, 1e308)])
    sc = base_dry()
    return _wall(sc, 0, phases=(sc.walls[0].phases[0], _set(sc.walls[0].phases[1], pivot=v))), \
        "scene.walls[0].phases[1].pivot", v


@fault("types", "phase of the wrong type")
def _(pick):
    v = pick([None, 10, (10, (0.0, 0.1)), {"cycles": 10}])
    sc = base_dry()
    kind = pick(["entry", "container"])
    if kind == "entry":
        return _wall(sc, 0, phases=(v, sc.walls[0].phases[1])), "scene.walls[0].phases[0]", v
    v = pick([Phase(10), 5, "phases"])
    return _wall(sc, 0, phases=v), "scene.walls[0].phases", v


# servo ------------------------------------------------------------------------------------
@fault("servos", "servo parameter")
def _(pick):
    key = pick(["force", "gain", "v_max"])
    v = pick(BAD_POSITIVE)
    sc = base_dry()
    return _wall(sc, 2, servo=_set(sc.walls[2].servo, **{key: v})), f"scene.walls[2].servo.{key}", v


@fault("servos", "servo direction")
def _(pick):
    v = pick(BAD_DIRECTION)
    sc = base_dry()
    return _wall(sc, 2, servo=_set(sc.walls[2].servo, direction=v)), "scene.walls[2].servo.direction", v


@fault("servos", "servo start")
def _(pick):
    v = pick(BAD_WHOLE)
    sc = base_dry()
    return _wall(sc, 2, servo=_set(sc.walls[2].servo, start=v)), "scene.walls[2].servo.start", v


@fault("servos", "servo schedule")
def _(pick):
    kind = pick(["step", "force", "shape"])
    if kind == "step":
        v = pick(BAD_WHOLE)
        sched = ((v, 12.0),)
    elif kind == "force":
        v = pick(BAD_POSITIVE)
        sched = ((20, v),)
    else:
        v = pick([(20,), (20, 12.0, 1.0), 20, None, "x"])
        sched = (v,)
    sc = base_dry()
    path = "scene.walls[2].servo.schedule[0]"
    if kind == "shape" and pick([0, 1]):
        sched = v = pick([5, "x", None, 1.0])
        path = "scene.walls[2].servo.schedule"
    return _wall(sc, 2, servo=_set(sc.walls[2].servo, schedule=sched)), path, v


@fault("types", "servo of the wrong type")
def _(pick):
    v = pick([10.0, (10.0, (0, -1), 0.1, 0.5), {"force": 10.0}, "servo"])
    return _wall(base_dry(), 2, servo=v), "scene.walls[2].servo", v


# outputs ---------------------------------------------------------------------------------
@fault("outputs", "outputs.every")
def _(pick):
    v = pick(BAD_WHOLE)
    sc = base_dry()
    sc.outputs = _set(sc.outputs, every=v)
    return sc, "scene.outputs.every", v


@fault("outputs", "outputs.snapshots")
def _(pick):
    sc = base_dry()
    if pick([0, 1]):
        v = pick(BAD_WHOLE + [0])  # 0: the step of snapshots[0] again
        sc.outputs = _set(sc.outputs, snapshots=(0, v))
        return sc, "scene.outputs.snapshots[1]", v
    v = pick([5, None, "0, 50", 1.5])
    sc.outputs = _set(sc.outputs, snapshots=v)
    return sc, "scene.outputs.snapshots", v


@fault("outputs", "outputs.track_pairs")
def _(pick):
    v = pick([(0, 3), (0, -1), (0, 7), (0, "wall:roof"), ("wall:top", "wall:bottom"), (0, 1.5), (True, 1), (0,),
              (0, 1, 2), None, 0, (0, "top"), (0, "wall:top\n"), (0, None), (NAN, 1), (1, 1)])
    sc = base_dry()
    sc.outputs = _set(sc.outputs, track_pairs=((0, 1), v))
    return sc, "scene.outputs.track_pairs[1]", v


# box -------------------------------------------------------------------------------------
@fault("box", "periodic bounds")
def _(pick):
    key = pick(["periodic_x", "periodic_y"])
    v = pick([(0.0, NAN), (NAN, 1.0), (0.0, INF), (5.0, 5.0), (10.0, 0.0), (0.0,), "ab", (True, 20.0),
              (0.0, "20"), 20.0, (0.0, 20.0, 40.0), (None, 20.0)])
    sc = base_periodic()
    sc.box = _set(sc.box, **{key: v})
    return sc, f"scene.box.{key}", v


@fault("box", "period below the neighbour reach")
def _(pick):
    L = pick([3.0, 4.0, 4.3])
    sc = base_periodic()
    sc.discs = _set(sc.discs, x=[1.0, 1.0 + L / 2], y=[1.0, 3.0])
    sc.box = Box(periodic_x=(0.0, L))
    return sc, "scene.box.periodic_x", L


# fluid -----------------------------------------------------------------------------------
@fault("fluids", "fluid number")
def _(pick):
    key = pick(["viscosity", "density", "element_length", "min_gap", "safety"])
    v = pick(BAD_POSITIVE if key != "density" else BAD_NONNEG)
    if v is None and key in ("element_length", "min_gap"):  # None is these fields' default (derived)
        v = -1.0
    if key == "safety":
        v = pick([v, 1.5, 2.0])
    sc = base_fluid()
    sc.fluid = _set(sc.fluid, **{key: v})
    return sc, f"scene.fluid.{key}", v


@fault("fluids", "fluid whole number")
def _(pick):
    key = pick(["elements_per_disc", "stride", "record_every", "quadrature", "start"])
    v = pick(BAD_WHOLE + ([4, 7] if key == "elements_per_disc" else [0] if key in ("stride", "record_every")
                          else [-2, 3, 128] if key == "quadrature" else []))
    if key == "quadrature" and v in (-1, -3):
        v = -2
    sc = base_fluid()
    sc.fluid = _set(sc.fluid, **{key: v})
    return sc, f"scene.fluid.{key}", v


@fault("fluids", "fluid flag")
def _(pick):
    key = pick(["adaptive", "moments"])
    v = pick(BAD_FLAG)
    sc = base_fluid()
    sc.fluid = _set(sc.fluid, **{key: v})
    return sc, f"scene.fluid.{key}", v


@fault("fluids", "fluid boundary")
def _(pick):
    v = pick([("bottom", "right", "roof", "left"), ("bottom", "left", "top", "right"), ("bottom", "right"),
              ("bottom", "right", "top", "top"), ("bottom", None, "top", "left"), "bottom", 5,
              ("bottom", "top", "right")])
    sc = base_fluid()
    sc.fluid = _set(sc.fluid, boundary=v)
    return sc, "scene.fluid.boundary", v


@fault("fluids", "fluid load")
def _(pick):
    kind = pick(["force", "direction", "wall", "type"])
    sc = base_fluid()
    load = sc.fluid.loads[0]
    path = f"scene.fluid.loads[0].{kind}"
    if kind == "force":
        v = pick(BAD_POSITIVE)
        load = _set(load, force=v)
    elif kind == "direction":
        v = pick(BAD_DIRECTION + [(1.0, -1.0), (1.0, 0.0)])
        load = _set(load, direction=v)
    elif kind == "wall":
        v = pick(["roof", None, 3, "top\n"])
        load = _set(load, wall=v)
    else:
        v = load = pick([1.0, ("top", 1.0), None])
        path = "scene.fluid.loads[0]"
    sc.fluid = _set(sc.fluid, loads=(load,))
    return sc, path, v


@fault("fluids", "fluid placement")
def _(pick):
    v = pick([(0.0, 20.0), (10.0, 0.0)])
    sc = base_fluid()
    sc.discs = _set(sc.discs, x=[v[0]], y=[v[1]])
    return sc, "scene.fluid.boundary", v


# superquadrics (the 2D shape family of scene.discs, demflow/simulation_sq2d.py) -------------------------
def base_superquadric() -> Scene:
    """Three superquadrics of two materials (n = 2, 4 and 1.5; tilted; a disc-like one) resting apart
    above a floor between two side walls, with restitution damping, gravity and a given dt."""
    law = LinearLaw(kn=1e5, ks=5e4, cn=1.0, cs=0.5, friction=0.3)
    walls = [Wall("floor", (3.0, 0.0), (1.0, 0.0), -6.0, 6.0, "w"),
             Wall("right", (9.0, 3.0), (0.0, 1.0), -3.0, 3.0, "w"),
             Wall("left", (-3.0, 3.0), (0.0, -1.0), -3.0, 3.0, "w")]
    return Scene(name="fuzz-superquadric",
                 discs=Superquadrics(x=[0.0, 3.0, 6.0], y=[2.0, 2.0, 2.0], a=[1.0, 1.2, 0.8], b=[0.6, 0.5, 0.8],
                                     n=[2.0, 4.0, 1.5], material=["g", "g", "h"], theta=[0.0, 0.3, -0.2],
                                     velocity=[[0.1, 0.0], [0.0, 0.0], [0.0, 0.1]], angular_velocity=[0.0, 0.1, 0.0],
                                     restitution=0.5),
                 materials={"g": Material(density=2.0), "h": Material(density=3.0), "w": Material()},
                 laws={("g", "g"): law, ("g", "h"): law, ("g", "w"): law, ("h", "w"): law},
                 walls=walls, gravity=(0.0, -9.81), dt=1e-4, n_steps=50, outputs=Outputs(every=5))


BASES["superquadric"] = base_superquadric

BAD_EXPONENT = [1.0, 0.5, 0.0, -2.0, 10.5, 1e6, NAN, INF, -INF] + NOT_NUMBERS  # 1 < n <= 10
_SQ_ENTRY_POOLS = {"x": BAD_ENTRY, "y": BAD_ENTRY, "theta": BAD_ENTRY, "angular_velocity": BAD_ENTRY,
                   "a": BAD_POSITIVE[:6] + BAD_ENTRY, "b": BAD_POSITIVE[:6] + BAD_ENTRY, "n": BAD_EXPONENT,
                   "mass": BAD_POSITIVE[:6] + BAD_ENTRY}
_SQ_VALID = {"x": [0.0, 3.0, 6.0], "y": [2.0, 2.0, 2.0], "a": [1.0, 1.2, 0.8], "b": [0.6, 0.5, 0.8],
             "n": [2.0, 4.0, 1.5], "theta": [0.0, 0.3, -0.2], "angular_velocity": [0.0, 0.1, 0.0],
             "mass": [1.0, 2.0, 3.0], "material": ["g", "g", "h"]}


def _sq(sc, **kw):
    sc.discs = _set(sc.discs, **kw)
    return sc


@fault("superquadrics", "superquadric entry")
def _(pick):
    key = pick(sorted(_SQ_ENTRY_POOLS))
    v = pick(_SQ_ENTRY_POOLS[key])
    k = pick([0, 1, 2])
    return _sq(base_superquadric(), **{key: _entry(_SQ_VALID[key], k, v)}), f"scene.discs.{key}[{k}]", v


@fault("superquadrics", "superquadric array of the wrong length or shape")
def _(pick):
    key = pick(sorted(_SQ_VALID))
    kind = pick(["length", "shape"])
    if kind == "length":
        v = _SQ_VALID[key][:pick([0, 2])] if key != "x" else _SQ_VALID[key][:2]
        if key == "x":  # x sets the count: a fourth entry disagrees with every other array
            v = _SQ_VALID["x"] + [pick([9.0, 12.0])]
    else:
        v = pick([[_SQ_VALID[key]], 5.0, "abc", np.zeros((3, 1)), {"0": 1.0}] + ([None] if key not in (
            "theta", "mass", "angular_velocity") else []))  # None: the default of theta, mass, angular_velocity
    return _sq(base_superquadric(), **{key: v}), f"scene.discs.{key}", v


@fault("superquadrics", "superquadric material")
def _(pick):
    v = pick(["sand", "G", "g\n", "", None, 3, ["g", "sand", "h"], ["g", None, "h"], ("g\n", "g", "h"), 2.5,
              {"g": 1}])
    sc = _sq(base_superquadric(), material=v)
    path = "scene.discs.material"
    if isinstance(v, (list, tuple)):
        path += f"[{next(k for k, m in enumerate(v) if m not in ('g', 'h'))}]"
    return sc, path, v


@fault("superquadrics", "superquadric velocity")
def _(pick):
    sc = base_superquadric()
    if pick(["entry", "shape"]) == "entry":
        k, c = pick([0, 1, 2]), pick([0, 1])
        v = pick(BAD_ENTRY)
        vel = [list(r) for r in sc.discs.velocity]
        vel[k][c] = v
        return _sq(sc, velocity=vel), f"scene.discs.velocity[{k}]", v
    v = pick([[[0.0, 0.0]] * 2, [[0.0, 0.0, 0.0]] * 3, [0.0, 0.0, 0.0], "fast", 1.0, [[0.0], [0.0], [0.0]]])
    return _sq(sc, velocity=v), "scene.discs.velocity", v


@fault("superquadrics", "superquadric knob")
def _(pick):
    key = pick(["restitution", "tolerance", "window", "max_overlap"])
    extra = {"restitution": [1.5, 2.0], "tolerance": [1.0, 3.0, None], "window": [4.0, 2 * math.pi, None],
             "max_overlap": [1.0, 1.5, None]}[key]
    v = pick([b for b in BAD_POSITIVE if b is not None] + extra)  # restitution None: no dashpot (valid)
    return _sq(base_superquadric(), **{key: v}), f"scene.discs.{key}", v


@fault("superquadrics", "superquadric mass overflowing")
def _(pick):
    """Semi-axes within the length range (±1e150) whose moment of inertia ρ(∫x² + ∫y²)dA overflows."""
    v = pick([1e110, 1e130, 1e149])
    key = pick(["a", "b"])
    return _sq(base_superquadric(), **{key: [1.0, v, 0.8] if key == "a" else [0.6, v, 0.8]}), f"scene.discs.{key}[1]", v


@fault("superquadrics", "superquadric scene unsupported or overlapping")
def _(pick):
    kind = pick(["overlap", "fluid", "box", "track_pairs", "snapshots", "family", "n_steps"])
    sc = base_superquadric()
    if kind == "n_steps":  # records beyond what can be stored
        v = pick([10 ** 12, 10 ** 15, 2 ** 62])
        return _set(sc, n_steps=v, outputs=Outputs(every=1)), "scene.n_steps", v
    if kind == "overlap":
        d = pick([0.5, 1.0, 1.5])
        return _sq(sc, x=[0.0, d, 6.0]), "scene.discs", d
    if kind == "fluid":
        v = base_fluid().fluid
        return _set(sc, fluid=v), "scene.fluid", v
    if kind == "box":
        v = Box(periodic_x=(-3.0, 1.0))  # periodic boxes run (miyata-uniaxial-2d); this one is narrower than
        return _set(sc, box=v), "scene.box", v  # twice the bounding circles' reach, which minimum image needs
    if kind in ("track_pairs", "snapshots"):
        v = ((0, 1),) if kind == "track_pairs" else (0, 10)
        return _set(sc, outputs=_set(sc.outputs, **{kind: v})), f"scene.outputs.{kind}", v
    v = pick([5, "superquadrics", [1.0, 2.0], {"x": [0.0]}, None, sc.discs.__dict__])  # the entry itself
    return _set(sc, discs=v), "scene.discs", v


CATEGORIES = sorted({f.category for f in FAULTS})


# ----------------------------------------------------------------------------- running one
def classify(scene, path) -> tuple[str, str]:
    """Build ``scene``: ("clear", message) for a SceneError naming ``path``; ("unnamed", message) for one
    that does not; ("accepted", "") if it builds; ("other", "TypeName: message") for any other exception."""
    try:
        build(scene)
    except SceneError as e:
        msg = str(e)
        return ("clear" if path in msg else "unnamed"), msg
    except Exception as e:  # noqa: BLE001 - the point is to see every other exception
        return "other", f"{type(e).__name__}: {e}"
    return "accepted", ""


def field_paths() -> list[str]:
    """Every dataclass field of the scene objects (for the coverage test)."""
    out = []
    for cls in (Scene, Discs, Material, LinearLaw, Wall, Phase, Servo, Outputs, Box, ContactModel, GlobalDamping,
                Fluid, WallLoad, Superquadrics):
        out += [f"{cls.__name__}.{f.name}" for f in dataclasses.fields(cls)]
    return out
