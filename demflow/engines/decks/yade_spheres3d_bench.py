# demflow benchmark deck for YADE (2023.02a): 3D spheres, Hertz-Mindlin contacts, static planes,
# nothing recorded during the run.  This program is fixed; the scene reaches it only as numbers and
# validated identifiers in scene.json (written by demflow.engines.yade3d with benchmark=True, the same
# numbers as the conformance deck yade_spheres3d.py: materials, MatchMakers, compensated plane boxes).
# Run: yade -n -j1 -x deck.py
# Unlike yade_spheres3d.py no PyRunner runs during the steps (the planes are static: the writer refuses
# moving ones), so the timed steps are YADE's C++ engines only.  After the run the deck writes
# yade_out.json: the step count, the touching sphere-sphere and sphere-plane contacts, the kinetic
# energy and the force of the spheres on each plane (an equivalence check, the same work in every run).
import json
import math
import os
import sys

from yade import O, Quaternion, Vector3, utils
from yade.wrapper import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                          Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin, MatchMaker,
                          NewtonIntegrator)

S = json.load(open("scene.json"))
dt = float(S["dt"])
n = int(S["n_spheres"])
D = S["spheres"]
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

bodies = []
for i in range(n):
    b = utils.sphere((D["x"][i] + shift[0], D["y"][i] + shift[1], D["z"][i] + shift[2]), D["r"][i],
                     material=mat_id[D["material"][i]])
    b.state.mass = D["mass"][i]
    inertia = D["inertia"][i]
    b.state.inertia = (inertia, inertia, inertia)
    b.state.vel = (D["vx"][i], D["vy"][i], D["vz"][i])
    b.state.angVel = (D["wx"][i], D["wy"][i], D["wz"][i])
    bodies.append(b)
O.bodies.append(bodies)

P = S["planes"]
H = 0.5 * S["wall_thickness"]
for k, p in enumerate(P):
    # a static box on the far side of the plane, its +z face on the plane, orientation taking z to the normal
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

law = Law2_ScGeom_MindlinPhys_Mindlin()
O.engines = [ForceResetter(),
             InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()], allowBiggerThanPeriod=True),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=bool(S["avoid_ratcheting"])),
                              Ig2_Box_Sphere_ScGeom()],
                             [Ip2_FrictMat_FrictMat_MindlinPhys(betan=MatchMaker(matches=betan),
                                                                betas=MatchMaker(matches=betas),
                                                                frictAngle=MatchMaker(matches=phi))],
                             [law]),
             NewtonIntegrator(damping=S["local_damping"], gravity=tuple(S["gravity"]))]
O.dt = dt
O.run(n_steps, True)

# after the run: touching contacts (penetration > 0) of the last step, kinetic energy, plane forces
ss = sp = 0
for I in O.interactions:
    if not I.isReal or I.geom.penetrationDepth <= 0.0:
        continue
    if I.id1 < n and I.id2 < n:
        ss += 1
    else:
        sp += 1
ke = 0.0
for i in range(n):
    s = O.bodies[i].state
    ke += 0.5 * s.mass * s.vel.squaredNorm()
out = dict(complete=True, steps=int(O.iter), sphere_contacts=ss, plane_contacts=sp, kinetic=ke,
           planes=[list(O.forces.f(n + q)) for q in range(len(P))],
           yade_version=str(__import__("yade.config").config.version))
with open("yade_out.json.tmp", "w") as fh:
    json.dump(out, fh)
os.replace("yade_out.json.tmp", "yade_out.json")
sys.exit(0)
