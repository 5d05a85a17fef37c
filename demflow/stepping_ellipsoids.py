"""The compiled cycle of an ellipsoid scene (Miyata §2.4): plane motion, the ellipsoid pair pass,
the aspherical rigid-body leapfrog shared with clumps.

The step is :mod:`demflow.stepping3d`'s: the rotations of the bodies are refreshed from their
quaternions, :func:`demflow.contacts.ellipsoids.ellipsoid_forces` computes the contact forces and
moments at x_n, :func:`demflow.stepping3d.body_step` advances every ellipsoid (translation as a
sphere's; rotation by the angular-momentum leapfrog of YADE's exactAsphericalRot, or exactly as a
sphere when the three moments are equal), then planes and meshes move and the rebuild test runs.
This is a separate kernel beside :func:`demflow.stepping3d.run_steps3` (a copy of its loop with the
two calls changed) so that the sphere cycle, and its golden bits, stay untouched.
"""
from __future__ import annotations

import math

import numpy as np

from .contacts.ellipsoids import ellipsoid_forces
from .jit import njit
from .shapes.ellipsoid import rotations
from .stepping3d import (BLOWUP, DONE, MAX_OVERLAP_RATIO, MAX_STEP_RATIO, REBUILD, adapt_damping, body_step,
                         set_plane_velocities)


@njit
def run_steps_ellipsoids(n_steps, step0, skin, sp, ell, bodies, pairs, planes, tris, ld, law, g, dmp, dt, rec,
                         rec_count, work):
    """Run up to ``n_steps`` steps of an ellipsoid scene from step ``step0``; stop early for a rebuild
    or a blow-up.  :func:`demflow.stepping3d.run_steps3` with the ellipsoid pair pass and every
    particle moved by its body (:func:`demflow.stepping3d.body_step`).

    ``work`` (4,) accumulates the work done by the planes and by damping (energy balance), the
    Newton iterations of the potential-point solves and the energy the contacts dissipated.  Returns (steps done, status, records written)."""
    n = sp.pos.shape[0]
    npl = planes.point.shape[0]
    limit2 = (0.5 * skin) ** 2
    for s in range(n_steps):
        step = step0 + s
        set_plane_velocities(step, planes, ld)
        recording = rec.every > 0 and step % rec.every == 0 and rec_count < rec.step.shape[0]
        rotations(bodies.quat, ell.rot)
        status, eel, iters, diss = ellipsoid_forces(sp, ell, pairs, planes, tris, law, dt, recording,
                                                    MAX_OVERLAP_RATIO)
        work[2] += iters
        work[3] += diss
        if status != 0:
            return s, BLOWUP, rec_count
        # work of the planes on the spheres in this step: -F_plane · v_plane Δt
        for p in range(npl):
            work[0] -= dt * (planes.force[p, 0] * planes.vel[p, 0] + planes.force[p, 1] * planes.vel[p, 1]
                             + planes.force[p, 2] * planes.vel[p, 2])
        if dmp.adaptive:
            adapt_damping(sp, g, dmp)
        if recording:
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
            rec.unbalanced[rec_count] = (rsum / nfree) / (fsum / nc) if nfree > 0 and nc > 0 and fsum > 0 else np.inf
        ekt, ekr, epot, bjump2, wdamp = body_step(sp, bodies, g, dmp, dt, recording)
        jump = math.sqrt(bjump2) if bjump2 == bjump2 else np.inf
        work[1] += wdamp
        if jump > MAX_STEP_RATIO or not math.isfinite(jump):
            return s + 1, BLOWUP, rec_count
        if recording:
            r = rec_count
            rec.step[r] = step
            for p in range(npl):
                for a in range(3):
                    rec.plane_force[r, p, a] = planes.force[p, a]
                    rec.plane_pos[r, p, a] = planes.point[p, a]
            rec.energy[r, 0] = ekt
            rec.energy[r, 1] = ekr
            rec.energy[r, 2] = eel
            rec.energy[r, 3] = epot
            rec.energy[r, 4] = work[1]
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
            rec_count += 1
        for p in range(npl):
            for a in range(3):
                planes.point[p, a] += dt * planes.vel[p, a]
        for t in range(tris.v.shape[0]):  # triangles translate with their wall body
            w = tris.wall[t]
            for c in range(3):
                for a in range(3):
                    tris.v[t, 3 * c + a] += dt * planes.vel[w, a]
        # rebuild test: largest sphere displacement plus largest plane displacement since the build
        dmax2 = 0.0
        for i in range(n):
            d2 = ((sp.pos[i, 0] - sp.ref[i, 0]) ** 2 + (sp.pos[i, 1] - sp.ref[i, 1]) ** 2
                  + (sp.pos[i, 2] - sp.ref[i, 2]) ** 2)
            if d2 > dmax2:
                dmax2 = d2
        pmax2 = 0.0
        for p in range(npl):
            d2 = ((planes.point[p, 0] - planes.ref[p, 0]) ** 2 + (planes.point[p, 1] - planes.ref[p, 1]) ** 2
                  + (planes.point[p, 2] - planes.ref[p, 2]) ** 2)
            if d2 > pmax2:
                pmax2 = d2
        if (math.sqrt(dmax2) + math.sqrt(pmax2)) ** 2 > limit2:
            return s + 1, REBUILD, rec_count
    return n_steps, DONE, rec_count
