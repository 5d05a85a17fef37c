"""Hertz-Mindlin contact law for spheres (ch3 eqs 3.21-3.25, 3.28; Miyata eqs 13-33).

Normal (Hertz, ch3 eq 3.21): F = 4/3 E* √R* δ^{3/2}, with 1/R* = 1/R₁ + 1/R₂ (eq 3.22; a plane
has R = ∞) and 1/E* = (1-ν₁²)/E₁ + (1-ν₂²)/E₂ (eq 3.23).  The tangent normal stiffness is
k_n = dF/dδ = 2E*a with a = √(R*δ) the contact radius.

Tangential, three variants:

- ``"mindlin"`` — Mindlin's no-slip stiffness k_t = 8G*a (Miyata eqs 31, 47-49), with
  1/G* = 2(2-ν₁)(1+ν₁)/E₁ + 2(2-ν₂)(1+ν₂)/E₂, capped by Coulomb.  What YADE's
  ``Law2_ScGeom_MindlinPhys_Mindlin`` (``shear_spring="incremental"``: T += -k_t v_t Δt, the
  tangent stiffness applied to each increment) and LIGGGHTS's ``tangential history``
  (``shear_spring="total"``: the total tangential displacement u is stored and T = -k_t u, the
  *current* stiffness times all of it) compute.
- ``"mindlin-deresiewicz"`` — ch3 eqs 3.24-3.25: loading from a virgin contact with tangent
  stiffness k_t = 8G*a (1 - |T|/μN)^{1/3} (the derivative of eq 3.24), unloading and reloading
  from a reversal at T_r with k_t = 8G*a (1 - |T - T_r|/(2μN))^{1/3} (the derivative of eq 3.25;
  Masing's rule), back on the virgin curve once |T| passes |T_r|.  The hysteresis is applied to
  the component of the tangential force along the contact's first direction of tangential motion
  (stored, kept in the tangent plane); motion across that direction uses the no-slip stiffness.
  Exact for loading in one direction (normal and oblique impacts, cyclic shear along a line);
  a documented approximation for paths that turn.  demflow only: neither engine has it.
- ``"none"`` — frictionless, no tangential force.

Damping: dashpots c_n = 2ζ_n √(m* k_n), c_t = 2ζ_t √(m* k_t) (ch3 eq 3.28 with the tangent
stiffness; m* = m_i m_j/(m_i + m_j), the body mass against a plane), ζ from the restitution in one
of the conventions of :mod:`demflow.laws.restitution`.  The normal force is never tensile
(Fn = max(0, F + c_n v_n)).  Coulomb (``friction_cap``): the elastic tangential force is capped at
μ·Fn with Fn the total normal force (``"total"``: YADE, LIGGGHTS) or its elastic part
(``"elastic"``: Miyata eq 32's text); while sliding there is no tangential dashpot (both engines).
"""
from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass

import numpy as np
from numba.extending import overload

from ..jit import njit, njit_inline
from .base import LawFamily, is_params_of, law_energy3, law_force3, law_turns_history
from .restitution import CONVENTIONS, zeta_for

TANGENTIAL_NONE = 0
TANGENTIAL_MINDLIN = 1
TANGENTIAL_MD = 2
SHEAR_INCREMENTAL = 0  # YADE: T += -k_t v_t Δt
SHEAR_TOTAL = 1  # LIGGGHTS: u += v_t Δt, T = -k_t u
CAP_TOTAL = 0
CAP_ELASTIC = 1
ROTATION_RESCALE = 0  # demflow: the pair pass projects the history onto the new tangent plane and rescales it, then the law
ROTATION_PROJECT = 1  # LIGGGHTS: the law increments the history, then projects it onto the tangent plane (no rescale)

