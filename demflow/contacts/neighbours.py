"""Neighbour lists: which disc-disc and disc-wall pairs may touch before the next rebuild.

A pair is listed when the gap between the two surfaces is below ``skin`` (thesis DNTOL,
eq 2.33).  The list is rebuilt when the largest disc displacement since the last build,
plus the largest wall displacement, exceeds skin/2, so no contact can form unseen.

Pairs are keyed: every disc-disc pair is "found" by one of its two discs, the *finder*
(the larger disc; for equal radii the lower index), so the key (finder, other) is unique.
Walls are numbered after the discs (other = n_discs + w).  Lists are produced sorted by
key, which lets :func:`transfer_history` carry tangential history across rebuilds with a
merge (keyed by pair, thesis §2.2.4.5 "update list of contacts made or broken").

Cell search (thesis §2.2.4.5 boxes, generalised): discs are binned by centre into square
cells of side h ≈ 2·r_median + skin; each disc searches only for discs no larger than
itself, within ceil((2r + skin)/h) cells.  Small discs look at their 3×3 block, a rare
large disc at a wider block, so the search stays O(N) for radius ratios of 100:1 and more.
:func:`pairs_brute_force` is the O(N²) reference the cell search is tested against.
"""
from __future__ import annotations

import numpy as np

from ..jit import njit, njit_parallel
from numba import prange


@njit
def point_segment_distance(cx, cy, ax, ay, bx, by):
    """Nearest point q of segment AB to point C; returns (qx, qy, |C - q|)."""
    ux = bx - ax
    uy = by - ay
    L2 = ux * ux + uy * uy
    t = 0.0
    if L2 > 0.0:
        t = ((cx - ax) * ux + (cy - ay) * uy) / L2
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
    qx = ax + t * ux
    qy = ay + t * uy
    dx = cx - qx
    dy = cy - qy
    return qx, qy, np.sqrt(dx * dx + dy * dy)


@njit
def _finds(i, j, r):
    """True when disc i is the finder of pair (i, j)."""
    if r[i] > r[j]:
        return True
    if r[i] == r[j] and i < j:
        return True
    return False


@njit
def _grid(x, y, r, skin):
    n = x.shape[0]
    xmin = x.min()
    ymin = y.min()
    xmax = x.max()
    ymax = y.max()
    h = 2.0 * np.median(r) + skin
    # cap the grid at ~4 cells per disc (and 1e7 cells) so sparse scenes stay cheap
    while ((xmax - xmin) / h + 1.0) * ((ymax - ymin) / h + 1.0) > max(4.0 * n, 16.0) and h < 1e300:
        h *= 1.5
    nx = int((xmax - xmin) / h) + 1
    ny = int((ymax - ymin) / h) + 1
    cell = np.empty(n, np.int64)
    for i in range(n):
        cx = int((x[i] - xmin) / h)
        cy = int((y[i] - ymin) / h)
        if cx >= nx:
            cx = nx - 1
        if cy >= ny:
            cy = ny - 1
        cell[i] = cy * nx + cx
    counts = np.zeros(nx * ny + 1, np.int64)
    for i in range(n):
        counts[cell[i] + 1] += 1
    start = np.cumsum(counts)
    order = np.empty(n, np.int64)
    fill = start[:-1].copy()
    for i in range(n):
        c = cell[i]
        order[fill[c]] = i
        fill[c] += 1
    return xmin, ymin, h, nx, ny, cell, start, order


@njit
def _disc_candidates(i, x, y, r, skin, xmin, ymin, h, nx, ny, start, order, out):
    """Write the 'other' discs of pairs found by disc i into out; return their count."""
    reach = int(np.ceil((2.0 * r[i] + skin) / h))
    cx = int((x[i] - xmin) / h)
    cy = int((y[i] - ymin) / h)
    if cx >= nx:
        cx = nx - 1
    if cy >= ny:
        cy = ny - 1
    m = 0
    for gy in range(max(cy - reach, 0), min(cy + reach, ny - 1) + 1):
        for gx in range(max(cx - reach, 0), min(cx + reach, nx - 1) + 1):
            c = gy * nx + gx
            for k in range(start[c], start[c + 1]):
                j = order[k]
                if j == i or not _finds(i, j, r):
                    continue
                dx = x[j] - x[i]
                dy = y[j] - y[i]
                lim = r[i] + r[j] + skin
                if dx * dx + dy * dy < lim * lim:
                    if out.shape[0] > 0:
                        out[m] = j
                    m += 1
    return m


