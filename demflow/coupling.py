"""The saturated (NePTune) step: the DEM coupled to the Stokes BEM (thesis §3.4, eq 4.39, §5.3.2).

Before each fluid solve (every ``stride`` DEM steps at most):

1. *Shrink* (thesis §3.4, Fig. 3.2; §5.3.3).  In 2D the pore fluid can split into pockets closed
   by contacts; NePTune shrinks the discs just enough to leave a gap ``g`` between neighbours and
   against the walls, so that the fluid is one domain with the discs as holes.  As in §5.3.3 the
   gap width is constant and only the discs that need it shrink: for a pair with centre distance
   d and r_i + r_j + g > d, each disc gives up the shortfall in proportion to its radius; against
   a wall at distance d_w, r_i' <= d_w - g.  A disc keeps the largest shrink any of its pairs
   asks for, so every gap is >= g.
2. *Remesh* from the current positions: the walls of ``Fluid.boundary`` (consecutive walls' lines
   meet at the corners) form the outer boundary, counter-clockwise; each disc is a clockwise
   inscribed regular polygon of its shrunk radius.  Wall elements are graded: near a disc they are
   as long as a disc element, far from every disc up to ``element_length``.
3. *Boundary conditions*: walls and discs carry their rigid velocities; a loaded wall
   (:class:`demflow.scene.WallLoad`) carries the unbalanced load F_A − F_C as a uniform normal
   traction (F_A − F_C)/L and its tangential velocity (thesis §5.3.2).
4. *Solve* (:mod:`demflow.bem`) and add the fluid force (and moment) on each disc, plus the
   buoyancy B = −ρ_l A g (thesis eq 4.39, A = πR² of the real disc), to the DEM force sums.  The
   solve uses positions x_i and velocities v_{i−1/2}: the half-step lag of thesis §3.4.  The
   force is held for the next k DEM steps.

Time step (thesis §5.2 found it "by trial and error").  Under a lagged explicit drag F = −K v a
disc's velocity obeys v ← v + kΔt(W − K v)/m between solves, which is stable only for
kΔt < 2τ with τ = m/K the relaxation time of its velocity under its drag (and monotone for
kΔt < τ).  K is the disc's self-resistance: measured by BEM unit-velocity solves at the start
(:meth:`FluidCoupler.self_resistance`) and raised by the growth of the exact one-wall resistance
4πμ/(α − tanh α), cosh α = d/R (:func:`wall_resistance`; long-ranged in 2D: a disc 2R from a wall
already feels several times its open-fluid drag) as the disc nears a wall, or a neighbour, which
is treated like a wall at the same gap (at small gaps that is the squeeze film 3√2π μ (R/h)^{3/2}).
Its spin likewise needs kΔt < 2I/K_rot (for a disc in an unbounded fluid K_rot = 4πμR², so
I/K_rot = m/8πμ, shorter than m/K: rotation is the binding limit of a free disc).
:meth:`FluidCoupler.stable_stride` gives the number of DEM steps between solves that keeps
kΔt <= safety·2τ; :meth:`FluidCoupler.time_step_bound` the bound a scene's Δt must meet (a wall
at the minimum gap), which build() enforces.

Units: the scene's consistent units; forces and moments per unit thickness.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from . import libm
from .bem.geometry import Boundary, Domain
from .bem.solve import Problem


def wall_resistance(mu, r, d):
    """Resistance of a cylinder of radius R translating towards a plane wall at centre distance d,
    4πμ/(α − tanh α) with cosh α = d/R (2D Stokes, exact for one wall; Jeffrey & Onishi 1981)
    [force/(length/time) per unit thickness].  Long-ranged (~4πμ/(ln(2d/R) − 1) far away) and
    3√2π μ (R/h)^{3/2} at a small gap h = d − R."""
    a = libm.arccosh(np.maximum(np.asarray(d, dtype=float) / r, 1.0 + 1e-12))
    return 4.0 * math.pi * mu / (a - libm.tanh(a))


def side_distances(x, y, corners):
    """(n, m) distance from each disc centre to each side of the outer polygon."""
    m = len(corners)
    return np.column_stack([_segment_distance(x, y, corners[k], corners[(k + 1) % m]) for k in range(m)])


@dataclass
class FluidSetup:
    """The checked fluid declaration (made by :func:`demflow.build.build`)."""

    mu: float
    rho: float
    boundary: np.ndarray  # wall indices, counter-clockwise
    n_disc: int
    element_length: float
    gap: float
    stride: int
    adaptive: bool
    safety: float
    moments: bool
    load_wall: np.ndarray  # wall index per load
    load_force: np.ndarray
    load_dir: np.ndarray  # (nl, 2)
    record_every: int
    quadrature: int
    start: int = 0  # first step with the fluid present (thesis §5.3.3, §5.5.4: liquid added after a dry stage)


def wall_lines(sim, setup):
    """Point A and unit direction e of each boundary wall's line, in boundary order."""
    ax, ay, bx, by = sim.wall_endpoints()
    w = setup.boundary
    p = np.column_stack([ax[w], ay[w]])
    e = np.column_stack([sim.wex[w], sim.wey[w]])
    return p, e