_TANGENTIAL = {"none": TANGENTIAL_NONE, "mindlin": TANGENTIAL_MINDLIN, "mindlin-deresiewicz": TANGENTIAL_MD}
_SHEAR = {"incremental": SHEAR_INCREMENTAL, "total": SHEAR_TOTAL}
_CAP = {"total": CAP_TOTAL, "elastic": CAP_ELASTIC}
_ROTATION = {"rescale": ROTATION_RESCALE, "project": ROTATION_PROJECT}


@dataclass(frozen=True)
class HertzMindlinLaw:
    """Hertz-Mindlin law of a material pair (this module's docstring).  The elastic constants come
    from the two :class:`demflow.scene.Material` s (``young`` E [force/length²], ``poisson`` ν).

    friction : μ = tan φ (Coulomb)
    restitution : normal coefficient of restitution e_n (1: no normal dashpot)
    restitution_tangential : e_t for the tangential dashpot (None: the same as e_n; 1: none)
    damping : convention from e to the dashpot ("exact", "yade", "liggghts"; see
              :mod:`demflow.laws.restitution`)
    tangential : "mindlin" (k_t = 8G*a), "mindlin-deresiewicz" (ch3 3.24-3.25) or "none"
    shear_spring : "incremental" (YADE) or "total" (LIGGGHTS) storage of the Mindlin spring
    friction_cap : Coulomb against the "total" normal force (engines) or its "elastic" part
    history_rotation : how the tangential history follows a turning contact normal: "rescale" (before the
              increment, projected onto the new tangent plane and rescaled to its length: its magnitude is kept)
              or "project" (after the increment, projected onto the tangent plane without rescaling: LIGGGHTS
              3.8.0's rule, its matching mode; the two differ by O(θ²) per step, θ the normal's turn in a step:
              capabilities feature 'history-rotation')
    """

    friction: float = 0.0
    restitution: float = 1.0
    restitution_tangential: float | None = None
    damping: str = "exact"
    tangential: str = "mindlin"
    shear_spring: str = "incremental"
    friction_cap: str = "total"
    history_rotation: str = "rescale"

    def check(self, pair) -> None:
        from ..scene import SceneError

        for key in ("friction", "restitution", "restitution_tangential"):
            v = getattr(self, key)
            if v is None and key == "restitution_tangential":
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise SceneError(f"scene.laws[{pair!r}].{key}={v!r} is not a finite number; give a float")
            if v < 0:
                raise SceneError(f"scene.laws[{pair!r}].{key}={v} is negative; give {key} >= 0")
        for key in ("restitution", "restitution_tangential"):
            v = getattr(self, key)
            if v is not None and not (0.0 < v <= 1.0):
                raise SceneError(f"scene.laws[{pair!r}].{key}={v} is outside (0, 1]; a Hertz dashpot reaches "
                                 "any e > 0: give 0 < e <= 1")
        for key, allowed in (("damping", CONVENTIONS[:3]), ("tangential", tuple(_TANGENTIAL)),
                             ("shear_spring", tuple(_SHEAR)), ("friction_cap", tuple(_CAP)),
                             ("history_rotation", tuple(_ROTATION))):
            v = getattr(self, key)
            if v not in allowed:
                raise SceneError(f"scene.laws[{pair!r}].{key}={v!r} is not one of {allowed}")
        if self.tangential == "mindlin-deresiewicz" and self.shear_spring != "incremental":
            raise SceneError(f"scene.laws[{pair!r}].tangential='mindlin-deresiewicz' is incremental by nature; "
                             "give shear_spring='incremental'")
        if self.tangential == "mindlin-deresiewicz" and self.history_rotation != "rescale":
            raise SceneError(f"scene.laws[{pair!r}].tangential='mindlin-deresiewicz' keeps its direction of loading "
                             "in the tangent plane the pair pass turns it into: give history_rotation='rescale'")


# ------------------------------------------------------------------------------ pure functions
@njit
def effective_modulus(E1, nu1, E2, nu2):
    """E* of ch3 eq 3.23 [force/length²]; a rigid body has E = inf."""
    return 1.0 / ((1.0 - nu1 * nu1) / E1 + (1.0 - nu2 * nu2) / E2)


