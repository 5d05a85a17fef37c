# demflow deck for YADE (2023.02a): 2D discs, linear spring-dashpot-Coulomb contacts, walls with
# prescribed motion.  This program is fixed; the scene reaches it only as numbers and validated
# identifiers in scene.json (written by demflow.engines.yade).  Run: yade -n -x deck.py
# Model (see demflow's equivalence table): spheres with blockedDOFs 'zXY' and the disc mass and
# inertia per body; ViscElMat per material with the per-pair contact values split in series;
# walls as fixed boxes whose velocity a PyRunner sets each step (after the InteractionLoop, before
# the NewtonIntegrator); global damping applied as the force that reproduces thesis eq 2.27.
# Periodic along x (scene.json "periodic_x"): a periodic cell, walls as boxes longer than the period, and the
# disc-wall contacts created from the walls' geometry before the InteractionLoop (2023.02a's periodic collider
# misses some contacts with bodies bigger than the period).  Disc-wall laws YADE's series rule cannot give
# ("wall_phys"): each such contact is created the same way and given the pair's ViscElPhys when it forms.
import json
import math
import os
import sys

import numpy as np
from yade import O, Quaternion, Vector3, utils
from yade.wrapper import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, Ig2_Box_Sphere_ScGeom,
                          Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_ViscElMat_ViscElMat_ViscElPhys, Law2_ScGeom_ViscElPhys_Basic,
                          NewtonIntegrator, PyRunner, ViscElMat)

S = json.load(open("scene.json"))
dt = float(S["dt"])
n = int(S["n_discs"])
D = S["discs"]
gx, gy = S["gravity"]
mat_id = {}
for m in S["materials"]:
    p = S["yade_materials"][m]
    mat_id[m] = O.materials.append(ViscElMat(kn=p["kn"], ks=p["ks"], cn=p["cn"], cs=p["cs"],
                                             frictionAngle=p["phi"], density=1.0))
for i in range(n):
    b = utils.sphere((D["x"][i], D["y"][i], 0.0), D["r"][i], material=mat_id[D["material"][i]])
    b.state.mass = D["mass"][i]
    I = D["inertia"][i]
    b.state.inertia = (I, I, I)
    b.state.blockedDOFs = "zXY"
    b.state.vel = (D["vx"][i], D["vy"][i], 0.0)
    b.state.angVel = (0.0, 0.0, D["omega"][i])
    O.bodies.append(b)
W = S["walls"]
rmax = max(D["r"])
thick = S["wall_thickness"]
P = []  # reference point P of each wall, tracked as demflow tracks it
for w in W:
    L = w["h2"] - w["h1"]
    cx = w["px"] + 0.5 * (w["h1"] + w["h2"]) * w["ex"] - 0.5 * thick * w["nx_in"]
    cy = w["py"] + 0.5 * (w["h1"] + w["h2"]) * w["ey"] - 0.5 * thick * w["ny_in"]
    ang = math.atan2(w["ey"], w["ex"])
    q = Quaternion((0, 0, 1), ang)
    b = utils.box((cx, cy, 0.0), (0.5 * L, 0.5 * thick, 20.0 * rmax), orientation=q, fixed=True,
                  material=mat_id[w["material"]])
    O.bodies.append(b)
    P.append([w["px"], w["py"]])

PX = S.get("periodic_x")
WP = S.get("wall_phys") or {}
if PX is not None:
    ext = max(max(abs(v) for v in D["y"]), max(abs(w["py"]) for w in W), PX[1] - PX[0]) + 10.0 * rmax
    O.periodic = True
    O.cell.setBox(PX[1] - PX[0], 1000.0 * ext, 1000.0 * ext)
# walls whose disc contacts the deck creates itself (periodic scene: every wall; else those with "wall_phys")
own = [w for w in range(len(W)) if PX is not None or W[w]["material"] in WP]
side = [W[w]["nx_in"] * -W[w]["ey"] + W[w]["ny_in"] * W[w]["ex"] for w in range(len(W))]  # n_in = side (-e_y, e_x)


