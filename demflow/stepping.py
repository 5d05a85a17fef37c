"""The calculation cycle (thesis §2.2.4.8, C&S "The calculation cycle"), compiled.

:func:`run_steps` advances a built simulation by up to ``n`` steps without returning to
Python, and stops early when the neighbour list must be rebuilt or the run blows up.
Every array is passed in; nothing is allocated per step.
"""
from __future__ import annotations

import numpy as np

from .contacts.forces import contact_forces, particle_sums, wall_sums
from .integrate import central_difference
from .jit import njit
from .walls import move_walls, set_wall_velocities

DONE = 0
REBUILD = 1
BLOWUP = 2

# A contact overlapping more than this fraction of the smaller radius is a blow-up
# (the linear law is only meaningful for overlaps of a few per cent, thesis §2.2.4.7).
MAX_OVERLAP_RATIO = 0.5


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
def elastic_energy(finder, other, hist, ovl, mat, wmat, n, kn, ks, has_shear):
    """Energy stored in the contact springs, Σ N²/2kN + S²/2kS [force·length]."""
    e = 0.0
    for k in range(finder.shape[0]):
        if ovl[k] <= 0.0:
            continue
        i = finder[k]
        j = other[k]
        mb = wmat[j - n] if j >= n else mat[j]
        e += 0.5 * hist[k, 0] ** 2 / kn[mat[i], mb]
        if has_shear and ks[mat[i], mb] > 0.0:
            e += 0.5 * hist[k, 1] ** 2 / ks[mat[i], mb]
    return e


@njit
def kinetic_energy(vx, vy, om, mass, inertia):
    """½Σ(m v² + I ω²) with the half-step velocities [force·length]."""
    e = 0.0
    for i in range(vx.shape[0]):
        e += 0.5 * (mass[i] * (vx[i] ** 2 + vy[i] ** 2) + inertia[i] * om[i] ** 2)
    return e


@njit
def run_steps(n, step0, skin, disp_walls,
              # discs
              x, y, th, vx, vy, om, r, mass, inertia, C, Cr, mat, xref, yref, gx, gy,
              # contacts
              finder, other, hist, start, idx, side,
              fx, fy, mi, mj, fn, fs, slide, ovl, cpx, cpy, Fx, Fy, M, d2,
              # walls
              wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, wmat, wall_force,
              phase_start, phase_end, phase_vx, phase_vy, phase_om, phase_cx, phase_cy, phase_about_p,
              servo_on, servo_start, servo_F, servo_dx, servo_dy, servo_G, servo_vmax,
              # law
              kn, ks, cn, cs, mu, coh, dt, normal_mode, sliding_mode, has_shear,
              # records
              every, rec_count, rec_step, rec_wall, rec_wallpos, track_a, track_b, rec_track, rec_energy):
    """Run up to n steps from step ``step0``.

    Returns (steps done, status, disp_walls, rec_count): status DONE, REBUILD (the
    neighbour list is stale: the largest disc displacement since the build plus the wall
    displacement exceeds skin/2) or BLOWUP (non-finite force or overlap beyond
    MAX_OVERLAP_RATIO of a radius; the step that found it was not applied).
    """
    nd = x.shape[0]
    nw = wpx.shape[0]
    n_keys = nd + nw
    for s in range(n):
        step = step0 + s
        nbad = contact_forces(finder, other, hist, x, y, r, vx, vy, om, mat, nd,
                              wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, wmat,
                              kn, ks, cn, cs, mu, coh, dt, normal_mode, sliding_mode, has_shear,
                              fx, fy, mi, mj, fn, fs, slide, ovl, cpx, cpy, MAX_OVERLAP_RATIO)
        if nbad > 0:
            return s, BLOWUP, disp_walls, rec_count
        particle_sums(start, idx, side, fx, fy, mi, mj, Fx, Fy, M)
        wall_sums(finder, other, nd, fx, fy, ovl, cpx, cpy, wpx, wpy, wall_force)
        if every > 0 and step % every == 0 and rec_count < rec_step.shape[0]:
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
                    rec_track[q, t, 0] = fn[k]
                    rec_track[q, t, 1] = fs[k]
                else:
                    rec_track[q, t, 0] = 0.0
                    rec_track[q, t, 1] = 0.0
            rec_energy[q, 0] = kinetic_energy(vx, vy, om, mass, inertia)
            rec_energy[q, 1] = elastic_energy(finder, other, hist, ovl, mat, wmat, nd, kn, ks, has_shear)
            rec_count += 1
        set_wall_velocities(step, wall_force, wpx, wpy, wvx, wvy, wom, wcx, wcy,
                            phase_start, phase_end, phase_vx, phase_vy, phase_om,
                            phase_cx, phase_cy, phase_about_p,
                            servo_on, servo_start, servo_F, servo_dx, servo_dy, servo_G, servo_vmax)
        dmax2 = central_difference(x, y, th, vx, vy, om, Fx, Fy, M, mass, inertia, C, Cr,
                                   gx, gy, dt, xref, yref, d2)
        disp_walls += move_walls(wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, dt)
        if np.sqrt(dmax2) + disp_walls > 0.5 * skin:
            return s + 1, REBUILD, disp_walls, rec_count
    return n, DONE, disp_walls, rec_count