@njit
def effective_shear_modulus(E1, nu1, E2, nu2):
    """G* with 1/G* = (2-ν₁)/G₁ + (2-ν₂)/G₂, G = E/2(1+ν) (Mindlin; Miyata eq 31) [force/length²]."""
    return 1.0 / (2.0 * (2.0 - nu1) * (1.0 + nu1) / E1 + 2.0 * (2.0 - nu2) * (1.0 + nu2) / E2)


@njit
def hertz_force(Estar, rstar, overlap):
    """Hertz normal force 4/3 E* √R* δ^{3/2} (ch3 eq 3.21) [force]."""
    return 4.0 / 3.0 * Estar * math.sqrt(rstar) * overlap ** 1.5


@njit
def hertz_stiffness(Estar, rstar, overlap):
    """Tangent normal stiffness dF/dδ = 2E*√(R*δ) [force/length]."""
    return 2.0 * Estar * math.sqrt(rstar * overlap)


@njit
def mindlin_stiffness(Gstar, rstar, overlap):
    """No-slip tangential stiffness 8G*a, a = √(R*δ) (Miyata eq 31) [force/length]."""
    return 8.0 * Gstar * math.sqrt(rstar * overlap)


@njit
def md_tangent_factor(T, T_rev, on_branch, muN):
    """Mindlin-Deresiewicz tangent stiffness / 8G*a for tangential force T (signed, one direction).

    Virgin curve (ch3 eq 3.24): (1 - |T|/μN)^{1/3}.  On a branch from a reversal at T_rev (eq 3.25,
    Masing): (1 - |T - T_rev|/(2μN))^{1/3}.  Zero at gross sliding.
    """
    if muN <= 0.0:
        return 0.0
    if on_branch:
        x = 1.0 - abs(T - T_rev) / (2.0 * muN)
    else:
        x = 1.0 - abs(T) / muN
    if x <= 0.0:
        return 0.0
    return x ** (1.0 / 3.0)


@njit
def md_step(T, T_rev, direction, on_branch, k0, du, muN):
    """One Mindlin-Deresiewicz increment along a line: force T (signed) for a tangential
    displacement increment du (the force on the body opposes it: dT = -k du).

    State: T_rev the force at the last reversal, direction the sign of the last force increment
    (0 before the first), on_branch whether the path is on an unloading/reloading branch.
    Returns (T, T_rev, direction, on_branch).
    """
    dT_sign = -1.0 if du > 0.0 else (1.0 if du < 0.0 else 0.0)
    if dT_sign == 0.0:
        return T, T_rev, direction, on_branch
    if direction != 0.0 and dT_sign != direction:
        T_rev = T  # a reversal: a new Masing branch starts here
        on_branch = True
    if on_branch and abs(T) >= abs(T_rev) and (T - T_rev) * dT_sign > 0.0 and T * dT_sign > 0.0:
        on_branch = False  # the branch has met the virgin curve on the other side
    # midpoint tangent stiffness (second order in du)
    k1 = k0 * md_tangent_factor(T, T_rev, on_branch, muN)
    Th = T - 0.5 * k1 * du
    k2 = k0 * md_tangent_factor(Th, T_rev, on_branch, muN)
    T = T - k2 * du
    if T > muN:
        T = muN
    elif T < -muN:
        T = -muN
    return T, T_rev, dT_sign, on_branch


# ---------------------------------------------------------------------------- the law interface
HertzParams = namedtuple("HertzParams", [
    "Estar", "Gstar",  # (nm, nm) effective moduli [force/length²]
    "mu",              # (nm, nm) Coulomb coefficient
    "zn", "zt",        # (nm, nm) damping ratios ζ of the normal and tangential dashpots
    "tangential",      # (nm, nm) int64 TANGENTIAL_*
    "shear_spring",    # SHEAR_* (scene-wide)
    "cap",             # CAP_* (scene-wide)
    "rotation",        # ROTATION_* (scene-wide)
])
"""Parameters of the Hertz-Mindlin law as the compiled cycle sees them (see :mod:`demflow.laws.base`), for a
scene none of whose material pairs uses Mindlin-Deresiewicz: its pair pass is compiled without that branch."""

