"""The calculation cycle (thesis §2.2.4.8, C&S "The calculation cycle"), compiled.

:func:`run_steps` advances a built simulation by up to ``n`` steps without returning to
Python, and stops early when the neighbour list must be rebuilt or the run blows up.
Every array is passed in; nothing is allocated per step.

The steps run on a copy of the state with the discs renumbered in spatial (cell) order,
made at each neighbour-list build, so that a pair's two discs lie close in memory
whatever the user's numbering; the public arrays keep the user's numbering.
Per step: the pair forces (one parallel pass over the pair list, writing only what the
later stages read unless the step records), the wall reactions (over the wall pairs
only), the records, the wall velocities, then the force sums and the central-difference
update of every disc fused in one parallel pass over the discs.  The order of every
floating-point operation is that of the original separate kernels (pair forces, per-disc
sums in the CSR order, thesis eqs 2.27-2.30; commit ff80386), so results are the same to
the bit and do not depend on the number of threads.
"""
from __future__ import annotations

import numpy as np

from .contacts.forces import contact_forces_step, pack_discs, wall_sums_listed
from .integrate import sum_and_integrate
from .jit import njit
from .walls import move_walls, set_wall_velocities

DONE = 0
REBUILD = 1
BLOWUP = 2

# A contact overlapping more than this fraction of the smaller radius is a blow-up
# (the linear law is only meaningful for overlaps of a few per cent, thesis §2.2.4.7).
MAX_OVERLAP_RATIO = 0.5
# A disc moving more than this fraction of its radius in one step can cross a contact (or a
# wall) between two force evaluations: the time step no longer resolves the motion.
MAX_STEP_RATIO = 0.5


@njit
def find_pair(finder, other, a, b, n_keys):
    """Index of pair (a, b) in the sorted list, or -1."""
    key = a * n_keys + b
    lo = 0
    hi = finder.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        kk = finder[mid] * n_keys + other[mid]
        if kk < key:
            lo = mid + 1
        else:
            hi = mid
    if lo < finder.shape[0] and finder[lo] * n_keys + other[lo] == key:
        return lo
    return -1




@njit
def kinetic_energy_perm(vx, vy, om, mass, inertia, inv):
    """½Σ(m v² + I ω²) [force·length] of discs stored in slots (disc i in slot inv[i]), summed in
    disc order (the same sum to the bit)."""
    e = 0.0
    for i in range(inv.shape[0]):
        p = inv[i]
        e += 0.5 * (mass[p] * (vx[p] ** 2 + vy[p] ** 2) + inertia[p] * om[p] ** 2)
    return e


@njit
def elastic_energy_perm(finder, other, pos, hist, ovl, mat, wmat, n, kn, ks, has_shear):
    """Energy in the contact springs, Σ N²/2kN + S²/2kS [force·length], with pair k's history and overlap in row pos[k], summed in
    key order (the same sum to the bit)."""
    e = 0.0
    for k in range(finder.shape[0]):
        t = pos[k]
        if ovl[t] <= 0.0:
            continue
        i = finder[k]
        j = other[k]
        mb = wmat[j - n] if j >= n else mat[j]
        e += 0.5 * hist[t, 0] ** 2 / kn[mat[i], mb]
        if has_shear and ks[mat[i], mb] > 0.0:
            e += 0.5 * hist[t, 1] ** 2 / ks[mat[i], mb]
    return e


