"""Ellipsoid geometry: mass properties, the Lin & Ng geometric-potential contact, ellipsoid-plane and
ellipsoid-triangle contact (Miyata §2.4, eqs 43-59).

An ellipsoid has semi-axes (a1, a2, a3) [length] along its body axes; its geometric potential is
f(x) = (x1/a1)² + (x2/a2)² + (x3/a3)² - 1 in body coordinates (Miyata eqs 43-44): < 0 inside,
0 on the surface.  Orientation: a rotation matrix R (body -> world) stored row-major as 9 numbers.

Ellipsoid-ellipsoid contact (Lin & Ng 1995, 1997 as Miyata §2.4(1) describes it).  P_i is the point
of i's surface where j's potential is smallest (the point of i deepest inside j), P_j likewise with
the roles swapped (Miyata Fig. 20).  Writing i's surface as x = c_i + R_i A_i u, |u| = 1
(A = diag(a)), j's potential is |M u + b|² - 1 with M = A_j⁻¹ R_jᵀ R_i A_i and
b = A_j⁻¹ R_jᵀ (c_i - c_j), so P_i solves min uᵀHu + 2gᵀu on |u| = 1 with H = MᵀM, g = Mᵀb: the
trust-region sub-problem.  Its global minimiser is u = -(H - λI)⁻¹ g with λ < h_min (the smallest
eigenvalue of H) the root of the secular equation |(H - λI)⁻¹ g| = 1 (Moré & Sorensen 1983).
How it is solved (:func:`potential_point`):

1. Newton on ψ(λ) = 1/|s(λ)| - 1 (s = -(H - λI)⁻¹ g by a 3×3 Cholesky factorisation), started
   from the contact's λ of the last step (the warm start: λ fixes the last contact point) or,
   cold, from the left end of the bracket; every iterate is kept inside the bracket
   [-|g|, min Hₖₖ] (at -|g|, |s| ≤ 1; past h_min the Cholesky fails), replaced by the bracket's
   midpoint when Newton would leave it (safeguarded Newton, at most ``NEWTON_MAX`` steps).
2. Fallback (not converged, or the "hard case" g ⊥ lowest eigenvector, which needs a centre deep
   inside the other body): eigen-decomposition of H and bisection of the secular equation
   Σ g'ₖ²/(hₖ - λ)² = 1 in the bracket [h₀ - |g|, h₀ - |g'₀|]; in the hard case u takes the
   component along the lowest eigenvector that makes it a unit vector.

From P_i, P_j: the outward surface normals n_i at P_i and n_j at P_j (by the Lagrange condition
they are parallel to the other body's potential gradient there), the contact normal
n = (n_i - n_j)/|n_i - n_j| (from i to j), the overlap δ = (P_i - P_j)·n (< 0: a gap), the contact
point (P_i + P_j)/2.  For spheres P_i = c_i + R_i n, P_j = c_j - R_j n and these are the sphere
code's n, δ = R_i + R_j - |d| and contact point.

Contact curvature (Miyata eqs 45-48, Johnson 1985 §4.1).  The gap between the two surfaces near
the contact is h = A u² + B v² (eq 45) with A, B the eigenvalues of S = (K_i + K_j)/2, K the
surfaces' curvature tensors (second fundamental forms) in the common tangent plane; tr S is eq 46a
and the eigenvalue difference eq 46b.  The equivalent radius is R_e = 1/(2√(AB)) = √(R'R'')
(Johnson eq 4.20, with A = 1/2R', B = 1/2R''): this is Hertz's R* = R_iR_j/(R_i + R_j) for
spheres.  Miyata's eq 48 prints R_e = 1/√(AB), which with the A, B of eq 46 is 2R* for spheres
(a factor √2 on the Hertz force of eq 47); we keep Johnson's form so that the sphere limit is
exact, and take ψ(B/A) = 1 as Miyata does.  An ellipsoid's curvature tensor at a surface point x
(body frame) is Rᵀ-rotated D/|Dx| restricted to the tangent plane, D = A⁻², the Hessian of f over
the length of its gradient (Lipschutz 1969's principal radii are its inverse eigenvalues).

Ellipsoid-plane (eqs 50-55): the point of the ellipsoid farthest along -n (n the plane's unit
normal towards the ellipsoid) is x_p = -A² n_b / √(n_bᵀ A² n_b) in body coordinates (eq 54 with
λ fixed by f = 0), n_b = Rᵀ n; the overlap is √(n_bᵀ A² n_b) - (c - p₀)·n.  Curvature: K of the
ellipsoid alone, R_e = 1/√(det K) = √(R'R'').

Ellipsoid-triangle (eqs 55-59): the plane of the triangle as above gives the support point P and
its projection Q (eq 56); Q's triangle coordinates (L_I, L_J, L_K) (eqs 57-59) all > 0 make a
FACE contact.  Otherwise the ellipsoid can only touch an edge or a vertex (when it reaches the
plane at all): for each edge, the line's penetration is the distance from the line's shadow point
q to the boundary of the ellipsoid's shadow (an ellipse) on the plane normal to the edge (the
smallest translation that clears the line); the ellipsoid's silhouette point above that boundary
point projects onto the line at a parameter τ: inside the edge an EDGE contact, beyond an end a
VERTEX contact of that end (distance from the vertex to the ellipsoid's surface).  The deepest of
the three edges is the triangle's contact.  On a shared edge of a flat mesh the EDGE overlap equals
the FACE overlap of the plane (the support point is a stationary point of both distances), so the
force is continuous as Q crosses it; the face/edge/vertex dedup is the sphere code's
(:func:`demflow.contacts.spheres.triangle_contacts`).
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import njit, njit_inline

FACE = 0
EDGE = 1
VERTEX = 2

NEWTON_MAX = 30  # safeguarded Newton steps before the eigen/bisection fallback
SECULAR_TOL = 1e-14  # | |s| - 1 | accepted by Newton (a unit vector to round-off)
NEWTON_LAST = 1e-7  # below this | |s| - 1 | the last Newton step reuses the factorisation: s(λ + d) = s + d K⁻¹s,
                    # truncation O((d/(h - λ))²) ≈ 1e-14


# --------------------------------------------------------------------------- mass properties
def ellipsoid_mass_properties(axes, density: float) -> tuple[float, np.ndarray]:
    """Mass 4/3 π a1 a2 a3 ρ [mass] and principal moments m(a2² + a3²)/5, m(a1² + a3²)/5,
    m(a1² + a2²)/5 [mass·length²] of a solid ellipsoid (closed form)."""
    a1, a2, a3 = (float(v) for v in axes)
    m = 4.0 / 3.0 * math.pi * a1 * a2 * a3 * float(density)
    return m, m / 5.0 * np.array([a2 * a2 + a3 * a3, a1 * a1 + a3 * a3, a1 * a1 + a2 * a2])


@njit_inline
def quat_rotation(q, out):
    """Row-major rotation matrix (9,) of the unit quaternion q = (w, x, y, z): body -> world."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    out[0] = 1.0 - 2.0 * (y * y + z * z)
    out[1] = 2.0 * (x * y - w * z)
    out[2] = 2.0 * (x * z + w * y)
    out[3] = 2.0 * (x * y + w * z)
    out[4] = 1.0 - 2.0 * (x * x + z * z)
    out[5] = 2.0 * (y * z - w * x)
    out[6] = 2.0 * (x * z - w * y)
    out[7] = 2.0 * (y * z + w * x)
    out[8] = 1.0 - 2.0 * (x * x + y * y)