HertzParamsMD = namedtuple("HertzParamsMD", HertzParams._fields)
"""The same fields as :data:`HertzParams`, for a scene some of whose material pairs use Mindlin-Deresiewicz
(``tangential == TANGENTIAL_MD``): the one type whose pair pass compiles that branch.  The tangential mode is a table
per material pair, read per contact; which of the two types a scene gets is settled once, by
:meth:`HertzMindlin.params`, so a scene without Mindlin-Deresiewicz pays nothing for it: the branch, dead but
compiled into the inlined law, made the pair pass's loop larger: without it the 3D benchmark's step took 0.892 and
0.906 of the time with it at 1e4 and 1e5 spheres (per-round medians; benchmarks/results/speed3d_session37_ab.md)."""

HERTZ_PARAMS_TYPES = (HertzParams, HertzParamsMD)

HISTORY_WIDTH_3D = 8  # T (or u) vector, MD direction e (3), T_rev, MD state (direction·(1 + on_branch))


@njit_inline
def _in_plane(x, y, z, nx, ny, nz):
    """The vector (x, y, z) less its component along the unit normal n (history_rotation='project')."""
    c = x * nx + y * ny + z * nz
    return x - c * nx, y - c * ny, z - c * nz


@njit_inline
def hertz_contact3(E, G, mu, zn, zt, mode, shear_spring, cap, rotation, row, meff, rstar, overlap, vn, vtx, vty, vtz,
                   nx, ny, nz, dt, with_md):
    """The Hertz-Mindlin force of one 3D contact from the pair's scalar parameters and the contact's history
    (law_force3's contract); returns (Fn, Tx, Ty, Tz, sliding, dissipated) and the history after the step.

    E*, G* the effective moduli, mu the Coulomb coefficient, zn/zt the damping ratios, mode TANGENTIAL_*,
    shear_spring SHEAR_*, cap CAP_*, rotation ROTATION_* (ROTATION_PROJECT: the pair pass has not turned the history;
    the spring's state after the increment is projected onto the tangent plane here, LIGGGHTS's rule).  ``with_md``:
    a compile-time constant, False where no contact can be Mindlin-Deresiewicz (:data:`HertzParamsMD`): the branch is
    then not compiled, and a ``mode`` of TANGENTIAL_MD would be taken as TANGENTIAL_MINDLIN (the parameters' type rules
    that out).  ``row``: the contact's history (:data:`HISTORY_WIDTH_3D` values): the tangential vector (h0, h1, h2); for Mindlin-Deresiewicz the direction e (e0, e1, e2), T_rev and the
    state (passed through unused otherwise).

    Scalars in and out, and one return: law_force3's implementation reads the tables and the history row,
    and the pair pass writes the row back.  Numba (0.68) keeps the reference-count updates of an array passed into an
    inlined body whose uses end in several branches: the tables read here made the whole pair pass 1.8x
    slower (2.47 against 1.37 ms a step on benchmarks/packing3d.py's 10 000-sphere packing, one thread,
    measured 2026-11-25), and the history array passed here cost an atomic increment and decrement per
    touching pair, 11-14 % of the pass's samples (perf, 2026-11-28, an Intel Xeon host; the same bits), and
    returning the row took 6 % off the step at 1e4 spheres (benchmarks/results/speed3d_history_row_ab.md)."""
    h0, h1, h2, e0, e1, e2, T_rev, state = row
    a = math.sqrt(rstar * overlap)
    kn = 2.0 * E * a
    Fe = 4.0 / 3.0 * E * a * overlap
    Fn = Fe + 2.0 * zn * math.sqrt(meff * kn) * vn if zn > 0.0 else Fe
    if Fn < 0.0:
        Fn = 0.0
    diss = (Fn - Fe) * vn * dt  # the normal dashpot (what the no-tension cut leaves of it)
    Tx = 0.0
    Ty = 0.0
    Tz = 0.0
    sliding = False
    if mode != TANGENTIAL_NONE:
        kt = 8.0 * G * a
        at_rest = False  # Mindlin-Deresiewicz before any tangential motion: the history's force as it is
        if mode == TANGENTIAL_MINDLIN or not with_md:
            if shear_spring == SHEAR_TOTAL:
                h0 += vtx * dt
                h1 += vty * dt
                h2 += vtz * dt
                if rotation == ROTATION_PROJECT:
                    h0, h1, h2 = _in_plane(h0, h1, h2, nx, ny, nz)
                Tx = -kt * h0
                Ty = -kt * h1
                Tz = -kt * h2
            else:
                Tx = h0 - kt * vtx * dt
                Ty = h1 - kt * vty * dt
                Tz = h2 - kt * vtz * dt
                if rotation == ROTATION_PROJECT:
                    Tx, Ty, Tz = _in_plane(Tx, Ty, Tz, nx, ny, nz)
        elif with_md:
            # Mindlin-Deresiewicz along the contact's first direction of motion e
            e_dot_n = e0 * nx + e1 * ny + e2 * nz
            ex = e0 - e_dot_n * nx
            ey = e1 - e_dot_n * ny
            ez = e2 - e_dot_n * nz
            en = math.sqrt(ex * ex + ey * ey + ez * ez)
            vt = math.sqrt(vtx * vtx + vty * vty + vtz * vtz)
            if en == 0.0:
                if vt == 0.0:
                    at_rest = True
                    Tx = h0
                    Ty = h1
                    Tz = h2
                else:
                    ex, ey, ez, en = vtx, vty, vtz, vt
            if not at_rest:
                ex /= en
                ey /= en
                ez /= en
                e0 = ex
                e1 = ey
                e2 = ez
                Tpar = h0 * ex + h1 * ey + h2 * ez
                direction = 0.0 if state == 0.0 else math.copysign(1.0, state)
                on_branch = abs(state) > 1.5
                muN = mu * (Fn if cap == CAP_TOTAL else Fe)
                du = (vtx * ex + vty * ey + vtz * ez) * dt
                Tnew, T_rev, direction, on_branch = md_step(Tpar, T_rev, direction, on_branch, kt, du, muN)
                state = direction * (2.0 if on_branch else 1.0)
                # across e: the no-slip stiffness
                Tx = h0 - Tpar * ex - kt * (vtx * dt - du * ex) + Tnew * ex
                Ty = h1 - Tpar * ey - kt * (vty * dt - du * ey) + Tnew * ey
                Tz = h2 - Tpar * ez - kt * (vtz * dt - du * ez) + Tnew * ez
        if not at_rest:
            Tcap = mu * (Fn if cap == CAP_TOTAL else Fe)
            Tm2 = Tx * Tx + Ty * Ty + Tz * Tz
            sliding = Tm2 > Tcap * Tcap
            if sliding:
                Tm = math.sqrt(Tm2)
                s = Tcap / Tm
                # Coulomb slip: the spring force beyond the cap, (|T_trial| - T_cap)/k_t of slip at T_cap
                diss += Tcap * (Tm - Tcap) / kt
                Tx *= s
                Ty *= s
                Tz *= s
                if shear_spring == SHEAR_TOTAL and mode == TANGENTIAL_MINDLIN:
                    h0 *= s
                    h1 *= s
                    h2 *= s
                else:
                    h0 = Tx
                    h1 = Ty
                    h2 = Tz
            else:
                if not (shear_spring == SHEAR_TOTAL and mode == TANGENTIAL_MINDLIN):
                    h0 = Tx
                    h1 = Ty
                    h2 = Tz
                if zt > 0.0:
                    ct = 2.0 * zt * math.sqrt(meff * kt)
                    Tx -= ct * vtx
                    Ty -= ct * vty
                    Tz -= ct * vtz
                    diss += ct * (vtx * vtx + vty * vty + vtz * vtz) * dt
    return Fn, Tx, Ty, Tz, sliding, diss, (h0, h1, h2, e0, e1, e2, T_rev, state)


