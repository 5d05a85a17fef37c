"""The block pass of the linear law (demflow.contacts.forces_blocks) computes pair_forces's numbers to the bit.

Each case builds a 2D scene, runs it a little (contacts touching, sliding and parting), and then evaluates the
same state twice: pair_forces on every pair, and linear_pair_forces on the disc-disc pairs plus pair_forces on
the wall pairs only (what a step that does not record runs).  History, force rows, dissipation sums, wall work
and the blow-up count must be equal bit for bit.  The cases cover what the block pass branches on: one material
and several (the per-block row), the overlap and incremental normal laws, both sliding rules, no shear spring
(a history of one column), a periodic box (image shifts), pair counts below, at and above a block, coincident
centres, a blow-up (a deep overlap, a NaN velocity), and two threads.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from demflow import Box, ContactModel, Discs, LinearLaw, Material, Scene, Wall, build
from demflow.contacts.forces import NO_PAIRS, pair_forces
from demflow.contacts.forces_blocks import BLOCK, linear_pair_forces
from demflow.jit import set_threads
from demflow.stepping import MAX_OVERLAP_RATIO


def bed(n: int, seed: int = 3, materials: int = 1, periodic: bool = False, law: LinearLaw | None = None,
        contact_model: ContactModel | None = None) -> Scene:
    """n discs on a jittered square lattice about touching, with random velocities and spins, in
    a box of four walls (or between a floor and a lid, periodic along x)."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n)))
    r = rng.uniform(0.45, 0.55, n)
    ix, iy = np.arange(n) % side, np.arange(n) // side
    x = 1.0 + ix * 1.0 + rng.uniform(-0.03, 0.03, n)
    y = 1.0 + iy * 1.0 + rng.uniform(-0.03, 0.03, n)
    v = rng.normal(0.0, 0.3, (n, 2))
    mats = [f"m{rng.integers(materials)}" for _ in range(n)] if materials > 1 else "m0"
    law = law or LinearLaw(kn=1e4, ks=8e3, cn=5.0, cs=2.0, friction=0.3)
    names = [f"m{c}" for c in range(materials)] + ["wall"]
    laws = {}
    for a in names:
        for b in names:
            if (b, a) not in laws and not (a == "wall" and b == "wall"):
                k = 1.0 + 0.1 * (names.index(a) + names.index(b))  # each material pair its own numbers
                laws[(a, b)] = dataclasses.replace(law, kn=law.kn * k, friction=law.friction / k)
    L = side * 1.0 + 1.5
    walls = [Wall("floor", (0.0, 0.4), (1.0, 0.0), -5.0, L + 5.0, "wall"),
             Wall("lid", (L, L), (-1.0, 0.0), -5.0, L + 5.0, "wall")]
    if not periodic:
        walls += [Wall("right", (L, 0.0), (0.0, 1.0), -5.0, L + 5.0, "wall"),
                  Wall("left", (0.4, L), (0.0, -1.0), -5.0, L + 5.0, "wall")]
    kw = dict(box=Box(periodic_x=(0.5, 0.5 + side * 1.0))) if periodic else {}  # the lattice's own period
    return Scene(name="blocks", discs=Discs(x=x, y=y, radius=r, material=mats, velocity=v,
                                            angular_velocity=rng.normal(0.0, 0.5, n)),
                 materials={**{m: Material(density=1.0) for m in names}}, laws=laws, walls=walls,
                 gravity=(0.0, -1.0), dt_fraction=0.1, contact_model=contact_model or ContactModel(),
                 overlap_tolerance=0.3, **kw)


def both_passes(sim, tweak=None):
    """(pair_forces on every pair, the block pass + pair_forces on the wall pairs) on sim's state: per result the
    arrays (hist, f, diss, wwork) and the blow-up count."""
    pairs, P, n = sim.pairs, sim.layout.P.copy(), sim.n
    if tweak is not None:
        tweak(P)
    m = pairs.fin_p.shape[0]
    o = pairs.out
    rng = np.random.default_rng(0)
    diss0 = rng.uniform(0.0, 1.0, m)  # earlier steps' sums, not zero, so an addition is seen
    runs = []
    for blocks in (False, True):
        hist, f, diss, wwork = pairs.hist_p.copy(), np.full((m, 3), 7.0), diss0.copy(), np.zeros(m)
        args = (pairs.fin_p, pairs.oth_p, hist, pairs.sx_p, pairs.sy_p, P, n, sim.walls, sim.law_params, sim.box,
                sim.dt, f, False, o.fn, o.fs, o.slide, o.ovl, o.cpx, o.cpy, MAX_OVERLAP_RATIO, diss, wwork)
        if blocks:
            bad = linear_pair_forces(pairs.fin_p, pairs.oth_p, hist, pairs.sx_p, pairs.sy_p, P, n, sim.law_params,
                                     sim.box, sim.dt, f, MAX_OVERLAP_RATIO, diss)
            bad += pair_forces(*args, pairs.wall_p, True)
        else:
            bad = pair_forces(*args, NO_PAIRS, False)
        runs.append(((hist, f, diss, wwork), bad))
    return runs