@njit
def rotations(quat, rot):
    """rot[i] = the row-major rotation matrix of quat[i] (n, 4) -> (n, 9)."""
    for i in range(quat.shape[0]):
        quat_rotation(quat[i], rot[i])


# --------------------------------------------------------------------------- the potential point
@njit_inline
def _cholesky_solve(H, g, lam, s, w, z):
    """Factor K = H - λI = LLᵀ; s = -K⁻¹g, w = L⁻¹s, z = K⁻¹s.  Returns False when K is not positive
    definite (λ ≥ h_min)."""
    k00 = H[0, 0] - lam
    if not k00 > 0.0:
        return False
    # three square roots and three divisions (the inverse diagonal), then products only
    i00 = 1.0 / math.sqrt(k00)
    l10 = H[1, 0] * i00
    l20 = H[2, 0] * i00
    k11 = H[1, 1] - lam - l10 * l10
    if not k11 > 0.0:
        return False
    i11 = 1.0 / math.sqrt(k11)
    l21 = (H[2, 1] - l20 * l10) * i11
    k22 = H[2, 2] - lam - l20 * l20 - l21 * l21
    if not k22 > 0.0:
        return False
    i22 = 1.0 / math.sqrt(k22)
    # L y = -g
    y0 = -g[0] * i00
    y1 = (-g[1] - l10 * y0) * i11
    y2 = (-g[2] - l20 * y0 - l21 * y1) * i22
    # Lᵀ s = y
    s[2] = y2 * i22
    s[1] = (y1 - l21 * s[2]) * i11
    s[0] = (y0 - l10 * s[1] - l20 * s[2]) * i00
    # L w = s
    w[0] = s[0] * i00
    w[1] = (s[1] - l10 * w[0]) * i11
    w[2] = (s[2] - l20 * w[0] - l21 * w[1]) * i22
    # Lᵀ z = w
    z[2] = w[2] * i22
    z[1] = (w[1] - l21 * z[2]) * i11
    z[0] = (w[0] - l10 * z[1] - l20 * z[2]) * i00
    return True