@overload(law_turns_history, inline="always")
def _hertz_turns_history(law):
    if not (is_params_of(law, HertzParams) or is_params_of(law, HertzParamsMD)):
        return None

    def impl(law):
        return law.rotation == ROTATION_PROJECT
    return impl


@overload(law_force3, inline="always")
def _hertz_force3(law, hist, k, ma, mb, meff, rstar, overlap, vn, vtx, vty, vtz, nx, ny, nz, dt):
    if is_params_of(law, HertzParams):
        return _hertz_force3_impl(False)
    if is_params_of(law, HertzParamsMD):
        return _hertz_force3_impl(True)
    return None


def _hertz_force3_impl(with_md: bool):
    """law_force3's implementation for one of the two parameter types; ``with_md`` a constant of the compiled code."""

    def impl(law, hist, k, ma, mb, meff, rstar, overlap, vn, vtx, vty, vtz, nx, ny, nz, dt):
        # the history row is read here, in one block (columns past the row's width read as its last column,
        # values no mode but Mindlin-Deresiewicz uses), and written back by the caller (law_force3's contract)
        mode = law.tangential[ma, mb]
        last = hist.shape[1] - 1
        row = (hist[k, 0], hist[k, 1], hist[k, 2], hist[k, min(3, last)], hist[k, min(4, last)],
               hist[k, min(5, last)], hist[k, min(6, last)], hist[k, min(7, last)])
        Fn, Tx, Ty, Tz, sliding, diss, row = hertz_contact3(
            law.Estar[ma, mb], law.Gstar[ma, mb], law.mu[ma, mb], law.zn[ma, mb], law.zt[ma, mb], mode,
            law.shear_spring, law.cap, law.rotation, row, meff, rstar, overlap, vn, vtx, vty, vtz, nx, ny, nz, dt, with_md)
        n_row = HISTORY_WIDTH_3D if with_md and mode == TANGENTIAL_MD else 3
        return Fn, Tx, Ty, Tz, sliding, diss, row, n_row
    return impl


