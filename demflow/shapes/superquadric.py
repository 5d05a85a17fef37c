"""2D superquadric particles (Miyata §2.3, eqs 34-42): shape, mass properties and contact geometry.

A superquadric ("superellipse") of semi-axes a, b and exponent n is, in its body frame (centroid at
the origin, x along the body's local axis),

    f(x, y) = |x/a|^n + |y/b|^n - 1                                      (Miyata eq 34)

outside where f > 0, inside where f < 0.  demflow takes 1 < n <= 10, Miyata's range (smooth, convex;
n = 2, a = b is a disc of radius a).  For n <= 2 its surface is parametrised by the angle α of eq 35:

    x(α) = a sign(cos α)|cos α|^(2/n),   y(α) = b sign(sin α)|sin α|^(2/n);

for n > 2 by the polar angle α of the point, r(α)(cos α, sin α) with r = (|cos α/a|^n + |sin α/b|^n)^(-1/n).
Eq 35 is singular at the axes for n > 2 (dx/dα is unbounded where the surface is flattest): Brent's
accuracy in the parameter, √eps·|α| + tol, was an accuracy of b(√eps·π)^(2/n) in the point there, 0.7 % of b
at n = 6.7 and 3 % at n = 10 (found by tests/test_superquadric.py's comparison with fine polygons on
2026-11-27: a minimiser 0.006 b from the true one on a flat face).  The polar angle moves the point by at
most r·|Δα|/cos(angle between the radius and the normal), bounded on a convex outline.  Circles and sharp
shapes (n <= 2) keep eq 35, which is smooth there.  The contact is defined by the surface, not by the
parameter: only the accuracy of the minimiser changes.

Contact between two bodies i and j (Miyata §2.3 (2), the geometric potential): P_i is the point of
∂i that minimises f_j (the point of i deepest in j; eqs 36-37 express it in j's frame), P_j the
point of ∂j minimising f_i.  Each minimisation is a 1-D Brent minimisation (Brent 1973, *Algorithms
for Minimization without Derivatives*, ch. 5, procedure ``localmin``; the seed cites Brent's method)
along the surface parameter, warm-started from the last step's parameter (the seed's "incremental
iterative updates"); the tolerance on α is a knob.  The contact is then reduced to the two circles of
curvature at P_i and P_j (eqs 38-41): radius ρ_k, centre C_k = P_k - ρ_k n_k, and

    δ = ρ_i + ρ_j - |C_j - C_i|,   n̂ = (C_j - C_i)/|C_j - C_i|           (eq 42)

with the contact at the middle of the overlap on the line of centres, as between two discs.  The
contact kinematics are then exactly those of two discs (centres C_i, C_j, radii ρ_i, ρ_j) fixed to
the bodies: the lever arms are Q_i - x_i and Q_j - x_j with Q_i = C_i + ρ_i n̂, Q_j = C_j - ρ_j n̂
(for a disc Q - x = ±R n̂, the thesis's convention, eq 2.20), so n = 2, a = b reproduces the disc
code.

Assumptions (stated because the seed does not):

- ρ_k is clamped to [RHO_MIN_RATIO, RHO_MAX_RATIO] × the body's bounding radius: at the axis points
  of n > 2 the surface is flat (ρ = ∞, eq 39's denominator vanishes) and for n < 2 the curvature
  there is infinite.  eq 42 is evaluated in a rearranged form (see :func:`circles_overlap`) that
  does not lose the overlap to cancellation when ρ is large.
- The centres C_i, C_j are taken in the order of the outward normals (n_i - n_j points from i to
  j); where they have crossed (two sharp tips, n < 2, overlapping by more than ρ_i + ρ_j) the
  circles are past each other and δ = ρ_i + ρ_j + d, n̂ = (C_i - C_j)/d (continuous at d = 0).
- Overlaps are small against the particles (a few per cent), so ∂i ∩ j is one arc and f_j along ∂i
  has one minimum near the contact: the warm-started bracket is ±``window`` around the last α; a
  minimum found at the bracket's edge (or a pair seen for the first time) triggers a scan of
  N_SCAN samples of the whole surface followed by Brent around the best one.

Superquadric-segment (wall) contact: the wall's line is a body of infinite radius: the point of i
deepest beyond the line is the support point of i in the wall's direction (closed form: ∇f ∥ the
direction, :func:`support_point`) and δ = h_i(-m) - dist(centroid, line), m the wall's unit normal
towards the particle.  When that support point projects beyond the segment's end, the end point E
is a circle of radius 0 (eq 42 with ρ_j = 0): P_i is the point of ∂i nearest to E (Brent on
|P_i(α) - E|²) and δ = ρ_i - |E - C_i|.

All kernels are ``@njit`` functions of scalars (no arrays, no Python objects).
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import njit

N_MIN = 1.0   # exclusive: n > 1 (smooth convex; n = 1 is a rhombus with corners)
N_MAX = 10.0  # inclusive: Miyata §2.3 "1 < n <= 10"
# circles of curvature: radius kept within these multiples of the bounding radius (see module doc)
RHO_MIN_RATIO = 1e-6
RHO_MAX_RATIO = 1e3
N_SCAN = 32  # samples of the global scan (a new pair, or a minimum at the warm-start bracket's edge)
DEFAULT_TOL = 1e-9  # Brent tolerance on the surface parameter α [rad] (eq 35 for n <= 2, the polar angle for n > 2)
DEFAULT_WINDOW = math.pi / 8  # warm-start bracket half-width [rad]
_GOLD = 0.3819660112501051  # (3 - √5)/2
_SQRT_EPS = 1.4901161193847656e-08  # √(float64 eps)


# ----------------------------------------------------------------------------- mass properties
def dirichlet_integral(p: float, q: float, n: float) -> float:
    """∫∫ x^(p-1) y^(q-1) dx dy over the quarter x, y >= 0, x^n + y^n <= 1 (Dirichlet's integral,
    Whittaker & Watson, *A Course of Modern Analysis*, §12.5): Γ(p/n)Γ(q/n) / (n² Γ(1 + (p+q)/n))."""
    return math.exp(math.lgamma(p / n) + math.lgamma(q / n) - 2.0 * math.log(n) - math.lgamma(1.0 + (p + q) / n))


def area(a: float, b: float, n: float) -> float:
    """Area of the superquadric [length²] = 4ab·Γ(1+1/n)²/Γ(1+2/n) (Dirichlet's integral, p = q = 1)."""
    return 4.0 * a * b * dirichlet_integral(1.0, 1.0, n)


def second_moments(a: float, b: float, n: float) -> tuple[float, float]:
    """(∫x² dA, ∫y² dA) [length⁴] about the centroid, body frame: 4a³b·D(3, 1), 4ab³·D(1, 3)
    (D: :func:`dirichlet_integral`)."""
    return 4.0 * a ** 3 * b * dirichlet_integral(3.0, 1.0, n), 4.0 * a * b ** 3 * dirichlet_integral(1.0, 3.0, n)


def mass_properties(a: float, b: float, n: float, density: float) -> tuple[float, float]:
    """(mass, polar moment of inertia about the centroid) for unit thickness and areal density ρ:
    m = ρA, I = ρ(∫x² dA + ∫y² dA) [mass], [mass·length²].  In 2D the polar moment does not change
    with the orientation (rotation about the normal to the plane).  n = 2, a = b = R: ρπR², ½mR²."""
    ixx, iyy = second_moments(a, b, n)
    return density * area(a, b, n), density * (ixx + iyy)


@njit
def bounding_radius(a, b, n):
    """Largest distance from the centroid to the surface [length], closed form.

    r² = a²u^(2/n) + b²(1-u)^(2/n) with u = cos²α (eq 35).  For n <= 2 it is convex in u, so the
    largest r is max(a, b); for n > 2 it is concave and its maximum is where the derivative vanishes:
    u/(1-u) = (b²/a²)^(1/(2/n - 1))."""
    if n <= 2.0:
        return max(a, b)
    e = 2.0 / n - 1.0
    L = 2.0 * math.log(b / a) / e  # log(u/(1-u)), taken in logs: 1/e is large for n near 2
    u = 1.0 / (1.0 + math.exp(-L)) if L > 0.0 else math.exp(L) / (1.0 + math.exp(L))
    r = math.sqrt(a * a * u ** (2.0 / n) + b * b * (1.0 - u) ** (2.0 / n))
    return max(r, a, b)


# ----------------------------------------------------------------------------- surface functions
@njit
def surface_point(alpha, a, b, n):
    """Body-frame point of surface parameter α [length] (module docstring): for n <= 2 Miyata's eq 35,
    for n > 2 the point at polar angle α, r(α)(cos α, sin α) with r = (|cos α/a|^n + |sin α/b|^n)^(-1/n)
    (evaluated as 1/(u(1 + (v/u)^n)^(1/n)) with u the larger of |cos α|/a and |sin α|/b: no power overflows)."""
    c = math.cos(alpha)
    s = math.sin(alpha)
    if n <= 2.0:
        e = 2.0 / n
        return a * math.copysign(abs(c) ** e, c), b * math.copysign(abs(s) ** e, s)
    u = abs(c) / a
    v = abs(s) / b
    hi = max(u, v)
    r = 1.0 / (hi * (1.0 + (min(u, v) / hi) ** n) ** (1.0 / n))
    return r * c, r * s


@njit
def potential(x, y, a, b, n):
    """Miyata eq 34 (and 36): f = |x/a|^n + |y/b|^n - 1 at a body-frame point (x, y)."""
    return abs(x / a) ** n + abs(y / b) ** n - 1.0


@njit
def normal_and_curvature(x, y, a, b, n):
    """Outward unit normal (eq 40) and curvature κ = 1/ρ (eq 39, f_xy = 0) at a body-frame surface
    point.  Returns (nx, ny, κ) [-, -, 1/length]; κ = 0 where the surface is flat (n > 2 on an axis)
    and inf where it is infinitely curved (n < 2 on an axis)."""
    ux = abs(x) / a
    uy = abs(y) / b
    gx = math.copysign(n / a * ux ** (n - 1.0), x)
    gy = math.copysign(n / b * uy ** (n - 1.0), y)
    if ux == 0.0 and n < 2.0:
        gxx = math.inf
    else:
        gxx = n * (n - 1.0) / (a * a) * ux ** (n - 2.0)
    if uy == 0.0 and n < 2.0:
        gyy = math.inf
    else:
        gyy = n * (n - 1.0) / (b * b) * uy ** (n - 2.0)
    g2 = gx * gx + gy * gy
    g = math.sqrt(g2)
    num = gxx * gy * gy + gyy * gx * gx
    if not math.isfinite(num):
        kappa = math.inf
    else:
        kappa = num / (g2 * g)
    return gx / g, gy / g, kappa


@njit
def support_point(ux, uy, a, b, n):
    """Body-frame point of the surface farthest along the unit direction (ux, uy) and the support
    h = max p·u [length]: ∇f ∥ u gives |x|/a = (a|u_x|)^(1/(n-1)) / S^(1/n),
    S = (a|u_x|)^q + (b|u_y|)^q, q = n/(n-1), and h = S^(1/q)."""
    q = n / (n - 1.0)
    sx = (a * abs(ux)) ** q
    sy = (b * abs(uy)) ** q
    S = sx + sy
    h = S ** (1.0 / q)
    # |x|/a = (a|ux|)^(1/(n-1)) / S^(1/n) = (sx/S)^(1/n)
    x = a * math.copysign((sx / S) ** (1.0 / n), ux)
    y = b * math.copysign((sy / S) ** (1.0 / n), uy)
    return x, y, h


# ----------------------------------------------------------------------------- Brent minimisation
@njit
def _phi(alpha, ai, bi, ni, c, s, ox, oy, aj, bj, nj, ex, ey):
    """The geometric potential along ∂i: f_j of P_i(α) in j's frame (eqs 36-37), c, s the cosine
    and sine of θ_i - θ_j, (ox, oy) the centre of i in j's frame; with aj = 0 instead the squared
    distance to the point (ex, ey) of i's frame (the wall end of :func:`segment_contact`)."""
    px, py = surface_point(alpha, ai, bi, ni)
    if aj == 0.0:
        return (px - ex) ** 2 + (py - ey) ** 2
    return potential(c * px - s * py + ox, s * px + c * py + oy, aj, bj, nj)


@njit
def _brent(lo, hi, tol, ai, bi, ni, c, s, ox, oy, aj, bj, nj, ex, ey):
    """Brent's localmin (Brent 1973, ch. 5) of :func:`_phi` on [lo, hi]: golden section with
    parabolic steps, stopping when the bracket around the minimiser is below 2(√eps|x| + tol/3).
    Returns (α, φ(α), evaluations)."""
    a = lo
    b = hi
    x = a + _GOLD * (b - a)
    w = x
    v = x
    fx = _phi(x, ai, bi, ni, c, s, ox, oy, aj, bj, nj, ex, ey)
    fw = fx
    fv = fx
    d = 0.0
    e = 0.0
    evals = 1
    for _ in range(200):
        m = 0.5 * (a + b)
        tol1 = _SQRT_EPS * abs(x) + tol / 3.0
        t2 = 2.0 * tol1
        if abs(x - m) <= t2 - 0.5 * (b - a):
            break
        p = 0.0
        q = 0.0
        r = 0.0
        if abs(e) > tol1:
            r = (x - w) * (fx - fv)
            q = (x - v) * (fx - fw)
            p = (x - v) * q - (x - w) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            else:
                q = -q
            r = e
            e = d
        if abs(p) < abs(0.5 * q * r) and p > q * (a - x) and p < q * (b - x):
            d = p / q  # parabolic step
            u = x + d
            if u - a < t2 or b - u < t2:
                d = tol1 if x < m else -tol1
        else:
            e = (b - x) if x < m else (a - x)  # golden-section step
            d = _GOLD * e
        if abs(d) >= tol1:
            u = x + d
        else:
            u = x + (tol1 if d > 0.0 else -tol1)
        fu = _phi(u, ai, bi, ni, c, s, ox, oy, aj, bj, nj, ex, ey)
        evals += 1
        if fu <= fx:
            if u < x:
                b = x
            else:
                a = x
            v = w
            fv = fw
            w = x
            fw = fx
            x = u
            fx = fu
        else:
            if u < x:
                a = u
            else:
                b = u
            if fu <= fw or w == x:
                v = w
                fv = fw
                w = u
                fw = fu
            elif fu <= fv or v == x or v == w:
                v = u
                fv = fu
    return x, fx, evals


@njit
def minimise_on_surface(alpha0, warm, tol, window, ai, bi, ni, c, s, ox, oy, aj, bj, nj, ex, ey):
    """Minimise :func:`_phi` over the whole surface parameter: Brent on α0 ± ``window`` when ``warm``
    (the last step's minimiser), else (or when that minimum lies on the bracket's edge) a scan of
    N_SCAN samples and Brent between the best sample's neighbours.  Returns (α in [-π, π), evals)."""
    evals = 0
    if warm:
        lo = alpha0 - window
        hi = alpha0 + window
        x, fx, k = _brent(lo, hi, tol, ai, bi, ni, c, s, ox, oy, aj, bj, nj, ex, ey)
        evals += k
        edge = 4.0 * (_SQRT_EPS * abs(x) + tol)
        if x - lo > edge and hi - x > edge:
            return _wrap_angle(x), evals
    h = 2.0 * math.pi / N_SCAN
    best = 0
    fbest = math.inf
    for q in range(N_SCAN):
        fq = _phi(-math.pi + q * h, ai, bi, ni, c, s, ox, oy, aj, bj, nj, ex, ey)
        if fq < fbest:
            fbest = fq
            best = q
    evals += N_SCAN
    centre = -math.pi + best * h
    x, fx, k = _brent(centre - h, centre + h, tol, ai, bi, ni, c, s, ox, oy, aj, bj, nj, ex, ey)
    return _wrap_angle(x), evals + k


@njit
def _wrap_angle(a):
    return a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))


