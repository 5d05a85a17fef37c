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
                         largest_displacements, move_walls3, plane_work, record_step, set_plane_velocities,
                         unbalanced_ratio)


@njit
def run_steps_ellipsoids(n_steps, step0, skin, sp, ell, bodies, pairs, planes, tris, ld, law, g, dmp, dt, rec,
                         rec_count, work):
    """Run up to ``n_steps`` steps of an ellipsoid scene from step ``step0``; stop early for a rebuild
    or a blow-up.  :func:`demflow.stepping3d.run_steps3` with the ellipsoid pair pass and every
    particle moved by its body (:func:`demflow.stepping3d.body_step`).

    ``work`` (4,) accumulates the work done by the planes and by damping (energy balance), the
    Newton iterations of the potential-point solves and the energy the contacts dissipated.  Returns (steps done, status, records written)."""
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
        work[0] += plane_work(planes, dt)
        if dmp.adaptive:
            adapt_damping(sp, g, dmp)
        if recording:
            rec.unbalanced[rec_count] = unbalanced_ratio(sp, bodies, pairs, g)
        ekt, ekr, epot, bjump2, wdamp = body_step(sp, bodies, g, dmp, dt, recording)
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
