"""Self-collision of two links on the sphere model: the sphere-pair clearance, pruned.

The clearance of a link pair is the smallest ``|c_s - c_t| - r_s - r_t`` over the spheres
``s`` of one link and ``t`` of the other. Certified covers of meshed links hold many spheres
(the Panda with its hand: 778 at 1 cm, up to 131 per link), so the full product (link 5 against
the hand: 131 x 79 pairs, each with a square root) made the self-collision pairs 98 % of a
planning query's time on MotionBenchMaker problems. :func:`pair_clearance` prunes it with the
links' bounding spheres (each contains its link's spheres, :mod:`drake_mh.scene.batch`):

* a sphere ``s`` of link a whose distance to link b's bounding sphere ``(C_b, R_b)`` is at
  least ``bound`` cannot be in a pair below ``bound``: for every sphere ``t`` of link b,
  ``|c_t - C_b| <= R_b - r_t``, so ``|c_s - c_t| - r_s - r_t >= |c_s - C_b| - r_s - R_b``;
* the same for the spheres of link b against link a's bounding sphere;
* the pairs of the spheres left are compared by squared distance, and a square root is taken
  only for a pair below ``bound``.

Below ``bound`` the answer is the clearance exactly (a pair below ``bound`` has both of its
spheres left, and every other value is at least ``bound``), so a caller that asks "below
``bound``?" or needs the value only below ``bound`` gets what the full product gave; above it,
``bound`` or a lower bound of the clearance.

Pairs that one or two joints move also have floor tables (:mod:`drake_mh.scene.pair_table`):
:func:`pair_floor` reads a configuration's floor, :func:`segment_floor` a straight motion's.
And every link has a bounding capsule, tighter than its sphere for long links:
:func:`capsule_gap` is the pair's lower bound from the two capsules.
"""

from __future__ import annotations

import math

import numba

from drake_mh._support.compilation import stable_calls

