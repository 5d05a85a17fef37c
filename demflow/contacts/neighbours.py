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
itself, in the cells overlapping the square of half-side 2r + skin around its centre.
Small discs look at a 2×2 to 3×3 block, a rare large disc at a wider block, so the search
stays O(N) for radius ratios of 100:1 and more.
:func:`pairs_brute_force` is the O(N²) reference the cell search is tested against.

Builds from a wider list (session 49): a cell search with a larger skin lists every pair the cell search with
the skin would list for as long as the discs and walls moved little since (:func:`outer_list_holds`), so a
build can take the pairs of that wider list whose gap is below the skin now (:func:`pairs_within`, one pass in
key order) and run the cell search only when the wider list no longer holds
(:meth:`demflow.simulation.Simulation._pairs_from_outer_list`).  The lists are the same either way.
"""
from __future__ import annotations

import numpy as np

from numba import prange

from ..jit import njit, njit_inline, njit_parallel


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


@njit_inline
def _finds(i, j, r):
    """True when disc i is the finder of pair (i, j)."""
    if r[i] > r[j]:
        return True
    if r[i] == r[j] and i < j:
        return True
    return False


@njit
def cell_side(r, skin):
    """The cell search's base cell side 2·r_median + skin [length] (before :func:`_grid` widens it for a sparse
    scene): a function of the radii and the skin only, so a simulation computes it once, not at every
    neighbour-list build (the median of 1e5 radii took 1.2 ms of a 28 ms build, session 49)."""
    return 2.0 * np.median(r) + skin


@njit
def _grid(x, y, r, skin):
    return _grid_of_side(x, y, cell_side(r, skin))


@njit
def _grid_of_side(x, y, h):
    """The cell grid of the centres x, y with base cell side h (:func:`cell_side`)."""
    n = x.shape[0]
    xmin = x.min()
    ymin = y.min()
    xmax = x.max()
    ymax = y.max()
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
def _cell_sorted(x, y, r, order):
    """x, y, r in cell order (contiguous per cell: the candidate scan reads no gathers)."""
    n = order.shape[0]
    xs = np.empty(n)
    ys = np.empty(n)
    rs = np.empty(n)
    for k in range(n):
        j = order[k]
        xs[k] = x[j]
        ys[k] = y[j]
        rs[k] = r[j]
    return xs, ys, rs


@njit_inline
def _disc_candidates(i, x, y, r, skin, xmin, ymin, h, nx, ny, start, order, xs, ys, rs, out, a, cap):
    """Count the 'other' discs of pairs found by disc i; write the first ``cap`` of them
    to out[a:].

    Disc i finds discs no larger than itself, so its partners' centres lie within
    L = 2r_i + skin of its own: only the cells overlapping the square [x_i ± L] x [y_i ± L]
    are scanned (2-3 per axis for a typical disc, more for a large one), widened by a
    relative 1e-12 so that rounding in the cell index cannot miss a partner.
    """
    xi = x[i]
    yi = y[i]
    ri = r[i]
    L = 2.0 * ri + skin
    Lm = L + 1e-12 * (L + abs(xi - xmin) + abs(yi - ymin))
    gx0 = max(int((xi - Lm - xmin) / h), 0)
    gx1 = min(int((xi + Lm - xmin) / h), nx - 1)
    gy0 = max(int((yi - Lm - ymin) / h), 0)
    gy1 = min(int((yi + Lm - ymin) / h), ny - 1)
    m = 0
    for gy in range(gy0, gy1 + 1):
        # the cells gx0..gx1 of row gy are contiguous in cell order: one run of candidates
        for k in range(start[gy * nx + gx0], start[gy * nx + gx1 + 1]):
            rj = rs[k]
            dx = xs[k] - xi
            dy = ys[k] - yi
            lim = ri + rj + skin
            if dx * dx + dy * dy < lim * lim:
                j = order[k]
                if j == i or rj > ri or (rj == ri and j < i):
                    continue  # not found by i (see _finds)
                if m < cap:
                    out[a + m] = j
                m += 1
    return m


@njit
def _wall_boxes(wall_ax, wall_ay, wall_bx, wall_by, reach):
    """Each wall segment's bounding box widened by ``reach`` (the largest radius plus the skin) and by a relative
    1e-9 of its size and coordinates: rows (x0, y0, x1, y1).  A centre outside the box is farther than reach
    from the segment by more than the rounding of :func:`point_segment_distance`, so that test would reject it
    too (it is skipped, with its division and square root)."""
    nw = wall_ax.shape[0]
    box = np.empty((nw, 4))
    for w in range(nw):
        e = reach + 1e-9 * (reach + abs(wall_ax[w]) + abs(wall_ay[w]) + abs(wall_bx[w]) + abs(wall_by[w]))
        box[w, 0] = min(wall_ax[w], wall_bx[w]) - e
        box[w, 1] = min(wall_ay[w], wall_by[w]) - e
        box[w, 2] = max(wall_ax[w], wall_bx[w]) + e
        box[w, 3] = max(wall_ay[w], wall_by[w]) + e
    return box


@njit_inline
def _wall_candidates(i, x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, wall_box, n, out, a, cap, m0):
    m = m0
    xi = x[i]
    yi = y[i]
    for w in range(wall_ax.shape[0]):
        if not (wall_box[w, 0] <= xi <= wall_box[w, 2] and wall_box[w, 1] <= yi <= wall_box[w, 3]):
            continue  # certainly farther than r + skin (see _wall_boxes)
        qx, qy, d = point_segment_distance(xi, yi, wall_ax[w], wall_ay[w], wall_bx[w], wall_by[w])
        if d < r[i] + skin:
            if m < cap:
                out[a + m] = n + w
            m += 1
    return m


@njit
def _sort_small(v, a, b):
    """Sort v[a:b] in place: insertion sort for the usual handful of entries, np.sort
    (allocating) only for long lists (a large disc among many small ones)."""
    if b - a > 32:
        v[a:b] = np.sort(v[a:b])
        return
    for p in range(a + 1, b):
        t = v[p]
        q = p - 1
        while q >= a and v[q] > t:
            v[q + 1] = v[q]
            q -= 1
        v[q + 1] = t


@njit
def pairs_cell_search(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by):
    """All pairs with surface gap < skin, by cell search.

    Parameters: disc centres x, y [length], radii r [length], skin [length], wall
    endpoints A and B (arrays, one entry per wall).  Returns (finder, other) int64 arrays
    sorted by key; other >= n_discs denotes wall other - n_discs.
    """
    if x.shape[0] == 0:
        empty = np.empty(0, np.int64)
        return empty.copy(), empty.copy()
    finder, other, _ = pairs_cell_search_ordered(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by,
                                                 cell_side(r, skin))
    return finder, other


@njit_parallel
def pairs_cell_search_ordered(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, h0):
    """:func:`pairs_cell_search`'s (finder, other) and the discs in its cell order (:func:`spatial_order` of
    the same arguments, from the grid the search built: one grid per neighbour-list build); ``h0`` =
    :func:`cell_side` (r, skin), which the caller keeps while the radii and the skin stay as they are."""
    n = x.shape[0]
    empty = np.empty(0, np.int64)
    if n == 0:
        return empty.copy(), empty.copy(), empty.copy()
    xmin, ymin, h, nx, ny, cell, start, order = _grid_of_side(x, y, h0)
    xs, ys, rs = _cell_sorted(x, y, r, order)
    # one scan per disc into a fixed-size scratch row (K partners); discs with more
    # (large discs among small ones) are scanned again straight into the result
    wall_box = _wall_boxes(wall_ax, wall_ay, wall_bx, wall_by, r.max() + skin)
    K = 8
    scratch = np.empty(n * K, np.int64)
    count = np.zeros(n + 1, np.int64)
    for i in prange(n):
        m = _disc_candidates(i, x, y, r, skin, xmin, ymin, h, nx, ny, start, order, xs, ys, rs,
                             scratch, i * K, K)
        m = _wall_candidates(i, x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, wall_box, n, scratch, i * K, K, m)
        count[i + 1] = m
    offs = np.cumsum(count)
    total = offs[n]
    finder = np.empty(total, np.int64)
    other = np.empty(total, np.int64)
    for i in prange(n):
        a = offs[i]
        b = offs[i + 1]
        if b - a <= K:
            for k in range(b - a):
                other[a + k] = scratch[i * K + k]
        else:
            m = _disc_candidates(i, x, y, r, skin, xmin, ymin, h, nx, ny, start, order, xs, ys, rs,
                                 other, a, b - a)
            _wall_candidates(i, x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, wall_box, n, other, a, b - a, m)
        _sort_small(other, a, b)
        for k in range(a, b):
            finder[k] = i
    return finder, other, order


@njit
def pairs_within(finder_o, other_o, x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by):
    """The pairs of a wider list (finder_o, other_o) (key order, e.g. :func:`pairs_cell_search_ordered` with a larger
    skin) whose gap is below ``skin`` now, in key order: the test of :func:`_disc_candidates` and
    :func:`_wall_candidates` on the same numbers (x_j - x_i, r_i + r_j + skin; the segment distance against
    r_i + skin), so where the wider list holds every pair the cell search would list, the result is the cell
    search's (finder, other) exactly (:func:`outer_list_holds` says when; tests/test_properties.py)."""
    n = x.shape[0]
    m = finder_o.shape[0]
    keep = np.empty(m, np.bool_)
    total = 0
    for k in range(m):
        i = finder_o[k]
        j = other_o[k]
        xi = x[i]
        yi = y[i]
        ri = r[i]
        if j < n:
            dx = x[j] - xi
            dy = y[j] - yi
            lim = ri + r[j] + skin
            ok = dx * dx + dy * dy < lim * lim
        else:
            w = j - n
            qx, qy, d = point_segment_distance(xi, yi, wall_ax[w], wall_ay[w], wall_bx[w], wall_by[w])
            ok = d < ri + skin
        keep[k] = ok
        total += 1 if ok else 0
    finder = np.empty(total, np.int64)
    other = np.empty(total, np.int64)
    t = 0
    for k in range(m):
        if keep[k]:
            finder[t] = finder_o[k]
            other[t] = other_o[k]
            t += 1
    return finder, other


