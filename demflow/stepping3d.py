"""The compiled 3D calculation cycle: plane motion, contact forces, central-difference integration.

One step (ch3 eqs 3.19-3.20, the leapfrog scheme of the thesis §2.2.4 in 3D):

1. planes take their velocity for this step (prescribed phases or the servo, eqs 5.11-5.12);
2. contact forces and moments at the positions x_n (:func:`demflow.contacts.spheres.sphere_forces`);
3. each free sphere: F = F_contact + m g, Cundall's local damping (Miyata eq 33) on every component,
   F_c ← F_c (1 - α_l sign(F_c (v_c + F_c Δt/2m))) (YADE's NewtonIntegrator), then with
   mass-proportional damping C = αm (ch3 eq 3.19)
   v_{n+1/2} = ((m/Δt - C/2) v_{n-1/2} + F) / (m/Δt + C/2), x_{n+1} = x_n + Δt v_{n+1/2};
   the same for ω with the moment of inertia and the moment (a sphere's inertia is isotropic, so
   Euler's equations reduce to this); the orientation quaternion turns by |ω|Δt about ω;
4. planes and triangle meshes move by Δt × their velocity;
5. the neighbour list is rebuilt (by the caller) once a sphere or plane has moved half the skin.

Energies on recorded steps: kinetic with the on-step velocity (v_{n-1/2} + v_{n+1/2})/2, elastic and
potential (-m g·x) at x_n, and the running work of damping and of the planes.
"""
from __future__ import annotations

import math

import numpy as np

from .contacts.spheres import OK, pack_rows, sphere_forces
from .jit import njit, njit_inline

DONE = 0
REBUILD = 1
BLOWUP = 2
MAX_OVERLAP_RATIO = 0.5  # an overlap beyond half the smaller radius is a blow-up
MAX_STEP_RATIO = 0.5  # a step longer than half a radius is a blow-up


@njit_inline
def damped_leapfrog(f, v0, m, a, b, local, dt):
    """One component of the central-difference update (ch3 eq 3.19) with Cundall's local damping (Miyata
    eq 33, YADE's rule: the sign of f·(v0 + f Δt/2m)): returns (damped force, v1 = (a v0 + f) b) with
    a = m/Δt - C/2, b = 1/(m/Δt + C/2) (a moment and a moment of inertia alike)."""
    if local > 0.0:
        s = f * (v0 + 0.5 * dt * f / m)
        if s > 0.0:
            f *= 1.0 - local
        elif s < 0.0:
            f *= 1.0 + local
    return f, (a * v0 + f) * b


@njit
def set_plane_velocities(step, planes, ld):
    for p in range(planes.vel.shape[0]):
        planes.vel[p, 0] = 0.0
        planes.vel[p, 1] = 0.0
        planes.vel[p, 2] = 0.0
        if ld.servo_on[p] and step >= ld.servo_start[p]:
            # spheres push the plane along -normal; F_C is that push
            fc = -(planes.force[p, 0] * planes.normal[p, 0] + planes.force[p, 1] * planes.normal[p, 1]
                   + planes.force[p, 2] * planes.normal[p, 2])
            fa = ld.servo_F[p]
            v = ld.servo_G[p] * (fa - fc) / fa
            vm = ld.servo_vmax[p]
            if v > vm:
                v = vm
            elif v < -vm:
                v = -vm
            for a in range(3):
                planes.vel[p, a] = v * planes.normal[p, a]  # towards the spheres while F_C < F_A
            continue
        for q in range(ld.phase_start.shape[1]):
            if ld.phase_start[p, q] <= step < ld.phase_end[p, q]:
                for a in range(3):
                    planes.vel[p, a] = ld.phase_v[p, q, a]
                break


