"""Time parameterization under joint limits: toppra, ruckig, Drake ``Toppra``.

``retime(waypoints, robot, method=...)`` turns a joint path into a :class:`Trajectory` that is
**certified** (:func:`~drake_mh.trajectories.certify.certify`, dense sampling) to respect the
robot's position limits and the requested limits within ``1 + tol``, or raises.

* ``"toppra"`` (Pham & Pham, "A new approach to time-optimal path parameterization based on
  reachability analysis", IEEE T-RO 2018; the ``toppra`` package): the path is the ``C²``
  cubic spline of :func:`~drake_mh.trajectories.paths.joint_path`; velocity, acceleration and
  torque limits (torque ``a(s) s̈ + b(s) ṡ² + c(s)`` with gravity, coefficients from the
  plant-compiled RNEA of :mod:`~drake_mh.trajectories.dynamics`), toppra's seidel TOPP-RA (ported to
  the compiled core where it is built: the package's answers), toppra's
  interpolation discretization plus the same rows at ``check_points`` interior points of every
  gridpoint interval (:mod:`~drake_mh.trajectories.toppra_time`). The time law is built from toppra's gridpoints and ``ṡ`` with constant ``s̈``
  between gridpoints — the same law as toppra's ``ParametrizeConstAccel``, which does not
  overshoot (``ParametrizeSpline`` does: +2.5 % velocity, +12 % acceleration measured), but
  evaluated here with exact chain-rule derivatives.
* ``"drake-toppra"``: Drake's ``Toppra`` on the same spline and gridpoints (CLP LPs; its torque
  constraint uses the plant), the cross-check baseline.
* ``"ruckig"`` (Berscheid & Kröger, "Jerk-limited real-time trajectory generation with
  arbitrary target states", RSS 2021; community edition): jerk-limited, **exactly on the
  piecewise-linear joint-space path**, **at rest at every waypoint**. The community edition has
  no intermediate waypoints (they call a cloud API), ignores position limits, and its phase
  synchronization falls back to time synchronization when it cannot synchronize (segments then
  left the straight line by up to 0.11 rad); so each segment ``q_a -> q_b`` is a one-dimensional
  ruckig profile of its parameter ``s: 0 -> 1`` with ``v_s = min_j v_j / |Δq_j|`` (the same for
  acceleration and jerk), and ``q(t) = q_a + s(t) (q_b - q_a)`` (:mod:`~drake_mh.trajectories.ruckig_time`): every
  configuration lies on the segment (to rounding), ``s`` is monotone (rest to rest), the
  segment stays in the convex position box, and under the joints' box limits no rest-to-rest
  motion along the segment is faster (ruckig does not plan torque: where the certificate finds
  an excess, the motion is slowed down uniformly, below).

Limits are enforced at the check points by toppra; between them the chain-rule values can
exceed a limit slightly. Every candidate is certified. A velocity, acceleration or torque excess
is repaired by uniform time scalings (:func:`_slow_down`: the torque moves towards gravity's; the
path, and ruckig's rests at the waypoints, stay; jerk only shrinks; where gravity alone exceeds
the limit, :class:`InfeasibleTrajectory` says so); any other violation scales the
offending quantity's limit by ``1 / ratio`` (times ``1 - 1e-3``; for ruckig a torque excess
scales its velocity and acceleration limits) and solves again, at most ``max_attempts`` times,
then :class:`~drake_mh.errors.LimitViolation` is raised.
"""

from __future__ import annotations

import logging
import numbers
import time

import numpy as np

from drake_mh.errors import InfeasibleTrajectory, InvalidArgument, LimitViolation, UnknownMethod
from drake_mh.trajectories.certify import certify
from drake_mh.trajectories.paths import check_waypoints
from drake_mh.trajectories.ruckig_time import _ruckig_path, ruckig_state_to_state
from drake_mh.trajectories.toppra_time import gravity_torques, timing_from_gridpoints, toppra_like
from drake_mh.trajectories.trajectory import Trajectory

__all__ = ["retime", "RETIMERS", "timing_from_gridpoints", "ruckig_state_to_state"]

_log = logging.getLogger(__name__)

#: toppra's first solve uses velocity and acceleration limits 1 % tighter. Between the check
#: points the chain-rule values exceed the limits by up to ~1-2 % at 100 gridpoints. Measured on
#: 12 random Panda paths at 100 gridpoints: without head-room 12/12 solves needed the
#: time-scaling repair and a second certification (9.6 ms per retime, duration 0.985 x Drake's
#: Toppra); with 1 %: 1/12 (6.6 ms, 0.988 x); with 2 %: 0/12 (6.3 ms, 0.998 x).
_FIRST_MARGIN = 0.01

