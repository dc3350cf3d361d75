"""Numba kernels behind :mod:`drake_mh.scene.batch` and :mod:`drake_mh.scene.segments`.

Every kernel evaluates the robot's sphere model in blocks of ``LANES`` configurations with
the lane index innermost (structure of arrays, as :mod:`drake_mh.kinematics.kernels`), so LLVM
vectorizes each per-joint and per-sphere operation across configurations (SIMD). Branches
depend on the link, sphere or obstacle only, or reduce over the block ("does any lane need the
fine spheres of this link?") — the scheme of VAMP (Thomason, Kingston, Kavraki, ICRA 2024):
a bounding sphere per link first, the link's spheres only where it is near.

The *constraint values* of one configuration are, in this order,

* ``S`` per-sphere obstacle clearances: ``min_k sd_k(c_s) - r_s`` (``sd_k`` the closed-form
  signed distance of obstacle k, exact for spheres, boxes, cylinders and capsules), replaced by
  the link's bounding-sphere value (a lower bound of it) where that is already at least
  ``fine_below``;
* ``P`` per-link-pair self clearances: ``min |c_i - c_j| - r_i - r_j`` over the spheres of the
  two links, or the bounding spheres' value where that is at least ``fine_below``.

Obstacle kinds: 0 sphere (radius), 1 box (half sizes), 2 cylinder (radius, half length),
3 capsule (radius, half length); axes along z of the obstacle frame, as in
:mod:`drake_mh.geometry.shapes`; 4 a convex piece of a mesh and 5 a point cloud, whose values
are lower bounds of the signed distance (exact inside a piece, exact for a cloud), their data in
the rows of ``dims`` after the obstacles' own (:mod:`.pieces`). An obstacle may move: at lane parameter ``tau`` it is at
``p_WO + tau * v_WO`` (``v_WO`` a displacement [m] per unit of ``tau``).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from drake_mh._support.compilation import stable_calls
from drake_mh.kinematics.kernels import frames_block
from drake_mh.scene.kernels.pairs import FASTMATH, _lane_point, capsule_gap, pair_clearance, pair_floor
from drake_mh.scene.kernels.cloud import cloud_free, cloud_nearest2, cloud_radius
from drake_mh.scene.kernels.pieces import CLOUD, CONVEX, convex_free, convex_value

LANES = 128
"""Configurations per block (measured: 32 / 64 / 128 lanes gave 164 / 137 / 123 ns per Panda
configuration against 10 obstacles, the fixed cost per block shrinking with its size)."""

SPHERE, BOX, CYLINDER, CAPSULE = 0, 1, 2, 3

PER_LINK, PER_OBSTACLE, OVERALL = 0, 1, 2
"""The modes of :func:`link_clearances`: per link and link pair, per obstacle, over all obstacles."""


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _centre_block(m, a, offsets, i, R, p, cx, cy, cz):
    """World position of offset ``offsets[i] (3,)`` fixed in moving frame ``a`` (-1: the world),
    read in place (no view: :func:`.pairs._lane_point`)."""
    o0, o1, o2 = offsets[i, 0], offsets[i, 1], offsets[i, 2]
    if a < 0:
        for b in range(m):
            cx[b] = o0
            cy[b] = o1
            cz[b] = o2
    else:
        for b in range(m):
            cx[b] = p[a, 0, b] + R[a, 0, 0, b] * o0 + R[a, 0, 1, b] * o1 + R[a, 0, 2, b] * o2
            cy[b] = p[a, 1, b] + R[a, 1, 0, b] * o0 + R[a, 1, 1, b] * o1 + R[a, 1, 2, b] * o2
            cz[b] = p[a, 2, b] + R[a, 2, 0, b] * o0 + R[a, 2, 1, b] * o1 + R[a, 2, 2, b] * o2


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _obstacle_sd(m, k, kinds, R_WO, p_WO, v_WO, dims, tau, cx, cy, cz, out):
    """``out[b]`` = signed distance of point ``c[b]`` to obstacle k (at parameter ``tau[b]``)."""
    kind = kinds[k]
    px, py, pz = p_WO[k, 0], p_WO[k, 1], p_WO[k, 2]
    vx, vy, vz = v_WO[k, 0], v_WO[k, 1], v_WO[k, 2]
    r00, r01, r02 = R_WO[k, 0, 0], R_WO[k, 0, 1], R_WO[k, 0, 2]
    r10, r11, r12 = R_WO[k, 1, 0], R_WO[k, 1, 1], R_WO[k, 1, 2]
    r20, r21, r22 = R_WO[k, 2, 0], R_WO[k, 2, 1], R_WO[k, 2, 2]
    d0, d1, d2 = dims[k, 0], dims[k, 1], dims[k, 2]
    if kind == SPHERE:
        for b in range(m):
            dx = cx[b] - px - vx * tau[b]
            dy = cy[b] - py - vy * tau[b]
            dz = cz[b] - pz - vz * tau[b]
            out[b] = math.sqrt(dx * dx + dy * dy + dz * dz) - d0
    elif kind == BOX:
        for b in range(m):
            dx = cx[b] - px - vx * tau[b]
            dy = cy[b] - py - vy * tau[b]
            dz = cz[b] - pz - vz * tau[b]
            qx = abs(r00 * dx + r10 * dy + r20 * dz) - d0
            qy = abs(r01 * dx + r11 * dy + r21 * dz) - d1
            qz = abs(r02 * dx + r12 * dy + r22 * dz) - d2
            ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
            out[b] = math.sqrt(ox * ox + oy * oy + oz * oz) + min(max(qx, max(qy, qz)), 0.0)
    elif kind == CYLINDER:
        for b in range(m):
            dx = cx[b] - px - vx * tau[b]
            dy = cy[b] - py - vy * tau[b]
            dz = cz[b] - pz - vz * tau[b]
            x = r00 * dx + r10 * dy + r20 * dz
            y = r01 * dx + r11 * dy + r21 * dz
            z = r02 * dx + r12 * dy + r22 * dz
            qr = math.sqrt(x * x + y * y) - d0
            qa = abs(z) - d1
            orr, oa = max(qr, 0.0), max(qa, 0.0)
            out[b] = math.sqrt(orr * orr + oa * oa) + min(max(qr, qa), 0.0)
    elif kind == CAPSULE:
        for b in range(m):
            dx = cx[b] - px - vx * tau[b]
            dy = cy[b] - py - vy * tau[b]
            dz = cz[b] - pz - vz * tau[b]
            x = r00 * dx + r10 * dy + r20 * dz
            y = r01 * dx + r11 * dy + r21 * dz
            z = r02 * dx + r12 * dy + r22 * dz
            z = z - min(max(z, -d1), d1)
            out[b] = math.sqrt(x * x + y * y + z * z) - d0
    elif kind == CONVEX:
        for b in range(m):
            out[b] = convex_value(k, dims, cx[b] - px - vx * tau[b], cy[b] - py - vy * tau[b], cz[b] - pz - vz * tau[b])
    else:  # CLOUD (points in W)
        rho = cloud_radius(k, dims)
        for b in range(m):
            out[b] = math.sqrt(cloud_nearest2(k, dims, cx[b] - vx * tau[b], cy[b] - vy * tau[b], cz[b] - vz * tau[b],
                                              np.inf)) - rho


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _obstacle_free(m, k, kinds, R_WO, p_WO, dims, reach, cx, cy, cz, alive):
    """``alive[b] &=`` point ``c[b]`` is at least ``reach`` from obstacle k, with squared
    distances where the shape allows (no square root: the kernel's cost)."""
    kind = kinds[k]
    px, py, pz = p_WO[k, 0], p_WO[k, 1], p_WO[k, 2]
    r00, r01, r02 = R_WO[k, 0, 0], R_WO[k, 0, 1], R_WO[k, 0, 2]
    r10, r11, r12 = R_WO[k, 1, 0], R_WO[k, 1, 1], R_WO[k, 1, 2]
    r20, r21, r22 = R_WO[k, 2, 0], R_WO[k, 2, 1], R_WO[k, 2, 2]
    d0, d1, d2 = dims[k, 0], dims[k, 1], dims[k, 2]
    if kind == SPHERE:
        lim = (reach + d0) * (reach + d0)
        for b in range(m):
            dx, dy, dz = cx[b] - px, cy[b] - py, cz[b] - pz
            alive[b] &= dx * dx + dy * dy + dz * dz >= lim
    elif kind == BOX:
        lim = reach * reach
        for b in range(m):
            dx, dy, dz = cx[b] - px, cy[b] - py, cz[b] - pz
            ox = max(abs(r00 * dx + r10 * dy + r20 * dz) - d0, 0.0)
            oy = max(abs(r01 * dx + r11 * dy + r21 * dz) - d1, 0.0)
            oz = max(abs(r02 * dx + r12 * dy + r22 * dz) - d2, 0.0)
            alive[b] &= ox * ox + oy * oy + oz * oz >= lim
    elif kind == CYLINDER:
        lim = reach * reach
        for b in range(m):
            dx, dy, dz = cx[b] - px, cy[b] - py, cz[b] - pz
            x = r00 * dx + r10 * dy + r20 * dz
            y = r01 * dx + r11 * dy + r21 * dz
            z = r02 * dx + r12 * dy + r22 * dz
            orr = max(math.sqrt(x * x + y * y) - d0, 0.0)
            oa = max(abs(z) - d1, 0.0)
            alive[b] &= orr * orr + oa * oa >= lim
    elif kind == CAPSULE:
        lim = (reach + d0) * (reach + d0)
        for b in range(m):
            dx, dy, dz = cx[b] - px, cy[b] - py, cz[b] - pz
            x = r00 * dx + r10 * dy + r20 * dz
            y = r01 * dx + r11 * dy + r21 * dz
            z = r02 * dx + r12 * dy + r22 * dz
            z = z - min(max(z, -d1), d1)
            alive[b] &= x * x + y * y + z * z >= lim
    elif kind == CONVEX:
        for b in range(m):
            if alive[b]:
                alive[b] = convex_free(k, dims, cx[b] - px, cy[b] - py, cz[b] - pz, reach)
    else:  # CLOUD
        lim = reach + cloud_radius(k, dims)
        for b in range(m):
            if alive[b]:
                alive[b] = cloud_free(k, dims, cx[b], cy[b], cz[b], lim)




@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _gather(c, idx, a, R, p, Rc, pc):
    """Pose of moving frame ``a`` for the ``c`` lanes listed in ``idx``, compacted."""
    for i in range(c):
        b = idx[i]
        for u in range(3):
            pc[u, i] = p[a, u, b] if a >= 0 else 0.0
            for v in range(3):
                Rc[u, v, i] = R[a, u, v, b] if a >= 0 else (1.0 if u == v else 0.0)


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _point_free(k, kinds, R_WO, p_WO, dims, reach, x, y, z):
    """Whether point ``(x, y, z)`` is at least ``reach`` from obstacle k (squared distances:
    :func:`_obstacle_free` for one point)."""
    kind = kinds[k]
    dx, dy, dz = x - p_WO[k, 0], y - p_WO[k, 1], z - p_WO[k, 2]
    d0 = dims[k, 0]
    if kind == SPHERE:
        return dx * dx + dy * dy + dz * dz >= (reach + d0) * (reach + d0)
    if kind == CONVEX:
        return convex_free(k, dims, dx, dy, dz, reach)
    if kind == CLOUD:
        return cloud_free(k, dims, x, y, z, reach + cloud_radius(k, dims))
    u = R_WO[k, 0, 0] * dx + R_WO[k, 1, 0] * dy + R_WO[k, 2, 0] * dz
    v = R_WO[k, 0, 1] * dx + R_WO[k, 1, 1] * dy + R_WO[k, 2, 1] * dz
    w = R_WO[k, 0, 2] * dx + R_WO[k, 1, 2] * dy + R_WO[k, 2, 2] * dz
    if kind == BOX:
        ox, oy, oz = max(abs(u) - d0, 0.0), max(abs(v) - dims[k, 1], 0.0), max(abs(w) - dims[k, 2], 0.0)
        return ox * ox + oy * oy + oz * oz >= reach * reach
    if kind == CYLINDER:
        orr, oa = max(math.sqrt(u * u + v * v) - d0, 0.0), max(abs(w) - dims[k, 1], 0.0)
        return orr * orr + oa * oa >= reach * reach
    w = w - min(max(w, -dims[k, 1]), dims[k, 1])  # CAPSULE
    return u * u + v * v + w * w >= (reach + d0) * (reach + d0)


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def point_distance(k, kinds, R_WO, p_WO, dims, x, y, z):
    """Distance [m] of point ``(x, y, z)`` outside obstacle k (0 or less inside: the value
    :func:`_point_free` compares with its reach, with a square root)."""
    kind = kinds[k]
    dx, dy, dz = x - p_WO[k, 0], y - p_WO[k, 1], z - p_WO[k, 2]
    d0 = dims[k, 0]
    if kind == SPHERE:
        return math.sqrt(dx * dx + dy * dy + dz * dz) - d0
    if kind == CONVEX:
        return convex_value(k, dims, dx, dy, dz)
    if kind == CLOUD:
        return math.sqrt(cloud_nearest2(k, dims, x, y, z, np.inf)) - cloud_radius(k, dims)
    u = R_WO[k, 0, 0] * dx + R_WO[k, 1, 0] * dy + R_WO[k, 2, 0] * dz
    v = R_WO[k, 0, 1] * dx + R_WO[k, 1, 1] * dy + R_WO[k, 2, 1] * dz
    w = R_WO[k, 0, 2] * dx + R_WO[k, 1, 2] * dy + R_WO[k, 2, 2] * dz
    if kind == BOX:
        ox, oy, oz = max(abs(u) - d0, 0.0), max(abs(v) - dims[k, 1], 0.0), max(abs(w) - dims[k, 2], 0.0)
        return math.sqrt(ox * ox + oy * oy + oz * oz)
    if kind == CYLINDER:
        orr, oa = max(math.sqrt(u * u + v * v) - d0, 0.0), max(abs(w) - dims[k, 1], 0.0)
        return math.sqrt(orr * orr + oa * oa)
    w = w - min(max(w, -dims[k, 1]), dims[k, 1])  # CAPSULE
    return math.sqrt(u * u + v * v + w * w) - d0


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _range_free(b, a, s0, s1, s_offset, s_radius, clearance, R, p, k, kinds, R_WO, p_WO, dims):
    """Whether spheres ``s0 .. s1-1`` (fixed in frame ``a``) of lane ``b`` are all at least
    ``clearance`` from obstacle k; stops at the first that is not."""
    for s in range(s0, s1):
        x, y, z = _lane_point(a, s_offset, s, 0, R, p, b)
        if not _point_free(k, kinds, R_WO, p_WO, dims, clearance + s_radius[s], x, y, z):
            return False
    return True


@stable_calls()
@numba.njit(cache=True, fastmath=FASTMATH)  # not inlined: a copy in collision_free's lane loop slowed it 25 %
def _groups_free(b, a, u0, u1, u_start, u_offset, u_radius, s_offset, s_radius, clearance, R, p, k, kinds, R_WO,
                 p_WO, dims):
    """Whether the spheres of groups ``u0 .. u1-1`` (fixed in frame ``a``) of lane ``b`` are all
    at least ``clearance`` from obstacle k; stops at the first that is not. A group whose
    bounding sphere keeps the clearance is passed whole (:func:`drake_mh.scene.batch.sphere_groups`).

    For a link of several groups: a link of one group is its bounding sphere, known to be near,
    and its spheres are tested directly (:func:`_range_free`; a group test there measured
    20-30 % slower planning on the capsule Panda). Not inlined: inlined into the batch kernel it
    measured 136 ns per capsule-Panda configuration against 10 obstacles instead of 107.

    Scalar on purpose: the lanes that reach a link's spheres are few per block (about 4 of 128
    per link and obstacle in the 10-obstacle benchmark), where SIMD loops over compacted lanes
    cost more in loop overhead than they save (measured 128 ns per configuration against 115)."""
    for u in range(u0, u1):
        x, y, z = _lane_point(a, u_offset, u, 0, R, p, b)
        if not _point_free(k, kinds, R_WO, p_WO, dims, clearance + u_radius[u], x, y, z) and not _range_free(
                b, a, u_start[u], u_start[u + 1], s_offset, s_radius, clearance, R, p, k, kinds, R_WO, p_WO, dims):
            return False
    return True


@numba.njit(cache=True, fastmath=FASTMATH)
def collision_free(QT, clearance, self_clearance, parent, KR, Kp, perm, kind, qidx,
                   g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
                   kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule,
                   g_ustart, u_start, u_offset, u_radius, out):
    """``out (N,)``: every sphere at least ``clearance`` from every obstacle and every checked
    link pair at least ``self_clearance`` apart (both > 0: the tests compare squares; the pairs'
    floor tables ``t_meta, t_grid, t_vals`` of :mod:`drake_mh.scene.pair_table` and the links'
    bounding capsules ``g_capsule`` of :class:`drake_mh.scene.batch.CollisionModel`). A (link,
    obstacle) pair whose static gap ``o_gap[g, k]`` (:meth:`~drake_mh.scene.batch.CollisionModel.static_gaps`:
    no configuration brings the two bounding spheres closer) keeps the clearance is skipped."""
    F, G, N, K = parent.shape[0], g_anchor.shape[0], QT.shape[1], kinds.shape[0]
    L = min(LANES, N)  # one configuration allocates one lane
    R, p = np.empty((F, 3, 3, L)), np.empty((F, 3, L))
    sn, cs = np.empty(L), np.empty(L)
    Gx, Gy, Gz = np.empty((G, L)), np.empty((G, L)), np.empty((G, L))
    cx, cy, cz = np.empty(L), np.empty(L), np.empty(L)
    alive, near = np.empty(L, np.bool_), np.empty(L, np.bool_)
    idx = np.empty(L, np.int64)
    hit = np.zeros(8 * ((L + 7) // 8), np.uint8)
    words = hit.view(np.uint64)
    pbuf = np.empty((s_radius.shape[0], 4))
    for n0 in range(0, N, LANES):
        m = used = min(LANES, N - n0)
        nw = (m + 7) // 8
        for b in range(m, 8 * nw):  # lanes past m read 0
            hit[b] = 0
        frames_block(QT, n0, m, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs)
        for b in range(m):
            alive[b] = True
        for g in range(G):
            a = g_anchor[g]
            _centre_block(m, a, g_offset, g, R, p, cx, cy, cz)
            for b in range(m):
                Gx[g, b], Gy[g, b], Gz[g, b] = cx[b], cy[b], cz[b]
            for k in range(K):
                if o_gap[g, k] >= clearance:  # no configuration brings them near
                    continue
                # the link's bounding sphere vs the obstacle's: most pairs end here
                lim = clearance + g_radius[g] + o_radius[k]
                lim *= lim
                px, py, pz = p_WO[k, 0], p_WO[k, 1], p_WO[k, 2]
                close = False
                for b in range(m):
                    dx, dy, dz = cx[b] - px, cy[b] - py, cz[b] - pz
                    close |= dx * dx + dy * dy + dz * dz < lim
                if not close:
                    continue
                for b in range(m):  # the link's bounding sphere vs the obstacle's shape
                    near[b] = True
                _obstacle_free(m, k, kinds, R_WO, p_WO, dims, clearance + g_radius[g], cx, cy, cz, near)
                for b in range(m):  # the lanes still near, as bytes read 8 at a time (few are set)
                    hit[b] = alive[b] > near[b]
                for w in range(nw):
                    if words[w] != 0:
                        for b in range(8 * w, 8 * w + 8):
                            if not hit[b]:
                                continue
                            if g_ustart[g + 1] - g_ustart[g] > 1:  # the link's spheres a group at a time
                                alive[b] = _groups_free(b, a, g_ustart[g], g_ustart[g + 1], u_start, u_offset,
                                                        u_radius, s_offset, s_radius, clearance, R, p, k, kinds,
                                                        R_WO, p_WO, dims)
                            else:  # one group: the link's bounding sphere, known to be near
                                alive[b] = _range_free(b, a, g_start[g], g_start[g + 1], s_offset, s_radius,
                                                       clearance, R, p, k, kinds, R_WO, p_WO, dims)
            any_alive = False
            for b in range(m):
                any_alive |= alive[b]
            if not any_alive:
                break
        for i in range(pair_a.shape[0]):
            ga, gb = pair_a[i], pair_b[i]
            lim = self_clearance + g_radius[ga] + g_radius[gb]
            c = 0
            for b in range(m):
                dx, dy, dz = Gx[ga, b] - Gx[gb, b], Gy[ga, b] - Gy[gb, b], Gz[ga, b] - Gz[gb, b]
                if alive[b] and dx * dx + dy * dy + dz * dz < lim * lim:
                    idx[c] = b
                    c += 1
            if c == 0:
                continue
            for j in range(c):  # the lanes whose bounding spheres are near: their sphere pairs
                b = idx[j]
                if pair_floor(i, QT, n0 + b, t_meta, t_grid, t_vals) >= self_clearance:
                    continue  # the pair's table shows it clear
                if capsule_gap(b, ga, gb, g_anchor, g_capsule, R, p) >= self_clearance:
                    continue  # so do the links' bounding capsules
                alive[b] &= pair_clearance(b, ga, gb, self_clearance, self_clearance, False, g_anchor, g_start,
                                           g_radius, g_ustart, u_start, u_offset, u_radius, Gx[ga, b], Gy[ga, b],
                                           Gz[ga, b], Gx[gb, b], Gy[gb, b], Gz[gb, b], s_offset, s_radius, R, p,
                                           pbuf) >= self_clearance
        for b in range(used):
            out[n0 + b] = alive[b]


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _compact_centres(c, offsets, r, Rc, pc, ccx, ccy, ccz):
    """World position of offset ``offsets[r] (3,)`` for the ``c`` compacted lanes of pose
    ``(Rc, pc)`` (:func:`_gather`), read in place (no view: :func:`.pairs._lane_point`)."""
    o0, o1, o2 = offsets[r, 0], offsets[r, 1], offsets[r, 2]
    for i in range(c):
        ccx[i] = pc[0, i] + Rc[0, 0, i] * o0 + Rc[0, 1, i] * o1 + Rc[0, 2, i] * o2
        ccy[i] = pc[1, i] + Rc[1, 0, i] * o0 + Rc[1, 1, i] * o1 + Rc[1, 2, i] * o2
        ccz[i] = pc[2, i] + Rc[2, 0, i] * o0 + Rc[2, 1, i] * o1 + Rc[2, 2, i] * o2


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _cloud_sd(c, k, dims, v_WO, tc, ccx, ccy, ccz, cap, grow, sd):
    """``sd[i]``: the signed distance of point ``cc[i]`` to cloud k (at ``tc[i]``) where it is
    below ``cap[i] + grow``, else a lower bound of it at least ``cap[i] + grow`` (the search looks
    no farther: :func:`.cloud.cloud_nearest2`). ``cap`` may be ``sd`` itself (each value is
    read before it is written). A cloud's signed distance is at least ``-rho``, the value given
    where the cap is below it."""
    rho = cloud_radius(k, dims)
    vx, vy, vz = v_WO[k, 0], v_WO[k, 1], v_WO[k, 2]
    for i in range(c):
        reach = cap[i] + grow + rho
        if reach <= 0.0:
            sd[i] = -rho
            continue
        bound2 = reach * reach if reach < np.inf else np.inf
        sd[i] = math.sqrt(cloud_nearest2(k, dims, ccx[i] - vx * tc[i], ccy[i] - vy * tc[i], ccz[i] - vz * tc[i],
                                         bound2)) - rho


@stable_calls()
@numba.njit(cache=True, fastmath=FASTMATH)
def _spheres_sd(c, s0, s1, k, kinds, R_WO, p_WO, v_WO, dims, tc, Rc, pc, s_offset, s_radius, ccx, ccy, ccz, sd, sc,
                lim):
    """``sc[i] = min(sc[i], sd_k(c_s) - r_s)`` over spheres ``s0 .. s1-1`` for the ``c``
    compacted lanes of pose ``(Rc, pc)`` (obstacles at ``tc``), SIMD across the lanes. For a
    point cloud, each sphere's nearest-point search looks no farther than the distance that
    could still lower ``min(sc[i], lim[i])``: ``sc`` ends exact where it is below ``lim``, a
    lower bound of at least ``lim`` above it (as for :func:`_groups_sd`)."""
    cloud = kinds[k] == CLOUD
    for s in range(s0, s1):
        _compact_centres(c, s_offset, s, Rc, pc, ccx, ccy, ccz)
        if cloud:
            for i in range(c):
                sd[i] = min(sc[i], lim[i])  # a point nearer than this + r_s lowers sc[i]
            _cloud_sd(c, k, dims, v_WO, tc, ccx, ccy, ccz, sd, s_radius[s], sd)
        else:
            _obstacle_sd(c, k, kinds, R_WO, p_WO, v_WO, dims, tc, ccx, ccy, ccz, sd)
        for i in range(c):
            sc[i] = min(sc[i], sd[i] - s_radius[s])


@stable_calls()
@numba.njit(cache=True, fastmath=FASTMATH)
def _groups_sd(c, u0, u1, lim, k, kinds, R_WO, p_WO, v_WO, dims, tc, Rc, pc, u_start, u_offset, u_radius, s_offset,
               s_radius, ccx, ccy, ccz, sd, sc, glb, fl):
    """:func:`_spheres_sd` over the spheres of groups ``u0 .. u1-1``, a group at a time, the
    nearest (by its bounding sphere) first. A group whose bounding-sphere value
    ``sd_k(C_u) - R_u`` (a lower bound of its spheres') is at least ``min(sc[i], lim[i])`` in
    every lane is skipped: it cannot lower a value below that, and the lane's value becomes at
    most that bound. So ``sc`` is exact where it ends below ``lim``, a lower bound above it (the
    contract of :func:`link_clearances`, with ``lim`` its ``fine_below``; per obstacle ``lim`` is
    an upper bound of the minimum over all links, so the minimum stays exact). Scratch:
    ``glb (U, L)``, ``fl (L,)``. The verification of a meshed-Panda plan spends most of its time
    here."""
    nu = u1 - u0
    key = np.empty(nu)
    for j in range(nu):
        _compact_centres(c, u_offset, u0 + j, Rc, pc, ccx, ccy, ccz)
        if kinds[k] == CLOUD:  # exact below lim only: above it the group is skipped either way
            _cloud_sd(c, k, dims, v_WO, tc, ccx, ccy, ccz, lim, u_radius[u0 + j], sd)
        else:
            _obstacle_sd(c, k, kinds, R_WO, p_WO, v_WO, dims, tc, ccx, ccy, ccz, sd)
        lowest = np.inf
        for i in range(c):
            glb[j, i] = sd[i] - u_radius[u0 + j]
            lowest = min(lowest, glb[j, i])
        key[j] = lowest
    for i in range(c):
        fl[i] = np.inf
    for j in np.argsort(key):
        need = False
        for i in range(c):
            need |= glb[j, i] < min(sc[i], lim[i])
        if need:
            u = u0 + j
            _spheres_sd(c, u_start[u], u_start[u + 1], k, kinds, R_WO, p_WO, v_WO, dims, tc, Rc, pc, s_offset,
                        s_radius, ccx, ccy, ccz, sd, sc, lim)
        else:
            for i in range(c):
                fl[i] = min(fl[i], glb[j, i])
    for i in range(c):
        sc[i] = min(sc[i], fl[i])


@stable_calls()
@numba.njit(cache=True, fastmath=FASTMATH)
def link_clearances(QT, tau, fine_below, pair_fine_below, mode, parent, KR, Kp, perm, kind, qidx,
                    g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
                    kinds, R_WO, p_WO, v_WO, dims, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart,
                    u_start, u_offset, u_radius, out):
    """Clearance values of every configuration of ``QT (nq, N)`` (obstacles at ``tau (N,)``).

    ``mode`` 1 (:data:`PER_OBSTACLE`): ``out (N, K)``, the smallest ``sd_k(c_s) - r_s`` over
    all spheres, per obstacle (exact for the model); 2 (:data:`OVERALL`): ``out (N, 1)``, the
    smallest over all obstacles too, where each (link, obstacle) pair whose bounding value cannot
    go below the smallest value so far is skipped (exact too: at N = 1 on the capsule Panda
    against ten obstacles far fewer spheres than per obstacle). 0 (:data:`PER_LINK`):
    ``out (N, G + P)``: per link the smallest value over its spheres and all obstacles where it
    is below ``fine_below``, above it a lower bound of it that is at least ``fine_below`` (the
    link's bounding-sphere value, or, for a point cloud, where its searches stopped); then per checked link pair the
    smallest sphere-sphere clearance where that is below the pair's ``pair_fine_below (P,)``
    (above it, a lower bound of it at least the bounding spheres' value:
    :func:`.pairs.pair_clearance`, or the pair's floor table where that is at least
    ``pair_fine_below``: :mod:`drake_mh.scene.pair_table`; ``-inf``: the bounding spheres' value).
    """
    F, G, N, K, P = parent.shape[0], g_anchor.shape[0], QT.shape[1], kinds.shape[0], pair_a.shape[0]
    per_obstacle, overall = mode != PER_LINK, mode == OVERALL
    L = max(1, min(LANES, N))  # a short batch (segment bisection) allocates its lanes only
    R, p = np.empty((F, 3, 3, L)), np.empty((F, 3, L))
    sn, cs = np.empty(L), np.empty(L)
    Gx, Gy, Gz = np.empty((G, L)), np.empty((G, L)), np.empty((G, L))
    cx, cy, cz, sd, tb = np.empty(L), np.empty(L), np.empty(L), np.empty(L), np.empty(L)
    lb = np.empty((G, K, L))
    best = np.empty((max(K, G), L))
    idx = np.empty(L, np.int64)
    pbuf = np.empty((s_radius.shape[0], 4))
    pc, Rc = np.empty((3, L)), np.empty((3, 3, L))
    ccx, ccy, ccz, tc, sc, fl, lim = np.empty(L), np.empty(L), np.empty(L), np.empty(L), np.empty(L), np.empty(L), \
        np.empty(L)
    glb = np.empty((max(1, int(np.max(np.diff(g_ustart)))) if G else 1, L))
    for n0 in range(0, N, LANES):
        m = used = min(LANES, N - n0)  # a short batch (segment bisection) computes its lanes only
        for b in range(m):
            tb[b] = tau[n0 + b]
        frames_block(QT, n0, m, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs)
        for g in range(G):  # bounding spheres: a lower bound per link and obstacle
            _centre_block(m, g_anchor[g], g_offset, g, R, p, cx, cy, cz)
            for b in range(m):
                Gx[g, b], Gy[g, b], Gz[g, b] = cx[b], cy[b], cz[b]
            for k in range(K):
                if kinds[k] == CLOUD and not per_obstacle:  # per link, exact below fine_below only
                    for b in range(m):
                        lim[b] = fine_below
                    _cloud_sd(m, k, dims, v_WO, tb, cx, cy, cz, lim, g_radius[g], sd)
                else:  # per obstacle, exact: lb + 2 radius bounds the minimum from above
                    _obstacle_sd(m, k, kinds, R_WO, p_WO, v_WO, dims, tb, cx, cy, cz, sd)
                for b in range(m):
                    lb[g, k, b] = sd[b] - g_radius[g]
        # where the fine value is needed: per obstacle, below an upper bound of the minimum
        # (a link's spheres lie within its bounding sphere: value <= lower bound + 2 radius);
        # per link, below fine_below
        for r in range(best.shape[0]):
            for b in range(m):
                best[r, b] = np.inf
        if per_obstacle:
            for k in range(K):
                rk = 0 if overall else k
                for g in range(G):
                    for b in range(m):
                        best[rk, b] = min(best[rk, b], lb[g, k, b] + 2.0 * g_radius[g])
        for g in range(G):
            a = g_anchor[g]
            for k in range(K):
                rk = 0 if overall else k  # the row of best that obstacle k lowers
                c = 0
                for b in range(m):
                    limit = best[rk, b] if per_obstacle else fine_below
                    if lb[g, k, b] < limit:
                        idx[c] = b
                        c += 1
                if c == 0:
                    if not per_obstacle:
                        for b in range(m):
                            best[g, b] = min(best[g, b], lb[g, k, b])
                    continue
                _gather(c, idx, a, R, p, Rc, pc)
                for i in range(c):
                    tc[i] = tb[idx[i]]
                    sc[i] = np.inf
                for i in range(c):  # per obstacle: the smallest value so far (an upper bound of the minimum)
                    lim[i] = best[rk, idx[i]] if per_obstacle else fine_below
                if g_ustart[g + 1] - g_ustart[g] > 1:  # a group at a time, nearest first
                    _groups_sd(c, g_ustart[g], g_ustart[g + 1], lim, k, kinds, R_WO, p_WO, v_WO, dims, tc, Rc, pc,
                               u_start, u_offset, u_radius, s_offset, s_radius, ccx, ccy, ccz, sd, sc, glb, fl)
                else:
                    _spheres_sd(c, g_start[g], g_start[g + 1], k, kinds, R_WO, p_WO, v_WO, dims, tc, Rc, pc, s_offset,
                                s_radius, ccx, ccy, ccz, sd, sc, lim)
                if per_obstacle:
                    for i in range(c):
                        best[rk, idx[i]] = min(best[rk, idx[i]], sc[i])
                else:
                    for b in range(m):  # lanes not listed keep the lower bound
                        best[g, b] = min(best[g, b], lb[g, k, b]) if lb[g, k, b] >= fine_below else best[g, b]
                    for i in range(c):
                        best[g, idx[i]] = min(best[g, idx[i]], sc[i])
        rows = 1 if overall else K if per_obstacle else G
        for r in range(rows):
            for b in range(used):
                out[n0 + b, r] = best[r, b]
        if per_obstacle:
            continue
        for i in range(P):
            ga, gb = pair_a[i], pair_b[i]
            for b in range(used):
                dx, dy, dz = Gx[ga, b] - Gx[gb, b], Gy[ga, b] - Gy[gb, b], Gz[ga, b] - Gz[gb, b]
                v = math.sqrt(dx * dx + dy * dy + dz * dz) - g_radius[ga] - g_radius[gb]
                fine = pair_fine_below[i]
                if v < fine:  # the bounding capsules' value, a lower bound too
                    v = max(v, capsule_gap(b, ga, gb, g_anchor, g_capsule, R, p))
                if v < fine:  # exact below the pair's fine_below, a lower bound (at least v) above
                    floor = pair_floor(i, QT, n0 + b, t_meta, t_grid, t_vals)
                    if floor >= fine:  # the pair's table: a lower bound above fine
                        out[n0 + b, G + i] = max(v, floor)
                        continue
                    v = pair_clearance(b, ga, gb, fine, -np.inf, True, g_anchor, g_start, g_radius, g_ustart, u_start,
                                       u_offset, u_radius, Gx[ga, b], Gy[ga, b], Gz[ga, b], Gx[gb, b], Gy[gb, b],
                                       Gz[gb, b], s_offset, s_radius, R, p, pbuf)
                out[n0 + b, G + i] = v