@njit
def adapt_damping(sp, g, dmp):
    """Adaptive dynamic relaxation (Underwood 1983), ch3 §3.5.4.2's "adaptive equilibrium DR": the
    lowest frequency of the assembly is estimated every step from the Rayleigh quotient of the last
    step, ω² = Σ Δx·(R_old - R_new) / Σ m Δx² (R the out-of-balance force, Δx the last step), and
    the mass-proportional damping is set to its critical value α = 2ω.  Called after the contact
    forces of the step; keeps α when the quotient is not positive."""
    num = 0.0
    den = 0.0
    for i in range(sp.pos.shape[0]):
        if sp.fixed[i]:
            continue
        m = sp.mass[i]
        for a in range(3):
            r = sp.FM[i, a] + m * g[a]
            dx = dmp.prev_dx[i, a]
            num += dx * (dmp.prev_r[i, a] - r)
            den += m * dx * dx
            dmp.prev_r[i, a] = r
    if num > 0.0 and den > 0.0:
        dmp.alpha_now[0] = 2.0 * math.sqrt(num / den)


@njit
def integrate(sp, g, dmp, dt, recording, orient):
    """Advance free spheres by one step (module docstring).  Returns (kinetic translation,
    kinetic rotation, potential, largest step length / radius, damping work this step, work of the
    fixed spheres on the others this step).  A fixed sphere moves with its prescribed velocity whatever
    its contacts push, so it works on the free spheres: -(F·v + M·ω)Δt, F and M its contact sums
    (the energy balance of :class:`demflow.simulation3d.Simulation3D`; every step)."""
    n = sp.pos.shape[0]
    alpha = dmp.alpha + (dmp.alpha_now[0] if dmp.adaptive else 0.0)
    c_abs = dmp.c_abs
    alpha_rot_abs = dmp.c_rot_abs
    local = dmp.local
    damped = alpha != 0.0 or c_abs != 0.0 or alpha_rot_abs != 0.0 or local > 0.0  # its work: every step
    ekt = 0.0
    ekr = 0.0
    epot = 0.0
    jump2 = 0.0
    wdamp = 0.0
    wfix = 0.0
    inv_dt = 1.0 / dt
    for i in range(n):
        m = sp.mass[i]
        I = sp.inertia[i]
        if sp.fixed[i] == 2:  # a clump member: its body moves it (body_step)
            continue
        if recording:
            epot -= m * (g[0] * sp.pos[i, 0] + g[1] * sp.pos[i, 1] + g[2] * sp.pos[i, 2])
        if sp.fixed[i]:
            for a in range(3):
                wfix -= dt * (sp.FM[i, a] * sp.vel[i, a] + sp.FM[i, 3 + a] * sp.angvel[i, a])
                sp.pos[i, a] += dt * sp.vel[i, a]
            if recording:
                for a in range(3):
                    ekt += 0.5 * m * sp.vel[i, a] ** 2
                    ekr += 0.5 * I * sp.angvel[i, a] ** 2
            continue
        C = alpha * m + c_abs
        Cr = alpha * I + alpha_rot_abs
        # v1 = ((m/Δt - C/2) v0 + F) / (m/Δt + C/2), one division per sphere
        a_t = m * inv_dt - 0.5 * C
        b_t = 1.0 / (m * inv_dt + 0.5 * C)
        a_r = I * inv_dt - 0.5 * Cr
        b_r = 1.0 / (I * inv_dt + 0.5 * Cr)
        step2 = 0.0
        for a in range(3):
            v0 = sp.vel[i, a]
            f, v1 = damped_leapfrog(sp.FM[i, a] + m * g[a], v0, m, a_t, b_t, local, dt)
            sp.vel[i, a] = v1
            d = dt * v1
            sp.pos[i, a] += d
            if dmp.adaptive:
                dmp.prev_dx[i, a] = d
            step2 += d * d
            vm = 0.5 * (v0 + v1)
            if recording:
                ekt += 0.5 * m * vm * vm
            if damped:
                wdamp += (f - sp.FM[i, a] - m * g[a]) * vm * dt - C * vm * vm * dt
        for a in range(3):
            w0 = sp.angvel[i, a]
            t, w1 = damped_leapfrog(sp.FM[i, 3 + a], w0, I, a_r, b_r, local, dt)
            sp.angvel[i, a] = w1
            wm = 0.5 * (w0 + w1)
            if recording:
                ekr += 0.5 * I * wm * wm
            if damped:
                wdamp += (t - sp.FM[i, 3 + a]) * wm * dt - Cr * wm * wm * dt
        if orient:  # q <- dq(ω Δt) ⊗ q (ω in the fixed frame); only when the scene asks for orientations
            wx = sp.angvel[i, 0]
            wy = sp.angvel[i, 1]
            wz = sp.angvel[i, 2]
            wn = math.sqrt(wx * wx + wy * wy + wz * wz)
            if wn > 0.0:
                h = 0.5 * wn * dt
                s = math.sin(h) / wn
                dw, dx, dy, dz = math.cos(h), s * wx, s * wy, s * wz
                qw, qx, qy, qz = sp.quat[i, 0], sp.quat[i, 1], sp.quat[i, 2], sp.quat[i, 3]
                nw = dw * qw - dx * qx - dy * qy - dz * qz
                nx = dw * qx + dx * qw + dy * qz - dz * qy
                ny = dw * qy - dx * qz + dy * qw + dz * qx
                nz = dw * qz + dx * qy - dy * qx + dz * qw
                qi = 1.0 / math.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
                sp.quat[i, 0] = nw * qi
                sp.quat[i, 1] = nx * qi
                sp.quat[i, 2] = ny * qi
                sp.quat[i, 3] = nz * qi
        rel2 = step2 * sp.inv_r2[i]
        if not rel2 <= jump2:  # also catches NaN
            jump2 = rel2 if rel2 == rel2 else np.inf
    return ekt, ekr, epot, math.sqrt(jump2), wdamp, wfix


