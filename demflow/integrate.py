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

from . import libm
from .jit import njit_parallel


def critical_time_step(mass: np.ndarray, stiffness_max: float) -> float:
    """Estimated critical time step 2√(m_min/k_max) (thesis §2.2.4.4) [time].

    The single-spring estimate: one mass on one spring.  It is the base of ``Scene.dt_fraction``
    (kept so that every derived Δt stays what it was), not a stability guarantee: a packing's
    discs have several contacts each, and with a shear spring the rotations couple in, so the
    highest mode of a frictional packing is several times stiffer (:func:`safe_time_step`).
    """
    if mass.size == 0 or stiffness_max <= 0:
        return math.inf
    return 2.0 * math.sqrt(float(mass.min()) / stiffness_max)


def kissing_number(R: np.ndarray, r: float) -> np.ndarray:
    """How many discs of radius ``r`` can touch a disc of radius R without overlapping each other:
    ⌊π / arcsin(r/(R + r))⌋ (each subtends 2 arcsin(r/(R + r)) seen from the centre; 6 for equal
    discs).  A uniform relative overlap of every contact leaves the count unchanged."""
    return np.floor(math.pi / libm.arcsin(r / (R + r)) + 1e-9)


def safe_time_step(r: np.ndarray, mass: np.ndarray, inertia: np.ndarray, mat: np.ndarray, disc_laws: dict,
                   wall_laws: dict, kissing=kissing_number, partners: np.ndarray | None = None) -> dict:
    """A critical time step that is safe for any packing the scene's discs can form [time].

    The central-difference scheme is stable while Δt ≤ 2/ω_max, ω_max² the largest eigenvalue of
    M⁻¹K, K the stiffness of every contact in the translations and rotations of the discs
    (O'Sullivan & Bray 2004 bound it with Gershgorin's theorem; the bound below is derived the
    same way).  In mass-scaled coordinates q = M^½ u a contact between discs i and j with normal
    n and tangent t stores ½(a·q)² + ½(b·q)², a = √kN (−n/√m_i, 0, n/√m_j, 0) and
    b = √kT (−t/√m_i, −R_i/√I_i, t/√m_j, −R_j/√I_j).  a and b are orthogonal on each disc, so with
    A_i = max(kN/m_i, kT(1/m_i + R_i²/I_i)) and (x + y)² ≤ (1 + s)x² + (1 + 1/s)y², s = √(A_j/A_i),
    the contact adds at most √A_i(√A_i + √A_j)|q_i|² to disc i's row (a wall: A_j = 0), and

        ω_max² ≤ max_i Σ_{contacts of i} √A_i (√A_i + √A_j).

    Unknown future contacts are bounded a priori: disc i touches at most :func:`kissing_number`
    (R_i, r_min) discs (a wall takes at least a disc's angular room, and its term is never larger)
    and at most every other disc and wall, each through the law of its material pair that gives the
    largest term and against the lightest disc of the partner's material; a disc whose material
    meets no disc touches at most one contact per wall.  For equal discs with kT = kN: 6 contacts, ω_max² ≤ 36 kN/m, Δt ≤ 0.333√(m/kN)
    (the all-discs-spinning mode of a hexagonal packing has ω² = 24 kN/m, Δt = 0.408√(m/kN)).

    Contact dashpots act on the lagged half-step velocities: a mode of frequency ω with damping
    rate γ is stable for Δt ≤ (√(γ² + 4ω²) − γ)/ω² (= (2/ω)(√(1 + ζ²) − ζ), Belytschko 1983);
    γ is bounded like ω² with the dashpots in place of the springs.  Global damping is centred
    (eq 2.27) and does not lower the limit.

    ``disc_laws`` {(material a, material b): (kN, kT, cN, cT)} for every pair of disc materials
    that can meet (both orders), ``wall_laws`` {material a: [(kN, kT, cN, cT), ...]} the laws of
    disc material a against the walls; kT and cT are the shear spring and dashpot that can act
    (zero for a law that always slides).  A law may also be a function of a boolean mask of the
    particles (those of material a), returning those four as arrays over them (a Hertzian law, whose
    stiffness grows with the contact size: :func:`safe_time_step_3d`).  ``kissing(R, r)`` bounds
    the contacts of a particle of radius R with particles of radius r.  Returns dict(dt, omega2,
    gamma, disc, contacts): the safe step, the bounds on ω_max² and γ_max, the disc whose row gives
    ω_max² and its contact count.
    """
    n = r.shape[0]
    if n == 0:
        return dict(dt=math.inf, omega2=0.0, gamma=0.0, disc=-1, contacts=0)
    inv_m = 1.0 / mass
    rot = inv_m + r * r / inertia
    mats = np.unique(mat)
    inv_m_max = {int(b): float(inv_m[mat == b].max()) for b in mats}
    rot_max = {int(b): float(rot[mat == b].max()) for b in mats}

    def rows(which):  # which = 0: springs (kN, kT), 2: dashpots (cN, cT)
        term = np.zeros(n)
        count = np.zeros(n)
        for a in mats:
            a = int(a)
            sel = mat == a
            mates = [(law, b) for (ma, b), law in disc_laws.items() if ma == a]
            n_walls = len(wall_laws.get(a, ()))
            if mates:  # at most the kissing number, and at most every other disc and wall
                others = sum(int((mat == b).sum()) - (b == a) for _, b in mates)
                count[sel] = np.minimum(kissing(r[sel], float(r.min())), others + n_walls)
            else:
                count[sel] = n_walls
            best = np.zeros(int(sel.sum()))
            for law, b in mates + [(law, None) for law in wall_laws.get(a, ())]:
                if callable(law):
                    law = law(sel)
                kn, kt = law[which], law[which + 1]
                Ai = np.maximum(kn * inv_m[sel], kt * rot[sel])
                Aj = 0.0 if b is None else np.maximum(kn * inv_m_max[int(b)], kt * rot_max[int(b)])
                best = np.maximum(best, np.sqrt(Ai) * (np.sqrt(Ai) + np.sqrt(Aj)))
            term[sel] = best
        if partners is not None:  # the particles and walls each can meet at all
            count = np.minimum(count, partners)
        return count * term, count

    s_k, count = rows(0)
    s_c, _ = rows(2)
    i = int(np.argmax(s_k))
    w2, g = float(s_k[i]), float(s_c.max())
    if w2 <= 0.0:
        dt = math.inf
    else:
        dt = (math.sqrt(g * g + 4.0 * w2) - g) / w2
    return dict(dt=dt, omega2=w2, gamma=g, disc=i, contacts=int(count[i]))



