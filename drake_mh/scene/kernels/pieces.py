"""Numba kernels of the obstacle kinds whose data live in the shape table: convex pieces (of a
mesh) and point clouds.

The collision kernels (:mod:`.collision`) read each obstacle k from ``kinds[k]``, ``R_WO[k]``,
``p_WO[k]`` and the row ``dims[k]`` of the *shape table* ``dims (D, 3)``. For a primitive the
row holds its sizes; for these two kinds it says where the obstacle's data start in the rows
after the obstacles' own (built by :func:`drake_mh.scene.batch.obstacle_arrays`):

* **convex piece** (``CONVEX``), ``dims[k] = (s, M, radius)`` (``radius``: of a ball about
  ``p_WO[k]`` that holds the piece): rows ``s .. s+M-1`` are unit normals
  ``n_i`` in W, and the offsets ``h_i`` follow, three to a row (``h_i = dims[s + M + i // 3, i % 3]``),
  of supporting planes of the piece relative to ``p_WO[k]``: every point x of the piece has
  ``n_i · (x - p_WO) <= h_i``. So for any point x,

      ``v(x) = max_i (n_i · (x - p_WO) - h_i) <= sd(x)``,

  the piece's signed distance: outside, each plane bounds the distance from below (the piece
  lies in its half space); inside, the ball of radius ``-sd(x)`` about x lies in the piece, so
  in every half space, and ``v(x) <= sd(x)`` again, with equality when the planes include the
  piece's facets. The planes are the facets and, to tighten ``v`` near edges and corners, the
  normalised sums of the facet normals that meet at each edge and at each vertex (each with its
  support value ``h = max_vertices n · v``): :mod:`drake_mh.geometry.convex_pieces`.
* **point cloud** (``CLOUD``), ``dims[k] = (s, N, radius)``: row ``s`` holds the points'
  radius ``rho``, the grid's cell size ``h`` and where the points start, ``f - s``; row ``s+1``
  the grid's corner in W, row ``s+2`` its cell counts; from row ``s+3`` one value per cell,
  three to a row (cell ``(i, j, l)`` is number ``(i ny + j) nz + l``); rows ``f .. f+N-1`` the
  points in W as an implicit k-d tree (the median of a range ``[lo, hi)`` at
  ``mid = (lo + hi) // 2``, its split axis at ``dims[f + N + mid // 3, mid % 3]``, the lower
  half before it, the upper half after it; with ``b = f + N + (N + 2) // 3``, rows ``b + 2 mid``
  and ``b + 2 mid + 1`` the lower and upper corners of the bounding box of the range's points,
  for the ranges of more than ``_LEAF`` points: :func:`kd_build`). The obstacle is the union of
  balls of radius ``rho`` around the points, its signed distance ``min_j |x - p_j| - rho``:
  :func:`cloud_nearest2` computes it exactly (a k-d tree search: Friedman, Bentley, Finkel,
  ACM TOMS 3(3), 1977; a range whose box is no nearer than the best so far is skipped whole,
  which keeps queries far from a cloud of surface samples cheap). The grid answers most "free" questions in O(1)
  (:func:`cloud_free`): a cell's value is ``h`` times the Euclidean distance transform, in
  cells, of the occupied cells dilated by one cell, that is the least box-to-box distance
  ``h |max(|Δ| - 1, 0)|`` from the cell to an occupied cell, so no point of the cell is nearer
  to any cloud point (:func:`drake_mh.scene.batch.obstacle_arrays` builds it); outside the grid
  the distance to its box bounds it.
"""

from __future__ import annotations

import numba
import numpy as np

from drake_mh.scene.kernels.pairs import FASTMATH

CONVEX, CLOUD = 4, 5
"""The kinds after the primitives' 0-3 (:mod:`.collision`)."""

_LEAF = 8
"""Ranges of at most this many points are scanned, not split further."""

_UPPER = 2.0 * np.sqrt(3.0)
"""[cells] a grid cell's upper bound exceeds its lower bound by this (:func:`_cloud_bounds`)."""