# ----------------------------------------------------------------------------- contact geometry
@njit
def _curvature_radius(kappa, rb):
    """ρ = 1/κ clamped to [RHO_MIN_RATIO, RHO_MAX_RATIO] × the bounding radius rb."""
    lo = RHO_MIN_RATIO * rb
    hi = RHO_MAX_RATIO * rb
    if kappa * hi <= 1.0:
        return hi
    if kappa * lo >= 1.0:
        return lo
    return 1.0 / kappa


@njit
def circles_overlap(Dx, Dy, nix, niy, njx, njy, rhoi, rhoj, cx, cy):
    """eq 42 for the circles of curvature (radius ρ, centre C = P - ρn) at P_i and P_j = P_i + D,
    with C_j - C_i = (cx, cy) computed by the caller.  Evaluated as

        δ = [(ρ_i + ρ_j)² - d²] / (ρ_i + ρ_j + d),
        (ρ_i + ρ_j)² - d² = ρ_iρ_j|n_i + n_j|² - |D|² - 2ρ_i D·n_i + 2ρ_j D·n_j,

    (algebraically eq 42) so that no two large numbers are subtracted when ρ is large (flat parts).
    Returns (δ, d)."""
    d = math.sqrt(cx * cx + cy * cy)
    sx = nix + njx
    sy = niy + njy
    num = rhoi * rhoj * (sx * sx + sy * sy) - (Dx * Dx + Dy * Dy) - 2.0 * rhoi * (Dx * nix + Dy * niy) \
        + 2.0 * rhoj * (Dx * njx + Dy * njy)
    return num / (rhoi + rhoj + d), d