RETIMERS = ("toppra", "drake-toppra", "ruckig")
_SUPPORTED = {"toppra": {"velocity", "acceleration", "torque"},
              "drake-toppra": {"velocity", "acceleration", "torque"},
              "ruckig": {"velocity", "acceleration", "jerk", "torque"}}
_REPORTED = ("position", "velocity", "acceleration", "jerk", "torque")
"""Every quantity is certified (ratios where a limit is enforced, absolute bounds everywhere);
only the enforced ones are checked."""


def retime(path, robot, method: str = "toppra", *, limits=None, velocity_scaling: float | None = None,
           acceleration_scaling: float | None = None, gridpoints: int | None = None,
           scale: float = 1.0, tol: float = 1e-6, max_attempts: int = 4,
           bc_type: str = "not-a-knot", check_points: int = 1) -> Trajectory:
    """Time-parameterize a joint path under the robot's limits; the result is certified.

    What the result guarantees, by method:

    * every method: starts at ``path[0]`` and ends at ``path[-1]`` at rest, passes through
      every waypoint, stays within the position limits and, checked by dense certification
      (:func:`~drake_mh.trajectories.certify.certify`), within ``scale`` × the enforced limits
      up to ``1 + tol``;
    * ``"toppra"`` / ``"drake-toppra"``: the *geometric* path is the ``C²`` cubic spline through
      the waypoints (:func:`~drake_mh.trajectories.paths.joint_path`), not the straight
      segments between them; it does not stop at the waypoints; jerk is not limited;
    * ``"ruckig"``: the motion lies **exactly on the piecewise-linear path** (every
      configuration on the straight segment between two consecutive waypoints, to rounding:
      3e-15 rad measured), moves forward along it, **rests at every waypoint**, and each
      segment is the time-optimal jerk-limited rest-to-rest motion along its line (a 1-D
      profile of the segment parameter, module docstring); torque is certified, not planned.

    Which limits (:func:`~drake_mh.trajectories.limits_for.enforced_limits`): what the robot
    declares (``robot.limits``: the model, a limits file, code); on a robot without acceleration
    limits (a vendor URDF) the toppra methods bound acceleration through the torque limits
    (effort, gravity included), ruckig gets accelerations derived from the effort limits along
    the path; a limit neither declared nor derivable takes a documented default with a warning.
    ``trajectory.info["enforced_limits"]`` lists every enforced value and its source.

    Args:
        path: ``(K, nq)`` joint waypoints [rad], ``K >= 2``, inside the position limits.
        robot: the :class:`~drake_mh.robot.Robot` (limits and dynamics).
        method: ``"toppra"``, ``"drake-toppra"`` or ``"ruckig"``.
        limits: quantities to enforce besides position (always enforced); default velocity and
            torque (where effort is declared) for every method, acceleration where declared (or
            where torque does not bound it) for the toppra methods and on every joint for
            ruckig, jerk for ruckig. toppra trajectories have piecewise-constant ``s̈``: their
            jerk is not limited. ruckig enforces torque by certification only (limits scaled on
            failure).
        velocity_scaling, acceleration_scaling: MoveIt's scaling factors in ``(0, 1]``: the
            fraction of the velocity / acceleration limits to use (``None``: the robot's
            defaults, ``robot.limits.scaling``, 1 unless a limits file sets them).
        gridpoints: toppra gridpoints (spline knots are always added); ``None`` chooses them
            with toppra's ``propose_gridpoints`` (interpolation error <= 1e-3, >= 100 points).
        scale: fraction of every limit to use, in ``(0, 1]`` (a safety margin).
        tol: certification tolerance on the ratios (``1 + tol``).
        max_attempts: solves with tightened limits before giving up.
        bc_type: end conditions of the spline (toppra methods).
        check_points: interior points of every gridpoint interval where toppra's acceleration
            and torque rows are also imposed (``"toppra"`` only; 0 = toppra's interpolation
            discretization).

    Returns:
        A :class:`Trajectory`; ``trajectory.info`` holds ``certificate``, ``enforced_limits``
        (:class:`~drake_mh.robot.limits.JointLimits`), ``limits`` (the enforced quantities),
        ``attempts``, ``solve_time`` [s] (last attempt, without certification), ``certify_time``
        [s] (the certifications and time scalings of every attempt), ``gridpoints``.

    Raises:
        UnknownMethod: ``method`` not in ``RETIMERS``.
        InvalidArgument: bad waypoints, unsupported limit for the method, bad ``scale`` or
            scaling factor.
        MissingLimits: torque asked for on a robot that declares no effort limit.
        InfeasibleTrajectory: no parameterization exists (e.g. gravity alone exceeds an effort
            limit on the path, a waypoint outside the position limits).
        LimitViolation: still violating after ``max_attempts`` tightened solves.
    """
    from drake_mh.trajectories.limits_for import enforced_limits

    if method not in RETIMERS:
        raise UnknownMethod(method, RETIMERS, what="retime method")
    if limits is not None:
        limits = tuple(limits)
        bad = [q for q in limits if q not in _SUPPORTED[method]]
        if bad:
            raise InvalidArgument(f"{method} cannot enforce {bad}; it supports {sorted(_SUPPORTED[method])}"
                                  + ("; use method='ruckig' for jerk limits" if "jerk" in bad else ""))
    _check_options(scale, tol, max_attempts, gridpoints, check_points, bc_type)
    W = check_waypoints(path, robot, method)
    table = enforced_limits(robot, method, W, limits, velocity_scaling, acceleration_scaling)
    limits = tuple("torque" if q == "effort" else q for q in table.enforced)
    arrays = {q: table[q] for q in ("velocity", "acceleration", "jerk", "torque")}
    factors = {q: float(scale) for q in limits}
    if method == "ruckig" and "torque" in limits:
        _check_gravity_on_segments(W, robot, arrays["torque"] * factors["torque"])
    if method != "ruckig":  # head-room for what the check points miss (see _FIRST_MARGIN)
        for q in ("velocity", "acceleration"):
            if q in factors:
                factors[q] *= 1.0 - _FIRST_MARGIN
    quantities = ("position",) + limits
    attempts, certifying = 0, 0.0
    while True:
        attempts += 1
        start = time.perf_counter()
        if method == "ruckig":
            traj = _ruckig_path(W, robot, factors, arrays)
        else:
            traj = toppra_like(W, robot, arrays, method, factors, gridpoints, bc_type, check_points)
        solve_time = time.perf_counter() - start
        cert = certify(traj, robot, quantities=_REPORTED, scale=scale, enforced=quantities, limits=table)
        if not cert.ok(quantities, tol):
            traj, cert = _slow_down(traj, robot, cert, quantities, tol)
        certifying += time.perf_counter() - start - solve_time
        traj.info.update(certificate=cert, attempts=attempts, solve_time=solve_time, limits=limits,
                         factors=dict(factors), enforced_limits=table, certify_time=certifying)
        _log.debug("%s attempt %d: ratios %s", method, attempts,
                   {q: round(cert.max_ratio((q,)), 6) for q in quantities})
        if cert.ok(quantities, tol):
            return traj
        quantity, joint, t, ratio = cert.worst(quantities)
        if quantity == "torque" and method != "ruckig":
            r_g = _gravity_ratios(traj, robot, cert)
            j = list(robot.joint_names).index(joint)
            if r_g[j] > 1.0 + tol:  # holding the arm there needs more than the limit: no speed helps
                raise InfeasibleTrajectory(
                    method, f"holding the arm against gravity at t = {t:.4g} s needs "
                    f"{r_g[j]:.4g} x the effort limit of joint {joint!r} (after scaling), between the "
                    "gridpoints: no speed helps; change the path or the payload")
        if quantity == "position" or attempts >= max_attempts:
            raise LimitViolation(joint, quantity, t, ratio, tol,
                                 hint=f"{method} after {attempts} attempt(s): use more gridpoints, "
                                 "a smaller `scale`, or waypoints further from the limits")
        for q in quantities[1:]:  # tighten every violated quantity by its own ratio
            r = cert.max_ratio((q,))
            if r <= 1.0 + tol:
                continue
            if q == "torque" and method == "ruckig":  # ruckig has no torque limit: slow it down
                factors["velocity"] = factors.get("velocity", 1.0) * (1.0 - 1e-3) / np.sqrt(r)
                factors["acceleration"] = factors.get("acceleration", 1.0) * (1.0 - 1e-3) / r
            else:
                factors[q] *= (1.0 - 1e-3) / r