def outer_corners(p, e):
    """Corners of the outer boundary: corner k is where line k-1 meets line k (side k runs from
    corner k to corner k+1).  Raises ValueError for parallel consecutive walls."""
    m = len(p)
    v = np.zeros((m, 2))
    for k in range(m):
        j = (k - 1) % m
        den = e[j, 0] * e[k, 1] - e[j, 1] * e[k, 0]
        if abs(den) < 1e-12:
            raise ValueError("consecutive boundary walls are parallel: their lines do not meet at a corner")
        d = p[k] - p[j]
        t = (d[0] * e[k, 1] - d[1] * e[k, 0]) / den
        v[k] = p[j] + t * e[j]
    return v


def _segment_distance(px, py, a, b):
    d = b - a
    L2 = float(d @ d)
    s = np.clip(((px - a[0]) * d[0] + (py - a[1]) * d[1]) / L2, 0.0, 1.0)
    return np.hypot(a[0] + s * d[0] - px, a[1] + s * d[1] - py)


def shrunk_radii(x, y, r, corners, gap):
    """Radii r' <= r leaving at least ``gap`` between discs and against the outer polygon
    (thesis §3.4, §5.3.3; see the module docstring).  Returns (r', smallest gap to a wall per
    disc, pairs (i, j, gap) of discs closer than r_i + r_j after shrinking)."""
    n = x.shape[0]
    shrink = np.zeros(n)
    m = len(corners)
    dwall = np.full(n, np.inf)
    for k in range(m):
        dk = _segment_distance(x, y, corners[k], corners[(k + 1) % m])
        dwall = np.minimum(dwall, dk)
    shrink = np.maximum(shrink, r + gap - dwall)
    # disc pairs (brute force over a cell-free O(n²) sweep is fine for the BEM's disc counts)
    dx = x[:, None] - x[None, :]
    dy = y[:, None] - y[None, :]
    d = np.hypot(dx, dy)
    np.fill_diagonal(d, np.inf)
    rs = r[:, None] + r[None, :]
    short = rs + gap - d
    i, j = np.nonzero(np.triu(short > 0, 1))
    for a, b in zip(i, j):
        s = short[a, b]
        shrink[a] = max(shrink[a], s * r[a] / rs[a, b])
        shrink[b] = max(shrink[b], s * r[b] / rs[a, b])
    rp = r - shrink
    bad = np.flatnonzero(rp < 0.5 * r)
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"disc {k} would shrink to {rp[k]:.4g} (< half its radius {r[k]:.4g}) to leave the "
                         f"fluid gap {gap:.4g}: it overlaps a neighbour or a wall too much")
    return rp, dwall - rp, d


def _graded_side(a, b, h_of, h_max):
    """Points from a (included) towards b (excluded) with local spacing min(h_max, h_of(point)),
    rescaled so that the last element ends at b; at least two elements."""
    L = float(np.hypot(*(b - a)))
    e = (b - a) / L
    s = [0.0]
    while s[-1] < L:
        s.append(s[-1] + min(h_max, h_of(a + s[-1] * e)))
    s = np.array(s)
    if len(s) < 3:
        s = np.array([0.0, 0.5 * L, L])
    s = s[:-1] * (L / s[-1])
    return a + s[:, None] * e


