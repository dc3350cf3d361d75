"""Numba kernels of point-cloud obstacles: their shape-table entry and the sphere queries on it.

A cloud k is the union of balls of radius ``rho`` around its points; its signed distance at x is
``d(x) - rho``, ``d(x) = min_j |x - p_j|``. ``dims[k] = (s, N, radius)`` (``radius``: of a ball
about ``p_WO[k]`` that holds every point's ball); from row ``s`` the entry (:func:`cloud_table`):

* row ``s``: ``rho``, the grid's cell size ``h``, where the points start ``f - s``; row ``s+1``
  the grid's corner ``o`` in W (the points' lowest coordinates), row ``s+2`` its cell counts
  ``(nx, ny, nz)``; from row ``s+3`` one value per cell, a uint16 (the rows' bytes read as
  :data:`CELLS_PER_ROW` uint16 a row; cell ``(i, j, l)``, the box ``o + h [i, i+1] x [j, j+1] x
  [l, l+1]``, is number ``(i ny + j) nz + l``);
* rows ``f .. f+N-1``: the points in W, sorted by their Morton codes (each coordinate's offset
  from ``o`` quantised to :data:`MORTON_BITS` bits over the largest side of the bounding box,
  the bits interleaved, x first; equal codes in their input order);
* from row ``f + N``, :data:`NODE_ROWS` rows per node of a binary tree over the sorted points:
  the bounding box of each child's points (lower corner, upper corner; the first child's, then
  the second's), then the two children's codes. A node's points are a range of the sorted
  points, split where the highest bit in which the range's first and last codes differ turns 1
  (a spatial split at a power-of-two fraction of the box: Lauterbach et al., "Fast BVH
  Construction on GPUs", Eurographics 2009; at the middle where all codes are equal). A child of
  more than :data:`LEAF` points is a node (code >= 0, its number; node 0 is the root, nodes in
  depth-first order), else a leaf, code ``-(1 + start * 64 + count)``.

**The grid's bounds.** Let ``L`` be the least distance between a cell's box and the box of a
cell that holds a point, ``h |max(|Δ| - 1, 0)|`` over the cell offsets Δ (the exact Euclidean
distance transform, in cells, of the occupied cells dilated by one cell, times h, less 1e-9 for
round-off): no point of the cell is nearer than ``L`` to any point of the cloud. That occupied
cell's box is within ``L`` of the cell and both have the diagonal ``sqrt(3) h``, so some point
is within ``L + 2 sqrt(3) h`` of any point of the cell. The cell holds ``u``, the whole steps of
``h / STEPS`` in ``L`` (at most :data:`SATURATED`): ``u h / STEPS <= L < (u + 1) h / STEPS``
(unbounded above where saturated); a grid of 2 bytes a cell stays in a core's cache. Outside the grid, with y the projection
of x onto the grid's box (which holds every point, on the far side of y's tangent plane):
``d(x)^2 >= |x - y|^2 + L(y)^2`` and ``d(x) <= |x - y| + L(y) + 2 sqrt(3) h``
(:func:`cloud_bounds`).

**The exact answers.** :func:`cloud_free` answers "is every point at least ``reach`` from x"
from the bounds where they tell, else by a depth-first search of the tree (the nearer child
first; a child whose box is no nearer than the nearest point so far, or than ``reach``, is
skipped) that stops at the first point nearer than ``reach``; :func:`cloud_nearest2` gives the
exact nearest squared distance (or the bound asked, if nothing is nearer). Neither answer
depends on the grid or on the tree's shape: both only skip what cannot be nearer. The compiled
core (``cpp/cloud.hpp``, ``cpp/cloud_build.hpp``) builds the same table and answers the same.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from drake_mh.scene.kernels.pairs import FASTMATH

LEAF = 16
"""A range of at most this many points is a leaf of the tree (scanned, not split)."""

COUNT_BITS = 6
"""A leaf's code holds its count in this many bits (:data:`LEAF` < 64)."""

MORTON_BITS = 8
"""Bits per axis of the points' Morton codes."""

NODE_ROWS = 5
"""Rows of the table per node of the tree."""

STACK = 3 * MORTON_BITS + 66
"""Deeper than any path of the tree (each node splits a code bit, or halves a range of equal
codes): the searches' stack."""

UPPER = 2.0 * np.sqrt(3.0)
"""[cells] a cell's upper bound exceeds its lower bound by this (and one step)."""

STEPS = 256.0
"""A cell's value counts steps of ``h / STEPS``."""

SATURATED = 65535.0
"""A cell's value of this many steps: at least that far (no upper bound)."""

CELLS_PER_ROW = 12
"""Cells' values (uint16) in a row of the table (three float64)."""


