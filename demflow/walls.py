"""Wall motion: prescribed phases (translation, rotation about a point) and servo control.

Timing matches the particles' central differences: the wall velocity used by the contact
law at step N is the one that moved the wall from t_{N-1} to t_N (as v_{N-1/2} for a
disc); walls are at rest before step 0, so at the first step a wall that starts moving
produces no force yet, and one step later the overlap is vΔt (C&S Fig. 1).

Per wall w, phase k covers steps [phase_start[w, k], phase_end[w, k]) with velocity
(phase_vx, phase_vy) of the reference point P and angular velocity phase_om about the
pivot (phase_cx, phase_cy), or about P itself when phase_about_p is 1 (C&S Fig. 4).
Servo walls (thesis eqs 5.11-5.12) override the phases from step servo_start on.
"""
from __future__ import annotations

import numpy as np

from .jit import njit


@njit
def servo_wall_velocity(force_on_wall_x, force_on_wall_y, F_A, dx, dy, gain, v_max):
    """Servo speed along the load direction d (thesis eqs 5.11-5.12) [length/time].

    F_C = -(F_wall · d) is the discs' reaction against the applied load F_A;
    err = (F_A - F_C)/F_A, v₁ = G·err, v = min(v_max, |v₁|)·sign(v₁).
    """
    F_C = -(force_on_wall_x * dx + force_on_wall_y * dy)
    err = (F_A - F_C) / F_A
    v1 = gain * err
    v = min(v_max, abs(v1))
    return v if v1 >= 0.0 else -v


@njit
def set_wall_velocities(step, wall_force, wpx, wpy, wvx, wvy, wom, wcx, wcy,
                        phase_start, phase_end, phase_vx, phase_vy, phase_om,
                        phase_cx, phase_cy, phase_about_p,
                        servo_on, servo_start, servo_F, servo_dx, servo_dy, servo_G, servo_vmax):
    """Choose each wall's velocity for the move from step ``step`` to ``step + 1``."""
    nw = wpx.shape[0]
    for w in range(nw):
        vx = 0.0
        vy = 0.0
        om = 0.0
        cx = wpx[w]
        cy = wpy[w]
        if servo_on[w] and step >= servo_start[w]:
            v = servo_wall_velocity(wall_force[w, 0], wall_force[w, 1], servo_F[w],
                                    servo_dx[w], servo_dy[w], servo_G[w], servo_vmax[w])
            vx = v * servo_dx[w]
            vy = v * servo_dy[w]
        else:
            for k in range(phase_start.shape[1]):
                if phase_start[w, k] <= step < phase_end[w, k]:
                    vx = phase_vx[w, k]
                    vy = phase_vy[w, k]
                    om = phase_om[w, k]
                    if not phase_about_p[w, k]:
                        cx = phase_cx[w, k]
                        cy = phase_cy[w, k]
                    break
        wvx[w] = vx
        wvy[w] = vy
        wom[w] = om
        wcx[w] = cx
        wcy[w] = cy


@njit
def move_walls(wpx, wpy, wex, wey, wh1, wh2, wvx, wvy, wom, wcx, wcy, dt):
    """Move every wall by one step: rotate P and e by ωΔt about the pivot, then translate
    P and the pivot by vΔt.  Returns the largest displacement of any wall point [length]."""
    dmax = 0.0
    for w in range(wpx.shape[0]):
        a = wom[w] * dt
        if a != 0.0:
            c = np.cos(a)
            s = np.sin(a)
            rx = wpx[w] - wcx[w]
            ry = wpy[w] - wcy[w]
            wpx[w] = wcx[w] + c * rx - s * ry
            wpy[w] = wcy[w] + s * rx + c * ry
            ex = wex[w]
            ey = wey[w]
            wex[w] = c * ex - s * ey
            wey[w] = s * ex + c * ey
        wpx[w] += wvx[w] * dt
        wpy[w] += wvy[w] * dt
        wcx[w] += wvx[w] * dt
        wcy[w] += wvy[w] * dt
        # farthest wall point from the pivot bounds the rotational displacement
        reach = 0.0
        for h in (wh1[w], wh2[w]):
            qx = wpx[w] + h * wex[w] - wcx[w]
            qy = wpy[w] + h * wey[w] - wcy[w]
            reach = max(reach, np.sqrt(qx * qx + qy * qy))
        d = np.sqrt(wvx[w] ** 2 + wvy[w] ** 2) * dt + abs(a) * reach
        dmax = max(dmax, d)
    return dmax