FASTMATH = {"nnan", "nsz", "contract"}
"""Fast-math flags of the collision kernels. No ``ninf``: infinite values mean "nothing near"
here, and LLVM may fold ``x < inf`` under it."""


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _lane_point(a, table, i, c, R, p, b):
    """World position of the offset ``table[i, c:c + 3]`` fixed in moving frame ``a`` (-1: the
    world), lane ``b``. The offset is read in place: a view (``table[i]``) costs a reference
    count in and out, about 65 ns a view in these kernels (measured: eleven ``g_offset[g]`` views
    were 0.7 of the 1.5 µs that a planner's state check cost before any configuration)."""
    o0, o1, o2 = table[i, c], table[i, c + 1], table[i, c + 2]
    if a < 0:
        return o0, o1, o2
    return (p[a, 0, b] + R[a, 0, 0, b] * o0 + R[a, 0, 1, b] * o1 + R[a, 0, 2, b] * o2,
            p[a, 1, b] + R[a, 1, 0, b] * o0 + R[a, 1, 1, b] * o1 + R[a, 1, 2, b] * o2,
            p[a, 2, b] + R[a, 2, 0, b] * o0 + R[a, 2, 1, b] * o1 + R[a, 2, 2, b] * o2)


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _near_spheres(b, a, s0, s1, s_offset, s_radius, R, p, cx, cy, cz, reach, bound, lower, buf, n):
    """Append to ``buf[n:]`` (rows ``x, y, z, r``) the spheres ``s0 .. s1-1`` (frame ``a``, lane
    ``b``) closer than ``bound`` to the sphere ``(c, reach)``.

    Returns:
        ``(rows, low)``: the new row count, and (with ``lower``, else ``inf``) the smallest
        distance of a sphere left out from that sphere (a lower bound of its pairs).
    """
    low = math.inf
    for s in range(s0, s1):
        x, y, z = _lane_point(a, s_offset, s, 0, R, p, b)
        lim = bound + s_radius[s] + reach
        dx, dy, dz = x - cx, y - cy, z - cz
        d2 = dx * dx + dy * dy + dz * dz
        if lim > 0.0 and d2 < lim * lim:
            buf[n, 0], buf[n, 1], buf[n, 2], buf[n, 3] = x, y, z, s_radius[s]
            n += 1
        elif lower:
            low = min(low, math.sqrt(d2) - s_radius[s] - reach)
    return n, low


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _near_groups(b, a, u0, u1, u_start, u_offset, u_radius, s_offset, s_radius, R, p, cx, cy, cz, reach, bound, lower,
                 buf, n):
    """:func:`_near_spheres` of the spheres of groups ``u0 .. u1-1`` (frame ``a``), with the
    test in frame ``a``: the sphere's centre is moved into it once, a group whose bounding
    sphere is at least ``bound`` from it is passed whole (its spheres are inside it,
    :func:`drake_mh.scene.batch.sphere_groups`; with ``lower`` its value is the bound of its
    spheres), and only the spheres kept are moved into the world. Link 5 against link 7 of the
    hand Panda (131 x 40 spheres) near a collision: 0.56 µs per call, 0.89 with every sphere
    moved into the world first."""
    if a >= 0:
        dx, dy, dz = cx - p[a, 0, b], cy - p[a, 1, b], cz - p[a, 2, b]
        lx = R[a, 0, 0, b] * dx + R[a, 1, 0, b] * dy + R[a, 2, 0, b] * dz
        ly = R[a, 0, 1, b] * dx + R[a, 1, 1, b] * dy + R[a, 2, 1, b] * dz
        lz = R[a, 0, 2, b] * dx + R[a, 1, 2, b] * dy + R[a, 2, 2, b] * dz
    else:
        lx, ly, lz = cx, cy, cz
    low = math.inf
    for u in range(u0, u1):
        dx, dy, dz = u_offset[u, 0] - lx, u_offset[u, 1] - ly, u_offset[u, 2] - lz
        d2 = dx * dx + dy * dy + dz * dz
        lim = bound + u_radius[u] + reach
        if not (lim > 0.0 and d2 < lim * lim):
            if lower:
                low = min(low, math.sqrt(d2) - u_radius[u] - reach)
            continue
        for s in range(u_start[u], u_start[u + 1]):
            ox, oy, oz = s_offset[s, 0], s_offset[s, 1], s_offset[s, 2]
            dx, dy, dz = ox - lx, oy - ly, oz - lz
            d2 = dx * dx + dy * dy + dz * dz
            lim = bound + s_radius[s] + reach
            if lim > 0.0 and d2 < lim * lim:
                if a >= 0:
                    buf[n, 0] = p[a, 0, b] + R[a, 0, 0, b] * ox + R[a, 0, 1, b] * oy + R[a, 0, 2, b] * oz
                    buf[n, 1] = p[a, 1, b] + R[a, 1, 0, b] * ox + R[a, 1, 1, b] * oy + R[a, 1, 2, b] * oz
                    buf[n, 2] = p[a, 2, b] + R[a, 2, 0, b] * ox + R[a, 2, 1, b] * oy + R[a, 2, 2, b] * oz
                else:
                    buf[n, 0], buf[n, 1], buf[n, 2] = ox, oy, oz
                buf[n, 3] = s_radius[s]
                n += 1
            elif lower:
                low = min(low, math.sqrt(d2) - s_radius[s] - reach)
    return n, low