@njit
def outer_list_holds(skin, skin_o, x, y, x0, y0, wall_ax, wall_ay, wall_bx, wall_by, wall_ax0, wall_ay0, wall_bx0,
                     wall_by0):
    """True when a list of every pair with gap below ``skin_o`` at the centres (x0, y0) and walls (A0, B0) holds
    every pair with gap below ``skin`` now.  A disc pair's centre distance changed by at most the two discs'
    displacements, so it is enough that skin + 2D <= skin_o, D the largest displacement since (x0, y0); a
    disc's distance to a segment by at most its displacement plus the larger of the segment's endpoint
    displacements W (the distance to a segment is 1-Lipschitz in each endpoint), so also skin + D + W <= skin_o.
    Both with a margin of 1e-9 of the lengths and coordinates involved, far above the rounding of the tests."""
    n = x.shape[0]
    d2 = 0.0
    scale = skin_o
    for i in range(n):
        dx = x[i] - x0[i]
        dy = y[i] - y0[i]
        d2 = max(d2, dx * dx + dy * dy)
        scale = max(scale, abs(x[i]), abs(y[i]), abs(x0[i]), abs(y0[i]))
    W = 0.0
    for w in range(wall_ax.shape[0]):
        da = np.sqrt((wall_ax[w] - wall_ax0[w]) ** 2 + (wall_ay[w] - wall_ay0[w]) ** 2)
        db = np.sqrt((wall_bx[w] - wall_bx0[w]) ** 2 + (wall_by[w] - wall_by0[w]) ** 2)
        W = max(W, da, db)
        scale = max(scale, abs(wall_ax[w]), abs(wall_ay[w]), abs(wall_bx[w]), abs(wall_by[w]))
    D = np.sqrt(d2)
    margin = 1e-9 * scale
    if not (np.isfinite(D) and np.isfinite(W) and np.isfinite(scale)):
        return False
    return skin + 2.0 * D + margin <= skin_o and skin + D + W + margin <= skin_o