def kissing_number_3d(R: np.ndarray, r: float) -> np.ndarray:
    """An upper bound on how many spheres of radius ``r`` can touch a sphere of radius R without
    overlapping each other: each blocks a cap of half-angle θ, sin θ = r/(R + r), seen from the centre,
    and the caps do not overlap, so N ≤ 4π / 2π(1 − cos θ) (14 for equal spheres, whose kissing number is
    12: the bound is safe)."""
    s = r / (R + r)
    return np.floor(2.0 / (1.0 - np.sqrt(1.0 - s * s)) + 1e-9)


def safe_time_step_3d(r: np.ndarray, mass: np.ndarray, mat: np.ndarray, pair_laws: dict, wall_laws: dict,
                      partners: np.ndarray | None = None, inertia: np.ndarray | None = None) -> dict:
    """The safe critical time step of a 3D sphere packing [time]: :func:`safe_time_step`'s Gershgorin
    bound with spheres (I = 2/5 m R², so a tangential spring acts through 1/m + R²/I = 3.5/m) and at most
    :func:`kissing_number_3d` contacts per sphere.  ``pair_laws`` {(a, b): law} and ``wall_laws``
    {a: [law, ...]} as there: constants (kN, kT, cN, cT), or for a Hertzian law a function of the mask of
    material a's spheres giving the stiffness at the largest expected overlap and the dashpots
    (:meth:`demflow.laws.hertz_mindlin.HertzMindlin.time_step_law`).  ``inertia`` (default
    2/5 m R²) may be infinite for a particle whose ``mass`` already bounds its mobility in every direction
    (a clump member: see :func:`demflow.build3d`)."""
    inertia = 0.4 * mass * r * r if inertia is None else inertia
    return safe_time_step(r, mass, inertia, mat, pair_laws, wall_laws, kissing=kissing_number_3d,
                          partners=partners)


