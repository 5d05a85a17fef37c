"""Faults of 3D scenes (spheres, planes, plates, meshes, clumps, the Hertz-Mindlin law), one each,
for the scene fuzz suite (issue 19 item 1: "those the other issues add").  Same protocol as
:mod:`scene_faults`: ``make(pick)`` returns (scene, dotted path of the broken field, value)."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import replace

import numpy as np

from demflow import (Box, ClumpTemplate, Clumps, Ellipsoids, HertzMindlinLaw, Material, Outputs3D, Plane, PlanePhase,
                     PlateServo, Scene3D, Spheres, TriangleMesh)
from demflow.scene import GlobalDamping

from scene_faults import (BAD_FLAG, BAD_IDENT, BAD_NONNEG, BAD_POSITIVE, BAD_WHOLE, BAD_ENTRY, Fault,
                          NAN, INF, NOT_NUMBERS)

FAULTS3D: list[Fault] = []
BAD_VECTOR3 = [(NAN, 0.0, 0.0), (0.0, INF, 0.0), (1.0, 2.0), (1.0, 2.0, 3.0, 4.0), "abc", None, (True, 0.0, 0.0),
               ("1", 0.0, 0.0), 5.0, ()]


def fault3d(category, name):
    def deco(fn):
        FAULTS3D.append(Fault(category, name, fn))
        return fn
    return deco


def _template():
    return ClumpTemplate(centres=np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0]]), radii=np.array([0.01, 0.008]),
                         mass=0.02, moments=np.array([1e-6, 2e-6, 2.5e-6]))


def base3d() -> Scene3D:
    """Three spheres and two clumps over a floor, a servo plate above, a mesh ramp, periodic x/y."""
    law = HertzMindlinLaw(friction=0.4, restitution=0.7)
    return Scene3D(
        name="fuzz-3d",
        spheres=Spheres(x=[0.01, 0.05, 0.09], y=[0.05, 0.05, 0.05], z=[0.02, 0.02, 0.05], radius=[0.01, 0.012, 0.01],
                        material="g", velocity=[[0.0, 0.0, -0.1]] * 3, angular_velocity=[[0.0, 1.0, 0.0]] * 3,
                        fixed=[False, False, False]),
        materials={"g": Material(density=2500.0, young=1e8, poisson=0.3), "w": Material(young=math.inf, poisson=0.25)},
        laws={("g", "g"): law, ("g", "w"): law},
        planes=[Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "w", phases=(PlanePhase(10, (0.0, 0.0, 0.0)),)),
                Plane("plate", (0.0, 0.0, 0.1), (0.0, 0.0, -1.0), "w",
                      servo=PlateServo(force=1.0, gain=0.1, v_max=0.1, start=2))],
        meshes=[TriangleMesh("ramp", [(0.0, 0.0, 0.001), (0.05, 0.0, 0.001), (0.05, 0.05, 0.001)], [(0, 1, 2)], "w")],
        clumps=Clumps(_template(), x=[0.03, 0.07], y=[0.08, 0.08], z=[0.03, 0.03], material="g"),
        gravity=(0.0, 0.0, -9.81), local_damping=0.1, damping=GlobalDamping(alpha=0.1), n_steps=20,
        box=Box(periodic_x=(0.0, 0.12), periodic_y=(0.0, 0.12)),
        outputs=Outputs3D(every=2, snapshots=(0, 10), track_spheres=(0, 1)))


def _set(obj, **kw):
    return replace(obj, **kw)


@fault3d("3d scene", "scene number")
def _(pick):
    key = pick(["dt", "dt_fraction", "skin", "local_damping", "max_overlap"])
    pools = {"dt": BAD_POSITIVE, "dt_fraction": BAD_POSITIVE, "skin": BAD_POSITIVE,
             "local_damping": BAD_NONNEG + [1.0, 1.5], "max_overlap": BAD_POSITIVE + [0.6, 1.0]}
    v = pick([x for x in pools[key] if not (x is None and key in ("dt", "skin"))])
    return _set(base3d(), **{key: v}), f"scene.{key}", v


@fault3d("3d scene", "scene whole number or flag")
def _(pick):
    key = pick(["n_steps", "adaptive_damping", "allow_supercritical", "allow_unsafe_dt", "max_contacts"])
    if key == "max_contacts":  # None is valid (no bound)
        v = pick([x for x in BAD_WHOLE if x is not None] + [0, -3])
    else:
        v = pick(BAD_WHOLE if key == "n_steps" else BAD_FLAG)
    return _set(base3d(), **{key: v}), f"scene.{key}", v


@fault3d("3d scene", "gravity")
def _(pick):
    v = pick(BAD_VECTOR3)
    return _set(base3d(), gravity=v), "scene.gravity", v


@fault3d("3d scene", "scene name")
def _(pick):
    v = pick(BAD_IDENT)
    return _set(base3d(), name=v), "scene.name", v


@fault3d("3d spheres", "sphere array entry")
def _(pick):
    key = pick(["x", "y", "z", "radius"])
    v = pick(BAD_ENTRY + ([0.0, -0.01] if key == "radius" else []))
    sc = base3d()
    k = pick([0, 1, 2])
    arr = list(getattr(sc.spheres, key))
    arr[k] = v
    sc.spheres = _set(sc.spheres, **{key: arr})
    return sc, f"scene.spheres.{key}", v


@fault3d("3d spheres", "sphere array length or shape")
def _(pick):
    key = pick(["x", "radius", "velocity", "angular_velocity", "fixed", "material", "mass"])
    sc = base3d()
    bad = {"x": [0.0, 1.0], "radius": [0.01], "velocity": [[0.0, 0.0]] * 3, "angular_velocity": [[0.0] * 3] * 2,
           "fixed": [True], "material": ["g", "g"], "mass": [1.0, 1.0]}[key]
    sc.spheres = _set(sc.spheres, **{key: bad})
    return sc, f"scene.spheres.{key}", bad


@fault3d("3d spheres", "sphere entry of a vector or flag array")
def _(pick):
    key = pick(["velocity", "angular_velocity", "mass", "fixed"])
    sc = base3d()
    v = {"velocity": [[0.0, NAN, 0.0]] * 3, "angular_velocity": [[INF, 0.0, 0.0]] * 3,
         "mass": pick([[1.0, -1.0, 1.0], [1.0, NAN, 1.0], [1.0, 0.0, 1.0]]),
         "fixed": pick([[1, 0, 0], ["yes", False, False], [None, False, False]])}[key]
    sc.spheres = _set(sc.spheres, **{key: v})
    return sc, f"scene.spheres.{key}", v


@fault3d("3d spheres", "sphere material")
def _(pick):
    v = pick(["nope", 5, None])
    sc = base3d()
    sc.spheres = _set(sc.spheres, material=v)
    return sc, "scene.spheres.material", v


@fault3d("3d materials", "elastic constants")
def _(pick):
    key = pick(["young", "poisson", "density"])
    pool = {"young": [NAN, -INF, -1.0, 0.0] + [x for x in NOT_NUMBERS if x is not None],
            "poisson": [NAN, INF, 0.5, 0.7, -1.0] + [x for x in NOT_NUMBERS if x is not None],
            "density": BAD_NONNEG}[key]
    v = pick(pool)
    sc = base3d()
    m = sc.materials["g"]
    sc.materials = dict(sc.materials, g=_set(m, **{key: v}))
    return sc, f"scene.materials['g'].{key}", v


@fault3d("3d laws", "Hertz-Mindlin number")
def _(pick):
    key = pick(["friction", "restitution", "restitution_tangential"])
    v = pick(BAD_NONNEG + ([0.0, 1.5] if key != "friction" else []))
    if v is None and key == "restitution_tangential":
        v = 2.0
    sc = base3d()
    sc.laws = dict(sc.laws, **{}) | {("g", "g"): _set(sc.laws[("g", "g")], **{key: v})}
    return sc, f"scene.laws[('g', 'g')].{key}", v


@fault3d("3d laws", "Hertz-Mindlin choice")
def _(pick):
    key = pick(["damping", "tangential", "shear_spring", "friction_cap", "history_rotation"])
    v = pick(["nope", None, 1, "YADE"])
    sc = base3d()
    sc.laws = dict(sc.laws) | {("g", "g"): _set(sc.laws[("g", "g")], **{key: v})}
    return sc, f"scene.laws[('g', 'g')].{key}", v


@fault3d("3d walls", "plane geometry")
def _(pick):
    key = pick(["point", "normal"])
    v = pick(BAD_VECTOR3 + ([(0.0, 0.0, 0.0)] if key == "normal" else []))
    sc = base3d()
    planes = list(sc.planes)
    k = pick([0, 1])
    planes[k] = _set(planes[k], **{key: v})
    sc.planes = planes
    return sc, f"scene.planes[{k}].{key}", v


@fault3d("3d walls", "plane name or material")
def _(pick):
    key = pick(["name", "material"])
    v = pick(BAD_IDENT if key == "name" else ["nope", None, 5])
    sc = base3d()
    planes = list(sc.planes)
    planes[0] = _set(planes[0], **{key: v})
    sc.planes = planes
    return sc, f"scene.planes[0].{key}", v


@fault3d("3d walls", "plane phase")
def _(pick):
    key = pick(["cycles", "velocity"])
    v = pick(BAD_WHOLE if key == "cycles" else BAD_VECTOR3)
    sc = base3d()
    planes = list(sc.planes)
    planes[0] = _set(planes[0], phases=(_set(planes[0].phases[0], **{key: v}),))
    sc.planes = planes
    return sc, f"scene.planes[0].phases[0].{key}", v


@fault3d("3d walls", "plate servo")
def _(pick):
    key = pick(["force", "gain", "v_max", "start"])
    v = pick(BAD_WHOLE if key == "start" else BAD_POSITIVE)
    sc = base3d()
    planes = list(sc.planes)
    planes[1] = _set(planes[1], servo=_set(planes[1].servo, **{key: v}))
    sc.planes = planes
    return sc, f"scene.planes[1].servo.{key}", v


@fault3d("3d walls", "triangle mesh")
def _(pick):
    key = pick(["vertices", "triangles", "material", "name", "phases", "periodic_images"])
    sc = base3d()
    m = sc.meshes[0]
    v = {"vertices": pick([[(0.0, 0.0)], [(NAN, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)], "abc"]),
         "triangles": pick([[(0, 1, 3)], [(0, 1)], [(0.0, 1.0, 2.0)], [(0, 0, 1)], []]),
         "material": pick(["nope", None]), "name": pick(BAD_IDENT),
         "phases": (PlanePhase(pick([-1, 1.5, None]), (0.0, 0.0, 0.0)),),
         "periodic_images": pick(["yes", None, 2])}[key]
    sc.meshes = [_set(m, **{key: v})]
    path = "scene.meshes[0]." + ("phases[0].cycles" if key == "phases" else key)
    return sc, path, v


@fault3d("3d clumps", "clump field")
def _(pick):
    key = pick(["x", "orientation", "velocity", "angular_velocity", "material", "template"])
    sc = base3d()
    c = sc.clumps
    v = {"x": pick([[NAN, 0.07], [0.03], "ab"]),
         "orientation": pick([[[1.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0]] * 2, [[NAN, 0, 0, 1]] * 2]),
         "velocity": pick([[[0.0, 0.0]] * 2, [[INF, 0.0, 0.0]] * 2]),
         "angular_velocity": pick([[[0.0, NAN, 0.0]] * 2, [[0.0] * 3]]),
         "material": pick(["nope", None]), "template": pick([None, "ellipsoid", 5])}[key]
    sc.clumps = _set(c, **{key: v})
    return sc, f"scene.clumps.{key}", v


def base3d_ellipsoids() -> Scene3D:
    """Two ellipsoids over a floor under a mesh ramp, periodic x/y (the ellipsoid family of the 3D scene)."""
    sc = base3d()
    return replace(sc, spheres=None, clumps=None, planes=sc.planes[:1], outputs=Outputs3D(every=2, track_spheres=(0,)),
                   ellipsoids=Ellipsoids(axes=[[0.012, 0.01, 0.008], [0.01, 0.01, 0.01]], x=[0.03, 0.07], y=[0.05, 0.05],
                                         z=[0.03, 0.03], material="g", orientation=[[1.0, 0.0, 0.0, 0.0]] * 2,
                                         velocity=[[0.0, 0.0, -0.1]] * 2, angular_velocity=[[0.0, 1.0, 0.0]] * 2))


@fault3d("3d ellipsoids", "ellipsoid field")
def _(pick):
    key = pick(["axes", "x", "y", "z", "orientation", "velocity", "angular_velocity", "material", "family"])
    sc = base3d_ellipsoids()
    if key == "family":  # the scene entry itself: not an Ellipsoids
        v = pick([5, "ellipsoids", [1.0, 2.0]])
        return replace(sc, ellipsoids=v), "scene.ellipsoids", v
    v = {"axes": pick([[[0.01, 0.01, 0.0], [0.01] * 3], [[0.01, 0.01]] * 2, [[NAN, 0.01, 0.01]] * 2,
                       [[0.01, -0.01, 0.01]] * 2, "abc", [[0.01, "a", 0.01]] * 2]),
         "x": pick([[NAN, 0.07], [0.03], "ab"]), "y": pick([[0.05, INF], [0.05], None]),
         "z": pick([[0.03, "a"], [0.03, 0.03, 0.03]]),
         "orientation": pick([[[1.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0]] * 2, [[NAN, 0, 0, 1]] * 2]),
         "velocity": pick([[[0.0, 0.0]] * 2, [[INF, 0.0, 0.0]] * 2]),
         "angular_velocity": pick([[[0.0, NAN, 0.0]] * 2, [[0.0] * 3]]),
         "material": pick(["nope", None, ["g"]])}[key]
    sc.ellipsoids = _set(sc.ellipsoids, **{key: v})
    return sc, f"scene.ellipsoids.{key}", v


@fault3d("3d outputs", "outputs")
def _(pick):
    key = pick(["every", "snapshots", "track_spheres", "orientation"])
    v = {"every": pick(BAD_WHOLE), "snapshots": pick([(-1,), (1.5,), (NAN,), "ab", (None,)]),
         "track_spheres": pick([(99,), (-1,), (1.5,), ("a",), (None,)]), "orientation": pick(BAD_FLAG)}[key]
    sc = base3d()
    sc.outputs = _set(sc.outputs, **{key: v})
    return sc, f"scene.outputs.{key}", v


@fault3d("3d box", "periodic bounds")
def _(pick):
    key = pick(["periodic_x", "periodic_y"])
    v = pick([(1.0, 0.0), (NAN, 1.0), (0.0, INF), "ab", (0.0,), (0.0, 0.01)])
    sc = base3d()
    sc.box = _set(sc.box, **{key: v})
    return sc, f"scene.box.{key}", v


@fault3d("3d scene", "energy check")
def _(pick):
    v = pick(["stop", "Raise", "", None, 1, True, ["raise"]])
    return _set(base3d(), energy_check=v), "scene.energy_check", v


CATEGORIES3D = sorted({f.category for f in FAULTS3D})


def field_paths3d() -> list[str]:
    """Every dataclass field of the 3D scene objects (for the coverage test)."""
    out = []
    for cls in (Scene3D, Spheres, Plane, PlanePhase, PlateServo, TriangleMesh, Clumps, Ellipsoids, Outputs3D,
                HertzMindlinLaw):
        out += [f"{cls.__name__}.{f.name}" for f in dataclasses.fields(cls)]
    return out
