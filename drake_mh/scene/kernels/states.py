"""Early-exit state check at two clearances: the batched check that motion planners call.

:func:`check_states` answers, for a block of configurations, one of

* ``COLLISION`` — some sphere of the model is below its *plain* clearance in some lane; it
  returns at the first one found (VAMP's early exit: Thomason, Kingston, Kavraki, "Motions in
  Microseconds via Vectorized Sampling-Based Planning", ICRA 2024);
* ``NEAR`` — no collision, but some configuration is below a *margin* clearance (``out[n]``
  tells which configurations kept every margin, ``tau[n]`` how far each certifies the motion
  around it from the clearance values of the rows below their margins);
* ``CLEAR`` — every sphere of every configuration keeps its link's margin from every obstacle
  and every checked link pair keeps its pair's margin.

It differs from :func:`drake_mh.scene.kernels.collision.collision_free` (one boolean per
configuration at one clearance, a block stopping only when *all* of its configurations
collide) in both respects. The margins are per constraint row (a link against the obstacles,
a checked link pair), so a caller can ask each row for the extra clearance that certifies the
motion between the configurations: ``rrt_connect`` asks ``Λ_c / 2n`` (the Lipschitz bound of
:mod:`drake_mh.scene.segments`), and a ``CLEAR`` answer certifies a whole motion in one pass.

The geometry is :mod:`.collision`' (same sphere model, bounding spheres, closed-form
obstacle tests, squared distances, so the same conservative guarantee): forward kinematics of
the block with the lane index innermost (SIMD), each link's bounding sphere against each
obstacle's bounding sphere and then its shape over all lanes, and the link's spheres only for
the lanes still near: a group of spheres at a time over all lanes where four or more are near
(:func:`_groups_lanes`), else lane by lane; then sphere by sphere (first collision returns).

The workspace remembers the last collision: each link is tested first against the obstacle it
last collided with, and the links in the order of their last collisions (move to front). A
planner's rejected motions (three of four) then mostly end at the first test. The order
changes the cost, never the answer.

Typical use (compiled code; the workspace is allocated once per plan)::

    arrays = unpack(ints, floats)                  # a scene's packed arrays
    ws = state_workspace(F, G, S, P, lanes)
    ctx = CheckContext(arrays, ws, None)                     # one pointer (drake_mh.scene.kernels.context)
    answer = check_states(QT, n0, m, link_margin, pair_margin, link_plain, pair_plain, inv_lam, speeds, ctx,
                          out, tau)
"""

from __future__ import annotations

import math

import numba
import numpy as np

from drake_mh._support.compilation import stable_calls
from drake_mh.kinematics.kernels import frames_block
from drake_mh.scene.kernels.collision import _centre_block, _obstacle_free, point_distance, _point_free
from drake_mh.scene.kernels.pairs import FASTMATH, _lane_point, capsule_gap, pair_clearance, pair_floor

CLEAR, NEAR, COLLISION = 0, 1, 2
"""Answers of :func:`check_states`."""


