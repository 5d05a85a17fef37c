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
def set_wall_velocities(step, walls, ld):
    """Choose each wall's velocity for the move from step ``step`` to ``step + 1``
    (``walls``: :class:`~demflow.state.Walls`, ``ld``: :class:`~demflow.state.Loading`)."""
    nw = walls.px.shape[0]
    for w in range(nw):
        vx = 0.0
        vy = 0.0
        om = 0.0
        cx = walls.px[w]
        cy = walls.py[w]
        if ld.servo_on[w] and step >= ld.servo_start[w]:
            v = servo_wall_velocity(walls.force[w, 0], walls.force[w, 1], ld.servo_F[w],
                                    ld.servo_dx[w], ld.servo_dy[w], ld.servo_G[w], ld.servo_vmax[w])
            vx = v * ld.servo_dx[w]
            vy = v * ld.servo_dy[w]
        else:
            for k in range(ld.phase_start.shape[1]):
                if ld.phase_start[w, k] <= step < ld.phase_end[w, k]:
                    vx = ld.phase_vx[w, k]
                    vy = ld.phase_vy[w, k]
                    om = ld.phase_om[w, k]
                    if not ld.phase_about_p[w, k]:
                        cx = ld.phase_cx[w, k]
                        cy = ld.phase_cy[w, k]
                    break
        walls.vx[w] = vx
        walls.vy[w] = vy
        walls.om[w] = om
        walls.cx[w] = cx
        walls.cy[w] = cy


@njit
def move_walls(walls, dt):
    """Move every wall by one step: rotate P and e by ωΔt about the pivot, then translate
    P and the pivot by vΔt.  Returns the largest displacement of any wall point [length]."""
    wpx, wpy, wex, wey = walls.px, walls.py, walls.ex, walls.ey
    wcx, wcy, wvx, wvy, wom = walls.cx, walls.cy, walls.vx, walls.vy, walls.om
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
        for h in (walls.h1[w], walls.h2[w]):
            qx = wpx[w] + h * wex[w] - wcx[w]
            qy = wpy[w] + h * wey[w] - wcy[w]
            reach = max(reach, np.sqrt(qx * qx + qy * qy))
        d = np.sqrt(wvx[w] ** 2 + wvy[w] ** 2) * dt + abs(a) * reach
        dmax = max(dmax, d)
    return dmax


def prescribed_wall_points(walls, loading, dt, steps):
    """Each wall's reference point P after each step in ``steps`` (int), moving the walls of a built,
    un-run simulation by their phases only (servo control off) on a copy [length]; (len(steps), nw, 2)."""
    w = walls._replace(**{k: np.array(getattr(walls, k), dtype=np.float64) for k in
                          ("px", "py", "ex", "ey", "vx", "vy", "om", "cx", "cy")})
    w = w._replace(force=np.zeros_like(walls.force), cx=w.px.copy(), cy=w.py.copy(),
                   vx=np.zeros_like(w.vx), vy=np.zeros_like(w.vy), om=np.zeros_like(w.om))
    ld = loading._replace(servo_on=np.zeros_like(loading.servo_on))
    out = np.zeros((len(steps), w.px.shape[0], 2))
    want = {int(st): q for q, st in enumerate(steps)}
    last = int(max(steps)) if len(steps) else 0
    for st in range(last + 1):
        if st in want:
            out[want[st], :, 0] = w.px
            out[want[st], :, 1] = w.py
        set_wall_velocities(st, w, ld)
        move_walls(w, dt)
    return out
