"""3D sphere contacts: the neighbour list (cells, periodic x/y by minimum image) and the pair pass.

Neighbour list.  Spheres are binned in cubic cells of side ≥ 2 r_max + skin over their bounding
box (a periodic axis: over its period, the cell count floor(L/side)); each sphere looks at the
distinct cells of its 3×3×3 stencil (wrapped along periodic axes, so a period of two cells is not
listed twice) and lists the pairs i < j whose surfaces are within ``skin``, the shift of j's image
chosen by minimum image.  Planes list every sphere within r + skin.  Pairs come out in key order
(i, then j; planes after spheres, j = n + plane), so history is carried across rebuilds by key
(:func:`carry_index`: one merge of the two lists) and every sum runs in the same order whatever the
thread count.  The search is one pass (each sphere's pairs put in order by j as they are found, in
place), the planes' and triangles' pairs merged in after it: a rebuild of the 1e5-sphere benchmark
packing took 106 ms against 477 ms for the two passes, NumPy sorts and search of before, the same
list and history to the bit (2026-11-29, best of 7 rebuilds of one state; at 1e4 16 against 40 ms).

Pair pass (:func:`sphere_forces`).  n is the unit normal from i to j (to the plane: minus its
normal), δ = R_i + R_j - |d| (plane: R_i - distance), the contact point mid-overlap, lever arms
(R - δ/2) as YADE's ScGeom.  The tangential history vector (columns 0-2) is rotated into the
current tangent plane keeping its length (projection and rescale, before the law's increment; LIGGGHTS
3.8.0 projects after the increment without rescaling, YADE 2023.02a rotates by T × (n_old × n): an
O(θ²)-per-step difference, capabilities feature 'history-rotation') — unless the law turns it itself
(:func:`demflow.laws.base.law_turns_history`: HertzMindlinLaw(history_rotation='project'), LIGGGHTS's rule, the
projection after the increment; the pass then skips the turn and its division and square root), then the law
(:func:`demflow.laws.base.law_force3`) returns the normal force Fn and tangential force T on i:
F_i = -Fn n + T, F_j = -F_i, moments (R_i - δ/2) n × T and (R_j - δ/2) n × T.
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import njit, njit_inline
from ..laws.base import law_energy3, law_force3, law_turns_history
from .spheres_blocks import (AI_AT, AJ_AT, BLOCK, COL, CX_AT, CY_AT, CZ_AT, DISS_AT, FN_AT, FX_AT, FY_AT, FZ_AT,
                             H0_AT, H1_AT, H2_AT, LANES, MA_AT, MB_AT, MEFF_AT, NH0_AT, NH1_AT, NH2_AT, NX_AT, NY_AT,
                             NZ_AT, OV_AT, RI_AT, RJ_AT, RSTAR_AT, SLIDE_AT, TX_AT, TY_AT, TZ_AT, VIX_AT, VJX_AT,
                             hertz_blocks, law_block3, law_columns, law_fill, work_array)

OK = 0
BLOWUP_OVERLAP = 1


@njit_inline
def _cell_of(p, lo, side, nc, periodic):
    """The cell (c0, c1, c2) of point p: wrapped along a periodic axis, clamped into the grid along the others."""
    c0 = _axis_cell(p[0], lo[0], side[0], nc[0], periodic[0])
    c1 = _axis_cell(p[1], lo[1], side[1], nc[1], periodic[1])
    c2 = _axis_cell(p[2], lo[2], side[2], nc[2], periodic[2])
    return c0, c1, c2


@njit_inline
def _axis_cell(x, lo, side, nc, periodic):
    k = int(math.floor((x - lo) / side))
    if periodic:
        k %= nc
    elif k < 0:
        k = 0
    elif k >= nc:
        k = nc - 1
    return k


@njit
def _sphere_candidates(pos, r, body, skin, lo, side, nc, periodic, period, out_i, out_j, out_s):
    """Sphere pairs i < j within ``skin`` (module docstring), in key order (i, then j): written to out_* while
    they have room; returns the count found (more than their length: call again with room for all)."""
    n = pos.shape[0]
    cap = out_i.shape[0]
    ncell = nc[0] * nc[1] * nc[2]
    cid = np.empty(n, np.int64)
    for i in range(n):
        c0, c1, c2 = _cell_of(pos[i], lo, side, nc, periodic)
        cid[i] = (c0 * nc[1] + c1) * nc[2] + c2
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
    quarter = 0.25 * period
    # a periodic axis of fewer than three cells wraps two stencil cells onto one: only then are they deduplicated
    dedup = (periodic[0] and nc[0] < 3) or (periodic[1] and nc[1] < 3)
    for i in range(n):
        c0 = cid[i] // (nc[1] * nc[2])  # sphere i's cell (as binned above)
        c1 = (cid[i] // nc[2]) % nc[1]
        c2 = cid[i] % nc[2]
        ns = 0
        m0 = m  # sphere i's pairs start here
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                for dz in range(-1, 2):
                    q0 = c0 + dx
                    q1 = c1 + dy
                    q2 = c2 + dz
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
                    if dedup:
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
                        if j <= i or (body[i] >= 0 and body[i] == body[j]):  # no contacts inside a clump
                            continue
                        sx = 0.0
                        sy = 0.0
                        ddx = pos[j, 0] - pos[i, 0]
                        ddy = pos[j, 1] - pos[i, 1]
                        # minimum image; within a quarter period of i the image is j itself, and the formula's
                        # shift is -period × 0.0 = -0.0 (adding it changes no bit): the division skipped
                        if periodic[0]:
                            if abs(ddx) < quarter[0]:
                                sx = -0.0
                            else:
                                sx = -period[0] * math.floor(ddx / period[0] + 0.5)
                                ddx += sx
                        if periodic[1]:
                            if abs(ddy) < quarter[1]:
                                sy = -0.0
                            else:
                                sy = -period[1] * math.floor(ddy / period[1] + 0.5)
                                ddy += sy
                        ddz = pos[j, 2] - pos[i, 2]
                        reach = r[i] + r[j] + skin
                        if ddx * ddx + ddy * ddy + ddz * ddz < reach * reach:
                            if m < cap:  # written in place, by insertion among sphere i's pairs so far (by j)
                                u = m
                                while u > m0 and out_j[u - 1] > j:
                                    out_j[u] = out_j[u - 1]
                                    out_s[u, 0] = out_s[u - 1, 0]
                                    out_s[u, 1] = out_s[u - 1, 1]
                                    u -= 1
                                out_i[m] = i
                                out_j[u] = j
                                out_s[u, 0] = sx
                                out_s[u, 1] = sy
                                out_s[m, 2] = 0.0
                            m += 1
    return m


@njit
def _merge_by_key(pi, pj, ps, qi, qj, qs, nk):
    """The two lists (each in key order i·nk + j, no key in both) merged in key order."""
    m = pi.shape[0] + qi.shape[0]
    oi = np.empty(m, np.int64)
    oj = np.empty(m, np.int64)
    os_ = np.empty((m, 3))
    a = 0
    b = 0
    for k in range(m):
        if b == qi.shape[0] or (a < pi.shape[0] and pi[a] * nk + pj[a] < qi[b] * nk + qj[b]):
            oi[k] = pi[a]
            oj[k] = pj[a]
            os_[k, 0] = ps[a, 0]
            os_[k, 1] = ps[a, 1]
            os_[k, 2] = ps[a, 2]
            a += 1
        else:
            oi[k] = qi[b]
            oj[k] = qj[b]
            os_[k, 0] = qs[b, 0]
            os_[k, 1] = qs[b, 1]
            os_[k, 2] = qs[b, 2]
            b += 1
    return oi, oj, os_


FACE = 0
EDGE = 1
VERTEX = 2


@njit
def closest_point_triangle(px, py, pz, v):
    """The point of triangle v = (a, b, c) (9 numbers) closest to p, and where it lies (FACE, EDGE or
    VERTEX): the Voronoi-region test on barycentric coordinates (Ericson 2005, §5.1.5)."""
    ax, ay, az = v[0], v[1], v[2]
    abx, aby, abz = v[3] - ax, v[4] - ay, v[5] - az
    acx, acy, acz = v[6] - ax, v[7] - ay, v[8] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return ax, ay, az, VERTEX
    bpx, bpy, bpz = px - v[3], py - v[4], pz - v[5]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return v[3], v[4], v[5], VERTEX
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        return ax + t * abx, ay + t * aby, az + t * abz, EDGE
    cpx, cpy, cpz = px - v[6], py - v[7], pz - v[8]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return v[6], v[7], v[8], VERTEX
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        return ax + t * acx, ay + t * acy, az + t * acz, EDGE
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return v[3] + t * (v[6] - v[3]), v[4] + t * (v[7] - v[4]), v[5] + t * (v[8] - v[5]), EDGE
    den = 1.0 / (va + vb + vc)
    t1 = vb * den
    t2 = vc * den
    return ax + abx * t1 + acx * t2, ay + aby * t1 + acy * t2, az + abz * t1 + acz * t2, FACE


@njit_inline
def _near_triangle(px, py, pz, reach, tv, t):
    """Is the point (px, py, pz) within ``reach`` of triangle t (a bounding-box rejection first)?"""
    lo0 = min(tv[t, 0], tv[t, 3], tv[t, 6]) - reach
    hi0 = max(tv[t, 0], tv[t, 3], tv[t, 6]) + reach
    if px < lo0 or px > hi0:
        return False
    lo1 = min(tv[t, 1], tv[t, 4], tv[t, 7]) - reach
    hi1 = max(tv[t, 1], tv[t, 4], tv[t, 7]) + reach
    if py < lo1 or py > hi1:
        return False
    lo2 = min(tv[t, 2], tv[t, 5], tv[t, 8]) - reach
    hi2 = max(tv[t, 2], tv[t, 5], tv[t, 8]) + reach
    if pz < lo2 or pz > hi2:
        return False
    cx, cy, cz, _ = closest_point_triangle(px, py, pz, tv[t])
    return (cx - px) ** 2 + (cy - py) ** 2 + (cz - pz) ** 2 < reach * reach


@njit
def _triangle_candidates(pos, r, skin, tv, imaged, periodic, period, count_only, out_i, out_t, out_s):
    """Sphere-triangle pairs within r + skin (brute force over triangles: O(n × n_triangles),
    with an early bounding-box rejection).  A triangle with ``imaged`` set is also tried at its
    periodic images (shifted by ±period along each periodic axis); out_s holds the shift of the
    image found (build allows at most one within reach: see TriangleMesh.periodic_images)."""
    m = 0
    for i in range(pos.shape[0]):
        reach = r[i] + skin
        for t in range(tv.shape[0]):
            sx = 0.0
            sy = 0.0
            found = _near_triangle(pos[i, 0], pos[i, 1], pos[i, 2], reach, tv, t)
            if not found and imaged[t]:
                for ix in range(-1, 2):
                    if ix != 0 and not periodic[0]:
                        continue
                    for iy in range(-1, 2):
                        if (iy != 0 and not periodic[1]) or (ix == 0 and iy == 0):
                            continue
                        # the sphere against the triangle shifted by s is the sphere at -s against the triangle
                        if _near_triangle(pos[i, 0] - ix * period[0], pos[i, 1] - iy * period[1], pos[i, 2], reach,
                                          tv, t):
                            found = True
                            sx = ix * period[0]
                            sy = iy * period[1]
                            break
                    if found:
                        break
            if found:
                if not count_only:
                    out_i[m] = i
                    out_t[m] = t
                    out_s[m, 0] = sx
                    out_s[m, 1] = sy
                    out_s[m, 2] = 0.0
                m += 1
    return m


def sphere_pairs(pos: np.ndarray, r: np.ndarray, skin: float, box, planes_point: np.ndarray,
                 planes_normal: np.ndarray, is_mesh: np.ndarray | None = None, tri_v: np.ndarray | None = None,
                 body: np.ndarray | None = None, tri_imaged: np.ndarray | None = None, capacity: int | None = None):
    """The neighbour list (i, j, shift) in key order: sphere pairs within ``skin`` by cells, then
    sphere-plane pairs (j = n + wall) within r + skin, then sphere-triangle pairs
    (j = n + n_walls + triangle) whose closest point is within r + skin.  ``shift``: the image
    shift of the other sphere, or of the triangle (those with ``tri_imaged`` set, in a periodic box:
    the particle meets the triangle at vertices + shift); zero for planes.  ``capacity``: room for this many
    sphere pairs in the first pass (a rebuild passes the last list's length plus an eighth and 64; default
    6 n + 64); a longer list costs a second pass, a shorter one a copy."""
    n = pos.shape[0]
    side0 = 2.0 * (float(r.max()) if n else 1.0) + skin
    periodic = np.array([box.periodic_x, box.periodic_y, False])
    period = np.array([box.lx, box.ly, 0.0])
    lo = np.empty(3)
    nc = np.empty(3, np.int64)
    side = np.empty(3)
    span = np.zeros(3)
    for a in range(3):
        if periodic[a]:
            lo[a] = (box.x0, box.y0)[a]
            nc[a] = max(1, int(period[a] // side0))
            side[a] = period[a] / nc[a]
        else:
            lo[a] = pos[:, a].min() if n else 0.0
            span[a] = (pos[:, a].max() - lo[a]) if n else 0.0
            nc[a] = max(1, int(span[a] // side0) + 1)
            side[a] = side0
    # sparse scenes: never more cells than ~8 per sphere.  The cells a doubled side needs are counted afresh from
    # the span (halving the count, nc // 2 + 1, stayed at 2 for ever: a sparse periodic bed two cells deep hung here)
    while nc.prod() > 8 * max(n, 1) + 27:
        for a in range(3):
            if not periodic[a] and nc[a] > 1:
                side[a] *= 2.0
                nc[a] = max(1, int(span[a] // side[a]) + 1)
        if all(periodic[a] or nc[a] == 1 for a in range(3)):
            break
    e_s = np.empty((0, 3))
    if body is None:
        body = np.full(n, -1, np.int64)
    # one pass with room for ``capacity`` pairs (a second only if they are more; the count is exact then)
    room = int(capacity) if capacity is not None else 6 * n + 64
    pi = np.empty(room, np.int64)
    pj = np.empty(room, np.int64)
    ps = np.empty((room, 3))
    m = _sphere_candidates(pos, r, body, skin, lo, side, nc, periodic, period, pi, pj, ps)
    if m > room:
        pi = np.empty(m, np.int64)
        pj = np.empty(m, np.int64)
        ps = np.empty((m, 3))
        _sphere_candidates(pos, r, body, skin, lo, side, nc, periodic, period, pi, pj, ps)
    elif m < room:
        pi, pj, ps = pi[:m].copy(), pj[:m].copy(), ps[:m].copy()
    wi, wj = [], []
    nw = planes_point.shape[0]
    for p in range(nw):
        if is_mesh is not None and is_mesh[p]:
            continue
        h = (pos - planes_point[p]) @ planes_normal[p]
        near = np.nonzero(h < r + skin)[0]
        wi.append(near)
        wj.append(np.full(near.size, n + p, np.int64))
    ws = [np.zeros((len(a), 3)) for a in wi]
    if tri_v is not None and tri_v.shape[0]:
        imaged = np.zeros(tri_v.shape[0], np.int8) if tri_imaged is None else tri_imaged
        e = np.empty(0, np.int64)
        mt = _triangle_candidates(pos, r, skin, tri_v, imaged, periodic, period, True, e, e, e_s)
        ti = np.empty(mt, np.int64)
        tt = np.empty(mt, np.int64)
        ts = np.empty((mt, 3))
        _triangle_candidates(pos, r, skin, tri_v, imaged, periodic, period, False, ti, tt, ts)
        wi.append(ti)
        wj.append(n + nw + tt)
        ws.append(ts)
    if wi:
        qi = np.concatenate(wi)
        qj = np.concatenate(wj)
        qs = np.concatenate(ws)
        order = np.lexsort((qj, qi))
        qi, qj, qs = qi[order], qj[order], qs[order]
        nk = n + nw + (0 if tri_v is None else tri_v.shape[0])
        return _merge_by_key(pi, pj, ps, np.ascontiguousarray(qi, np.int64), np.ascontiguousarray(qj, np.int64),
                             np.ascontiguousarray(qs, np.float64).reshape(-1, 3), nk)
    return pi, pj, ps


def sphere_pairs_brute_force(pos, r, skin, box, planes_point, planes_normal, body=None):
    """O(N²) reference for :func:`sphere_pairs` (tests): every pair by minimum image."""
    n = pos.shape[0]
    nplanes = planes_point.shape[0]
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            if body is not None and body[i] >= 0 and body[i] == body[j]:
                continue
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


@njit
def carry_index(old_i, old_j, new_i, new_j, n_keys):
    """For each pair of the new list, its row in the old list (-1: listed anew).  Keys i·n_keys + j; the old list
    is in key order (every list is), and so is the new one, so one merge finds them all (a new list out of order
    would only restart the scan, never give a wrong row)."""
    src = np.full(new_i.shape[0], -1, np.int64)
    a = 0
    last = -1
    for b in range(new_i.shape[0]):
        kn = new_i[b] * n_keys + new_j[b]
        if kn < last:
            a = 0
        last = kn
        while a < old_i.shape[0] and old_i[a] * n_keys + old_j[a] < kn:
            a += 1
        if a < old_i.shape[0] and old_i[a] * n_keys + old_j[a] == kn:
            src[b] = a
    return src


@njit
def carry_rows(src, old, out):
    """out[k] = old[src[k]] where src[k] >= 0, else zero (rows of a 2D array)."""
    for k in range(src.shape[0]):
        a = src[k]
        for c in range(out.shape[1]):
            out[k, c] = old[a, c] if a >= 0 else 0


@njit
def carry_values(src, old, out):
    """out[k] = old[src[k]] where src[k] >= 0, else zero (a 1D array)."""
    for k in range(src.shape[0]):
        a = src[k]
        out[k] = old[a] if a >= 0 else 0


@njit
def pack_rows(sp):
    """Copy the moving state into the packed rows P the pair pass reads (one 128-byte row per sphere:
    a touching pair then reads two rows instead of fourteen scattered values)."""
    P = sp.P
    for i in range(sp.pos.shape[0]):
        for a in range(3):
            P[i, a] = sp.pos[i, a]
            P[i, 3 + a] = sp.vel[i, a]
            P[i, 6 + a] = sp.angvel[i, a]


@njit_inline
def triangle_image(tv, t, shift, k, image):
    """Triangle t's vertices as pair k sees them: tv[t] itself, or its periodic image tv[t] + shift[k]
    written into ``image`` (9)."""
    if shift[k, 0] == 0.0 and shift[k, 1] == 0.0 and shift[k, 2] == 0.0:
        return tv[t]
    for c in range(3):
        image[3 * c] = tv[t, 3 * c] + shift[k, 0]
        image[3 * c + 1] = tv[t, 3 * c + 1] + shift[k, 1]
        image[3 * c + 2] = tv[t, 3 * c + 2] + shift[k, 2]
    return image


@njit
def triangle_contacts(P, pairs, n, nw, tris):
    """Closest points of the listed sphere-triangle pairs (in pair order) and which of them act:
    a face contact always; an edge or vertex contact only when no face of the same mesh touches
    that sphere, once per point (two triangles sharing the edge or vertex give the same point), and
    only when no touching triangle of the mesh holds that point and has a closer point of its own
    (then the distance falls from it across that triangle: it is no local minimum of the distance to
    the mesh, e.g. a vertex near a sphere whose closest point lies on a shared edge of a flat mesh).
    Returns (points (mt, 3), active (mt,) int8)."""
    m = pairs.i.shape[0]
    mt = 0
    for k in range(m):
        if pairs.j[k] >= n + nw:
            mt += 1
    cp = np.empty((mt, 3))
    region = np.empty(mt, np.int64)
    touch = np.zeros(mt, np.int8)
    active = np.zeros(mt, np.int8)
    dist2 = np.empty(mt)
    image = np.empty(9)
    q = 0
    k = 0
    while k < m:
        if pairs.j[k] < n + nw:
            k += 1
            continue
        i = pairs.i[k]
        q0 = q
        while k < m and pairs.i[k] == i and pairs.j[k] >= n + nw:
            t = pairs.j[k] - n - nw
            cx, cy, cz, reg = closest_point_triangle(P[i, 0], P[i, 1], P[i, 2],
                                                     triangle_image(tris.v, t, pairs.shift, k, image))
            cp[q, 0] = cx
            cp[q, 1] = cy
            cp[q, 2] = cz
            region[q] = reg
            d2 = (cx - P[i, 0]) ** 2 + (cy - P[i, 1]) ** 2 + (cz - P[i, 2]) ** 2
            dist2[q] = d2
            touch[q] = 1 if d2 < P[i, 9] * P[i, 9] else 0
            q += 1
            k += 1
        tol2 = (1e-9 * P[i, 9]) ** 2
        for a in range(q0, q):
            if not touch[a]:
                continue
            wa = tris.wall[pairs.j[k - (q - a)] - n - nw]
            if region[a] == FACE:
                active[a] = 1
                continue
            ok = True
            for b in range(q0, q):
                wb = tris.wall[pairs.j[k - (q - b)] - n - nw]
                if b == a or wb != wa or not touch[b]:
                    continue
                if region[b] == FACE:
                    ok = False
                    break
                if b < a and active[b] and ((cp[a, 0] - cp[b, 0]) ** 2 + (cp[a, 1] - cp[b, 1]) ** 2
                                            + (cp[a, 2] - cp[b, 2]) ** 2) <= tol2:
                    ok = False
                    break
                if dist2[b] < dist2[a]:
                    kb = k - (q - b)
                    px, py, pz, _ = closest_point_triangle(
                        cp[a, 0], cp[a, 1], cp[a, 2], triangle_image(tris.v, pairs.j[kb] - n - nw, pairs.shift, kb, image))
                    if (px - cp[a, 0]) ** 2 + (py - cp[a, 1]) ** 2 + (pz - cp[a, 2]) ** 2 <= tol2:
                        ok = False
                        break
            active[a] = 1 if ok else 0
    return cp, active


@njit_inline
def _apart(pairs, k, ovl):
    """Pair k is not touching: clear its history and outputs; record ``ovl`` (its gap, <= 0)."""
    for c in range(pairs.hist.shape[1]):
        pairs.hist[k, c] = 0.0
    pairs.fn[k] = 0.0
    pairs.ft[k, 0] = 0.0
    pairs.ft[k, 1] = 0.0
    pairs.ft[k, 2] = 0.0
    pairs.ovl[k] = ovl
    pairs.slide[k] = 0


@njit_inline
def _point_velocity(P, i, arm, nx, ny, nz):
    """Velocity of the point at ``arm`` × n from sphere i's centre: v + ω × (arm n)."""
    return (P[i, 3] + arm * (P[i, 7] * nz - P[i, 8] * ny), P[i, 4] + arm * (P[i, 8] * nx - P[i, 6] * nz),
            P[i, 5] + arm * (P[i, 6] * ny - P[i, 7] * nx))


