"""Contact forces on every listed pair, and their sums per wall.

:func:`pair_forces` evaluates every pair of the neighbour list in parallel (one pair, one
iteration: no write conflicts).  Per pair it stores only what the next stages read — the force on the
finder and the shear force, (fx, fy, Fs), in the pair's own row (written in pair order, one row per pair),
plus overlap and contact point of wall pairs (for :func:`wall_sums`) — and the full per-pair outputs
(normal and shear force, sliding flag, overlap, contact point) on steps that record.  Each disc then
sums its shares, (fx, fy, Fs·R) as the finder and (-fx, -fy, Fs·R) as the other disc, in CSR order
(:func:`demflow.integrate.sum_and_integrate`, fixed order: results do not depend on the thread count).  A pair whose centres are certainly farther apart than the sum
of the radii (d² > (R_i + R_j)²·APART_MARGIN) skips the square root on steps that do not record.

For the linear law, a step that does not record evaluates the disc-disc pairs in blocks for the vector units
instead (:mod:`demflow.contacts.forces_blocks`, the same numbers) and this kernel the wall pairs only
(``walls_only``).

The kernel is one loop for every law and every box: the law's compiled functions
(:mod:`demflow.laws.base`) and the box's image rule (:func:`demflow.space.other_centre`) are
selected by the types of the ``law`` and ``box`` structures when the cycle is compiled.
Helpers called per pair receive scalars or are inlined, because every array handed to a compiled
call costs reference-count updates, which are atomic and serialise threads.  Rows are indexed with unsigned
integers (``np.uint64``): for a signed index Numba adds the arithmetic that makes a negative one count from the
end, which LLVM cannot drop when the index is loaded from the pair list (with the sums' indices, 5 % of the 2D
step at 1e4 discs: benchmarks/results/speed2d_session34_ab.md).  The material indices that read the law's tables are
unsigned too, as in the 3D pass (the same bits; the step's time within the A/B's noise:
benchmarks/results/speed_experiments_session40.md).
"""
from __future__ import annotations

import numpy as np
from numba import prange

from ..jit import njit, njit_parallel
from ..laws.base import law_force_dissipation, law_separate
from ..space import other_centre
from .neighbours import point_segment_distance


# d² > fl(fl(rs·rs)·APART_MARGIN) implies d² > rs² exactly (the margin exceeds the two roundings,
# 2.2e-16 each), hence fl(√d²) >= rs and an overlap rs - √d² <= 0: the skipped test would have said
# "apart" too, so skipping it changes no bit
APART_MARGIN = 1.0 + 1e-12

# pair_forces's ``wall_p`` when ``walls_only`` is False (not read)
NO_PAIRS = np.zeros(0, np.int64)


