"""The vector path of the 3D pair pass (demflow.contacts.spheres_blocks) computes the scalar path's numbers to the bit.

Each case builds a 3D Hertz-Mindlin scene, runs it a little (contacts touching, sliding and parting), and then
evaluates the same state twice with :func:`sphere_forces`: with the scene's parameters (``HertzParams``: the sphere
pairs through the vector lanes) and with the same tables typed as ``HertzParamsMD`` (no lane path: every pair through
``law_force3``, whose Mindlin branch is the same arithmetic).  Forces and moments, plane forces, history, per-pair
outputs, the dissipation and elastic-energy sums and the status must be equal bit for bit.  The cases cover what the
vector path chooses between: one material and several (a fill per run of one-material blocks, or each lane's row),
the incremental and total shear springs, both history rotations, both Coulomb caps, no tangential model for one
material pair, no damping, fixed spheres (the effective mass), planes and triangles among the sphere pairs, a
periodic box, a recording step, pair counts below and above a block, and blow-ups (a deep overlap, a NaN velocity).
"""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import demflow as df
from demflow.contacts.spheres import pack_rows, sphere_forces
from demflow.contacts.spheres_blocks import BLOCK
from demflow.laws.hertz_mindlin import HertzParams, HertzParamsMD
from demflow.stepping3d import MAX_OVERLAP_RATIO


def bed(n: int = 300, seed: int = 5, materials: int = 1, law: df.HertzMindlinLaw | None = None,
        none_pair: bool = False, fixed: int = 0, mesh: bool = False, periodic: bool = True) -> df.Scene3D:
    """n spheres on a jittered cubic lattice about touching, with random velocities and spins, on a floor under a
    plate (and a triangle-mesh ramp), periodic along x and y."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(n ** (1.0 / 3.0)))
    r = rng.uniform(0.45, 0.55, n)
    idx = np.arange(n)
    ix, iy, iz = idx % side, (idx // side) % side, idx // (side * side)
    pos = np.stack([0.5 + ix, 0.5 + iy, 0.6 + iz], axis=1) + rng.uniform(-0.04, 0.04, (n, 3))
    vel = rng.normal(0.0, 0.3, (n, 3))
    names = [f"m{c}" for c in range(materials)]
    mat = [names[c] for c in rng.integers(materials, size=n)] if materials > 1 else names[0]
    if materials > 1:  # runs of one material, so some blocks are of one material and some are mixed
        mat = [names[0] if (p // 40) % 2 == 0 else mat[p] for p in range(n)]
    law = law or df.HertzMindlinLaw(friction=0.3, restitution=0.6)
    mats = {m: df.Material(density=1.0 + 0.2 * c, young=1e4 * (1.0 + 0.5 * c), poisson=0.25 + 0.02 * c)
            for c, m in enumerate(names)}
    mats["steel"] = df.Material(density=8.0, young=5e4, poisson=0.3)
    laws = {}
    for a in names + ["steel"]:
        for b in names + ["steel"]:
            if (b, a) not in laws and not (a == "steel" and b == "steel"):
                k = 1.0 + 0.1 * (len(laws))
                laws[(a, b)] = dataclasses.replace(law, friction=law.friction / k)
    if none_pair:
        laws[(names[0], names[0])] = dataclasses.replace(laws[(names[0], names[0])], tangential="none")
    top = 0.6 + side + 0.2
    planes = [df.Plane("floor", (0.0, 0.0, 0.1), (0.0, 0.0, 1.0), "steel"),
              df.Plane("plate", (0.0, 0.0, top), (0.0, 0.0, -1.0), "steel")]
    L = float(side)
    meshes = []
    if mesh:
        meshes = [df.TriangleMesh("ramp", [(0.0, 0.0, 0.0), (0.45 * L, 0.0, 0.2), (0.45 * L, 0.45 * L, 0.2),
                                           (0.0, 0.45 * L, 0.0)], [(0, 1, 2), (0, 2, 3)], "steel",
                                  periodic_images=False)]
    box = df.Box(periodic_x=(0.0, L), periodic_y=(0.0, L)) if periodic else None
    kw = dict(box=box) if box is not None else {}
    fix = None
    if fixed:
        fix = np.zeros(n, bool)
        fix[rng.choice(n, fixed, replace=False)] = True
    return df.Scene3D(
        name="blocks3d", spheres=df.Spheres(x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], radius=r, material=mat,
                                            velocity=vel, angular_velocity=rng.normal(0.0, 0.5, (n, 3)), fixed=fix),
        materials=mats, laws=laws, planes=planes, meshes=meshes, gravity=(0.0, 0.0, -1.0), dt_fraction=0.1,
        allow_unsafe_dt=True, **kw)


def state(sim):
    p, sp, pl = sim.pairs, sim.spheres, sim.planes
    return dict(hist=p.hist.copy(), fn=p.fn.copy(), ft=p.ft.copy(), ovl=p.ovl.copy(), slide=p.slide.copy(),
                FM=sp.FM.copy(), plane_force=pl.force.copy())


def both_paths(sim, recording=False, tweak=None):
    """[(vector path), (scalar path)]: each (arrays after the pass, (status, energy, dissipation))."""
    keep = sim._copy_state()
    out = []
    for typed in (HertzParams, HertzParamsMD):
        sim._restore_state(keep)
        pack_rows(sim.spheres)
        if tweak is not None:
            tweak(sim.spheres.P)
        law = typed(*sim.law_params)
        res = sphere_forces(sim.spheres, sim.pairs, sim.planes, sim.tris, law, sim.dt, recording, MAX_OVERLAP_RATIO)
        out.append((state(sim), tuple(res)))
    sim._restore_state(keep)
    return out


def assert_same_bits(a, b):
    (sa, ra), (sb, rb) = a, b
    for key in sa:
        assert sa[key].tobytes() == sb[key].tobytes(), f"{key} differs"
    assert np.array(ra).tobytes() == np.array(rb).tobytes(), f"(status, energy, dissipation) {ra} != {rb}"


def run_bed(scene, steps=60):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the unsafe-step and overlap-tolerance notices of these small beds
        sim = df.build(scene)
    sim.run(steps)
    return sim


CASES = {
    "one-material": dict(),
    "three-materials": dict(materials=3),
    "total-spring": dict(law=df.HertzMindlinLaw(friction=0.3, restitution=0.6, shear_spring="total")),
    "project": dict(law=df.HertzMindlinLaw(friction=0.3, restitution=0.6, history_rotation="project")),
    "total-project": dict(law=df.HertzMindlinLaw(friction=0.3, restitution=0.6, shear_spring="total",
                                                 history_rotation="project")),
    "elastic-cap": dict(law=df.HertzMindlinLaw(friction=0.3, restitution=0.6, friction_cap="elastic")),
    "no-damping": dict(law=df.HertzMindlinLaw(friction=0.3, restitution=1.0)),
    "frictionless-pair": dict(materials=2, none_pair=True),
    "engine-conventions": dict(law=df.HertzMindlinLaw(friction=0.5, restitution=0.9, damping="liggghts",
                                                      shear_spring="total", history_rotation="project")),
    "fixed-spheres": dict(fixed=30),
    "mesh": dict(mesh=True),
    "walled": dict(periodic=False),
}


@pytest.fixture(scope="module")
def sims():
    return {}


def sim_for(sims, name):
    if name not in sims:
        sims[name] = run_bed(bed(**CASES[name]))
    return sims[name]


@pytest.mark.parametrize("name", sorted(CASES))
def test_vector_path_same_bits(sims, name):
    sim = sim_for(sims, name)
    touching = int((sim.pairs.ovl > 0).sum())
    assert touching > BLOCK // 2, "the case must have touching pairs in several blocks"
    assert sim.pairs.i.size > 2 * BLOCK
    sliding = int(sim.pairs.slide.sum())
    if CASES[name].get("law") is None or CASES[name]["law"].friction > 0:
        assert sliding > 0, "some contacts must slide (the Coulomb choice)"
    vec, scal = both_paths(sim)
    assert_same_bits(vec, scal)
    assert np.any(vec[0]["FM"] != 0.0)


def test_recording_step_same_bits(sims):
    sim = sim_for(sims, "three-materials")
    vec, scal = both_paths(sim, recording=True)
    assert vec[1][1] > 0.0  # an elastic energy was summed
    assert_same_bits(vec, scal)


def test_small_scene_partial_block():
    """Fewer listed pairs than one block, and fewer queued pairs than the lane count's multiple."""
    sim = run_bed(bed(n=12), steps=20)
    assert 0 < sim.pairs.i.size < BLOCK
    assert_same_bits(*both_paths(sim))


