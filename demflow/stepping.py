"""The calculation cycle (thesis §2.2.4.8, C&S "The calculation cycle"), compiled.

:func:`run_steps` advances a built simulation by up to ``n`` steps without returning to
Python, and stops early when the neighbour list must be rebuilt or the run blows up.
Every array is passed in; nothing is allocated per step.

The steps run on a copy of the state with the discs renumbered in spatial (cell) order,
made at each neighbour-list build (packed rows, :func:`demflow.integrate.pack_rows`), so that a
pair's two discs lie close in memory whatever the user's numbering; the public arrays keep the
user's numbering.
Per step: the pair forces (one parallel pass over the pair list, writing only what the
later stages read unless the step records), the wall reactions (over the wall pairs
only), the records, the wall velocities, then the force sums and the central-difference
update of every disc fused in one parallel pass over the discs.  The order of every
floating-point operation is that of the original separate kernels (pair forces, per-disc
sums in the CSR order, thesis eqs 2.27-2.30; commit ff80386), so results are the same to
the bit and do not depend on the number of threads.
"""
from __future__ import annotations

import numpy as np

from .contacts.forces import wall_sums
from .contacts.forces_blocks import step_pair_forces
from .integrate import Q_INERTIA, Q_MASS, pack_rows, sum_and_integrate, unpack_rows
from .jit import njit
from .laws.base import law_energy_add
from .walls import move_walls, set_wall_velocities

DONE = 0
REBUILD = 1
BLOWUP = 2
NONFINITE = 3  # a NaN or inf in the state after the steps (state_is_finite), whatever its origin

# A contact overlapping more than this fraction of the smaller radius is a blow-up
# (the linear law is only meaningful for overlaps of a few per cent, thesis §2.2.4.7).
MAX_OVERLAP_RATIO = 0.5
# A disc moving more than this fraction of its radius in one step can cross a contact (or a
# wall) between two force evaluations: the time step no longer resolves the motion.
MAX_STEP_RATIO = 0.5


@njit
def find_pair(finder, other, a, b, n_keys):
    """Index of pair (a, b) in the sorted list, or -1."""
    key = a * n_keys + b
    lo = 0
    hi = finder.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        kk = finder[mid] * n_keys + other[mid]
        if kk < key:
            lo = mid + 1
        else:
            hi = mid
    if lo < finder.shape[0] and finder[lo] * n_keys + other[lo] == key:
        return lo
    return -1




@njit
def _finite(a):
    for v in a.flat:
        if not np.isfinite(v):
            return False
    return True


@njit
def state_is_finite(d, walls, hist):
    """True when every dynamic quantity is finite: the discs' positions, rotations, velocities and contact
    force sums (:class:`~demflow.state.Discs`, disc order), the walls' points, directions, velocities,
    pivots and forces, and the contact history.  One compiled pass, stopping at the first NaN or inf."""
    for a in (d.x, d.y, d.th, d.vx, d.vy, d.om, d.Fx, d.Fy, d.M, walls.px, walls.py, walls.ex, walls.ey,
              walls.vx, walls.vy, walls.om, walls.cx, walls.cy):
        if not _finite(a):
            return False
    return _finite(walls.force) and _finite(hist)


@njit
def kinetic_energy_perm(P, Q, inv):
    """½Σ(m v² + I ω²) [force·length] of the discs in the packed rows P, Q of the cycle
    (:func:`demflow.integrate.sum_and_integrate`; disc i in slot inv[i]), summed in disc order (the same sum
    to the bit)."""
    e = 0.0
    for i in range(inv.shape[0]):
        p = inv[i]
        e += 0.5 * (Q[p, Q_MASS] * (P[p, 2] ** 2 + P[p, 3] ** 2) + Q[p, Q_INERTIA] * P[p, 4] ** 2)
    return e


@njit
def elastic_energy_perm(pairs, mat, wmat, n, law):
    """Energy in the contact springs [force·length] (the law's, e.g. Σ N²/2kN + S²/2kS), with pair k's
    history and overlap in row pairs.pos[k], summed in key order (the same sum to the bit)."""
    e = 0.0
    finder = pairs.finder
    other = pairs.other
    for k in range(finder.shape[0]):
        t = pairs.pos[k]
        if pairs.out.ovl[t] <= 0.0:
            continue
        j = other[k]
        mb = wmat[j - n] if j >= n else mat[j]
        e = law_energy_add(law, e, pairs.hist_p, t, mat[finder[k]], mb)
    return e


@njit
def elastic_energy_keys(finder, other, hist, mat, wmat, n, law):
    """Energy in the contact springs [force·length] of pairs in key order with history ``hist`` (disc
    materials ``mat`` in disc order); a pair apart has cleared history and adds nothing."""
    e = 0.0
    for k in range(finder.shape[0]):
        j = other[k]
        mb = wmat[j - n] if j >= n else mat[j]
        e = law_energy_add(law, e, hist, k, mat[finder[k]], mb)
    return e