@overload(law_energy3, inline="always")
def _hertz_energy3(law, e, hist, k, ma, mb, rstar, overlap):
    if not any(is_params_of(law, cls) for cls in HERTZ_PARAMS_TYPES):
        return None

    def impl(law, e, hist, k, ma, mb, rstar, overlap):
        return hertz_energy_contact3(law.Estar[ma, mb], law.Gstar[ma, mb], law.tangential[ma, mb], law.shear_spring,
                                     e, hist[k, 0], hist[k, 1], hist[k, 2], rstar, overlap)
    return impl


@njit_inline
def hertz_energy_contact3(E, G, mode, shear_spring, e, h0, h1, h2, rstar, overlap):
    """e plus the elastic energy of one 3D contact with tangential history (h0, h1, h2), from the pair's scalar
    parameters (scalars for the reason given in :func:`hertz_contact3`)."""
    if overlap <= 0.0:
        return e
    e += 8.0 / 15.0 * E * math.sqrt(rstar) * overlap ** 2.5  # ∫F dδ
    if mode != TANGENTIAL_NONE:
        kt = 8.0 * G * math.sqrt(rstar * overlap)
        if shear_spring == SHEAR_TOTAL and mode == TANGENTIAL_MINDLIN:
            e += 0.5 * kt * (h0 ** 2 + h1 ** 2 + h2 ** 2)
        else:
            e += 0.5 * (h0 ** 2 + h1 ** 2 + h2 ** 2) / kt
    return e


