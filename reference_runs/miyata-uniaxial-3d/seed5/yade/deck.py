# demflow deck for YADE (2023.02a): miyata-uniaxial-3d, uniaxial compression of a bed of rigid sphere
# clumps.  This program is fixed; the protocol reaches it only as numbers and validated identifiers in
# scene.json (written by demflow.engines.yade_uniaxial3d).  Run: yade -n -j1 -x deck.py
# Model (demflow's capabilities table, ENGINES.md "3D clumps and Hertz"): FrictMat for the particles,
# Ip2_FrictMat_FrictMat_MindlinPhys with betan/betas (demflow's damping ratios) and frictAngle per
# material pair, Law2_ScGeom_MindlinPhys_Mindlin; clumps by appendClumped on demflow's lattice and
# orientations, their mass and principal moments set to demflow's template (each YADE principal axis
# takes the moment of the template axis it is parallel to), every member's mass set to its clump's
# (YADE's dashpot takes member masses; demflow's and LIGGGHTS's take the body's); floor and plate as
# boxes much wider than the period whose material makes YADE's box-sphere contact (R* = R/2) give
# demflow's plane stiffness; NewtonIntegrator local damping (demflow's) with exactAsphericalRot.
# Protocol: settle (kinetic energy < fraction x weight x 1 m, checked every settle_check_every steps),
# delete the clumps whose centre is above the trim height (then a fresh collider: the 2023.02a defect),
# settle again, put the plate at the highest point + gap and lower it at the plate speed, recording
# every record_every steps.  Output: uniaxial_out.json, curve.csv, snapshots.csv
# (demflow.engines.uniaxial3d).
import csv
import json
import math
import os
import sys

from yade import O, Vector3, utils
from yade.wrapper import (PyRunner, Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                          Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin, MatchMaker,
                          NewtonIntegrator)

S = json.load(open("scene.json"))
P = S["protocol"]
L = float(P["box"])
A = L * L
dt = float(S["dt"])
g = float(S["gravity"][2])
T = S["template"]
M = float(T["mass"])

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

O.periodic = True
O.cell.setBox(L, L, float(S["cell_height"]))
H = 0.5 * float(S["wall_thickness"])
W = float(S["wall_half_size"])
floor = O.bodies.append(utils.box((0.5 * L, 0.5 * L, -H), (W, W, H), fixed=True, material=mat_id["wall"]))

clumps = []
axis_dot = 1.0
for i, members in enumerate(S["members"]):
    sph = [utils.sphere(tuple(c), r, material=mat_id["particle"]) for c, r in zip(members, T["radii"])]
    cid, mids = O.bodies.appendClumped(sph, discretization=int(S["discretization"]))
    st = O.bodies[cid].state
    R = st.ori.toRotationMatrix()
    axes = S["body_axes"][i]  # demflow's principal axes in the world, one per row
    mom = []
    for k in range(3):
        col = Vector3(R[0, k], R[1, k], R[2, k])
        dots = [abs(col.dot(Vector3(*axes[j]))) for j in range(3)]
        j = max(range(3), key=lambda q: dots[q])
        axis_dot = min(axis_dot, dots[j])
        mom.append(T["moments"][j])
    st.mass = M
    st.inertia = Vector3(*mom)
    for m in mids:
        O.bodies[m].state.mass = M
    clumps.append(cid)

law = Law2_ScGeom_MindlinPhys_Mindlin()


def engines():
    return [ForceResetter(),
            InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()], allowBiggerThanPeriod=True),
            InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False), Ig2_Box_Sphere_ScGeom()],
                            [Ip2_FrictMat_FrictMat_MindlinPhys(betan=MatchMaker(matches=betan),
                                                               betas=MatchMaker(matches=betas),
                                                               frictAngle=MatchMaker(matches=phi))],
                            [law]),
            NewtonIntegrator(damping=float(S["local_damping"]), gravity=(0.0, 0.0, g), exactAsphericalRot=True)]


