"""Contact forces on every listed pair, and their sums per disc and per wall.

``contact_forces`` evaluates every pair of the neighbour list in parallel (one pair, one
iteration: no write conflicts), storing the force on the pair's finder and every per-pair
output (used for snapshots); each disc then sums its own contacts through the CSR list
(:func:`demflow.integrate.sum_and_integrate`, no conflicts, fixed order: results do not
depend on the thread count); :func:`wall_sums_listed` adds the reactions on each wall.

The calculation cycle (:func:`demflow.stepping.run_steps`) uses the leaner
:func:`contact_forces_step`: the same arithmetic, but per pair it stores only what the
next stages read, (fx, fy, Fs) packed in one row, plus overlap and contact point of wall
pairs (for :func:`wall_sums_listed`); the full per-pair outputs are written only on
steps that record.  Moments are formed when summing (Fs·R of the summing disc, the same
product :func:`contact_forces` stores), so forces are bit-for-bit those of the
reference kernels.  Hot kernels take arrays only at their top level: helpers called per
pair receive scalars (or are inlined), because every array handed to a compiled call
costs reference-count updates, which are atomic and serialise threads.
"""
from __future__ import annotations

import numpy as np
from numba import prange

from ..jit import JIT_FLAGS, njit, njit_parallel
from ..laws.linear import linear_contact
from .neighbours import point_segment_distance


import numba

# per-pair helpers that take arrays are inlined at the Numba IR level (no call, no
# reference counting per pair)
njit_inline = numba.njit(inline="always", **JIT_FLAGS)


@njit_inline
def wall_segment(w, wpx, wpy, wex, wey, wh1, wh2):
    """Endpoints A = P + h1·e and B = P + h2·e of wall w (C&S Fig. 4)."""
    return (wpx[w] + wh1[w] * wex[w], wpy[w] + wh1[w] * wey[w],
            wpx[w] + wh2[w] * wex[w], wpy[w] + wh2[w] * wey[w])


@njit_inline
def pair_geometry(k, finder, other, x, y, r, vx, vy, om, n,
                  wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy):
    """Geometry and relative velocity of listed pair k.

    Returns (overlap, ex, ey, ndot, sdot, px, py): overlap δ [length] (<= 0: apart),
    ε = (ex, ey) from the finder to the other body, ṅ and ṡ (thesis eqs 2.9-2.10, with the
    wall velocity taken at the wall's nearest point), contact point (px, py) halfway between
    the two surfaces along ε (C&S, contact A).
    """
    i = finder[k]
    j = other[k]
    if j < n:
        dx = x[j] - x[i]
        dy = y[j] - y[i]
        D = np.sqrt(dx * dx + dy * dy)
        overlap = r[i] + r[j] - D
        if D > 0.0:
            ex = dx / D
            ey = dy / D
        else:
            ex = 1.0
            ey = 0.0
        rvx = vx[i] - vx[j]
        rvy = vy[i] - vy[j]
        spin = om[i] * r[i] + om[j] * r[j]
        px = x[i] + (r[i] - 0.5 * overlap) * ex
        py = y[i] + (r[i] - 0.5 * overlap) * ey
    else:
        w = j - n
        ax, ay, bx, by = wall_segment(w, wpx, wpy, wex, wey, wh1, wh2)
        qx, qy, D = point_segment_distance(x[i], y[i], ax, ay, bx, by)
        overlap = r[i] - D
        if D > 0.0:
            ex = (qx - x[i]) / D
            ey = (qy - y[i]) / D
        else:
            ex = -wey[w]
            ey = wex[w]
        wvqx = wvx[w] - wom[w] * (qy - wcy[w])
        wvqy = wvy[w] + wom[w] * (qx - wcx[w])
        rvx = vx[i] - wvqx
        rvy = vy[i] - wvqy
        spin = om[i] * r[i]
        px = x[i] + 0.5 * (r[i] + D) * ex
        py = y[i] + 0.5 * (r[i] + D) * ey
    tx = ey
    ty = -ex
    ndot = rvx * ex + rvy * ey
    sdot = rvx * tx + rvy * ty - spin
    return overlap, ex, ey, ndot, sdot, px, py