def test_deep_overlap_blow_up_same_status():
    sim = run_bed(bed(n=60), steps=10)
    p = sim.pairs
    k = int(np.flatnonzero((p.ovl > 0) & (p.j < sim.n))[0])
    i, j = int(p.i[k]), int(p.j[k])

    def tweak(P):  # sphere j onto sphere i: an overlap beyond the blow-up ratio
        P[j, 0:3] = P[i, 0:3] + 0.05 * (P[j, 0:3] - P[i, 0:3])
    vec, scal = both_paths(sim, tweak=tweak)
    assert vec[1][0] != 0 and vec[1][0] == scal[1][0]
    assert_same_bits(vec, scal)


def test_nan_velocity_same_bits():
    sim = run_bed(bed(n=60), steps=10)
    p = sim.pairs
    k = int(np.flatnonzero((p.ovl > 0) & (p.j < sim.n))[0])

    def tweak(P):
        P[int(p.i[k]), 3] = np.nan
    vec, scal = both_paths(sim, tweak=tweak)
    assert np.isnan(vec[0]["FM"]).any()
    assert_same_bits(vec, scal)


def test_negative_control_detects_one_ulp(sims):
    """The comparison sees a one-ulp change of one material pair's modulus in one path."""
    sim = sim_for(sims, "one-material")
    keep = sim._copy_state()
    pack_rows(sim.spheres)
    law = HertzParams(*sim.law_params)
    res_a = sphere_forces(sim.spheres, sim.pairs, sim.planes, sim.tris, law, sim.dt, False, MAX_OVERLAP_RATIO)
    a = (state(sim), tuple(res_a))
    sim._restore_state(keep)
    pack_rows(sim.spheres)
    E = law.Estar.copy()
    E[0, 0] = np.nextafter(E[0, 0], np.inf)
    res_b = sphere_forces(sim.spheres, sim.pairs, sim.planes, sim.tris, law._replace(Estar=E), sim.dt, False,
                          MAX_OVERLAP_RATIO)
    b = (state(sim), tuple(res_b))
    sim._restore_state(keep)
    with pytest.raises(AssertionError):
        assert_same_bits(a, b)