def wall_contacts():
    for w in own:
        wid = n + w
        e = O.bodies[wid].state.ori * Vector3(1, 0, 0)
        ex, ey = e[0], e[1]
        nx, ny = -side[w] * ey, side[w] * ex
        laws = WP.get(W[w]["material"])
        for i in range(n):
            pos = O.bodies[i].state.pos
            dx, dy = pos[0] - P[w][0], pos[1] - P[w][1]
            t = dx * ex + dy * ey
            if dx * nx + dy * ny >= D["r"][i] or not W[w]["h1"] <= t <= W[w]["h2"]:
                continue
            inter = O.interactions[i, wid] if O.interactions.has(i, wid) else None
            if inter is None or not inter.isReal:
                try:
                    inter = utils.createInteraction(i, wid)
                except RuntimeError:  # the box-sphere geometry finds no overlap (a last-bit difference)
                    continue
            if laws is not None:
                L = laws[D["material"][i]]
                ph = inter.phys
                if ph.kn != L["kn"]:  # set on YADE's own object: a ViscElPhys made in Python crashes the
                    # run when YADE frees it without the GIL (2023.02a, measured)
                    ph.kn, ph.ks, ph.cn, ph.cs = L["kn"], L["ks"], L["cn"], L["cs"]
                    ph.tangensOfFrictionAngle = L["mu"]


C = S["damping"]["C"]
Cr = S["damping"]["Cr"]
damped = any(c > 0 for c in C) or any(c > 0 for c in Cr)
every = int(S["every"])
snapshots = set(int(s) for s in S["snapshots"])
track = S["track"]
rec = dict(step=[], wall=[], wallpos=[], track=[], kinetic=[])
snaps = []


def phase_of(w, step):
    s0 = 0
    for ph in W[w]["phases"]:
        if s0 <= step < s0 + ph["cycles"]:
            return ph
        s0 += ph["cycles"]
    return None


def walls():
    step = O.iter
    for w in range(len(W)):
        b = O.bodies[n + w]
        ph = phase_of(w, step)
        vx = vy = om = 0.0
        pivx, pivy = P[w]
        if ph is not None:
            vx, vy, om = ph["vx"], ph["vy"], ph["omega"]
            if ph["pivot"] is not None:
                pivx, pivy = ph["pivot"]
        pos = b.state.pos
        b.state.vel = (vx - om * (pos[1] - pivy), vy + om * (pos[0] - pivx), 0.0)
        b.state.angVel = (0.0, 0.0, om)
        # P moves as demflow moves it: rotate about the pivot, then translate
        a = om * dt
        rx, ry = P[w][0] - pivx, P[w][1] - pivy
        P[w] = [pivx + math.cos(a) * rx - math.sin(a) * ry + vx * dt,
                pivy + math.sin(a) * rx + math.cos(a) * ry + vy * dt]


def damping():
    # force that turns Newton's explicit update into thesis eq 2.27/2.28 (implicit global damping)
    for i in range(n):
        b = O.bodies[i]
        m, I = D["mass"][i], D["inertia"][i]
        F = O.forces.f(i)
        T = O.forces.t(i)
        v = b.state.vel
        a = C[i] * dt / (2.0 * m)
        vnx = (v[0] * (1 - a) + (F[0] / m + gx) * dt) / (1 + a)
        vny = (v[1] * (1 - a) + (F[1] / m + gy) * dt) / (1 + a)
        c = Cr[i] * dt / (2.0 * I)
        w = b.state.angVel[2]
        wn = (w * (1 - c) + T[2] * dt / I) / (1 + c)
        O.forces.addF(i, (m * (vnx - v[0]) / dt - F[0] - m * gx, m * (vny - v[1]) / dt - F[1] - m * gy, 0.0))
        O.forces.addT(i, (0.0, 0.0, I * (wn - w) / dt - T[2]))


def pair_forces(inter, a):
    """(fn, fs, ex, ey, px, py, overlap) of an interaction, seen from body a (demflow's finder)."""
    nrm = inter.geom.normal
    sgn = 1.0 if inter.id1 == a else -1.0  # YADE's normal points from id1 to id2
    ex, ey = sgn * nrm[0], sgn * nrm[1]
    fnv = inter.phys.normalForce
    fsv = inter.phys.shearForce  # force on id2
    fn = math.hypot(fnv[0], fnv[1])
    # force on the other body is Fn ε + Fs τ, τ = (ε_y, -ε_x)
    sx, sy = (fsv[0], fsv[1]) if inter.id1 == a else (-fsv[0], -fsv[1])
    fs = sx * ey - sy * ex
    cp = inter.geom.contactPoint
    return fn, fs, ex, ey, cp[0], cp[1], inter.geom.penetrationDepth