@njit
def _qmul(aw, ax, ay, az, bw, bx, by, bz):
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


@njit
def _rot(qw, qx, qy, qz, vx, vy, vz, inverse):
    """R(q) v (body -> world), or R(q)^T v with ``inverse``."""
    if inverse:
        qx, qy, qz = -qx, -qy, -qz
    # v' = v + 2 w (u × v) + 2 u × (u × v), u = (qx, qy, qz)
    cx = qy * vz - qz * vy
    cy = qz * vx - qx * vz
    cz = qx * vy - qy * vx
    return (vx + 2.0 * (qw * cx + qy * cz - qz * cy), vy + 2.0 * (qw * cy + qz * cx - qx * cz),
            vz + 2.0 * (qw * cz + qx * cy - qy * cx))


@njit
def body_step(sp, bd, g, dmp, dt, recording):
    """Advance the rigid clumps by one step and place their members.

    Force and moment on a body: the sums over its members of F_p and of M_p + (x_p - x_b) × F_p (in
    member order).  Translation exactly as a sphere's.  Rotation: an isotropic body (equal principal
    moments) turns exactly as a sphere; an aspherical one by the leapfrog of the angular momentum
    L_{n+1/2} = L_{n-1/2} + Δt T with the orientation advanced at the half step (YADE's
    ``exactAsphericalRot``, Omelyan 1998): ω_n = I⁻¹ R_nᵀ(L_{n-1/2} + Δt T/2), q_{n+1/2} from ω_n,
    ω_{n+1/2} = I⁻¹ R_{n+1/2}ᵀ L_{n+1/2}, q_{n+1} = q_n + Δt q̇(q_{n+1/2}, ω_{n+1/2}).  Mass-proportional
    damping acts on L as dL/dt = T - αL; its work and local damping's, (T_damped - T - α L_n)·ω_n Δt, are
    counted every step of a damped run (to O(Δt²) per step for an aspherical body; for the others exactly the
    change of ½ m v_{n+1/2}² that damping makes).
    Returns (kinetic translation, kinetic rotation, potential,
    largest squared member step / radius², damping work)."""
    ekt = 0.0
    ekr = 0.0
    epot = 0.0
    jump2 = 0.0
    wdamp = 0.0
    inv_dt = 1.0 / dt
    alpha = dmp.alpha + (dmp.alpha_now[0] if dmp.adaptive else 0.0)
    local = dmp.local
    damped = alpha != 0.0 or dmp.c_abs != 0.0 or dmp.c_rot_abs != 0.0 or local > 0.0  # its work: every step
    F = np.empty(3)  # the body's force and moment sums, reused body after body (no allocation per body)
    T = np.empty(3)
    for b in range(bd.pos.shape[0]):
        m = bd.mass[b]
        s0 = bd.start[b]
        s1 = bd.start[b + 1]
        for a in range(3):
            F[a] = 0.0
            T[a] = 0.0
        for p in range(s0, s1):
            rx = sp.pos[p, 0] - bd.pos[b, 0]
            ry = sp.pos[p, 1] - bd.pos[b, 1]
            rz = sp.pos[p, 2] - bd.pos[b, 2]
            fx = sp.FM[p, 0]
            fy = sp.FM[p, 1]
            fz = sp.FM[p, 2]
            F[0] += fx
            F[1] += fy
            F[2] += fz
            T[0] += sp.FM[p, 3] + (ry * fz - rz * fy)
            T[1] += sp.FM[p, 4] + (rz * fx - rx * fz)
            T[2] += sp.FM[p, 5] + (rx * fy - ry * fx)
        if recording:
            epot -= m * (g[0] * bd.pos[b, 0] + g[1] * bd.pos[b, 1] + g[2] * bd.pos[b, 2])
        C = alpha * m + dmp.c_abs
        a_t = m * inv_dt - 0.5 * C
        b_t = 1.0 / (m * inv_dt + 0.5 * C)
        for a in range(3):
            v0 = bd.vel[b, a]
            f, v1 = damped_leapfrog(F[a] + m * g[a], v0, m, a_t, b_t, local, dt)
            bd.vel[b, a] = v1
            bd.pos[b, a] += dt * v1
            vm = 0.5 * (v0 + v1)
            if recording:
                ekt += 0.5 * m * vm * vm
            if damped:
                wdamp += (f - F[a] - m * g[a]) * vm * dt - C * vm * vm * dt
        I0 = bd.moments[b, 0]
        I1 = bd.moments[b, 1]
        I2 = bd.moments[b, 2]
        qw, qx, qy, qz = bd.quat[b, 0], bd.quat[b, 1], bd.quat[b, 2], bd.quat[b, 3]
        if I0 == I1 and I1 == I2:  # isotropic: as a sphere
            Cr = alpha * I0 + dmp.c_rot_abs
            a_r = I0 * inv_dt - 0.5 * Cr
            b_r = 1.0 / (I0 * inv_dt + 0.5 * Cr)
            for a in range(3):
                w0 = bd.angvel[b, a]
                t, w1 = damped_leapfrog(T[a], w0, I0, a_r, b_r, local, dt)
                bd.angvel[b, a] = w1
                bd.L[b, a] = I0 * w1
                wm = 0.5 * (w0 + w1)
                if recording:
                    ekr += 0.5 * I0 * wm * wm
                if damped:
                    wdamp += (t - T[a]) * wm * dt - Cr * wm * wm * dt
            wx = bd.angvel[b, 0]
            wy = bd.angvel[b, 1]
            wz = bd.angvel[b, 2]
            wn = math.sqrt(wx * wx + wy * wy + wz * wz)
            if wn > 0.0:
                h = 0.5 * wn * dt
                sn = math.sin(h) / wn
                nw, nx, ny, nz = _qmul(math.cos(h), sn * wx, sn * wy, sn * wz, qw, qx, qy, qz)
                qi = 1.0 / math.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
                qw, qx, qy, qz = nw * qi, nx * qi, ny * qi, nz * qi
        else:
            T0x, T0y, T0z = T[0], T[1], T[2]  # the contacts' moment, before local damping
            for a in range(3):
                if local > 0.0:
                    s = T[a] * bd.angvel[b, a]
                    if s > 0.0:
                        T[a] *= 1.0 - local
                    elif s < 0.0:
                        T[a] *= 1.0 + local
            # ω_n (body frame) from L_n = L_{n-1/2} + Δt T / 2
            Lx = bd.L[b, 0] + 0.5 * dt * T[0]
            Ly = bd.L[b, 1] + 0.5 * dt * T[1]
            Lz = bd.L[b, 2] + 0.5 * dt * T[2]
            lx, ly, lz = _rot(qw, qx, qy, qz, Lx, Ly, Lz, True)
            wbx, wby, wbz = lx / I0, ly / I1, lz / I2
            if recording:
                ekr += 0.5 * (wbx * lx + wby * ly + wbz * lz)
            # L_{n+1/2}, with mass-proportional damping dL/dt = T - αL
            Lmx = 0.5 * bd.L[b, 0]
            Lmy = 0.5 * bd.L[b, 1]
            Lmz = 0.5 * bd.L[b, 2]
            for a in range(3):
                L0 = bd.L[b, a]
                bd.L[b, a] = ((inv_dt - 0.5 * alpha) * L0 + T[a]) / (inv_dt + 0.5 * alpha)
            if damped:  # the damping moment (T_damped - T) - α L_n, L_n ≈ (L_{n-1/2} + L_{n+1/2})/2, times ω_n Δt
                Lmx += 0.5 * bd.L[b, 0]
                Lmy += 0.5 * bd.L[b, 1]
                Lmz += 0.5 * bd.L[b, 2]
                ox, oy, oz = _rot(qw, qx, qy, qz, wbx, wby, wbz, False)
                wdamp += dt * ((T[0] - T0x - alpha * Lmx) * ox + (T[1] - T0y - alpha * Lmy) * oy
                               + (T[2] - T0z - alpha * Lmz) * oz)
            # q_{n+1/2} = q_n + Δt/2 · ½ q_n ⊗ (0, ω_n)
            dw, dx, dy, dz = _qmul(qw, qx, qy, qz, 0.0, wbx, wby, wbz)
            hw, hx, hy, hz = qw + 0.25 * dt * dw, qx + 0.25 * dt * dx, qy + 0.25 * dt * dy, qz + 0.25 * dt * dz
            qi = 1.0 / math.sqrt(hw * hw + hx * hx + hy * hy + hz * hz)
            hw, hx, hy, hz = hw * qi, hx * qi, hy * qi, hz * qi
            lx, ly, lz = _rot(hw, hx, hy, hz, bd.L[b, 0], bd.L[b, 1], bd.L[b, 2], True)
            wbx, wby, wbz = lx / I0, ly / I1, lz / I2
            dw, dx, dy, dz = _qmul(hw, hx, hy, hz, 0.0, wbx, wby, wbz)
            nw, nx, ny, nz = qw + 0.5 * dt * dw, qx + 0.5 * dt * dx, qy + 0.5 * dt * dy, qz + 0.5 * dt * dz
            qi = 1.0 / math.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
            qw, qx, qy, qz = nw * qi, nx * qi, ny * qi, nz * qi
            ax_, ay_, az_ = _rot(hw, hx, hy, hz, wbx, wby, wbz, False)
            bd.angvel[b, 0] = ax_
            bd.angvel[b, 1] = ay_
            bd.angvel[b, 2] = az_
        bd.quat[b, 0] = qw
        bd.quat[b, 1] = qx
        bd.quat[b, 2] = qy
        bd.quat[b, 3] = qz
        # place the members: x_p = x_b + R d_p, v_p = v_b + ω × (x_p - x_b), ω_p = ω
        wx = bd.angvel[b, 0]
        wy = bd.angvel[b, 1]
        wz = bd.angvel[b, 2]
        for p in range(s0, s1):
            k = p - bd.start[0]
            dx, dy, dz = _rot(qw, qx, qy, qz, bd.offset[k, 0], bd.offset[k, 1], bd.offset[k, 2], False)
            nx = bd.pos[b, 0] + dx
            ny = bd.pos[b, 1] + dy
            nz = bd.pos[b, 2] + dz
            st = ((nx - sp.pos[p, 0]) ** 2 + (ny - sp.pos[p, 1]) ** 2 + (nz - sp.pos[p, 2]) ** 2) * sp.inv_r2[p]
            if not st <= jump2:
                jump2 = st if st == st else np.inf
            sp.pos[p, 0] = nx
            sp.pos[p, 1] = ny
            sp.pos[p, 2] = nz
            sp.vel[p, 0] = bd.vel[b, 0] + (wy * dz - wz * dy)
            sp.vel[p, 1] = bd.vel[b, 1] + (wz * dx - wx * dz)
            sp.vel[p, 2] = bd.vel[b, 2] + (wx * dy - wy * dx)
            sp.angvel[p, 0] = wx
            sp.angvel[p, 1] = wy
            sp.angvel[p, 2] = wz
    return ekt, ekr, epot, jump2, wdamp


