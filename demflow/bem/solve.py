"""Boundary conditions, the linear system and its solution (thesis eqs 4.5, 4.49-4.55).

Units: lengths [m], velocities [m/s], μ [Pa s], tractions and stresses [Pa], forces per unit
thickness [N/m], moments per unit thickness [N].

Two things the thesis leaves implicit are handled explicitly here.

*Scale.*  The 2D Stokeslet has ln(1/r): for one "degenerate" size of a boundary (a circle of radius
√e for the single layer) the first-kind operator G is singular.  The system is therefore solved
in coordinates scaled by ℓ, the diagonal of the domain's bounding box (x' = x/ℓ, t' = ℓ t,
velocities unchanged), which keeps every boundary well below that size; results are scaled back.

*Pressure null space.*  If the normal velocity is prescribed all around a closed boundary Γ_k,
t + c n|Γ_k satisfies the boundary equation as well as t does (the Stokeslet is solenoidal, so
∮_Γk u*_ij n_j dΓ = 0).  For the outer boundary this is the physical p_0 (the traction is known
up to -p_0 n); for a hole it is spurious.  Neither changes a force or moment (∮ n dΓ = 0 and
∮ x × n dΓ = 0 exactly on a closed polygon), but they make [A] singular up to discretisation error.
Each such mode gets a Lagrange multiplier (bordered system): a column w_k (n times the node
weight L/2 on Γ_k) and a gauge row: for a hole, the exterior null-field identity - the pressure
represented by eqs 4.93-4.96 at a point inside the hole vanishes for the true solution; for the
outer boundary, the mean boundary pressure (eqs 4.97-4.105) along it equals ``p_ref`` (or the
pressure at a given interior point does).  When every boundary carries such a mode the domain is
closed to flux, and the prescribed velocities must satisfy ∮ u·n dΓ = 0: a problem that does not
is refused.  The multipliers (≈ discretisation error) are reported as ``Solution.multipliers``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from .assembly import assemble_HG, assemble_system, interior_fields, pressure_coefficients
from .geometry import Domain, points_in_polygon
from .quadrature import FINE, TABLE


class IncompatibleFluxError(ValueError):
    """The prescribed velocities put a net flux through a closed incompressible domain."""


class Problem:
    """Boundary conditions per node and component (eq 4.5) on a :class:`Domain`.

    Everything starts as zero velocity (no slip on fixed walls).  ``where`` is a boundary name,
    a (boundary name, side name) pair, or a boolean node mask; ``value`` a constant pair or a
    function f(x, y) → (vx, vy) of node coordinates [m].
    """

    def __init__(self, domain: Domain, mu: float = 1.0):
        if mu <= 0:
            raise ValueError(f"viscosity mu must be > 0 [Pa s], got {mu}")
        self.domain = domain
        self.mu = float(mu)
        self.traction_given = np.zeros((domain.n_nodes, 2), dtype=bool)
        self.value = np.zeros((domain.n_nodes, 2))

    def _set(self, where, value, traction, components):
        mask = self.domain.node_mask(where)
        pts = self.domain.nodes[mask]
        if callable(value):
            v = np.asarray(value(pts[:, 0], pts[:, 1]), dtype=float)
            v = v.T if v.shape == (2, len(pts)) else v
        else:
            v = np.broadcast_to(np.asarray(value, dtype=float), (len(pts), 2))
        for c in components:
            self.traction_given[mask, c] = traction
            self.value[mask, c] = v[:, c]
        return self

    def velocity(self, where, value=(0.0, 0.0), components=(0, 1)):
        """Prescribe velocity [m/s] (Γ_1 of eq 4.5)."""
        return self._set(where, value, False, components)

    def traction(self, where, value=(0.0, 0.0), components=(0, 1)):
        """Prescribe traction t = σ n [Pa], n out of the fluid (Γ_2 of eq 4.5)."""
        return self._set(where, value, True, components)

    def rigid(self, name, U=(0.0, 0.0), omega=0.0, center=None):
        """Rigid-body velocity U + Ω × (x - c) of boundary ``name`` (U [m/s], Ω [rad/s])."""
        c = self.domain.boundaries[self.domain.index(name)].center if center is None else center
        return self.velocity(name, lambda x, y: (U[0] - omega * (y - c[1]), U[1] + omega * (x - c[0])))

    def matrices(self, quad=TABLE):
        """[H], [G] of eq 4.53 in physical coordinates (for checks on small problems)."""
        d = self.domain
        return assemble_HG(d.nodes, d.a, d.tangent, d.normal, d.length, int(quad), self.mu)

    def net_flux(self):
        """∮ u·n dΓ [m²/s] of the prescribed velocities (exact for the linear interpolation)."""
        d = self.domain
        un = np.sum(self.value * d.node_normal, axis=1)
        return float(np.sum(d.node_weight * un)), float(np.sum(d.node_weight * np.abs(un)))

    def solve(self, quad=TABLE, p_ref=0.0, pressure_point=None, flux_rtol=1e-6):
        """Assemble [A]Y = R (eq 4.55), add the null-space constraints, solve by LU (LAPACK).

        ``quad``: 0 Table 4.1, -1 FINE, n > 0 fixed n-point Gauss.  ``p_ref`` [Pa]: the mean
        pressure along the outer boundary (or, with ``pressure_point=(x, y)``, the pressure there)
        when the pressure level is otherwise undetermined.
        """
        d = self.domain
        t0 = time.perf_counter()
        ell = float(np.hypot(*(np.ptp(d.a, axis=0))))
        tg = self.traction_given.ravel()
        val = self.value.ravel().copy()
        val[tg] *= ell  # t' = ℓ t
        nodes, a, L = d.nodes / ell, d.a / ell, d.length / ell
        A, R = assemble_system(nodes, a, d.tangent, d.normal, L, int(quad), self.mu, tg, val)
        t1 = time.perf_counter()

        # null-space modes: boundaries whose normal velocity is prescribed all around
        nrm = d.node_normal
        modes = []
        for k in range(len(d.boundaries)):
            sel = d.node_boundary == k
            need = np.abs(nrm[sel]) > 1e-12
            if not np.any(self.traction_given[sel][need]):
                modes.append(k)
        if len(modes) == len(d.boundaries):
            flux, scale = self.net_flux()
            if abs(flux) > flux_rtol * scale + 1e-300:
                raise IncompatibleFluxError(
                    f"prescribed velocities give a net flux ∮u·n dΓ = {flux:.6g} m²/s (relative {flux / scale:.3g}) "
                    "out of a closed domain of incompressible fluid: no Stokes flow satisfies them. "
                    "Make inflow and outflow balance, or prescribe traction on part of the boundary.")
        n_dof = 2 * d.n_nodes
        K = len(modes)
        Wc = np.zeros((n_dof, K))
        Cr = np.zeros((K, n_dof))
        dr = np.zeros(K)
        for j, k in enumerate(modes):
            sel = np.repeat(d.node_boundary == k, 2)
            Wc[sel, j] = (nrm * (d.node_weight / ell)[:, None]).ravel()[sel]
            b = d.boundaries[k]
            if b.hole:
                cT, cU, const = self._hole_gauge(b, ell, nodes, a, L)
            else:
                cT, cU, const = self._outer_gauge(k, ell, p_ref, pressure_point, nodes, a, L)
            # p = cT·T + cU·U + const = 0 in the unknowns Y (T where velocity given, U where traction given)
            Cr[j] = np.where(tg, cU, cT)
            dr[j] = -(np.sum(np.where(tg, cT, cU) * val) + const)
        M = np.zeros((n_dof + K, n_dof + K))
        M[:n_dof, :n_dof] = A
        M[:n_dof, n_dof:] = Wc
        M[n_dof:, :n_dof] = Cr
        rhs = np.concatenate([R, dr])
        t2 = time.perf_counter()
        lu = scipy.linalg.lu_factor(M, overwrite_a=True, check_finite=False)
        Y = scipy.linalg.lu_solve(lu, rhs, check_finite=False)
        t3 = time.perf_counter()
        U = np.where(tg, Y[:n_dof], self.value.ravel())
        T = np.where(tg, self.value.ravel(), Y[:n_dof] / ell)
        return Solution(self, U.reshape(-1, 2), T.reshape(-1, 2), quad,
                        multipliers=Y[n_dof:], modes=[d.boundaries[k].name for k in modes],
                        assembly_s=(t1 - t0) + (t2 - t1), solve_s=t3 - t2, n_unknowns=n_dof)

    def _hole_gauge(self, b, ell, nodes, a, L):
        d = self.domain
        c = np.asarray(b.center, dtype=float)
        if not points_in_polygon(c[None, :], b.ends)[0]:
            k = int(np.argmax(d.length * (d.elem_boundary == d.index(b.name))))
            c = 0.5 * (d.a[k] + d.b[k]) + 0.25 * d.length[k] * d.normal[k]
        cT, cU = pressure_coefficients(c[0] / ell, c[1] / ell, a, d.tangent, d.normal, L, self.mu)
        return cT, cU, 0.0

    def _outer_gauge(self, k, ell, p_ref, pressure_point, nodes, a, L):
        d = self.domain
        if pressure_point is not None:
            cT, cU = pressure_coefficients(pressure_point[0] / ell, pressure_point[1] / ell, a, d.tangent,
                                           d.normal, L, self.mu)
            return cT, cU, -p_ref * ell
        # mean boundary pressure on Γ_k: p_i = -n·t_i - 2μ ε_ss (corrected eq 4.105), weights L/2
        n_dof = 2 * d.n_nodes
        cT = np.zeros(n_dof)
        cU = np.zeros(n_dof)
        sel = np.flatnonzero(d.node_boundary == k)
        wsum = np.sum(d.node_weight[sel] / ell)
        for i in sel:
            e = i // 2
            w = d.node_weight[i] / ell / wsum
            cT[2 * i:2 * i + 2] -= w * d.normal[e]
            # ε_ss = (2/L)(u(P2) - u(P1))·τ  (eq 4.97)
            g = 2.0 / L[e] * d.tangent[e]
            cU[4 * e + 2:4 * e + 4] -= 2 * self.mu * w * g
            cU[4 * e:4 * e + 2] += 2 * self.mu * w * g
        return cT, cU, -p_ref * ell


@dataclass
class Solution:
    """Nodal velocities ``u`` [m/s] and tractions ``t`` [Pa] (t = σ n, n out of the fluid), shape
    (2E, 2), with the quantities derived from them (thesis §4.3.6-4.3.9)."""

    problem: Problem
    u: np.ndarray
    t: np.ndarray
    quad: int
    multipliers: np.ndarray = None
    modes: list = field(default_factory=list)
    assembly_s: float = 0.0
    solve_s: float = 0.0
    n_unknowns: int = 0

    @property
    def domain(self):
        return self.problem.domain

    def _elems(self, name):
        return np.flatnonzero(self.domain.elem_boundary == self.domain.index(name))

    def force(self, name):
        """Force per unit thickness [N/m] the fluid exerts on boundary ``name``: -∮ t dΓ with t the
        traction on the fluid.  Thesis eqs 4.106-4.107 sum (t(P1) + t(P2))/2 L, the exact integral
        of the linear interpolation, with the traction taken on the solid (opposite sign)."""
        d = self.domain
        e = self._elems(name)
        tm = 0.5 * (self.t[2 * e] + self.t[2 * e + 1])
        return -np.sum(tm * d.length[e][:, None], axis=0)

    def moment(self, name, center=None):
        """Moment per unit thickness [N] of the fluid on boundary ``name`` about ``center``
        (default: the boundary's centre): -∮ (x - c) × t dΓ, integrated exactly (two-point Gauss on
        a quadratic).  Thesis eq 4.108 prints t_x d_y + t_y d_x; the moment is d_x t_y - d_y t_x."""
        d = self.domain
        b = d.boundaries[d.index(name)]
        c = np.asarray(b.center if center is None else center, dtype=float)
        e = self._elems(name)
        M = 0.0
        for g in (-1 / np.sqrt(3), 1 / np.sqrt(3)):
            x = 0.5 * (1 - g) * d.a[e] + 0.5 * (1 + g) * d.b[e] - c
            tt = (0.5 - g) * self.t[2 * e] + (0.5 + g) * self.t[2 * e + 1]
            M += np.sum((x[:, 0] * tt[:, 1] - x[:, 1] * tt[:, 0]) * 0.5 * d.length[e])
        return -M

    def strain_ss(self):
        """ε_ss = ∂u_s/∂s along each element (thesis eq 4.97), per node [1/s]."""
        d = self.domain
        du = self.u[1::2] - self.u[0::2]
        e = 2.0 / d.length * np.sum(du * d.tangent, axis=1)
        return np.repeat(e, 2)

    def boundary_pressure(self, printed=False):
        """Pressure at the nodes [Pa] (thesis eqs 4.97-4.105, corrected).

        In the element frame (s along τ, n out of the fluid): σ_ns = t·τ, σ_nn = t·n, and
        incompressibility on a straight element gives ε_nn = -ε_ss, so σ_nn = -p + 2μ ε_nn and
        p = -t·n - 2μ ε_ss.  The thesis's eq 4.105 prints p = -σ_22 + μ ε_22 (a factor 2 is lost
        from eq 4.103); ``printed=True`` evaluates that form (and its eqs 4.98-4.99 label the
        traction components σ_11, σ_12 where σ_12, σ_22 are meant).
        """
        tn = np.sum(self.t * self.domain.node_normal, axis=1)
        f = 1.0 if printed else 2.0
        return -tn - f * self.problem.mu * self.strain_ss()

    def shear_traction(self):
        """Tangential traction t·τ [Pa] at the nodes (τ along the boundary's numbering)."""
        return np.sum(self.t * self.domain.node_tangent, axis=1)

    def interior_velocity(self, points, quad=FINE):
        """Velocity [m/s] only at interior points (eq 4.92) - cheaper than :meth:`interior`."""
        d = self.domain
        pts = np.ascontiguousarray(np.atleast_2d(points), dtype=float)
        return interior_fields(pts, d.a, d.tangent, d.normal, d.length, int(quad), self.problem.mu,
                               self.u.ravel(), self.t.ravel(), -1)[0]

    def combine(self, other, alpha=1.0, beta=1.0):
        """α·self + β·other: superposition of two solutions on the same domain (Stokes is linear)."""
        return Solution(self.problem, alpha * self.u + beta * other.u, alpha * self.t + beta * other.t, self.quad)

    def interior(self, points, quad=FINE, printed=False):
        """Velocity [m/s], stress (σ_xx, σ_xy, σ_yy) [Pa] and pressure [Pa] at interior points
        (thesis eqs 4.92-4.96).  FINE quadrature by default, so points may lie close to walls."""
        d = self.domain
        pts = np.ascontiguousarray(np.atleast_2d(points), dtype=float)
        uo, so = interior_fields(pts, d.a, d.tangent, d.normal, d.length, int(quad), self.problem.mu,
                                 self.u.ravel(), self.t.ravel(), 1 if printed else 0)
        p = -0.5 * (so[:, 0] + so[:, 2])
        return uo, so, p
