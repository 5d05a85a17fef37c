"""The state a compiled cycle works on: a few named structures of arrays.

Each structure is a ``namedtuple`` of NumPy arrays (``float64`` unless said) and scalars.  Numba
passes a namedtuple to a kernel as one argument and specialises the kernel on its type, so kernels
take a handful of named structures instead of dozens of loose arrays, and a structure of another
*type* (a periodic box instead of an open one, a Hertz law instead of a linear one) selects other
compiled code once, at build time, with no per-pair branch (see :mod:`demflow.laws.base`).
Python objects never enter a kernel: only these tuples of arrays and numbers do.

Structures (2D discs; the disc is its own body, so bodies and particles coincide):

- :class:`Discs`: per disc, in disc order (the cycle's internal copy is in slot order, packed rows,
  discs renumbered in spatial order at every neighbour-list build).
- :class:`Layout`: the renumbering (perm, inv), the packed rows P the pair kernel reads and the rows
  P, Q and F the step advances.
- :class:`Pairs`: the neighbour list in key order (public) and in internal order, each pair's
  history, the per-step work arrays and the per-pair image shifts of a periodic box.
- :class:`Walls`: segment walls (C&S Fig. 4) and their force; :class:`Loading` their phases and
  servo control (thesis eqs 5.11-5.12).
- :class:`Records`: what a run records per recorded step.
- :class:`OpenBox`, :class:`PeriodicBox`: the space the discs live in.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

Discs = namedtuple("Discs", [
    "x", "y", "th",        # centre [length], rotation θ [rad]
    "vx", "vy", "om",      # velocity at the half step [length/time], spin ω [1/time]
    "r", "mass", "inertia",  # radius [length], mass [mass], moment of inertia ½mR² [mass·length²]
    "C", "Cr",             # global dashpots C [force·time/length] and C* [force·length·time] (eqs 2.27-2.28)
    "mat",                 # material index (int64)
    "xref", "yref",        # position at the last neighbour-list build [length]
    "Fx", "Fy", "M",       # contact force and moment sums of the last step [force], [force·length]
])

Layout = namedtuple("Layout", [
    "perm",  # slot p holds disc perm[p] (int64)
    "inv",   # disc i sits in slot inv[i] (int64)
    "P",     # (n, 8) packed rows (x, y, vx, vy, ω, R, material, θ) of the slots
    "Q",     # (n, 8) packed rows (m, I, C, C*, x_ref, y_ref, 1/R², 0), read-only in the steps (demflow.integrate)
    "F",     # (n, 3) packed rows (F_x, F_y, M): the contact sums of the last step
])

Pairs = namedtuple("Pairs", [
    "finder", "other",   # listed pairs in key order (int64; other >= n: wall other - n)
    "hist",              # (m, width) contact history in key order (the law's, e.g. N and S)
    "sx", "sy",          # image shift of the other disc [length], key order (periodic boxes; else empty)
    "pos",               # pair k in key order sits at internal position pos[k] (int64)
    "fin_p", "oth_p",    # pairs in internal order and slot numbering (uint32)
    "hist_p",            # history in internal order
    "sx_p", "sy_p",      # image shifts in internal order
    "start_p", "sidx_p",  # CSR contacts of each slot (sidx uint32: 2k as pair k's finder, 2k + 1 as its other)
    "wall_p",            # internal positions of the disc-wall pairs, increasing (int64)
    "f",                 # (m, 3) per step, internal order: each pair's force on its finder (fx, fy) and its
                         # shear force Fs (pair_forces; each disc's share is formed where the sums are taken)
    "out",               # PairOutputs in internal order
])

PairOutputs = namedtuple("PairOutputs", [
    "fn", "fs",          # total normal and shear force [force] (written on recorded steps)
    "slide",             # sliding flag (int8)
    "ovl",               # overlap δ [length] (wall pairs: every step)
    "cpx", "cpy",        # contact point [length] (wall pairs: every step)
])

Walls = namedtuple("Walls", [
    "px", "py",   # reference point P [length]
    "ex", "ey",   # unit direction e
    "h1", "h2",   # endpoints P + h1·e, P + h2·e
    "vx", "vy", "om",  # velocity of P [length/time] and spin [1/time] for the current move
    "cx", "cy",   # pivot of the current rotation [length]
    "mat",        # material index (int64)
    "force",      # (nw, 3): force of the discs on the wall and its moment about P
])

Loading = namedtuple("Loading", [
    "phase_start", "phase_end",  # (nw, K) step ranges [start, end) of the phases (int64)
    "phase_vx", "phase_vy", "phase_om",  # (nw, K) prescribed velocity and spin
    "phase_cx", "phase_cy",      # (nw, K) pivot of a rotation
    "phase_about_p",             # (nw, K) int8: 1 = rotate about P itself
    "servo_on", "servo_start",   # (nw,) int8 / int64
    "servo_F", "servo_dx", "servo_dy", "servo_G", "servo_vmax",  # (nw,) target, direction, gain, cap
])

Records = namedtuple("Records", [
    "every",      # record every this many steps (0: never)
    "step",       # (R,) int64
    "wall",       # (R, nw, 3) wall force and moment
    "wallpos",    # (R, nw, 2) wall point P
    "track_a", "track_b",  # tracked pairs (int64 keys)
    "track",      # (R, nt, 2) total normal and shear force of the tracked pairs
    "energy",     # (R, 2) kinetic and elastic energy
])

# The space.  A box is open (no periodic axis) or periodic along x and/or y; the type selects the
# compiled pair geometry (an open box pays nothing for periodicity).
OpenBox = namedtuple("OpenBox", ["dim"])
PeriodicBox = namedtuple("PeriodicBox", [
    "dim",
    "periodic_x", "periodic_y",  # bool
    "x0", "y0",                  # lower corner [length]
    "lx", "ly",                  # period along x and y [length] (inf where not periodic)
])


def empty_pairs(n_hist: int) -> Pairs:
    """A pair list with no pairs and history width ``n_hist``."""
    i0 = np.empty(0, np.int64)
    f0 = np.empty(0)
    return Pairs(finder=i0, other=i0.copy(), hist=np.zeros((0, n_hist)), sx=f0, sy=f0.copy(),
                 pos=i0.copy(), fin_p=np.empty(0, np.uint32), oth_p=np.empty(0, np.uint32),
                 hist_p=np.zeros((0, n_hist)),
                 sx_p=f0.copy(), sy_p=f0.copy(), start_p=np.zeros(1, np.int64), sidx_p=np.empty(0, np.uint32),
                 wall_p=i0.copy(), f=np.zeros((0, 3)), out=pair_outputs(0))


def pair_outputs(m: int) -> PairOutputs:
    """Zeroed per-pair outputs for ``m`` pairs."""
    return PairOutputs(fn=np.zeros(m), fs=np.zeros(m), slide=np.zeros(m, np.int8), ovl=np.zeros(m),
                       cpx=np.zeros(m), cpy=np.zeros(m))


def new_discs(n: int) -> Discs:
    """Zeroed disc arrays for ``n`` discs (material int64)."""
    z = [np.zeros(n) for _ in Discs._fields]
    d = Discs(*z)
    return d._replace(mat=np.zeros(n, np.int64))