@njit_inline
def plane_work(planes, dt):
    """The work the planes did on the spheres in this step, -Σ F_plane·v_plane Δt (F_plane: the spheres'
    force on the plane)."""
    w = 0.0
    for p in range(planes.point.shape[0]):
        w -= dt * (planes.force[p, 0] * planes.vel[p, 0] + planes.force[p, 1] * planes.vel[p, 1]
                   + planes.force[p, 2] * planes.vel[p, 2])
    return w


@njit_inline
def unbalanced_ratio(sp, bodies, pairs, g):
    """YADE's unbalanced force: the mean |out-of-balance force| (contacts + gravity) of the free spheres and
    the clumps (a clump: the resultant over its members) over the mean normal force of the touching pairs
    (inf when there is none)."""
    n = sp.pos.shape[0]
    rsum = 0.0
    nfree = 0
    for i in range(n):
        if not sp.fixed[i]:
            nfree += 1
            rsum += math.sqrt((sp.FM[i, 0] + sp.mass[i] * g[0]) ** 2 + (sp.FM[i, 1] + sp.mass[i] * g[1]) ** 2
                              + (sp.FM[i, 2] + sp.mass[i] * g[2]) ** 2)
    for b in range(bodies.pos.shape[0]):  # a clump: the resultant over its members
        fx = bodies.mass[b] * g[0]
        fy = bodies.mass[b] * g[1]
        fz = bodies.mass[b] * g[2]
        for p in range(bodies.start[b], bodies.start[b + 1]):
            fx += sp.FM[p, 0]
            fy += sp.FM[p, 1]
            fz += sp.FM[p, 2]
        nfree += 1
        rsum += math.sqrt(fx * fx + fy * fy + fz * fz)
    fsum = 0.0
    nc = 0
    for k in range(pairs.fn.shape[0]):
        if pairs.fn[k] > 0.0:
            fsum += pairs.fn[k]
            nc += 1
    return (rsum / nfree) / (fsum / nc) if nfree > 0 and nc > 0 and fsum > 0 else np.inf