@njit
def _to_global(c, s, x, y):
    return c * x - s * y, s * x + c * y


@njit
def pair_contact(dx, dy, thi, thj, ai, bi, ni, rbi, aj, bj, nj, rbj, alpha_i, alpha_j, warm, tol, window):
    """Contact geometry of superquadrics i and j (Miyata eqs 35-42).

    dx, dy: centre of j minus centre of i [length]; θ_i, θ_j their orientations [rad]; a, b, n, rb
    their shapes and bounding radii; alpha_i, alpha_j the last minimisers (used when ``warm``);
    tol: Brent tolerance on α [rad]; window: warm-start bracket half-width [rad].

    Returns (δ, n̂x, n̂y, Cix, Ciy, ρi, Cjx, Cjy, ρj, αi, αj, evals): overlap [length] (> 0 touching),
    the unit normal from C_i to C_j, the circles of curvature with their centres relative to the
    centre of i and of j respectively [length], the new minimisers, and the potential evaluations
    spent.  Contact point: C_i + (ρ_i - δ/2) n̂ (relative to i's centre)."""
    ci = math.cos(thi)
    si = math.sin(thi)
    cj = math.cos(thj)
    sj = math.sin(thj)
    # relative rotation θ_i - θ_j and the centre of i in j's frame (eq 37), and vice versa
    c = ci * cj + si * sj
    s = si * cj - ci * sj
    oxj = -(cj * dx + sj * dy)
    oyj = -(-sj * dx + cj * dy)
    oxi = ci * dx + si * dy
    oyi = -si * dx + ci * dy
    ai_new, ev1 = minimise_on_surface(alpha_i, warm, tol, window, ai, bi, ni, c, s, oxj, oyj, aj, bj, nj, 0.0, 0.0)
    aj_new, ev2 = minimise_on_surface(alpha_j, warm, tol, window, aj, bj, nj, c, -s, oxi, oyi, ai, bi, ni, 0.0, 0.0)
    # P_i, n_i, ρ_i in i's frame, then rotated to the global axes (relative to i's centre)
    pxi, pyi = surface_point(ai_new, ai, bi, ni)
    nxi, nyi, ki = normal_and_curvature(pxi, pyi, ai, bi, ni)
    rhoi = _curvature_radius(ki, rbi)
    pxj, pyj = surface_point(aj_new, aj, bj, nj)
    nxj, nyj, kj = normal_and_curvature(pxj, pyj, aj, bj, nj)
    rhoj = _curvature_radius(kj, rbj)
    Cix, Ciy = _to_global(ci, si, pxi - rhoi * nxi, pyi - rhoi * nyi)  # eq 41
    Cjx, Cjy = _to_global(cj, sj, pxj - rhoj * nxj, pyj - rhoj * nyj)
    Pix, Piy = _to_global(ci, si, pxi, pyi)
    Pjx, Pjy = _to_global(cj, sj, pxj, pyj)
    gnix, gniy = _to_global(ci, si, nxi, nyi)
    gnjx, gnjy = _to_global(cj, sj, nxj, nyj)
    cx = dx + Cjx - Cix
    cy = dy + Cjy - Ciy
    delta, d = circles_overlap(dx + Pjx - Pix, dy + Pjy - Piy, gnix, gniy, gnjx, gnjy, rhoi, rhoj, cx, cy)
    # the circles' centres in the order of the outward normals (n_i - n_j points from i to j); when they
    # have crossed (sharp tips, ρ_i + ρ_j < δ) the circles are past each other: δ = ρ_i + ρ_j + d
    if cx * (gnix - gnjx) + cy * (gniy - gnjy) < 0.0:
        delta = rhoi + rhoj + d
        ex = -cx / d
        ey = -cy / d
    elif d > 0.0:
        ex = cx / d
        ey = cy / d
    else:
        ex = gnix
        ey = gniy
    return delta, ex, ey, Cix, Ciy, rhoi, Cjx, Cjy, rhoj, ai_new, aj_new, ev1 + ev2


