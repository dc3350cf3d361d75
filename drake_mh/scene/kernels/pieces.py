"""Numba kernels of convex pieces (of a mesh), one of the obstacle kinds whose data live in the
shape table (the other, point clouds: :mod:`.cloud`).

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
* **point cloud** (``CLOUD``), ``dims[k] = (s, N, radius)``: its grid of distance bounds, its
  points and their tree from row ``s`` (:mod:`.cloud`, which holds its kernels).
"""

from __future__ import annotations

import numba
import numpy as np

from drake_mh.scene.kernels.pairs import FASTMATH

CONVEX, CLOUD = 4, 5
"""The kinds after the primitives' 0-3 (:mod:`.collision`)."""


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
