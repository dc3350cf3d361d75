"""The entry points of the collision kernels that Python calls (:mod:`drake_mh.scene.batch`).

Each reads the arrays of :func:`drake_mh.scene.kernels.packing.pack` from two buffers (numba's
dispatch costs per argument: 6 arguments instead of 33), takes the configurations as the caller
has them, ``Q (N, nq)``, and checks their finiteness while transposing them to the kernels'
layout (:func:`_transposed_finite`). The one-configuration path (:func:`collision_free_one`) is
scalar, allocates nothing and is called through the compiled entry point of its one signature
(:func:`one_entry_point`), its arrays and workspace in one buffer (:func:`one_buffer`).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.lib.stride_tricks import as_strided

from drake_mh.kinematics.kernels import frames_block
from drake_mh.scene.kernels.collision import _groups_free, _point_free, _range_free, collision_free, link_clearances
from drake_mh.scene.kernels.packing import _rows, unpack, _unpack_views
from drake_mh.scene.kernels.pairs import FASTMATH, _lane_point, capsule_gap, pair_clearance, pair_floor


@numba.njit(cache=True, inline="always")
def _transposed_finite(Q, QT):
    """``QT[:] = Q.T`` for ``Q (N, nq)``; False (stopping there) at a NaN or an infinity
    (without fast-math: 3.4 ns per Panda configuration, against 8.5-8.9 ns for numpy's check and
    transposition from Python)."""
    for n in range(Q.shape[0]):
        for j in range(Q.shape[1]):
            x = Q[n, j]
            if not math.isfinite(x):
                return False
            QT[j, n] = x
    return True


@numba.njit(cache=True)
def collision_free_packed(Q, clearance, self_clearance, ints, floats, out):
    """:func:`collision_free` of ``Q (N, nq)`` on the buffers of :func:`pack`; ``False``
    (nothing computed) if ``Q`` holds a NaN or an infinity (checked while ``Q`` is transposed to
    the kernels' layout, :func:`_transposed_finite`)."""
    QT = np.empty((Q.shape[1], Q.shape[0]))
    if not _transposed_finite(Q, QT):
        return False
    (parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
     kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
     u_offset, u_radius) = unpack(ints, floats)
    collision_free(QT, clearance, self_clearance, parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius,
                   g_start, s_offset, s_radius, kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta,
                   t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset, u_radius, out)
    return True


@numba.njit(cache=True)
def obstacle_clearances_packed(Q, mode, ints, floats, v_WO, out):
    """``out``: :func:`link_clearances` of ``Q (N, nq)`` per obstacle (``mode``
    :data:`~.collision.PER_OBSTACLE`, ``out (N, K)``) or over all obstacles
    (:data:`~.collision.OVERALL`, ``out (N, 1)``), obstacles where they are, on the
    buffers of :func:`pack` (no link pairs); ``False`` (nothing computed) if ``Q`` holds a NaN
    or an infinity. One call from Python passes 6 arguments instead of 33 (numba's dispatch cost
    about 12 µs of a one-configuration call)."""
    N = Q.shape[0]
    QT = np.empty((Q.shape[1], N))
    if not _transposed_finite(Q, QT):
        return False
    (parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
     kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
     u_offset, u_radius) = unpack(ints, floats)
    link_clearances(QT, np.zeros(N), np.inf, np.zeros(0), mode, parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset,
                    g_radius, g_start, s_offset, s_radius, kinds, R_WO, p_WO, v_WO, dims, pair_a, pair_b, t_meta,
                    t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset, u_radius, out)
    return True


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _free_one(QT, clearance, self_clearance, parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius,
              g_start, s_offset, s_radius, kinds, R_WO, p_WO, dims, o_radius, o_gap, pairs, R, p, sn, cs, gc, pbuf):
    """:func:`collision_free` of the one configuration ``QT (nq, 1)``, scalar (no lane arrays,
    no allocation: ``R, p, sn, cs``, ``gc (G, 3)`` and ``pbuf (S, 4)`` are the caller's),
    stopping at the first sphere below the clearance. Same tests in the same order, so the same
    answer. ``pairs``: :attr:`drake_mh.scene.batch.CollisionModel.pair_arrays`."""
    pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset, u_radius = pairs
    frames_block(QT, 0, 1, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs)
    for g in range(g_anchor.shape[0]):
        a = g_anchor[g]
        x, y, z = _lane_point(a, g_offset, g, 0, R, p, 0)
        gc[g, 0], gc[g, 1], gc[g, 2] = x, y, z
        reach = clearance + g_radius[g]
        for k in range(kinds.shape[0]):
            if o_gap[g, k] >= clearance:  # no configuration brings them near
                continue
            dx, dy, dz = x - p_WO[k, 0], y - p_WO[k, 1], z - p_WO[k, 2]
            lim = reach + o_radius[k]
            if dx * dx + dy * dy + dz * dz >= lim * lim:  # bounding spheres apart
                continue
            if _point_free(k, kinds, R_WO, p_WO, dims, reach, x, y, z):  # bounding sphere vs the shape
                continue
            if g_ustart[g + 1] - g_ustart[g] > 1:
                if not _groups_free(0, a, g_ustart[g], g_ustart[g + 1], u_start, u_offset, u_radius, s_offset,
                                    s_radius, clearance, R, p, k, kinds, R_WO, p_WO, dims):
                    return False
            elif not _range_free(0, a, g_start[g], g_start[g + 1], s_offset, s_radius, clearance, R, p, k, kinds,
                                 R_WO, p_WO, dims):
                return False
    for i in range(pair_a.shape[0]):
        ga, gb = pair_a[i], pair_b[i]
        dx, dy, dz = gc[ga, 0] - gc[gb, 0], gc[ga, 1] - gc[gb, 1], gc[ga, 2] - gc[gb, 2]
        lim = self_clearance + g_radius[ga] + g_radius[gb]
        if dx * dx + dy * dy + dz * dz < lim * lim and pair_floor(i, QT, 0, t_meta, t_grid, t_vals) < self_clearance \
                and capsule_gap(0, ga, gb, g_anchor, g_capsule, R, p) < self_clearance and pair_clearance(
                0, ga, gb, self_clearance, self_clearance, False, g_anchor, g_start, g_radius, g_ustart, u_start,
                u_offset, u_radius, gc[ga, 0], gc[ga, 1], gc[ga, 2], gc[gb, 0], gc[gb, 1], gc[gb, 2], s_offset,
                s_radius, R, p, pbuf) < self_clearance:
            return False
    return True


ONE_SIGNATURE = (numba.types.Array(numba.float64, 1, "A"), numba.float64, numba.float64,
                 numba.types.Array(numba.float64, 1, "C"))
"""The one signature :func:`collision_free_one` is called with (``q`` of any strides)."""


def one_entry_point():
    """The compiled entry point of :func:`collision_free_one` for :data:`ONE_SIGNATURE`: a call
    skips numba's type dispatch (about 0.15 µs per call), so its caller
    must pass exactly those types (:meth:`drake_mh.scene.batch.CollisionModel.free_function`)."""
    return collision_free_one.compile(ONE_SIGNATURE)  # the compiled entry point (numba Dispatcher.compile)


def one_buffer(ints, floats) -> np.ndarray:
    """The one float64 buffer :func:`collision_free_one` reads: ``[len(ints), len(floats)]``,
    the bits of :func:`pack`'s ``ints``, its ``floats``, then the workspace it writes (one
    array argument instead of three: each costs about 50 ns of a call's unboxing)."""
    F, G, S = int(ints[0]), int(ints[1]), int(ints[2])
    work = np.empty(12 * F + 2 + 3 * G + 4 * S)
    head = np.array([len(ints), len(floats)], dtype=np.float64)
    return np.ascontiguousarray(np.concatenate([head, np.ascontiguousarray(ints, np.int64).view(np.float64),
                                                floats, work]))


@numba.njit(cache=True)
def collision_free_one(q, clearance, self_clearance, buf):
    """:func:`collision_free` of one configuration ``q (nq,)`` on the buffer of
    :func:`one_buffer`, allocating nothing (clearances >= 0; 0 counts touching as a
    collision, as :meth:`drake_mh.scene.Scene.collision_free`).

    Returns:
        1 (free), 0 (not free), -1 (``q`` holds a NaN or an infinity) or -2 (a clearance is not
        in [0, inf)); checked here, without fast-math.
    """
    if not (0.0 <= clearance < np.inf and 0.0 <= self_clearance < np.inf):
        return -2
    for j in range(q.shape[0]):
        if not math.isfinite(q[j]):
            return -1
    clearance, self_clearance = max(clearance, 1e-12), max(self_clearance, 1e-12)  # squared tests
    n_ints, n_floats = int(buf[0]), int(buf[1])
    ints = buf[2:2 + n_ints].view(np.int64)
    floats = buf[2 + n_ints:2 + n_ints + n_floats]
    work = buf[2 + n_ints + n_floats:]
    (parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
     kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
     u_offset, u_radius) = _unpack_views(ints, floats)
    F, G = parent.shape[0], g_anchor.shape[0]
    R = as_strided(work[:9 * F], shape=(F, 3, 3, 1), strides=(72, 24, 8, 8))
    p = as_strided(work[9 * F:12 * F], shape=(F, 3, 1), strides=(24, 8, 8))
    sn, cs = work[12 * F:12 * F + 1], work[12 * F + 1:12 * F + 2]
    gc = _rows(work, 12 * F + 2, G, 3)
    pbuf = _rows(work, 12 * F + 2 + 3 * G, s_radius.shape[0], 4)
    QT = as_strided(q, shape=(q.shape[0], 1), strides=(q.strides[0], 8))  # (nq, 1), q's own strides
    free = _free_one(QT, clearance, self_clearance, parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius,
                     g_start, s_offset, s_radius, kinds, R_WO, p_WO, dims, o_radius, o_gap,
                     (pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset, u_radius), R, p,
                     sn, cs, gc, pbuf)
    return 1 if free else 0