@njit_parallel
def pair_forces(fin, oth, hist, sx, sy, P, n, walls, law, box, dt, f, full,
                o_fn, o_fs, o_slide, o_ovl, o_cpx, o_cpy, max_overlap_ratio, diss, wwork, wall_p, walls_only):
    """Evaluate every listed pair (thesis eqs 2.7-2.20) and update its history in place.

    fin, oth: the pairs (other >= n: wall other - n); hist: their history rows; sx, sy: image
    shifts (periodic boxes); P (n, 8): each disc's (x, y, vx, vy, ω, R, material, -) in one 64-byte
    row, so a pair gathers one cache line per disc (see :func:`demflow.integrate.pack_rows`).  Writes pair k's
    force on its finder and its shear force, f[k] = (fx, fy, Fs) (the finder's share is (fx, fy, Fs·R_i),
    the other disc's (-fx, -fy, Fs·R_j): :func:`demflow.integrate.sum_and_integrate` forms them); the fields
    of :class:`~demflow.state.PairOutputs`, passed one by one (o_fn, ..., o_cpy; see
    :mod:`demflow.jit` for why): ovl, cpx, cpy for wall pairs always and for every pair when
    ``full``, fn, fs, slide only when ``full``.  Pairs not touching get zero force and lose
    their history (contact broken).  diss[k] += the energy pair k's dashpots and friction dissipated
    in the step (:func:`demflow.laws.base.law_force_dissipation`; summed in pair order by the caller),
    and for a wall pair wwork[k] += the work the wall's contact point (velocity v_w) did on the disc,
    -(Fn_work v_w·ε + Fs_work v_w·τ)Δt.  Returns the number of pairs overlapping more than
    ``max_overlap_ratio`` of the smaller radius or with a non-finite force (a blow-up).  With ``walls_only`` only
    the pairs ``wall_p`` (the wall pairs' indices) are evaluated
    (:func:`demflow.contacts.forces_blocks.step_pair_forces` does the others).
    """
    m = wall_p.shape[0] if walls_only else fin.shape[0]
    nbad = 0
    for kk in prange(m):
        # unsigned indices: no wrap-around arithmetic for negative indices (module docstring)
        k = np.uint64(wall_p[kk]) if walls_only else np.uint64(kk)
        i = np.uint64(fin[k])
        j = oth[k]
        ju = np.uint64(j)  # the other disc's row (j < n)
        xi = P[i, 0]
        yi = P[i, 1]
        ri = P[i, 5]
        ma = np.uint64(np.int64(P[i, 6]))  # unsigned: the law's tables read without a wrap-around test
        if j < n:
            rj = P[ju, 5]
            xj, yj = other_centre(box, sx, sy, k, P[ju, 0], P[ju, 1])
            dx = xj - xi
            dy = yj - yi
            d2 = dx * dx + dy * dy
            rs = ri + rj
            if not full and d2 > rs * rs * APART_MARGIN:
                # certainly apart (the margin covers the rounding of rs·rs against that of √d2, so the
                # test below would say the same): no square root, nothing to write but the zero force
                law_separate(law, hist, k)
                f[k, 0] = 0.0
                f[k, 1] = 0.0
                f[k, 2] = 0.0
                continue
            D = np.sqrt(d2)
            overlap = rs - D
            if D > 0.0:
                ex = dx / D
                ey = dy / D
            else:
                ex = 1.0
                ey = 0.0
            rvx = P[i, 2] - P[ju, 2]
            rvy = P[i, 3] - P[ju, 3]
            spin = P[i, 4] * ri + P[ju, 4] * rj
            px = xi + (ri - 0.5 * overlap) * ex
            py = yi + (ri - 0.5 * overlap) * ey
            mb = np.uint64(np.int64(P[ju, 6]))
            rmin = min(ri, rj)
        else:
            w = j - n
            ax = walls.px[w] + walls.h1[w] * walls.ex[w]
            ay = walls.py[w] + walls.h1[w] * walls.ey[w]
            bx = walls.px[w] + walls.h2[w] * walls.ex[w]
            by = walls.py[w] + walls.h2[w] * walls.ey[w]
            qx, qy, D = point_segment_distance(xi, yi, ax, ay, bx, by)
            overlap = ri - D
            if D > 0.0:
                ex = (qx - xi) / D
                ey = (qy - yi) / D
            else:
                ex = -walls.ey[w]
                ey = walls.ex[w]
            wvqx = walls.vx[w] - walls.om[w] * (qy - walls.cy[w])
            wvqy = walls.vy[w] + walls.om[w] * (qx - walls.cx[w])
            rvx = P[i, 2] - wvqx
            rvy = P[i, 3] - wvqy
            spin = P[i, 4] * ri
            px = xi + 0.5 * (ri + D) * ex
            py = yi + 0.5 * (ri + D) * ey
            mb = np.uint64(walls.mat[w])
            rmin = ri
        tx = ey
        ty = -ex
        ndot = rvx * ex + rvy * ey
        sdot = rvx * tx + rvy * ty - spin
        if full or j >= n:
            o_ovl[k] = overlap
            o_cpx[k] = px
            o_cpy[k] = py
        if overlap <= 0.0:
            law_separate(law, hist, k)
            f[k, 0] = 0.0
            f[k, 1] = 0.0
            f[k, 2] = 0.0
            if full:
                o_fn[k] = 0.0
                o_fs[k] = 0.0
                o_slide[k] = 0
            continue
        Fn, Fs, sliding, dissipated, Fn_work, Fs_work = law_force_dissipation(law, hist, k, ma, mb, overlap, ndot,
                                                                              sdot, dt)
        diss[k] += dissipated
        if j >= n:
            wwork[k] -= (Fn_work * (wvqx * ex + wvqy * ey) + Fs_work * (wvqx * tx + wvqy * ty)) * dt
        fx = -Fn * ex - Fs * tx
        fy = -Fn * ey - Fs * ty
        f[k, 0] = fx
        f[k, 1] = fy
        f[k, 2] = Fs
        if full:
            o_fn[k] = Fn
            o_fs[k] = Fs
            o_slide[k] = 1 if sliding else 0
        if not (overlap <= max_overlap_ratio * rmin and np.isfinite(Fn) and np.isfinite(Fs)):
            nbad += 1
    return nbad


@njit
def wall_sums(wall_pairs, oth, n, f, out, walls):
    """Force of the discs on each wall and its moment about the wall point P,
    walls.force[w] = (Fx, Fy, M_P), summed over the wall pairs only (``wall_pairs``: their
    indices k, in increasing order, so the sums are the same to the bit); f as in pair_forces."""
    wf = walls.force
    wf[:, :] = 0.0
    for q in range(wall_pairs.shape[0]):
        k = wall_pairs[q]
        if out.ovl[k] <= 0.0:
            continue
        w = oth[k] - n
        Fwx = -f[k, 0]
        Fwy = -f[k, 1]
        wf[w, 0] += Fwx
        wf[w, 1] += Fwy
        wf[w, 2] += (out.cpx[k] - walls.px[w]) * Fwy - (out.cpy[k] - walls.py[w]) * Fwx