@njit
def force_sums_keys(finder, other, f, r, n):
    """Each disc's contact force and moment sums (fx, fy, M) from the pairs in key order with forces ``f``
    (each pair's force on its finder and its shear force, :func:`demflow.contacts.forces.pair_forces`): the
    finder's share (fx, fy, Fs·R) added in key order, then the other disc's (-fx, -fy, Fs·R) in key order (wall
    pairs: the finder only), R the disc's own radius; the additions of ``np.add.at`` over those index lists in
    that order (the sums to the bit, one compiled pass: session 49)."""
    fx = np.zeros(n)
    fy = np.zeros(n)
    mo = np.zeros(n)
    m = finder.shape[0]
    for k in range(m):
        i = finder[k]
        fx[i] += f[k, 0]
        fy[i] += f[k, 1]
    for k in range(m):
        i = finder[k]
        mo[i] += f[k, 2] * r[i]
    for k in range(m):
        j = other[k]
        if j < n:
            fx[j] += -f[k, 0]
            fy[j] += -f[k, 1]
    for k in range(m):
        j = other[k]
        if j < n:
            mo[j] += f[k, 2] * r[j]
    return fx, fy, mo


@njit
def _rows_to(src, dst, pos):
    """dst[pos[k]] = src[k] for every row k (key order to internal order)."""
    for k in range(pos.shape[0]):
        for c in range(src.shape[1]):
            dst[pos[k], c] = src[k, c]


@njit
def _rows_from(src, dst, pos):
    """dst[k] = src[pos[k]] for every row k (internal order to key order)."""
    for k in range(pos.shape[0]):
        for c in range(src.shape[1]):
            dst[k, c] = src[pos[k], c]


@njit
def run_steps(n, step0, skin, disp_walls, pub, lay, pairs, walls, loading, law, box, dt, gx, gy,
              rec, rec_count, ext, has_ext, acc, diss_pairs, wwork_pairs, diss_discs):
    """Run up to n steps from step ``step0``.

    ``pub`` (:class:`~demflow.state.Discs`) are the discs in disc order; the steps advance the packed rows lay.P
    and lay.Q of the slots (slot p holds disc lay.perm[p], see
    :func:`demflow.contacts.neighbours.internal_layout`); ``pairs`` (:class:`~demflow.state.Pairs`), ``walls``,
    ``loading``, ``rec`` (:class:`~demflow.state.Records`) as in :mod:`demflow.state`; ``law`` the contact law's
    parameters (its type selects the compiled law, :mod:`demflow.laws.base`); ``box`` the space
    (its type selects the image rule, :mod:`demflow.space`); gravity (gx, gy) [length/time²].

    Returns (steps done, status, disp_walls, rec_count): status DONE, REBUILD (the
    neighbour list is stale: the largest disc displacement since the build plus the wall
    displacement exceeds skin/2), BLOWUP (non-finite force or overlap beyond
    MAX_OVERLAP_RATIO of a radius; the step that found it was not applied) or NONFINITE (the
    state on return holds a NaN or inf that no contact saw, e.g. a disc in free flight under a
    NaN gravity or external force, or a wall driven to infinity: one O(n) pass per call,
    :func:`state_is_finite`, never per step).

    The state is gathered into the slots' rows on entry and scattered back on return
    (:func:`demflow.integrate.pack_rows`, :func:`demflow.integrate.unpack_rows`), so the
    public discs and pairs.hist are in disc and key order between calls (as are Fx, Fy, M: each
    disc's contact force and moment sums of the last step applied).  Every sum is taken in the
    order of the disc-order reference.
    With ``has_ext`` the (n, 3) array ``ext`` (disc order: fx, fy, moment) is added to every
    disc's force sums at every step (the fluid force of a saturated scene, held between fluid
    solves); a dry scene passes has_ext=False and the cycle is unchanged.

    Energy accounts for the balance of :class:`~demflow.simulation.Simulation` (nothing in the
    state reads them): ``acc`` += (energy dissipated by the contacts' dashpots and friction, by
    global damping, work of the walls on the discs) [force·length] over the steps done, summed in
    pair and disc order (``diss_pairs``, ``wwork_pairs`` (pairs, internal order) and ``diss_discs``
    (discs, slot order) are scratch sums, zero on entry and on return).
    """
    _rows_to(pairs.hist, pairs.hist_p, pairs.pos)
    done, status, disp_walls, rec_count = _cycle(n, step0, skin, disp_walls, pub, lay, pairs, walls, loading, law,
                                                 box, dt, gx, gy, rec, rec_count, ext, has_ext, acc, diss_pairs,
                                                 wwork_pairs, diss_discs)
    e = 0.0
    ew = 0.0
    for k in range(pairs.pos.shape[0]):  # key order
        e += diss_pairs[pairs.pos[k]]
        ew += wwork_pairs[pairs.pos[k]]
    diss_pairs[:] = 0.0
    wwork_pairs[:] = 0.0
    acc[0] += e
    acc[2] += ew
    e = 0.0
    for i in range(diss_discs.shape[0]):  # disc order
        e += diss_discs[lay.inv[i]]
    diss_discs[:] = 0.0
    acc[1] += e
    _rows_from(pairs.hist_p, pairs.hist, pairs.pos)
    if status != BLOWUP and not state_is_finite(pub, walls, pairs.hist):
        status = NONFINITE
    return done, status, disp_walls, rec_count