@njit
def _wall_candidates(i, x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, n, out, m0):
    m = m0
    for w in range(wall_ax.shape[0]):
        qx, qy, d = point_segment_distance(x[i], y[i], wall_ax[w], wall_ay[w], wall_bx[w], wall_by[w])
        if d < r[i] + skin:
            if out.shape[0] > 0:
                out[m] = n + w
            m += 1
    return m


@njit_parallel
def pairs_cell_search(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by):
    """All pairs with surface gap < skin, by cell search.

    Parameters: disc centres x, y [length], radii r [length], skin [length], wall
    endpoints A and B (arrays, one entry per wall).  Returns (finder, other) int64 arrays
    sorted by key; other >= n_discs denotes wall other - n_discs.
    """
    n = x.shape[0]
    empty = np.empty(0, np.int64)
    if n == 0:
        return empty.copy(), empty.copy()
    xmin, ymin, h, nx, ny, cell, start, order = _grid(x, y, r, skin)
    count = np.zeros(n + 1, np.int64)
    for i in prange(n):
        m = _disc_candidates(i, x, y, r, skin, xmin, ymin, h, nx, ny, start, order, empty)
        m = _wall_candidates(i, x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, n, empty, m)
        count[i + 1] = m
    offs = np.cumsum(count)
    total = offs[n]
    finder = np.empty(total, np.int64)
    other = np.empty(total, np.int64)
    for i in prange(n):
        a = offs[i]
        b = offs[i + 1]
        buf = other[a:b]
        m = _disc_candidates(i, x, y, r, skin, xmin, ymin, h, nx, ny, start, order, buf)
        _wall_candidates(i, x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, n, buf, m)
        buf[:m] = np.sort(buf[:m])
        for k in range(a, b):
            finder[k] = i
    return finder, other


@njit
def pairs_brute_force(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by):
    """The O(N²) reference for :func:`pairs_cell_search` (same keys, same order)."""
    n = x.shape[0]
    nw = wall_ax.shape[0]
    cap = n * (n - 1) // 2 + n * nw
    finder = np.empty(cap, np.int64)
    other = np.empty(cap, np.int64)
    m = 0
    for i in range(n):
        for j in range(n):
            if j == i or not _finds(i, j, r):
                continue
            dx = x[j] - x[i]
            dy = y[j] - y[i]
            lim = r[i] + r[j] + skin
            if dx * dx + dy * dy < lim * lim:
                finder[m] = i
                other[m] = j
                m += 1
        for w in range(nw):
            qx, qy, d = point_segment_distance(x[i], y[i], wall_ax[w], wall_ay[w], wall_bx[w], wall_by[w])
            if d < r[i] + skin:
                finder[m] = i
                other[m] = n + w
                m += 1
    return finder[:m].copy(), other[:m].copy()


@njit
def transfer_history(old_finder, old_other, old_hist, new_finder, new_other, n_keys):
    """Carry per-contact history (rows of old_hist) to the new pair list, keyed by pair.

    Both lists are sorted by key = finder·n_keys + other.  Pairs new to the list start with
    zero history; pairs dropped from it lose theirs (they are apart by more than the skin).
    old_hist has shape (n_old, k); the result has shape (n_new, k).
    """
    k = old_hist.shape[1]
    out = np.zeros((new_finder.shape[0], k))
    a = 0
    na = old_finder.shape[0]
    for b in range(new_finder.shape[0]):
        key = new_finder[b] * n_keys + new_other[b]
        while a < na and old_finder[a] * n_keys + old_other[a] < key:
            a += 1
        if a < na and old_finder[a] * n_keys + old_other[a] == key:
            for c in range(k):
                out[b, c] = old_hist[a, c]
    return out


@njit
def contacts_of_particles(finder, other, n):
    """CSR list of the contacts of each disc: (start[n+1], contact index, side).

    side 0: the disc is the pair's finder (force as computed), 1: it is the other disc
    (equal and opposite force, thesis eq 2.20 moment with its own radius).
    """
    m = finder.shape[0]
    count = np.zeros(n + 1, np.int64)
    for k in range(m):
        count[finder[k] + 1] += 1
        if other[k] < n:
            count[other[k] + 1] += 1
    start = np.cumsum(count)
    fill = start[:-1].copy()
    idx = np.empty(start[n], np.int64)
    side = np.empty(start[n], np.int8)
    for k in range(m):
        i = finder[k]
        idx[fill[i]] = k
        side[fill[i]] = 0
        fill[i] += 1
        j = other[k]
        if j < n:
            idx[fill[j]] = k
            side[fill[j]] = 1
            fill[j] += 1
    return start, idx, side
