# demflow deck for YADE (2023.02a): 3D spheres, Hertz-Mindlin contacts, planes with prescribed
# translation.  This program is fixed; the scene reaches it only as numbers and validated
# identifiers in scene.json (written by demflow.engines.yade3d).  Run: yade -n -j1 -x deck.py
# Model (see demflow's capabilities table): FrictMat per material, Ip2_FrictMat_FrictMat_MindlinPhys
# with betan/betas (demflow's damping ratios) and the friction angle per material pair,
# Law2_ScGeom_MindlinPhys_Mindlin; mass and inertia set per body to demflow's values; planes as
# boxes whose material is chosen by demflow so that YADE's box-sphere geometry (equivalent radius
# R/2) gives demflow's normal and tangential stiffness (scene.json "yade_materials"); before the
# InteractionLoop of each step a plane's box is put at the plane's point (advanced as demflow
# advances it) and given that step's velocity.
# Output yade_out.json: after each recorded step n the centres x_n, v_{n-1/2}, w_{n-1/2}, and
# the force of the spheres on each plane evaluated at x_n.
import json
import math
import os
import sys

from yade import O, Quaternion, Vector3, utils
from yade.wrapper import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                          Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin, MatchMaker,
                          NewtonIntegrator, PyRunner)

S = json.load(open("scene.json"))
dt = float(S["dt"])
n = int(S["n_spheres"])
D = S["spheres"]
every = int(S["every"])
n_steps = int(S["n_steps"])
shift = S["yade_shift"]  # added to demflow's coordinates (YADE's periodic cell starts at 0)

mat_id = {}
for name, m in S["yade_materials"].items():
    mat_id[name] = O.materials.append(FrictMat(young=m["young"], poisson=m["poisson"], density=1.0,
                                               frictionAngle=0.0))
betan, betas, phi = [], [], []
for p in S["yade_pairs"]:
    a, b = mat_id[p["a"]], mat_id[p["b"]]
    betan.append((a, b, p["betan"]))
    betas.append((a, b, p["betas"]))
    phi.append((a, b, p["phi"]))

if S["box"]["periodic"]:
    O.periodic = True
    O.cell.setBox(S["box"]["lx"], S["box"]["ly"], S["box"]["lz"])

for i in range(n):
    b = utils.sphere((D["x"][i] + shift[0], D["y"][i] + shift[1], D["z"][i] + shift[2]), D["r"][i],
                     material=mat_id[D["material"][i]])
    b.state.mass = D["mass"][i]
    inertia = D["inertia"][i]
    b.state.inertia = (inertia, inertia, inertia)
    b.state.vel = (D["vx"][i], D["vy"][i], D["vz"][i])
    b.state.angVel = (D["wx"][i], D["wy"][i], D["wz"][i])
    O.bodies.append(b)

P = S["planes"]
H = 0.5 * S["wall_thickness"]
point = [list(p["point"]) for p in P]  # each plane's point, advanced as demflow advances it
for k, p in enumerate(P):
    # a box on the far side of the plane, its +z face on the plane, orientation taking z to the normal
    nx, ny, nz = p["normal"]
    axis = Vector3(0.0, 0.0, 1.0).cross(Vector3(nx, ny, nz))
    if axis.norm() > 0.0:
        q = Quaternion(axis / axis.norm(), math.atan2(axis.norm(), nz))
    elif nz > 0:
        q = Quaternion((1.0, 0.0, 0.0), 0.0)
    else:
        q = Quaternion((1.0, 0.0, 0.0), math.pi)
    c = [p["point"][a] + shift[a] - H * p["normal"][a] for a in range(3)]
    body = utils.box(c, (S["wall_half_size"], S["wall_half_size"], H), orientation=q, fixed=True,
                     material=mat_id[p["yade_material"]])
    O.bodies.append(body)


def plane_velocity(k, step):
    s0 = 0
    for ph in P[k]["phases"]:
        if s0 <= step < s0 + ph["cycles"]:
            return ph["v"]
        s0 += ph["cycles"]
    return [0.0, 0.0, 0.0]


def planes():
    # before the InteractionLoop of step O.iter: the box at demflow's plane point (set, not accumulated
    # from the box centre, whose rounding differs) with the velocity of this step
    for k in range(len(P)):
        b = O.bodies[n + k].state
        b.pos = tuple(point[k][a] + shift[a] - H * P[k]["normal"][a] for a in range(3))
        b.vel = plane_velocity(k, O.iter)


def advance_planes():
    # after the NewtonIntegrator: the plane point moves by dt x the velocity of this step (demflow's order)
    for k in range(len(P)):
        v = plane_velocity(k, O.iter)
        point[k] = [point[k][a] + dt * v[a] for a in range(3)]


rec = dict(sphere_steps=[], spheres=[], plane_steps=[], planes=[])


def state():
    out = []
    for i in range(n):
        s = O.bodies[i].state
        out.append([s.pos[0] - shift[0], s.pos[1] - shift[1], s.pos[2] - shift[2], s.vel[0], s.vel[1], s.vel[2],
                    s.angVel[0], s.angVel[1], s.angVel[2]])
    return out


def record():
    advance_planes()
    k = O.iter  # this iteration evaluated the forces at x_k and moved the spheres to x_{k+1}
    if k % every == 0:
        rec["plane_steps"].append(k)
        rec["planes"].append([list(O.forces.f(n + q)) for q in range(len(P))])
    if (k + 1) % every == 0:
        rec["sphere_steps"].append(k + 1)
        rec["spheres"].append(state())


law = Law2_ScGeom_MindlinPhys_Mindlin()
engines = [ForceResetter(),
           InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()], allowBiggerThanPeriod=True),
           PyRunner(command="planes()", iterPeriod=1, initRun=True),
           InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=bool(S["avoid_ratcheting"])),
                            Ig2_Box_Sphere_ScGeom()],
                           [Ip2_FrictMat_FrictMat_MindlinPhys(betan=MatchMaker(matches=betan),
                                                              betas=MatchMaker(matches=betas),
                                                              frictAngle=MatchMaker(matches=phi))],
                           [law]),
           NewtonIntegrator(damping=S["local_damping"], gravity=tuple(S["gravity"])),
           PyRunner(command="record()", iterPeriod=1, initRun=True)]
O.engines = engines
O.dt = dt
rec["sphere_steps"].append(0)
rec["spheres"].append(state())
O.run(n_steps, True)

out = dict(rec=rec, complete=True, yade_version=str(__import__("yade.config").config.version))
with open("yade_out.json.tmp", "w") as fh:
    json.dump(out, fh)
os.replace("yade_out.json.tmp", "yade_out.json")
sys.exit(0)