@njit_parallel
def contact_forces(finder, other, hist, x, y, r, vx, vy, om, mat, n,
                   wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, wmat,
                   kn, ks, cn, cs, mu, coh, dt, normal_mode, sliding_mode, has_shear,
                   fx, fy, mi, mj, fn, fs, slide, ovl, cpx, cpy, max_overlap_ratio):
    """Evaluate every listed pair (thesis eqs 2.7-2.20) and update its history in place.

    hist[k, 0] is the normal spring force N, hist[k, 1] (if has_shear) the shear spring S.
    Outputs per pair k: (fx, fy) force on the finder, moments mi, mj on the finder and the
    other disc, total normal/shear forces fn, fs, sliding flag, overlap ovl [length],
    contact point (cpx, cpy).
    Pairs not touching get zero force and lose their history (contact broken).
    Returns the number of pairs overlapping more than ``max_overlap_ratio`` of the smaller
    radius or with a non-finite force (a blow-up).
    """
    m = finder.shape[0]
    nbad = 0
    for k in prange(m):
        i = finder[k]
        j = other[k]
        overlap, ex, ey, ndot, sdot, px, py = pair_geometry(
            k, finder, other, x, y, r, vx, vy, om, n,
            wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy)
        ovl[k] = overlap
        cpx[k] = px
        cpy[k] = py
        if overlap <= 0.0:
            hist[k, 0] = 0.0
            if has_shear:
                hist[k, 1] = 0.0
            fx[k] = 0.0
            fy[k] = 0.0
            mi[k] = 0.0
            mj[k] = 0.0
            fn[k] = 0.0
            fs[k] = 0.0
            slide[k] = 0
            continue
        mb = wmat[j - n] if j >= n else mat[j]
        ma = mat[i]
        s_old = hist[k, 1] if has_shear else 0.0
        N, S, Fn, Fs, sliding = linear_contact(
            overlap, ndot, sdot, hist[k, 0], s_old, dt,
            kn[ma, mb], ks[ma, mb], cn[ma, mb], cs[ma, mb], mu[ma, mb], coh[ma, mb],
            normal_mode, sliding_mode, has_shear)
        hist[k, 0] = N
        if has_shear:
            hist[k, 1] = S
        tx = ey
        ty = -ex
        fx[k] = -Fn * ex - Fs * tx
        fy[k] = -Fn * ey - Fs * ty
        mi[k] = Fs * r[i]
        mj[k] = Fs * r[j] if j < n else 0.0
        fn[k] = Fn
        fs[k] = Fs
        slide[k] = 1 if sliding else 0
        rmin = min(r[i], r[j]) if j < n else r[i]
        if not (overlap <= max_overlap_ratio * rmin and np.isfinite(Fn) and np.isfinite(Fs)):
            nbad += 1
    return nbad