class FluidCoupler:
    """Builds and solves the fluid problem of a :class:`~demflow.simulation.Simulation` (see the
    module docstring); holds the timings and the records."""

    def __init__(self, sim, setup: FluidSetup):
        self.setup = setup
        self.names = [sim.wall_names[w] for w in setup.boundary]
        self.solves = 0
        self.bem_s = 0.0
        self.K0 = None  # self-resistance of each disc, initial configuration (time step, adaptive stride)
        self.K0rot = None
        self.records = []  # (step, forces (n, 3), wall fluid force (nb, 2), disc velocities seen and positions (n, 5))
        self.strides = []  # (step, DEM steps to the next solve)
        self.pressure = []  # (step, wall name, x, y, s, p)
        self.last_r = None
        self.last_solution = None

    # ------------------------------------------------------------------ geometry
    def domain(self, sim):
        """The BEM domain at the current positions: (Domain, shrunk radii, min wall gap per disc, distances)."""
        st = self.setup
        p, e = wall_lines(sim, st)
        corners = outer_corners(p, e)
        rp, gw, dist = shrunk_radii(sim.x, sim.y, sim.r, corners, st.gap)
        self.last_corners = corners
        h_disc = 2 * math.pi * float(rp.max()) / st.n_disc if sim.n else st.element_length
        xs, ys = sim.x, sim.y

        def h_of(q):
            if sim.n == 0:
                return st.element_length
            dd = np.hypot(xs - q[0], ys - q[1]) - rp
            return max(2 * math.pi * float(rp.min()) / st.n_disc, 0.7 * float(dd.min()), h_disc)

        ends, side = [], []
        m = len(corners)
        for k in range(m):
            pts = _graded_side(corners[k], corners[(k + 1) % m], h_of, st.element_length)
            ends.append(pts)
            side.append(np.full(len(pts), k))
        outer = Boundary("outer", np.vstack(ends), False, np.concatenate(side), tuple(self.names))
        holes = []
        for i in range(sim.n):
            th = -2 * np.pi * np.arange(st.n_disc) / st.n_disc
            holes.append(Boundary(f"d{i}", np.column_stack([xs[i] + rp[i] * libm.cos(th), ys[i] + rp[i] * libm.sin(th)]),
                                  True, center=(float(xs[i]), float(ys[i]))))
        return Domain([outer] + holes), rp, gw, dist

    # ------------------------------------------------------------------ problem
    def problem(self, sim, dom):
        st = self.setup
        pb = Problem(dom, st.mu)
        for k, w in enumerate(st.boundary):
            vx, vy, om, cx, cy = sim.wvx[w], sim.wvy[w], sim.wom[w], sim.wcx[w], sim.wcy[w]
            pb.velocity(("outer", self.names[k]),
                        lambda X, Y, vx=vx, vy=vy, om=om, cx=cx, cy=cy: (vx - om * (Y - cy), vy + om * (X - cx)))
        for i in range(sim.n):
            pb.rigid(f"d{i}", U=(sim.vx[i], sim.vy[i]), omega=sim.om[i], center=(sim.x[i], sim.y[i]))
        for q, w in enumerate(st.load_wall):
            d = st.load_dir[q]
            F_C = -(sim.wall_force[w, 0] * d[0] + sim.wall_force[w, 1] * d[1])
            L = sim.wh2[w] - sim.wh1[w]
            k = list(st.boundary).index(w)
            side_len = self._side_length(dom, k)
            L = side_len if side_len > 0 else L
            c = int(np.argmax(np.abs(d)))
            val = (st.load_force[q] - F_C) / L * d
            pb.traction(("outer", self.names[k]), value=tuple(val), components=(c,))
        return pb

    @staticmethod
    def _side_length(dom, k):
        sel = (dom.elem_boundary == 0) & (dom.elem_side == k)
        return float(dom.length[sel].sum())

    # ------------------------------------------------------------------ solve
    def solve(self, sim, record=True):
        """Solve the fluid at the current state; returns (n, 3) fluid force and moment per disc."""
        st = self.setup
        t0 = time.perf_counter()
        dom, rp, gw, dist = self.domain(sim)
        pb = self.problem(sim, dom)
        sol = pb.solve(quad=st.quadrature)
        out = np.zeros((sim.n, 3))
        for i in range(sim.n):
            out[i, :2] = sol.force(f"d{i}")
            if st.moments:
                out[i, 2] = sol.moment(f"d{i}")
        self.bem_s += time.perf_counter() - t0
        self.solves += 1
        self.last_r, self.last_gw, self.last_dist, self.last_solution = rp, gw, dist, sol
        if record and (self.solves - 1) % st.record_every == 0:
            self._record(sim, dom, sol, out)
        return out

    def _record(self, sim, dom, sol, out):
        wf = np.zeros((len(self.names), 2))
        p = sol.boundary_pressure()
        for k, name in enumerate(self.names):
            e = np.flatnonzero((dom.elem_boundary == 0) & (dom.elem_side == k))
            tm = 0.5 * (sol.t[2 * e] + sol.t[2 * e + 1])
            wf[k] = -np.sum(tm * dom.length[e][:, None], axis=0)
            nodes = np.flatnonzero((dom.node_boundary == 0) & (dom.node_side == k))
            xy = dom.nodes[nodes]
            a = dom.a[e[0]]
            s = np.hypot(xy[:, 0] - a[0], xy[:, 1] - a[1])
            self.pressure.append((sim.step, name, xy[:, 0].copy(), xy[:, 1].copy(), s, p[nodes].copy()))
        self.records.append((sim.step, out.copy(), wf, np.column_stack([sim.vx, sim.vy, sim.om, sim.x, sim.y])))

    # ------------------------------------------------------------------ time step
    def self_resistance(self, sim):
        """(K, K_rot) per disc: K [force/(length/time)] the larger eigenvalue of the disc's 2×2
        translational self-resistance (force on disc i for unit velocity of disc i, everything else
        at rest) and K_rot [force·length·time] its rotational self-resistance (moment for unit ω),
        by BEM solves in the current shrunk configuration (three per disc)."""
        dom, rp, _, d = self.domain(sim)
        self.h0_pairs = np.maximum(d - (rp[:, None] + rp[None, :]), self.setup.gap)
        self.d0_walls = np.maximum(side_distances(sim.x, sim.y, self.last_corners), rp[:, None] + self.setup.gap)
        K = np.zeros(sim.n)
        Kr = np.zeros(sim.n)
        for i in range(sim.n):
            R = np.zeros((2, 2))
            c_i = (sim.x[i], sim.y[i])
            for c in range(2):
                pb = Problem(dom, self.setup.mu)
                pb.rigid(f"d{i}", U=(1.0, 0.0) if c == 0 else (0.0, 1.0), center=c_i)
                R[:, c] = -pb.solve(quad=self.setup.quadrature).force(f"d{i}")
            K[i] = float(np.max(np.linalg.eigvalsh(0.5 * (R + R.T))))
            if self.setup.moments:
                pb = Problem(dom, self.setup.mu)
                pb.rigid(f"d{i}", omega=1.0, center=c_i)
                Kr[i] = -pb.solve(quad=self.setup.quadrature).moment(f"d{i}", center=c_i)
        return K, Kr

    def _taus(self, sim, K):
        """Relaxation time per disc [time]: min(m/K, I/K_rot) (rotation only when moments apply)."""
        tau = sim.mass / np.maximum(K, 1e-300)
        if self.setup.moments:
            tau = np.minimum(tau, sim.inertia / np.maximum(self.K0rot, 1e-300))
        return tau

    def resistance_estimate(self, sim):
        """Current self-resistance per disc: the measured K0 (first solve) plus the growth since then
        of the exact one-wall resistance (:func:`wall_resistance`) for each wall and for each other
        disc, treated as a wall at the current gap (BEM geometry).  For a neighbour this is
        conservative: at small gaps it is √2 × the squeeze resistance of two equal discs, and it
        reaches the long range of 2D Stokes interactions (discs passing each other 1-2 radii
        apart oscillated at a stride the near-contact lubrication term alone allowed)."""
        st = self.setup
        if self.K0 is None:
            self.K0, self.K0rot = self.self_resistance(sim)
        K = self.K0.copy()
        rp, d = self.last_r, self.last_dist
        dw = np.maximum(side_distances(sim.x, sim.y, self.last_corners), rp[:, None] + st.gap)
        grow = wall_resistance(st.mu, rp[:, None], dw) - wall_resistance(st.mu, rp[:, None], self.d0_walls)
        K += np.sum(np.maximum(grow, 0.0), axis=1)
        if sim.n > 1:
            h = np.maximum(d - (rp[:, None] + rp[None, :]), st.gap)
            grow = wall_resistance(st.mu, rp[:, None], rp[:, None] + h) - \
                wall_resistance(st.mu, rp[:, None], rp[:, None] + self.h0_pairs)
            np.fill_diagonal(grow, 0.0)
            K += np.sum(np.maximum(grow, 0.0), axis=1)
        return K

    def time_step_bound(self, sim):
        """The largest DEM Δt [time] the lagged explicit drag tolerates anywhere in the run:
        safety × 2 min_i τ_i with τ_i = min(m_i / (K0_i + K_w(R_i + g)), I_i / K0rot_i), K0 the
        measured self-resistance of the initial configuration and K_w the resistance
        (:func:`wall_resistance`) of a wall at the minimum gap g (the closest a disc's BEM boundary can come to a wall, see
        the module docstring)."""
        st = self.setup
        if sim.n == 0:
            return math.inf
        if self.K0 is None:
            self.K0, self.K0rot = self.self_resistance(sim)
        Kw = self.K0 + wall_resistance(st.mu, sim.r, sim.r + st.gap)
        return st.safety * 2.0 * float(np.min(self._taus(sim, Kw)))

    def stable_stride(self, sim):
        """DEM steps until the next solve: the largest k <= stride with kΔt <= safety·2·min τ_i,
        τ_i = m_i/K_i (see the module docstring); at least 1."""
        st = self.setup
        if not st.adaptive or sim.n == 0:
            return st.stride
        K = self.resistance_estimate(sim)
        tau = float(np.min(self._taus(sim, K)))
        self.last_tau = tau
        k = int(st.safety * 2.0 * tau / sim.dt)
        return max(1, min(st.stride, k))