@njit
def pairs_brute_force(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by):
    """The O(N²) reference for :func:`pairs_cell_search` (same keys, same order)."""
    finder, other, _, _ = pairs_brute_force_images(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by,
                                                   False, False, 1.0, 1.0)
    return finder, other


@njit
def pairs_brute_force_images(x, y, r, skin, wall_ax, wall_ay, wall_bx, wall_by, periodic_x, periodic_y, lx, ly):
    """Every pair by the O(N²) search, by the minimum-image distance along the periodic axes (period
    lx, ly [length]); returns (finder, other, sx, sy), (sx, sy) the image shift of the other disc.
    The reference for :func:`pairs_cell_search` and :func:`demflow.contacts.periodic.pairs_periodic`."""
    n = x.shape[0]
    nw = wall_ax.shape[0]
    cap = n * (n - 1) // 2 + n * nw
    finder = np.empty(cap, np.int64)
    other = np.empty(cap, np.int64)
    sxo = np.zeros(cap)
    syo = np.zeros(cap)
    m = 0
    for i in range(n):
        for j in range(n):
            if j == i or not _finds(i, j, r):
                continue
            dx = x[j] - x[i]
            dy = y[j] - y[i]
            sx = -lx * np.round(dx / lx) if periodic_x else 0.0
            sy = -ly * np.round(dy / ly) if periodic_y else 0.0
            dx += sx
            dy += sy
            lim = r[i] + r[j] + skin
            if dx * dx + dy * dy < lim * lim:
                finder[m] = i
                other[m] = j
                sxo[m] = sx
                syo[m] = sy
                m += 1
        for w in range(nw):
            qx, qy, d = point_segment_distance(x[i], y[i], wall_ax[w], wall_ay[w], wall_bx[w], wall_by[w])
            if d < r[i] + skin:
                finder[m] = i
                other[m] = n + w
                m += 1
    return finder[:m].copy(), other[:m].copy(), sxo[:m].copy(), syo[:m].copy()


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
def spatial_order(x, y, r, skin):
    """Disc indices in cell order (the cells of :func:`pairs_cell_search`, row by row):
    discs close in space come close in memory."""
    if x.shape[0] == 0:
        return np.empty(0, np.int64)
    return _grid(x, y, r, skin)[7]


