"""The linear law's disc-disc pairs in blocks of :data:`BLOCK` pairs, so the vector units do the arithmetic.

:func:`pair_forces` evaluates one pair at a time: each pair's square root, divisions and law run one after
another in scalar registers.  Here a block of pairs is (1) gathered, pair by pair, into a work array of
columns (the centre difference, radii sum, relative velocities, the law's six numbers, the old history),
(2) advanced in one loop over the block with no branch (every condition of the law a choice), which LLVM
turns into vector instructions (on the AVX-512 host of 2026-12-03: ``vsqrtpd`` and ``vdivpd`` on 8-lane zmm
registers, masked stores for the choices), and (3) scattered back: the history, the force row and the dissipation
sum of each pair.  A block's columns are ``COL`` = BLOCK + 8 numbers long: with 256-pair blocks (sessions 45-48)
columns a multiple of 4096 bytes apart made loads wait on unrelated stores (4K aliasing; on that host's 1e4-disc
benchmark state the padding took the pass from 1.03 of the scalar pass's time to 0.74-0.77, ratio of the minima:
benchmarks/results/speed_experiments_session45.md).  Blocks of 16 pairs since session 49 (see :data:`BLOCK`).  One material pair in a block (a packing of
one material) fills the law's six columns with its row instead of reading each pair's, and once for a chunk of such
blocks (session 48).

Measured (benchmarks/results/speed2d_session45_blocks_ab.md, in one process against the scalar pass, 20 rounds,
AMD EPYC Zen 4): the whole 2D step 0.885 of its time at 1e4 discs (per-round median; ratio of the minima 0.896);
at 1e5 0.992 (1.057) with 256-pair blocks, whose 44 KB of work arrays pushed the pairs' rows out of the first-level
cache between the gather and the scatter: what sessions 45-48 read as the pass waiting on memory.

The numbers are those of :func:`pair_forces` with :func:`demflow.laws.linear.linear_contact` to the bit:
every operation is the same IEEE operation in the same order (a vector square root or division rounds as
the scalar one does; no contraction into fused multiply-adds, no reassociation: ``fastmath`` stays off),
and every branch of the scalar code is a choice between the same two values.  Pairs not touching get zero
force and lose their history; every pair adds its dissipation to ``diss``, 0.0 for a pair not touching, which
leaves a sum as it was unless the sum is -0.0: the sums start at +0.0 (:func:`demflow.stepping.run_steps`: zero on
entry) and a round-to-nearest sum is -0.0 only when both terms are.  The golden tests and tests/test_forces_blocks.py hold the two
passes equal.

Only what the vector loop can do is done here: disc-disc pairs on steps that do not record.  Wall pairs
(``oth >= n``) are left untouched, for :func:`pair_forces` called on ``pairs.wall_p`` only; a recording step
runs :func:`pair_forces` on every pair (it writes the full per-pair outputs).  :func:`step_pair_forces` is
the step's choice (compiled per law: other laws keep the scalar pass).
"""
from __future__ import annotations

import numpy as np
from numba import prange
from numba.extending import overload

from ..jit import njit, njit_parallel
from ..laws.base import is_params_of
from ..laws.linear import LinearParams, linear_contact
from ..space import other_centre
from .forces import pair_forces

# pairs per block: a fixed trip count, so the vector loop's columns are provably apart.  16 since session 49: the work
# arrays of a block (21 columns) then take 4 KB instead of 44 KB (256 pairs, sessions 45-48), and the pass over the
# 1e5-disc benchmark state took 0.72-0.73 of its time (10.6 against 14.8 ns a pair, nearly the 1e4 state's 9.5), at
# 1e4 0.88-0.93 (speed_experiments_session49.md): a block's gathered rows and its history, force and dissipation
# rows are still in the first-level cache when the block scatters back
BLOCK = 16
COL = BLOCK + 8  # a column's length in the work arrays: columns not 4096 bytes apart (no 4K aliasing)
CHUNK = 256  # blocks per parallel task (its work arrays allocated once: 4096 pairs); the results do not depend on it

# the work array's input columns (each BLOCK long)
_DX, _DY, _RS, _RMIN, _RVX, _RVY, _SPIN, _KN, _KS, _CN, _CS, _MU, _COH, _NOLD, _SOLD = range(15)
N_IN = 15
# output columns
_N, _S, _FX, _FY, _FS, _DISS = range(6)
N_OUT = 6