@njit
def run_steps(n, step0, skin, disp_walls,
              # discs, public (disc order)
              x, y, th, vx, vy, om, r, mass, inertia, C, Cr, mat, xref, yref, gx, gy,
              # discs, internal (slot order: slot p holds disc perm[p])
              perm, inv, r_p, mass_p, inertia_p, C_p, Cr_p, mat_p,
              x_p, y_p, th_p, vx_p, vy_p, om_p, xref_p, yref_p, Fx_p, Fy_p, M_p, P, Fx, Fy, M,
              # contacts, public (key order) and internal
              finder, other, hist, pos, fin_p, oth_p, hist_p, start_p, sidx_p, wall_p,
              f, fn, fs, slide, ovl, cpx, cpy,
              # walls
              wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, wmat, wall_force,
              phase_start, phase_end, phase_vx, phase_vy, phase_om, phase_cx, phase_cy, phase_about_p,
              servo_on, servo_start, servo_F, servo_dx, servo_dy, servo_G, servo_vmax,
              # law
              kn, ks, cn, cs, mu, coh, dt, normal_mode, sliding_mode, has_shear,
              # records
              every, rec_count, rec_step, rec_wall, rec_wallpos, track_a, track_b, rec_track, rec_energy,
              # external force per disc (fluid, thesis §3.4)
              ext, has_ext):
    """Run up to n steps from step ``step0``.

    Returns (steps done, status, disp_walls, rec_count): status DONE, REBUILD (the
    neighbour list is stale: the largest disc displacement since the build plus the wall
    displacement exceeds skin/2) or BLOWUP (non-finite force or overlap beyond
    MAX_OVERLAP_RATIO of a radius; the step that found it was not applied).

    The cycle runs on an internal copy of the state with the discs in spatial order
    (slot p holds disc perm[p], see :func:`demflow.contacts.neighbours.internal_layout`):
    the state is gathered into the slot arrays on entry and scattered back on return, so
    x, y, th, vx, vy, om and hist are the public ones, in disc and key order, between
    calls (as are Fx, Fy, M: each disc's contact force and moment sums of the last step
    applied).  Every sum is taken in the order of the disc-order reference.
    With ``has_ext`` the (n, 3) array ``ext`` (disc order: fx, fy, moment) is added to every
    disc's force sums at every step (the fluid force of a saturated scene, held between fluid
    solves); a dry scene passes has_ext=False and the cycle is unchanged.
    """
    nd = x.shape[0]
    m = finder.shape[0]
    nh = hist.shape[1]
    for p in range(nd):
        i = perm[p]
        x_p[p] = x[i]
        y_p[p] = y[i]
        th_p[p] = th[i]
        vx_p[p] = vx[i]
        vy_p[p] = vy[i]
        om_p[p] = om[i]
        xref_p[p] = xref[i]
        yref_p[p] = yref[i]
        r_p[p] = r[i]
        mass_p[p] = mass[i]
        inertia_p[p] = inertia[i]
        C_p[p] = C[i]
        Cr_p[p] = Cr[i]
        mat_p[p] = mat[i]
    for k in range(m):
        for c in range(nh):
            hist_p[pos[k], c] = hist[k, c]
    done, status, disp_walls, rec_count = _cycle(
        n, step0, skin, disp_walls, inv, mat, x_p, y_p, th_p, vx_p, vy_p, om_p, r_p, mass_p,
        inertia_p, C_p, Cr_p, mat_p, xref_p, yref_p, gx, gy, P, Fx_p, Fy_p, M_p,
        finder, other, pos, fin_p, oth_p, hist_p, start_p, sidx_p, wall_p,
        f, fn, fs, slide, ovl, cpx, cpy,
        wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, wmat, wall_force,
        phase_start, phase_end, phase_vx, phase_vy, phase_om, phase_cx, phase_cy, phase_about_p,
        servo_on, servo_start, servo_F, servo_dx, servo_dy, servo_G, servo_vmax,
        kn, ks, cn, cs, mu, coh, dt, normal_mode, sliding_mode, has_shear,
        every, rec_count, rec_step, rec_wall, rec_wallpos, track_a, track_b, rec_track, rec_energy,
        ext, perm, has_ext)
    for p in range(nd):
        i = perm[p]
        x[i] = x_p[p]
        y[i] = y_p[p]
        th[i] = th_p[p]
        vx[i] = vx_p[p]
        vy[i] = vy_p[p]
        om[i] = om_p[p]
        Fx[i] = Fx_p[p]
        Fy[i] = Fy_p[p]
        M[i] = M_p[p]
    for k in range(m):
        for c in range(nh):
            hist[k, c] = hist_p[pos[k], c]
    return done, status, disp_walls, rec_count


