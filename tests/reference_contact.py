"""A one-contact reference model of the Hertz-Mindlin law, in plain Python floats, with each engine's
conventions as switches (test helper for tests/test_conformance3d.py).

It is written from the equations (demflow.laws.hertz_mindlin's docstring; YADE 2023.02a's
Law2_ScGeom_MindlinPhys_Mindlin and ScGeom::rotate; LIGGGHTS 3.8.0's ``model hertz tangential
history``), independently of demflow's compiled kernels, for scenes of two bodies: two spheres (open
or periodic box) or one sphere and one plane.  Each named difference of the capabilities table is
one field of :class:`Conventions`; the model in an engine's conventions must reproduce that engine
to round-off, and flipping one field at a time measures that difference alone.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from demflow.build import build
from demflow.engines.base3d import trajectory_from_arrays


@dataclass(frozen=True)
class Conventions:
    """shear_spring: "incremental" | "total" | None (the scene's own); rotation of the tangential
    history when the normal turns: "demflow" (project and rescale, before the increment), "yade"
    (T −= T × (n_old × n), then the twist), "liggghts" (increment, then project); plane_radius: R* of a
    sphere-plane contact in units of R (YADE's own box: 0.5); plane_normal_velocity: "ahead" (the
    velocity of the step, demflow) or "behind" (the velocity that moved the plane there, LIGGGHTS);
    friction_cap: None (the scene's own), "total" or "elastic"; dashpot_mass of a sphere pair: "reduced"
    m_i m_j/(m_i + m_j), or one sphere's own mass ("first", "second")."""

    shear_spring: str | None = None
    rotation: str = "demflow"
    plane_radius: float = 1.0
    plane_normal_velocity: str = "ahead"
    friction_cap: str | None = None
    dashpot_mass: str = "reduced"


DEMFLOW = Conventions()
YADE = Conventions(shear_spring="incremental", rotation="yade")
LIGGGHTS = Conventions(shear_spring="total", rotation="liggghts", plane_normal_velocity="behind")


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def run(scene, conv: Conventions = DEMFLOW):
    """Run a two-body scene in the reference model; returns a Trajectory3D (same convention as the
    engines': x_n, v_{n-1/2}, ω_{n-1/2} after n steps; plane force evaluated at x_n)."""
    sim = build(scene)
    sp, law = sim.spheres, sim.law_params
    n_sph, n_pl = sim.n, sim.n_planes
    if n_sph + n_pl != 2:
        raise ValueError("the reference model has two bodies: two spheres, or a sphere and a plane")
    dt = sim.dt
    g = [float(c) for c in sim.g]
    x = [list(map(float, sp.pos[i])) for i in range(n_sph)]
    v = [list(map(float, sp.vel[i])) for i in range(n_sph)]
    w = [list(map(float, sp.angvel[i])) for i in range(n_sph)]
    m = [float(c) for c in sp.mass]
    inertia = [float(c) for c in sp.inertia]
    r = [float(c) for c in sp.r]
    mi = int(sp.mat[0])
    if n_pl:
        mj = int(sim.planes.mat[0])
        p_point = list(map(float, sim.planes.point[0]))
        p_normal = tuple(map(float, sim.planes.normal[0]))
        phases = [(int(ph.cycles), tuple(map(float, ph.velocity))) for ph in scene.planes[0].phases]
    else:
        mj = int(sp.mat[1])
    E, G, mu = float(law.Estar[mi, mj]), float(law.Gstar[mi, mj]), float(law.mu[mi, mj])
    zn, zt = float(law.zn[mi, mj]), float(law.zt[mi, mj])
    tangential = int(law.tangential[mi, mj]) != 0
    spring = conv.shear_spring or ("total" if law.shear_spring == 1 else "incremental")
    cap = conv.friction_cap or ("total" if law.cap == 0 else "elastic")
    box = sim.box

    def plane_velocity(step):
        s0 = 0
        for cyc, vel in phases:
            if s0 <= step < s0 + cyc:
                return vel
            s0 += cyc
        return (0.0, 0.0, 0.0)

    h = [0.0, 0.0, 0.0]
    n_old = None
    every = max(int(scene.outputs.every), 1)
    s_steps, s_rows, p_steps, p_rows = [0], [[x[i] + v[i] + w[i] for i in range(n_sph)]], [], []
    for step in range(int(scene.n_steps)):
        vp = plane_velocity(step) if n_pl else None
        # --- contact geometry: n from body i (sphere 0) to body j, overlap, arms, reduced values
        if n_pl:
            nrm = (-p_normal[0], -p_normal[1], -p_normal[2])
            hgt = -((x[0][0] - p_point[0]) * nrm[0] + (x[0][1] - p_point[1]) * nrm[1]
                    + (x[0][2] - p_point[2]) * nrm[2])
            delta = r[0] - hgt
            rstar = r[0] * conv.plane_radius
            meff = m[0]
        else:
            d = [x[1][a] - x[0][a] for a in range(3)]
            if box.periodic_x:
                d[0] += -box.lx * math.floor(d[0] / box.lx + 0.5)
            if box.periodic_y:
                d[1] += -box.ly * math.floor(d[1] / box.ly + 0.5)
            dist = math.sqrt(_dot(d, d))
            delta = r[0] + r[1] - dist
            nrm = (d[0] / dist, d[1] / dist, d[2] / dist)
            rstar = r[0] * r[1] / (r[0] + r[1])
            meff = {"reduced": m[0] * m[1] / (m[0] + m[1]), "first": m[0], "second": m[1]}[conv.dashpot_mass]
        F = (0.0, 0.0, 0.0)
        Ti = Tj = (0.0, 0.0, 0.0)
        if delta <= 0.0:
            h = [0.0, 0.0, 0.0]
            n_old = None
        else:
            ai = r[0] - 0.5 * delta
            aj = (r[1] - 0.5 * delta) if not n_pl else 0.0
            wi = _cross(w[0], nrm)
            vci = [v[0][a] + ai * wi[a] for a in range(3)]
            if n_pl:
                vcj = list(vp)
                if conv.plane_normal_velocity == "behind" and step > 0:  # normal part of the previous step's
                    prev = plane_velocity(step - 1)
                    for a in range(3):
                        if p_normal[a] != 0.0:
                            vcj[a] = prev[a]
            else:
                wj = _cross(w[1], nrm)
                vcj = [v[1][a] - aj * wj[a] for a in range(3)]
            rv = [vci[a] - vcj[a] for a in range(3)]
            vn = _dot(rv, nrm)
            vt = [rv[a] - vn * nrm[a] for a in range(3)]
            a_c = math.sqrt(rstar * delta)
            kn = 2.0 * E * a_c
            Fe = 4.0 / 3.0 * E * a_c * delta
            Fn = Fe + 2.0 * zn * math.sqrt(meff * kn) * vn if zn > 0.0 else Fe
            Fn = max(Fn, 0.0)
            T = (0.0, 0.0, 0.0)
            if tangential:
                kt = 8.0 * G * a_c
                # --- the history into the current tangent plane
                if conv.rotation == "demflow":
                    h2 = _dot(h, h)
                    if h2 > 0.0:
                        hn = _dot(h, nrm)
                        t = [h[a] - hn * nrm[a] for a in range(3)]
                        t2 = _dot(t, t)
                        s = math.sqrt(h2 / t2) if t2 > 0.0 else 0.0
                        h = [t[a] * s for a in range(3)]
                elif conv.rotation == "yade" and n_old is not None:
                    ax = _cross(n_old, nrm)
                    c = _cross(h, ax)
                    h = [h[a] - c[a] for a in range(3)]
                    wsum = [w[0][a] + (w[1][a] if not n_pl else 0.0) for a in range(3)]
                    tw = dt * 0.5 * _dot(n_old, wsum)
                    c = _cross(h, (tw * n_old[0], tw * n_old[1], tw * n_old[2]))
                    h = [h[a] - c[a] for a in range(3)]
                # --- the spring
                if spring == "total":
                    h = [h[a] + vt[a] * dt for a in range(3)]
                    if conv.rotation == "liggghts":
                        hn = _dot(h, nrm)
                        h = [h[a] - hn * nrm[a] for a in range(3)]
                    T = (-kt * h[0], -kt * h[1], -kt * h[2])
                else:
                    T = (h[0] - kt * vt[0] * dt, h[1] - kt * vt[1] * dt, h[2] - kt * vt[2] * dt)
                tcap = mu * (Fn if cap == "total" else Fe)
                T2 = _dot(T, T)
                if T2 > tcap * tcap:
                    s = tcap / math.sqrt(T2)
                    T = (T[0] * s, T[1] * s, T[2] * s)
                    h = [h[a] * s for a in range(3)] if spring == "total" else list(T)
                else:
                    if spring == "incremental":
                        h = list(T)
                    if zt > 0.0:
                        ct = 2.0 * zt * math.sqrt(meff * kt)
                        T = (T[0] - ct * vt[0], T[1] - ct * vt[1], T[2] - ct * vt[2])
            F = (-Fn * nrm[0] + T[0], -Fn * nrm[1] + T[1], -Fn * nrm[2] + T[2])
            c = _cross(nrm, T)
            Ti = (ai * c[0], ai * c[1], ai * c[2])
            Tj = (aj * c[0], aj * c[1], aj * c[2])
            n_old = nrm
        if step % every == 0 and n_pl:
            p_steps.append(step)
            p_rows.append([[-F[0], -F[1], -F[2]]])
        # --- integration (v_{n+1/2} = v_{n-1/2} + Δt F/m; x_{n+1} = x_n + Δt v_{n+1/2})
        forces = [F, (-F[0], -F[1], -F[2])]
        torques = [Ti, Tj]
        for i in range(n_sph):
            for a in range(3):
                v[i][a] += dt * (forces[i][a] / m[i] + g[a])
                x[i][a] += dt * v[i][a]
                w[i][a] += dt * torques[i][a] / inertia[i]
        if n_pl:
            p_point = [p_point[a] + dt * vp[a] for a in range(3)]
        if (step + 1) % every == 0:
            s_steps.append(step + 1)
            s_rows.append([x[i] + v[i] + w[i] for i in range(n_sph)])
    return trajectory_from_arrays(sim, "reference", s_steps, np.array(s_rows), p_steps,
                                  np.array(p_rows).reshape(len(p_steps), n_pl, 3))


def conventions_for(engine: str, variant: str) -> Conventions:
    """The reference model's conventions for an engine's stored run of a conformance-3d variant
    (with the variant's engine options: YADE's own box is plane_radius 0.5).  YADE's default
    avoidGranularRatcheting (variant periodic-pair-ratcheting) has no switch here: its rule is not a
    plain lever-arm change (R instead of R − δ/2 misses YADE's run by 3e-4) and is only measured."""
    base = {"demflow": DEMFLOW, "yade": YADE, "liggghts": LIGGGHTS}[engine]
    if (variant, engine) == ("oblique-plane-r2", "yade"):
        return replace(base, plane_radius=0.5)
    return base