@njit_inline
def record_step(rec, r, step, planes, pairs, sp, ekt, ekr, eel, epot, damping_work, dt):
    """Store record row r of step ``step``: plane forces and positions, energies (module docstring),
    touching pairs, the largest normal force and overlap, and the tracked spheres (position at step n,
    velocity v_{n+1/2})."""
    npl = planes.point.shape[0]
    rec.step[r] = step
    for p in range(npl):
        for a in range(3):
            rec.plane_force[r, p, a] = planes.force[p, a]
            rec.plane_pos[r, p, a] = planes.point[p, a]
    rec.energy[r, 0] = ekt
    rec.energy[r, 1] = ekr
    rec.energy[r, 2] = eel
    rec.energy[r, 3] = epot
    rec.energy[r, 4] = damping_work
    c = 0
    fmax = 0.0
    omax = -np.inf
    for k in range(pairs.fn.shape[0]):
        if pairs.ovl[k] > 0.0:
            c += 1
        fmax = max(fmax, pairs.fn[k])
        omax = max(omax, pairs.ovl[k])
    rec.contacts[r] = c
    rec.peak[r, 0] = fmax
    rec.peak[r, 1] = omax
    for t in range(rec.track_ids.shape[0]):
        i = rec.track_ids[t]
        for a in range(3):
            # the position at step n and the on-step velocity estimate v_{n+1/2} (leapfrog)
            rec.track[r, t, a] = sp.pos[i, a] - dt * sp.vel[i, a]
            rec.track[r, t, 3 + a] = sp.vel[i, a]