def record():
    step = O.iter
    if step in snapshots:
        take_snapshot(step)
    if every > 0 and step % every == 0:
        rec["step"].append(step)
        row, pos = [], []
        for w in range(len(W)):
            f = O.forces.f(n + w)
            t = O.forces.t(n + w)
            c = O.bodies[n + w].state.pos
            # moment about P: torque about the box centre plus (c - P) × F
            mp = t[2] + (c[0] - P[w][0]) * f[1] - (c[1] - P[w][1]) * f[0]
            row.append([f[0], f[1], mp])
            pos.append(list(P[w]))
        rec["wall"].append(row)
        rec["wallpos"].append(pos)
        tr = []
        for a, b in track:
            inter = O.interactions[a, b] if O.interactions.has(a, b) else None
            if inter is not None and inter.isReal:
                fn, fs = pair_forces(inter, a)[:2]
                tr.append([fn, fs])
            else:
                tr.append([0.0, 0.0])
        rec["track"].append(tr)
        ke = sum(0.5 * (D["mass"][i] * (O.bodies[i].state.vel[0] ** 2 + O.bodies[i].state.vel[1] ** 2)
                        + D["inertia"][i] * O.bodies[i].state.angVel[2] ** 2) for i in range(n))
        rec["kinetic"].append(ke)


def take_snapshot(step):
    parts = [[O.bodies[i].state.pos[0], O.bodies[i].state.pos[1], O.bodies[i].state.ori.toAxisAngle()[1] *
              O.bodies[i].state.ori.toAxisAngle()[0][2], O.bodies[i].state.vel[0], O.bodies[i].state.vel[1],
              O.bodies[i].state.angVel[2], D["r"][i]] for i in range(n)]
    cons = []
    for inter in O.interactions:
        if not inter.isReal:
            continue
        i1, i2 = inter.id1, inter.id2
        if i1 >= n and i2 >= n:
            continue
        if i2 >= n or i1 >= n:
            a, b = (i1, i2) if i1 < n else (i2, i1)
        else:
            r1, r2 = D["r"][i1], D["r"][i2]
            a, b = (i1, i2) if (r1 > r2 or (r1 == r2 and i1 < i2)) else (i2, i1)
        fn, fs, ex, ey, px, py, ov = pair_forces(inter, a)
        cons.append([a, b, px, py, ex, ey, fn, fs, ov])
    walls_now = [[P[w][0], P[w][1]] + list(O.bodies[n + w].state.ori * Vector3(1, 0, 0))[:2] for w in range(len(W))]
    snaps.append(dict(step=step, particles=parts, contacts=cons, walls=walls_now))


engines = [ForceResetter(),
           InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()], allowBiggerThanPeriod=True)
           if PX is not None else InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()])]
if own:
    engines.append(PyRunner(command="wall_contacts()", iterPeriod=1, initRun=True))
loop = InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
                       [Ip2_ViscElMat_ViscElMat_ViscElPhys()], [Law2_ScGeom_ViscElPhys_Basic()])
n_force = len(engines) + 1  # the engines that compute forces: up to and including the InteractionLoop
engines += [loop,
           PyRunner(command="record()", iterPeriod=1, initRun=True),
           PyRunner(command="walls()", iterPeriod=1, initRun=True)]
if damped:
    engines.append(PyRunner(command="damping()", iterPeriod=1, initRun=True))
engines.append(NewtonIntegrator(damping=0.0, gravity=(gx, gy, 0.0)))
O.engines = engines
O.dt = dt
O.run(int(S["n_steps"]), True)
if int(S["n_steps"]) in snapshots:
    O.engines = engines[:n_force]
    O.forces.reset()
    O.step()  # evaluate forces at the final state without moving (snapshot semantics)
    take_snapshot(int(S["n_steps"]))

out = dict(rec=rec, snapshots=snaps, complete=True, yade_version=str(__import__("yade.config").config.version))
with open("yade_out.json.tmp", "w") as fh:
    json.dump(out, fh)
os.replace("yade_out.json.tmp", "yade_out.json")
sys.exit(0)