O.engines = engines()
O.dt = dt


def kinetic():
    e = 0.0
    for c in clumps:
        st = O.bodies[c].state
        w = st.ori.conjugate() * st.angVel
        e += 0.5 * st.mass * st.vel.squaredNorm() + 0.5 * sum(st.inertia[k] * w[k] ** 2 for k in range(3))
    return e


def settle():
    weight = -g * M * len(clumps)
    done = 0
    while done < int(P["settle_max"]):
        O.run(int(P["settle_check_every"]), True)
        done += int(P["settle_check_every"])
        ke = kinetic()
        print(f"settling: {done} steps, kinetic energy {ke:.3g} J (at rest below "
              f"{float(P['settle_ke_fraction']) * weight:.3g})", flush=True)
        if ke < float(P["settle_ke_fraction"]) * weight * 1.0:
            return done
    return -done


if S.get("benchmark"):
    # speed runs (benchmarks/bench_uniaxial_engines.py): the first settling stage only, timed in the deck
    import time

    t0 = time.perf_counter()
    steps1 = settle()
    wall = time.perf_counter() - t0
    with open("bench.json.tmp", "w") as fh:
        json.dump(dict(steps=abs(steps1), wall_s=wall, clumps=len(clumps), kinetic=kinetic(), complete=True), fh)
    os.replace("bench.json.tmp", "bench.json")
    sys.exit(0)
steps1 = settle()
n_inserted = len(clumps)
above = [c for c in clumps if O.bodies[c].state.pos[2] > float(P["trim"])]
for c in above:
    O.bodies.deleteClumpBody(O.bodies[c])
clumps = [c for c in clumps if c not in above]
O.engines = engines()  # a fresh collider after deleting bodies in a periodic scene (2023.02a hangs otherwise)
steps2 = settle()
floor_settled = -O.forces.f(floor)[2]
weight = -g * M * len(clumps)

top = max(b.state.pos[2] + b.shape.radius for b in O.bodies if b.isClumpMember)
plate_start = top + float(P["plate_gap"])
plate = O.bodies.append(utils.box((0.5 * L, 0.5 * L, plate_start + H), (W, W, H), fixed=True,
                                  material=mat_id["wall"]))
# a dynamic body with every DOF blocked keeps the prescribed velocity and, unlike a fixed one, counts in the
# NewtonIntegrator's largest velocity: a fixed moving plate is never re-detected by the collider in a bed
# at rest (measured: it sank 23 mm into the top clump unseen).  Its mass is set so large that YADE's
# dashpot reduced mass is the member's (that of a fixed wall).
ps_ = O.bodies[plate]
ps_.dynamic = True
ps_.state.blockedDOFs = "xyzXYZ"
ps_.state.mass = 1e30
ps_.state.inertia = (1e30, 1e30, 1e30)
ps_.state.vel = (0.0, 0.0, -float(P["plate_speed"]))
O.engines = engines()


members = [b.id for b in O.bodies if b.isClumpMember]
created = {"plate": 0, "floor": 0}
candidates = []


def plate_z():
    return O.bodies[plate].state.pos[2] - H


def near_walls():
    # the members within 2 cm of the plate or the floor (refreshed every record: 0.1 mm of plate travel)
    zp = plate_z()
    candidates[:] = [m for m in members if O.bodies[m].state.pos[2] + O.bodies[m].shape.radius > zp - 0.02
                     or O.bodies[m].state.pos[2] - O.bodies[m].shape.radius < 0.02]


def watchdog():
    # 2023.02a's periodic collider misses some member-plate contacts with a box bigger than the period
    # (measured: the plate sank 23 mm into members whose centre has x < 0, none detected, while
    # utils.createInteraction finds the overlap): every WATCH steps any candidate member overlapping the
    # plate or the floor without a real contact gets one.  How many were made is written to the output.
    zp = plate_z()
    for m in candidates:
        st = O.bodies[m].state
        r = O.bodies[m].shape.radius
        for name, wall, over in (("plate", plate, st.pos[2] + r > zp), ("floor", floor, st.pos[2] - r < 0.0)):
            if over:
                i = O.interactions[m, wall] if O.interactions.has(m, wall) else None
                if i is None or not i.isReal:
                    utils.createInteraction(m, wall)
                    created[name] += 1