@njit
def _secular_fallback(H, g, u):
    """Eigen-decomposition of H and bisection of Σ g'ₖ²/(hₖ - λ)² = 1 on λ < h₀ (the bracketing
    fallback, hard case included).  Writes u, returns λ."""
    h, Q = np.linalg.eigh(H)
    gp = np.empty(3)
    for k in range(3):
        gp[k] = Q[0, k] * g[0] + Q[1, k] * g[1] + Q[2, k] * g[2]
    gn = math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    scale = abs(h[2]) + gn
    if abs(gp[0]) <= 1e-13 * scale:
        # hard case candidate: λ = h₀ if the rest of s is shorter than 1
        s2 = 0.0
        sp = np.zeros(3)
        for k in range(1, 3):
            d = h[k] - h[0]
            if d > 1e-13 * scale:
                sp[k] = -gp[k] / d
                s2 += sp[k] * sp[k]
        if s2 <= 1.0:
            sp[0] = math.sqrt(1.0 - s2)
            for a in range(3):
                u[a] = Q[a, 0] * sp[0] + Q[a, 1] * sp[1] + Q[a, 2] * sp[2]
            return h[0]
    lo = h[0] - gn
    hi = h[0] - abs(gp[0])
    lam = 0.5 * (lo + hi)
    for _ in range(200):
        lam = 0.5 * (lo + hi)
        if lam <= lo or lam >= hi:
            break
        phi = 0.0
        for k in range(3):
            phi += (gp[k] / (h[k] - lam)) ** 2
        if phi < 1.0:
            lo = lam
        else:
            hi = lam
    sp = np.empty(3)
    nrm = 0.0
    for k in range(3):
        sp[k] = -gp[k] / (h[k] - lam)
        nrm += sp[k] * sp[k]
    nrm = math.sqrt(nrm)
    for a in range(3):
        u[a] = (Q[a, 0] * sp[0] + Q[a, 1] * sp[1] + Q[a, 2] * sp[2]) / nrm
    return lam


@njit_inline
def potential_point(H, g, lam0, warm, u, s, w, z):
    """The global minimiser u (|u| = 1, written into ``u``) of uᵀHu + 2gᵀu, H symmetric positive
    definite (3, 3), g (3,): safeguarded Newton on the secular equation from λ0 (``warm``) or from
    the bracket's left end, then the eigen/bisection fallback (module docstring).  Close to the root
    (| |s| - 1 | ≤ NEWTON_LAST) the last Newton step reuses the factorisation (s + d K⁻¹s, exact to
    ~1e-14; a warm start then needs one factorisation).  ``s``, ``w``, ``z`` are (3,) work arrays.
    Returns (λ, factorisations; NEWTON_MAX + 1 when the fallback ran)."""
    gn = math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    lo = -gn
    hi = min(H[0, 0], min(H[1, 1], H[2, 2]))
    lam = lam0 if (warm and lo < lam0 < hi) else lo
    if gn > 0.0:
        for it in range(NEWTON_MAX):
            if _cholesky_solve(H, g, lam, s, w, z):
                sn = math.sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2])
                if abs(sn - 1.0) <= SECULAR_TOL:
                    isn = 1.0 / sn
                    for a in range(3):
                        u[a] = s[a] * isn
                    return lam, it + 1
                if sn < 1.0:
                    lo = lam
                else:
                    hi = lam
                wn2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
                d = sn * sn * (1.0 - sn) / wn2
                new = lam + d
                if abs(sn - 1.0) <= NEWTON_LAST and lo < new < hi:
                    u0 = s[0] + d * z[0]
                    u1 = s[1] + d * z[1]
                    u2 = s[2] + d * z[2]
                    iun = 1.0 / math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
                    u[0] = u0 * iun
                    u[1] = u1 * iun
                    u[2] = u2 * iun
                    return new, it + 1
            else:
                hi = lam
                new = hi  # force a bisection
            if not (lo < new < hi):
                new = 0.5 * (lo + hi)
            if new == lam:
                break
            lam = new
    lam = _secular_fallback(H, g, u)
    return lam, NEWTON_MAX + 1


