"""toppra and Drake's ``Toppra`` on a joint spline: the solve behind ``retime(method="toppra")``.

:func:`toppra_like` builds the toppra problem of :func:`~drake_mh.trajectories.retime.retime`
(Pham & Pham, "A new approach to time-optimal path parameterization based on reachability
analysis", IEEE T-RO 2018; the ``toppra`` package): velocity rows at the gridpoints, second-order
rows (acceleration, torque with gravity from the plant-compiled RNEA) at both ends and at interior
check points of every gridpoint interval (:func:`~drake_mh.trajectories.toppra_solve.stage_rows`),
solved by the compiled core's port of toppra's seidel TOPP-RA where it is built, else by the
package (:func:`~drake_mh.trajectories.toppra_solve.solve_sd`), and the time law with constant
``s̈`` between gridpoints (:func:`timing_from_gridpoints`). ``method=
"drake-toppra"`` solves the same spline and gridpoints with Drake's ``Toppra`` (:func:`_drake_toppra`).

Limits come in as arrays (``limits["velocity"]`` etc., ``(nq,)``, ``inf`` for none) already
chosen by :func:`~drake_mh.trajectories.limits_for.enforced_limits`, times the retiming's
``factors`` (head-room and tightening).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PPoly

from drake_mh._support.native import compiled_core
from drake_mh.errors import InfeasibleTrajectory, InvalidArgument
from drake_mh.trajectories.dynamics import batch_dynamics
from drake_mh.trajectories.paths import joint_path
from drake_mh.trajectories.toppra_solve import solve_spline
from drake_mh.trajectories.trajectory import Trajectory

__all__ = ["toppra_like", "timing_from_gridpoints", "gravity_torques"]


def gravity_torques(robot, Q: np.ndarray) -> np.ndarray:
    """``(N, nq)`` torques [N·m] that hold the arm still at the configurations ``Q (N, nq)``."""
    return batch_dynamics(robot).inverse_dynamics(Q, np.zeros_like(Q), np.zeros_like(Q))


def timing_from_gridpoints(ss: np.ndarray, sd: np.ndarray) -> PPoly:
    """Time law ``t -> s`` with constant ``s̈`` between gridpoints (toppra's ``ParametrizeConstAccel``).

    Between ``s_i`` and ``s_{i+1}`` with path speeds ``ṡ_i, ṡ_{i+1}``:
    ``s̈ = (ṡ_{i+1}² - ṡ_i²) / (2 Δs)`` and ``Δt = 2 Δs / (ṡ_i + ṡ_{i+1})``.

    Args:
        ss: ``(N,)`` gridpoints, increasing.
        sd: ``(N,)`` path speeds ``ṡ >= 0`` (toppra's ``sd_vec``).

    Raises:
        InfeasibleTrajectory: two consecutive zero speeds (the motion would never get there).
    """
    sd = np.maximum(np.asarray(sd, dtype=float), 0.0)
    ds = np.diff(ss)
    vsum = sd[:-1] + sd[1:]
    if np.any(vsum <= 0):
        i = int(np.argmax(vsum <= 0))
        raise InfeasibleTrajectory("toppra", f"zero path speed on both ends of gridpoint interval {i} "
                                   f"(s = {ss[i]:.4g}): the limits leave no motion there")
    dt = 2.0 * ds / vsum
    u = (sd[1:] ** 2 - sd[:-1] ** 2) / (2.0 * ds)
    t = np.r_[0.0, np.cumsum(dt)]
    c = np.vstack([0.5 * u, sd[:-1], ss[:-1]])
    return PPoly(c, t)



def propose_gridpoints(spline, max_err_threshold: float = 1e-3, max_iteration: int = 100,
                       max_seg_length: float = 0.05, min_nb_points: int = 100) -> np.ndarray:
    """toppra's ``interpolator.propose_gridpoints`` on a scipy spline, one pass at a time in
    arrays: the same gridpoints (the same midpoints split for the same reasons, in the same
    order), without a Python call per interval.

    Each pass halves every interval longer than ``max_seg_length`` or whose estimated
    interpolation error ``0.5 max_j |p_j''(mid)| h²`` exceeds ``max_err_threshold``; then every
    interval is halved until there are ``min_nb_points``.

    Raises:
        ValueError: as toppra's, when the passes do not settle within ``max_iteration``.
    """
    gp = np.array([spline.x[0], spline.x[-1]], dtype=float)
    iteration = 0
    for iteration in range(max_iteration):
        mid = 0.5 * (gp[:-1] + gp[1:])
        h = gp[1:] - gp[:-1]
        long = h > max_seg_length
        split = long.copy()
        check = np.flatnonzero(~long)
        if len(check):
            err = np.max(np.abs(0.5 * spline(mid[check], nu=2) * h[check, None] ** 2), axis=1)
            split[check] = err > max_err_threshold
        if not np.any(split):
            break
        gp = np.sort(np.r_[gp, mid[split]])
    while len(gp) < min_nb_points:
        gp = np.sort(np.r_[gp, 0.5 * (gp[:-1] + gp[1:])])
    if iteration == max_iteration - 1:
        raise ValueError("Unable to find a good gridpoint for this path.")
    return gp


def _gridpoints(spline, knots: np.ndarray, gridpoints: int | None) -> np.ndarray:
    s_end = float(spline.x[-1])
    core = compiled_core()
    if gridpoints is None and core is not None:  # the same passes, knots and ends in one call
        return core.spline_gridpoints(np.ascontiguousarray(spline.c, dtype=float),
                                      np.ascontiguousarray(spline.x, dtype=float), 1e-3, 100, 0.05, 100)
    if gridpoints is None:
        gp = propose_gridpoints(spline, max_err_threshold=1e-3, min_nb_points=100)
    else:
        if int(gridpoints) < 2:
            raise InvalidArgument(f"gridpoints must be >= 2, got {gridpoints}")
        gp = np.linspace(0.0, s_end, int(gridpoints))
    gp = np.unique(np.r_[gp, spline.x])
    gp = gp[np.r_[True, np.diff(gp) > 1e-9 * s_end]]
    gp[0], gp[-1] = 0.0, s_end
    return gp


def _diagnose(robot, method, spline, gp, factors, effort) -> InfeasibleTrajectory:
    """Turn a failed solve into an exception that says why (gravity or limits)."""
    if "torque" in factors:
        g = gravity_torques(robot, spline(gp))
        ratio = np.abs(g) / (effort * factors["torque"])
        if np.max(ratio) > 1.0:
            i, j = np.unravel_index(np.argmax(ratio), ratio.shape)
            return InfeasibleTrajectory(
                method, f"holding the arm against gravity at s = {gp[i]:.4g} needs "
                f"{abs(g[i, j]):.4g} N·m on joint {robot.joint_names[j]!r}, above its effort limit "
                f"{effort[j] * factors['torque']:.4g} N·m (after scaling): no speed helps; change the path or "
                "the payload")
    return InfeasibleTrajectory(method, "no feasible path parameterization (empty controllable set); "
                                "check the limits and the path")


def toppra_like(W, robot, limits: dict, method: str, factors: dict, gridpoints, bc_type, check_points,
                backend: str = "auto") -> Trajectory:
    """One toppra (or Drake ``Toppra``) solve through the waypoints ``W (K, nq)``.

    Args:
        W: checked waypoints.
        robot: dynamics and position limits.
        limits: ``{"velocity", "acceleration", "torque"}`` -> ``(nq,)`` limits (``inf``: none).
        method: ``"toppra"`` or ``"drake-toppra"``.
        factors: quantity -> fraction of its limit; only these quantities are enforced.
        gridpoints, bc_type, check_points: as for :func:`~drake_mh.trajectories.retime.retime`.
        backend: which solves ``"toppra"``'s rows (:data:`~drake_mh.trajectories.toppra_solve.BACKENDS`:
            ``"auto"`` the compiled core where built, else the ``toppra`` package); the trajectory's
            ``info["solver"]`` says which did.

    Raises:
        InfeasibleTrajectory: no parameterization (the message says whether gravity is why).
    """
    spline, s_way = joint_path(W, robot, method, bc_type=bc_type)
    gp = _gridpoints(spline, s_way, gridpoints)
    vmax = limits["velocity"] * factors.get("velocity", np.inf)
    amax = limits["acceleration"] * factors.get("acceleration", np.inf)
    tmax = limits["torque"] * factors.get("torque", np.inf)
    info = {"gridpoints": len(gp), "path_knots": len(spline.x)}
    if method == "toppra":
        sd, info["solver"] = solve_spline(robot, spline, gp, vmax, amax, tmax,
                                          np.linspace(0.0, 1.0, int(check_points) + 2),
                                          velocity_bound="velocity" in factors, backend=backend)
        if sd is None:
            raise _diagnose(robot, method, spline, gp, factors, limits["torque"])
        timing = timing_from_gridpoints(gp, sd)
    else:
        timing = _drake_toppra(robot, spline, gp, factors, vmax, amax, tmax, limits["torque"])
    return Trajectory(spline, timing, tuple(robot.joint_names), method, info)


_DRAKE_BIG = 1e9
"""stand-in for an undeclared (infinite) limit in Drake's ``Toppra`` (its LPs take finite bounds)."""


def _drake_toppra(robot, spline, gp, factors, vmax, amax, tmax, effort) -> PPoly:
    from pydrake.multibody.optimization import Toppra
    from pydrake.trajectories import PiecewisePolynomial

    knots = spline.x
    drake_path = PiecewisePolynomial.CubicHermite(knots, spline(knots).T, spline(knots, nu=1).T)
    solver = Toppra(drake_path, robot.plant, gp)
    vmax, amax, tmax = (np.minimum(x, _DRAKE_BIG) for x in (vmax, amax, tmax))
    if "velocity" in factors:
        solver.AddJointVelocityLimit(-vmax, vmax)
    if "acceleration" in factors:
        solver.AddJointAccelerationLimit(-amax, amax)
    if "torque" in factors:
        solver.AddJointTorqueLimit(-tmax, tmax)
    s_traj = solver.SolvePathParameterization()
    if s_traj is None:
        raise _diagnose(robot, "drake-toppra", spline, gp, factors, effort)
    return _ppoly_from_drake(s_traj)


def _ppoly_from_drake(traj) -> PPoly:
    """Exact ``PPoly`` of a scalar Drake ``PiecewisePolynomial`` (Taylor coefficients per segment)."""
    n = traj.get_number_of_segments()
    breaks = np.asarray(traj.get_segment_times(), dtype=float)
    deg = max(traj.getSegmentPolynomialDegree(i) for i in range(n))
    c = np.zeros((deg + 1, n))
    from math import factorial

    derivs = [traj] + [traj.MakeDerivative(k) for k in range(1, deg + 1)]
    for i in range(n):
        t0 = breaks[i]
        for k in range(deg + 1):
            c[deg - k, i] = float(np.asarray(derivs[k].value(t0)).ravel()[0]) / factorial(k)
    return PPoly(c, breaks)
