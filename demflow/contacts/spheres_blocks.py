"""The Hertz-Mindlin law of the touching sphere pairs of a block, in one loop the vector units can run.

:func:`demflow.contacts.spheres.sphere_forces` queues a block's touching pairs (its stages 1 and 2) and then, in
pair order, turns each pair's history into the new tangent plane, evaluates the law
(:func:`demflow.laws.hertz_mindlin.hertz_contact3`) and adds the forces (stage 3): a touching pair's three to five
square roots and two or three divisions run one after another in scalar registers, behind branches.  For a
Hertz-Mindlin scene without Mindlin-Deresiewicz (every material pair's tangential model Mindlin's no-slip stiffness,
the engines' model, or none) the pass instead writes each queued sphere pair's numbers into its lane of one work
array (in :func:`demflow.contacts.spheres.sphere_forces` itself: an inlined helper handed the array would keep an
atomic reference-count update per pair), advances all lanes in :func:`hertz_block` -- one loop without a branch,
every condition of the rotation and of the law a choice between two values, which LLVM compiles to vector
instructions (zmm ``vsqrtpd``/``vdivpd`` on the AVX-512 host of 2026-12-03) -- and adds the forces in pair order from
the lanes (stage 3).  Planes and triangles keep the scalar path.

The numbers are those of the scalar path to the bit: every operation is the same IEEE operation in the same order
(a vector square root or division rounds as the scalar one does; ``fastmath`` stays off, so nothing is contracted
or reassociated) and every branch of :func:`demflow.contacts.spheres.rotate_history` and
:func:`demflow.laws.hertz_mindlin.hertz_contact3` is a choice between the same two values, with the same test
(a NaN takes the same side).  The golden tests and tests/test_spheres_blocks.py hold the two paths equal.

The work array is flat, one column of ``COL`` = BLOCK + 8 numbers per quantity: columns a multiple of 4096 bytes
apart make loads wait on unrelated stores (4K aliasing, measured on the 2D pass:
:mod:`demflow.contacts.forces_blocks`), and one array with columns a constant apart lets LLVM prove them
independent for any trip count.
"""
from __future__ import annotations

import math

import numpy as np
from numba.extending import overload

from ..jit import njit, njit_inline
from ..laws.hertz_mindlin import (HERTZ_PARAMS_TYPES, ROTATION_PROJECT, ROTATION_RESCALE, SHEAR_INCREMENTAL,
                                  SHEAR_TOTAL, TANGENTIAL_MINDLIN, TANGENTIAL_NONE, HertzParams, hertz_contact3)
from ..laws.base import is_params_of

BLOCK = 256  # the pair pass's block (demflow.contacts.spheres.BLOCK): at most BLOCK queued pairs
COL = BLOCK + 8  # a column's length: columns not 4096 bytes apart
LANES = 8  # the loop's trip count is rounded up to a multiple of this (padding lanes keep earlier lanes' numbers)

# input columns: the normal, overlap, effective mass and radius, radii, both spheres' velocity and spin,
# the history row (before its turn into the new tangent plane), the law's five numbers and its tangential model
# (1.0: Mindlin's no-slip stiffness, 0.0: none), the two spheres' material indices (as the packed rows hold them)
(NX, NY, NZ, OV, MEFF, RSTAR, RI, RJ, VIX, VIY, VIZ, WIX, WIY, WIZ, VJX, VJY, VJZ, WJX, WJY, WJZ, H0, H1, H2,
 EST, GST, MU, ZN, ZT, TG, MA, MB) = range(31)
# output columns: the total normal force, the tangential force, the history after the step, sliding (1.0/0.0),
# the energy dissipated, the contact points' arms, the force on sphere i and the moment's cross product n x T
(FN, TX, TY, TZ, NH0, NH1, NH2, SLIDE, DISS, AI, AJ, FX, FY, FZ, CX, CY, CZ) = range(31, 48)
N_COLUMNS = 48
# where each column starts in the work array, unsigned: an index built from these and an unsigned lane is never
# tested for wrap-around (Numba's negative-index test on a signed index)
(NX_AT, NY_AT, NZ_AT, OV_AT, MEFF_AT, RSTAR_AT, RI_AT, RJ_AT, VIX_AT, VIY_AT, VIZ_AT, WIX_AT, WIY_AT, WIZ_AT, VJX_AT,
 VJY_AT, VJZ_AT, WJX_AT, WJY_AT, WJZ_AT, H0_AT, H1_AT, H2_AT, EST_AT, GST_AT, MU_AT, ZN_AT, ZT_AT, TG_AT, MA_AT, MB_AT,
 FN_AT, TX_AT, TY_AT, TZ_AT, NH0_AT, NH1_AT, NH2_AT, SLIDE_AT, DISS_AT, AI_AT, AJ_AT, FX_AT, FY_AT, FZ_AT, CX_AT, CY_AT,
 CZ_AT) = (np.uint64(c * COL) for c in range(N_COLUMNS))