@njit
def _record(q, step, pairs, walls, lay, mat, law, rec, n_keys):
    """Store recorded step number q (wall forces and points, tracked pairs, energies)."""
    nd = lay.P.shape[0]
    nw = walls.px.shape[0]
    rec.step[q] = step
    for w in range(nw):
        rec.wall[q, w, 0] = walls.force[w, 0]
        rec.wall[q, w, 1] = walls.force[w, 1]
        rec.wall[q, w, 2] = walls.force[w, 2]
        rec.wallpos[q, w, 0] = walls.px[w]
        rec.wallpos[q, w, 1] = walls.py[w]
    for t in range(rec.track_a.shape[0]):
        k = find_pair(pairs.finder, pairs.other, rec.track_a[t], rec.track_b[t], n_keys)
        if k >= 0:
            rec.track[q, t, 0] = pairs.out.fn[pairs.pos[k]]
            rec.track[q, t, 1] = pairs.out.fs[pairs.pos[k]]
        else:
            rec.track[q, t, 0] = 0.0
            rec.track[q, t, 1] = 0.0
    rec.energy[q, 0] = kinetic_energy_perm(lay.P, lay.Q, lay.inv)
    rec.energy[q, 1] = elastic_energy_perm(pairs, mat, walls.mat, nd, law)


@njit
def _cycle(n, step0, skin, disp_walls, pub, lay, pairs, walls, loading, law, box, dt, gx, gy, rec, rec_count, ext,
           has_ext, acc, diss_pairs, wwork_pairs, diss_discs):
    """The steps of :func:`run_steps` on the slot-ordered state: the packed rows lay.P and lay.Q
    (:func:`demflow.integrate.sum_and_integrate`), filled from the public discs ``pub`` here (slot p from disc
    lay.perm[p]) and written back to them on return."""
    pack_rows(pub, lay.perm, lay.P, lay.Q, lay.F)
    out = _steps(n, step0, skin, disp_walls, pub.mat, lay, pairs, walls, loading, law, box, dt, gx, gy,
                 rec, rec_count, ext, has_ext, acc, diss_pairs, wwork_pairs, diss_discs)
    unpack_rows(lay.P, lay.F, lay.perm, pub.x, pub.y, pub.vx, pub.vy, pub.om, pub.th, pub.Fx, pub.Fy, pub.M)
    return out


@njit
def _steps(n, step0, skin, disp_walls, mat, lay, pairs, walls, loading, law, box, dt, gx, gy,
           rec, rec_count, ext, has_ext, acc, diss_pairs, wwork_pairs, diss_discs):
    """The loop of :func:`_cycle` over the steps."""
    nd = lay.P.shape[0]
    nw = walls.px.shape[0]
    n_keys = nd + nw
    P = lay.P
    for s in range(n):
        step = step0 + s
        recording = rec.every > 0 and step % rec.every == 0 and rec_count < rec.step.shape[0]
        o = pairs.out
        nbad = step_pair_forces(pairs.fin_p, pairs.oth_p, pairs.hist_p, pairs.sx_p, pairs.sy_p, P, nd, walls, law,
                                box, dt, pairs.f, recording, o.fn, o.fs, o.slide, o.ovl, o.cpx, o.cpy,
                                MAX_OVERLAP_RATIO, diss_pairs, wwork_pairs, pairs.wall_p)
        if nbad > 0:
            return s, BLOWUP, disp_walls, rec_count
        wall_sums(pairs.wall_p, pairs.oth_p, nd, pairs.f, pairs.out, walls)
        if recording:
            _record(rec_count, step, pairs, walls, lay, mat, law, rec, n_keys)
            rec_count += 1
        set_wall_velocities(step, walls, loading)
        dmax2, jump2 = sum_and_integrate(lay.Q, P, lay.F, pairs.start_p, pairs.sidx_p, pairs.f, gx, gy, dt, ext,
                                         lay.perm, has_ext, diss_discs)
        if jump2 > MAX_STEP_RATIO * MAX_STEP_RATIO or not np.isfinite(jump2):
            return s + 1, BLOWUP, disp_walls, rec_count
        disp_walls += move_walls(walls, dt)
        if np.sqrt(dmax2) + disp_walls > 0.5 * skin:
            return s + 1, REBUILD, disp_walls, rec_count
    return n, DONE, disp_walls, rec_count
