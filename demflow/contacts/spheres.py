"""3D sphere contacts: the neighbour list (cells, periodic x/y by minimum image) and the pair pass.

Neighbour list.  Spheres are binned in cubic cells of side ≥ 2 r_max + skin over their bounding
box (a periodic axis: over its period, the cell count floor(L/side)); each sphere looks at the
distinct cells of its 3×3×3 stencil (wrapped along periodic axes, so a period of two cells is not
listed twice) and lists the pairs i < j whose surfaces are within ``skin``, the shift of j's image
chosen by minimum image.  Planes list every sphere within r + skin.  Pairs come out in key order
(i, then j; planes after spheres, j = n + plane), so history is carried across rebuilds by key
and every sum runs in the same order whatever the thread count.

Pair pass (:func:`sphere_forces`).  n is the unit normal from i to j (to the plane: minus its
normal), δ = R_i + R_j - |d| (plane: R_i - distance), the contact point mid-overlap, lever arms
(R - δ/2) as YADE's ScGeom.  The tangential history vector (columns 0-2) is rotated into the
current tangent plane keeping its length (projection and rescale, before the law's increment; LIGGGHTS
3.8.0 projects after the increment without rescaling, YADE 2023.02a rotates by T × (n_old × n): an
O(θ²)-per-step difference, capabilities feature 'history-rotation'), then the law
(:func:`demflow.laws.base.law_force3`) returns the normal force Fn and tangential force T on i:
F_i = -Fn n + T, F_j = -F_i, moments (R_i - δ/2) n × T and (R_j - δ/2) n × T.
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import njit
from ..laws.base import law_energy3, law_force3

OK = 0
BLOWUP_OVERLAP = 1
BLOWUP_NONFINITE = 2


@njit
def _cell_of(p, lo, side, nc, periodic):
    c = np.empty(3, np.int64)
    for a in range(3):
        k = int(math.floor((p[a] - lo[a]) / side[a]))
        if periodic[a]:
            k %= nc[a]
        elif k < 0:
            k = 0
        elif k >= nc[a]:
            k = nc[a] - 1
        c[a] = k
    return c


@njit
def _sphere_candidates(pos, r, skin, lo, side, nc, periodic, period, count_only, out_i, out_j, out_s):
    n = pos.shape[0]
    ncell = nc[0] * nc[1] * nc[2]
    cid = np.empty(n, np.int64)
    for i in range(n):
        c = _cell_of(pos[i], lo, side, nc, periodic)
        cid[i] = (c[0] * nc[1] + c[1]) * nc[2] + c[2]
    start = np.zeros(ncell + 1, np.int64)
    for i in range(n):
        start[cid[i] + 1] += 1
    for c in range(ncell):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(n, np.int64)
    for i in range(n):  # ascending i inside each cell
        order[fill[cid[i]]] = i
        fill[cid[i]] += 1
    m = 0
    seen = np.empty(27, np.int64)
    for i in range(n):
        c = _cell_of(pos[i], lo, side, nc, periodic)
        ns = 0
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                for dz in range(-1, 2):
                    q0 = c[0] + dx
                    q1 = c[1] + dy
                    q2 = c[2] + dz
                    if periodic[0]:
                        q0 %= nc[0]
                    elif q0 < 0 or q0 >= nc[0]:
                        continue
                    if periodic[1]:
                        q1 %= nc[1]
                    elif q1 < 0 or q1 >= nc[1]:
                        continue
                    if q2 < 0 or q2 >= nc[2]:
                        continue
                    q = (q0 * nc[1] + q1) * nc[2] + q2
                    dup = False
                    for s in range(ns):
                        if seen[s] == q:
                            dup = True
                            break
                    if dup:
                        continue
                    seen[ns] = q
                    ns += 1
                    for t in range(start[q], start[q + 1]):
                        j = order[t]
                        if j <= i:
                            continue
                        sx = 0.0
                        sy = 0.0
                        ddx = pos[j, 0] - pos[i, 0]
                        ddy = pos[j, 1] - pos[i, 1]
                        if periodic[0]:
                            sx = -period[0] * math.floor(ddx / period[0] + 0.5)
                            ddx += sx
                        if periodic[1]:
                            sy = -period[1] * math.floor(ddy / period[1] + 0.5)
                            ddy += sy
                        ddz = pos[j, 2] - pos[i, 2]
                        reach = r[i] + r[j] + skin
                        if ddx * ddx + ddy * ddy + ddz * ddz < reach * reach:
                            if not count_only:
                                out_i[m] = i
                                out_j[m] = j
                                out_s[m, 0] = sx
                                out_s[m, 1] = sy
                                out_s[m, 2] = 0.0
                            m += 1
    return m


def sphere_pairs(pos: np.ndarray, r: np.ndarray, skin: float, box, planes_point: np.ndarray,
                 planes_normal: np.ndarray):
    """The neighbour list (i, j, shift) in key order: sphere pairs within ``skin`` by cells, then
    sphere-plane pairs (j = n + plane) within r + skin."""
    n = pos.shape[0]
    side0 = 2.0 * (float(r.max()) if n else 1.0) + skin
    periodic = np.array([box.periodic_x, box.periodic_y, False])
    period = np.array([box.lx, box.ly, 0.0])
    lo = np.empty(3)
    nc = np.empty(3, np.int64)
    side = np.empty(3)
    for a in range(3):
        if periodic[a]:
            lo[a] = (box.x0, box.y0)[a]
            nc[a] = max(1, int(period[a] // side0))
            side[a] = period[a] / nc[a]
        else:
            lo[a] = pos[:, a].min() if n else 0.0
            span = (pos[:, a].max() - lo[a]) if n else 0.0
            nc[a] = max(1, int(span // side0) + 1)
            side[a] = side0
    # sparse scenes: never more cells than ~8 per sphere
    while nc.prod() > 8 * max(n, 1) + 27:
        for a in range(3):
            if not periodic[a] and nc[a] > 1:
                side[a] *= 2.0
                nc[a] = max(1, int(nc[a] // 2) + 1)
        if all(periodic[a] or nc[a] == 1 for a in range(3)):
            break
    e_i = np.empty(0, np.int64)
    e_s = np.empty((0, 3))
    m = _sphere_candidates(pos, r, skin, lo, side, nc, periodic, period, True, e_i, e_i, e_s)
    pi = np.empty(m, np.int64)
    pj = np.empty(m, np.int64)
    ps = np.empty((m, 3))
    _sphere_candidates(pos, r, skin, lo, side, nc, periodic, period, False, pi, pj, ps)
    order = np.lexsort((pj, pi))
    pi, pj, ps = pi[order], pj[order], ps[order]
    wi, wj = [], []
    for p in range(planes_point.shape[0]):
        h = (pos - planes_point[p]) @ planes_normal[p]
        near = np.nonzero(h < r + skin)[0]
        wi.append(near)
        wj.append(np.full(near.size, n + p, np.int64))
    if wi:
        qi = np.concatenate(wi)
        qj = np.concatenate(wj)
        order = np.lexsort((qj, qi))
        qi, qj = qi[order], qj[order]
        allk = np.concatenate([pi * (n + planes_point.shape[0]) + pj, qi * (n + planes_point.shape[0]) + qj])
        ii = np.concatenate([pi, qi])
        jj = np.concatenate([pj, qj])
        ss = np.concatenate([ps, np.zeros((qi.size, 3))])
        order = np.argsort(allk, kind="stable")
        return ii[order], jj[order], ss[order]
    return pi, pj, ps


def sphere_pairs_brute_force(pos, r, skin, box, planes_point, planes_normal):
    """O(N²) reference for :func:`sphere_pairs` (tests): every pair by minimum image."""
    n = pos.shape[0]
    nplanes = planes_point.shape[0]
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            d = pos[j] - pos[i]
            s = np.zeros(3)
            if box.periodic_x:
                s[0] = -box.lx * math.floor(d[0] / box.lx + 0.5)
            if box.periodic_y:
                s[1] = -box.ly * math.floor(d[1] / box.ly + 0.5)
            if np.linalg.norm(d + s) < r[i] + r[j] + skin:
                out.append((i, j, s))
        for p in range(nplanes):
            if (pos[i] - planes_point[p]) @ planes_normal[p] < r[i] + skin:
                out.append((i, n + p, np.zeros(3)))
    out.sort(key=lambda t: (t[0], t[1]))
    return (np.array([t[0] for t in out], np.int64), np.array([t[1] for t in out], np.int64),
            np.array([t[2] for t in out]).reshape(-1, 3))


def carry_history(old_i, old_j, old_hist, new_i, new_j, n_keys: int) -> np.ndarray:
    """History of the new pair list: rows of pairs listed before are kept (by key), new ones zero."""
    hist = np.zeros((new_i.size, old_hist.shape[1]))
    if old_i.size == 0 or new_i.size == 0:
        return hist
    ko = old_i * n_keys + old_j
    kn = new_i * n_keys + new_j
    idx = np.searchsorted(ko, kn)
    idx_c = np.minimum(idx, ko.size - 1)
    hit = ko[idx_c] == kn
    hist[hit] = old_hist[idx_c[hit]]
    return hist


@njit
def sphere_forces(sp, pairs, planes, law, dt, recording, max_overlap_ratio):
    """One pass over the pair list: contact forces and moments into sp.force / sp.torque (zeroed
    here) and planes.force, per-pair outputs into pairs.fn/ft/ovl/slide.  Returns (status, elastic
    energy) — the energy only when ``recording``."""
    n = sp.pos.shape[0]
    pos = sp.pos
    vel = sp.vel
    w = sp.angvel
    F = sp.force
    M = sp.torque
    F[:] = 0.0
    M[:] = 0.0
    planes.force[:] = 0.0
    hist = pairs.hist
    energy = 0.0
    status = 0
    for k in range(pairs.i.shape[0]):
        i = pairs.i[k]
        j = pairs.j[k]
        if j < n:
            dx = pos[j, 0] + pairs.shift[k, 0] - pos[i, 0]
            dy = pos[j, 1] + pairs.shift[k, 1] - pos[i, 1]
            dz = pos[j, 2] + pairs.shift[k, 2] - pos[i, 2]
            dist = math.sqrt(dx * dx + dy * dy + dz * dz)
            overlap = sp.r[i] + sp.r[j] - dist
            if overlap <= 0.0:
                for c in range(hist.shape[1]):
                    hist[k, c] = 0.0
                pairs.fn[k] = 0.0
                pairs.ft[k, 0] = 0.0
                pairs.ft[k, 1] = 0.0
                pairs.ft[k, 2] = 0.0
                pairs.ovl[k] = overlap
                pairs.slide[k] = 0
                continue
            nx = dx / dist
            ny = dy / dist
            nz = dz / dist
            ai = sp.r[i] - 0.5 * overlap
            aj = sp.r[j] - 0.5 * overlap
            # contact-point velocities: v + ω × arm (arm_i = ai n, arm_j = -aj n)
            vix = vel[i, 0] + ai * (w[i, 1] * nz - w[i, 2] * ny)
            viy = vel[i, 1] + ai * (w[i, 2] * nx - w[i, 0] * nz)
            viz = vel[i, 2] + ai * (w[i, 0] * ny - w[i, 1] * nx)
            vjx = vel[j, 0] - aj * (w[j, 1] * nz - w[j, 2] * ny)
            vjy = vel[j, 1] - aj * (w[j, 2] * nx - w[j, 0] * nz)
            vjz = vel[j, 2] - aj * (w[j, 0] * ny - w[j, 1] * nx)
            mi = sp.mass[i]
            mj = sp.mass[j]
            if sp.fixed[j]:
                meff = mi
            elif sp.fixed[i]:
                meff = mj
            else:
                meff = mi * mj / (mi + mj)
            rstar = sp.r[i] * sp.r[j] / (sp.r[i] + sp.r[j])
            mb = sp.mat[j]
            rmin = min(sp.r[i], sp.r[j])
        else:
            p = j - n
            nx = -planes.normal[p, 0]
            ny = -planes.normal[p, 1]
            nz = -planes.normal[p, 2]
            h = -((pos[i, 0] - planes.point[p, 0]) * nx + (pos[i, 1] - planes.point[p, 1]) * ny
                  + (pos[i, 2] - planes.point[p, 2]) * nz)
            overlap = sp.r[i] - h
            if overlap <= 0.0:
                for c in range(hist.shape[1]):
                    hist[k, c] = 0.0
                pairs.fn[k] = 0.0
                pairs.ft[k, 0] = 0.0
                pairs.ft[k, 1] = 0.0
                pairs.ft[k, 2] = 0.0
                pairs.ovl[k] = overlap
                pairs.slide[k] = 0
                continue
            ai = sp.r[i] - 0.5 * overlap
            aj = 0.0
            vix = vel[i, 0] + ai * (w[i, 1] * nz - w[i, 2] * ny)
            viy = vel[i, 1] + ai * (w[i, 2] * nx - w[i, 0] * nz)
            viz = vel[i, 2] + ai * (w[i, 0] * ny - w[i, 1] * nx)
            vjx = planes.vel[p, 0]
            vjy = planes.vel[p, 1]
            vjz = planes.vel[p, 2]
            meff = sp.mass[i]
            rstar = sp.r[i]
            mb = planes.mat[p]
            rmin = sp.r[i]
        if overlap > max_overlap_ratio * rmin:
            status = BLOWUP_OVERLAP
        rvx = vix - vjx
        rvy = viy - vjy
        rvz = viz - vjz
        vn = rvx * nx + rvy * ny + rvz * nz
        vtx = rvx - vn * nx
        vty = rvy - vn * ny
        vtz = rvz - vn * nz
        # rotate the tangential history vector into the current tangent plane, keeping its length
        hx = hist[k, 0]
        hy = hist[k, 1]
        hz = hist[k, 2]
        h2 = hx * hx + hy * hy + hz * hz
        if h2 > 0.0:
            hn = hx * nx + hy * ny + hz * nz
            tx = hx - hn * nx
            ty = hy - hn * ny
            tz = hz - hn * nz
            t2 = tx * tx + ty * ty + tz * tz
            if t2 > 0.0:
                s = math.sqrt(h2 / t2)
                hist[k, 0] = tx * s
                hist[k, 1] = ty * s
                hist[k, 2] = tz * s
            else:
                hist[k, 0] = 0.0
                hist[k, 1] = 0.0
                hist[k, 2] = 0.0
        Fn, Tx, Ty, Tz, sliding = law_force3(law, hist, k, sp.mat[i], mb, meff, rstar, overlap, vn,
                                             vtx, vty, vtz, nx, ny, nz, dt)
        fx = -Fn * nx + Tx
        fy = -Fn * ny + Ty
        fz = -Fn * nz + Tz
        if not (math.isfinite(fx) and math.isfinite(fy) and math.isfinite(fz)):
            status = BLOWUP_NONFINITE
        # moment arm × T: (a n) × T
        cx = ny * Tz - nz * Ty
        cy = nz * Tx - nx * Tz
        cz = nx * Ty - ny * Tx
        F[i, 0] += fx
        F[i, 1] += fy
        F[i, 2] += fz
        M[i, 0] += ai * cx
        M[i, 1] += ai * cy
        M[i, 2] += ai * cz
        if j < n:
            F[j, 0] -= fx
            F[j, 1] -= fy
            F[j, 2] -= fz
            M[j, 0] += aj * cx
            M[j, 1] += aj * cy
            M[j, 2] += aj * cz
        else:
            planes.force[j - n, 0] -= fx
            planes.force[j - n, 1] -= fy
            planes.force[j - n, 2] -= fz
        pairs.fn[k] = Fn
        pairs.ft[k, 0] = Tx
        pairs.ft[k, 1] = Ty
        pairs.ft[k, 2] = Tz
        pairs.ovl[k] = overlap
        pairs.slide[k] = 1 if sliding else 0
        if recording:
            energy = law_energy3(law, energy, hist, k, sp.mat[i], mb, rstar, overlap)
    return status, energy