def hertz_blocks(law):
    """True when the pair pass runs this scene's sphere pairs through :func:`hertz_block`: Hertz-Mindlin parameters
    without Mindlin-Deresiewicz (:data:`demflow.laws.hertz_mindlin.HertzParams`: every material pair's tangential
    model Mindlin's no-slip one or none).  Compiled per law (overload): False for every other law."""
    raise NotImplementedError


@overload(hertz_blocks, inline="always")
def _hertz_blocks(law):
    if is_params_of(law, HertzParams):
        def impl(law):
            return True
        return impl

    def impl(law):
        return False
    return impl


def work_array(law):
    """The pass's work array (N_COLUMNS columns of COL), its lanes a contact of finite numbers before any is written
    (every column 1.0 but the history and the velocities, 0.0, and the normal, (1, 0, 0)): a lane the pass does not
    write (a plane's or triangle's slot, or padding) keeps earlier numbers, is computed and never read.  Compiled per
    law (overload): an empty array for a law that has no vector path."""
    raise NotImplementedError


def law_fill(law, W, m):
    """Every lane's law columns those of material m with itself (m as the packed rows hold it).  Compiled per law
    (overload)."""
    raise NotImplementedError


def law_columns(law, W, nl):
    """Lanes 0..nl-1's law columns from their material pair (columns MA, MB: the material indices as the packed
    rows hold them).  Compiled per law (overload)."""
    raise NotImplementedError


def law_block3(law, W, nl, dt):
    """:func:`hertz_block` on lanes 0..nl-1 with the law's scene-wide modes.  Compiled per law (overload)."""
    raise NotImplementedError


@overload(work_array, inline="always")
def _work_array(law):
    if not any(is_params_of(law, cls) for cls in HERTZ_PARAMS_TYPES):
        def impl(law):
            return np.empty(0)
        return impl

    def impl(law):
        W = np.ones(N_COLUMNS * COL)
        for c in (NY, NZ, VIX, VIY, VIZ, WIX, WIY, WIZ, VJX, VJY, VJZ, WJX, WJY, WJZ, H0, H1, H2):
            W[c * COL:(c + 1) * COL] = 0.0
        return W
    return impl


@overload(law_fill)
def _law_fill(law, W, m):
    if not any(is_params_of(law, cls) for cls in HERTZ_PARAMS_TYPES):
        def impl(law, W, m):
            pass
        return impl

    def impl(law, W, m):
        mu = np.uint64(np.int64(m))
        W[EST * COL:(EST + 1) * COL] = law.Estar[mu, mu]
        W[GST * COL:(GST + 1) * COL] = law.Gstar[mu, mu]
        W[MU * COL:(MU + 1) * COL] = law.mu[mu, mu]
        W[ZN * COL:(ZN + 1) * COL] = law.zn[mu, mu]
        W[ZT * COL:(ZT + 1) * COL] = law.zt[mu, mu]
        W[TG * COL:(TG + 1) * COL] = 1.0 if law.tangential[mu, mu] == TANGENTIAL_MINDLIN else 0.0
    return impl


@overload(law_columns)
def _law_columns(law, W, nl):
    if not any(is_params_of(law, cls) for cls in HERTZ_PARAMS_TYPES):
        def impl(law, W, nl):
            pass
        return impl

    def impl(law, W, nl):
        C = COL
        for t in range(nl):
            ma = np.uint64(np.int64(W[MA * C + t]))
            mb = np.uint64(np.int64(W[MB * C + t]))
            W[EST * C + t] = law.Estar[ma, mb]
            W[GST * C + t] = law.Gstar[ma, mb]
            W[MU * C + t] = law.mu[ma, mb]
            W[ZN * C + t] = law.zn[ma, mb]
            W[ZT * C + t] = law.zt[ma, mb]
            W[TG * C + t] = 1.0 if law.tangential[ma, mb] == TANGENTIAL_MINDLIN else 0.0
    return impl


@overload(law_block3, inline="always")
def _law_block3(law, W, nl, dt):
    if not any(is_params_of(law, cls) for cls in HERTZ_PARAMS_TYPES):
        def impl(law, W, nl, dt):
            pass
        return impl

    def impl(law, W, nl, dt):
        hertz_block(W, nl, dt, law.shear_spring, law.rotation, law.cap)
    return impl