WATCH = int(S["watch_every"])
O.engines = engines() + [PyRunner(command="watchdog()", iterPeriod=WATCH)]
near_walls()


def per_particle(wall):
    """{clump id: [normal force, x, y]} on the wall: the members' forces summed, and where the clump touches
    (the force-weighted mean of its touching members' centres, minimum image from its first one, wrapped)."""
    f = {}
    for i in O.interactions.withBody(wall):
        if not i.isReal:
            continue
        other = i.id2 if i.id1 == wall else i.id1
        fn = i.phys.normalForce.norm()
        if fn > 0.0:
            c = O.bodies[other].clumpId
            pos = O.bodies[other].state.pos
            if c not in f:
                f[c] = [0.0, 0.0, 0.0, pos[0], pos[1]]
            e = f[c]
            dx = pos[0] - e[3]
            dy = pos[1] - e[4]
            e[0] += fn
            e[1] += fn * (dx - L * round(dx / L))
            e[2] += fn * (dy - L * round(dy / L))
    return {c: [e[0], (e[3] + e[1] / e[0]) % L, (e[4] + e[2] / e[0]) % L] for c, e in f.items()}


rows, snaps = [], []
levels = list(P["snapshot_levels"])
touched = None
step = 0
while True:
    O.run(int(P["record_every"]), True)
    step += int(P["record_every"])
    near_walls()
    zp = plate_z()
    ps = O.forces.f(plate)[2] / A
    fs = -O.forces.f(floor)[2] / A
    if touched is None and ps > 0.0:
        touched = zp
    fp, ff = per_particle(plate), per_particle(floor)
    rows.append([step, zp, (touched - zp) if touched is not None else 0.0, ps, fs, len(fp), len(ff)])
    while levels and ps >= levels[0]:  # snapshot numbers 0, 1, ... in the order taken
        k = len(P["snapshot_levels"]) - len(levels)
        snaps += [[k, ps, name, v] for name, per in (("plate", fp), ("floor", ff)) for v in per.values()]
        levels.pop(0)
    if step % (25 * int(P["record_every"])) == 0:
        print(f"loading: {step} steps, plate at {zp:.4f} m, plate stress {ps / 1e3:.1f} kPa", flush=True)
    if ps >= float(P["stress_max"]) or zp < float(P["plate_z_min"]):
        break


def write_csv(name, header, data):
    with open(name + ".tmp", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(data)
    os.replace(name + ".tmp", name)


write_csv("curve.csv", ["step", "plate_z", "settlement", "plate_stress", "floor_stress", "plate_contacts",
                        "floor_contacts"], [[r[0]] + [repr(float(v)) for v in r[1:5]] + r[5:] for r in rows])
write_csv("snapshots.csv", ["snapshot", "stress", "wall", "force", "x", "y"],
          [[r[0], repr(r[1]), r[2]] + [repr(float(v)) for v in r[3]] for r in snaps])
st = O.bodies[clumps[0]].state
res = dict(n_inserted=n_inserted, n_particles=len(clumps), weight=weight, floor_settled=floor_settled,
           settle_steps=[steps1, steps2], dt=dt, plate_start=plate_start, clump_mass=st.mass,
           clump_inertia=[st.inertia[0], st.inertia[1], st.inertia[2]], principal_axis_alignment=axis_dot,
           contacts_made_by_watchdog=created,
           yade_version=str(__import__("yade.config").config.version))
with open("uniaxial_out.json.tmp", "w") as fh:
    json.dump(res, fh)
os.replace("uniaxial_out.json.tmp", "uniaxial_out.json")
sys.exit(0)