@njit_inline
def _potential_problem(ci, Ri, ai, cj, Rj, aj, H, g, M):
    """H = MᵀM, g = Mᵀb of the point of i's surface minimising j's potential:
    M = A_j⁻¹ R_jᵀ R_i A_i, b = A_j⁻¹ R_jᵀ (c_i - c_j).  R row-major (9,)."""
    for r in range(3):
        ia = 1.0 / aj[r]
        for c in range(3):
            # (R_jᵀ R_i)[r, c] = Σ_k R_j[k, r] R_i[k, c]
            v = Rj[r] * Ri[c] + Rj[3 + r] * Ri[3 + c] + Rj[6 + r] * Ri[6 + c]
            M[r, c] = v * ai[c] * ia
    dx = ci[0] - cj[0]
    dy = ci[1] - cj[1]
    dz = ci[2] - cj[2]
    b0 = (Rj[0] * dx + Rj[3] * dy + Rj[6] * dz) / aj[0]
    b1 = (Rj[1] * dx + Rj[4] * dy + Rj[7] * dz) / aj[1]
    b2 = (Rj[2] * dx + Rj[5] * dy + Rj[8] * dz) / aj[2]
    for r in range(3):
        for c in range(r, 3):
            v = M[0, r] * M[0, c] + M[1, r] * M[1, c] + M[2, r] * M[2, c]
            H[r, c] = v
            H[c, r] = v
        g[r] = M[0, r] * b0 + M[1, r] * b1 + M[2, r] * b2


@njit_inline
def _surface(c, R, a, u):
    """World point c + R A u and the outward unit normal there, R (A⁻¹u)/|A⁻¹u|."""
    x0 = a[0] * u[0]
    x1 = a[1] * u[1]
    x2 = a[2] * u[2]
    px = c[0] + R[0] * x0 + R[1] * x1 + R[2] * x2
    py = c[1] + R[3] * x0 + R[4] * x1 + R[5] * x2
    pz = c[2] + R[6] * x0 + R[7] * x1 + R[8] * x2
    g0 = u[0] / a[0]
    g1 = u[1] / a[1]
    g2 = u[2] / a[2]
    nx = R[0] * g0 + R[1] * g1 + R[2] * g2
    ny = R[3] * g0 + R[4] * g1 + R[5] * g2
    nz = R[6] * g0 + R[7] * g1 + R[8] * g2
    inn = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    return px, py, pz, nx * inn, ny * inn, nz * inn


@njit_inline
def curvature_form(R, a, u, t1x, t1y, t1z, t2x, t2y, t2z):
    """The ellipsoid's curvature tensor at its surface point A u (body frame) in the tangent basis
    (t1, t2) (world vectors): K_ab = (Rᵀt_a)ᵀ D (Rᵀt_b) / |D A u|, D = A⁻² (the Hessian of f over
    its gradient's length).  Returns (K11, K12, K22) [1/length]."""
    gl = math.sqrt((u[0] / a[0]) ** 2 + (u[1] / a[1]) ** 2 + (u[2] / a[2]) ** 2)
    k11 = 0.0
    k12 = 0.0
    k22 = 0.0
    for r in range(3):
        b1 = R[r] * t1x + R[3 + r] * t1y + R[6 + r] * t1z  # (Rᵀ t1)_r
        b2 = R[r] * t2x + R[3 + r] * t2y + R[6 + r] * t2z
        d = 1.0 / (a[r] * a[r])
        k11 += b1 * b1 * d
        k12 += b1 * b2 * d
        k22 += b2 * b2 * d
    igl = 1.0 / gl
    return k11 * igl, k12 * igl, k22 * igl


@njit_inline
def tangent_basis(nx, ny, nz):
    """Two unit vectors completing n to a right-handed orthonormal basis."""
    ax, ay, az = abs(nx), abs(ny), abs(nz)
    if ax <= ay and ax <= az:  # t1 = n × e_x normalised
        t1x, t1y, t1z = 0.0, nz, -ny
    elif ay <= az:
        t1x, t1y, t1z = -nz, 0.0, nx
    else:
        t1x, t1y, t1z = ny, -nx, 0.0
    itn = 1.0 / math.sqrt(t1x * t1x + t1y * t1y + t1z * t1z)
    t1x *= itn
    t1y *= itn
    t1z *= itn
    return t1x, t1y, t1z, ny * t1z - nz * t1y, nz * t1x - nx * t1z, nx * t1y - ny * t1x


