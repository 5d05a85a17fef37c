"""The space discs live in: an open box or one periodic along x and/or y (minimum image).

A periodic box wraps disc centres into [x0, x0 + lx) × [y0, y0 + ly) at every neighbour-list
build, counting the periods crossed per disc (image counters, so unwrapped displacements are
x + ix·lx).  Between builds the centres move freely and each listed pair carries the shift
(sx, sy) [length] that places its other disc at the image nearest the finder
(:mod:`demflow.contacts.periodic`), so a contact across the boundary is an ordinary pair with
history, keyed by (finder, other) like any other.

:func:`other_centre` is compiled per box type: for :class:`~demflow.state.OpenBox` it returns
the other disc's centre unchanged (an open box pays nothing), for
:class:`~demflow.state.PeriodicBox` the centre plus the pair's shift.
"""
from __future__ import annotations

import math

import numpy as np
from numba.extending import overload

from .laws.base import is_params_of
from .state import OpenBox, PeriodicBox


def other_centre(box, sx, sy, k, xj, yj):
    """Centre of pair k's other disc as the finder sees it [length].  Compiled per box type."""
    raise NotImplementedError


@overload(other_centre, inline="always")
def _other_centre(box, sx, sy, k, xj, yj):
    if is_params_of(box, OpenBox):
        return lambda box, sx, sy, k, xj, yj: (xj, yj)
    if is_params_of(box, PeriodicBox):
        return lambda box, sx, sy, k, xj, yj: (xj + sx[k], yj + sy[k])
    return None


def open_box() -> OpenBox:
    return OpenBox(dim=2)


def periodic_box(x0: float, y0: float, lx: float, ly: float) -> PeriodicBox:
    """A box periodic along x when ``lx`` is finite and along y when ``ly`` is finite [length]."""
    return PeriodicBox(dim=2, periodic_x=bool(math.isfinite(lx)), periodic_y=bool(math.isfinite(ly)),
                       x0=float(x0), y0=float(y0), lx=float(lx), ly=float(ly))


def wrap(box, x: np.ndarray, y: np.ndarray, ix: np.ndarray, iy: np.ndarray) -> None:
    """Wrap centres into the periodic box in place, adding the periods crossed to the image
    counters ix, iy (int64).  An open box leaves everything unchanged."""
    if not isinstance(box, PeriodicBox):
        return
    if box.periodic_x:
        _wrap_axis(x, ix, box.x0, box.lx)
    if box.periodic_y:
        _wrap_axis(y, iy, box.y0, box.ly)


def _wrap_axis(x, ix, x0, lx):
    k = np.floor((x - x0) / lx)
    # rounding can leave x - k·lx just at x0 + lx: count one more period there
    k += (x - k * lx) >= x0 + lx
    if np.any(k):
        x -= k * lx
        ix += k.astype(np.int64)
