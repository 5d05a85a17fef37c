"""Linear spring-dashpot-Coulomb contact law for one contact (thesis §2.2.4.2, C&S eqs 8-27).

Sign conventions (thesis §2.2.4.1, C&S Fig. 3): ε is the unit vector from disc α (the
pair's finder) to β (the other disc or the wall point), τ its clockwise perpendicular
(τ = (ε_y, -ε_x)).  ṅ = (v_α - v_β)·ε > 0 while approaching; ṡ is the relative
tangential velocity of the contact points (eq 2.10).  N and S are positive when they act
on α against ε and τ: the force on α is -(N + D_N)ε - (S + D_S)τ, on β the opposite, and
both discs receive the moment +(S + D_S)·R (eq 2.20).
"""
from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba.extending import overload

from ..jit import njit, njit_inline
from .base import (LawFamily, is_params_of, law_energy3, law_energy_add, law_force, law_force3, law_force_dissipation,
                   law_separate, law_turns_history)

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


# ---------------------------------------------------------------------------- the law interface
LinearParams = namedtuple("LinearParams", [
    "kn", "ks",   # (nm, nm) normal and shear spring stiffness per material pair [force/length]
    "cn", "cs",   # (nm, nm) normal and shear dashpots [force·time/length]
    "mu", "coh",  # (nm, nm) Coulomb coefficient tan φ_μ and cohesion c [force]
    "normal_mode", "sliding_mode",  # NORMAL_* and SLIDING_* (scene-wide, ContactModel)
    "has_shear",  # bool: some law has a shear spring (history has a shear column)
    "row",  # (nm, nm, 8) the six tables above packed per material pair, (kn, ks, cn, cs, mu, coh, 0, 0)
])
"""Parameters of the linear law as the compiled cycle sees them (see :mod:`demflow.laws.base`).

The per-contact force (:func:`law_force`, :func:`law_force_dissipation`, :func:`law_force3`) reads a
pair's six numbers from ``row[ma, mb]``, one 64-byte row, instead of six tables (which are views of
``row``): the same numbers, read from one cache line (benchmarks/results/speed2d_inprocess_ab.md)."""

TABLE_KEYS = ("kn", "ks", "cn", "cs", "mu", "coh")


def packed_rows(tables: dict) -> np.ndarray:
    """The (nm, nm, 8) array of rows (kn, ks, cn, cs, mu, coh, 0, 0) of the (nm, nm) ``tables``."""
    first = tables[TABLE_KEYS[0]]
    row = np.zeros(first.shape + (8,))
    for c, key in enumerate(TABLE_KEYS):
        row[:, :, c] = tables[key]
    return row


@overload(law_force, inline="always")
def _linear_force(law, hist, k, ma, mb, overlap, ndot, sdot, dt):
    if not is_params_of(law, LinearParams):
        return None

    def impl(law, hist, k, ma, mb, overlap, ndot, sdot, dt):
        has_shear = law.has_shear
        s_old = hist[k, 1] if has_shear else 0.0
        row = law.row
        N, S, Fn, Fs, sliding = linear_contact(
            overlap, ndot, sdot, hist[k, 0], s_old, dt,
            row[ma, mb, 0], row[ma, mb, 1], row[ma, mb, 2], row[ma, mb, 3], row[ma, mb, 4], row[ma, mb, 5],
            law.normal_mode, law.sliding_mode, has_shear)
        hist[k, 0] = N
        if has_shear:
            hist[k, 1] = S
        return Fn, Fs, sliding
    return impl


@overload(law_force_dissipation, inline="always")
def _linear_force_dissipation(law, hist, k, ma, mb, overlap, ndot, sdot, dt):
    """The linear law with the energy dissipated in the step: the dashpots' (Fn - N)ṅΔt + (Fs - S)ṡΔt
    (cN ṅ²Δt and cS ṡ²Δt, or the part a no-tension cut leaves), and while sliding the Coulomb slip
    work |S|·|S_trial - S|/kS, S_trial the shear spring before the cap; and the forces that worked over
    the step, ½(N_old + N) + (Fn - N) and ½(S_old + S) + (Fs - S) (the springs store exactly their
    mean times the increment)."""
    if not is_params_of(law, LinearParams):
        return None

    def impl(law, hist, k, ma, mb, overlap, ndot, sdot, dt):
        has_shear = law.has_shear
        s_old = hist[k, 1] if has_shear else 0.0
        hist_n_old = hist[k, 0]
        row = law.row
        ks = row[ma, mb, 1]
        N, S, Fn, Fs, sliding = linear_contact(
            overlap, ndot, sdot, hist_n_old, s_old, dt,
            row[ma, mb, 0], ks, row[ma, mb, 2], row[ma, mb, 3], row[ma, mb, 4], row[ma, mb, 5],
            law.normal_mode, law.sliding_mode, has_shear)
        hist[k, 0] = N
        if has_shear:
            hist[k, 1] = S
        dissipated = ((Fn - N) * ndot + (Fs - S) * sdot) * dt
        if sliding and ks > 0.0:
            dissipated += abs(S) * abs(s_old + ks * sdot * dt - S) / ks
        # the forces that did work over the step: the springs' mean and the dashpots'
        Fn_work = 0.5 * (hist_n_old + N) + (Fn - N)
        Fs_work = 0.5 * (s_old + S) + (Fs - S)
        return Fn, Fs, sliding, dissipated, Fn_work, Fs_work
    return impl