# The packed per-disc rows of the cycle (see :func:`pack_rows`): P (n, 8) = (x, y, vx, vy, ω, R, material, θ), the
# row the pair pass gathers and the update writes; Q (n, 8), the columns Q_* below: what the update of a disc reads
# and never writes, one 64-byte line; F (n, 3) = (F_x, F_y, M), the contact sums it writes.  Before session 49 θ and
# the sums sat in a 16-column Q (two lines, both written every step): the pass over the discs at 1e5 took 0.96 of
# its time with this split (speed_experiments_session49.md).
P_TH = 7
Q_MASS, Q_INERTIA, Q_C, Q_CR, Q_XREF, Q_YREF, Q_INV_R2 = range(7)
Q_WIDTH = 8


@njit_parallel
def pack_rows(d, perm, P, Q, F):
    """Fill the rows P (n, 8), Q (n, 8) and F (n, 3) of the slots from discs ``d`` (disc order), slot p from disc
    perm[p]: P[p] = (x, y, vx, vy, ω, R, material, θ), the row :func:`demflow.contacts.forces.pair_forces` reads
    (θ in its spare column, which the pair pass does not read), Q[p] = (m, I, C, C*, x_ref, y_ref, 1/R², 0), the
    columns Q_* of this module, and F[p] = (F_x, F_y, M): the state :func:`sum_and_integrate` advances, three
    rows per disc instead of sixteen arrays.  One pass from the public arrays (the discs were gathered into
    slot-order arrays and packed from them in two passes before session 48: the same numbers, copies and
    1/(R·R))."""
    x, y, vx, vy, om, r, mat = d.x, d.y, d.vx, d.vy, d.om, d.r, d.mat
    th, mass, inertia, C, Cr, xref, yref, Fx, Fy, M = (d.th, d.mass, d.inertia, d.C, d.Cr, d.xref, d.yref, d.Fx,
                                                       d.Fy, d.M)
    for p in prange(perm.shape[0]):
        i = np.uint64(perm[p])
        P[p, 0] = x[i]
        P[p, 1] = y[i]
        P[p, 2] = vx[i]
        P[p, 3] = vy[i]
        P[p, 4] = om[i]
        P[p, 5] = r[i]
        P[p, 6] = mat[i]
        P[p, P_TH] = th[i]
        Q[p, Q_MASS] = mass[i]
        Q[p, Q_INERTIA] = inertia[i]
        Q[p, Q_C] = C[i]
        Q[p, Q_CR] = Cr[i]
        Q[p, Q_XREF] = xref[i]
        Q[p, Q_YREF] = yref[i]
        Q[p, Q_INV_R2] = 1.0 / (r[i] * r[i])
        Q[p, 7] = 0.0
        F[p, 0] = Fx[i]
        F[p, 1] = Fy[i]
        F[p, 2] = M[i]


@njit_parallel
def unpack_rows(P, F, perm, x, y, vx, vy, om, th, Fx, Fy, M):
    """Write the rows P and F of the slots back into the disc arrays (disc order; slot p is disc perm[p]) the step
    advanced: x, y, v, ω, θ and the force sums of the last step (the arrays are passed one by one: see
    :mod:`demflow.jit`)."""
    for p in prange(perm.shape[0]):
        i = np.uint64(perm[p])
        x[i] = P[p, 0]
        y[i] = P[p, 1]
        vx[i] = P[p, 2]
        vy[i] = P[p, 3]
        om[i] = P[p, 4]
        th[i] = P[p, P_TH]
        Fx[i] = F[p, 0]
        Fy[i] = F[p, 1]
        M[i] = F[p, 2]