@njit_inline
def relative_velocity(rvx, rvy, rvz, nx, ny, nz):
    """Normal and tangential parts of the contact points' relative velocity rv = v_i - v_j:
    (vn = rv·n, > 0 approaching; v_t = rv - vn n)."""
    vn = rvx * nx + rvy * ny + rvz * nz
    return vn, rvx - vn * nx, rvy - vn * ny, rvz - vn * nz


@njit_inline
def rotate_history(hist, k, nx, ny, nz):
    """Turn contact k's tangential history vector (columns 0-2) into the current tangent plane (normal n),
    keeping its length (a vector along n is dropped)."""
    hx = hist[k, 0]
    hy = hist[k, 1]
    hz = hist[k, 2]
    hn = hx * nx + hy * ny + hz * nz
    if hn != 0.0:
        h2 = hx * hx + hy * hy + hz * hz
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


@njit_inline
def _effective_mass(mi, mj, fixed_i, fixed_j):
    """The pair's effective mass m_i m_j / (m_i + m_j), or the free sphere's mass against a fixed one (the packed
    rows' column 12 non-zero)."""
    if fixed_j != 0.0:
        return mi
    if fixed_i != 0.0:
        return mj
    return mi * mj / (mi + mj)


@njit_inline
def _separation(P, pairs, k):
    """Sphere pair k (j < n): d = c_j + shift - c_i, |d|² and R_i + R_j (stage 1 and the pairs apart of
    :func:`sphere_forces`: one expression, so both compute the same bits)."""
    i = np.uint64(pairs.i[k])
    j = np.uint64(pairs.j[k])
    dx = P[j, 0] + pairs.shift[k, 0] - P[i, 0]
    dy = P[j, 1] + pairs.shift[k, 1] - P[i, 1]
    dz = P[j, 2] + pairs.shift[k, 2] - P[i, 2]
    return dx, dy, dz, dx * dx + dy * dy + dz * dz, P[i, 9] + P[j, 9]