@njit_inline
def _lanes(W, nl, dt, shear_spring, rotation, cap):
    """The loop of :func:`hertz_block`; ``shear_spring`` and ``rotation`` are constants where it is inlined."""
    project = rotation == ROTATION_PROJECT
    C = COL
    for q in range(nl):
        nx = W[NX * C + q]
        ny = W[NY * C + q]
        nz = W[NZ * C + q]
        overlap = W[OV * C + q]
        meff = W[MEFF * C + q]
        rstar = W[RSTAR * C + q]
        h0 = W[H0 * C + q]
        h1 = W[H1 * C + q]
        h2 = W[H2 * C + q]
        E = W[EST * C + q]
        G = W[GST * C + q]
        mu = W[MU * C + q]
        zn = W[ZN * C + q]
        zt = W[ZT * C + q]
        mindlin = W[TG * C + q] != 0.0
        if not project:
            # demflow.contacts.spheres.rotate_history: into the new tangent plane, its length kept
            hn = h0 * nx + h1 * ny + h2 * nz
            hh = h0 * h0 + h1 * h1 + h2 * h2
            tx = h0 - hn * nx
            ty = h1 - hn * ny
            tz = h2 - hn * nz
            t2 = tx * tx + ty * ty + tz * tz
            s = math.sqrt(hh / t2)
            rx = tx * s if t2 > 0.0 else 0.0
            ry = ty * s if t2 > 0.0 else 0.0
            rz = tz * s if t2 > 0.0 else 0.0
            turned = hn != 0.0
            h0 = rx if turned else h0
            h1 = ry if turned else h1
            h2 = rz if turned else h2
        # the contact points' velocities (spheres._point_velocity) and their difference (relative_velocity)
        ai = W[RI * C + q] - 0.5 * overlap
        aj = W[RJ * C + q] - 0.5 * overlap
        bj = -aj
        vix = W[VIX * C + q] + ai * (W[WIY * C + q] * nz - W[WIZ * C + q] * ny)
        viy = W[VIY * C + q] + ai * (W[WIZ * C + q] * nx - W[WIX * C + q] * nz)
        viz = W[VIZ * C + q] + ai * (W[WIX * C + q] * ny - W[WIY * C + q] * nx)
        vjx = W[VJX * C + q] + bj * (W[WJY * C + q] * nz - W[WJZ * C + q] * ny)
        vjy = W[VJY * C + q] + bj * (W[WJZ * C + q] * nx - W[WJX * C + q] * nz)
        vjz = W[VJZ * C + q] + bj * (W[WJX * C + q] * ny - W[WJY * C + q] * nx)
        rvx = vix - vjx
        rvy = viy - vjy
        rvz = viz - vjz
        vn = rvx * nx + rvy * ny + rvz * nz
        vtx = rvx - vn * nx
        vty = rvy - vn * ny
        vtz = rvz - vn * nz
        # the law itself, inlined: its branches become the loop's choices (Mindlin-Deresiewicz compiled out)
        mode = TANGENTIAL_MINDLIN if mindlin else TANGENTIAL_NONE
        Fn, Tx, Ty, Tz, sliding, diss, row = hertz_contact3(
            E, G, mu, zn, zt, mode, shear_spring, cap, rotation, (h0, h1, h2, 0.0, 0.0, 0.0, 0.0, 0.0), meff, rstar,
            overlap, vn, vtx, vty, vtz, nx, ny, nz, dt, False)
        g0, g1, g2 = row[0], row[1], row[2]
        W[FN * C + q] = Fn
        W[TX * C + q] = Tx
        W[TY * C + q] = Ty
        W[TZ * C + q] = Tz
        W[NH0 * C + q] = g0
        W[NH1 * C + q] = g1
        W[NH2 * C + q] = g2
        W[SLIDE * C + q] = 1.0 if sliding else 0.0
        W[DISS * C + q] = diss
        W[AI * C + q] = ai
        W[AJ * C + q] = aj
        W[FX * C + q] = -Fn * nx + Tx
        W[FY * C + q] = -Fn * ny + Ty
        W[FZ * C + q] = -Fn * nz + Tz
        W[CX * C + q] = ny * Tz - nz * Ty
        W[CY * C + q] = nz * Tx - nx * Tz
        W[CZ * C + q] = nx * Ty - ny * Tx


@njit
def hertz_block(W, nl, dt, shear_spring, rotation, cap):
    """Advance lanes 0..nl-1 of the work array (input columns NX..ZT) by one step: the history turned into the new
    tangent plane (``rotation`` not ROTATION_PROJECT), the contact points' relative velocity, and
    :func:`demflow.laws.hertz_mindlin.hertz_contact3` with Mindlin's no-slip stiffness; writes the output columns
    FN..CZ.  ``shear_spring``, ``rotation``, ``cap``: the law's scene-wide SHEAR_*, ROTATION_*, CAP_* values (one
    loop compiled per combination of the first two)."""
    if shear_spring == SHEAR_TOTAL:
        if rotation == ROTATION_PROJECT:
            _lanes(W, nl, dt, SHEAR_TOTAL, ROTATION_PROJECT, cap)
        else:
            _lanes(W, nl, dt, SHEAR_TOTAL, ROTATION_RESCALE, cap)
    else:
        if rotation == ROTATION_PROJECT:
            _lanes(W, nl, dt, SHEAR_INCREMENTAL, ROTATION_PROJECT, cap)
        else:
            _lanes(W, nl, dt, SHEAR_INCREMENTAL, ROTATION_RESCALE, cap)
