"""Batched state check for motions: collision (early exit), within a margin, or clear.

A motion is invalid as soon as one of its states collides, and certified at once when every
state keeps a margin (:func:`drake_mh.planning.rrt_connect._kernels._motion`). So the
planner's check differs from :func:`drake_mh.scene._collision_kernels.collision_free` (one
answer per configuration at one clearance; a block stops only when *every* configuration in
it collides) in two respects:

* it returns COLLISION at the first sphere found below the plain clearance in any lane,
  VAMP's early exit (Thomason, Kingston, Kavraki, ICRA 2024);
* it tests two clearances in one pass, each per link and per link pair: the margins (a
  certificate asks each constraint row for a margin proportional to how fast it can move)
  and, only for the spheres below a margin, the plain clearance. So one pass tells a
  collision (reject) from a state that is free but within its margin (refine), and says
  per configuration which kept the margins.

It works in a workspace allocated once per plan. The geometry is the scene kernel's, through
its own inline helpers (forward kinematics of the block, link bounding spheres, the
closed-form obstacle tests, sphere pairs): CLEAR means every sphere of the model is at least
its link's margin from every obstacle and every checked link pair at least its margin apart,
in every lane."""

from __future__ import annotations

import numba
import numpy as np

from drake_mh._kernels import _frames_block
from drake_mh.scene._collision_kernels import FASTMATH, _centre_block, _gather, _obstacle_free, _pair_min


@numba.njit(cache=True)
def make_workspace(F, G, lanes):
    """Arrays :func:`block_check` writes into, for ``F`` moving frames, ``G`` links, ``lanes`` lanes."""
    L = lanes
    return (np.empty((F, 3, 3, L)), np.empty((F, 3, L)), np.empty(L), np.empty(L), np.empty((G, L)),
            np.empty((G, L)), np.empty((G, L)), np.empty(L), np.empty(L), np.empty(L), np.empty(L, np.bool_),
            np.empty(L, np.bool_), np.empty(L, np.bool_), np.empty(L, np.bool_), np.empty(L, np.int64),
            np.empty((3, L)), np.empty((3, 3, L)), np.empty(L), np.empty(L), np.empty(L))


CLEAR, NEAR, COLLISION = 0, 1, 2
"""Answers of :func:`block_check`."""


@numba.njit(cache=True, fastmath=FASTMATH)
def block_check(QT, n0, m, link_margin, pair_margin, link_plain, pair_plain, arrays, ws, out):
    """Check configurations ``QT[:, n0:n0+m]`` (``m`` at most the workspace's lanes) at two
    clearance levels in one pass.

    Args:
        link_margin, pair_margin: ``(G,)`` / ``(P,)`` clearances [m] each link must keep from
            every obstacle and each checked link pair between its links, with a margin.
        link_plain, pair_plain: the same without the margin (each at most its margin value;
            all > 0: the tests compare squares).
        arrays: the unpacked scene arrays (:func:`drake_mh.scene._collision_kernels._unpack`).
        ws: :func:`make_workspace`.
        out: ``out[n0 + b]`` is set to whether configuration ``n0 + b`` keeps the margins
            (unless the answer is COLLISION).

    Returns:
        COLLISION at the first configuration found below the plain clearances (early exit),
        else NEAR if some configuration is below the margins, else CLEAR.
    """
    (parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
     kinds, R_WO, p_WO, dims, o_radius, pair_a, pair_b) = arrays
    R, p, sn, cs, Gx, Gy, Gz, cx, cy, cz, keep, near, ok, okp, idx, pc, Rc, ccx, ccy, ccz = ws
    G, K = g_anchor.shape[0], kinds.shape[0]
    _frames_block(QT, n0, m, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs)
    for b in range(m):
        keep[b] = True
    for g in range(G):
        a = g_anchor[g]
        margin, plain = link_margin[g], link_plain[g]
        _centre_block(m, a, g_offset[g], R, p, cx, cy, cz)
        for b in range(m):
            Gx[g, b], Gy[g, b], Gz[g, b] = cx[b], cy[b], cz[b]
        for k in range(K):
            lim = margin + g_radius[g] + o_radius[k]  # bounding sphere vs bounding sphere
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
            _obstacle_free(m, k, kinds, R_WO, p_WO, dims, margin + g_radius[g], cx, cy, cz, near)
            c = 0
            for b in range(m):
                if not near[b]:
                    idx[c] = b
                    c += 1
            if c == 0:
                continue
            _gather(c, idx, a, R, p, Rc, pc)  # the link's spheres, for the lanes near only
            for i in range(c):
                ok[i] = True
                okp[i] = True
            below = False  # some lane below the margin: test the plain clearance too
            for s in range(g_start[g], g_start[g + 1]):
                o = s_offset[s]
                for i in range(c):
                    ccx[i] = pc[0, i] + Rc[0, 0, i] * o[0] + Rc[0, 1, i] * o[1] + Rc[0, 2, i] * o[2]
                    ccy[i] = pc[1, i] + Rc[1, 0, i] * o[0] + Rc[1, 1, i] * o[1] + Rc[1, 2, i] * o[2]
                    ccz[i] = pc[2, i] + Rc[2, 0, i] * o[0] + Rc[2, 1, i] * o[1] + Rc[2, 2, i] * o[2]
                _obstacle_free(c, k, kinds, R_WO, p_WO, dims, margin + s_radius[s], ccx, ccy, ccz, ok)
                if not below:
                    for i in range(c):
                        below |= not ok[i]
                if below:
                    _obstacle_free(c, k, kinds, R_WO, p_WO, dims, plain + s_radius[s], ccx, ccy, ccz, okp)
            for i in range(c):
                if not okp[i]:
                    return COLLISION
                keep[idx[i]] &= ok[i]
    for i in range(pair_a.shape[0]):
        ga, gb = pair_a[i], pair_b[i]
        lim = pair_margin[i] + g_radius[ga] + g_radius[gb]
        c = 0
        for b in range(m):
            dx, dy, dz = Gx[ga, b] - Gx[gb, b], Gy[ga, b] - Gy[gb, b], Gz[ga, b] - Gz[gb, b]
            if dx * dx + dy * dy + dz * dz < lim * lim:
                idx[c] = b
                c += 1
        for j in range(c):  # the lanes whose bounding spheres are near: every sphere pair, once
            b = idx[j]
            value = _pair_min(b, g_anchor[ga], g_anchor[gb], g_start[ga], g_start[ga + 1], g_start[gb],
                              g_start[gb + 1], s_offset, s_radius, R, p)
            if value < pair_plain[i]:
                return COLLISION
            if value < pair_margin[i]:
                keep[b] = False
    answer = CLEAR
    for b in range(m):
        out[n0 + b] = keep[b]
        if not keep[b]:
            answer = NEAR
    return answer