@njit_inline
def equivalent_radius(k11, k12, k22):
    """R_e = 1/(2√(AB)) with A, B the eigenvalues of S = (K11 K12; K12 K22) (module docstring;
    Johnson eq 4.20 for Miyata's eqs 45-48)."""
    det = k11 * k22 - k12 * k12
    return 0.5 / math.sqrt(det) if det > 0.0 else math.inf


@njit_inline
def ellipsoid_pair(ci, Ri, ai, cj, Rj, aj, lam_i, lam_j, warm, work, M, H):
    """Lin & Ng contact of ellipsoids i and j (module docstring).

    ci, cj (3,) centres [length] (j's image), Ri, Rj (9,) rotations, ai, aj (3,) semi-axes; lam_i,
    lam_j the last step's multipliers (used when ``warm``); work (6, 3), M, H (3, 3) scratch.
    Returns (overlap δ (< 0: gap), nx, ny, nz (from i to j), contact point x, y, z, R_e, λ_i, λ_j,
    Newton iterations i + j)."""
    u = work[0]
    s = work[1]
    w = work[2]
    g = work[3]
    v = work[4]
    z = work[5]
    _potential_problem(ci, Ri, ai, cj, Rj, aj, H, g, M)
    li, iti = potential_point(H, g, lam_i, warm, u, s, w, z)
    _potential_problem(cj, Rj, aj, ci, Ri, ai, H, g, M)
    lj, itj = potential_point(H, g, lam_j, warm, v, s, w, z)
    pix, piy, piz, nix, niy, niz = _surface(ci, Ri, ai, u)
    pjx, pjy, pjz, njx, njy, njz = _surface(cj, Rj, aj, v)
    nx = nix - njx
    ny = niy - njy
    nz = niz - njz
    inn = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    nx *= inn
    ny *= inn
    nz *= inn
    overlap = (pix - pjx) * nx + (piy - pjy) * ny + (piz - pjz) * nz
    t1x, t1y, t1z, t2x, t2y, t2z = tangent_basis(nx, ny, nz)
    a11, a12, a22 = curvature_form(Ri, ai, u, t1x, t1y, t1z, t2x, t2y, t2z)
    b11, b12, b22 = curvature_form(Rj, aj, v, t1x, t1y, t1z, t2x, t2y, t2z)
    re = equivalent_radius(0.5 * (a11 + b11), 0.5 * (a12 + b12), 0.5 * (a22 + b22))
    return (overlap, nx, ny, nz, 0.5 * (pix + pjx), 0.5 * (piy + pjy), 0.5 * (piz + pjz), re, li, lj,
            iti + itj)


@njit_inline
def _support(c, R, a, mx, my, mz):
    """The ellipsoid's farthest point along -m (m a world unit vector) and its extent
    √(m_bᵀA²m_b) (Miyata eq 54); returns (px, py, pz, extent, body point x (3 values))."""
    b0 = R[0] * mx + R[3] * my + R[6] * mz
    b1 = R[1] * mx + R[4] * my + R[7] * mz
    b2 = R[2] * mx + R[5] * my + R[8] * mz
    e = math.sqrt((a[0] * b0) ** 2 + (a[1] * b1) ** 2 + (a[2] * b2) ** 2)
    x0 = -a[0] * a[0] * b0 / e
    x1 = -a[1] * a[1] * b1 / e
    x2 = -a[2] * a[2] * b2 / e
    px = c[0] + R[0] * x0 + R[1] * x1 + R[2] * x2
    py = c[1] + R[3] * x0 + R[4] * x1 + R[5] * x2
    pz = c[2] + R[6] * x0 + R[7] * x1 + R[8] * x2
    return px, py, pz, e, x0, x1, x2


@njit_inline
def _radius_at(R, a, x0, x1, x2, nx, ny, nz):
    """R_e = 1/√(det K) of the ellipsoid alone at its body point x, n the contact normal."""
    u = (x0 / a[0], x1 / a[1], x2 / a[2])  # a tuple: no allocation per plane contact
    t1x, t1y, t1z, t2x, t2y, t2z = tangent_basis(nx, ny, nz)
    k11, k12, k22 = curvature_form(R, a, u, t1x, t1y, t1z, t2x, t2y, t2z)
    return equivalent_radius(0.5 * k11, 0.5 * k12, 0.5 * k22)


