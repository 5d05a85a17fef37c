"""Central-difference motion with global damping (thesis eqs 2.21-2.30, C&S eqs 29-36).

Velocities live at half steps: from v_{i-1/2}, the force sum at t_i and the global
dashpots C (translation) and C* (rotation),

    v_{i+1/2} = [v_{i-1/2}(1 - CΔt/2m) + (ΣF_i/m + g)Δt] / (1 + CΔt/2m)     (eq 2.27)
    ω_{i+1/2} = [ω_{i-1/2}(1 - C*Δt/2I) + ΣM_i Δt/I] / (1 + C*Δt/2I)        (eq 2.28)
    x_{i+1} = x_i + v_{i+1/2}Δt,  θ_{i+1} = θ_i + ω_{i+1/2}Δt                (eqs 2.29-2.30)

C&S's mass-proportional form (eq 34, C = αm, C* = αI) is the same update with per-disc
coefficients, which is how both are stored.
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from .jit import njit_parallel


def critical_time_step(mass: np.ndarray, stiffness_max: float) -> float:
    """Estimated critical time step 2√(m_min/k_max) (thesis §2.2.4.4) [time]."""
    if mass.size == 0 or stiffness_max <= 0:
        return math.inf
    return 2.0 * math.sqrt(float(mass.min()) / stiffness_max)



@njit_parallel
def sum_and_integrate(d, P, start, sidx, f, gx, gy, dt, ext, ext_perm, has_ext):
    """Sum each disc's contact forces and advance it, in one pass (no conflicts, fixed order).

    ``d`` (:class:`~demflow.state.Discs`, slot order).  Each disc sums its contacts in CSR order:
    ``sidx[e]`` is the contact index k when the disc is the pair's finder and -(k+1) when it is the
    other disc; f[k] = (fx, fy, Fs) from :func:`demflow.contacts.forces.pair_forces`, the moment
    being Fs·R of the disc.  The update is thesis eqs 2.27-2.30 (see the module docstring); the new
    x, y, v, ω are also written to the packed rows P (see :func:`demflow.contacts.forces.pack_discs`),
    the contact sums to d.Fx, d.Fy, d.M.  With ``has_ext`` the external force and moment
    ``ext[ext_perm[i]]`` = (fx, fy, m) (the fluid force, moment and buoyancy of a saturated scene,
    thesis §3.4 and eq 4.39, in disc order, ``ext_perm`` mapping slot to disc) is added to disc i's
    sums; without it ``ext`` is not read.  Returns the largest squared displacement since
    (xref, yref) and the largest squared displacement of this step in radii ((|v|Δt/R)², a disc
    that jumps a large part of its radius in one step can pass through a contact unseen).
    """
    # fields are read into local names before the prange loop: Numba (0.68) loses writes made
    # through a namedtuple's field inside a parallel loop (see demflow.jit)
    x = d.x
    y = d.y
    vx = d.vx
    vy = d.vy
    om = d.om
    r = d.r
    mass = d.mass
    inertia = d.inertia
    th, C, Cr, xref, yref, Fx, Fy, M = d.th, d.C, d.Cr, d.xref, d.yref, d.Fx, d.Fy, d.M
    n = x.shape[0]
    dmax2 = 0.0
    jump2 = 0.0
    for i in prange(n):
        ri = r[i]
        sx = 0.0
        sy = 0.0
        sm = 0.0
        for e in range(start[i], start[i + 1]):
            k = sidx[e]
            if k >= 0:
                sx += f[k, 0]
                sy += f[k, 1]
            else:
                k = -k - 1
                sx -= f[k, 0]
                sy -= f[k, 1]
            sm += f[k, 2] * ri
        Fx[i] = sx
        Fy[i] = sy
        M[i] = sm
        if has_ext:
            q = ext_perm[i]
            sx += ext[q, 0]
            sy += ext[q, 1]
            sm += ext[q, 2]
        a = C[i] * dt / (2.0 * mass[i])
        vxi = (vx[i] * (1.0 - a) + (sx / mass[i] + gx) * dt) / (1.0 + a)
        vyi = (vy[i] * (1.0 - a) + (sy / mass[i] + gy) * dt) / (1.0 + a)
        b = Cr[i] * dt / (2.0 * inertia[i])
        omi = (om[i] * (1.0 - b) + sm * dt / inertia[i]) / (1.0 + b)
        vx[i] = vxi
        vy[i] = vyi
        om[i] = omi
        xi = x[i] + vxi * dt
        yi = y[i] + vyi * dt
        x[i] = xi
        y[i] = yi
        th[i] += omi * dt
        P[i, 0] = xi
        P[i, 1] = yi
        P[i, 2] = vxi
        P[i, 3] = vyi
        P[i, 4] = omi
        ddx = xi - xref[i]
        ddy = yi - yref[i]
        dmax2 = max(dmax2, ddx * ddx + ddy * ddy)
        jump2 = max(jump2, (vxi * vxi + vyi * vyi) * dt * dt / (ri * ri))
    return dmax2, jump2