def _check_options(scale, tol, max_attempts, gridpoints, check_points, bc_type) -> None:
    """Named errors for bad options (instead of a TypeError deep in toppra or scipy)."""
    def real(x):
        return isinstance(x, numbers.Real) and not isinstance(x, bool) and np.isfinite(x)

    def integer(x):
        return isinstance(x, numbers.Integral) and not isinstance(x, bool)

    if not (real(scale) and 0.0 < scale <= 1.0):
        raise InvalidArgument(f"scale must be a number in (0, 1] (fraction of every limit), got {scale!r}")
    if not (real(tol) and tol >= 0.0):
        raise InvalidArgument(f"tol must be a finite number >= 0 (certification slack on the ratios), got {tol!r}")
    if not (integer(max_attempts) and max_attempts >= 1):
        raise InvalidArgument(f"max_attempts must be an integer >= 1, got {max_attempts!r}")
    if gridpoints is not None and not (integer(gridpoints) and gridpoints >= 2):
        raise InvalidArgument(f"gridpoints must be an integer >= 2 or None (toppra proposes them), got {gridpoints!r}")
    if not (integer(check_points) and check_points >= 0):
        raise InvalidArgument(f"check_points must be an integer >= 0, got {check_points!r}")
    if isinstance(bc_type, str) and bc_type not in _BC_TYPES:
        raise InvalidArgument(f"bc_type must be one of {_BC_TYPES} (scipy CubicSpline), got {bc_type!r}")


