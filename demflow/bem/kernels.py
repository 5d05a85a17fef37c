"""Fundamental solutions of 2D Stokes flow (thesis §4.3.1, §4.3.6).

u* and t* are evaluated inline in the element integrals of :mod:`demflow.bem.assembly`; this
module holds the stress kernels D and S of the interior stress (eq 4.93).

Convention (thesis eq 4.22): P is the source (collocation or interior) point, Q the field point
on the boundary, r_i = x_i(Q) - x_i(P), r = |r|, r̂_i = r_{,i} = r_i / r; n is the unit normal at Q
pointing out of the fluid.  Units: lengths [m], μ [Pa s].

* u*_ij = (1/4πμ) (ln(1/r) δ_ij + r̂_i r̂_j)                     thesis eq 4.20   [1/(Pa s)]
* t*_ij = -(1/πr) (∂r/∂n) r̂_i r̂_j                               thesis eq 4.21   [1/m]
* D_kij = (1/πr) r̂_i r̂_j r̂_k                                    thesis eq 4.94   [1/m]
* S_kij = μ/(πr²) { ∂r/∂n (δ_ik r̂_j + δ_jk r̂_i - 8 r̂_i r̂_j r̂_k)
                     + n_i r̂_j r̂_k + n_j r̂_i r̂_k + n_k δ_ij }      eq 4.95 corrected [Pa s/m²]

so that σ_ij(P) = ∫ D_kij t_k dΓ - ∫ S_kij u_k dΓ (eq 4.93).  The thesis prints -4 r̂_i r̂_j r̂_k in
eq 4.95 (and the same slip in its elastic parent, eq 4.91, where the ν'-factor was put on the
whole bracket; Brebbia's S_kij has 2∂r/∂n[(1-2ν)δ_ij r̂_k + ν(δ_ik r̂_j + δ_jk r̂_i) - 4 r̂_i r̂_j r̂_k],
which at ν = 1/2 gives -8).  The printed form violates the exact stress of known Stokes flows
(tests/test_bem.py); ``printed=True`` reproduces it for that demonstration.
Eq 4.94 is correct as printed.
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import njit

INV_PI = 1.0 / math.pi


@njit
def stress_kernels(rx, ry, nx, ny, mu, printed):
    """D_kij and S_kij (thesis eqs 4.94, 4.95) as two arrays indexed [k, i, j].

    ``printed=True`` uses the coefficient -4 printed in eq 4.95 instead of the correct -8.
    """
    r = math.hypot(rx, ry)
    e = np.array([rx / r, ry / r])
    n = np.array([nx, ny])
    drdn = e[0] * n[0] + e[1] * n[1]
    c8 = 4.0 if printed else 8.0
    D = np.empty((2, 2, 2))
    S = np.empty((2, 2, 2))
    cd = INV_PI / r
    cs = mu * INV_PI / (r * r)
    for k in range(2):
        for i in range(2):
            for j in range(2):
                dik = 1.0 if i == k else 0.0
                djk = 1.0 if j == k else 0.0
                dij = 1.0 if i == j else 0.0
                D[k, i, j] = cd * e[i] * e[j] * e[k]
                S[k, i, j] = cs * (drdn * (dik * e[j] + djk * e[i] - c8 * e[i] * e[j] * e[k])
                                   + n[i] * e[j] * e[k] + n[j] * e[i] * e[k] + n[k] * dij)
    return D, S
