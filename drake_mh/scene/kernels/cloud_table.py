"""The shape-table entry of a point cloud (its layout: :mod:`.cloud`), built by numba where the
compiled core is not: :func:`cloud_table` takes the same steps on the same values as
``cpp/cloud_build.hpp`` (compiled without floating-point contraction), so both write the same
table.
"""

from __future__ import annotations

import numba
import numpy as np

from drake_mh.scene.kernels.cloud import CELLS_PER_ROW, COUNT_BITS, LEAF, MORTON_BITS, NODE_ROWS, SATURATED, STEPS

_RADIX = 11
"""Bits per pass of the codes' radix sort."""


@numba.njit(cache=True)
def _parabolas(f, n, d, v, z):
    """``d[q] = min_p ((q - p)^2 + f[p])`` over the ``p < n`` with a finite ``f[p]`` (``inf``
    if none): the lower envelope of parabolas (Felzenszwalb & Huttenlocher, Theory of Computing
    8, 2012, Algorithm 1), ``v``, ``z`` its scratch."""
    k = -1
    for q in range(n):
        if f[q] == np.inf:
            continue
        fq = f[q] + float(q) * float(q)
        while k >= 0:
            p = v[k]
            s = (fq - (f[p] + float(p) * float(p))) / (2.0 * float(q - p))
            if s <= z[k]:
                k -= 1
            else:
                break
        k += 1
        v[k] = q
        z[k] = -np.inf if k == 0 else (fq - (f[v[k - 1]] + float(v[k - 1]) * float(v[k - 1]))) / (2.0 * float(q - v[k - 1]))
    if k < 0:
        for q in range(n):
            d[q] = np.inf
        return
    j = 0
    for q in range(n):
        while j < k and z[j + 1] < q:
            j += 1
        d[q] = float(q - v[j]) * float(q - v[j]) + f[v[j]]


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
    :func:`_parabolas`, one per axis (the squared distance is separable; its values are sums of
    squared integers, exact in floating point)."""
    D = np.empty(zero.shape)
    for i in range(zero.shape[0]):
        for j in range(zero.shape[1]):
            for l in range(zero.shape[2]):
                D[i, j, l] = 0.0 if zero[i, j, l] else np.inf
    _envelope_pass(D, False)  # along z
    _envelope_pass(D.transpose((0, 2, 1)), False)  # along y
    _envelope_pass(D.transpose((1, 2, 0)), True)  # along x
    return D


@numba.njit(cache=True)
def _spread(v):
    """The bits of ``v`` (< 2^21, uint64) spread to every third bit."""
    v &= np.uint64(0x1FFFFF)
    v = (v | (v << np.uint64(32))) & np.uint64(0x1F00000000FFFF)
    v = (v | (v << np.uint64(16))) & np.uint64(0x1F0000FF0000FF)
    v = (v | (v << np.uint64(8))) & np.uint64(0x100F00F00F00F00F)
    v = (v | (v << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
    v = (v | (v << np.uint64(2))) & np.uint64(0x1249249249249249)
    return v


@numba.njit(cache=True)
def _morton_order(P, low, high):
    """``(codes (N,) uint64 sorted, order (N,))``: the points' Morton codes (module docstring of
    :mod:`.cloud`) and the stable order that sorts them (least significant digit first)."""
    N = P.shape[0]
    extent = max(high[0] - low[0], max(high[1] - low[1], high[2] - low[2]))
    scale = float(1 << MORTON_BITS) / extent if extent > 0.0 else 0.0
    top = np.uint64((1 << MORTON_BITS) - 1)
    code = np.empty(N, np.uint64)
    order = np.arange(N)
    for j in range(N):
        m = np.uint64(0)
        for a in range(3):
            q = min(np.uint64((P[j, a] - low[a]) * scale), top)
            m |= _spread(q) << np.uint64(2 - a)
        code[j] = m
    mask = np.uint64((1 << _RADIX) - 1)
    sorted_code, sorted_order = np.empty(N, np.uint64), np.empty(N, np.int64)
    count = np.empty((1 << _RADIX) + 1, np.int64)
    for shift in range(0, 3 * MORTON_BITS, _RADIX):
        count[:] = 0
        for j in range(N):
            count[int((code[j] >> np.uint64(shift)) & mask) + 1] += 1
        for b in range(1, count.shape[0]):
            count[b] += count[b - 1]
        for j in range(N):
            digit = int((code[j] >> np.uint64(shift)) & mask)
            sorted_code[count[digit]] = code[j]
            sorted_order[count[digit]] = order[j]
            count[digit] += 1
        code, sorted_code = sorted_code, code
        order, sorted_order = sorted_order, order
    return code, order


@numba.njit(cache=True)
def _leaf(lo, hi):
    return -(1 + (lo << COUNT_BITS) + (hi - lo))


@numba.njit(cache=True)
def _tree(code):
    """``children (M, 2)``: the tree's nodes in depth-first order (module docstring of
    :mod:`.cloud`), each child's code."""
    N = code.shape[0]
    children = np.zeros((N + 1, 2), np.int64)  # at most N nodes: each splits a range in two
    frames = np.empty((N + 1, 4), np.int64)  # (lo, hi, parent, side)
    frames[0, 0], frames[0, 1], frames[0, 2], frames[0, 3] = 0, N, -1, 0
    top, M = 1, 0
    while top > 0:
        top -= 1
        lo, hi, parent, side = frames[top, 0], frames[top, 1], frames[top, 2], frames[top, 3]
        node = M
        M += 1
        if parent >= 0:
            children[parent, side] = node
        if code[lo] == code[hi - 1]:
            split = (lo + hi) >> 1
        else:
            diff = code[lo] ^ code[hi - 1]
            bit = np.uint64(1)
            while diff > np.uint64(1):  # the highest set bit of diff
                diff >>= np.uint64(1)
                bit <<= np.uint64(1)
            a, b = lo, hi  # the first index whose code has the bit set
            while a < b:
                m = (a + b) >> 1
                if code[m] & bit:
                    b = m
                else:
                    a = m + 1
            split = a
        children[node, 0] = _leaf(lo, split) if split - lo <= LEAF else 0
        children[node, 1] = _leaf(split, hi) if hi - split <= LEAF else 0
        if hi - split > LEAF:
            frames[top, 0], frames[top, 1], frames[top, 2], frames[top, 3] = split, hi, node, 1
            top += 1
        if split - lo > LEAF:
            frames[top, 0], frames[top, 1], frames[top, 2], frames[top, 3] = lo, split, node, 0
            top += 1
    return children[:M]