@overload(law_separate, inline="always")
def _linear_separate(law, hist, k):
    if not is_params_of(law, LinearParams):
        return None

    def impl(law, hist, k):
        hist[k, 0] = 0.0
        if law.has_shear:
            hist[k, 1] = 0.0
    return impl


@overload(law_energy_add, inline="always")
def _linear_energy(law, e, hist, k, ma, mb):
    if not is_params_of(law, LinearParams):
        return None

    def impl(law, e, hist, k, ma, mb):
        # N²/2kN + S²/2kS [force·length], added term by term (the order of the reference sum).  Both stiffnesses
        # are read before the branch: an array of the params tuple read inside it kept Numba's reference counts
        # in the loop (elastic_energy_keys at 1e5 pairs 9.3 -> 0.9 ms, speed_experiments_session49.md)
        kn = law.kn[ma, mb]
        ks = law.ks[ma, mb]
        e += 0.5 * hist[k, 0] ** 2 / kn
        if law.has_shear and ks > 0.0:
            e += 0.5 * hist[k, 1] ** 2 / ks
        return e
    return impl


@overload(law_turns_history, inline="always")
def _linear_turns_history(law):
    """The pair pass turns the linear law's shear spring (projected and rescaled)."""
    if not is_params_of(law, LinearParams):
        return None

    def impl(law):
        return False
    return impl


@overload(law_force3, inline="always")
def _linear_force3(law, hist, k, ma, mb, meff, rstar, overlap, vn, vtx, vty, vtz, nx, ny, nz, dt):
    """The linear law for 3D contacts: history (S vector, N); the shear spring is a vector
    in the tangent plane (rotated there by the pass), incremented by -k_S v_t Δt (eqs 2.14/2.16)."""
    if not is_params_of(law, LinearParams):
        return None

    def impl(law, hist, k, ma, mb, meff, rstar, overlap, vn, vtx, vty, vtz, nx, ny, nz, dt):
        row = law.row
        Fn, Tx, Ty, Tz, sliding, diss, Sx, Sy, Sz, N = linear_contact3(
            row[ma, mb, 0], row[ma, mb, 1], row[ma, mb, 2], row[ma, mb, 3], row[ma, mb, 4], row[ma, mb, 5],
            law.normal_mode, law.sliding_mode, law.has_shear, hist[k, 0], hist[k, 1], hist[k, 2], hist[k, 3],
            overlap, vn, vtx, vty, vtz, dt)
        return Fn, Tx, Ty, Tz, sliding, diss, (Sx, Sy, Sz, N), 4
    return impl


@njit_inline
def linear_contact3(kn, ks, cn, cs, mu, coh, normal_mode, sliding_mode, has_shear, Sx, Sy, Sz, N, overlap, vn, vtx,
                    vty, vtz, dt):
    """The linear law's force on one 3D contact with history (shear spring S, normal spring N), from the pair's
    scalar parameters; returns law_force3's six values and the history after the step (scalars in and out
    for the reason given in :func:`demflow.laws.hertz_mindlin.hertz_contact3`)."""
    if normal_mode == NORMAL_INCREMENTAL:
        N = N + kn * vn * dt
    else:
        N = kn * overlap
    if N < 0.0:
        N = 0.0
    Fn = N + cn * vn
    if Fn < 0.0:
        Fn = 0.0
    diss = (Fn - N) * vn * dt  # the normal dashpot (what the no-tension cut leaves of it)
    Tx = 0.0
    Ty = 0.0
    Tz = 0.0
    sliding = False
    if has_shear:
        Sx = Sx - ks * vtx * dt
        Sy = Sy - ks * vty * dt
        Sz = Sz - ks * vtz * dt
        smax = mu * (Fn if sliding_mode == SLIDING_CS else N) + coh
        s2 = Sx * Sx + Sy * Sy + Sz * Sz
        sliding = s2 > smax * smax
        if sliding:
            sm = math.sqrt(s2)
            f = smax / sm
            Sx *= f
            Sy *= f
            Sz *= f
            cs = 0.0  # no shear dashpot while sliding
            if ks > 0.0:  # Coulomb slip: (|S_trial| - S_max)/k_S at S_max
                diss += smax * (sm - smax) / ks
        else:
            diss += cs * (vtx * vtx + vty * vty + vtz * vtz) * dt
        Tx = Sx - cs * vtx
        Ty = Sy - cs * vty
        Tz = Sz - cs * vtz
    return Fn, Tx, Ty, Tz, sliding, diss, Sx, Sy, Sz, N