@numba.njit(cache=True)
def state_workspace(F, G, S, P, lanes):
    """Arrays :func:`check_states` writes into, for ``F`` moving frames, ``G`` links, ``S``
    spheres, ``P`` checked link pairs and at most ``lanes`` configurations per call (allocate
    once per scene, reuse for every call: it remembers where the last collision was). Element
    22, ``rows_near (G + P,)`` bool, is set for each constraint row (link, then pair) found below
    its margin in some configuration; the caller clears it."""
    L = lanes
    hit = np.zeros(8 * ((L + 7) // 8), np.uint8)
    return (np.empty((F, 3, 3, L)), np.empty((F, 3, L)), np.empty(L), np.empty(L), np.empty((G, L)),
            np.empty((G, L)), np.empty((G, L)), np.empty(L), np.empty(L), np.empty(L), np.empty(L, np.bool_),
            np.empty(L, np.bool_), np.empty(L, np.int64), hit, hit.view(np.uint64), np.empty((S, 4)),
            np.arange(G), np.zeros(G, np.int64), np.empty(L), np.empty(L), np.empty(L), np.empty(L, np.bool_),
            np.zeros(G + P, np.bool_), np.empty(L), np.empty(L))


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _spheres_state(b, a, s0, s1, s_offset, s_radius, margin, plain, R, p, k, kinds, R_WO, p_WO, dims):
    """Spheres ``s0 .. s1-1`` (fixed in frame ``a``) of lane ``b`` against obstacle k:
    ``(answer, value)``, the answer CLEAR (all at least ``margin``), NEAR (some below ``margin``,
    none below ``plain``) or COLLISION (one below ``plain``: returned at once), the value the
    smallest clearance [m] of the spheres below ``margin`` (``inf`` if none)."""
    answer, low = CLEAR, math.inf
    for s in range(s0, s1):
        x, y, z = _lane_point(a, s_offset, s, 0, R, p, b)
        if not _point_free(k, kinds, R_WO, p_WO, dims, margin + s_radius[s], x, y, z):
            if not _point_free(k, kinds, R_WO, p_WO, dims, plain + s_radius[s], x, y, z):
                return COLLISION, low
            answer = NEAR
            low = min(low, point_distance(k, kinds, R_WO, p_WO, dims, x, y, z) - s_radius[s])
    return answer, low


@numba.njit(cache=True, fastmath=FASTMATH)  # not inlined: a second copy in check_states slowed its loop
def _groups_state(b, a, u0, u1, margin, plain, k, ctx):
    """:func:`_spheres_state` of the spheres of groups ``u0 .. u1-1``, a group whose bounding
    sphere keeps the margin passed whole (:func:`drake_mh.scene.batch.sphere_groups`):
    ``(answer, value)``. The arrays come from ``ctx`` (:func:`check_states`'), not as arguments:
    passing them cost more than reading them."""
    s_offset, s_radius, kinds, R_WO, p_WO, dims = ctx.arrays[10:16]  # (the names of check_states' unpacking)
    u_start, u_offset, u_radius = ctx.arrays[25:28]
    R, p = ctx.ws[0:2]
    answer, low = CLEAR, math.inf
    for u in range(u0, u1):
        x, y, z = _lane_point(a, u_offset, u, 0, R, p, b)
        if _point_free(k, kinds, R_WO, p_WO, dims, margin + u_radius[u], x, y, z):
            continue
        state, value = _spheres_state(b, a, u_start[u], u_start[u + 1], s_offset, s_radius, margin, plain, R, p, k,
                                      kinds, R_WO, p_WO, dims)
        if state == COLLISION:
            return COLLISION, value
        if state == NEAR:
            answer, low = NEAR, min(low, value)
    return answer, low


@numba.njit(cache=True, inline="always")
def _remember(order, k_first, gi, k):
    """A collision of link ``order[gi]`` with obstacle ``k``: that link is tested first from now
    on (move to front), and first against ``k``."""
    g = order[gi]
    k_first[g] = k
    for j in range(gi, 0, -1):
        order[j] = order[j - 1]
    order[0] = g


@numba.njit(cache=True, fastmath=FASTMATH)
def _link_tau(gap, inv_lam, g, b, anchor, speeds, ctx):
    """How far (in the motion's parameter t) link ``g``, ``gap`` [m] above its plain clearance in
    lane ``b``, certifies the motion around that state: the larger of the static bound
    ``gap / Λ_g`` and a local one from where the joint axes are in this state.

    Local bound: a sphere of the link moves at most ``lin = Σ_k |Δq_k| (d_k + r_g)`` per unit of
    t, ``d_k`` the distance of the link's bounding-sphere centre from joint k's axis (the frames
    ``k`` from the link's anchor to the root), ``r_g`` its bounding radius (1 per unit for a
    prismatic joint). ``d_k`` changes only by the joints beyond k, no faster than
    ``Λ_g + W r_g`` (``W = Σ |Δq_k|`` over the revolute joints that move the link), so within
    ``τ`` of this state the clearance falls by at most ``τ (lin + τ W (Λ_g + W r_g))``; ``τ`` is
    where that reaches ``gap``. On the MotionBenchMaker motions that the planner refines, the
    hand's ``lin`` is 0.61-0.67 of ``Λ_g`` (median), and the refinement evaluates 26.3 instead
    of 41.5 configurations per motion. ``speeds`` all zero (unknown): the static bound."""
    static = gap * inv_lam
    if inv_lam <= 0.0 or gap <= 0.0:
        return static
    parent, kind, qidx, g_radius = ctx.arrays[0], ctx.arrays[4], ctx.arrays[5], ctx.arrays[8]
    R, p, Gx, Gy, Gz = ctx.ws[0], ctx.ws[1], ctx.ws[4], ctx.ws[5], ctx.ws[6]
    cx, cy, cz = Gx[g, b], Gy[g, b], Gz[g, b]
    r = g_radius[g]
    lin, W = 0.0, 0.0
    k = anchor
    while k >= 0:
        wk = speeds[qidx[k]]
        if wk > 0.0:
            if kind[k] == 0:
                ux, uy, uz = cx - p[k, 0, b], cy - p[k, 1, b], cz - p[k, 2, b]
                ax, ay, az = R[k, 0, 2, b], R[k, 1, 2, b], R[k, 2, 2, b]  # the joint's axis
                X, Y, Z = uy * az - uz * ay, uz * ax - ux * az, ux * ay - uy * ax
                lin += wk * (math.sqrt(X * X + Y * Y + Z * Z) + r)
                W += wk
            else:
                lin += wk
        k = parent[k]
    if lin <= 0.0:
        return static
    quad = W * (1.0 / inv_lam + W * r)
    return max(static, 2.0 * gap / (lin + math.sqrt(lin * lin + 4.0 * quad * gap)))


GROUP_LANES = 4
"""Lanes near an obstacle from which :func:`check_states` tests a link's sphere groups over all
lanes at once (SIMD, :func:`_groups_lanes`) rather than lane by lane."""


@numba.njit(cache=True, fastmath=FASTMATH)
def _groups_lanes(m, a, u0, u1, margin, plain, k, ctx):
    """:func:`_groups_state` of the lanes with ``hit[b]`` set, a group at a time over all ``m``
    lanes (the group's centres and its obstacle test vectorize across lanes); the spheres of a
    group near the obstacle in a hit lane are then tested in that lane. Returns COLLISION at
    the first sphere below ``plain``, else NEAR if it cleared ``keep[b]`` for a lane below
    ``margin`` (and lowered its smallest gap, the workspace's ``gap_l[b]``, see
    :func:`check_states`), else CLEAR."""
    s_offset, s_radius, kinds, R_WO, p_WO, dims = ctx.arrays[10:16]  # (the names of check_states' unpacking)
    u_start, u_offset, u_radius = ctx.arrays[25:28]
    R, p = ctx.ws[0:2]
    keep, hit, gap_l = ctx.ws[10], ctx.ws[13], ctx.ws[24]
    ux, uy, uz, ufree = ctx.ws[18:22]
    answer = CLEAR
    for u in range(u0, u1):
        _centre_block(m, a, u_offset, u, R, p, ux, uy, uz)
        for b in range(m):
            ufree[b] = True
        _obstacle_free(m, k, kinds, R_WO, p_WO, dims, margin + u_radius[u], ux, uy, uz, ufree)
        for b in range(m):
            if hit[b] and not ufree[b]:
                state, value = _spheres_state(b, a, u_start[u], u_start[u + 1], s_offset, s_radius, margin, plain, R,
                                              p, k, kinds, R_WO, p_WO, dims)
                if state == COLLISION:
                    return COLLISION
                if state == NEAR:
                    keep[b] = False
                    gap_l[b] = min(gap_l[b], value - plain)
                    answer = NEAR
    return answer


@stable_calls()
@numba.njit(cache=True, fastmath=FASTMATH)
def check_states(QT, n0, m, link_margin, pair_margin, link_plain, pair_plain, inv_lam, speeds, ctx, out, tau):
    """Check configurations ``QT[:, n0:n0+m]`` at two clearance levels in one pass.

    Args:
        QT: ``(nq, N)`` configurations, one per column.
        n0, m: the first column and how many (``m`` at most the workspace's lanes).
        link_margin, pair_margin: ``(G,)`` / ``(P,)`` clearances [m] each link must keep from
            every obstacle and each checked link pair between its links, with a margin (a row
            at ``-inf`` is not checked: the caller knows it clear on these configurations).
        link_plain, pair_plain: the same without the margin (each at most its margin value;
            all > 0: the tests compare squares, so pass 1e-12 for "touching collides").
        inv_lam: ``(G + P,)`` per row (links, then pairs) ``1 / Λ_c``, for ``tau``.
        speeds: ``(nq,)`` ``|Δq_j|`` of the motion the configurations lie on (per unit of its
            parameter), for the links' local bound on ``tau`` (:func:`_link_tau`); all zero:
            the static bound ``(v_c - plain_c) / Λ_c`` only.
        ctx: :class:`~drake_mh.scene.kernels.context.CheckContext` of the scene's unpacked
            arrays (:func:`drake_mh.scene.kernels.packing.unpack` of
            :func:`~drake_mh.scene.kernels.packing.pack`'s buffers) and a :func:`state_workspace`.
        out: ``(N,)`` bool; ``out[n0 + b]`` is set to whether configuration ``n0 + b`` keeps
            every margin (unless the answer is COLLISION: then ``out`` is not written).
            The workspace's ``rows_near[c]`` is set for each row below its margin (a link or a
            pair at ``-inf`` is not checked at all).
        tau: ``(N,)``; ``tau[n0 + b]`` is set (unless COLLISION) to the smallest bound over
            the rows below their margins in configuration ``n0 + b``, ``inf`` if none: how far
            (in the motion's parameter) the configuration certifies its neighbourhood on those
            rows. A pair's bound is ``(v_c - plain_c) / Λ_c`` (``v_c``: the row's clearance
            value), a link's at least that (:func:`_link_tau`).

    Returns:
        COLLISION at the first sphere found below its plain clearance (early exit), else NEAR
        if some configuration is below a margin, else CLEAR. The answer and ``out`` depend on
        the inputs only (not on the order of the tests, which the workspace's memory of the
        last collision sets), so results are deterministic.
    """
    (parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
     kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
     u_offset, u_radius) = ctx.arrays
    (R, p, sn, cs, Gx, Gy, Gz, cx, cy, cz, keep, near, idx, hit, words, pbuf, order, k_first, ux, uy, uz, ufree,
     rows_near, tau_l, gap_l) = ctx.ws
    G, K = g_anchor.shape[0], kinds.shape[0]
    nw = (m + 7) // 8
    for b in range(m, 8 * nw):  # lanes past m read 0
        hit[b] = 0
    frames_block(QT, n0, m, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs)
    for b in range(m):
        keep[b] = True
        tau_l[b] = math.inf
    for gi in range(G):
        g = order[gi]
        k0 = k_first[g] if k_first[g] < K else 0
        a = g_anchor[g]
        margin, plain = link_margin[g], link_plain[g]
        _centre_block(m, a, g_offset, g, R, p, cx, cy, cz)
        for b in range(m):
            Gx[g, b], Gy[g, b], Gz[g, b] = cx[b], cy[b], cz[b]
            gap_l[b] = math.inf
        near_link = False
        for ki in range(K):
            k = k0 if ki == 0 else (ki - 1 if ki <= k0 else ki)
            if o_gap[g, k] >= margin:  # no configuration brings them near (plain <= margin)
                continue
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
            for b in range(m):  # the lanes still near, as bytes read 8 at a time (few are set)
                hit[b] = not near[b]
                c += hit[b]
            if c >= GROUP_LANES and g_ustart[g + 1] - g_ustart[g] > 1:  # many: each group over all lanes at once
                state = _groups_lanes(m, a, g_ustart[g], g_ustart[g + 1], margin, plain, k, ctx)
                if state == COLLISION:
                    _remember(order, k_first, gi, k)
                    return COLLISION
                if state == NEAR:
                    rows_near[g] = True
                    near_link = True
                continue
            for w in range(nw):
                if words[w] == 0:
                    continue
                for b in range(8 * w, 8 * w + 8):
                    if hit[b]:  # the link's spheres
                        if g_ustart[g + 1] - g_ustart[g] > 1:  # the link's spheres a group at a time
                            state, value = _groups_state(b, a, g_ustart[g], g_ustart[g + 1], margin, plain, k, ctx)
                        else:  # one group: the link's bounding sphere, known to be near
                            state, value = _spheres_state(b, a, g_start[g], g_start[g + 1], s_offset, s_radius,
                                                          margin, plain, R, p, k, kinds, R_WO, p_WO, dims)
                        if state == COLLISION:
                            _remember(order, k_first, gi, k)
                            return COLLISION
                        if state == NEAR:
                            keep[b] = False
                            rows_near[g] = True
                            gap_l[b] = min(gap_l[b], value - plain)
                            near_link = True
        if near_link:  # each near lane's tau from its smallest gap to the link's plain clearance (tau grows with it)
            for b in range(m):
                if gap_l[b] < math.inf:
                    tau_l[b] = min(tau_l[b], _link_tau(gap_l[b], inv_lam[g], g, b, a, speeds, ctx))
    for i in range(pair_a.shape[0]):
        if pair_margin[i] == -math.inf:
            continue  # the caller has certified the pair on these configurations (rrt_connect: its floor table)
        ga, gb = pair_a[i], pair_b[i]
        lim = pair_margin[i] + g_radius[ga] + g_radius[gb]
        lim *= lim
        close = False
        for b in range(m):  # any lane whose bounding spheres are near (vectorizes; most pairs are far in every lane)
            dx, dy, dz = Gx[ga, b] - Gx[gb, b], Gy[ga, b] - Gy[gb, b], Gz[ga, b] - Gz[gb, b]
            close |= dx * dx + dy * dy + dz * dz < lim
        if not close:
            continue
        c = 0
        for b in range(m):  # those lanes (a compaction: scalar)
            dx, dy, dz = Gx[ga, b] - Gx[gb, b], Gy[ga, b] - Gy[gb, b], Gz[ga, b] - Gz[gb, b]
            if dx * dx + dy * dy + dz * dz < lim:
                idx[c] = b
                c += 1
        for j in range(c):  # the lanes whose bounding spheres are near: their sphere pairs, once
            b = idx[j]
            if pair_floor(i, QT, n0 + b, t_meta, t_grid, t_vals) >= pair_margin[i]:
                continue  # the pair's table shows it keeping its margin (drake_mh.scene.pair_table)
            if capsule_gap(b, ga, gb, g_anchor, g_capsule, R, p) >= pair_margin[i]:
                continue  # so do the links' bounding capsules
            value = pair_clearance(b, ga, gb, pair_margin[i], pair_plain[i], False, g_anchor, g_start, g_radius,
                                   g_ustart, u_start, u_offset, u_radius, Gx[ga, b], Gy[ga, b], Gz[ga, b],
                                   Gx[gb, b], Gy[gb, b], Gz[gb, b], s_offset, s_radius, R, p, pbuf)
            if value < pair_plain[i]:
                return COLLISION
            if value < pair_margin[i]:
                keep[b] = False
                rows_near[G + i] = True
                tau_l[b] = min(tau_l[b], (value - pair_plain[i]) * inv_lam[G + i])
    answer = CLEAR
    for b in range(m):
        out[n0 + b] = keep[b]
        tau[n0 + b] = tau_l[b]
        if not keep[b]:
            answer = NEAR
    return answer


@stable_calls()
@numba.njit(cache=True)
def check_blocks(QT, n, lanes, margins, plain, inv_lam, speeds, ctx, out, tau):
    """Columns ``0 .. n-1`` of ``QT`` in blocks (:func:`check_states`): the first of ``lanes[0]``
    columns (VAMP's "rake": states spread over a motion, so a collision is found early), the
    others of ``lanes[1]``.

    ``margins``, ``plain``: ``(link clearances (G,), pair clearances (P,))``; ``inv_lam``,
    ``speeds``, ``ctx``, ``tau``: as :func:`check_states`'.

    Returns:
        ``(answer, configurations checked)``: COLLISION (stops there), NEAR (``out[w]``: column
        ``w`` kept the margins; ``tau[w]``), or CLEAR.
    """
    answer = CLEAR
    n0 = 0
    while n0 < n:
        m = min(lanes[0] if n0 == 0 else lanes[1], n - n0)
        r = check_states(QT, n0, m, margins[0], margins[1], plain[0], plain[1], inv_lam, speeds, ctx, out, tau)
        if r == COLLISION:
            return COLLISION, n0 + m
        if r == NEAR:
            answer = NEAR
        n0 += m
    return answer, n
