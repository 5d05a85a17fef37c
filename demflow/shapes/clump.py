"""Clump templates: a rigid body made of overlapping spheres, and the mass properties of their union.

"Ellipsoid-like clumps" (Miyata §3.3's rubble: semi-axes 37.1 × 26.0 × 18.2 cm, 1 : 0.7 : 0.49,
191 kg) are built as a *greedy sphere cover*: candidate centres on a regular grid inside the
ellipsoid, each with the largest sphere that fits inside it (its radius is the centre's distance to
the surface); spheres are taken one at a time, each time the one that covers the most of the
ellipsoid's volume not yet covered (measured on a regular grid of sample points), until there are
K.  Every member lies inside the ellipsoid, so the union's volume grows towards the ellipsoid's as
K grows; K is the resolution knob.

Mass properties of the union (members overlap: their masses must not be added) are integrated on a
regular grid of cell centres with spacing h over the union's bounding box (the midpoint rule on the
union's indicator), as YADE's ``appendClumped(discretization=...)`` does; the error falls with h
(tests).  A template is stored in its principal frame: centre of mass at the origin, the principal
axes along x, y, z, members' centres and radii, mass and principal moments.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..jit import njit

MIYATA_AXES = (0.371, 0.260, 0.182)  # semi-axes [m] (Miyata §3.3)
MIYATA_MASS = 191.0  # [kg]


def ellipsoid_surface_distance(p: np.ndarray, axes) -> np.ndarray:
    """Distance from interior points p (m, 3) to the surface of the ellipsoid x²/a² + y²/b² + z²/c² = 1.

    The closest surface point is x_i = a_i² p_i / (a_i² + t) with t the root in (-min a_i², 0] of
    Σ (a_i p_i / (a_i² + t))² = 1 (Eberly), found by bisection to machine precision.
    """
    p = np.atleast_2d(np.asarray(p, np.float64))
    a2 = np.asarray(axes, np.float64) ** 2
    lo = np.full(len(p), -a2.min() * (1 - 1e-15))
    hi = np.zeros(len(p))

    def f(t):
        return np.sum((np.sqrt(a2) * p / (a2 + t[:, None])) ** 2, axis=1) - 1.0

    for _ in range(200):
        mid = 0.5 * (lo + hi)
        inside = f(mid) < 0  # f decreases with t; f(hi=0) <= 0 inside
        hi = np.where(inside, mid, hi)
        lo = np.where(inside, lo, mid)
    t = 0.5 * (lo + hi)
    x = a2 * p / (a2 + t[:, None])
    d = np.linalg.norm(x - p, axis=1)
    d[np.abs(np.sum(x * x / a2, axis=1) - 1.0) > 1e-9] = np.inf  # no root (p on that plane): not a surface point
    # on the plane of the smallest axis the nearest point may be off that plane (t = -c²): Eberly's
    # degenerate case; a surface point either way, so the smaller distance is the true one
    k = int(np.argmin(a2))
    o = [a for a in range(3) if a != k]
    xo = a2[o] * p[:, o] / (a2[o] - a2[k])
    rest = 1.0 - np.sum(xo ** 2 / a2[o], axis=1)
    ok = rest >= 0.0
    if np.any(ok):
        y = np.zeros_like(p)
        y[:, o] = xo
        y[:, k] = np.sign(p[:, k] + (p[:, k] == 0)) * np.sqrt(np.maximum(rest, 0.0) * a2[k])
        d = np.where(ok, np.minimum(d, np.linalg.norm(y - p, axis=1)), d)
    return d


def _grid(lo, hi, h):
    axes = [np.arange(lo[a] + 0.5 * h, hi[a], h) for a in range(3)]
    g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return g


@njit
def _greedy_cover(cand, rad, inside, lo, h, K):
    """Greedy selection on a regular sample grid (``inside``: the ellipsoid's cells); returns the
    chosen candidate indices.  Each candidate only visits the grid cells of its bounding cube."""
    n0, n1, n2 = inside.shape
    covered = np.zeros(inside.shape, np.bool_)
    chosen = np.empty(K, np.int64)
    for step in range(K):
        best = -1
        best_gain = -1
        for c in range(cand.shape[0]):
            r = rad[c]
            r2 = r * r
            i0 = max(int(math.floor((cand[c, 0] - r - lo[0]) / h)), 0)
            i1 = min(int(math.ceil((cand[c, 0] + r - lo[0]) / h)), n0)
            j0 = max(int(math.floor((cand[c, 1] - r - lo[1]) / h)), 0)
            j1 = min(int(math.ceil((cand[c, 1] + r - lo[1]) / h)), n1)
            k0 = max(int(math.floor((cand[c, 2] - r - lo[2]) / h)), 0)
            k1 = min(int(math.ceil((cand[c, 2] + r - lo[2]) / h)), n2)
            gain = 0
            for i in range(i0, i1):
                dx = lo[0] + (i + 0.5) * h - cand[c, 0]
                for j in range(j0, j1):
                    dy = lo[1] + (j + 0.5) * h - cand[c, 1]
                    for k in range(k0, k1):
                        if inside[i, j, k] and not covered[i, j, k]:
                            dz = lo[2] + (k + 0.5) * h - cand[c, 2]
                            if dx * dx + dy * dy + dz * dz < r2:
                                gain += 1
            if gain > best_gain:
                best = c
                best_gain = gain
        chosen[step] = best
        r = rad[best]
        for i in range(n0):
            dx = lo[0] + (i + 0.5) * h - cand[best, 0]
            for j in range(n1):
                dy = lo[1] + (j + 0.5) * h - cand[best, 1]
                for k in range(n2):
                    dz = lo[2] + (k + 0.5) * h - cand[best, 2]
                    if dx * dx + dy * dy + dz * dz < r * r:
                        covered[i, j, k] = True
    return chosen


def ellipsoid_cover(axes=MIYATA_AXES, K: int = 12, candidates_per_axis: int = 25,
                    samples_per_axis: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """Greedy cover of an ellipsoid by K inscribed spheres (module docstring): (centres (K, 3), radii (K,)).

    Candidate centres on a grid of ``candidates_per_axis`` per axis inside the ellipsoid, coverage
    measured on a grid of ``samples_per_axis`` cells along the longest axis.  Deterministic (no
    random numbers); ties go to the lowest candidate index.
    """
    if isinstance(K, bool) or not isinstance(K, (int, np.integer)) or K < 1:
        raise ValueError(f"K={K!r}: give the number of member spheres, an integer >= 1")
    ax = np.asarray(axes, np.float64)
    if ax.shape != (3,) or not np.all(np.isfinite(ax)) or np.any(ax <= 0):
        raise ValueError(f"axes={axes!r}: give three positive semi-axes")
    cand = _grid(-ax, ax, 2 * ax.max() / candidates_per_axis)
    cand = cand[np.sum((cand / ax) ** 2, axis=1) < 1.0]
    rad = ellipsoid_surface_distance(cand, ax)
    h = 2 * ax.max() / samples_per_axis
    n = np.ceil(2 * ax / h).astype(np.int64)
    lo = -0.5 * n * h
    g = [lo[a] + (np.arange(n[a]) + 0.5) * h for a in range(3)]
    X, Y, Z = np.meshgrid(*g, indexing="ij")
    inside = (X / ax[0]) ** 2 + (Y / ax[1]) ** 2 + (Z / ax[2]) ** 2 < 1.0
    chosen = _greedy_cover(cand, rad, inside, lo, h, int(K))
    return cand[chosen].copy(), rad[chosen].copy()


@njit
def _union_moments(centres, radii, lo, h, n0, n1, n2):
    """Σ over grid cells inside the union of 1, x, x x^T (cell centres), times the cell volume."""
    V = 0.0
    s = np.zeros(3)
    S = np.zeros((3, 3))
    dv = h * h * h
    x = np.empty(3)
    for i in range(n0):
        x[0] = lo[0] + (i + 0.5) * h
        for j in range(n1):
            x[1] = lo[1] + (j + 0.5) * h
            for k in range(n2):
                x[2] = lo[2] + (k + 0.5) * h
                hit = False
                for m in range(radii.shape[0]):
                    d2 = (x[0] - centres[m, 0]) ** 2 + (x[1] - centres[m, 1]) ** 2 + (x[2] - centres[m, 2]) ** 2
                    if d2 < radii[m] * radii[m]:
                        hit = True
                        break
                if hit:
                    V += dv
                    for a in range(3):
                        s[a] += dv * x[a]
                        for b in range(3):
                            S[a, b] += dv * x[a] * x[b]
    return V, s, S


def union_mass_properties(centres, radii, density: float = 1.0, h: float | None = None) -> dict:
    """Mass, centre of mass and inertia tensor (about the centre of mass) of a union of spheres of
    uniform ``density`` [mass/length³], by the midpoint rule on a grid of spacing h (default: the
    smallest radius / 20).  Overlaps are counted once."""
    c = np.asarray(centres, np.float64).reshape(-1, 3)
    r = np.asarray(radii, np.float64).reshape(-1)
    if h is None:
        h = float(r.min()) / 20.0
    lo = (c - r[:, None]).min(axis=0)
    hi = (c + r[:, None]).max(axis=0)
    n = np.ceil((hi - lo) / h).astype(np.int64)
    V, s, S = _union_moments(c, r, lo, h, int(n[0]), int(n[1]), int(n[2]))
    mass = density * V
    com = s / V
    second = density * (S - V * np.outer(com, com))  # ∫ρ (x-c)(x-c)^T
    inertia = np.trace(second) * np.eye(3) - second
    return {"volume": V, "mass": mass, "com": com, "inertia": inertia}


def symmetric_eigen3(A) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and unit eigenvectors (columns) of a symmetric 3 × 3 matrix, by cyclic Jacobi
    rotations (Golub & Van Loan, Matrix Computations §8.5) in scalar arithmetic.

    Not ``np.linalg.eigh``: LAPACK's eigenvectors go through BLAS, whose kernels (chosen for the CPU) round
    differently, so a clump's principal frame, hence every clump run, differed in the last bits between hosts
    (measured 2026-11-25: the K = 8 template's axes between OpenBLAS's Haswell and SkylakeX kernels).  A
    rotation is skipped once its off-diagonal entry is below the round-off of both diagonal ones."""
    a = [[float(A[i][j]) for j in range(3)] for i in range(3)]
    v = [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
    for _ in range(50):
        if a[0][1] == 0.0 and a[0][2] == 0.0 and a[1][2] == 0.0:
            break
        for p, q in ((0, 1), (0, 2), (1, 2)):
            apq = a[p][q]
            if apq == 0.0:
                continue
            g = 100.0 * abs(apq)
            if abs(a[p][p]) + g == abs(a[p][p]) and abs(a[q][q]) + g == abs(a[q][q]):
                a[p][q] = a[q][p] = 0.0  # below the diagonal's round-off
                continue
            theta = (a[q][q] - a[p][p]) / (2.0 * apq)
            t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
            c = 1.0 / math.sqrt(t * t + 1.0)
            s_ = t * c
            for k in range(3):  # A <- A J (columns p, q)
                akp, akq = a[k][p], a[k][q]
                a[k][p] = c * akp - s_ * akq
                a[k][q] = s_ * akp + c * akq
            for k in range(3):  # A <- J^T A (rows p, q)
                apk, aqk = a[p][k], a[q][k]
                a[p][k] = c * apk - s_ * aqk
                a[q][k] = s_ * apk + c * aqk
            a[p][q] = a[q][p] = 0.0
            for k in range(3):  # V <- V J
                vkp, vkq = v[k][p], v[k][q]
                v[k][p] = c * vkp - s_ * vkq
                v[k][q] = s_ * vkp + c * vkq
    order = sorted(range(3), key=lambda i: a[i][i])
    w = np.array([a[i][i] for i in order])
    vecs = np.array([[v[k][i] for i in order] for k in range(3)])
    return w, vecs


def bounding_radius(centres, radii) -> float:
    """The radius of the smallest sphere about the origin (the centre of mass of a template) that holds every
    member: max_k |c_k| + r_k [length].  The insertion rules of demflow's uniaxial case and of the LIGGGHTS deck
    both use it."""
    c = np.asarray(centres, np.float64).reshape(-1, 3)
    return float(np.max(np.linalg.norm(c, axis=1) + np.asarray(radii, np.float64).reshape(-1)))


def check_members(path: str, centres, radii, error=ValueError):
    """Member centres (K, 3) and radii (K,) of a clump as float arrays: K >= 1, finite, radii > 0 (``error``, naming
    ``path``, otherwise)."""
    try:
        c = np.asarray(centres, np.float64)
        r = np.asarray(radii, np.float64)
    except (TypeError, ValueError):
        raise error(f"{path}: centres={centres!r} and radii={radii!r} are not numbers; give K centres (x, y, z) and "
                    "K radii") from None
    if c.ndim != 2 or c.shape[1:] != (3,) or r.ndim != 1 or r.shape[0] != c.shape[0] or r.shape[0] == 0:
        raise error(f"{path}: {c.shape[0] if c.ndim else 0} centres of shape {c.shape} and radii of shape {r.shape}; "
                    "give K >= 1 centres (K, 3) and K radii (K,)")
    for name, a in (("centres", c), ("radii", r)):
        bad = np.flatnonzero(~np.isfinite(a).reshape(a.shape[0], -1).all(axis=1))
        if bad.size:
            raise error(f"{path}.{name}[{int(bad[0])}]={a[bad[0]].tolist()!r} is not finite; give finite numbers")
    if np.any(r <= 0.0):
        k = int(np.flatnonzero(r <= 0.0)[0])
        raise error(f"{path}.radii[{k}]={float(r[k])!r} must be > 0; give positive member radii")
    return c, r


def check_template(path: str, t, error=ValueError) -> None:
    """A template's members (:func:`check_members`), mass (finite, > 0) and principal moments (3, finite, > 0)."""
    check_members(path, t.centres, t.radii, error)
    m = float(t.mass) if np.ndim(t.mass) == 0 else math.nan
    if not (math.isfinite(m) and m > 0.0):
        raise error(f"{path}.mass={t.mass!r} must be a finite number > 0 [mass]; give the clump's mass")
    mom = np.asarray(t.moments, np.float64)
    if mom.shape != (3,) or not np.all(np.isfinite(mom)) or np.any(mom <= 0.0):
        raise error(f"{path}.moments={np.asarray(t.moments).tolist()!r} must be three finite principal moments > 0 "
                    "[mass·length²]; build the template with ClumpTemplate.from_spheres")


@dataclass(frozen=True)
class ClumpTemplate:
    """A clump in its principal frame: member centres (K, 3) [length] and radii (K,), mass [mass] and
    principal moments of inertia (3,) [mass·length²] about the centre of mass (at the origin)."""

    centres: np.ndarray
    radii: np.ndarray
    mass: float
    moments: np.ndarray

    @classmethod
    def from_spheres(cls, centres, radii, *, mass: float | None = None, density: float | None = None,
                     h: float | None = None) -> "ClumpTemplate":
        """The template of a union of spheres, given its ``mass`` (the density follows) or ``density``."""
        if (mass is None) == (density is None):
            raise ValueError("give the clump's mass or its density, one of them")
        centres, radii = check_members("ClumpTemplate.from_spheres", centres, radii)
        for name, v in (("mass", mass), ("density", density)):
            if v is not None and not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                                      and v > 0):
                raise ValueError(f"ClumpTemplate.from_spheres: {name}={v!r} must be a finite number > 0")
        props = union_mass_properties(centres, radii, 1.0, h)
        rho = density if density is not None else mass / props["volume"]
        w, vecs = symmetric_eigen3(props["inertia"] * rho)
        if np.linalg.det(vecs) < 0:
            vecs[:, 2] *= -1.0
        # the centres in the principal frame, d·v_k summed in a fixed order: a matrix product goes through BLAS,
        # whose kernels (chosen for the CPU) round the last bit differently (measured 2026-11-25: 1 ulp in the
        # K = 8 template between OpenBLAS's Haswell and SkylakeX kernels), and every clump run would inherit it
        d = np.asarray(centres, np.float64).reshape(-1, 3) - props["com"]
        local = d[:, 0:1] * vecs[0] + d[:, 1:2] * vecs[1] + d[:, 2:3] * vecs[2]
        return cls(centres=local, radii=np.asarray(radii, np.float64).reshape(-1), mass=rho * props["volume"],
                   moments=w)

    @classmethod
    def ellipsoid_like(cls, K: int, axes=MIYATA_AXES, mass: float = MIYATA_MASS, **cover) -> "ClumpTemplate":
        """Miyata's ellipsoid-like rubble as a K-sphere greedy cover, scaled to ``mass``."""
        c, r = ellipsoid_cover(axes, K, **cover)
        return cls.from_spheres(c, r, mass=mass)


def ellipsoid_moments(axes, mass: float) -> np.ndarray:
    """Principal moments of a solid ellipsoid: m(b² + c²)/5, m(a² + c²)/5, m(a² + b²)/5."""
    a, b, c = axes
    return mass / 5.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])


def ellipsoid_volume(axes) -> float:
    return 4.0 / 3.0 * math.pi * float(np.prod(axes))