@stable_calls("lower")
@numba.njit(cache=True, fastmath=FASTMATH)
def pair_clearance(b, ga, gb, bound, stop, lower, g_anchor, g_start, g_radius, g_ustart, u_start, u_offset, u_radius,
                   cax, cay, caz, cbx, cby, cbz, s_offset, s_radius, R, p, buf):
    """The clearance of links ``ga`` and ``gb`` in lane ``b`` on the sphere model, where it is
    below ``bound``.

    Args:
        b: the lane (configuration) of ``R, p``.
        ga, gb: the two links (rows of ``g_anchor``, ``g_start``, ``g_radius``).
        bound: [m] exact values are needed only below it (``inf``: everywhere, no pruning).
        stop: [m] return at once with the first sphere pair below it (``-inf``: never); at most
            ``bound``.
        lower: above ``bound``, return the best lower bound the pruning gives (a square root
            per sphere left out) instead of ``bound``.
        g_anchor, g_start, g_radius: the links' frames, sphere ranges and bounding radii.
        g_ustart, u_start, u_offset, u_radius: the links' sphere groups (ranges of groups per
            link, of spheres per group, and the groups' bounding spheres): with a finite
            ``bound``, spheres are pruned a group at a time (:func:`_near_groups`).
        cax, cay, caz, cbx, cby, cbz: world centres of the two links' bounding spheres, lane ``b``.
        s_offset, s_radius: the spheres' centres in their frames and radii.
        R, p: the moving frames' rotations ``(F, 3, 3, L)`` and positions ``(F, 3, L)``.
        buf: ``(S, 4)`` scratch rows, ``S`` at least the two links' sphere counts together.

    Returns:
        ``v``, the smallest ``|c_s - c_t| - r_s - r_t``, where ``v < bound``; otherwise
        ``bound`` (or with ``lower`` a lower bound of ``v`` at least ``bound``). With ``stop``:
        a value below ``stop`` as soon as one pair is (then ``v`` is below it too).
    """
    grouped = bound < math.inf  # with nothing pruned, the plain loop is faster (7.8 against 11 µs)
    if grouped:
        na, low_a = _near_groups(b, g_anchor[ga], g_ustart[ga], g_ustart[ga + 1], u_start, u_offset, u_radius,
                                 s_offset, s_radius, R, p, cbx, cby, cbz, g_radius[gb], bound, lower, buf, 0)
    else:
        na, low_a = _near_spheres(b, g_anchor[ga], g_start[ga], g_start[ga + 1], s_offset, s_radius, R, p, cbx, cby,
                                  cbz, g_radius[gb], bound, lower, buf, 0)
    if na == 0:
        return low_a if lower else bound
    if grouped:
        n, low_b = _near_groups(b, g_anchor[gb], g_ustart[gb], g_ustart[gb + 1], u_start, u_offset, u_radius,
                                s_offset, s_radius, R, p, cax, cay, caz, g_radius[ga], bound, lower, buf, na)
    else:
        n, low_b = _near_spheres(b, g_anchor[gb], g_start[gb], g_start[gb + 1], s_offset, s_radius, R, p, cax, cay,
                                 caz, g_radius[ga], bound, lower, buf, na)
    # every pair with a sphere left out is at least its lower bound (and that is at least bound)
    best = min(low_a, low_b) if lower else bound
    for i in range(na):
        x, y, z, r = buf[i, 0], buf[i, 1], buf[i, 2], buf[i, 3]
        for j in range(na, n):
            dx, dy, dz = x - buf[j, 0], y - buf[j, 1], z - buf[j, 2]
            d2 = dx * dx + dy * dy + dz * dz
            lim = best + r + buf[j, 3]
            if lim > 0.0 and d2 >= lim * lim:  # the common case: not below the best so far
                continue
            value = math.sqrt(d2) - r - buf[j, 3]  # (lim <= 0: overlapping spheres, not compared squared)
            if value < best:
                best = value
                if best < stop:
                    return best
    return best


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def pair_floor(i, QT, col, t_meta, t_grid, t_vals):
    """A lower bound of pair ``i``'s clearance at configuration ``QT[:, col]`` from its floor
    table (:mod:`drake_mh.scene.pair_table`), or ``-inf`` where it has none (no table, or the
    configuration outside the table's joint limits)."""
    dims = t_meta[i, 0]
    if dims == 0:
        return -math.inf
    n1 = t_meta[i, 3]
    x = (QT[t_meta[i, 1], col] - t_grid[i, 0]) * t_grid[i, 1]
    if not (x >= 0.0 and x <= n1):
        return -math.inf
    cell = min(int(x), n1 - 1)
    if dims == 2:
        n2 = t_meta[i, 4]
        y = (QT[t_meta[i, 2], col] - t_grid[i, 2]) * t_grid[i, 3]
        if not (y >= 0.0 and y <= n2):
            return -math.inf
        cell = cell * n2 + min(int(y), n2 - 1)
    return t_vals[t_meta[i, 5] + cell]