def assert_same_bits(runs):
    (a, bad_a), (b, bad_b) = runs
    assert bad_a == bad_b
    for name, x, y in zip(("hist", "f", "diss", "wwork"), a, b):
        assert x.shape == y.shape
        assert np.array_equal(x.view(np.int64), y.view(np.int64)), f"{name} differs"


def run(scene, steps=60, threads=1):
    set_threads(threads)
    sim = build(scene)
    sim.run(steps, threads=threads)
    return sim


CASES = {
    "one material": dict(),
    "three materials": dict(materials=3),
    "periodic x": dict(periodic=True),
    "incremental normal, thesis sliding": dict(contact_model=ContactModel(normal="incremental", sliding="thesis")),
    "overlap normal": dict(contact_model=ContactModel(normal="overlap")),
    "no shear spring": dict(law=LinearLaw(kn=1e4, cn=5.0)),
    "cohesion, friction 0": dict(law=LinearLaw(kn=1e4, ks=8e3, cn=5.0, cs=2.0, friction=0.0, cohesion=0.5)),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_block_pass_equals_pair_forces(case):
    sim = run(bed(700, **CASES[case]))
    m = sim.pairs.fin_p.shape[0]
    assert m > 3 * BLOCK
    touching = sim.pairs.hist_p[:, 0] != 0.0
    assert 0.1 < touching.mean() < 0.9  # pairs touching and apart in the same blocks
    assert_same_bits(both_passes(sim))


def test_block_pass_sees_sliding_contacts():
    """The state of the comparisons holds sliding contacts (the Coulomb cap's choice is exercised)."""
    sim = run(bed(700))
    o = sim.pairs.out
    # the recording path fills the full outputs: force them with one recorded evaluation
    P = sim.layout.P
    m = sim.pairs.fin_p.shape[0]
    pair_forces(sim.pairs.fin_p, sim.pairs.oth_p, sim.pairs.hist_p.copy(), sim.pairs.sx_p, sim.pairs.sy_p, P, sim.n,
                sim.walls, sim.law_params, sim.box, sim.dt, np.zeros((m, 3)), True, o.fn, o.fs, o.slide, o.ovl, o.cpx,
                o.cpy, MAX_OVERLAP_RATIO, np.zeros(m), np.zeros(m), NO_PAIRS, False)
    assert o.slide.sum() > 0 and (o.slide == 0).sum() > 0


@pytest.mark.parametrize("n", [3, 40, 120])
def test_block_pass_small_and_partial_blocks(n):
    """Fewer pairs than a block, and a last block partly filled."""
    sim = run(bed(n), steps=20)
    assert sim.pairs.fin_p.shape[0] % BLOCK != 0
    assert_same_bits(both_passes(sim))


def test_block_pass_blow_ups_counted():
    """A disc pushed deep into its neighbour, a NaN velocity and two coincident centres: the same count of
    blow-ups and the same numbers (NaN bits included) as pair_forces."""
    sim = run(bed(300), steps=20)
    fin, oth = sim.pairs.fin_p, sim.pairs.oth_p
    disc = np.flatnonzero(oth < sim.n)
    a, b, c = disc[5], disc[50], disc[90]

    def tweak(P):
        i, j = fin[a], oth[a]
        P[i, 0:2] = P[j, 0:2] + 0.1 * (P[i, 0:2] - P[j, 0:2])  # 90 % of the way onto its neighbour
        P[fin[b], 2] = np.nan
        P[fin[c], 0:2] = P[oth[c], 0:2]  # the same centre: the normal falls back to (1, 0)

    runs = both_passes(sim, tweak)
    assert runs[0][1] >= 2
    assert_same_bits(runs)


def test_block_pass_two_threads():
    sim = run(bed(1500), threads=2)
    set_threads(2)
    try:
        runs2 = both_passes(sim)
    finally:
        set_threads(1)
    assert_same_bits(runs2)
    runs1 = both_passes(sim)
    assert_same_bits([runs1[1], runs2[1]])


def test_comparison_sees_one_ulp():
    """Negative control: the comparison fails when one history number differs by one unit in the last place."""
    sim = run(bed(300), steps=20)
    (a, bad_a), (b, bad_b) = both_passes(sim)
    k = int(np.flatnonzero(a[0][:, 0] != 0.0)[0])
    b[0][k, 0] = np.nextafter(b[0][k, 0], np.inf)
    with pytest.raises(AssertionError, match="hist differs"):
        assert_same_bits([(a, bad_a), (b, bad_b)])


def test_the_step_uses_the_block_pass_and_keeps_its_bits():
    """A whole run of the linear law (the block pass on steps that do not record, pair_forces on those that do)
    ends with the same state at one and two threads, and with the state of runs whose every step records (every
    step through pair_forces alone)."""
    from demflow import Outputs

    scene = bed(900)
    sims = [run(dataclasses.replace(scene, outputs=Outputs(every=every)), steps=150, threads=t)
            for every, t in ((0, 1), (0, 2), (1, 1))]
    set_threads(1)
    for other in sims[1:]:
        for name in ("x", "y", "vx", "vy", "om", "th"):
            assert np.array_equal(getattr(sims[0], name), getattr(other, name)), name
        assert np.array_equal(sims[0].pairs.hist, other.pairs.hist)
