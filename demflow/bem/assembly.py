"""Numba kernels: element integrals, assembly of H and G, interior-point sums (thesis §4.3.4).

Element e runs from a_e to b_e (length L_e, unit tangent τ_e, normal n_e out of the fluid); its
nodes 2e, 2e+1 sit at η = -1/2, +1/2 with N_1 = 1/2 - η, N_2 = 1/2 + η (eq 4.48), and its four
degrees of freedom are ordered (x, y at node 2e; x, y at node 2e+1) = columns 4e..4e+3 (eq 4.46).
A quadrature point is given by its arc length s ∈ [0, L] (η = 2s/L - 1) and a weight that
already contains |J| = L/2 (eq 4.57).

* Regular integrals (source not on the element): Gauss rule by distance (Table 4.1, eq 4.60),
  a fixed n-point rule, or the FINE rule (see :mod:`.quadrature`).
* Singular integrals (source node on its own element, eqs 4.61-4.82): the element is split at η_s;
  each part is mapped to ξ ∈ [0, 1] (eqs 4.62-4.63, 4.71); ln(1/r) = ln(ξ/r) + ln(1/ξ): the smooth
  part by 8-point Gauss (eqs 4.69, 4.73 - whose printed double factor 1/4πμ is a misprint), the
  ln(1/ξ) part by the 8-point logarithmic rule (eqs 4.70, 4.74).  On a straight element ∂r/∂n = 0,
  so the traction-kernel parts (4.81-4.82) vanish identically; they are evaluated anyway.
* c_ij = ½ δ_ij at every (smooth, element-interior) node (eq 4.36) is added to H (eq 4.51).
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..jit import njit, njit_inline, njit_parallel
from .kernels import stress_kernels
from .quadrature import GW, GX, LW, LX, fine_order, order_index, table_4_1

MAXQ = 4096  # quadrature points one element can need (FINE rule at 1e-18 distance: < 2500)


@njit
def point_segment_distance(px, py, ax, ay, tx, ty, L):
    """Distance [m] from P to the segment a + s τ, s ∈ [0, L], and the arc length of its foot."""
    s = (px - ax) * tx + (py - ay) * ty
    s = min(max(s, 0.0), L)
    return math.hypot(ax + s * tx - px, ay + s * ty - py), s


@njit
def _gauss_piece(s0, s1, n, s_out, w_out, m):
    k = order_index(n)
    h = 0.5 * (s1 - s0)
    for l in range(n):
        s_out[m] = s0 + h * (1.0 + GX[k, l])
        w_out[m] = h * GW[k, l]
        m += 1
    return m


@njit
def element_rule(px, py, ax, ay, tx, ty, L, quad, s_out, w_out):
    """Fill (s, w) for integrating over element (a, τ, L) as seen from a source P off the element.
    ``quad``: 0 Table 4.1, -1 FINE, n > 0 fixed n points.  Returns the number of points."""
    d, sp = point_segment_distance(px, py, ax, ay, tx, ty, L)
    rho = d / L
    if quad > 0:
        return _gauss_piece(0.0, L, quad, s_out, w_out, 0)
    if quad == 0:
        return _gauss_piece(0.0, L, table_4_1(rho), s_out, w_out, 0)
    if rho >= 1.0:
        return _gauss_piece(0.0, L, fine_order(rho), s_out, w_out, 0)
    # FINE: pieces graded geometrically away from the foot sp, each at least its length from P
    m = 0
    dd = max(d, 1e-300)
    pos = sp
    while pos < L and m < MAXQ - 16:
        step = max(dd, pos - sp)
        end = min(pos + step, L)
        dist = max(dd, pos - sp)
        m = _gauss_piece(pos, end, fine_order(dist / (end - pos)), s_out, w_out, m)
        pos = end
    pos = sp
    while pos > 0.0 and m < MAXQ - 16:
        step = max(dd, sp - pos)
        end = max(pos - step, 0.0)
        dist = max(dd, sp - pos)
        m = _gauss_piece(end, pos, fine_order(dist / (pos - end)), s_out, w_out, m)
        pos = end
    return m


@njit
def regular_blocks(px, py, ax, ay, tx, ty, nx, ny, L, mu, s, w, m, G, H):
    """Add ∫ u* N dΓ to G (2×4) and ∫ t* N dΓ to H (2×4) (eq 4.50) over the m points (s, w)."""
    c = 1.0 / (4.0 * math.pi * mu)
    for q in range(m):
        rx = ax + s[q] * tx - px
        ry = ay + s[q] * ty - py
        r = math.hypot(rx, ry)
        ex, ey = rx / r, ry / r
        lg = -math.log(r)
        u11, u12, u22 = c * (lg + ex * ex), c * ex * ey, c * (lg + ey * ey)
        ct = -(ex * nx + ey * ny) / (math.pi * r)
        t11, t12, t22 = ct * ex * ex, ct * ex * ey, ct * ey * ey
        eta = 2.0 * s[q] / L - 1.0
        for a in range(2):
            Nw = (0.5 - eta if a == 0 else 0.5 + eta) * w[q]
            G[0, 2 * a] += u11 * Nw
            G[0, 2 * a + 1] += u12 * Nw
            G[1, 2 * a] += u12 * Nw
            G[1, 2 * a + 1] += u22 * Nw
            H[0, 2 * a] += t11 * Nw
            H[0, 2 * a + 1] += t12 * Nw
            H[1, 2 * a] += t12 * Nw
            H[1, 2 * a + 1] += t22 * Nw


@njit
def singular_blocks(node, ax, ay, tx, ty, nx, ny, L, mu, G, H):
    """Self-element integrals for the source at the element's own node 0 (η_s = -1/2) or 1
    (η_s = +1/2): thesis eqs 4.61-4.82."""
    eta_s = -0.5 if node == 0 else 0.5
    c = 1.0 / (4.0 * math.pi * mu)
    J = 0.5 * L
    px = ax + (eta_s + 1.0) * J * tx
    py = ay + (eta_s + 1.0) * J * ty
    kg = order_index(8)
    for side in range(2):
        span = (1.0 + eta_s) if side == 0 else (1.0 - eta_s)  # (1 ± η_s), eqs 4.64, 4.71
        sgn = -1.0 if side == 0 else 1.0
        # smooth part: [ln(ξ/r) δ + r̂ r̂] and the traction kernel, Gauss on ξ ∈ [0, 1] (4.69, 4.73, 4.81-4.82)
        for l in range(8):
            xi = 0.5 * (1.0 + GX[kg, l])
            wq = 0.5 * GW[kg, l] * J * span
            eta = eta_s + sgn * span * xi
            rx = ax + (eta + 1.0) * J * tx - px
            ry = ay + (eta + 1.0) * J * ty - py
            r = math.hypot(rx, ry)
            ex, ey = rx / r, ry / r
            lg = math.log(xi / r)
            u11, u12, u22 = c * (lg + ex * ex), c * ex * ey, c * (lg + ey * ey)
            ct = -(ex * nx + ey * ny) / (math.pi * r)
            for a in range(2):
                Nw = (0.5 - eta if a == 0 else 0.5 + eta) * wq
                G[0, 2 * a] += u11 * Nw
                G[0, 2 * a + 1] += u12 * Nw
                G[1, 2 * a] += u12 * Nw
                G[1, 2 * a + 1] += u22 * Nw
                H[0, 2 * a] += ct * ex * ex * Nw
                H[0, 2 * a + 1] += ct * ex * ey * Nw
                H[1, 2 * a] += ct * ex * ey * Nw
                H[1, 2 * a + 1] += ct * ey * ey * Nw
        # ln(1/ξ) δ_ij part: logarithmic quadrature (4.70, 4.74)
        for l in range(LX.shape[0]):
            eta = eta_s + sgn * span * LX[l]
            wq = LW[l] * J * span * c
            for a in range(2):
                Nw = (0.5 - eta if a == 0 else 0.5 + eta) * wq
                G[0, 2 * a] += Nw
                G[1, 2 * a + 1] += Nw


@njit
def _row_blocks(i, e, nodes, a, t, nrm, L, quad, mu, s, w, G, H):
    G[:, :] = 0.0
    H[:, :] = 0.0
    if i // 2 == e:
        singular_blocks(i % 2, a[e, 0], a[e, 1], t[e, 0], t[e, 1], nrm[e, 0], nrm[e, 1], L[e], mu, G, H)
    else:
        px, py = nodes[i, 0], nodes[i, 1]
        m = element_rule(px, py, a[e, 0], a[e, 1], t[e, 0], t[e, 1], L[e], quad, s, w)
        regular_blocks(px, py, a[e, 0], a[e, 1], t[e, 0], t[e, 1], nrm[e, 0], nrm[e, 1], L[e], mu, s, w, m, G, H)


@njit_inline
def _row_scratch():
    """Per-row work arrays of the assembly loops: quadrature points and weights, the G and H blocks."""
    return np.empty(MAXQ), np.empty(MAXQ), np.empty((2, 4)), np.empty((2, 4))


@njit_parallel
def assemble_HG(nodes, a, t, nrm, L, quad, mu):
    """[H] and [G] of thesis eq 4.53 (2N_n × 2N_n), with c_ij = ½δ_ij in H (eq 4.51)."""
    nn = nodes.shape[0]
    ne = a.shape[0]
    Hm = np.zeros((2 * nn, 2 * nn))
    Gm = np.zeros((2 * nn, 2 * nn))
    for i in prange(nn):
        s, w, G, H = _row_scratch()
        for e in range(ne):
            _row_blocks(i, e, nodes, a, t, nrm, L, quad, mu, s, w, G, H)
            Hm[2 * i:2 * i + 2, 4 * e:4 * e + 4] = H
            Gm[2 * i:2 * i + 2, 4 * e:4 * e + 4] = G
        Hm[2 * i, 2 * i] += 0.5
        Hm[2 * i + 1, 2 * i + 1] += 0.5
    return Hm, Gm


@njit_parallel
def assemble_system(nodes, a, t, nrm, L, quad, mu, traction_given, value):
    """[A] Y = R of thesis eq 4.55 assembled directly (H and G never stored).

    ``traction_given[dof]`` is False where the velocity is prescribed (Y holds the traction) and
    True where the traction is (Y holds the velocity); ``value[dof]`` is the prescribed value.
    """
    nn = nodes.shape[0]
    ne = a.shape[0]
    A = np.zeros((2 * nn, 2 * nn))
    R = np.zeros(2 * nn)
    for i in prange(nn):
        s, w, G, H = _row_scratch()
        for e in range(ne):
            _row_blocks(i, e, nodes, a, t, nrm, L, quad, mu, s, w, G, H)
            if e == i // 2:
                H[0, 2 * (i % 2)] += 0.5
                H[1, 2 * (i % 2) + 1] += 0.5
            for r in range(2):
                row = 2 * i + r
                acc = 0.0
                for c in range(4):
                    col = 4 * e + c
                    if traction_given[col]:
                        A[row, col] = H[r, c]
                        acc += G[r, c] * value[col]
                    else:
                        A[row, col] = -G[r, c]
                        acc -= H[r, c] * value[col]
                R[row] += acc
    return A, R


@njit_parallel
def interior_fields(pts, a, t, nrm, L, quad, mu, U, T, printed):
    """Velocity (eq 4.92) and stress (eq 4.93 with D, S of eqs 4.94-4.95) at interior points.

    ``U``, ``T``: nodal velocity [m/s] and traction [Pa], shape (2N_n,).  Returns u (P, 2) and
    σ (P, 3) = (σ_xx, σ_xy, σ_yy) [Pa].  ``printed``: -1 velocity only (σ left 0), 0 stress by the
    corrected eq 4.95, 1 by the misprinted one (tests only).
    """
    npt = pts.shape[0]
    ne = a.shape[0]
    uo = np.zeros((npt, 2))
    so = np.zeros((npt, 3))
    c = 1.0 / (4.0 * math.pi * mu)
    with_stress = printed >= 0
    for p in prange(npt):
        s = np.empty(MAXQ)
        w = np.empty(MAXQ)
        px, py = pts[p, 0], pts[p, 1]
        for e in range(ne):
            m = element_rule(px, py, a[e, 0], a[e, 1], t[e, 0], t[e, 1], L[e], quad, s, w)
            for q in range(m):
                eta = 2.0 * s[q] / L[e] - 1.0
                N1, N2 = 0.5 - eta, 0.5 + eta
                tx = N1 * T[4 * e] + N2 * T[4 * e + 2]
                ty = N1 * T[4 * e + 1] + N2 * T[4 * e + 3]
                ux = N1 * U[4 * e] + N2 * U[4 * e + 2]
                uy = N1 * U[4 * e + 1] + N2 * U[4 * e + 3]
                rx = a[e, 0] + s[q] * t[e, 0] - px
                ry = a[e, 1] + s[q] * t[e, 1] - py
                r = math.hypot(rx, ry)
                ex, ey = rx / r, ry / r
                lg = -math.log(r)
                ct = -(ex * nrm[e, 0] + ey * nrm[e, 1]) / (math.pi * r)
                uo[p, 0] += w[q] * (c * ((lg + ex * ex) * tx + ex * ey * ty) - ct * ex * (ex * ux + ey * uy))
                uo[p, 1] += w[q] * (c * (ex * ey * tx + (lg + ey * ey) * ty) - ct * ey * (ex * ux + ey * uy))
                if not with_stress:
                    continue
                D, S = stress_kernels(rx, ry, nrm[e, 0], nrm[e, 1], mu, printed == 1)
                tv = (tx, ty)
                uv = (ux, uy)
                for k in range(2):
                    so[p, 0] += w[q] * (D[k, 0, 0] * tv[k] - S[k, 0, 0] * uv[k])
                    so[p, 1] += w[q] * (D[k, 0, 1] * tv[k] - S[k, 0, 1] * uv[k])
                    so[p, 2] += w[q] * (D[k, 1, 1] * tv[k] - S[k, 1, 1] * uv[k])
    return uo, so


@njit
def pressure_coefficients(px, py, a, t, nrm, L, mu):
    """Coefficients of the represented pressure p(P) = -½ σ_ii(P) = cT·T + cU·U (eqs 4.93-4.96)
    at a point P off the boundary (FINE rule).  Used to fix the pressure level inside holes."""
    ne = a.shape[0]
    cT = np.zeros(4 * ne)
    cU = np.zeros(4 * ne)
    s = np.empty(MAXQ)
    w = np.empty(MAXQ)
    for e in range(ne):
        m = element_rule(px, py, a[e, 0], a[e, 1], t[e, 0], t[e, 1], L[e], -1, s, w)
        for q in range(m):
            eta = 2.0 * s[q] / L[e] - 1.0
            rx = a[e, 0] + s[q] * t[e, 0] - px
            ry = a[e, 1] + s[q] * t[e, 1] - py
            D, S = stress_kernels(rx, ry, nrm[e, 0], nrm[e, 1], mu, False)
            for nd in range(2):
                N = (0.5 - eta if nd == 0 else 0.5 + eta) * w[q]
                for k in range(2):
                    cT[4 * e + 2 * nd + k] += -0.5 * (D[k, 0, 0] + D[k, 1, 1]) * N
                    cU[4 * e + 2 * nd + k] += 0.5 * (S[k, 0, 0] + S[k, 1, 1]) * N
    return cT, cU