@njit_inline
def ellipsoid_plane(c, R, a, px0, py0, pz0, mx, my, mz):
    """Ellipsoid against the plane through p0 with unit normal m towards the ellipsoid (Miyata eqs
    50-55).  Returns (overlap, nx, ny, nz (from the ellipsoid to the plane: -m), contact point
    (mid-overlap), R_e)."""
    px, py, pz, e, x0, x1, x2 = _support(c, R, a, mx, my, mz)
    h = (c[0] - px0) * mx + (c[1] - py0) * my + (c[2] - pz0) * mz
    overlap = e - h
    re = _radius_at(R, a, x0, x1, x2, -mx, -my, -mz)
    return (overlap, -mx, -my, -mz, px + 0.5 * overlap * mx, py + 0.5 * overlap * my, pz + 0.5 * overlap * mz, re)


@njit
def _nearest_boundary(d, q, dim, out):
    """Nearest point ``out`` of the boundary Σ d_k y_k² = 1 (d > 0, ``dim`` = 2 or 3 entries) to the
    interior point q (Σ d_k q_k² < 1): y_k = q_k/(1 + t d_k), t ∈ (-1/d_max, 0] the root of
    Σ d_k q_k²/(1 + t d_k)² = 1 (decreasing in t; Eberly), by safeguarded Newton with bisection.
    Returns the distance |y - q|."""
    dmax = d[0]
    for k in range(1, dim):
        dmax = max(dmax, d[k])
    lo = -1.0 / dmax
    hi = 0.0
    t = 0.0
    for _ in range(200):
        G = -1.0
        dG = 0.0
        for k in range(dim):
            den = 1.0 + t * d[k]
            G += d[k] * q[k] * q[k] / (den * den)
            dG -= 2.0 * d[k] * d[k] * q[k] * q[k] / (den * den * den)
        if G > 0.0:
            lo = t
        else:
            hi = t
        if abs(G) <= 1e-15:
            break
        new = t - G / dG if dG < 0.0 else 0.5 * (lo + hi)
        if not (lo < new < hi):
            new = 0.5 * (lo + hi)
        if new == t:
            break
        t = new
    dist2 = 0.0
    for k in range(dim):
        out[k] = q[k] / (1.0 + t * d[k])
        dist2 += (out[k] - q[k]) ** 2
    return math.sqrt(dist2)


@njit
def ellipsoid_vertex(c, R, a, vx, vy, vz):
    """Ellipsoid against a point: (overlap = distance from the point to the surface when inside,
    else ≤ 0, n = outward normal at the nearest surface point, contact point, body point (3))."""
    dx = vx - c[0]
    dy = vy - c[1]
    dz = vz - c[2]
    q = np.empty(3)
    q[0] = R[0] * dx + R[3] * dy + R[6] * dz
    q[1] = R[1] * dx + R[4] * dy + R[7] * dz
    q[2] = R[2] * dx + R[5] * dy + R[8] * dz
    d = np.empty(3)
    f = -1.0
    for k in range(3):
        d[k] = 1.0 / (a[k] * a[k])
        f += d[k] * q[k] * q[k]
    if f >= 0.0:
        return -1.0, 0.0, 0.0, 1.0, vx, vy, vz, 0.0, 0.0, 0.0
    y = np.empty(3)
    dist = _nearest_boundary(d, q, 3, y)
    g0 = y[0] * d[0]
    g1 = y[1] * d[1]
    g2 = y[2] * d[2]
    nx = R[0] * g0 + R[1] * g1 + R[2] * g2
    ny = R[3] * g0 + R[4] * g1 + R[5] * g2
    nz = R[6] * g0 + R[7] * g1 + R[8] * g2
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    nx /= nn
    ny /= nn
    nz /= nn
    return dist, nx, ny, nz, vx + 0.5 * dist * nx, vy + 0.5 * dist * ny, vz + 0.5 * dist * nz, y[0], y[1], y[2]


