"""Quadrature rules for the boundary integrals (thesis §4.3.4.6-4.3.4.7).

* Gauss-Legendre rules of 1, 2, 4, 8, 16, 32 and 64 points on [-1, 1], stored as padded tables
  so Numba kernels can index them (thesis eqs 4.58-4.59).
* Table 4.1 of the thesis: the number of points N_g chosen from ϱ = r_min / L (eq 4.60).
* A logarithmic Gauss rule for ∫_0^1 ln(1/ξ) f(ξ) dξ (thesis eqs 4.70, 4.74: "a suitable
  logarithmic quadrature"), exact for polynomials f of degree ≤ 2n - 1.  Its nodes come from the
  Stieltjes procedure on a discretisation of the measure ln(1/ξ) dξ that is exact to round-off
  (geometrically graded composite Gauss), followed by Golub-Welsch.

Quadrature modes used across :mod:`demflow.bem` (an ``int``):
``TABLE = 0`` Table 4.1; ``FINE = -1`` near-singular-safe rule (the element is split into pieces
graded geometrically towards the point closest to the source so that every piece is at least its
own length away, then 16/8/4 points by the piece's ϱ: round-off accuracy at any distance);
``n > 0`` an n-point rule everywhere (n in 1, 2, 4, 8, 16, 32, 64), for convergence studies.
"""
from __future__ import annotations

import numpy as np

from .. import libm
from ..jit import njit

TABLE = 0
FINE = -1
ORDERS = np.array([1, 2, 4, 8, 16, 32, 64], dtype=np.int64)


def _gauss_tables():
    gx = np.zeros((len(ORDERS), ORDERS[-1]))
    gw = np.zeros((len(ORDERS), ORDERS[-1]))
    for k, n in enumerate(ORDERS):
        x, w = np.polynomial.legendre.leggauss(int(n))
        gx[k, :n], gw[k, :n] = x, w
    return gx, gw


GX, GW = _gauss_tables()


def log_gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the n-point rule ∫_0^1 ln(1/ξ) f(ξ) dξ ≈ Σ w_l f(ξ_l).

    The measure is discretised exactly to round-off by 40-point Gauss rules on the intervals
    [2^-(j+1), 2^-j], j = 0..80 (ln is smooth on each), the three-term recurrence is obtained by
    the (discretised) Stieltjes procedure and the rule by Golub-Welsch.  Checked in the tests
    against the moments ∫_0^1 ln(1/ξ) ξ^k dξ = 1/(k+1)^2.
    """
    gx, gw = np.polynomial.legendre.leggauss(40)
    xs, ws = [], []
    for j in range(80):
        a, b = 2.0 ** -(j + 1), 2.0 ** -j
        x = 0.5 * (a + b) + 0.5 * (b - a) * gx
        xs.append(x)
        ws.append(0.5 * (b - a) * gw * libm.log(1.0 / x))
    x = np.concatenate(xs)
    w = np.concatenate(ws)
    alpha = np.zeros(n)
    beta = np.zeros(n)
    p_prev = np.zeros_like(x)
    p = np.ones_like(x)
    norm_prev = 1.0
    for k in range(n):
        norm = np.sum(w * p * p)
        alpha[k] = np.sum(w * x * p * p) / norm
        beta[k] = norm / norm_prev if k > 0 else norm
        p_next = (x - alpha[k]) * p - (beta[k] if k > 0 else 0.0) * p_prev
        p_prev, p, norm_prev = p, p_next, norm
    J = np.diag(alpha) + np.diag(np.sqrt(beta[1:]), 1) + np.diag(np.sqrt(beta[1:]), -1)
    nodes, vecs = np.linalg.eigh(J)
    weights = beta[0] * vecs[0, :] ** 2
    return nodes, weights


LOG_N = 8
LX, LW = log_gauss(LOG_N)


@njit
def order_index(n):
    """Row of GX/GW holding the n-point Gauss rule (n a power of two ≤ 64)."""
    for k in range(ORDERS.shape[0]):
        if ORDERS[k] == n:
            return k
    return ORDERS.shape[0] - 1


@njit
def table_4_1(rho):
    """Number of Gauss points N_g for ϱ = r_min / L by thesis Table 4.1 (eq 4.60)."""
    if rho > 200.0:
        return 1
    if rho > 20.0:
        return 2
    if rho > 2.0:
        return 4
    if rho > 0.1:
        return 16
    return 32


@njit
def fine_order(rho):
    """Points for one piece of the FINE rule, whose pieces all have ϱ ≥ 1: with the Bernstein
    ellipse parameter ρ_E ≈ 4ϱ the Gauss error ~ ρ_E^(-2n) stays below 1e-15."""
    if rho > 20.0:
        return 4
    if rho > 2.0:
        return 8
    return 16