@njit
def linear_block(W, O, dt, normal_mode, sliding_mode, has_shear, max_overlap_ratio):
    """Advance the BLOCK pairs of the work array W (columns ``_DX`` ...) by one step of the linear law,
    branch-free; writes O (columns ``_N`` ...): the new history (N, S), the force on the finder and the
    shear force (fx, fy, Fs) and the energy dissipated (0.0 when not touching).  Returns the number of pairs
    with a blow-up (overlap beyond ``max_overlap_ratio`` of the smaller radius, or a force not finite).
    The operations and their order are those of :func:`demflow.contacts.forces.pair_forces` and
    :func:`demflow.laws.linear.linear_contact`."""
    B = BLOCK
    C = COL
    nbad = 0
    for q in range(B):
        dx = W[_DX * C + q]
        dy = W[_DY * C + q]
        rs = W[_RS * C + q]
        rvx = W[_RVX * C + q]
        rvy = W[_RVY * C + q]
        spin = W[_SPIN * C + q]
        kn = W[_KN * C + q]
        ks = W[_KS * C + q]
        cn = W[_CN * C + q]
        cs = W[_CS * C + q]
        mu = W[_MU * C + q]
        coh = W[_COH * C + q]
        n_old = W[_NOLD * C + q]
        s_old = W[_SOLD * C + q]
        d2 = dx * dx + dy * dy
        D = np.sqrt(d2)
        overlap = rs - D
        ex = dx / D
        ey = dy / D
        if not D > 0.0:
            ex = 1.0
            ey = 0.0
        tx = ey
        ty = -ex
        ndot = rvx * ex + rvy * ey
        sdot = rvx * tx + rvy * ty - spin
        # the law (eqs 2.13-2.19): LLVM inlines it, and its branches become choices of the vector loop
        N, S, Fn, Fs, sliding = linear_contact(overlap, ndot, sdot, n_old, s_old, dt, kn, ks, cn, cs, mu, coh,
                                               normal_mode, sliding_mode, has_shear)
        dissipated = ((Fn - N) * ndot + (Fs - S) * sdot) * dt
        slip = abs(S) * abs(s_old + ks * sdot * dt - S) / ks
        if sliding and ks > 0.0:
            dissipated += slip
        fx = -Fn * ex - Fs * tx
        fy = -Fn * ey - Fs * ty
        touching = not overlap <= 0.0
        ok = overlap <= max_overlap_ratio * W[_RMIN * C + q] and np.isfinite(Fn) and np.isfinite(Fs)
        O[_N * C + q] = N if touching else 0.0
        O[_S * C + q] = S if touching else 0.0
        O[_FX * C + q] = fx if touching else 0.0
        O[_FY * C + q] = fy if touching else 0.0
        O[_FS * C + q] = Fs if touching else 0.0
        O[_DISS * C + q] = dissipated if touching else 0.0
        nbad += 1 if (touching and not ok) else 0
    return nbad


