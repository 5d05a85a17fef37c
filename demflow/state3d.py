"""The state a compiled 3D cycle works on (spheres; the sphere is its own body).

Like :mod:`demflow.state`, each structure is a ``namedtuple`` of NumPy arrays (``float64`` unless
said), passed to kernels as one argument; the law's parameters and the box select compiled code by
their types.  Vectors are (n, 3) C-ordered arrays.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

Spheres3 = namedtuple("Spheres3", [
    "pos",      # (n, 3) centre [length]
    "vel",      # (n, 3) velocity at the half step [length/time]
    "angvel",   # (n, 3) angular velocity at the half step [1/time]
    "quat",     # (n, 4) orientation (w, x, y, z), unit quaternion
    "r",        # radius [length]
    "mass",     # [mass]
    "inertia",  # 2/5 mR² [mass·length²]
    "inv_r2",   # 1/R² (the step-length test)
    "mat",      # material index (int64)
    "fixed",    # int8: 1 = not integrated (moves with its velocity); 2 = a clump member (moved by its body)
    "body",     # (n,) int64: the clump a member belongs to, -1 for a sphere that is its own body
    "FM",       # (n, 6) contact force (0-2) [force] and moment (3-5) [force·length] sums of the last step
    "P",        # (n, 16) packed rows the pair pass reads: pos, vel, angvel, r, mass, mat, fixed, 0...
    "ref",      # (n, 3) position at the last neighbour-list build [length]
    "img",      # (n, 2) int64 periodic image counters along x and y (unwrapped = pos + img·L)
])

Bodies3 = namedtuple("Bodies3", [
    # rigid clumps (bodies made of member spheres; a free sphere is its own body and is not listed here)
    "pos",      # (nb, 3) centre of mass [length]
    "vel",      # (nb, 3) velocity at the half step [length/time]
    "L",        # (nb, 3) angular momentum (world frame) at the half step [mass·length²/time]
    "angvel",   # (nb, 3) angular velocity (world frame) at the half step [1/time]
    "quat",     # (nb, 4) orientation (w, x, y, z): body frame -> world
    "mass",     # (nb,) [mass]
    "moments",  # (nb, 3) principal moments of inertia [mass·length²]
    "start",    # (nb + 1,) int64: members of body b are particles start[b] .. start[b+1]-1
    "offset",   # (n_members, 3) member centres in the body frame [length] (member k of the list)
])

Pairs3 = namedtuple("Pairs3", [
    "i", "j",    # listed pairs in key order, i < j (int64); n <= j < n + nw: plane j - n;
                 # j >= n + nw: triangle j - n - nw
    "hist",      # (m, width) contact history (the law's; columns 0-2 the tangential vector)
    "shift",     # (m, 3) image shift added to j's centre (periodic boxes)
    "fn",        # (m,) total normal force of the last step [force] (0: apart)
    "ft",        # (m, 3) total tangential force on i of the last step [force]
    "ovl",       # (m,) overlap δ of the last step [length] (<= 0: apart)
    "slide",     # (m,) int8 sliding flag
])

Planes3 = namedtuple("Planes3", [
    # every wall body: the planes, then the triangle meshes (a mesh: its reference point, no normal)
    "point", "normal",  # (np, 3) a point [length] and the unit normal towards the spheres
    "vel",              # (np, 3) velocity of the current step [length/time]
    "mat",              # material index (int64)
    "force",            # (np, 3) force of the spheres on the plane [force]
    "ref",              # (np, 3) point at the last neighbour-list build
    "is_mesh",          # (np,) int8: 1 = a triangle mesh (its triangles in Triangles3)
])

Triangles3 = namedtuple("Triangles3", [
    "v",     # (nt, 9) current vertices a, b, c [length]; they translate with their wall body
    "wall",  # (nt,) int64 the wall body (index into Planes3) each triangle belongs to
    "imaged",  # (nt,) int8: 1 = met through its nearest periodic image (TriangleMesh.periodic_images)
])

Loading3 = namedtuple("Loading3", [
    "phase_start", "phase_end",  # (np, K) int64 step ranges [start, end)
    "phase_v",                   # (np, K, 3) prescribed velocity
    "servo_on", "servo_start",   # (np,) int8 / int64
    "servo_F", "servo_G", "servo_vmax",  # (np,) target force, gain, cap
])

Records3 = namedtuple("Records3", [
    "every",       # record every this many steps (0: never)
    "orient",      # bool: integrate the orientation quaternions (Outputs3D.orientation)
    "step",        # (R,) int64
    "plane_force",  # (R, np, 3)
    "plane_pos",   # (R, np, 3)
    "energy",      # (R, 5): kinetic (translation), kinetic (rotation), elastic, potential -m g·x, dissipated
    "unbalanced",  # (R,) mean |out-of-balance force| of free spheres / mean contact normal force (YADE's)
    "contacts",    # (R,) int64 number of touching pairs (sphere-sphere and sphere-plane)
    "peak",        # (R, 2) largest normal force and largest overlap over the listed pairs (a gap is < 0)
    "track_ids",   # (nt,) int64 tracked spheres
    "track",       # (R, nt, 6) position and velocity of the tracked spheres
])

Damping3 = namedtuple("Damping3", [
    "alpha",        # mass-proportional damping C = αm, C* = αI [1/time] (ch3 eq 3.19, Miyata eq 32)
    "c_abs", "c_rot_abs",  # absolute global dashpots C [force·time/length], C* [force·length·time]
    "local",        # Cundall's local non-viscous damping coefficient (Miyata eq 33)
    "adaptive",     # bool: adaptive dynamic relaxation (Underwood 1983; ch3 §3.5.4.2)
    "alpha_now",    # (1,) the adaptive α of the current step [1/time]
    "prev_r",       # (n, 3) out-of-balance force of the previous step (adaptive; (0, 3) otherwise)
    "prev_dx",      # (n, 3) displacement of the previous step (adaptive; (0, 3) otherwise)
])

Box3 = namedtuple("Box3", [
    "periodic_x", "periodic_y",  # bool
    "x0", "y0",                  # lower corner [length]
    "lx", "ly",                  # periods [length] (0 where not periodic)
])


def empty_pairs3(width: int) -> Pairs3:
    i0 = np.empty(0, np.int64)
    return Pairs3(i=i0, j=i0.copy(), hist=np.zeros((0, width)), shift=np.zeros((0, 3)), fn=np.zeros(0),
                  ft=np.zeros((0, 3)), ovl=np.zeros(0), slide=np.zeros(0, np.int8))

Ellipsoids3 = namedtuple("Ellipsoids3", [
    # ellipsoids (each its own rigid body in Bodies3, with one particle row in Spheres3 whose radius
    # is the bounding radius, the largest semi-axis)
    "axes",  # (n, 3) semi-axes a1, a2, a3 along the body axes [length]
    "amin",  # (n,) smallest semi-axis [length] (blow-up test, dedup tolerance)
    "rot",   # (n, 9) row-major rotation body -> world of this step (from Bodies3.quat)
])
