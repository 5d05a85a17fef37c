"""What a built simulation carries: the physics manifest (issue 17 item 5, "model only what a scene
requires").

:func:`physics_manifest` reads a built 2D or 3D simulation (never the scene's intentions: what build
actually allocated and selected) and lists the contact-law family and its compiled variant, the
per-contact history arrays and their width, the fluid machinery (BEM elements, Gauss rule, solve
stride) or its absence, damping, walls and servos, periodic axes, bodies (clumps) and orientation
integration, and the memory of the state arrays.  ``Results.meta["physics"]`` (and so ``meta.json``)
and the report's case pages carry it.
"""
from __future__ import annotations

import numpy as np


def _nbytes(obj) -> int:
    """Bytes of the NumPy arrays held by a namedtuple-like structure (or an array)."""
    if isinstance(obj, np.ndarray):
        return int(obj.nbytes)
    fields = getattr(obj, "_fields", None)
    if fields is None:
        return 0
    return int(sum(getattr(obj, f).nbytes for f in fields if isinstance(getattr(obj, f), np.ndarray)))


def _law(sim, dim: int) -> dict:
    law = sim.law
    out = dict(family=law.name, kernel=type(sim.law_params).__name__,
               history_columns_per_contact=int(law.history_width(dim)))
    for flag in ("has_shear", "damping", "tangential", "shear_spring", "friction_cap"):
        v = getattr(law, flag, None)
        if isinstance(v, (bool, np.bool_, str, int, float)):
            out[flag] = v.item() if isinstance(v, np.generic) else v
    cm = getattr(sim.scene, "contact_model", None)
    if cm is not None and dim == 2:
        out.update(normal=cm.normal, sliding=cm.sliding)
    return out


def physics_manifest(sim) -> dict:
    """The manifest of a built simulation (module docstring): plain JSON types only."""
    dim = 3 if hasattr(sim, "spheres") else 2
    scene = sim.scene
    m = dict(dim=dim, law=_law(sim, dim))
    if dim == 2:
        d = sim.discs
        m.update(particles=dict(kind="discs", n=int(sim.n)),
                 contact_history=dict(rows=int(sim.pairs.hist.shape[0]), columns=int(sim.pairs.hist.shape[1])),
                 walls=dict(n=int(sim.nw), servos=int(sum(w.servo is not None for w in scene.walls)),
                            moving=int(sum(bool(w.phases) for w in scene.walls))),
                 damping=dict(global_translation=bool(np.any(d.C != 0)), global_rotation=bool(np.any(d.Cr != 0))),
                 periodic=[a for a, on in (("x", getattr(scene.box, "periodic_x", None)),
                                          ("y", getattr(scene.box, "periodic_y", None))) if on],
                 external_force=bool(sim.has_external_force))
        if sim.fluid is None:
            m["fluid"] = None
        else:
            fs = sim.fluid.setup
            m["fluid"] = dict(model="Stokes BEM (thesis ch. 4)", boundaries=len(sim.fluid.names),
                              **{k: (v.item() if isinstance(v, np.generic) else v)
                                 for k, v in vars(fs).items() if isinstance(v, (int, float, str, bool, np.generic))})
        state = _nbytes(d) + _nbytes(sim.pairs) + _nbytes(sim.walls)
    else:
        sp = sim.spheres
        nb = int(sim.bodies.pos.shape[0]) if getattr(sim, "bodies", None) is not None else 0
        m.update(particles=dict(kind="spheres", n=int(sim.n), clump_bodies=nb),
                 contact_history=dict(rows=int(sim.pairs.hist.shape[0]), columns=int(sim.pairs.hist.shape[1])),
                 planes=int(sim.planes.point.shape[0]), mesh_triangles=int(sim.tris.v.shape[0]),
                 orientation_integrated=bool(scene.outputs.orientation or nb > 0),
                 damping=dict(mass_proportional=bool(np.any(np.asarray(sim.damping.alpha) != 0)),
                              local=bool(np.any(np.asarray(sim.damping.local) != 0)),
                              adaptive=bool(np.any(np.asarray(sim.damping.adaptive)))),
                 periodic=[a for a, on in (("x", sim.box.periodic_x), ("y", sim.box.periodic_y)) if on],
                 fluid=None)
        state = _nbytes(sp) + _nbytes(sim.pairs) + _nbytes(sim.planes) + _nbytes(sim.tris)
        if nb:
            state += _nbytes(sim.bodies)
    m["state_bytes"] = int(state)
    return m


def describe(m: dict) -> str:
    """One line for a report: 'discs 197 · linear (LinearParams, 2 history columns) · no fluid · ...'."""
    p = m["particles"]
    law = m["law"]
    parts = [f"{p['kind']} {p['n']}", f"{law['family']} ({law['kernel']}, {law['history_columns_per_contact']} "
             f"history column{'s' if law['history_columns_per_contact'] != 1 else ''} per contact)"]
    f = m.get("fluid")
    parts.append("no fluid" if f is None else f"fluid: {f['model']}, {f.get('boundaries', '?')} boundaries")
    if m.get("periodic"):
        parts.append("periodic " + "".join(m["periodic"]))
    dm = m.get("damping", {})
    on = [k for k, v in dm.items() if v]
    parts.append("damping: " + (", ".join(on) if on else "none"))
    parts.append(f"state {m['state_bytes'] / 1024:.0f} KiB")
    return " · ".join(parts)


__all__ = ["physics_manifest", "describe"]