@numba.njit(cache=True)
def cloud_table(P, radius, h_min, max_cells):
    """``(table (rows, 3), low (3,), high (3,))``: the shape-table entry of the points ``P (N,
    3)`` (finite, N >= 1, in W) with balls of ``radius`` [m] (module docstring of :mod:`.cloud`),
    a grid of cells of at least ``h_min`` [m] and about at most ``max_cells`` cells over the
    points' bounding box ``low``, ``high``."""
    N = P.shape[0]
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    for j in range(N):
        for a in range(3):
            low[a] = min(low[a], P[j, a])
            high[a] = max(high[a], P[j, a])
    volume = (high[0] - low[0] + h_min) * (high[1] - low[1] + h_min) * (high[2] - low[2] + h_min)
    h = max(h_min, (volume / max_cells) ** (1.0 / 3.0))
    shape = np.empty(3, np.int64)
    for a in range(3):
        shape[a] = int(np.floor((high[a] - low[a]) / h)) + 1
    nx, ny, nz = shape[0], shape[1], shape[2]
    near = np.zeros((nx, ny, nz), np.bool_)
    for j in range(N):
        i0 = min(int((P[j, 0] - low[0]) / h), nx - 1)
        i1 = min(int((P[j, 1] - low[1]) / h), ny - 1)
        i2 = min(int((P[j, 2] - low[2]) / h), nz - 1)
        near[i0, i1, i2] = True
    grown = near.copy()  # dilated by one cell, one axis at a time
    grown[1:] |= near[:-1]
    grown[:-1] |= near[1:]
    near = grown.copy()
    grown[:, 1:] |= near[:, :-1]
    grown[:, :-1] |= near[:, 1:]
    near = grown.copy()
    grown[:, :, 1:] |= near[:, :, :-1]
    grown[:, :, :-1] |= near[:, :, 1:]
    D = distance_transform(grown).reshape(-1)
    code, order = _morton_order(P, low, high)
    children = _tree(code)
    M, n_cells = children.shape[0], nx * ny * nz
    head = 3 + (n_cells + CELLS_PER_ROW - 1) // CELLS_PER_ROW
    table = np.zeros((head + N + NODE_ROWS * M, 3))
    table[0, 0], table[0, 1], table[0, 2] = radius, h, head
    for a in range(3):
        table[1, a], table[2, a] = low[a], shape[a]
    cells = table[3:head].reshape(-1).view(np.uint16)  # steps of h / STEPS, rounded down
    step = h / STEPS
    for c in range(n_cells):
        cells[c] = np.uint16(min(np.floor(max(h * D[c] - 1e-9, 0.0) / step), SATURATED))
    for j in range(N):
        for a in range(3):
            table[head + j, a] = P[order[j], a]
    nodes = head + N
    for i in range(M - 1, -1, -1):  # children after their parents: boxes bottom-up
        row = nodes + NODE_ROWS * i
        for side in range(2):
            c = children[i, side]
            box = row + 2 * side
            for a in range(3):
                table[box, a], table[box + 1, a] = np.inf, -np.inf
            if c >= 0:
                child = nodes + NODE_ROWS * c
                for a in range(3):
                    table[box, a] = min(table[child, a], table[child + 2, a])
                    table[box + 1, a] = max(table[child + 1, a], table[child + 3, a])
            else:
                v = -c - 1
                j0 = v >> COUNT_BITS
                for j in range(j0, j0 + (v & ((1 << COUNT_BITS) - 1))):
                    for a in range(3):
                        table[box, a] = min(table[box, a], table[head + j, a])
                        table[box + 1, a] = max(table[box + 1, a], table[head + j, a])
            table[row + 4, side] = c
    return table, low, high
