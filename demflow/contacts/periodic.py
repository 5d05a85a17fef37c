"""Neighbour lists in a periodic box (minimum image), keyed like the open-box lists.

Discs within reach of a periodic edge get image copies (ghosts) on the far side, shifted by
±lx and/or ±ly; the open-box cell search (:func:`.neighbours.pairs_cell_search`) then runs on
discs plus ghosts, and every pair whose finder is a real disc is kept, its ghost partner
mapped back to the real disc with the shift (sx, sy) [length] that places the partner's image
next to the finder.  A pair whose finder is a ghost is the mirror image of a pair found by a
real finder and is dropped (if a ghost of j lies within reach of i, a ghost of i lies within
reach of j, on the opposite side).  The finder rule is the open box's, on real indices and radii,
so keys (finder, other) are unique and contact history carries across rebuilds and across the
boundary like any other pair's.

Minimum image requires the period to be at least twice the reach 2·r_max + skin, so that no
pair meets through two images and no disc touches its own image; :func:`check_period` refuses
smaller boxes.  :func:`pairs_periodic_brute_force` is the O(N²) reference.
"""
from __future__ import annotations

import numpy as np

from .neighbours import pairs_brute_force_images, pairs_cell_search


def reach(r: np.ndarray, skin: float) -> float:
    """Largest centre distance at which a pair is listed, 2·r_max + skin [length]."""
    return 2.0 * float(r.max()) + skin if r.size else skin


def check_period(box, r: np.ndarray, skin: float) -> None:
    """Refuse a period below twice the reach (minimum image would fail)."""
    need = 2.0 * reach(r, skin)
    for axis, on, L in (("x", box.periodic_x, box.lx), ("y", box.periodic_y, box.ly)):
        if on and not L >= need:
            raise ValueError(
                f"periodic length along {axis} is {L:.6g}, below twice the neighbour reach 2·(2·r_max + skin) = "
                f"{need:.6g}; enlarge the box or reduce the skin (minimum image needs it)")


def _ghosts(x, y, box, reach_):
    """Indices and shifts of the image copies of discs within ``reach_`` of a periodic edge."""
    idx, shx, shy = [], [], []
    xs = [(0.0, np.ones(x.shape[0], bool))]
    ys = [(0.0, np.ones(y.shape[0], bool))]
    if box.periodic_x:
        xs += [(box.lx, x - box.x0 < reach_), (-box.lx, box.x0 + box.lx - x < reach_)]
    if box.periodic_y:
        ys += [(box.ly, y - box.y0 < reach_), (-box.ly, box.y0 + box.ly - y < reach_)]
    for sx, mx in xs:
        for sy, my in ys:
            if sx == 0.0 and sy == 0.0:
                continue
            g = np.flatnonzero(mx & my)
            idx.append(g)
            shx.append(np.full(g.shape[0], sx))
            shy.append(np.full(g.shape[0], sy))
    cat = lambda a, dt: np.concatenate(a).astype(dt) if a else np.empty(0, dt)
    return cat(idx, np.int64), cat(shx, np.float64), cat(shy, np.float64)


def pairs_periodic(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, box):
    """All pairs with surface gap < skin in a periodic box, by cell search over discs and ghosts.

    Centres must lie in the box (see :func:`demflow.space.wrap`).  Returns (finder, other, sx, sy)
    sorted by key finder·(n + n_walls) + other; other >= n denotes wall other - n; (sx, sy) the
    shift of the other disc's image [length] (0 for walls and pairs inside the box).
    """
    n = x.shape[0]
    nw = wall_ax.shape[0]
    check_period(box, r, skin)
    g, gsx, gsy = _ghosts(x, y, box, reach(r, skin))
    ng = g.shape[0]
    xe = np.concatenate([x, x[g] + gsx])
    ye = np.concatenate([y, y[g] + gsy])
    re = np.concatenate([r, r[g]])
    fe, oe = pairs_cell_search(xe, ye, re, skin, wall_ax, wall_ay, wall_bx, wall_by)
    keep = fe < n
    fe, oe = fe[keep], oe[keep]
    is_ghost = (oe >= n) & (oe < n + ng)
    is_wall = oe >= n + ng
    other = oe.copy()
    sx = np.zeros(oe.shape[0])
    sy = np.zeros(oe.shape[0])
    q = oe[is_ghost] - n
    other[is_ghost] = g[q]
    sx[is_ghost] = gsx[q]
    sy[is_ghost] = gsy[q]
    other[is_wall] = oe[is_wall] - ng
    # a ghost partner is listed under the real finder rule only (the mirror pair has the other finder)
    rf, ro = r[fe], r[np.where(is_wall, fe, other)]  # a wall partner has no radius (and is never a ghost)
    finds = (rf > ro) | ((rf == ro) & (fe < other))  # _finds on real indices
    ok = ~is_ghost | finds
    fe, other, sx, sy = fe[ok], other[ok], sx[ok], sy[ok]
    order = np.argsort(fe * (n + nw) + other, kind="stable")
    return fe[order], other[order], sx[order], sy[order]


def pairs_periodic_brute_force(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, box):
    """The O(N²) reference for :func:`pairs_periodic`: every pair by the minimum-image distance."""
    return pairs_brute_force_images(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, box.periodic_x,
                                    box.periodic_y, box.lx, box.ly)