@njit_parallel
def linear_pair_forces(fin, oth, hist, sx, sy, P, n, law, box, dt, f, max_overlap_ratio, diss):
    """:func:`demflow.contacts.forces.pair_forces` for the disc-disc pairs of a linear-law scene on a step
    that does not record (the arguments of the same names; wall pairs are not touched): hist, f and diss
    updated in place, the same numbers.  Returns the number of pairs with a blow-up (as pair_forces)."""
    m = fin.shape[0]
    B = BLOCK
    C = COL
    nblocks = (m + B - 1) // B
    row = law.row
    has_shear = law.has_shear
    normal_mode = law.normal_mode
    sliding_mode = law.sliding_mode
    nbad = 0
    nchunks = (nblocks + CHUNK - 1) // CHUNK
    for chunk in prange(nchunks):  # the work arrays allocated once per chunk of blocks
        W = np.empty(N_IN * C)
        O = np.empty(N_OUT * C)
        mats = np.empty(2 * B, np.uint64)  # the block's material pairs (ma, mb), gathered with the geometry
        cbad = 0
        # the material whose law row the six columns of W hold for every lane (-1: none); a packing of one material
        # fills them once per chunk: 0.95 / 0.96 of the pass at 1e5 discs, 0.97 at 1e4 (speed_experiments_session48.md)
        filled = np.int64(-1)
        for b in range(chunk * CHUNK, min((chunk + 1) * CHUNK, nblocks)):
            k0 = b * B
            nb = min(B, m - k0)
            m0 = np.uint64(np.int64(P[np.uint64(fin[np.uint64(k0)]), 6]))  # the first pair's finder's material
            mixed = False
            for q in range(nb):
                k = np.uint64(k0 + q)
                j = oth[k]
                if j >= n:  # a wall pair: apart (an overlap of -1), never written back
                    W[_DX * C + q] = 0.0
                    W[_DY * C + q] = 0.0
                    W[_RS * C + q] = -1.0
                    mats[2 * q] = m0
                    mats[2 * q + 1] = m0
                    continue
                i = np.uint64(fin[k])
                ju = np.uint64(j)
                xi = P[i, 0]
                yi = P[i, 1]
                ri = P[i, 5]
                rj = P[ju, 5]
                xj, yj = other_centre(box, sx, sy, k, P[ju, 0], P[ju, 1])
                W[_DX * C + q] = xj - xi
                W[_DY * C + q] = yj - yi
                W[_RS * C + q] = ri + rj
                W[_RMIN * C + q] = min(ri, rj)
                W[_RVX * C + q] = P[i, 2] - P[ju, 2]
                W[_RVY * C + q] = P[i, 3] - P[ju, 3]
                W[_SPIN * C + q] = P[i, 4] * ri + P[ju, 4] * rj
                ma = np.uint64(np.int64(P[i, 6]))
                mb = np.uint64(np.int64(P[ju, 6]))
                mats[2 * q] = ma
                mats[2 * q + 1] = mb
                mixed |= (ma != m0) | (mb != m0)
                W[_NOLD * C + q] = hist[k, 0]
                W[_SOLD * C + q] = hist[k, 1] if has_shear else 0.0
            # the law's six numbers per lane: one row for the whole block when every pair has the same materials
            # (a packing of one material: no per-pair reads), else each pair's row
            if mixed:
                for q in range(nb):
                    ma = mats[2 * q]
                    mb = mats[2 * q + 1]
                    for c in range(6):
                        W[(_KN + c) * C + q] = row[ma, mb, c]
            elif filled != np.int64(m0):  # (columns already holding m0's row are left as they are)
                for c in range(6):
                    v = row[m0, m0, c]
                    for q in range(B):
                        W[(_KN + c) * C + q] = v
                filled = np.int64(m0)
            if mixed:
                filled = -1
            for q in range(nb, B):  # padding lanes: apart
                W[_DX * C + q] = 0.0
                W[_DY * C + q] = 0.0
                W[_RS * C + q] = -1.0
            bad = linear_block(W, O, dt, normal_mode, sliding_mode, has_shear, max_overlap_ratio)
            for q in range(nb):
                k = np.uint64(k0 + q)
                if oth[k] >= n:
                    continue
                hist[k, 0] = O[_N * C + q]
                if has_shear:
                    hist[k, 1] = O[_S * C + q]
                f[k, 0] = O[_FX * C + q]
                f[k, 1] = O[_FY * C + q]
                f[k, 2] = O[_FS * C + q]
                diss[k] += O[_DISS * C + q]
            cbad += bad
        nbad += cbad
    return nbad


def step_pair_forces(fin, oth, hist, sx, sy, P, n, walls, law, box, dt, f, full, o_fn, o_fs, o_slide, o_ovl, o_cpx,
                     o_cpy, max_overlap_ratio, diss, wwork, wall_p):
    """One step's pair pass: :func:`pair_forces` with its arguments, plus ``wall_p`` (the wall pairs' indices).
    Compiled per law: for the linear law a step that does not record runs :func:`linear_pair_forces` on the
    disc-disc pairs and :func:`pair_forces` on ``wall_p``; otherwise, and for every other law,
    :func:`pair_forces` on every pair.  Returns the number of pairs with a blow-up."""
    raise NotImplementedError


@overload(step_pair_forces, inline="always")
def _step_pair_forces(fin, oth, hist, sx, sy, P, n, walls, law, box, dt, f, full, o_fn, o_fs, o_slide, o_ovl, o_cpx,
                      o_cpy, max_overlap_ratio, diss, wwork, wall_p):
    if is_params_of(law, LinearParams):
        def impl(fin, oth, hist, sx, sy, P, n, walls, law, box, dt, f, full, o_fn, o_fs, o_slide, o_ovl, o_cpx,
                 o_cpy, max_overlap_ratio, diss, wwork, wall_p):
            if full:
                return pair_forces(fin, oth, hist, sx, sy, P, n, walls, law, box, dt, f, full, o_fn, o_fs, o_slide,
                                   o_ovl, o_cpx, o_cpy, max_overlap_ratio, diss, wwork, wall_p, False)
            nbad = linear_pair_forces(fin, oth, hist, sx, sy, P, n, law, box, dt, f, max_overlap_ratio, diss)
            return nbad + pair_forces(fin, oth, hist, sx, sy, P, n, walls, law, box, dt, f, full, o_fn, o_fs,
                                      o_slide, o_ovl, o_cpx, o_cpy, max_overlap_ratio, diss, wwork, wall_p, True)
        return impl

    def impl(fin, oth, hist, sx, sy, P, n, walls, law, box, dt, f, full, o_fn, o_fs, o_slide, o_ovl, o_cpx,
             o_cpy, max_overlap_ratio, diss, wwork, wall_p):
        return pair_forces(fin, oth, hist, sx, sy, P, n, walls, law, box, dt, f, full, o_fn, o_fs, o_slide, o_ovl,
                           o_cpx, o_cpy, max_overlap_ratio, diss, wwork, wall_p, False)
    return impl