@njit_inline
def move_walls3(planes, tris, dt):
    """Planes, and the triangles of each wall body, move by Δt × their velocity."""
    for p in range(planes.point.shape[0]):
        for a in range(3):
            planes.point[p, a] += dt * planes.vel[p, a]
    for t in range(tris.v.shape[0]):  # triangles translate with their wall body
        w = tris.wall[t]
        for c in range(3):
            for a in range(3):
                tris.v[t, 3 * c + a] += dt * planes.vel[w, a]


@njit_inline
def _largest_move2(x, ref):
    """max_i |x_i - ref_i|² over the rows of (m, 3) arrays."""
    m2 = 0.0
    for i in range(x.shape[0]):
        d2 = (x[i, 0] - ref[i, 0]) ** 2 + (x[i, 1] - ref[i, 1]) ** 2 + (x[i, 2] - ref[i, 2]) ** 2
        if d2 > m2:
            m2 = d2
    return m2


@njit_inline
def largest_displacements(sp, planes):
    """The largest squared displacement of a sphere and of a plane since the last neighbour-list build (the
    rebuild test)."""
    return _largest_move2(sp.pos, sp.ref), _largest_move2(planes.point, planes.ref)


@njit
def run_steps3(n_steps, step0, skin, sp, bodies, pairs, planes, tris, ld, law, g, dmp, dt, rec, rec_count, work):
    """Run up to ``n_steps`` steps from step ``step0``; stop early for a rebuild or a blow-up.

    ``work`` (4,) accumulates the work done on the free spheres by the planes and the fixed spheres
    (every step) [0] and by damping (every step of a damped run) [1], and the energy the contacts dissipated [3]
    (the energy balance; [2] is an ellipsoid scene's).  Returns (steps done, status, records written)."""
    limit2 = (0.5 * skin) ** 2
    for s in range(n_steps):
        step = step0 + s
        set_plane_velocities(step, planes, ld)
        recording = rec.every > 0 and step % rec.every == 0 and rec_count < rec.step.shape[0]
        pack_rows(sp)
        status, eel, diss = sphere_forces(sp, pairs, planes, tris, law, dt, recording, MAX_OVERLAP_RATIO)
        work[3] += diss
        if status != OK:
            return s, BLOWUP, rec_count
        work[0] += plane_work(planes, dt)
        if dmp.adaptive:
            adapt_damping(sp, g, dmp)
        if recording:
            rec.unbalanced[rec_count] = unbalanced_ratio(sp, bodies, pairs, g)
        ekt, ekr, epot, jump, wdamp, wfix = integrate(sp, g, dmp, dt, recording, rec.orient)
        work[0] += wfix
        if bodies.pos.shape[0]:
            bkt, bkr, bpot, bjump2, bdamp = body_step(sp, bodies, g, dmp, dt, recording)
            ekt += bkt
            ekr += bkr
            epot += bpot
            wdamp += bdamp
            if not bjump2 <= jump * jump:
                jump = math.sqrt(bjump2) if bjump2 == bjump2 else np.inf
        work[1] += wdamp
        if jump > MAX_STEP_RATIO or not math.isfinite(jump):
            return s + 1, BLOWUP, rec_count
        if recording:
            record_step(rec, rec_count, step, planes, pairs, sp, ekt, ekr, eel, epot, work[1], dt)
            rec_count += 1
        move_walls3(planes, tris, dt)
        dmax2, pmax2 = largest_displacements(sp, planes)
        if (math.sqrt(dmax2) + math.sqrt(pmax2)) ** 2 > limit2:
            return s + 1, REBUILD, rec_count
    return n_steps, DONE, rec_count
