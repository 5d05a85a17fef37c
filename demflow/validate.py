"""Every field of a scene checked before anything is computed (issue 19).

:func:`check_scene` walks the scene and refuses the first invalid field with a
:class:`~demflow.scene.SceneError` that names the field by its dotted path from the scene
(``scene.walls[2].servo.v_max``), the value, the rule it breaks and the fix: its type (a bool is not
a number, a string is not a number, a float with a fraction is not a count), finiteness, sign and
range, and the references between objects (declared materials, walls, law pairs, tracked bodies).
What needs the built geometry (initial overlaps, the critical time step, the period against the
neighbour reach, the fluid boundary) is checked by :func:`demflow.build.build` after it, which also
checks the per-disc arrays (:func:`demflow.build._check_discs`).

Each scene object checks its own fields (``Wall.check``, ``Servo.check``, ``LinearLaw.check``, ...:
:mod:`demflow.scene`); a new object does the same with the helpers there (``check_number``,
``check_whole``, ``check_vector``, ``check_name``, ``check_flag``, ...) and is called from here.
"""
from __future__ import annotations

from .laws import FAMILIES
from .scene import (Box, ContactModel, Discs, GlobalDamping, Material, Outputs, Scene, SceneError, Superquadrics, Wall,
                    check_choice, check_flag, check_items, check_name, check_number, check_type, check_vector,
                    check_whole, type_phrase)


def check_scene(scene) -> None:
    """Refuse the first invalid field of ``scene`` (see the module docstring)."""
    check_type("scene", scene, Scene)
    check_name("scene.name", scene.name)
    check_type("scene.description", scene.description, str)
    check_type("scene.discs", scene.discs, (Discs, Superquadrics))
    materials = _check_materials(scene)
    if isinstance(scene.discs, Superquadrics):
        scene.discs.check("scene.discs")
    _check_laws(scene, materials)
    check_type("scene.contact_model", scene.contact_model, ContactModel)
    scene.contact_model.check("scene.contact_model")
    check_type("scene.damping", scene.damping, GlobalDamping)
    scene.damping.check("scene.damping")
    check_vector("scene.gravity", scene.gravity, 2, unit="length/time²")
    if scene.dt is not None:
        check_number("scene.dt", scene.dt, gt=0.0, unit="time")
    check_number("scene.dt_fraction", scene.dt_fraction, gt=0.0, le=1.0)
    check_flag("scene.allow_supercritical", scene.allow_supercritical)
    check_flag("scene.allow_unsafe_dt", scene.allow_unsafe_dt)
    check_choice("scene.energy_check", scene.energy_check, ("raise", "warn"))
    check_whole("scene.n_steps", scene.n_steps)
    if scene.skin is not None:
        check_number("scene.skin", scene.skin, gt=0.0, unit="length")
    check_number("scene.overlap_tolerance", scene.overlap_tolerance, ge=0.0)
    check_type("scene.box", scene.box, Box)
    scene.box.check("scene.box")
    walls = check_items("scene.walls", scene.walls)
    names = {}
    for i, w in enumerate(walls):
        path = f"scene.walls[{i}]"
        check_type(path, w, Wall)
        w.check(path, materials)
        if w.name in names:
            raise SceneError(f"{path}.name={w.name!r} is also the name of scene.walls[{names[w.name]}]; "
                             "give every wall its own name")
        names[w.name] = i
    check_type("scene.outputs", scene.outputs, Outputs)
    scene.outputs.check("scene.outputs")
    if scene.fluid is not None:
        from .scene import Fluid

        check_type("scene.fluid", scene.fluid, Fluid, " or None")
        scene.fluid.check("scene.fluid")


def _check_materials(scene) -> set:
    """The declared material names (every key an identifier, every value a Material)."""
    mats = scene.materials
    check_type("scene.materials", mats, dict)
    for name, m in mats.items():
        path = f"scene.materials[{name!r}]"
        check_name(path, name)
        check_type(path, m, Material)
        m.check(path)
    return set(mats)


def _check_laws(scene, materials: set) -> None:
    """Every declared law: its key a pair of declared materials, declared once (not also reversed), and
    its own fields (``law.check(pair)``, which names scene.laws[pair].<field>)."""
    laws = scene.laws
    check_type("scene.laws", laws, dict)
    for key, law in laws.items():
        path = f"scene.laws[{key!r}]"
        if not (isinstance(key, tuple) and len(key) == 2 and all(isinstance(m, str) for m in key)):
            raise SceneError(f"{path}: the key {key!r} is not a pair of material names; key each law by "
                             "(material_a, material_b)")
        bad = [m for m in key if m not in materials]
        if bad:
            raise SceneError(f"{path} names material {bad[0]!r}, which scene.materials does not declare "
                             f"(declared: {sorted(materials)}); declare it or fix the name")
        a, b = key
        if a != b and (b, a) in laws:
            raise SceneError(f"{path} and scene.laws[{(b, a)!r}] both give the law of one material pair; "
                             "declare it once")
        if not any(f.accepts(law) for f in FAMILIES):
            raise SceneError(f"{path}={law!r} is {type_phrase(law)}, which no law family implements; give a "
                             f"law of one of the families {[f.name for f in FAMILIES]}, e.g. LinearLaw(kn=...)")
        law.check(key)