@njit
def ellipsoid_edge(c, R, a, v0x, v0y, v0z, v1x, v1y, v1z):
    """Ellipsoid against the segment v0-v1 (module docstring): the line's penetration in the plane
    normal to it.  Returns (overlap, nx, ny, nz, contact point, region EDGE or VERTEX, body point
    (3)); overlap ≤ 0 when the line misses the ellipsoid."""
    ex = v1x - v0x
    ey = v1y - v0y
    ez = v1z - v0z
    L = math.sqrt(ex * ex + ey * ey + ez * ez)
    ex /= L
    ey /= L
    ez /= L
    # body frame: the line through y0 with direction e
    dx = v0x - c[0]
    dy = v0y - c[1]
    dz = v0z - c[2]
    y0 = np.empty(3)
    eb = np.empty(3)
    y0[0] = R[0] * dx + R[3] * dy + R[6] * dz
    y0[1] = R[1] * dx + R[4] * dy + R[7] * dz
    y0[2] = R[2] * dx + R[5] * dy + R[8] * dz
    eb[0] = R[0] * ex + R[3] * ey + R[6] * ez
    eb[1] = R[1] * ex + R[4] * ey + R[7] * ez
    eb[2] = R[2] * ex + R[5] * ey + R[8] * ez
    D = np.empty(3)
    for k in range(3):
        D[k] = 1.0 / (a[k] * a[k])
    # basis of the plane normal to e (body frame)
    t1x, t1y, t1z, t2x, t2y, t2z = tangent_basis(eb[0], eb[1], eb[2])
    # shadow ellipse: D2 = Tᵀ (D - D e eᵀ D / eᵀDe) T
    De0 = D[0] * eb[0]
    De1 = D[1] * eb[1]
    De2 = D[2] * eb[2]
    eDe = eb[0] * De0 + eb[1] * De1 + eb[2] * De2
    tD1 = t1x * De0 + t1y * De1 + t1z * De2
    tD2 = t2x * De0 + t2y * De1 + t2z * De2
    m11 = D[0] * t1x * t1x + D[1] * t1y * t1y + D[2] * t1z * t1z - tD1 * tD1 / eDe
    m12 = D[0] * t1x * t2x + D[1] * t1y * t2y + D[2] * t1z * t2z - tD1 * tD2 / eDe
    m22 = D[0] * t2x * t2x + D[1] * t2y * t2y + D[2] * t2z * t2z - tD2 * tD2 / eDe
    q1 = y0[0] * t1x + y0[1] * t1y + y0[2] * t1z
    q2 = y0[0] * t2x + y0[1] * t2y + y0[2] * t2z
    if m11 * q1 * q1 + 2.0 * m12 * q1 * q2 + m22 * q2 * q2 >= 1.0:
        return -1.0, 0.0, 0.0, 1.0, v0x, v0y, v0z, EDGE, 0.0, 0.0, 0.0
    # eigenbasis of the 2×2 shadow matrix (closed form)
    tr = 0.5 * (m11 + m22)
    df = math.sqrt(0.25 * (m11 - m22) ** 2 + m12 * m12)
    d2 = np.empty(2)
    d2[0] = tr + df
    d2[1] = tr - df
    if abs(m12) > 0.0:
        c1 = d2[0] - m22
        c2 = m12
    elif m11 >= m22:
        c1, c2 = 1.0, 0.0
    else:
        c1, c2 = 0.0, 1.0
    cn = math.sqrt(c1 * c1 + c2 * c2)
    c1 /= cn
    c2 /= cn
    qq = np.empty(2)
    qq[0] = c1 * q1 + c2 * q2
    qq[1] = -c2 * q1 + c1 * q2
    yy = np.empty(2)
    dist = _nearest_boundary(d2, qq, 2, yy)
    p1 = c1 * yy[0] - c2 * yy[1]
    p2 = c2 * yy[0] + c1 * yy[1]
    # silhouette point x_s = p + σ e with σ = -(eᵀ D p)/(eᵀ D e), p = p1 t1 + p2 t2
    px = p1 * t1x + p2 * t2x
    py = p1 * t1y + p2 * t2y
    pz = p1 * t1z + p2 * t2z
    sig = -(De0 * px + De1 * py + De2 * pz) / eDe
    xs0 = px + sig * eb[0]
    xs1 = py + sig * eb[1]
    xs2 = pz + sig * eb[2]
    tau = (xs0 - y0[0]) * eb[0] + (xs1 - y0[1]) * eb[1] + (xs2 - y0[2]) * eb[2]
    if tau < 0.0:
        o, nx, ny, nz, cx, cy, cz, b0, b1, b2 = ellipsoid_vertex(c, R, a, v0x, v0y, v0z)
        return o, nx, ny, nz, cx, cy, cz, VERTEX, b0, b1, b2
    if tau > L:
        o, nx, ny, nz, cx, cy, cz, b0, b1, b2 = ellipsoid_vertex(c, R, a, v1x, v1y, v1z)
        return o, nx, ny, nz, cx, cy, cz, VERTEX, b0, b1, b2
    # outward normal at the silhouette point: D x_s (body) -> world
    g0 = D[0] * xs0
    g1 = D[1] * xs1
    g2 = D[2] * xs2
    nx = R[0] * g0 + R[1] * g1 + R[2] * g2
    ny = R[3] * g0 + R[4] * g1 + R[5] * g2
    nz = R[6] * g0 + R[7] * g1 + R[8] * g2
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    nx /= nn
    ny /= nn
    nz /= nn
    # contact point: midway between the silhouette point and the line point at τ
    wx = c[0] + R[0] * xs0 + R[1] * xs1 + R[2] * xs2
    wy = c[1] + R[3] * xs0 + R[4] * xs1 + R[5] * xs2
    wz = c[2] + R[6] * xs0 + R[7] * xs1 + R[8] * xs2
    lx = v0x + tau * ex
    ly = v0y + tau * ey
    lz = v0z + tau * ez
    return dist, nx, ny, nz, 0.5 * (wx + lx), 0.5 * (wy + ly), 0.5 * (wz + lz), EDGE, xs0, xs1, xs2