class HertzMindlin(LawFamily):
    """The Hertz-Mindlin law (this module) as a law family (3D spheres).

    History per 3D contact: the tangential spring (force, or displacement with
    ``shear_spring="total"``), and for Mindlin-Deresiewicz its direction and reversal state.
    Stiffness: Hertz has none fixed — see :meth:`stiffness_at`; the time step of a Hertzian scene
    comes from the Rayleigh-wave estimate (:func:`demflow.build3d.rayleigh_time_step`).
    """

    name = "hertz-mindlin"
    engines = {
        "yade": "FrictMat(young, poisson) + Ip2_FrictMat_FrictMat_MindlinPhys(en, es) + "
                "Law2_ScGeom_MindlinPhys_Mindlin (damping='yade', shear_spring='incremental')",
        "liggghts": "pair gran model hertz tangential history limitForce on "
                    "(damping='liggghts', shear_spring='total')",
    }

    @classmethod
    def accepts(cls, law) -> bool:
        return isinstance(law, HertzMindlinLaw)

    def history_width(self, dim: int = 3) -> int:
        """3 columns (the tangential vector); 8 when some pair uses Mindlin-Deresiewicz (its direction,
        reversal force and branch state): a scene pays only for the history it declares."""
        if dim != 3:
            raise ValueError("the Hertz-Mindlin law is implemented for 3D spheres (dim=3)")
        if any(law.tangential == "mindlin-deresiewicz" for law in self.laws_by_pair.values()):
            return HISTORY_WIDTH_3D
        return 3

    def tables(self) -> dict:
        from ..scene import SceneError

        nm = len(self.material_index)
        t = {key: np.zeros((nm, nm)) for key in ("Estar", "Gstar", "mu", "zn", "zt")}
        t["tangential"] = np.zeros((nm, nm), np.int64)
        for (a, b), law in self.laws_by_pair.items():
            ma, mb = self.scene.materials[a], self.scene.materials[b]
            for name, m in ((a, ma), (b, mb)):
                if m.young is None or m.poisson is None:
                    raise SceneError(f"material {name!r} has no elastic constants: a Hertz-Mindlin law "
                                     f"({a!r}, {b!r}) needs Material(young=E, poisson=nu)")
            ia, ib = self.material_index[a], self.material_index[b]
            et = law.restitution if law.restitution_tangential is None else law.restitution_tangential
            vals = {
                "Estar": effective_modulus(ma.young, ma.poisson, mb.young, mb.poisson),
                "Gstar": effective_shear_modulus(ma.young, ma.poisson, mb.young, mb.poisson),
                "mu": law.friction,
                "zn": zeta_for(law.restitution, law.damping),
                "zt": zeta_for(et, law.damping),
                "tangential": _TANGENTIAL[law.tangential],
            }
            for key, v in vals.items():
                t[key][ia, ib] = v
                t[key][ib, ia] = v
        return t

    def _scene_wide(self, key: str, table: dict):
        vals = {getattr(law, key) for law in self.laws_by_pair.values()}
        if len(vals) > 1:
            from ..scene import SceneError

            raise SceneError(f"Hertz-Mindlin laws disagree on {key} ({sorted(vals)}); it is scene-wide: "
                             "give every law the same")
        return table[vals.pop()] if vals else 0

    def params(self) -> HertzParams | HertzParamsMD:
        """:data:`HertzParamsMD` when some material pair uses Mindlin-Deresiewicz, else :data:`HertzParams`."""
        t = self.tables()
        cls = HertzParamsMD if bool(np.any(t["tangential"] == TANGENTIAL_MD)) else HertzParams
        return cls(**t, shear_spring=self._scene_wide("shear_spring", _SHEAR),
                   cap=self._scene_wide("friction_cap", _CAP),
                   rotation=self._scene_wide("history_rotation", _ROTATION))

    def stiffness_bound(self, law) -> float:
        raise NotImplementedError("Hertz stiffness grows with overlap: use stiffness_at(overlap)")

    def time_step_law(self, law, a: str, b: str, max_overlap: float, r_b: float = math.inf,
                      m_b: float = math.inf):
        """For :func:`demflow.integrate.safe_time_step_3d`: a function of the radii R and the masses m the
        contact dashpots use (a clump member's: its clump's) of spheres of material a, giving (kN, kT, cN, cT)
        of law (a, b) at the largest expected overlap, against partners of radius and dashpot mass at most
        ``r_b``, ``m_b`` (a plane: infinite).  A contact's
        R* = R r/(R + r) <= R r_b/(R + r_b) and δ <= max_overlap × R, so kN <= 2E*√(R*δ) and kT <= 8G*√(R*δ)
        there (the no-slip Mindlin stiffness, also the largest Mindlin-Deresiewicz tangent); kT = 0 when the
        tangential force can never be elastic (no friction, or tangential="none"); the dashpots 2ζ√(k m*)
        with m* = m m'/(m + m') <= m m_b/(m + m_b)."""
        ma, mb = self.scene.materials[a], self.scene.materials[b]
        E = effective_modulus(ma.young, ma.poisson, mb.young, mb.poisson)
        G = effective_shear_modulus(ma.young, ma.poisson, mb.young, mb.poisson)
        et = law.restitution if law.restitution_tangential is None else law.restitution_tangential
        zn, zt = zeta_for(law.restitution, law.damping), zeta_for(et, law.damping)
        sticks = law.friction > 0.0 and law.tangential != "none"

        def constants(R, m, depth=None):
            """``depth``: the length the overlap is a fraction of (default R; an ellipsoid: its smallest
            semi-axis, R being its largest radius of curvature)."""
            rstar = R if math.isinf(r_b) else R * r_b / (R + r_b)
            mstar = m if math.isinf(m_b) else m * m_b / (m + m_b)
            root = np.sqrt(rstar * max_overlap * (R if depth is None else depth))
            kn = 2.0 * E * root
            kt = 8.0 * G * root if sticks else np.zeros_like(R)
            return kn, kt, 2.0 * zn * np.sqrt(kn * mstar), 2.0 * zt * np.sqrt(kt * mstar)
        return constants

    def stiffness_at(self, a: str, b: str, rstar: float, overlap: float) -> tuple[float, float]:
        """(k_n, k_t) of material pair (a, b) at overlap δ for effective radius R* [force/length]."""
        ma, mb = self.scene.materials[a], self.scene.materials[b]
        E = effective_modulus(ma.young, ma.poisson, mb.young, mb.poisson)
        G = effective_shear_modulus(ma.young, ma.poisson, mb.young, mb.poisson)
        return hertz_stiffness(E, rstar, overlap), mindlin_stiffness(G, rstar, overlap)


# ---------------------------------------------------------------- analytic Hertz impact (Johnson)
def hertz_impact(Estar: float, rstar: float, meff: float, v: float) -> dict:
    """Closed-form elastic Hertz impact at relative normal speed v (Johnson 1985 §11.1).

    Peak overlap δ_max = (15 m* v² / (16 E* √R*))^{2/5}; peak force 4/3 E* √R* δ_max^{3/2};
    contact time t_c = 2 (δ_max/v) ∫₀¹ dx/√(1 - x^{5/2}) (= 2.9432 δ_max/v, the integral by scipy).
    """
    from scipy.integrate import quad

    dmax = (15.0 * meff * v * v / (16.0 * Estar * math.sqrt(rstar))) ** 0.4
    integral = quad(lambda x: 1.0 / math.sqrt(1.0 - x ** 2.5), 0.0, 1.0, limit=200)[0]
    return {"overlap_max": dmax, "force_max": 4.0 / 3.0 * Estar * math.sqrt(rstar) * dmax ** 1.5,
            "contact_time": 2.0 * dmax / v * integral}