@njit
def _cycle(n, step0, skin, disp_walls, inv, mat, x, y, th, vx, vy, om, r, mass, inertia, C, Cr,
           mat_p, xref, yref, gx, gy, P, Fx, Fy, M,
           finder, other, pos, fin_p, oth_p, hist, start, sidx, wall_pairs,
           f, fn, fs, slide, ovl, cpx, cpy,
           wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, wmat, wall_force,
           phase_start, phase_end, phase_vx, phase_vy, phase_om, phase_cx, phase_cy, phase_about_p,
           servo_on, servo_start, servo_F, servo_dx, servo_dy, servo_G, servo_vmax,
           kn, ks, cn, cs, mu, coh, dt, normal_mode, sliding_mode, has_shear,
           every, rec_count, rec_step, rec_wall, rec_wallpos, track_a, track_b, rec_track, rec_energy,
           ext, perm, has_ext):
    """The steps of :func:`run_steps` on the slot-ordered state (disc arrays and hist
    internal; finder, other, mat public, mapped through inv and pos where records need
    them)."""
    nd = x.shape[0]
    nw = wpx.shape[0]
    n_keys = nd + nw
    pack_discs(x, y, vx, vy, om, r, mat_p, P)
    for s in range(n):
        step = step0 + s
        rec = every > 0 and step % every == 0 and rec_count < rec_step.shape[0]
        nbad = contact_forces_step(fin_p, oth_p, hist, P, nd,
                                   wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, wmat,
                                   kn, ks, cn, cs, mu, coh, dt, normal_mode, sliding_mode, has_shear,
                                   f, rec, fn, fs, slide, ovl, cpx, cpy, MAX_OVERLAP_RATIO)
        if nbad > 0:
            return s, BLOWUP, disp_walls, rec_count
        wall_sums_listed(wall_pairs, oth_p, nd, f, ovl, cpx, cpy, wpx, wpy, wall_force)
        if rec:
            q = rec_count
            rec_step[q] = step
            for w in range(nw):
                rec_wall[q, w, 0] = wall_force[w, 0]
                rec_wall[q, w, 1] = wall_force[w, 1]
                rec_wall[q, w, 2] = wall_force[w, 2]
                rec_wallpos[q, w, 0] = wpx[w]
                rec_wallpos[q, w, 1] = wpy[w]
            for t in range(track_a.shape[0]):
                k = find_pair(finder, other, track_a[t], track_b[t], n_keys)
                if k >= 0:
                    rec_track[q, t, 0] = fn[pos[k]]
                    rec_track[q, t, 1] = fs[pos[k]]
                else:
                    rec_track[q, t, 0] = 0.0
                    rec_track[q, t, 1] = 0.0
            rec_energy[q, 0] = kinetic_energy_perm(vx, vy, om, mass, inertia, inv)
            rec_energy[q, 1] = elastic_energy_perm(finder, other, pos, hist, ovl, mat, wmat, nd, kn, ks,
                                                   has_shear)
            rec_count += 1
        set_wall_velocities(step, wall_force, wpx, wpy, wvx, wvy, wom, wcx, wcy,
                            phase_start, phase_end, phase_vx, phase_vy, phase_om,
                            phase_cx, phase_cy, phase_about_p,
                            servo_on, servo_start, servo_F, servo_dx, servo_dy, servo_G, servo_vmax)
        dmax2, jump2 = sum_and_integrate(start, sidx, f, r, x, y, th, vx, vy, om, mass, inertia, C, Cr,
                                         gx, gy, dt, xref, yref, P, Fx, Fy, M, ext, perm, has_ext)
        if jump2 > MAX_STEP_RATIO * MAX_STEP_RATIO or not np.isfinite(jump2):
            return s + 1, BLOWUP, disp_walls, rec_count
        disp_walls += move_walls(wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, dt)
        if np.sqrt(dmax2) + disp_walls > 0.5 * skin:
            return s + 1, REBUILD, disp_walls, rec_count
    return n, DONE, disp_walls, rec_count