@njit_parallel
def sum_and_integrate(Q, P, F, start, sidx, f, gx, gy, dt, ext, ext_perm, has_ext, diss):
    """Sum each disc's contact forces and advance it, in one pass (no conflicts, fixed order).

    The discs (slot order) are the packed rows P (x, y, vx, vy, ω, R, material, θ), Q (m, I, C, C*, x_ref, y_ref,
    1/R², 0) and F (F_x, F_y, M), all from :func:`pack_rows`: per disc three rows, so the pass reads and writes a few
    cache lines instead of sixteen
    arrays (benchmarks/results/speed2d_inprocess_ab.md).  Each disc sums its contacts in CSR order, entries
    e = start[i]..start[i+1] naming pair k by sidx[e] = 2k (this disc its finder) or 2k + 1 (its other disc):
    f[k] = (fx, fy, Fs) is pair k's force on its finder and shear force
    (:func:`demflow.contacts.forces.pair_forces`), and the disc's share is (fx, fy, Fs·R) as the finder and
    (-fx, -fy, Fs·R) as the other disc, R its own radius (the numbers the per-entry rows of 0ee02e7 held, so
    the same sums to the bit; a pair's force is written once and read twice instead of written twice).  The update is thesis
    eqs 2.27-2.30 (see the module docstring); the new x, y, v, ω and θ go to P, the contact sums to F (Q is only
    read).
    With ``has_ext`` the external force and moment ``ext[ext_perm[i]]`` = (fx, fy, m) (the fluid force,
    moment and buoyancy of a saturated scene, thesis §3.4 and eq 4.39, in disc order, ``ext_perm`` mapping
    slot to disc) is added to disc i's sums; without it ``ext`` is not read.  Returns the largest squared
    displacement since (x_ref, y_ref) and the largest squared displacement of this step in radii
    ((|v|Δt)²·(1/R²), a disc that jumps a large part of its radius in one step can pass through a contact
    unseen).  diss[i] += the energy disc i's global damping dissipated in the step, (C v̄² + C* ω̄²)Δt with
    v̄ = (v_{i-1/2} + v_{i+1/2})/2 (exactly what the centred dashpot of eq 2.27 removes from ½mv²).
    """
    n = P.shape[0]
    dmax2 = 0.0
    jump2 = 0.0
    for ii in prange(n):
        i = np.uint64(ii)  # unsigned indices: no wrap-around arithmetic for negative indices
        ri = P[i, 5]
        sx = 0.0
        sy = 0.0
        sm = 0.0
        for e in range(start[ii], start[ii + 1]):
            q = sidx[np.uint64(e)]
            k = q >> 1
            # as the other disc (q odd) the negated force: -x is x·(-1) exactly
            s = 1.0 - 2.0 * (q & 1)
            sx += s * f[k, 0]
            sy += s * f[k, 1]
            sm += f[k, 2] * ri
        F[i, 0] = sx
        F[i, 1] = sy
        F[i, 2] = sm
        if has_ext:
            q = ext_perm[i]
            sx += ext[q, 0]
            sy += ext[q, 1]
            sm += ext[q, 2]
        Ci = Q[i, Q_C]
        Cri = Q[i, Q_CR]
        mass = Q[i, Q_MASS]
        inertia = Q[i, Q_INERTIA]
        vx = P[i, 2]
        vy = P[i, 3]
        om = P[i, 4]
        if Ci == 0.0 and Cri == 0.0:
            # undamped: the same numbers as below with a = b = 0 (x(1 - 0) and y/(1 + 0) are exact), without
            # its divisions; nothing dissipated
            vxi = vx + (sx / mass + gx) * dt
            vyi = vy + (sy / mass + gy) * dt
            omi = om + sm * dt / inertia
        else:
            a = Ci * dt / (2.0 * mass)
            vxi = (vx * (1.0 - a) + (sx / mass + gx) * dt) / (1.0 + a)
            vyi = (vy * (1.0 - a) + (sy / mass + gy) * dt) / (1.0 + a)
            b = Cri * dt / (2.0 * inertia)
            omi = (om * (1.0 - b) + sm * dt / inertia) / (1.0 + b)
            mvx = 0.5 * (vx + vxi)
            mvy = 0.5 * (vy + vyi)
            mom = 0.5 * (om + omi)
            diss[i] += (Ci * (mvx * mvx + mvy * mvy) + Cri * mom * mom) * dt
        xi = P[i, 0] + vxi * dt
        yi = P[i, 1] + vyi * dt
        P[i, P_TH] += omi * dt
        P[i, 0] = xi
        P[i, 1] = yi
        P[i, 2] = vxi
        P[i, 3] = vyi
        P[i, 4] = omi
        ddx = xi - Q[i, Q_XREF]
        ddy = yi - Q[i, Q_YREF]
        dmax2 = max(dmax2, ddx * ddx + ddy * ddy)
        jump2 = max(jump2, (vxi * vxi + vyi * vyi) * dt * dt * Q[i, Q_INV_R2])
    return dmax2, jump2
