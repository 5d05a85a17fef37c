"""Contact forces on every listed pair, and their sums per disc and per wall.

``contact_forces`` evaluates every pair of the neighbour list in parallel (one pair, one
iteration: no write conflicts), storing the force on the pair's finder; ``particle_sums``
gathers them per disc through the CSR list (each disc sums its own contacts, again with
no conflicts, and in a fixed order: results do not depend on the thread count);
``wall_sums`` adds the reactions on each wall.
"""
from __future__ import annotations

import numpy as np
from numba import prange

from ..jit import njit, njit_parallel
from ..laws.linear import linear_contact
from .neighbours import point_segment_distance


@njit
def wall_segment(w, wpx, wpy, wex, wey, wh1, wh2):
    """Endpoints A = P + h1·e and B = P + h2·e of wall w (C&S Fig. 4)."""
    return (wpx[w] + wh1[w] * wex[w], wpy[w] + wh1[w] * wey[w],
            wpx[w] + wh2[w] * wex[w], wpy[w] + wh2[w] * wey[w])


@njit
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
def particle_sums(start, idx, side, fx, fy, mi, mj, Fx, Fy, M):
    """Sum the contact forces and moments on each disc (the force on the other disc of a
    pair is minus the force on its finder, Newton's third law)."""
    n = Fx.shape[0]
    for i in prange(n):
        sx = 0.0
        sy = 0.0
        sm = 0.0
        for e in range(start[i], start[i + 1]):
            k = idx[e]
            if side[e] == 0:
                sx += fx[k]
                sy += fy[k]
                sm += mi[k]
            else:
                sx -= fx[k]
                sy -= fy[k]
                sm += mj[k]
        Fx[i] = sx
        Fy[i] = sy
        M[i] = sm


@njit
def wall_sums(finder, other, n, fx, fy, ovl, cpx, cpy, wpx, wpy, out):
    """Force of the discs on each wall and its moment about the wall's point P.

    out[w] = (Fx, Fy, M_P) [force, force, force·length], counter-clockwise moment positive.
    """
    out[:, :] = 0.0
    for k in range(finder.shape[0]):
        j = other[k]
        if j < n or ovl[k] <= 0.0:
            continue
        w = j - n
        Fwx = -fx[k]
        Fwy = -fy[k]
        out[w, 0] += Fwx
        out[w, 1] += Fwy
        out[w, 2] += (cpx[k] - wpx[w]) * Fwy - (cpy[k] - wpy[w]) * Fwx
    return out