@numba.njit(cache=True, fastmath=FASTMATH)
def segment_floor(i, qa, qb, t_meta, t_grid, t_vals):
    """A lower bound of pair ``i``'s clearance on the whole straight motion ``qa -> qb`` from its
    floor table: the smallest floor of the cells the motion's projection on the table's joints
    passes through (a grid walk, Amanatides and Woo 1987), or ``-inf`` without a table or with
    an end outside the table's joint limits.

    Every point of the motion lies in a visited cell (up to round-off, which the tables' grown
    cells cover: :mod:`drake_mh.scene.pair_table`), so no Lipschitz margin is needed between
    the motion's states for this pair.
    """
    dims = t_meta[i, 0]
    if dims == 0:
        return -math.inf
    j1, j2, n1, n2, offset = t_meta[i, 1], t_meta[i, 2], t_meta[i, 3], t_meta[i, 4], t_meta[i, 5]
    x0 = (qa[j1] - t_grid[i, 0]) * t_grid[i, 1]
    x1 = (qb[j1] - t_grid[i, 0]) * t_grid[i, 1]
    if not (x0 >= 0.0 and x0 <= n1 and x1 >= 0.0 and x1 <= n1):
        return -math.inf
    cx, ex = min(int(x0), n1 - 1), min(int(x1), n1 - 1)
    best = math.inf
    if dims == 1:
        for c in range(min(cx, ex), max(cx, ex) + 1):
            best = min(best, t_vals[offset + c])
        return best
    y0 = (qa[j2] - t_grid[i, 2]) * t_grid[i, 3]
    y1 = (qb[j2] - t_grid[i, 2]) * t_grid[i, 3]
    if not (y0 >= 0.0 and y0 <= n2 and y1 >= 0.0 and y1 <= n2):
        return -math.inf
    cy, ey = min(int(y0), n2 - 1), min(int(y1), n2 - 1)
    dx, dy = x1 - x0, y1 - y0
    sx, sy = (1 if ex > cx else -1), (1 if ey > cy else -1)
    # the motion's parameter where it leaves the current cell along x / along y, and per cell
    tx = ((cx + 1.0 - x0) / dx if sx > 0 else (x0 - cx) / -dx) if dx != 0.0 else math.inf
    ty = ((cy + 1.0 - y0) / dy if sy > 0 else (y0 - cy) / -dy) if dy != 0.0 else math.inf
    ux = abs(1.0 / dx) if dx != 0.0 else math.inf
    uy = abs(1.0 / dy) if dy != 0.0 else math.inf
    for _ in range(abs(ex - cx) + abs(ey - cy) + 1):  # a staircase from the first cell to the last
        best = min(best, t_vals[offset + cx * n2 + cy])
        if cx != ex and (cy == ey or tx < ty):
            cx += sx
            tx += ux
        elif cy != ey:
            cy += sy
            ty += uy
    return best


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def capsule_gap(b, ga, gb, g_anchor, g_capsule, R, p):
    """A lower bound of links ``ga`` and ``gb``'s sphere-pair clearance in lane ``b``: the distance
    of their bounding capsules (``g_capsule[g]``: axis ends in the link's frame, radius; every
    sphere of the link inside, :class:`drake_mh.scene.batch.CollisionModel`), less 1 µm for
    round-off (the closest points of two segments, Ericson, *Real-Time Collision Detection*
    5.1.9; nearly parallel axes put them off by at most about 1e-8 m)."""
    ax0, ay0, az0 = _lane_point(g_anchor[ga], g_capsule, ga, 0, R, p, b)
    ax1, ay1, az1 = _lane_point(g_anchor[ga], g_capsule, ga, 3, R, p, b)
    bx0, by0, bz0 = _lane_point(g_anchor[gb], g_capsule, gb, 0, R, p, b)
    bx1, by1, bz1 = _lane_point(g_anchor[gb], g_capsule, gb, 3, R, p, b)
    ux, uy, uz = ax1 - ax0, ay1 - ay0, az1 - az0
    vx, vy, vz = bx1 - bx0, by1 - by0, bz1 - bz0
    wx, wy, wz = ax0 - bx0, ay0 - by0, az0 - bz0
    a = ux * ux + uy * uy + uz * uz
    e = vx * vx + vy * vy + vz * vz
    f = vx * wx + vy * wy + vz * wz
    eps = 1e-18
    if a <= eps and e <= eps:
        s, t = 0.0, 0.0
    elif a <= eps:
        s, t = 0.0, min(max(f / e, 0.0), 1.0)
    else:
        c = ux * wx + uy * wy + uz * wz
        if e <= eps:
            s, t = min(max(-c / a, 0.0), 1.0), 0.0
        else:
            bb = ux * vx + uy * vy + uz * vz
            denom = a * e - bb * bb
            s = min(max((bb * f - c * e) / denom, 0.0), 1.0) if denom > 0.0 else 0.0
            t = (bb * s + f) / e
            if t < 0.0:
                s, t = min(max(-c / a, 0.0), 1.0), 0.0
            elif t > 1.0:
                s, t = min(max((bb - c) / a, 0.0), 1.0), 1.0
    dx = wx + ux * s - vx * t
    dy = wy + uy * s - vy * t
    dz = wz + uz * s - vz * t
    return math.sqrt(dx * dx + dy * dy + dz * dz) - g_capsule[ga, 6] - g_capsule[gb, 6] - 1e-6
