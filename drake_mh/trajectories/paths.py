"""Geometric joint paths ``q(s)`` through waypoints, for time parameterization.

A joint path is a ``C²`` cubic spline (``scipy.interpolate.CubicSpline``) through the
waypoints, parameterized by the cumulative joint-space chord length ``s`` [rad] (the usual
choice: ``|q'(s)| ≈ 1``, so toppra's gridpoints are spread evenly over the motion).

A cubic spline can overshoot between waypoints and leave the joint limits even when every
waypoint is inside. :func:`joint_path` finds the extrema of every cubic piece exactly (roots of
its derivative) and, where a piece leaves ``[lower, upper]``, inserts points of the straight
segment between its two waypoints and refits (the spline then hugs the polyline there) — up to
``max_refinements`` times; then it raises :class:`~drake_mh.errors.InfeasibleTrajectory`.
"""

from __future__ import annotations

import copy
import weakref

import numpy as np
from scipy.interpolate import CubicSpline, PPoly
from scipy.linalg.lapack import dgtsv

from drake_mh._support.native import compiled_core
from drake_mh.errors import InfeasibleTrajectory, InvalidArgument

__all__ = ["joint_path", "piece_extrema", "check_waypoints"]


def check_waypoints(waypoints, robot, method: str) -> np.ndarray:
    """Validate ``waypoints (K, nq)``: numeric, finite, ``K >= 2``, inside the position limits.

    Consecutive duplicates are dropped (they would make zero-length spline pieces).

    Raises:
        InvalidArgument: wrong shape or non-finite values.
        InfeasibleTrajectory: a waypoint outside the position limits, or a path of zero length.
    """
    try:
        W = np.array(waypoints, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"waypoints must be a numeric (K, {robot.nq}) array") from exc
    if W.ndim != 2 or W.shape[1] != robot.nq or W.shape[0] < 2:
        raise InvalidArgument(
            f"waypoints must have shape (K >= 2, {robot.nq}) for {robot.name} (joints "
            f"{robot.joint_names}), got {W.shape}")
    if not np.all(np.isfinite(W)):
        raise InvalidArgument("waypoints contain NaN or inf")
    outside = ((W < robot.lower) | (W > robot.upper)) & ~robot.continuous
    if np.any(outside):
        k, j = np.argwhere(outside)[0]
        raise InfeasibleTrajectory(
            method, f"waypoint {k} has joint {robot.joint_names[j]!r} = {W[k, j]:.6g} outside "
            f"[{robot.lower[j]:.6g}, {robot.upper[j]:.6g}]; move it inside the position limits")
    keep = np.r_[True, np.any(np.abs(np.diff(W, axis=0)) > 1e-12, axis=1)]
    W = W[keep]
    if len(W) < 2:
        raise InfeasibleTrajectory(method, "all waypoints are equal: there is no motion to time")
    return W


def piece_extrema(spline: PPoly) -> tuple[np.ndarray, np.ndarray]:
    """Exact minimum and maximum ``(m, nq)`` of every piece of a cubic vector spline."""
    x, c = spline.x, spline.c  # c: (4, m, nq), highest power first
    h = np.diff(x)[:, None]
    a3, a2, a1 = 3 * c[0], 2 * c[1], c[2]  # derivative 3c0 y² + 2c1 y + c2
    vals = [c[3], ((c[0] * h + c[1]) * h + c[2]) * h + c[3]]  # each piece's own polynomial at its ends
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = a2 ** 2 - 4 * a3 * a1
        sq = np.sqrt(np.maximum(disc, 0.0))
        cands = [(-a2 + sq) / (2 * a3), (-a2 - sq) / (2 * a3), -a1 / a2]
    for y in cands:
        ok = np.isfinite(y) & (y > 0) & (y < h) & (disc >= 0)
        y = np.where(ok, y, 0.0)
        v = ((c[0] * y + c[1]) * y + c[2]) * y + c[3]
        vals.append(np.where(ok, v, vals[0]))
    V = np.stack(vals)
    return V.min(axis=0), V.max(axis=0)


def not_a_knot(s: np.ndarray, P: np.ndarray) -> CubicSpline:
    """``scipy.interpolate.CubicSpline(s, P)`` (not-a-knot ends) for strictly increasing ``s (K,)``
    and finite ``P (K, nq)``, ``K >= 2``, without its input checks: scipy's equations for the
    slopes at the knots (two points: the line; three: the parabola; more: its tridiagonal system,
    solved by LAPACK's ``dgtsv``), the same coefficients to round-off."""
    n, dx = len(s), np.diff(s)
    dxr = dx[:, None]
    slope = np.diff(P, axis=0) / dxr
    if n == 2:
        D = np.vstack([slope[0], slope[0]])
    elif n == 3:
        A = np.array([[1.0, 1.0, 0.0], [dx[1], 2.0 * (dx[0] + dx[1]), dx[0]], [0.0, 1.0, 1.0]])
        D = np.linalg.solve(A, np.vstack([2.0 * slope[0], 3.0 * (dx[0] * slope[1] + dx[1] * slope[0]),
                                          2.0 * slope[1]]))
    else:
        d0, d1 = s[2] - s[0], s[-1] - s[-3]
        diagonal = np.r_[dx[1], 2.0 * (dx[:-1] + dx[1:]), dx[-2]]
        upper, lower = np.r_[d0, dx[:-1]], np.r_[dx[1:], d1]
        b = np.empty_like(P)
        b[1:-1] = 3.0 * (dxr[1:] * slope[:-1] + dxr[:-1] * slope[1:])
        b[0] = ((dx[0] + 2.0 * d0) * dx[1] * slope[0] + dx[0] ** 2 * slope[1]) / d0
        b[-1] = (dx[-1] ** 2 * slope[-2] + (2.0 * d1 + dx[-1]) * dx[-2] * slope[-1]) / d1
        *_, D, info = dgtsv(lower, diagonal, upper, b, overwrite_b=True)
        if info != 0:  # a singular system (never for increasing s): scipy's own solve says why
            return CubicSpline(s, P)
    t = (D[:-1] + D[1:] - 2.0 * slope) / dxr
    return CubicSpline.construct_fast(np.stack([t / dxr, (slope - D[:-1]) / dxr - t, D[:-1], P[:-1]]), s)


