"""Closed boundaries discretised into discontinuous linear elements (thesis §4.3.4.4, §4.3.8).

Each boundary is a closed polygon of straight elements.  An element from end a to end b carries
two nodes at η = ∓1/2 (thesis eq 4.48: N_1 = 1/2 - η, N_2 = 1/2 + η), i.e. at a quarter and three
quarters of its length; the geometry is x(η) = ½(1-η) a + ½(1+η) b (eq 4.47).  Nodes are inside
elements, so the boundary is smooth at every node and c_ij = ½ δ_ij (eq 4.36).

Orientation (thesis §4.3.8): the outer boundary runs counter-clockwise, holes (particles)
clockwise, so that n = (τ_y, -τ_x) (τ the unit tangent a→b) points out of the fluid everywhere.
:class:`Domain` *checks* this (signed areas, holes inside the outer boundary and apart from each
other) and refuses a domain that breaks it.  Lengths in [m].
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import libm


@dataclass
class Boundary:
    """A closed polygonal boundary: ``ends[k]`` → ``ends[k+1]`` (cyclic) is element k.

    ``side[k]`` labels the element with an index into ``side_names`` (e.g. 'inlet', 'top'), so
    boundary conditions can be set per side.  ``hole`` says whether this is a hole in the fluid
    (a particle: clockwise) or the outer boundary (counter-clockwise).
    """

    name: str
    ends: np.ndarray
    hole: bool
    side: np.ndarray = None
    side_names: tuple = ("all",)
    center: tuple = None  # reference point for moments (default: centroid)

    def __post_init__(self):
        self.ends = np.asarray(self.ends, dtype=float)
        if self.ends.ndim != 2 or self.ends.shape[1] != 2 or len(self.ends) < 3:
            raise ValueError(f"boundary {self.name!r}: ends must be an (M >= 3, 2) array of points")
        if self.side is None:
            self.side = np.zeros(len(self.ends), dtype=np.int64)
        self.side = np.asarray(self.side, dtype=np.int64)
        if self.center is None:
            self.center = tuple(polygon_centroid(self.ends))

    @property
    def n_elements(self):
        return len(self.ends)

    def signed_area(self):
        return signed_area(self.ends)


def signed_area(v):
    """Shoelace area of a closed polygon [m²]; > 0 counter-clockwise."""
    x, y = v[:, 0], v[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def polygon_centroid(v):
    x, y = v[:, 0], v[:, 1]
    cr = x * np.roll(y, -1) - np.roll(x, -1) * y
    a = 0.5 * cr.sum()
    if abs(a) < 1e-300:
        return v.mean(axis=0)
    return np.array([np.sum((x + np.roll(x, -1)) * cr), np.sum((y + np.roll(y, -1)) * cr)]) / (6 * a)


def points_in_polygon(pts, v):
    """Even-odd ray casting: which of ``pts`` (P, 2) lie inside the closed polygon ``v``."""
    pts = np.atleast_2d(pts)
    x, y = pts[:, 0:1], pts[:, 1:2]
    x1, y1 = v[:, 0], v[:, 1]
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    cond = (y1 > y) != (y2 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
    return np.sum(cond & (x < xc), axis=1) % 2 == 1


def circle(center, radius, n, name="particle", hole=True):
    """Circle of ``radius`` [m] as an inscribed regular n-gon; clockwise if ``hole`` (a particle)."""
    th = 2 * np.pi * np.arange(n) / n
    if hole:
        th = -th
    ends = np.column_stack([center[0] + radius * libm.cos(th), center[1] + radius * libm.sin(th)])
    return Boundary(name, ends, hole, center=tuple(center))


def polygon(vertices, n_per_side, name="polygon", hole=False, side_names=None, center=None):
    """Polygon through ``vertices`` (in the order given, closed), each side cut into
    ``n_per_side`` (int, or one int per side) equal elements.  The order is *not* fixed up:
    :class:`Domain` refuses a hole given counter-clockwise or an outer boundary given clockwise.
    """
    v = np.asarray(vertices, dtype=float)
    m = len(v)
    ns = np.full(m, n_per_side, dtype=int) if np.isscalar(n_per_side) else np.asarray(n_per_side, dtype=int)
    ends, side = [], []
    for k in range(m):
        a, b = v[k], v[(k + 1) % m]
        s = np.arange(ns[k])[:, None] / ns[k]
        ends.append(a + s * (b - a))
        side.append(np.full(ns[k], k))
    names = tuple(side_names) if side_names is not None else tuple(f"side{k}" for k in range(m))
    return Boundary(name, np.vstack(ends), hole, np.concatenate(side), names, center)


def rectangle(x0, y0, x1, y1, n_per_side, name="rectangle", hole=False,
              side_names=("bottom", "right", "top", "left")):
    """Axis-aligned rectangle; counter-clockwise from (x0, y0) for an outer boundary, clockwise
    (reversed) for a hole.  Side names follow the geometric side, whatever the direction."""
    ns = [n_per_side] * 4 if np.isscalar(n_per_side) else list(n_per_side)
    if not hole:
        return polygon([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], ns, name, False, side_names)
    # clockwise: bottom-left → top-left → top-right → bottom-right
    b, r, t, l = side_names
    return polygon([(x0, y0), (x0, y1), (x1, y1), (x1, y0)], [ns[3], ns[2], ns[1], ns[0]], name, True,
                   (l, t, r, b))


def channel(length, half_width, n_length, n_width, x0=None):
    """Outer boundary of a channel |x| ≤ length/2, |y| ≤ half_width with sides named
    'bottom', 'outlet' (x = +length/2), 'top', 'inlet' (x = -length/2)."""
    xa = -0.5 * length if x0 is None else x0
    return rectangle(xa, -half_width, xa + length, half_width, [n_length, n_width, n_length, n_width],
                     name="channel", side_names=("bottom", "outlet", "top", "inlet"))


@dataclass
class Domain:
    """The fluid domain: one outer boundary and any number of holes, flattened into element and
    node arrays for the kernels.

    Arrays (E elements, 2E nodes; node 2e at η = -1/2 and 2e+1 at η = +1/2 of element e):
    ``a, b`` (E, 2) element ends [m]; ``length`` (E,) [m]; ``normal`` (E, 2) unit normal out of the
    fluid; ``tangent`` (E, 2); ``nodes`` (2E, 2) [m]; ``elem_boundary`` (E,) index into
    ``boundaries``; ``node_boundary`` (2E,).
    """

    boundaries: list
    a: np.ndarray = field(init=False)

    def __post_init__(self):
        self.check_orientation()
        bs = self.boundaries
        self.a = np.vstack([b.ends for b in bs])
        self.b = np.vstack([np.roll(b.ends, -1, axis=0) for b in bs])
        d = self.b - self.a
        self.length = np.hypot(d[:, 0], d[:, 1])
        if np.any(self.length <= 0):
            raise ValueError("zero-length element: repeated consecutive points in a boundary")
        self.tangent = d / self.length[:, None]
        self.normal = np.column_stack([self.tangent[:, 1], -self.tangent[:, 0]])
        self.elem_boundary = np.concatenate([np.full(b.n_elements, k) for k, b in enumerate(bs)])
        self.elem_side = np.concatenate([b.side for b in bs])
        self.nodes = np.empty((2 * len(self.a), 2))
        self.nodes[0::2] = 0.75 * self.a + 0.25 * self.b
        self.nodes[1::2] = 0.25 * self.a + 0.75 * self.b
        self.node_boundary = np.repeat(self.elem_boundary, 2)
        self.node_side = np.repeat(self.elem_side, 2)
        self.node_normal = np.repeat(self.normal, 2, axis=0)
        self.node_tangent = np.repeat(self.tangent, 2, axis=0)
        self.node_weight = np.repeat(0.5 * self.length, 2)  # ∫ N_m dΓ = L/2 (eq 4.48)

    @property
    def n_elements(self):
        return len(self.a)

    @property
    def n_nodes(self):
        return 2 * len(self.a)

    def index(self, name):
        for k, b in enumerate(self.boundaries):
            if b.name == name:
                return k
        raise KeyError(f"no boundary named {name!r}; boundaries: {[b.name for b in self.boundaries]}")

    def node_mask(self, where):
        """Nodes selected by a boundary name, a (boundary, side name) pair, or a boolean mask."""
        if isinstance(where, np.ndarray) and where.dtype == bool:
            return where
        if isinstance(where, str):
            return self.node_boundary == self.index(where)
        name, side = where
        k = self.index(name)
        names = self.boundaries[k].side_names
        if side not in names:
            raise KeyError(f"boundary {name!r} has no side {side!r}; sides: {names}")
        return (self.node_boundary == k) & (self.node_side == names.index(side))

    def check_orientation(self):
        """Thesis §4.3.8: exactly one outer boundary, counter-clockwise; holes clockwise, inside
        it and outside each other.  Raises ValueError naming the offending boundary."""
        outer = [b for b in self.boundaries if not b.hole]
        if len(outer) != 1:
            raise ValueError(f"a BEM domain needs exactly one outer boundary (hole=False); got {len(outer)}")
        names = [b.name for b in self.boundaries]
        if len(set(names)) != len(names):
            raise ValueError(f"boundary names must be unique: {names}")
        ob = outer[0]
        if ob.signed_area() <= 0:
            raise ValueError(f"outer boundary {ob.name!r} runs clockwise; thesis §4.3.8 requires "
                             "counter-clockwise numbering so the normal points out of the fluid")
        holes = [b for b in self.boundaries if b.hole]
        for h in holes:
            if h.signed_area() >= 0:
                raise ValueError(f"hole {h.name!r} runs counter-clockwise; thesis §4.3.8 requires "
                                 "clockwise numbering of internal boundaries")
            if not np.all(points_in_polygon(h.ends, ob.ends)):
                raise ValueError(f"hole {h.name!r} is not inside the outer boundary {ob.name!r}")
        for i, h in enumerate(holes):
            for g in holes[i + 1:]:
                if np.any(points_in_polygon(h.ends, g.ends)) or np.any(points_in_polygon(g.ends, h.ends)):
                    raise ValueError(f"holes {h.name!r} and {g.name!r} overlap")