@numba.njit(cache=True, fastmath=FASTMATH)
def cloud_bounds(k, dims, x, y, z):
    """``(lower, upper)`` [m]: bounds of the distance from (x, y, z) (in W) to the nearest point
    of cloud k, from its grid (module docstring)."""
    s = int(dims[k, 0])
    h = dims[s, 1]
    ox, oy, oz = dims[s + 1, 0], dims[s + 1, 1], dims[s + 1, 2]
    nx, ny, nz = int(dims[s + 2, 0]), int(dims[s + 2, 1]), int(dims[s + 2, 2])
    cells = dims.view(np.uint16)  # (D, CELLS_PER_ROW)
    step = h / STEPS
    fx, fy, fz = (x - ox) / h, (y - oy) / h, (z - oz) / h
    if fx >= 0.0 and fy >= 0.0 and fz >= 0.0 and fx < nx and fy < ny and fz < nz:
        c = (int(fx) * ny + int(fy)) * nz + int(fz)
        u = float(cells[s + 3 + c // CELLS_PER_ROW, c % CELLS_PER_ROW])
        upper = ((u + 1.0) * step + UPPER * h) * (1.0 + 1e-9) + 1e-9 if u < SATURATED else np.inf
        return u * step, upper
    ix = 0 if fx < 0.0 else nx - 1 if fx >= nx else int(fx)
    iy = 0 if fy < 0.0 else ny - 1 if fy >= ny else int(fy)
    iz = 0 if fz < 0.0 else nz - 1 if fz >= nz else int(fz)
    c = (ix * ny + iy) * nz + iz
    u = float(cells[s + 3 + c // CELLS_PER_ROW, c % CELLS_PER_ROW])
    cell = u * step
    gx = max(max(ox - x, 0.0), x - ox - nx * h)
    gy = max(max(oy - y, 0.0), y - oy - ny * h)
    gz = max(max(oz - z, 0.0), z - oz - nz * h)
    out2 = gx * gx + gy * gy + gz * gz
    # round-off: the lower bound never above the distance, the upper never below
    upper = (math.sqrt(out2) + (u + 1.0) * step + UPPER * h) * (1.0 + 1e-9) + 1e-9 if u < SATURATED else np.inf
    return math.sqrt(out2 + cell * cell) * (1.0 - 1e-12), upper


@numba.njit(cache=True, fastmath=FASTMATH)
def cloud_floor(k, dims, x, y, z):
    """A lower bound [m] of the distance from (x, y, z) (in W) to every point of cloud k."""
    return cloud_bounds(k, dims, x, y, z)[0]


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _box2(dims, row, x, y, z):
    """Squared distance from (x, y, z) to the box whose lower corner is row ``row`` of ``dims``
    and upper corner the next row."""
    gx = max(max(dims[row, 0] - x, 0.0), x - dims[row + 1, 0])
    gy = max(max(dims[row, 1] - y, 0.0), y - dims[row + 1, 1])
    gz = max(max(dims[row, 2] - z, 0.0), z - dims[row + 1, 2])
    return gx * gx + gy * gy + gz * gz


@numba.njit(cache=True, fastmath=FASTMATH)
def tree_nearest2(dims, first, nodes, x, y, z, best, stop):
    """The smaller of ``best`` and the smallest squared distance from (x, y, z) to the points of
    the tree whose points start at row ``first`` and nodes at row ``nodes``, returning as soon as
    it is below ``stop``: depth first, the nearer child first, a child whose box is no nearer than
    the best so far skipped (also when it comes off the stack)."""
    codes = np.empty(STACK, np.int64)
    boxes = np.empty(STACK)
    sp, c = 0, 0
    while True:
        descend = False
        if c >= 0:
            row = nodes + NODE_ROWS * c
            a, b = _box2(dims, row, x, y, z), _box2(dims, row + 2, x, y, z)
            ca, cb = int(dims[row + 4, 0]), int(dims[row + 4, 1])
            near_first = a <= b  # the nearer child now, the other on the stack
            near, far = (a, b) if near_first else (b, a)
            if near < best:
                codes[sp] = cb if near_first else ca
                boxes[sp] = far
                if far < best:
                    sp += 1
                c = ca if near_first else cb
                descend = True
        else:
            v = -c - 1
            j0 = v >> COUNT_BITS
            for j in range(j0, j0 + (v & ((1 << COUNT_BITS) - 1))):
                dx, dy, dz = x - dims[first + j, 0], y - dims[first + j, 1], z - dims[first + j, 2]
                best = min(best, dx * dx + dy * dy + dz * dz)
            if best < stop:
                return best
        if descend:
            continue
        while True:  # the deepest pending child still nearer than the best
            if sp == 0:
                return best
            sp -= 1
            if boxes[sp] < best:
                c = codes[sp]
                break


@numba.njit(cache=True)
def _rows(k, dims):
    """``(first point row, first node row)`` of cloud k."""
    s, N = int(dims[k, 0]), int(dims[k, 1])
    first = s + int(dims[s, 2])
    return first, first + N


@numba.njit(cache=True, fastmath=FASTMATH)
def cloud_nearest2(k, dims, x, y, z, bound2):
    """The smallest squared distance [m^2] from (x, y, z) (in W) to a point of cloud k, or
    ``bound2`` if none is nearer (pass the square of the largest distance that matters, ``inf``
    for the exact value). The grid's bounds first: a lower bound beyond ``bound2`` answers at
    once, and the upper bound starts the search."""
    lower, upper = cloud_bounds(k, dims, x, y, z)
    if lower * lower >= bound2:
        return bound2
    first, nodes = _rows(k, dims)
    start = upper * upper if upper * upper < bound2 else bound2
    return tree_nearest2(dims, first, nodes, x, y, z, start, -1.0)


@numba.njit(cache=True, fastmath=FASTMATH)
def cloud_free(k, dims, x, y, z, reach):
    """Whether every point of cloud k is at least ``reach`` [m] (> 0) from (x, y, z) (in W):
    the grid's bounds first (free above the lower, not free below the upper), the tree (stopping
    at the first point nearer) where they cannot tell."""
    lower, upper = cloud_bounds(k, dims, x, y, z)
    if lower >= reach:
        return True
    if upper < reach:
        return False
    first, nodes = _rows(k, dims)
    lim = reach * reach
    return tree_nearest2(dims, first, nodes, x, y, z, lim, lim) >= lim


@numba.njit(cache=True)
def cloud_radius(k, dims):
    """The radius [m] of cloud k's balls."""
    return dims[int(dims[k, 0]), 0]