def _cubic(s: np.ndarray, P: np.ndarray, bc_type: str) -> tuple[CubicSpline, np.ndarray, np.ndarray]:
    """``(spline, lo, hi)``: the cubic spline through ``P (K, nq)`` at the knots ``s (K,)`` and its
    :func:`piece_extrema`; the not-a-knot spline from the compiled core's ``cubic_path`` where it is
    built (:func:`not_a_knot`'s equations and solve, in one call), else from :func:`not_a_knot`."""
    core = compiled_core() if bc_type == "not-a-knot" else None
    fitted = None if core is None else core.cubic_path(s, P)
    if fitted is not None:
        c, lo, hi = fitted
        return CubicSpline.construct_fast(c, s), lo, hi
    spline = not_a_knot(s, P) if bc_type == "not-a-knot" else CubicSpline(s, P, bc_type=bc_type)
    return (spline, *piece_extrema(spline))


_LAST: dict = {}
"""The last :func:`joint_path` answer, by robot, waypoints and options: verification fits the
spline to certify it, then the retiming fits the same one."""


def joint_path(W: np.ndarray, robot, method: str = "retime", bc_type: str = "not-a-knot",
               max_refinements: int = 8) -> tuple[CubicSpline, np.ndarray]:
    """Cubic spline ``s -> q`` through the waypoints, inside the position limits.

    Args:
        W: ``(K, nq)`` checked waypoints (see :func:`check_waypoints`).
        robot: gives the position limits.
        method: name used in error messages.
        bc_type: scipy ``CubicSpline`` end conditions (``"not-a-knot"``, toppra's default;
            ``"natural"``; ``"clamped"``).
        max_refinements: rounds of straight-segment insertion before giving up.

    Returns:
        ``(spline, s_waypoints)``: the spline (its arrays read-only: the last answer is reused
        for the same robot, waypoints and options) and the parameter ``s`` [rad] of each
        original waypoint (breakpoints include inserted points).

    Raises:
        InfeasibleTrajectory: the spline still leaves the limits after the refinements.
    """
    P = np.array(W, dtype=float)
    key = (id(robot), P.shape, P.tobytes(), bc_type, max_refinements, np.asarray(robot.lower).tobytes(),
           np.asarray(robot.upper).tobytes(), np.asarray(robot.continuous).tobytes())
    last = _LAST.get("answer")
    if last is not None and last[0] == key and last[1]() is robot:
        return copy.copy(last[2]), last[3].copy()
    spline, s_way = _fit(P, robot, method, bc_type, max_refinements)
    for array in (spline.c, spline.x):  # shared by the callers that fit the same spline
        array.flags.writeable = False
    _LAST["answer"] = (key, weakref.ref(robot), spline, s_way)
    return copy.copy(spline), s_way.copy()


def _fit(P: np.ndarray, robot, method: str, bc_type: str, max_refinements: int) -> tuple[CubicSpline, np.ndarray]:
    """:func:`joint_path`'s fit (its docstring), not cached."""
    orig = np.ones(len(P), dtype=bool)  # which rows of P are the caller's waypoints
    lower = np.where(robot.continuous, -np.inf, robot.lower)
    upper = np.where(robot.continuous, np.inf, robot.upper)
    for _ in range(max_refinements + 1):
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
        spline, lo, hi = _cubic(s, P, bc_type)
        bad = np.any((lo < lower - 1e-12) | (hi > upper + 1e-12), axis=1)  # (pieces,)
        if not np.any(bad):
            return spline, s[orig]
        # insert the midpoint of the straight segment in every bad piece and its neighbours
        bad = bad | np.r_[bad[1:], False] | np.r_[False, bad[:-1]]
        newP, newO = [P[0]], [orig[0]]
        for i in range(len(P) - 1):
            if bad[i]:
                newP.append(0.5 * (P[i] + P[i + 1]))
                newO.append(False)
            newP.append(P[i + 1])
            newO.append(orig[i + 1])
        P, orig = np.array(newP), np.array(newO)
    i = int(np.argmax(bad))
    j = int(np.argmax((lo[i] < lower) | (hi[i] > upper)))
    raise InfeasibleTrajectory(
        method, f"the cubic spline through the waypoints leaves joint {robot.joint_names[j]!r}'s "
        f"position limits between s = {spline.x[i]:.4g} and {spline.x[i + 1]:.4g} even after "
        f"{max_refinements} refinements; add waypoints or move them away from the limits")