@njit_parallel
def contact_forces_step(finder, other, hist, P, n,
                        wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, wmat,
                        kn, ks, cn, cs, mu, coh, dt, normal_mode, sliding_mode, has_shear,
                        f, full, fn, fs, slide, ovl, cpx, cpy, max_overlap_ratio):
    """:func:`contact_forces` for the calculation cycle (same arithmetic, same history).

    P (n, 8) holds each disc's (x, y, vx, vy, ω, R, material, -) in one 64-byte row, so a
    pair gathers one cache line per disc instead of seven (see :func:`pack_discs`).
    f[k] = (fx, fy, Fs): force on the finder and total shear force (moments are Fs·R).
    ovl, cpx, cpy are written for wall pairs always and for every pair when ``full``;
    fn, fs, slide only when ``full``.  Returns the blow-up count as contact_forces does.
    """
    m = finder.shape[0]
    nbad = 0
    for k in prange(m):
        i = finder[k]
        j = other[k]
        xi = P[i, 0]
        yi = P[i, 1]
        ri = P[i, 5]
        ma = int(P[i, 6])
        if j < n:
            rj = P[j, 5]
            dx = P[j, 0] - xi
            dy = P[j, 1] - yi
            D = np.sqrt(dx * dx + dy * dy)
            overlap = ri + rj - D
            if D > 0.0:
                ex = dx / D
                ey = dy / D
            else:
                ex = 1.0
                ey = 0.0
            rvx = P[i, 2] - P[j, 2]
            rvy = P[i, 3] - P[j, 3]
            spin = P[i, 4] * ri + P[j, 4] * rj
            px = xi + (ri - 0.5 * overlap) * ex
            py = yi + (ri - 0.5 * overlap) * ey
            mb = int(P[j, 6])
            rmin = min(ri, rj)
        else:
            w = j - n
            ax = wpx[w] + wh1[w] * wex[w]
            ay = wpy[w] + wh1[w] * wey[w]
            bx = wpx[w] + wh2[w] * wex[w]
            by = wpy[w] + wh2[w] * wey[w]
            qx, qy, D = point_segment_distance(xi, yi, ax, ay, bx, by)
            overlap = ri - D
            if D > 0.0:
                ex = (qx - xi) / D
                ey = (qy - yi) / D
            else:
                ex = -wey[w]
                ey = wex[w]
            wvqx = wvx[w] - wom[w] * (qy - wcy[w])
            wvqy = wvy[w] + wom[w] * (qx - wcx[w])
            rvx = P[i, 2] - wvqx
            rvy = P[i, 3] - wvqy
            spin = P[i, 4] * ri
            px = xi + 0.5 * (ri + D) * ex
            py = yi + 0.5 * (ri + D) * ey
            mb = wmat[w]
            rmin = ri
        tx = ey
        ty = -ex
        ndot = rvx * ex + rvy * ey
        sdot = rvx * tx + rvy * ty - spin
        write = full or j >= n
        if write:
            ovl[k] = overlap
            cpx[k] = px
            cpy[k] = py
        if overlap <= 0.0:
            hist[k, 0] = 0.0
            if has_shear:
                hist[k, 1] = 0.0
            f[k, 0] = 0.0
            f[k, 1] = 0.0
            f[k, 2] = 0.0
            if full:
                fn[k] = 0.0
                fs[k] = 0.0
                slide[k] = 0
            continue
        s_old = hist[k, 1] if has_shear else 0.0
        N, S, Fn, Fs, sliding = linear_contact(
            overlap, ndot, sdot, hist[k, 0], s_old, dt,
            kn[ma, mb], ks[ma, mb], cn[ma, mb], cs[ma, mb], mu[ma, mb], coh[ma, mb],
            normal_mode, sliding_mode, has_shear)
        hist[k, 0] = N
        if has_shear:
            hist[k, 1] = S
        f[k, 0] = -Fn * ex - Fs * tx
        f[k, 1] = -Fn * ey - Fs * ty
        f[k, 2] = Fs
        if full:
            fn[k] = Fn
            fs[k] = Fs
            slide[k] = 1 if sliding else 0
        if not (overlap <= max_overlap_ratio * rmin and np.isfinite(Fn) and np.isfinite(Fs)):
            nbad += 1
    return nbad


@njit
def wall_sums_listed(wall_pairs, other, n, f, ovl, cpx, cpy, wpx, wpy, out):
    """Force of the discs on each wall and its moment about the wall point P, out[w] = (Fx, Fy,
    M_P), summed over the wall pairs only (``wall_pairs``: their indices k, in
    increasing order, so the sums are the same to the bit); f as in contact_forces_step."""
    out[:, :] = 0.0
    for q in range(wall_pairs.shape[0]):
        k = wall_pairs[q]
        if ovl[k] <= 0.0:
            continue
        w = other[k] - n
        Fwx = -f[k, 0]
        Fwy = -f[k, 1]
        out[w, 0] += Fwx
        out[w, 1] += Fwy
        out[w, 2] += (cpx[k] - wpx[w]) * Fwy - (cpy[k] - wpy[w]) * Fwx
    return out


@njit_parallel
def pack_discs(x, y, vx, vy, om, r, mat, P):
    """Fill P (n, 8) with rows (x, y, vx, vy, ω, R, material, 0) for contact_forces_step."""
    for i in prange(x.shape[0]):
        P[i, 0] = x[i]
        P[i, 1] = y[i]
        P[i, 2] = vx[i]
        P[i, 3] = vy[i]
        P[i, 4] = om[i]
        P[i, 5] = r[i]
        P[i, 6] = mat[i]
        P[i, 7] = 0.0
