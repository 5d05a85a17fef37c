"""Micro-mechanical averages of a 3D bed now: coordination, contact-normal fabric, average stress.

Works on a :class:`demflow.simulation3d.Simulation3D` of spheres and rigid clumps (a clump is one
*body*; a sphere that is its own body counts as one) and its plane walls, from the touching pairs
of the last step (``pairs.fn > 0``):

- contact normal n from member i towards member j (its periodic image ``pairs.shift``), or from
  the member towards a plane (minus the plane's normal); force on i: F = -fn n + ft (``ft`` is the
  tangential force on i); contact point x_c = x_i + (R_i - δ/2) n;
- coordination z = 2 C_bb / N_b with C_bb the body pairs in contact (a clump pair touching with
  several members counts once), z_walls = (2 C_bb + C_bw) / N_b with C_bw the (body, plane) pairs;
- fabric φ = (1/N_c) Σ_c n ⊗ n over the member contacts between bodies (3×3, trace 1);
- average stress of ch3 eq 3.17, σ_ab = -(1/V) Σ_b Σ_{c of b} (x_c - X_b)_a F_b (compression
  positive), X_b the body's centre of mass, wall contacts through their body's term only.

Statics (a bed at rest in a box periodic in x and y between a floor at z = 0 and a plate at z = H,
per unit area A): σ_zz V = σ_plate A H + W Z̄ exactly, Z̄ the bed's centre-of-mass height, W its
weight (the interior contact terms cancel in pairs), so σ_zz = σ_plate + (W/A)(Z̄/H);
:func:`statics_stress_zz` gives it, the reference the measured tensor is shown against.
"""
from __future__ import annotations

import numpy as np


def _bodies(sim):
    """(body index of each sphere, body centres (nb, 3), body masses) with free spheres as bodies."""
    sp = sim.spheres
    b = np.array(sp.body, np.int64, copy=True)
    free = b < 0
    nb = len(sim.bodies.mass) if getattr(sim, "bodies", None) is not None else 0
    b[free] = nb + np.arange(int(free.sum()))
    centre = np.vstack([sim.bodies.pos, sp.pos[free]]) if nb else sp.pos[free].copy()
    mass = np.concatenate([sim.bodies.mass, sp.mass[free]]) if nb else sp.mass[free].copy()
    return b, centre, mass


def _min_image(d, sim):
    box = sim.scene.box
    for k, per in enumerate((box.periodic_x, box.periodic_y)):
        if per is not None:
            L = per[1] - per[0]
            d[:, k] -= L * np.round(d[:, k] / L)
    return d


def micro_state(sim, volume: float) -> dict:
    """Coordination, fabric and average stress of ``sim`` now (module docstring); ``volume`` [length³]
    the region the stress is averaged over (the bed: area × plate height).  Planes only (a triangle
    mesh's contacts are left out)."""
    sp, pr = sim.spheres, sim.pairs
    n = sim.n
    npl = len(sim.planes.mat)
    on = pr.fn > 0
    i, j = pr.i[on], pr.j[on]
    fn, ft, ov, shift = pr.fn[on], pr.ft[on], pr.ovl[on], pr.shift[on]
    body, centre, mass = _bodies(sim)
    nb = centre.shape[0]
    rel = _min_image(sp.pos - centre[body], sim)  # member centre relative to its body's
    ss = j < n
    wall = (j >= n) & (j < n + npl)
    ss &= body[i] != body[np.where(ss, j, 0)]
    # sphere-sphere
    si, sj = i[ss], j[ss]
    d = sp.pos[sj] + shift[ss] - sp.pos[si]
    nvec = d / np.linalg.norm(d, axis=1)[:, None]
    F = -fn[ss, None] * nvec + ft[ss]
    lever_i = rel[si] + nvec * (sp.r[si] - 0.5 * ov[ss])[:, None]  # x_c - X_bi
    lever_j = lever_i - rel[si] - d + rel[sj]  # x_c - X_bj (in i's image frame)
    M = lever_i.T @ F - lever_j.T @ F
    # sphere-plane
    wi, w = i[wall], j[wall] - n
    nw = -sim.planes.normal[w]
    Fw = -fn[wall, None] * nw + ft[wall]
    lever_w = rel[wi] + nw * (sp.r[wi] - 0.5 * ov[wall])[:, None]
    M += lever_w.T @ Fw
    sigma = -M / float(volume)
    # distinct body pairs and (body, plane) pairs, each as one integer key (np.unique of a 1D array: the same
    # count as of the rows, several times faster than np.unique(axis=0) on the many records of a loading)
    lo, hi = np.minimum(body[si], body[sj]), np.maximum(body[si], body[sj])
    n_bb = np.unique(lo * nb + hi).size
    n_bw = np.unique(body[wi] * npl + w).size
    fabric = nvec.T @ nvec / max(nvec.shape[0], 1)
    z = 2.0 * n_bb / nb
    return {"coordination": z, "coordination_walls": (2.0 * n_bb + n_bw) / nb,
            "member_contacts_per_body_pair": (float(si.size) / n_bb) if n_bb else float("nan"),
            "fabric": fabric, "stress": sigma, "com_z": float(np.sum(mass * centre[:, 2]) / mass.sum())}


def statics_stress_zz(plate_stress: float, weight: float, area: float, com_z: float, height: float) -> float:
    """σ_zz of a bed at rest between a floor at z = 0 and a plate at ``height`` (module docstring):
    σ_plate + (W/A)(Z̄/H) [stress]."""
    return plate_stress + weight / area * com_z / height
