"""Linear spring-dashpot-Coulomb contact law for one contact (thesis §2.2.4.2, C&S eqs 8-27).

Sign conventions (thesis §2.2.4.1, C&S Fig. 3): ε is the unit vector from disc α (the
pair's finder) to β (the other disc or the wall point), τ its clockwise perpendicular
(τ = (ε_y, -ε_x)).  ṅ = (v_α - v_β)·ε > 0 while approaching; ṡ is the relative
tangential velocity of the contact points (eq 2.10).  N and S are positive when they act
on α against ε and τ: the force on α is -(N + D_N)ε - (S + D_S)τ, on β the opposite, and
both discs receive the moment +(S + D_S)·R (eq 2.20).
"""
from __future__ import annotations

import numpy as np

from ..jit import njit

NORMAL_INCREMENTAL = 0  # N += kN ṅ Δt (thesis eqs 2.11, 2.13, 2.15)
NORMAL_OVERLAP = 1  # N = kN δ (YADE / LIGGGHTS)
SLIDING_CS = 0  # |S| <= μ·Fn + c, no shear dashpot while sliding (C&S; engines)
SLIDING_THESIS = 1  # |S + D_S| <= |N tan φ + c| (thesis note to eq 2.20)


@njit
def linear_contact(overlap, ndot, sdot, n_old, s_old, dt, kn, ks, cn, cs, mu, coh,
                   normal_mode, sliding_mode, has_shear):
    """Advance one contact by one step.

    overlap δ [length] (> 0: touching), ndot, sdot [length/time] from the half-step
    velocities (eqs 2.31-2.32), n_old, s_old the spring forces of the previous step.
    Returns (N, S, Fn, Fs, sliding): the new spring forces (history) and the total normal
    and shear forces including dashpots, Fn >= 0 (no tension).
    """
    if normal_mode == NORMAL_INCREMENTAL:
        N = n_old + kn * ndot * dt  # eqs 2.13, 2.15
    else:
        N = kn * overlap
    if N < 0.0:
        N = 0.0
    Fn = N + cn * ndot  # eq 2.18: D_N = cN ṅ
    if Fn < 0.0:
        Fn = 0.0  # no tensile contact force
    S = 0.0
    Fs = 0.0
    sliding = False
    if has_shear:
        S = s_old + ks * sdot * dt  # eqs 2.14, 2.16
        Ds = cs * sdot  # eq 2.19
        if sliding_mode == SLIDING_CS:
            smax = mu * Fn + coh
            if abs(S) > smax:
                S = np.copysign(smax, S)
                Ds = 0.0  # no shear damping while sliding (C&S "Damping")
                sliding = True
        else:
            smax = abs(N * mu + coh)  # eq 2.17
            if abs(S + Ds) > smax:
                S = np.copysign(smax, S + Ds)
                Ds = 0.0
                sliding = True
        Fs = S + Ds
    return N, S, Fn, Fs, sliding
