"""The ellipsoid pair pass: contact forces of ellipsoids, planes and triangle meshes.

The neighbour list is the sphere list (:func:`demflow.contacts.spheres.sphere_pairs`) of the
ellipsoids' bounding spheres (radius the largest semi-axis), so every pair that can touch within
the skin is listed; each listed pair's contact is then found by its geometry
(:mod:`demflow.shapes.ellipsoid`): the Lin & Ng potential points for two ellipsoids (warm-started
from the multipliers of the last step, kept in the pair's history row after the law's columns),
the support point for a plane, the face/edge/vertex test for a triangle.  A pair whose bounding
spheres are apart, or whose extents along the line of centres do not meet (a separating axis), is
apart without a solve.

Forces: n from i to j, δ the overlap, C the contact point, arms r_i = C - c_i, r_j = C - c_j; the
tangential history vector (columns 0-2) is rotated into the current tangent plane keeping its
length exactly as in the sphere pass, then the law (:func:`demflow.laws.base.law_force3`) with
R* = R_e (the equivalent radius of the contact's curvature, Miyata eqs 45-48) gives Fn and T;
F_i = -Fn n + T, F_j = -F_i, moments r_i × F_i and r_j × F_j (the normal force has a moment on an
ellipsoid).  Each particle is its own rigid body (one member at offset 0), so the forces and
moments go to the particle rows and :func:`demflow.stepping3d.body_step` integrates them.

Triangle dedup (as :func:`demflow.contacts.spheres.triangle_contacts`): a FACE contact always
acts; an EDGE or VERTEX contact only when no face of the same mesh touches that ellipsoid, and once
per point (two triangles sharing the edge or vertex give the same point).
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import njit, njit_inline
from ..laws.base import law_energy3, law_force3, law_turns_history
from ..shapes.ellipsoid import FACE, ellipsoid_pair, ellipsoid_plane, ellipsoid_triangle
from .spheres import relative_velocity, rotate_history, triangle_image

BLOWUP_OVERLAP = 1
WARM_COLUMNS = 3  # history columns after the law's: warm flag, λ_i, λ_j


@njit
def _triangle_pass(pos, rot, axes, amin, pairs, n, nw, tris, out):
    """Every listed ellipsoid-triangle pair's contact in pair order into ``out`` (mt, 9):
    overlap, n (3), point (3), R_e, active (1/0)."""
    m = pairs.i.shape[0]
    region = np.empty(out.shape[0], np.int64)
    image = np.empty(9)
    q = 0
    k = 0
    while k < m:
        if pairs.j[k] < n + nw:
            k += 1
            continue
        i = pairs.i[k]
        q0 = q
        k0 = k
        while k < m and pairs.i[k] == i and pairs.j[k] >= n + nw:
            t = pairs.j[k] - n - nw
            o, nx, ny, nz, cx, cy, cz, re, reg = ellipsoid_triangle(pos[i], rot[i], axes[i],
                                                                    triangle_image(tris.v, t, pairs.shift, k, image))
            out[q, 0] = o
            out[q, 1] = nx
            out[q, 2] = ny
            out[q, 3] = nz
            out[q, 4] = cx
            out[q, 5] = cy
            out[q, 6] = cz
            out[q, 7] = re
            out[q, 8] = 0.0
            region[q] = reg
            q += 1
            k += 1
        tol2 = (1e-9 * amin[i]) ** 2
        for a in range(q0, q):
            if not out[a, 0] > 0.0:
                continue
            wa = tris.wall[pairs.j[k0 + a - q0] - n - nw]
            if region[a] == FACE:
                out[a, 8] = 1.0
                continue
            ok = True
            for b in range(q0, q):
                wb = tris.wall[pairs.j[k0 + b - q0] - n - nw]
                if b == a or wb != wa or not out[b, 0] > 0.0:
                    continue
                if region[b] == FACE:
                    ok = False
                    break
                if b < a and out[b, 8] == 1.0 and ((out[a, 4] - out[b, 4]) ** 2 + (out[a, 5] - out[b, 5]) ** 2
                                                   + (out[a, 6] - out[b, 6]) ** 2) <= tol2:
                    ok = False
                    break
            out[a, 8] = 1.0 if ok else 0.0


@njit
def ellipsoid_forces(sp, ell, pairs, planes, tris, law, dt, recording, max_overlap_ratio):
    """One pass over the pair list (module docstring): forces and moments into sp.FM (zeroed here)
    and planes.force, per-pair outputs into pairs.fn/ft/ovl/slide.  ``ell`` holds the semi-axes
    (n, 3), their smallest ``amin`` (n,) and the rotations ``rot`` (n, 9) of this step.
    Returns (status, elastic energy, Newton iterations of the pass, energy the contacts dissipated)."""
    n = sp.pos.shape[0]
    pos = sp.pos
    vel = sp.vel
    w = sp.angvel
    FM = sp.FM
    FM[:] = 0.0
    planes.force[:] = 0.0
    hist = pairs.hist
    c0 = hist.shape[1] - 3  # warm-start columns
    energy = 0.0
    status = 0
    iters = 0
    diss = 0.0
    nw = planes.point.shape[0]
    turns = law_turns_history(law)  # the law turns the history itself (after its increment)
    mt = 0
    for k in range(pairs.i.shape[0]):
        if pairs.j[k] >= n + nw:
            mt += 1
    tri = np.zeros((mt, 9))
    if mt:
        _triangle_pass(pos, ell.rot, ell.axes, ell.amin, pairs, n, nw, tris, tri)
    work = np.zeros((6, 3))
    M = np.zeros((3, 3))
    H = np.zeros((3, 3))
    cj = np.zeros(3)
    q = -1
    for k in range(pairs.i.shape[0]):
        i = pairs.i[k]
        j = pairs.j[k]
        if j >= n + nw:
            q += 1
            wall = tris.wall[j - n - nw]
            overlap = tri[q, 0]
            if tri[q, 8] == 0.0 or not overlap > 0.0:
                _clear(pairs, k, min(overlap, 0.0), c0)
                continue
            nx, ny, nz = tri[q, 1], tri[q, 2], tri[q, 3]
            cx, cy, cz = tri[q, 4], tri[q, 5], tri[q, 6]
            re = tri[q, 7]
            meff = sp.mass[i]
            mb = planes.mat[wall]
            rmin = ell.amin[i]
            vjx = planes.vel[wall, 0]
            vjy = planes.vel[wall, 1]
            vjz = planes.vel[wall, 2]
        elif j < n:
            cj[0] = pos[j, 0] + pairs.shift[k, 0]
            cj[1] = pos[j, 1] + pairs.shift[k, 1]
            cj[2] = pos[j, 2] + pairs.shift[k, 2]
            dx = cj[0] - pos[i, 0]
            dy = cj[1] - pos[i, 1]
            dz = cj[2] - pos[i, 2]
            reach = sp.r[i] + sp.r[j]  # bounding spheres apart: no contact, no solve
            d2 = dx * dx + dy * dy + dz * dz
            if d2 >= reach * reach:
                if pairs.ovl[k] >= 0.0:
                    _clear(pairs, k, -1.0, c0)
                    hist[k, c0] = 0.0
                pairs.ovl[k] = -1.0
                continue
            # separated along the line of centres (their extents along it do not meet): no solve
            dist = math.sqrt(d2)
            gap = dist - _extent(ell.rot[i], ell.axes[i], dx, dy, dz, dist) - _extent(ell.rot[j], ell.axes[j], dx, dy,
                                                                                    dz, dist)
            if gap >= 0.0:
                if pairs.ovl[k] >= 0.0:
                    _clear(pairs, k, -gap, c0)
                pairs.ovl[k] = -gap
                continue
            overlap, nx, ny, nz, cx, cy, cz, re, li, lj, it = ellipsoid_pair(
                pos[i], ell.rot[i], ell.axes[i], cj, ell.rot[j], ell.axes[j], hist[k, c0 + 1], hist[k, c0 + 2],
                hist[k, c0] != 0.0, work, M, H)
            iters += it
            hist[k, c0] = 1.0
            hist[k, c0 + 1] = li
            hist[k, c0 + 2] = lj
            if not overlap > 0.0:
                if pairs.ovl[k] >= 0.0:
                    _clear(pairs, k, overlap, c0)
                pairs.ovl[k] = overlap
                continue
            mi = sp.mass[i]
            mj = sp.mass[j]
            meff = mi * mj / (mi + mj)
            mb = sp.mat[j]
            rmin = min(ell.amin[i], ell.amin[j])
            vjx = vel[j, 0] + (w[j, 1] * (cz - cj[2]) - w[j, 2] * (cy - cj[1]))
            vjy = vel[j, 1] + (w[j, 2] * (cx - cj[0]) - w[j, 0] * (cz - cj[2]))
            vjz = vel[j, 2] + (w[j, 0] * (cy - cj[1]) - w[j, 1] * (cx - cj[0]))
        else:
            p = j - n
            overlap, nx, ny, nz, cx, cy, cz, re = ellipsoid_plane(
                pos[i], ell.rot[i], ell.axes[i], planes.point[p, 0], planes.point[p, 1], planes.point[p, 2],
                planes.normal[p, 0], planes.normal[p, 1], planes.normal[p, 2])
            if not overlap > 0.0:
                _clear(pairs, k, overlap, c0)
                continue
            meff = sp.mass[i]
            mb = planes.mat[p]
            rmin = ell.amin[i]
            vjx = planes.vel[p, 0]
            vjy = planes.vel[p, 1]
            vjz = planes.vel[p, 2]
        if overlap > max_overlap_ratio * rmin:
            status = BLOWUP_OVERLAP
        rix = cx - pos[i, 0]
        riy = cy - pos[i, 1]
        riz = cz - pos[i, 2]
        vix = vel[i, 0] + (w[i, 1] * riz - w[i, 2] * riy)
        viy = vel[i, 1] + (w[i, 2] * rix - w[i, 0] * riz)
        viz = vel[i, 2] + (w[i, 0] * riy - w[i, 1] * rix)
        vn, vtx, vty, vtz = relative_velocity(vix - vjx, viy - vjy, viz - vjz, nx, ny, nz)
        if not turns:
            rotate_history(hist, k, nx, ny, nz)
        ma = sp.mat[i]
        Fn, Tx, Ty, Tz, sliding, dissipated, row, n_row = law_force3(law, hist, k, ma, mb, meff, re, overlap, vn, vtx,
                                                                     vty, vtz, nx, ny, nz, dt)
        for c in range(n_row):
            hist[k, c] = row[c]
        diss += dissipated
        fx = -Fn * nx + Tx
        fy = -Fn * ny + Ty
        fz = -Fn * nz + Tz
        FM[i, 0] += fx
        FM[i, 1] += fy
        FM[i, 2] += fz
        FM[i, 3] += riy * fz - riz * fy
        FM[i, 4] += riz * fx - rix * fz
        FM[i, 5] += rix * fy - riy * fx
        if j < n:
            rjx = cx - cj[0]
            rjy = cy - cj[1]
            rjz = cz - cj[2]
            FM[j, 0] -= fx
            FM[j, 1] -= fy
            FM[j, 2] -= fz
            FM[j, 3] -= rjy * fz - rjz * fy
            FM[j, 4] -= rjz * fx - rjx * fz
            FM[j, 5] -= rjx * fy - rjy * fx
        else:
            wall = j - n if j < n + nw else tris.wall[j - n - nw]
            planes.force[wall, 0] -= fx
            planes.force[wall, 1] -= fy
            planes.force[wall, 2] -= fz
        pairs.fn[k] = Fn
        pairs.ft[k, 0] = Tx
        pairs.ft[k, 1] = Ty
        pairs.ft[k, 2] = Tz
        pairs.ovl[k] = overlap
        pairs.slide[k] = 1 if sliding else 0
        if recording:
            energy = law_energy3(law, energy, hist, k, ma, mb, re, overlap)
    return status, energy, iters, diss


@njit_inline
def _extent(R, a, dx, dy, dz, dist):
    """Half-width of the ellipsoid along the unit vector d/|d| (its support function):
    √(m_bᵀ A² m_b), m_b = Rᵀ d/|d|."""
    inv = 1.0 / dist
    b0 = (R[0] * dx + R[3] * dy + R[6] * dz) * inv * a[0]
    b1 = (R[1] * dx + R[4] * dy + R[7] * dz) * inv * a[1]
    b2 = (R[2] * dx + R[5] * dy + R[8] * dz) * inv * a[2]
    return math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)


@njit_inline
def _clear(pairs, k, ovl, c0):
    """Pair k is not touching: clear the law's history and the outputs (the warm start is kept)."""
    for c in range(c0):
        pairs.hist[k, c] = 0.0
    pairs.fn[k] = 0.0
    pairs.ft[k, 0] = 0.0
    pairs.ft[k, 1] = 0.0
    pairs.ft[k, 2] = 0.0
    pairs.ovl[k] = ovl
    pairs.slide[k] = 0