@numba.njit(cache=True, fastmath=FASTMATH)
def convex_value(k, dims, x, y, z):
    """``max_i (n_i · (x, y, z) - h_i)`` of convex piece k, the point relative to ``p_WO[k]``:
    a lower bound of its signed distance, exact inside (module docstring)."""
    s, M = int(dims[k, 0]), int(dims[k, 1])
    best = -np.inf
    for i in range(M):
        v = dims[s + i, 0] * x + dims[s + i, 1] * y + dims[s + i, 2] * z - dims[s + M + i // 3, i % 3]
        best = max(best, v)
    return best


@numba.njit(cache=True, fastmath=FASTMATH)
def convex_free(k, dims, x, y, z, reach):
    """Whether some plane of convex piece k keeps the point (relative to ``p_WO[k]``) at least
    ``reach`` away: a certificate that the piece is at least that far; stops at the first."""
    s, M = int(dims[k, 0]), int(dims[k, 1])
    for i in range(M):
        if dims[s + i, 0] * x + dims[s + i, 1] * y + dims[s + i, 2] * z - dims[s + M + i // 3, i % 3] >= reach:
            return True
    return False


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _box2(dims, b0, mid, x, y, z):
    """Squared distance from (x, y, z) to the bounding box of the range whose median is at
    ``mid`` (rows ``b0 + 2 mid``: its lower corner, ``b0 + 2 mid + 1``: its upper corner)."""
    lo, hi = b0 + 2 * mid, b0 + 2 * mid + 1
    gx = max(dims[lo, 0] - x, 0.0, x - dims[hi, 0])
    gy = max(dims[lo, 1] - y, 0.0, y - dims[hi, 1])
    gz = max(dims[lo, 2] - z, 0.0, z - dims[hi, 2])
    return gx * gx + gy * gy + gz * gz


@numba.njit(cache=True, fastmath=FASTMATH)
def _nearest2(dims, s, a0, b0, N, x, y, z, best, stop):
    """The smaller of ``best`` and the smallest squared distance from (x, y, z) to the points of
    the tree at rows ``s .. s+N-1`` (axes from row ``a0``, the ranges' bounding boxes from row
    ``b0``), returning as soon as it is below ``stop``. Depth first, the side with the nearer box
    first (the point's side of the split plane where a half is a leaf); a range whose bounding
    box is no nearer than the best so far is skipped whole, and the side beyond the split plane
    only while the plane is nearer than the best. No stack and no recursion
    (numba's cache does not reload recursive functions): bit ``d`` of ``path`` is the side taken
    at depth ``d``, of ``pending`` whether its far side is still to be tried, and a range is found
    again from the root by its path."""
    lo, hi, depth, path, pending = 0, N, 0, 0, 0
    while True:
        leaf = True
        while hi - lo > _LEAF:  # down to a leaf, the near side first
            mid = (lo + hi) >> 1
            if _box2(dims, b0, mid, x, y, z) >= best:  # nothing in this range is nearer
                leaf = False
                break
            dx, dy, dz = x - dims[s + mid, 0], y - dims[s + mid, 1], z - dims[s + mid, 2]
            best = min(best, dx * dx + dy * dy + dz * dz)
            if best < stop:
                return best
            axis = int(dims[a0 + mid // 3, mid % 3])
            diff = dx if axis == 0 else dy if axis == 1 else dz
            upper = diff >= 0.0  # the side of the split plane the point is on
            if mid - lo > _LEAF and hi - mid - 1 > _LEAF:  # two boxes: the nearer first
                upper = _box2(dims, b0, (mid + 1 + hi) >> 1, x, y, z) < _box2(dims, b0, (lo + mid) >> 1, x, y, z)
            if upper:
                lo = mid + 1
                path |= 1 << depth
            else:
                hi = mid
            pending |= 1 << depth
            depth += 1
        if leaf:
            for j in range(lo, hi):
                dx, dy, dz = x - dims[s + j, 0], y - dims[s + j, 1], z - dims[s + j, 2]
                best = min(best, dx * dx + dy * dy + dz * dz)
            if best < stop:
                return best
        while True:  # back to the deepest split whose far side can still hold a nearer point
            if pending == 0:
                return best
            d = depth - 1
            while not (pending >> d) & 1:
                d -= 1
            pending &= ~(1 << d)
            lo, hi = 0, N
            for e in range(d):
                mid = (lo + hi) >> 1
                if (path >> e) & 1:
                    lo = mid + 1
                else:
                    hi = mid
            mid = (lo + hi) >> 1
            axis = int(dims[a0 + mid // 3, mid % 3])
            diff = (x if axis == 0 else y if axis == 1 else z) - dims[s + mid, axis]
            far = 1 - ((path >> d) & 1)  # the side not taken: beyond the plane or the point's own
            if diff * diff < best or far == (1 if diff >= 0.0 else 0):
                if far:
                    lo = mid + 1
                else:
                    hi = mid
                path = (path & ((1 << d) - 1)) | (far << d)
                depth = d + 1
                break


@numba.njit(cache=True, fastmath=FASTMATH)
def _points(k, dims):
    """``(first point row, N, first axis row, first box row)`` of cloud k."""
    s, N = int(dims[k, 0]), int(dims[k, 1])
    first = s + int(dims[s, 2])
    return first, N, first + N, first + N + (N + 2) // 3


@numba.njit(cache=True, fastmath=FASTMATH)
def cloud_nearest2(k, dims, x, y, z, bound2):
    """The smallest squared distance [m^2] from (x, y, z) (in W) to a point of cloud k, or
    ``bound2`` if none is nearer (the search skips what cannot be: pass the square of the
    largest distance that matters, ``inf`` for the exact value). The grid's bounds
    (:func:`_cloud_bounds`) come first: a lower bound beyond ``bound2`` answers at once, and the
    upper bound starts the search (no point beyond it is visited)."""
    first, N, axes, boxes = _points(k, dims)
    lower, upper = _cloud_bounds(k, dims, x, y, z)
    if lower * lower >= bound2:  # no point nearer than the bound
        return bound2
    if upper * upper < bound2:  # the nearest point is within upper: the value is the same
        return _nearest2(dims, first, axes, boxes, N, x, y, z, upper * upper, -1.0)
    return _nearest2(dims, first, axes, boxes, N, x, y, z, bound2, -1.0)


@numba.njit(cache=True, fastmath=FASTMATH)
def _cloud_bounds(k, dims, x, y, z):
    """``(lower, upper)`` [m]: bounds of the distance from (x, y, z) (in W) to the nearest point
    of cloud k from its grid (module docstring). Inside the grid, ``lower`` is the cell's value
    ``D`` (at most the centre distance to the nearest cell of the dilated occupied set) and
    ``upper = D + 2 sqrt(3) h``: that dilated cell lies within one cell of an occupied one, so
    some point is within half the query cell's diagonal + ``D`` + one cell diagonal + half the
    occupied cell's diagonal. Outside the grid, the distance to its box and ``inf``."""
    s = int(dims[k, 0])
    h = dims[s, 1]
    ox, oy, oz = dims[s + 1, 0], dims[s + 1, 1], dims[s + 1, 2]
    nx, ny, nz = int(dims[s + 2, 0]), int(dims[s + 2, 1]), int(dims[s + 2, 2])
    fx, fy, fz = (x - ox) / h, (y - oy) / h, (z - oz) / h
    if fx < 0.0 or fy < 0.0 or fz < 0.0 or fx >= nx or fy >= ny or fz >= nz:
        gx = max(ox - x, 0.0, x - ox - nx * h)
        gy = max(oy - y, 0.0, y - oy - ny * h)
        gz = max(oz - z, 0.0, z - oz - nz * h)
        return np.sqrt(gx * gx + gy * gy + gz * gz), np.inf
    c = (int(fx) * ny + int(fy)) * nz + int(fz)
    lower = dims[s + 3 + c // 3, c % 3]
    return lower, (lower + _UPPER * h) * (1.0 + 1e-9) + 1e-9


@numba.njit(cache=True, fastmath=FASTMATH)
def cloud_floor(k, dims, x, y, z):
    """A lower bound [m] of the distance from (x, y, z) (in W) to every point of cloud k: its
    grid cell's value, or the distance to the grid's box outside it (module docstring)."""
    return _cloud_bounds(k, dims, x, y, z)[0]


@numba.njit(cache=True, fastmath=FASTMATH)
def cloud_free(k, dims, x, y, z, reach):
    """Whether every point of cloud k is at least ``reach`` [m] (> 0) from (x, y, z) (in W):
    the grid's bounds first (free above the lower, not free below the upper), the k-d tree
    (stopping at the first point nearer) where they cannot tell."""
    lower, upper = _cloud_bounds(k, dims, x, y, z)
    if lower >= reach:
        return True
    if upper < reach:
        return False
    first, N, axes, boxes = _points(k, dims)
    lim = reach * reach
    return _nearest2(dims, first, axes, boxes, N, x, y, z, lim, lim) >= lim


@numba.njit(cache=True)
def cloud_radius(k, dims):
    """The radius [m] of cloud k's balls."""
    return dims[int(dims[k, 0]), 0]


@numba.njit(cache=True)
def _select(W, idx, lo, hi, nth, axis):
    """Reorder the rows ``W[lo:hi]`` (and ``idx[lo:hi]`` with them) so that row ``nth`` holds the
    point with the ``nth``-smallest coordinate ``axis``, the smaller before it and the larger
    after it (Hoare's selection, on the rows themselves: contiguous reads)."""
    while hi - lo > 1:
        a, b, c = W[lo, axis], W[(lo + hi) >> 1, axis], W[hi - 1, axis]
        pivot = max(min(a, b), min(max(a, b), c))  # median of three
        i, j = lo, hi - 1
        while i <= j:
            while W[i, axis] < pivot:
                i += 1
            while W[j, axis] > pivot:
                j -= 1
            if i <= j:
                for u in range(3):
                    W[i, u], W[j, u] = W[j, u], W[i, u]
                idx[i], idx[j] = idx[j], idx[i]
                i += 1
                j -= 1
        if nth <= j:
            hi = j + 1
        elif nth >= i:
            lo = i
        else:
            return


@numba.njit(cache=True)
def kd_build(P):
    """``(order (N,), axes (N,), tree (N, 3), boxes (N, 6))``: the implicit k-d tree of points
    ``P (N, 3)`` (module docstring): ``tree = P[order]``, the points in tree order, ``axes[mid]``
    the split axis of the range whose median is at ``mid``: the widest side of a box that holds
    the range (the root's bounding box, cut at each median above; any axis gives a valid tree,
    the widest a balanced search); ``boxes[mid]`` the bounding box of that range's points (lower
    corner, upper corner), for the ranges of more than ``_LEAF`` points (other rows: 0)."""
    N = P.shape[0]
    W = P.copy()
    idx = np.arange(N)
    axes = np.zeros(N, np.int64)
    stack = np.empty((64, 2), np.int64)
    boxes = np.empty((64, 6))
    split = np.empty((max(N, 1), 3), np.int64)  # the split ranges (lo, median, hi), parents first
    n_split = 0
    for a in range(3):
        boxes[0, a], boxes[0, 3 + a] = np.inf, -np.inf
    for j in range(N):
        for a in range(3):
            boxes[0, a] = min(boxes[0, a], W[j, a])
            boxes[0, 3 + a] = max(boxes[0, 3 + a], W[j, a])
    stack[0, 0], stack[0, 1] = 0, N
    top = 1
    while top > 0:
        top -= 1
        lo, hi = stack[top, 0], stack[top, 1]
        if hi - lo <= _LEAF:
            continue
        axis, widest = 0, -1.0
        for a in range(3):
            if boxes[top, 3 + a] - boxes[top, a] > widest:
                axis, widest = a, boxes[top, 3 + a] - boxes[top, a]
        mid = (lo + hi) >> 1
        _select(W, idx, lo, hi, mid, axis)
        axes[mid] = axis
        split[n_split, 0], split[n_split, 1], split[n_split, 2] = lo, mid, hi
        n_split += 1
        cut = W[mid, axis]
        for u in range(6):
            boxes[top + 1, u] = boxes[top, u]
        boxes[top, 3 + axis] = cut  # the lower half, kept in place
        boxes[top + 1, axis] = cut  # the upper half
        stack[top, 0], stack[top, 1] = lo, mid
        stack[top + 1, 0], stack[top + 1, 1] = mid + 1, hi
        top += 2
    tight = np.zeros((N, 6))
    for r in range(n_split - 1, -1, -1):  # children before parents: a range's box from its halves
        lo, mid, hi = split[r, 0], split[r, 1], split[r, 2]
        for a in range(3):
            tight[mid, a] = tight[mid, 3 + a] = W[mid, a]
        for c0, c1 in ((lo, mid), (mid + 1, hi)):
            if c1 - c0 > _LEAF:
                c = (c0 + c1) >> 1
                for a in range(3):
                    tight[mid, a] = min(tight[mid, a], tight[c, a])
                    tight[mid, 3 + a] = max(tight[mid, 3 + a], tight[c, 3 + a])
            else:
                for j in range(c0, c1):
                    for a in range(3):
                        tight[mid, a] = min(tight[mid, a], W[j, a])
                        tight[mid, 3 + a] = max(tight[mid, 3 + a], W[j, a])
    return idx, axes, W, tight


@numba.njit(cache=True)
def _parabolas(f, n, d, v, z):
    """``d[q] = min_p ((q - p)^2 + f[p])`` over the ``p < n`` with a finite ``f[p]`` (``inf``
    if none): the lower envelope of parabolas (Felzenszwalb & Huttenlocher, Theory of Computing
    8, 2012, Algorithm 1), ``v``, ``z`` its scratch."""
    k = -1
    for q in range(n):
        if f[q] == np.inf:
            continue
        while k >= 0:
            p = v[k]
            s = ((f[q] + q * q) - (f[p] + p * p)) / (2.0 * (q - p))
            if s <= z[k]:
                k -= 1
            else:
                break
        k += 1
        v[k] = q
        z[k] = -np.inf if k == 0 else ((f[q] + q * q) - (f[v[k - 1]] + v[k - 1] * v[k - 1])) / (2.0 * (q - v[k - 1]))
    if k < 0:
        for q in range(n):
            d[q] = np.inf
        return
    j = 0
    for q in range(n):
        while j < k and z[j + 1] < q:
            j += 1
        d[q] = (q - v[j]) * (q - v[j]) + f[v[j]]


@numba.njit(cache=True)
def _envelope_pass(D, root):
    """Replace each row of ``D (a, b, n)`` along its last axis (a view) by :func:`_parabolas` of
    it, square-rooted with ``root``."""
    a, b, n = D.shape
    f, d, z = np.empty(n), np.empty(n), np.empty(n + 1)
    v = np.empty(n, np.int64)
    for i in range(a):
        for j in range(b):
            for l in range(n):
                f[l] = D[i, j, l]
            _parabolas(f, n, d, v, z)
            for l in range(n):
                D[i, j, l] = np.sqrt(d[l]) if root else d[l]


@numba.njit(cache=True)
def distance_transform(zero):
    """``(nx, ny, nz)`` float64: the Euclidean distance [cells] from each cell to the nearest
    cell where ``zero (nx, ny, nz)`` (bool) is True (``inf`` if none), exact: three passes of
    :func:`_parabolas`, one per axis (the squared distance is separable)."""
    D = np.empty(zero.shape)
    for i in range(zero.shape[0]):
        for j in range(zero.shape[1]):
            for l in range(zero.shape[2]):
                D[i, j, l] = 0.0 if zero[i, j, l] else np.inf
    _envelope_pass(D, False)  # along z
    _envelope_pass(D.transpose((0, 2, 1)), False)  # along y
    _envelope_pass(D.transpose((1, 2, 0)), True)  # along x
    return D