@njit
def cell_order(x, y, h0):
    """The discs in the cell order of the grid of base side ``h0`` (:func:`cell_side`)."""
    return _grid_of_side(x, y, h0)[7]


@njit
def internal_layout(finder, other, n, perm, n_keys):
    """Contact lists renumbered for discs stored in the order ``perm`` (slot p holds disc
    perm[p]), pairs grouped by their finder's slot (keeping the key order within a finder).

    Returns (inv, pos, fin_p, oth_p, start_p, sidx_p, wall_p): inv[disc] = slot,
    pos[k] = internal position of listed pair k; fin_p/oth_p the pairs in internal order
    and numbering (walls keep n + w; unsigned 32-bit, ``n_keys`` = discs + walls below 2**32: the pair pass
    streams them every step, and half the bytes took 2 % off the 2D block pass at 1e5 discs and nothing at 1e4,
    benchmarks/results/speed_experiments_session48.md); (start_p, sidx_p) the per-slot contacts, each
    slot's entries in key order of the disc's pairs (the order its force sums are added in), naming
    internal pairs: 2k' where the slot's disc is internal pair k''s finder, 2k' + 1 where it is its other
    disc (unsigned 32-bit: half the bytes of a signed 64-bit index, and indexing with it needs no
    negative-index test); wall_p the internal positions of the wall pairs, in key order.  Written straight
    from the key-order list (session 49: no per-disc list in disc order first, and the wall pairs found on
    the way: 5.4 -> 2.9 ms at 1e5 discs, the same arrays).
    """
    m = finder.shape[0]
    inv = np.empty(n, np.int64)
    for p in range(n):
        inv[perm[p]] = p
    fcount = np.zeros(n + 1, np.int64)
    deg = np.zeros(n, np.int64)
    nwall = 0
    for k in range(m):
        i = finder[k]
        fcount[i + 1] += 1
        deg[i] += 1
        j = other[k]
        if j < n:
            deg[j] += 1
        else:
            nwall += 1
    fstart = np.cumsum(fcount)
    pos = np.empty(m, np.int64)
    if n_keys > 0xFFFFFFFF:
        raise ValueError("more than 2**32 - 1 discs and walls: the internal pair list is 32-bit")
    fin_p = np.empty(m, np.uint32)
    oth_p = np.empty(m, np.uint32)
    start_p = np.zeros(n + 1, np.int64)
    t = 0
    for p in range(n):
        i = perm[p]
        start_p[p + 1] = start_p[p] + deg[i]
        for k in range(fstart[i], fstart[i + 1]):
            pos[k] = t
            fin_p[t] = p
            j = other[k]
            oth_p[t] = inv[j] if j < n else j
            t += 1
    if 2 * m + 1 > 0xFFFFFFFF:
        raise ValueError("more than 2**31 - 1 listed pairs: the contact entries are 32-bit (2k or 2k + 1)")
    fill = np.empty(n, np.int64)
    for i in range(n):
        fill[i] = start_p[inv[i]]
    sidx_p = np.empty(start_p[n], np.uint32)
    wall_p = np.empty(nwall, np.int64)
    q = 0
    for k in range(m):
        i = finder[k]
        sidx_p[fill[i]] = 2 * pos[k]
        fill[i] += 1
        j = other[k]
        if j < n:
            sidx_p[fill[j]] = 2 * pos[k] + 1
            fill[j] += 1
        else:
            wall_p[q] = pos[k]
            q += 1
    return inv, pos, fin_p, oth_p, start_p, sidx_p, wall_p