# BLOCK (spheres_blocks): listed pairs staged per block (module docstring of sphere_forces)


@njit
def sphere_forces(sp, pairs, planes, tris, law, dt, recording, max_overlap_ratio):
    """One pass over the pair list: contact forces and moments into sp.FM (force 0-2, moment 3-5;
    zeroed here) and planes.force, per-pair outputs into pairs.fn/ft/ovl/slide.  Reads the packed
    rows sp.P (:func:`pack_rows`).  Returns (status, elastic energy, energy the contacts' dashpots and
    slip dissipated in the step, summed in pair order) — the elastic energy only when ``recording``.  A non-finite force is caught by the integrator's step-length test.

    The pass runs in blocks of BLOCK listed pairs, in three stages, so that the square roots and divisions of
    many pairs are in flight at once (one touching pair is a few hundred instructions whose chain of square
    roots and divisions is longer than the processor's reordering window; pair by pair they ran one after
    the other): (1) the distance test of every sphere pair, without a branch on its outcome (in a dense packing it
    is a coin toss; its mispredictions cost 5-12 % of the step at 1e4 and 1e5 spheres:
    benchmarks/results/speed3d_session35_ab.md), the pairs touching queued in pair order with planes and
    triangles, the pairs apart that have something to write (just parted, listed anew, or a recording step)
    listed and handled after the test; (2) for the queued sphere pairs the distance, normal and
    overlap, and the history turned into the new tangent plane; (3) in pair order, the law and the sums.
    Each pair's arithmetic, and the order of every sum, are those of one pass pair by pair: the same bits.  Rows are
    indexed with unsigned integers (as in :mod:`demflow.contacts.forces`), and the law returns the contact's new
    history row, written here (:func:`demflow.laws.base.law_force3`): 14 % less time a step at 1e4 and 1e5 spheres
    together (benchmarks/results/speed3d_session34_ab.md).  The law's tables are read with unsigned material indices
    too: Numba's wrap-around test of a signed index cost 44 of the 370 instructions of a touching pair's path and
    8.5 % of the pass's instructions (valgrind's callgrind; the step's time moved within the A/B's noise:
    benchmarks/results/speed_experiments_session39.md).

    For a Hertz-Mindlin scene without Mindlin-Deresiewicz (:func:`demflow.contacts.spheres_blocks.hertz_blocks`)
    stages 2 and 3 take the vector path: stage 1 also copies each queued pair's history row into the work array
    (in pair order, so the reads stream), stage 2 writes each queued sphere pair's normal, overlap, masses, radii,
    velocities and materials into its lane, :func:`demflow.contacts.spheres_blocks.hertz_block` turns the history
    and evaluates the law for all lanes at once (vector instructions), and stage 3 adds the lanes' forces in pair
    order; planes and triangles keep the scalar path.  The same bits (tests/test_spheres_blocks.py)."""
    n = sp.P.shape[0]
    P = sp.P
    FM = sp.FM
    FM[:] = 0.0
    planes.force[:] = 0.0
    hist = pairs.hist
    energy = 0.0
    diss = 0.0
    status = 0
    nw = planes.point.shape[0]
    turns = law_turns_history(law)  # the law turns the history itself (after its increment)
    if tris.v.shape[0]:
        tcp, tact = triangle_contacts(P, pairs, n, nw, tris)
    else:
        tcp, tact = np.empty((0, 3)), np.empty(0, np.int8)
    q = -1
    m = pairs.i.shape[0]
    qk = np.empty(BLOCK, np.int64)  # the queued pairs of a block, in pair order
    rk = np.empty(BLOCK, np.int64)  # the block's pairs apart with something to write (stage 1)
    qx = np.empty(BLOCK)  # sphere pairs: d (stage 1), then n (stage 2); planes and triangles: qd2 = -1
    qy = np.empty(BLOCK)
    qz = np.empty(BLOCK)
    qd2 = np.empty(BLOCK)  # |d|² (stage 1), then the overlap (stage 2)
    qdist = np.empty(BLOCK)  # sphere pairs: |d| and 1/|d| (stage 2)
    qinv = np.empty(BLOCK)
    qm = np.empty(BLOCK)  # sphere pairs: the effective mass and radius (stage 2)
    qr = np.empty(BLOCK)
    qi = np.empty(BLOCK, np.uint64)  # the vector path's sphere pairs: their rows (stage 2, for stage 3)
    qj = np.empty(BLOCK, np.uint64)
    vec = hertz_blocks(law)  # the sphere pairs' law in vector lanes (demflow.contacts.spheres_blocks)
    W = work_array(law)
    filled = False  # the law columns hold material m_first's numbers in every lane
    m_first = P[0, 11] if n else 0.0  # a material of the scene: the padding lanes' (their law numbers are read)
    for k0 in range(0, m, BLOCK):
        k1 = min(k0 + BLOCK, m)
        nq = 0
        nr = 0
        # stage 1: the distance test
        for k in range(k0, k1):
            ku = np.uint64(k)
            j = pairs.j[ku]
            if j < n:
                dx, dy, dz, d2, rs = _separation(P, pairs, ku)
                # no branch on the test (a coin toss in a dense packing, whose mispredictions cost more than the
                # work): the pair is written to the queue's next slot, which it keeps if touching; a pair apart
                # with something to write (just parted, listed anew, or a recording step) is listed for later
                apart = np.int64(d2 >= rs * rs)
                slot = np.uint64(nq)
                qx[slot] = dx
                qy[slot] = dy
                qz[slot] = dz
                qd2[slot] = d2
                qk[slot] = k
                if vec:  # the history row, read here in pair order (read in stage 2 it waited on memory)
                    W[H0_AT + slot] = hist[ku, 0]
                    W[H1_AT + slot] = hist[ku, 1]
                    W[H2_AT + slot] = hist[ku, 2]
                nq += 1 - apart
                rk[np.uint64(nr)] = k
                nr += apart * np.int64(recording | (pairs.ovl[ku] != -1.0))
                continue
            slot = np.uint64(nq)
            qd2[slot] = -1.0
            qk[slot] = k
            nq += 1
        for t in range(nr):  # the pairs apart with something to write
            k = rk[t]
            ku = np.uint64(k)
            _, _, _, d2, rs = _separation(P, pairs, ku)
            if pairs.ovl[ku] >= 0.0:  # touching last step (or listed anew): clear it once
                _apart(pairs, ku, -1.0)
            if recording:
                pairs.ovl[ku] = rs - math.sqrt(d2)
            elif pairs.ovl[ku] != -1.0:  # written once, not every step (0.13 ms a step on 35 000 such pairs)
                pairs.ovl[ku] = -1.0
        # stage 2: normal, overlap and the history's turn of the queued sphere pairs; the roots and
        # reciprocals first, in a loop without branches (compiled to vector instructions)
        for t in range(nq):
            dist = math.sqrt(abs(qd2[t]))
            qdist[t] = dist
            qinv[t] = 1.0 / dist
        if vec:  # the lanes of the work array (demflow.contacts.spheres_blocks): written here, not by a helper
            # (an inlined helper handed an array keeps an atomic reference-count update per call)
            mixed = False
            for t in range(nq):
                tu = np.uint64(t)
                if qd2[tu] < 0.0:  # a plane's or triangle's slot: the lane keeps earlier numbers, computed, never read
                    W[MA_AT + tu] = m_first  # (a material the law's tables hold, for law_columns)
                    W[MB_AT + tu] = m_first
                    continue
                k = np.uint64(qk[tu])
                i = np.uint64(pairs.i[k])
                j = np.uint64(pairs.j[k])
                qi[tu] = i
                qj[tu] = j
                dist = qdist[tu]
                ri = P[i, 9]
                rj = P[j, 9]
                rs = ri + rj
                inv = qinv[tu]
                W[NX_AT + tu] = qx[tu] * inv
                W[NY_AT + tu] = qy[tu] * inv
                W[NZ_AT + tu] = qz[tu] * inv
                W[OV_AT + tu] = rs - dist
                W[MEFF_AT + tu] = _effective_mass(P[i, 10], P[j, 10], P[i, 12], P[j, 12])
                W[RSTAR_AT + tu] = ri * rj / rs
                W[RI_AT + tu] = ri
                W[RJ_AT + tu] = rj
                for a in range(6):  # velocity and spin of each sphere (columns VIX..WIZ, VJX..WJZ), unrolled
                    col = np.uint64(a * COL)
                    W[VIX_AT + col + tu] = P[i, 3 + a]
                    W[VJX_AT + col + tu] = P[j, 3 + a]
                ma = P[i, 11]
                mb = P[j, 11]
                W[MA_AT + tu] = ma
                W[MB_AT + tu] = mb
                mixed |= (ma != m_first) | (mb != m_first)
            nl = (nq + LANES - 1) // LANES * LANES
            for t in range(nq, nl):  # padding lanes: as a plane's slot
                W[MA_AT + np.uint64(t)] = m_first
                W[MB_AT + np.uint64(t)] = m_first
            # the law's columns: each lane's material pair, or one fill for blocks of one material (kept while
            # the blocks that follow are of it too)
            if mixed:
                law_columns(law, W, nl)
                filled = False
            elif not filled:
                law_fill(law, W, m_first)
                filled = True
            law_block3(law, W, nl, dt)
        for t in range(nq if not vec else 0):  # the scalar path's stage 2
            if qd2[t] < 0.0:
                continue
            k = np.uint64(qk[t])
            i = np.uint64(pairs.i[k])
            j = np.uint64(pairs.j[k])
            dist = qdist[t]
            ri = P[i, 9]
            rj = P[j, 9]
            rs = ri + rj
            qd2[t] = rs - dist
            inv = qinv[t]
            nx = qx[t] * inv
            ny = qy[t] * inv
            nz = qz[t] * inv
            qx[t] = nx
            qy[t] = ny
            qz[t] = nz
            if not turns:
                rotate_history(hist, k, nx, ny, nz)
            qm[t] = _effective_mass(P[i, 10], P[j, 10], P[i, 12], P[j, 12])
            qr[t] = ri * rj / rs
        # stage 3: the law (scalar path) and the sums, in pair order
        for t in range(nq):
            if vec and qd2[t] >= 0.0:  # a sphere pair's lane (its rows and index kept by stage 2)
                tu = np.uint64(t)
                k = np.uint64(qk[tu])
                i = qi[tu]
                ju = qj[tu]
                j = np.int64(ju)
                overlap = W[OV_AT + tu]
                if overlap > max_overlap_ratio * min(W[RI_AT + tu], W[RJ_AT + tu]):
                    status = BLOWUP_OVERLAP
                hist[k, 0] = W[NH0_AT + tu]
                hist[k, 1] = W[NH1_AT + tu]
                hist[k, 2] = W[NH2_AT + tu]
                Fn = W[FN_AT + tu]
                Tx = W[TX_AT + tu]
                Ty = W[TY_AT + tu]
                Tz = W[TZ_AT + tu]
                sliding = W[SLIDE_AT + tu] != 0.0
                dissipated = W[DISS_AT + tu]
                ai = W[AI_AT + tu]
                aj = W[AJ_AT + tu]
                fx = W[FX_AT + tu]
                fy = W[FY_AT + tu]
                fz = W[FZ_AT + tu]
                cx = W[CX_AT + tu]
                cy = W[CY_AT + tu]
                cz = W[CZ_AT + tu]
                rstar = W[RSTAR_AT + tu]
                ma = np.uint64(np.int64(P[i, 11])) if recording else np.uint64(0)  # (for the elastic energy)
                mb = np.uint64(np.int64(P[ju, 11])) if recording else np.uint64(0)
            else:
                k = np.uint64(qk[t])
                i = np.uint64(pairs.i[k])
                j = pairs.j[k]
                ju = np.uint64(j)  # the other sphere's row (j < n)
                ri = P[i, 9]
                if j >= n + nw:  # a triangle
                    q += 1
                    w = tris.wall[j - n - nw]
                    dx = tcp[q, 0] - P[i, 0]
                    dy = tcp[q, 1] - P[i, 1]
                    dz = tcp[q, 2] - P[i, 2]
                    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
                    overlap = ri - dist
                    if not tact[q] or dist == 0.0:
                        _apart(pairs, k, min(overlap, 0.0))
                        continue
                    nx = dx / dist
                    ny = dy / dist
                    nz = dz / dist
                    ai = ri - 0.5 * overlap
                    aj = 0.0
                    vix, viy, viz = _point_velocity(P, i, ai, nx, ny, nz)
                    vjx = planes.vel[w, 0]
                    vjy = planes.vel[w, 1]
                    vjz = planes.vel[w, 2]
                    meff = P[i, 10]
                    rstar = ri
                    mb = np.uint64(planes.mat[w])
                    rmin = ri
                    if not turns:
                        rotate_history(hist, k, nx, ny, nz)
                elif j < n:
                    nx = qx[t]
                    ny = qy[t]
                    nz = qz[t]
                    overlap = qd2[t]
                    rj = P[ju, 9]
                    ai = ri - 0.5 * overlap
                    aj = rj - 0.5 * overlap
                    # contact-point velocities: v + ω × arm (arm_i = ai n, arm_j = -aj n)
                    vix, viy, viz = _point_velocity(P, i, ai, nx, ny, nz)
                    vjx, vjy, vjz = _point_velocity(P, ju, -aj, nx, ny, nz)
                    meff = qm[t]
                    rstar = qr[t]
                    mb = np.uint64(np.int64(P[ju, 11]))
                    rmin = min(ri, rj)
                else:
                    p = j - n
                    nx = -planes.normal[p, 0]
                    ny = -planes.normal[p, 1]
                    nz = -planes.normal[p, 2]
                    h = -((P[i, 0] - planes.point[p, 0]) * nx + (P[i, 1] - planes.point[p, 1]) * ny
                          + (P[i, 2] - planes.point[p, 2]) * nz)
                    overlap = ri - h
                    if overlap <= 0.0:
                        _apart(pairs, k, overlap)
                        continue
                    ai = ri - 0.5 * overlap
                    aj = 0.0
                    vix, viy, viz = _point_velocity(P, i, ai, nx, ny, nz)
                    vjx = planes.vel[p, 0]
                    vjy = planes.vel[p, 1]
                    vjz = planes.vel[p, 2]
                    meff = P[i, 10]
                    rstar = ri
                    mb = np.uint64(planes.mat[p])
                    rmin = ri
                    if not turns:
                        rotate_history(hist, k, nx, ny, nz)
                if overlap > max_overlap_ratio * rmin:
                    status = BLOWUP_OVERLAP
                vn, vtx, vty, vtz = relative_velocity(vix - vjx, viy - vjy, viz - vjz, nx, ny, nz)
                ma = np.uint64(np.int64(P[i, 11]))  # unsigned: the law's tables are read without a wrap-around test
                Fn, Tx, Ty, Tz, sliding, dissipated, row, n_row = law_force3(law, hist, k, ma, mb, meff, rstar, overlap,
                                                                             vn, vtx, vty, vtz, nx, ny, nz, dt)
                for c in range(n_row):
                    hist[k, c] = row[c]
                fx = -Fn * nx + Tx
                fy = -Fn * ny + Ty
                fz = -Fn * nz + Tz
                # moment arm × T: (a n) × T
                cx = ny * Tz - nz * Ty
                cy = nz * Tx - nx * Tz
                cz = nx * Ty - ny * Tx
            diss += dissipated
            FM[i, 0] += fx
            FM[i, 1] += fy
            FM[i, 2] += fz
            FM[i, 3] += ai * cx
            FM[i, 4] += ai * cy
            FM[i, 5] += ai * cz
            if j < n:
                FM[ju, 0] -= fx
                FM[ju, 1] -= fy
                FM[ju, 2] -= fz
                FM[ju, 3] += aj * cx
                FM[ju, 4] += aj * cy
                FM[ju, 5] += aj * cz
            else:
                w = j - n if j < n + nw else tris.wall[j - n - nw]
                planes.force[w, 0] -= fx
                planes.force[w, 1] -= fy
                planes.force[w, 2] -= fz
            pairs.ovl[k] = overlap
            pairs.fn[k] = Fn
            pairs.ft[k, 0] = Tx
            pairs.ft[k, 1] = Ty
            pairs.ft[k, 2] = Tz
            pairs.slide[k] = 1 if sliding else 0
            if recording:
                energy = law_energy3(law, energy, hist, k, ma, mb, rstar, overlap)
    return status, energy, diss