@overload(law_energy3, inline="always")
def _linear_energy3(law, e, hist, k, ma, mb, rstar, overlap):
    if not is_params_of(law, LinearParams):
        return None

    def impl(law, e, hist, k, ma, mb, rstar, overlap):
        # the row read at once, before any branch (an array read across branches keeps Numba's reference counts:
        # hertz_mindlin.hertz_contact3)
        h0 = hist[k, 0]
        h1 = hist[k, 1]
        h2 = hist[k, 2]
        e += 0.5 * hist[k, 3] ** 2 / law.kn[ma, mb]
        if law.has_shear and law.ks[ma, mb] > 0.0:
            e += 0.5 * (h0 ** 2 + h1 ** 2 + h2 ** 2) / law.ks[ma, mb]
        return e
    return impl


class Linear(LawFamily):
    """The linear spring-dashpot-Coulomb law (this module) as a law family.

    History per contact: the normal spring force N and, when some law has a shear spring, the
    shear spring force S (2D: one column each; the shear history is a scalar in the contact's
    tangent τ).  Stiffness bound: max(kN, kS) (thesis §2.2.4.4).
    """

    name = "linear"
    engines = {
        "yade": "FrictMat + Ip2_FrictMat_FrictMat_FrictPhys + Law2_ScGeom_FrictPhys_CundallStrack "
                "(normal='overlap', sliding='cs')",
        "liggghts": "pair gran model hooke/stiffness tangential history (normal='overlap', sliding='cs')",
    }

    @classmethod
    def accepts(cls, law) -> bool:
        from ..scene import LinearLaw

        return isinstance(law, LinearLaw)

    def __init__(self, scene, laws_by_pair, material_index):
        super().__init__(scene, laws_by_pair, material_index)
        self.has_shear = bool(any(law.ks > 0 for law in laws_by_pair.values()))

    def history_width(self, dim: int = 2) -> int:
        if dim == 3:
            return 4  # shear spring vector S (3), normal spring N
        return 2 if self.has_shear else 1

    def tables(self) -> dict:
        """The (nm × nm) tables kn, ks, cn, cs, mu, coh (zero for pairs that never meet)."""
        nm = len(self.material_index)
        t = {key: np.zeros((nm, nm)) for key in TABLE_KEYS}
        for (a, b), law in self.laws_by_pair.items():
            ia, ib = self.material_index[a], self.material_index[b]
            for key in TABLE_KEYS:
                val = {"mu": law.friction, "coh": law.cohesion}.get(key, getattr(law, key, None))
                t[key][ia, ib] = val
                t[key][ib, ia] = val
        return t

    def params(self) -> LinearParams:
        cm = self.scene.contact_model
        row = packed_rows(self.tables())
        # the six tables are views of the packed rows: a change made to one (a test setting every dashpot
        # to NaN) is what the kernels read
        t = {key: row[:, :, c] for c, key in enumerate(TABLE_KEYS)}
        return LinearParams(**t, normal_mode=NORMAL_INCREMENTAL if cm.normal == "incremental" else NORMAL_OVERLAP,
                            sliding_mode=SLIDING_CS if cm.sliding == "cs" else SLIDING_THESIS,
                            has_shear=self.has_shear, row=row)

    def stiffness_bound(self, law) -> float:
        return max(law.kn, law.ks)

    def time_step_constants(self, law) -> tuple[float, float, float, float]:
        """(kN, kS, cN, cS); a shear spring without friction or cohesion always slides (its cap
        μFn + c is 0), so it adds no stiffness and no dashpot."""
        sticks = law.ks > 0 and (law.friction > 0 or law.cohesion > 0)
        return (float(law.kn), float(law.ks) if sticks else 0.0, float(law.cn), float(law.cs) if sticks else 0.0)
