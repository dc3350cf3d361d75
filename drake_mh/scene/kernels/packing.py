"""The arrays of the collision kernels (:mod:`drake_mh.scene.kernels.collision`) in two
buffers, one of int64 and one of float64 (:func:`pack`), and their views again inside compiled
code (:func:`unpack`, :func:`_unpack_views`): a call from Python then passes 6 arguments
instead of 32 (numba's dispatch costs per argument), and planners hand one tuple around.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.lib.stride_tricks import as_strided

from drake_mh.scene.pair_table import GRID_COLUMNS


@numba.njit(cache=True, inline="always")
def _rows(buf, i, n, width):
    """``buf[i:i + n * width]`` as an ``(n, width)`` view (``as_strided``: numba's reshape calls a
    C helper, about 12 ns each, which was most of a one-configuration call's unpacking)."""
    return as_strided(buf[i:i + n * width], shape=(n, width), strides=(8 * width, 8))


@numba.njit(cache=True, inline="always")
def _mats(buf, i, n):
    """``buf[i:i + 9 n]`` as an ``(n, 3, 3)`` view (see :func:`_rows`)."""
    return as_strided(buf[i:i + 9 * n], shape=(n, 3, 3), strides=(72, 24, 8))


@numba.njit(cache=True, inline="always")
def _offsets(ints):
    """Where each array of :func:`pack` starts in its buffer."""
    F, G, S, K, P, T, U, D = ints[0], ints[1], ints[2], ints[3], ints[4], ints[5], ints[6], ints[7]
    i_parent = 8
    i_perm = i_parent + F
    i_kind = i_perm + 3 * F
    i_qidx = i_kind + F
    i_anchor = i_qidx + F
    i_start = i_anchor + G
    i_kinds = i_start + G + 1
    i_a = i_kinds + K
    i_b = i_a + P
    i_meta = i_b + P
    i_ustart = i_meta + 6 * P
    i_ustart_s = i_ustart + G + 1
    f_KR = 0
    f_Kp = f_KR + 9 * F
    f_offset = f_Kp + 3 * F
    f_radius = f_offset + 3 * G
    f_soffset = f_radius + G
    f_sradius = f_soffset + 3 * S
    f_RWO = f_sradius + S
    f_pWO = f_RWO + 9 * K
    f_dims = f_pWO + 3 * K
    f_orad = f_dims + 3 * D
    f_ogap = f_orad + K
    f_grid = f_ogap + G * K
    f_vals = f_grid + GRID_COLUMNS * P
    f_caps = f_vals + T
    f_uoffset = f_caps + 7 * G
    f_uradius = f_uoffset + 3 * U
    return (F, G, S, K, P, T, U, D, i_parent, i_perm, i_kind, i_qidx, i_anchor, i_start, i_kinds, i_a, i_b, i_meta,
            i_ustart, i_ustart_s, f_KR, f_Kp, f_offset, f_radius, f_soffset, f_sradius, f_RWO, f_pWO, f_dims, f_orad,
            f_ogap, f_grid, f_vals, f_caps, f_uoffset, f_uradius)


@numba.njit(cache=True, inline="always")
def unpack(ints, floats):
    """Views of the arrays :func:`pack` laid out in two buffers (no copies), C-ordered: the
    array types a call from Python passes too, so the kernels they reach compile once."""
    (F, G, S, K, P, T, U, D, i_parent, i_perm, i_kind, i_qidx, i_anchor, i_start, i_kinds, i_a, i_b, i_meta, i_ustart,
     i_ustart_s, f_KR, f_Kp, f_offset, f_radius, f_soffset, f_sradius, f_RWO, f_pWO, f_dims, f_orad, f_ogap, f_grid,
     f_vals, f_caps, f_uoffset, f_uradius) = _offsets(ints)
    return (ints[i_parent:i_parent + F], floats[f_KR:f_KR + 9 * F].reshape((F, 3, 3)),
            floats[f_Kp:f_Kp + 3 * F].reshape((F, 3)), ints[i_perm:i_perm + 3 * F].reshape((F, 3)),
            ints[i_kind:i_kind + F], ints[i_qidx:i_qidx + F], ints[i_anchor:i_anchor + G],
            floats[f_offset:f_offset + 3 * G].reshape((G, 3)), floats[f_radius:f_radius + G],
            ints[i_start:i_start + G + 1], floats[f_soffset:f_soffset + 3 * S].reshape((S, 3)),
            floats[f_sradius:f_sradius + S], ints[i_kinds:i_kinds + K], floats[f_RWO:f_RWO + 9 * K].reshape((K, 3, 3)),
            floats[f_pWO:f_pWO + 3 * K].reshape((K, 3)), floats[f_dims:f_dims + 3 * D].reshape((D, 3)),
            floats[f_orad:f_orad + K], floats[f_ogap:f_ogap + G * K].reshape((G, K)), ints[i_a:i_a + P],
            ints[i_b:i_b + P], ints[i_meta:i_meta + 6 * P].reshape((P, 6)),
            floats[f_grid:f_grid + GRID_COLUMNS * P].reshape((P, GRID_COLUMNS)),
            floats[f_vals:f_vals + T], floats[f_caps:f_caps + 7 * G].reshape((G, 7)), ints[i_ustart:i_ustart + G + 1],
            ints[i_ustart_s:i_ustart_s + U + 1], floats[f_uoffset:f_uoffset + 3 * U].reshape((U, 3)),
            floats[f_uradius:f_uradius + U])


@numba.njit(cache=True, inline="always")
def _unpack_views(ints, floats):
    """:func:`unpack` with ``as_strided`` views instead of reshapes (about 1 ns instead of
    200 for all of them; any-layout array types): for
    :func:`drake_mh.scene.kernels.entry.collision_free_one`."""
    (F, G, S, K, P, T, U, D, i_parent, i_perm, i_kind, i_qidx, i_anchor, i_start, i_kinds, i_a, i_b, i_meta, i_ustart,
     i_ustart_s, f_KR, f_Kp, f_offset, f_radius, f_soffset, f_sradius, f_RWO, f_pWO, f_dims, f_orad, f_ogap, f_grid,
     f_vals, f_caps, f_uoffset, f_uradius) = _offsets(ints)
    return (ints[i_parent:i_parent + F], _mats(floats, f_KR, F), _rows(floats, f_Kp, F, 3), _rows(ints, i_perm, F, 3),
            ints[i_kind:i_kind + F], ints[i_qidx:i_qidx + F], ints[i_anchor:i_anchor + G],
            _rows(floats, f_offset, G, 3), floats[f_radius:f_radius + G], ints[i_start:i_start + G + 1],
            _rows(floats, f_soffset, S, 3), floats[f_sradius:f_sradius + S], ints[i_kinds:i_kinds + K],
            _mats(floats, f_RWO, K), _rows(floats, f_pWO, K, 3), _rows(floats, f_dims, D, 3),
            floats[f_orad:f_orad + K], _rows(floats, f_ogap, G, K), ints[i_a:i_a + P], ints[i_b:i_b + P],
            _rows(ints, i_meta, P, 6),
            _rows(floats, f_grid, P, GRID_COLUMNS), floats[f_vals:f_vals + T], _rows(floats, f_caps, G, 7),
            ints[i_ustart:i_ustart + G + 1], ints[i_ustart_s:i_ustart_s + U + 1], _rows(floats, f_uoffset, U, 3),
            floats[f_uradius:f_uradius + U])


def pack(parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
         kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
         u_offset, u_radius):
    """``(ints, floats)``: the arrays of :func:`drake_mh.scene.kernels.collision.collision_free`
    in two buffers (module docstring)."""
    sizes = [len(parent), len(g_anchor), len(s_radius), len(kinds), len(pair_a), len(t_vals), len(u_radius), len(dims)]
    ints = np.concatenate([np.asarray(sizes), parent, np.ravel(perm), kind, qidx, g_anchor, g_start, kinds,
                           pair_a, pair_b, np.ravel(t_meta), g_ustart, u_start]).astype(np.int64)
    floats = np.concatenate([np.ravel(a) for a in (KR, Kp, g_offset, g_radius, s_offset, s_radius, R_WO, p_WO,
                                                     dims, o_radius, o_gap, t_grid, t_vals, g_capsule, u_offset,
                                                     u_radius)]).astype(np.float64)
    return np.ascontiguousarray(ints), np.ascontiguousarray(floats)