#: end conditions scipy's CubicSpline accepts by name
_BC_TYPES = ("not-a-knot", "clamped", "natural", "periodic")


def _gravity_ratios(traj, robot, cert) -> np.ndarray:
    """``(nq,)``: per joint, gravity's torque ratio (to the scaled effort limit) at the time of
    the joint's worst torque sample."""
    t = np.asarray(cert.times["torque"], dtype=float)
    g = gravity_torques(robot, traj.derivatives(t, 0)[0])
    return np.abs(g[np.arange(len(t)), np.arange(len(t))]) / (cert.scale * cert.limits["torque"])


_TORQUE_SLOWDOWNS = 6
"""Time scalings :func:`_slow_down` tries at most against a torque excess (each from the worst
samples of the last certificate)."""


def _slow_down(traj, robot, cert, quantities, tol):
    """Repair small velocity, acceleration and torque excesses between gridpoints by uniform
    time scalings.

    With ``λ = min(1 / r_v, 1 / sqrt(r_a))`` the velocity and acceleration ratios become
    ``<= 1``; the torque ``λ² (M q̈ + C q̇) + g`` moves from its old value towards gravity's (see
    :meth:`Trajectory.time_scaled`). A torque excess ``r_τ`` of joint ``j`` whose gravity ratio
    ``r_g`` at that sample is below 1 asks ``λ² <= (1 - r_g) / (r_τ - r_g)`` too; another sample
    may then be the worst, so this repeats from each new certificate, at most
    :data:`_TORQUE_SLOWDOWNS` times (Drake's Toppra checks its limits at its gridpoints only: at 20
    gridpoints a torque excess between them did not shrink when the torque limit was tightened and
    solved again). What is still violated is left to a re-solve with tightened limits.
    """
    total = 1.0
    for _ in range(_TORQUE_SLOWDOWNS):
        r = {q: cert.max_ratio((q,)) for q in quantities}
        if r.get("position", 0.0) > 1.0 + tol or all(v <= 1.0 + tol for v in r.values()):
            break
        lam = min(1.0 / max(r.get("velocity", 0.0), 1.0), 1.0 / np.sqrt(max(r.get("acceleration", 0.0), 1.0)))
        if r.get("torque", 0.0) > 1.0 + tol:
            r_tau = np.asarray(cert.ratios["torque"], dtype=float)
            over = r_tau > 1.0 + tol
            r_g = _gravity_ratios(traj, robot, cert)
            if np.any(r_g[over] >= 1.0):
                break  # gravity alone exceeds the limit there: no speed helps
            lam = min(lam, float(np.min(np.sqrt((1.0 - r_g[over]) / (r_tau[over] - r_g[over])))) * (1.0 - 1e-3))
        lam *= 1.0 - 1e-9
        if lam >= 1.0:  # only a quantity no time scaling repairs (jerk is not enforced here)
            break
        total *= lam
        traj = traj.time_scaled(lam)
        traj.info["time_scaling"] = total
        cert = certify(traj, robot, quantities=_REPORTED, scale=cert.scale, enforced=cert.enforced,
                       limits=cert.limits)
    return traj, cert


def _check_gravity_on_segments(W, robot, effort: np.ndarray, samples: int = 64) -> None:
    """ruckig moves rest-to-rest along straight joint segments: if holding the arm anywhere on
    them needs more than the (scaled) effort limits ``effort (nq,)``, no slow-down helps, so say
    so before solving."""
    from drake_mh.trajectories.limits_for import path_samples

    g = gravity_torques(robot, path_samples(W, samples))
    ratio = np.abs(g) / effort
    if np.max(ratio) > 1.0:
        i, j = np.unravel_index(np.argmax(ratio), ratio.shape)
        raise InfeasibleTrajectory(
            "ruckig", f"holding the arm against gravity on segment {i // samples} needs {abs(g[i, j]):.4g} N·m "
            f"on joint {robot.joint_names[j]!r}, above its effort limit {effort[j]:.4g} "
            "N·m (after scaling): no speed helps; change the path or the payload")