@njit
def segment_contact(xi, yi, thi, ai, bi, ni, rbi, Ax, Ay, Bx, By, alpha_i, warm, tol, window):
    """Contact of superquadric i (centre (xi, yi), orientation θ_i) with the segment AB (a wall).

    Returns (δ, n̂x, n̂y, lx, ly, qx, qy, αi, evals): overlap [length] (> 0 touching), the unit
    normal from the particle towards the wall, the lever arm (lx, ly) of the particle's contact
    point relative to its centre (line: the support point; end: C_i + ρ_i n̂ on the circle of
    curvature), the wall point the contact meets (global) [length], the minimiser (end contacts)
    and the potential evaluations spent.  The contact point is the middle of (x_i + l) and q.
    See the module doc."""
    ci = math.cos(thi)
    si = math.sin(thi)
    ux = Bx - Ax
    uy = By - Ay
    L = math.sqrt(ux * ux + uy * uy)
    ux /= L
    uy /= L
    # unit normal m of the wall's line, pointing to the particle's side
    mx = -uy
    my = ux
    dist = (xi - Ax) * mx + (yi - Ay) * my
    if dist < 0.0:
        mx = -mx
        my = -my
        dist = -dist
    # support point of i in -m (body frame, then global relative to the centre)
    lx = -(ci * mx + si * my)
    ly = -(-si * mx + ci * my)
    spx, spy, h = support_point(lx, ly, ai, bi, ni)
    gx, gy = _to_global(ci, si, spx, spy)
    t = (xi + gx - Ax) * ux + (yi + gy - Ay) * uy
    if 0.0 <= t <= L:
        delta = h - dist
        # the support point's projection on the line
        return delta, -mx, -my, gx, gy, xi + gx + mx * delta, yi + gy + my * delta, alpha_i, 0
    # beyond an end: the end E is a circle of radius 0 (eq 42 with ρ_j = 0)
    Ex = Ax if t < 0.0 else Bx
    Ey = Ay if t < 0.0 else By
    ex_l = ci * (Ex - xi) + si * (Ey - yi)
    ey_l = -si * (Ex - xi) + ci * (Ey - yi)
    al, evals = minimise_on_surface(alpha_i, warm, tol, window, ai, bi, ni, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                                    ex_l, ey_l)
    px, py = surface_point(al, ai, bi, ni)
    nx, ny, k = normal_and_curvature(px, py, ai, bi, ni)
    rho = _curvature_radius(k, rbi)
    Cx, Cy = _to_global(ci, si, px - rho * nx, py - rho * ny)
    cx = Ex - xi - Cx
    cy = Ey - yi - Cy
    d = math.sqrt(cx * cx + cy * cy)
    gnx, gny = _to_global(ci, si, nx, ny)
    sign = 1.0
    if cx * gnx + cy * gny < 0.0:
        sign = -1.0  # E is past the centre of curvature (a sharp tip): see pair_contact
    if d > 0.0:
        ex = sign * cx / d
        ey = sign * cy / d
    else:
        ex = gnx
        ey = gny
    return rho - sign * d, ex, ey, Cx + rho * ex, Cy + rho * ey, Ex, Ey, al, evals


def outline(a: float, b: float, n: float, theta: float = 0.0, count: int = 256) -> np.ndarray:
    """(count, 2) body outline rotated by θ, from eq 35 (for pictures)."""
    al = np.linspace(-np.pi, np.pi, count, endpoint=False)
    c, s = np.cos(al), np.sin(al)
    x = a * np.sign(c) * np.abs(c) ** (2.0 / n)
    y = b * np.sign(s) * np.abs(s) ** (2.0 / n)
    return np.column_stack([np.cos(theta) * x - np.sin(theta) * y, np.sin(theta) * x + np.cos(theta) * y])