@njit
def ellipsoid_triangle(c, R, a, v):
    """Ellipsoid against triangle v = (I, J, K) (9 numbers) (module docstring, Miyata eqs 50-59).
    Returns (overlap, nx, ny, nz (from the ellipsoid to the triangle), contact point, R_e,
    region FACE/EDGE/VERTEX); overlap ≤ 0: apart."""
    ux = v[3] - v[0]
    uy = v[4] - v[1]
    uz = v[5] - v[2]
    wx = v[6] - v[0]
    wy = v[7] - v[1]
    wz = v[8] - v[2]
    mx = uy * wz - uz * wy
    my = uz * wx - ux * wz
    mz = ux * wy - uy * wx
    area2 = math.sqrt(mx * mx + my * my + mz * mz)
    mx /= area2
    my /= area2
    mz /= area2
    if (c[0] - v[0]) * mx + (c[1] - v[1]) * my + (c[2] - v[2]) * mz < 0.0:  # the normal towards the centre
        mx = -mx
        my = -my
        mz = -mz
    o, nx, ny, nz, cx, cy, cz, re = ellipsoid_plane(c, R, a, v[0], v[1], v[2], mx, my, mz)
    if o <= 0.0:
        return o, nx, ny, nz, cx, cy, cz, re, FACE
    # Q = P + δ m (eq 56) and its triangle coordinates (eqs 57-59: signed sub-areas over the area)
    qx = cx + 0.5 * o * mx
    qy = cy + 0.5 * o * my
    qz = cz + 0.5 * o * mz
    inside = True
    for e in range(3):
        a0 = 3 * ((e + 1) % 3)
        a1 = 3 * ((e + 2) % 3)
        # sub-area of the triangle (Q, edge e's ends) along m, over the whole area
        p0x = v[a0] - qx
        p0y = v[a0 + 1] - qy
        p0z = v[a0 + 2] - qz
        p1x = v[a1] - qx
        p1y = v[a1 + 1] - qy
        p1z = v[a1 + 2] - qz
        Ls = ((p0y * p1z - p0z * p1y) * mx + (p0z * p1x - p0x * p1z) * my + (p0x * p1y - p0y * p1x) * mz)
        # orientation of (I, J, K) along m
        if (mx * (uy * wz - uz * wy) + my * (uz * wx - ux * wz) + mz * (ux * wy - uy * wx)) < 0.0:
            Ls = -Ls
        if not Ls > 0.0:
            inside = False
            break
    if inside:
        return o, nx, ny, nz, cx, cy, cz, re, FACE
    best = -np.inf
    bnx = bny = bnz = bcx = bcy = bcz = bre = 0.0
    breg = EDGE
    for e in range(3):
        a0 = 3 * e
        a1 = 3 * ((e + 1) % 3)
        oe, ex, ey, ez, px, py, pz, reg, b0, b1, b2 = ellipsoid_edge(c, R, a, v[a0], v[a0 + 1], v[a0 + 2],
                                                                  v[a1], v[a1 + 1], v[a1 + 2])
        if oe > best:
            best = oe
            bnx, bny, bnz, bcx, bcy, bcz, breg = ex, ey, ez, px, py, pz, reg
            bre = _radius_at(R, a, b0, b1, b2, ex, ey, ez) if oe > 0.0 else 0.0
    return best, bnx, bny, bnz, bcx, bcy, bcz, bre, breg
