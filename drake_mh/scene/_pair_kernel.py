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
"""

from __future__ import annotations

import math

import numba

FASTMATH = {"nnan", "nsz", "contract"}
"""Fast-math flags of the collision kernels. No ``ninf``: infinite values mean "nothing near"
here, and LLVM may fold ``x < inf`` under it."""


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _lane_point(a, o, R, p, b):
    """World position of offset ``o`` fixed in moving frame ``a`` (-1: the world), lane ``b``."""
    if a < 0:
        return o[0], o[1], o[2]
    return (p[a, 0, b] + R[a, 0, 0, b] * o[0] + R[a, 0, 1, b] * o[1] + R[a, 0, 2, b] * o[2],
            p[a, 1, b] + R[a, 1, 0, b] * o[0] + R[a, 1, 1, b] * o[1] + R[a, 1, 2, b] * o[2],
            p[a, 2, b] + R[a, 2, 0, b] * o[0] + R[a, 2, 1, b] * o[1] + R[a, 2, 2, b] * o[2])


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
        x, y, z = _lane_point(a, s_offset[s], R, p, b)
        lim = bound + s_radius[s] + reach
        dx, dy, dz = x - cx, y - cy, z - cz
        d2 = dx * dx + dy * dy + dz * dz
        if lim > 0.0 and d2 < lim * lim:
            buf[n, 0], buf[n, 1], buf[n, 2], buf[n, 3] = x, y, z, s_radius[s]
            n += 1
        elif lower:
            low = min(low, math.sqrt(d2) - s_radius[s] - reach)
    return n, low


@numba.njit(cache=True, fastmath=FASTMATH)
def pair_clearance(b, ga, gb, bound, stop, lower, g_anchor, g_start, g_radius, cax, cay, caz, cbx, cby, cbz,
                   s_offset, s_radius, R, p, buf):
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
        cax, cay, caz, cbx, cby, cbz: world centres of the two links' bounding spheres, lane ``b``.
        s_offset, s_radius: the spheres' centres in their frames and radii.
        R, p: the moving frames' rotations ``(F, 3, 3, L)`` and positions ``(F, 3, L)``.
        buf: ``(S, 4)`` scratch rows, ``S`` at least the two links' sphere counts together.

    Returns:
        ``v``, the smallest ``|c_s - c_t| - r_s - r_t``, where ``v < bound``; otherwise
        ``bound`` (or with ``lower`` a lower bound of ``v`` at least ``bound``). With ``stop``:
        a value below ``stop`` as soon as one pair is (then ``v`` is below it too).
    """
    na, low_a = _near_spheres(b, g_anchor[ga], g_start[ga], g_start[ga + 1], s_offset, s_radius, R, p, cbx, cby,
                              cbz, g_radius[gb], bound, lower, buf, 0)
    if na == 0:
        return low_a if lower else bound
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
