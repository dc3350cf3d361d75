"""Time parameterization under joint limits: toppra, ruckig, Drake ``Toppra``.

``retime(waypoints, robot, method=...)`` turns a joint path into a :class:`Trajectory` that is
**certified** (:func:`~drake_mh.trajectories.certify.certify`, dense sampling) to respect the
robot's position limits and the requested limits within ``1 + tol``, or raises.

* ``"toppra"`` (Pham & Pham, "A new approach to time-optimal path parameterization based on
  reachability analysis", IEEE T-RO 2018; the ``toppra`` package): the path is the ``C²``
  cubic spline of :func:`~drake_mh.trajectories.paths.joint_path`; velocity, acceleration and
  torque limits (torque ``a(s) s̈ + b(s) ṡ² + c(s)`` with gravity, coefficients from the
  plant-compiled RNEA of :mod:`~drake_mh.trajectories.dynamics`), seidel solver, toppra's
  interpolation discretization plus the same rows at ``check_points`` interior points of every
  gridpoint interval (:func:`_dense_constraints`). The time law is built from toppra's gridpoints and ``ṡ`` with constant ``s̈``
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
  acceleration and jerk), and ``q(t) = q_a + s(t) (q_b - q_a)`` (:func:`_ruckig_line`): every
  configuration lies on the segment (to rounding), ``s`` is monotone (rest to rest), the
  segment stays in the convex position box, and under the joints' box limits no rest-to-rest
  motion along the segment is faster.

Limits are enforced at the check points by toppra; between them the chain-rule values can
exceed a limit slightly. Every candidate is certified. A velocity, acceleration or torque excess
of a toppra method is repaired by uniform time scalings (:func:`_slow_down`: the torque moves
towards gravity's; where gravity alone exceeds the limit, :class:`InfeasibleTrajectory` says so);
any other violation scales the
offending quantity's limit by ``1 / ratio`` (times ``1 - 1e-3``; for ruckig a torque excess
scales its velocity and acceleration limits) and solves again, at most ``max_attempts`` times,
then :class:`~drake_mh.errors.LimitViolation` is raised.
"""

from __future__ import annotations

import logging
import numbers
import time

import numpy as np
from scipy.interpolate import PPoly

from drake_mh.errors import InfeasibleTrajectory, InvalidArgument, LimitViolation, UnknownMethod
from drake_mh.trajectories.certify import certify
from drake_mh.trajectories.dynamics import batch_dynamics
from drake_mh.trajectories.paths import check_waypoints, joint_path
from drake_mh.trajectories.ruckig_time import _ruckig_path, ruckig_state_to_state
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
_DEFAULT_LIMITS = {"toppra": ("velocity", "acceleration", "torque"),
                   "drake-toppra": ("velocity", "acceleration", "torque"),
                   "ruckig": ("velocity", "acceleration", "jerk")}
_SUPPORTED = {"toppra": {"velocity", "acceleration", "torque"},
              "drake-toppra": {"velocity", "acceleration", "torque"},
              "ruckig": {"velocity", "acceleration", "jerk", "torque"}}


def retime(path, robot, method: str = "toppra", *, limits=None, gridpoints: int | None = None,
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

    Args:
        path: ``(K, nq)`` joint waypoints [rad], ``K >= 2``, inside the position limits.
        robot: the :class:`~drake_mh.robot.Robot` (limits and dynamics).
        method: ``"toppra"``, ``"drake-toppra"`` or ``"ruckig"``.
        limits: quantities to enforce besides position (always enforced); default
            velocity/acceleration/torque for the toppra methods and velocity/acceleration/jerk
            for ruckig, torque and jerk only where the robot declares them. toppra
            trajectories have piecewise-constant ``s̈``: their jerk is not limited. ruckig
            enforces torque by certification only (limits scaled on failure).
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
        A :class:`Trajectory`; ``trajectory.info`` holds ``certificate``, ``attempts``,
        ``solve_time`` [s] (last attempt, without certification), ``gridpoints``.

    Raises:
        UnknownMethod: ``method`` not in ``RETIMERS``.
        InvalidArgument: bad waypoints, unsupported limit for the method, bad ``scale``.
        MissingLimits: an enforced velocity or acceleration limit undeclared on some joint, or
            an asked-for jerk or torque limit declared on none (the message names the joints and
            how to supply the limits).
        InfeasibleTrajectory: no parameterization exists (e.g. gravity alone exceeds an effort
            limit on the path, a waypoint outside the position limits).
        LimitViolation: still violating after ``max_attempts`` tightened solves.
    """
    if method not in RETIMERS:
        raise UnknownMethod(method, RETIMERS, what="retime method")
    if limits is None:  # the method's quantities; jerk and torque where the robot declares them
        limits = tuple(q for q in _DEFAULT_LIMITS[method]
                       if q in _REQUIRED or np.any(np.isfinite(_limit(robot, q))))
    limits = tuple(limits)
    bad = [q for q in limits if q not in _SUPPORTED[method]]
    if bad:
        raise InvalidArgument(f"{method} cannot enforce {bad}; it supports {sorted(_SUPPORTED[method])}"
                              + ("; use method='ruckig' for jerk limits" if "jerk" in bad else ""))
    _check_options(scale, tol, max_attempts, gridpoints, check_points, bc_type)
    for q in limits:
        lacking = [n for n, v in zip(robot.joint_names, _limit(robot, q)) if not np.isfinite(v)]
        if lacking and (q in _REQUIRED or len(lacking) == robot.nq):
            raise missing_limits(robot, q, lacking, method)
    W = check_waypoints(path, robot, method)
    factors = {q: float(scale) for q in limits}
    if method == "ruckig" and "torque" in limits:
        _check_gravity_on_segments(W, robot, factors["torque"])
    if method != "ruckig":  # head-room for what the check points miss (see _FIRST_MARGIN)
        for q in ("velocity", "acceleration"):
            if q in factors:
                factors[q] *= 1.0 - _FIRST_MARGIN
    quantities = ("position",) + limits
    # everything the robot has limits for is reported; only `quantities` are enforced
    reported = ("position",) + tuple(q for q in ("velocity", "acceleration", "jerk", "torque")
                                     if np.any(np.isfinite(_limit(robot, q))))
    attempts = 0
    while True:
        attempts += 1
        start = time.perf_counter()
        if method == "ruckig":
            traj = _ruckig_path(W, robot, factors)
        else:
            traj = _toppra_like(W, robot, method, factors, gridpoints, bc_type, check_points)
        solve_time = time.perf_counter() - start
        cert = certify(traj, robot, quantities=reported, scale=scale, enforced=quantities)
        if not cert.ok(quantities, tol) and method != "ruckig":
            traj, cert = _slow_down(traj, robot, cert, quantities, reported, tol)
        traj.info.update(certificate=cert, attempts=attempts, solve_time=solve_time, limits=limits,
                         factors=dict(factors))
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
                    "gridpoints; the path cannot be followed at any speed: change the path or the payload")
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


_REQUIRED = ("velocity", "acceleration")
"""Quantities every joint must declare when they are enforced (the time law is not bounded
otherwise); jerk and torque may be declared on some joints only."""

_HOW = {"velocity": ("velocity_limits", "rad/s", 'velocity="…"'),
        "acceleration": ("acceleration_limits", "rad/s²",
                         'drake:acceleration="…" (xmlns:drake="http://drake.mit.edu")'),
        "jerk": ("jerk_limits", "rad/s³", 'drake_mh:jerk="…" (xmlns:drake_mh="https://github.com/drake-mh/ns")'),
        "torque": ("effort_limits", "N·m", 'effort="…"')}


def missing_limits(robot, quantity: str, joints, method: str = "retime"):
    """The :class:`~drake_mh.errors.MissingLimits` for ``quantity`` undeclared on ``joints``:
    names the robot and the joints and says how to supply the limits."""
    from drake_mh.errors import MissingLimits

    attr, unit, urdf = _HOW[quantity]
    return MissingLimits(
        f"robot {robot.name!r} declares no {quantity} limits for joint(s) {list(joints)}, and {method} needs "
        f"them to time a path (no motion can be retimed or verified without them). Supply them [{unit}], one per "
        f"joint in robot.joint_names order: `robot.{attr} = np.array([...])` before retiming, or in the URDF's "
        f"<limit {urdf} .../> of each joint (example-robot-data's UR5 and Panda declare no acceleration: "
        f"drake_mh.planning.problems.load_problem_robot('ur5') / ('panda_hand') load copies that do); or "
        f"leave {quantity!r} out of `limits=`")


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


def _gravity(robot, Q: np.ndarray) -> np.ndarray:
    """``(N, nq)`` torques [N·m] that hold the arm still at the configurations ``Q (N, nq)``."""
    return batch_dynamics(robot).inverse_dynamics(Q, np.zeros_like(Q), np.zeros_like(Q))


def _gravity_ratios(traj, robot, cert) -> np.ndarray:
    """``(nq,)``: per joint, gravity's torque ratio (to the scaled effort limit) at the time of
    the joint's worst torque sample."""
    t = np.asarray(cert.times["torque"], dtype=float)
    g = _gravity(robot, traj.derivatives(t, 0)[0])
    return np.abs(g[np.arange(len(t)), np.arange(len(t))]) / (cert.scale * robot.effort_limits)


_TORQUE_SLOWDOWNS = 6
"""Time scalings :func:`_slow_down` tries at most against a torque excess (each from the worst
samples of the last certificate)."""


def _slow_down(traj, robot, cert, quantities, reported, tol):
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
        cert = certify(traj, robot, quantities=reported, scale=cert.scale, enforced=cert.enforced)
    return traj, cert


def _limit(robot, quantity: str) -> np.ndarray:
    return {"velocity": robot.velocity_limits, "acceleration": robot.acceleration_limits,
            "jerk": robot.jerk_limits, "torque": robot.effort_limits}[quantity]


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


# --- toppra and Drake Toppra ----------------------------------------------------------------------


def _gridpoints(spline, knots: np.ndarray, gridpoints: int | None) -> np.ndarray:
    s_end = float(spline.x[-1])
    if gridpoints is None:
        import toppra

        gp = toppra.interpolator.propose_gridpoints(_ToppraPath(spline), max_err_threshold=1e-3,
                                                    min_nb_points=100)
    else:
        if int(gridpoints) < 2:
            raise InvalidArgument(f"gridpoints must be >= 2, got {gridpoints}")
        gp = np.linspace(0.0, s_end, int(gridpoints))
    gp = np.unique(np.r_[gp, spline.x])
    gp = gp[np.r_[True, np.diff(gp) > 1e-9 * s_end]]
    gp[0], gp[-1] = 0.0, s_end
    return gp


class _ToppraPath:
    """toppra's geometric-path interface over a scipy spline (``AbstractGeometricPath``)."""

    def __init__(self, spline):
        self.spline = spline
        self.dof = spline.c.shape[2]
        self.path_interval = np.array([spline.x[0], spline.x[-1]])
        self.waypoints = (spline.x, spline(spline.x))

    def __call__(self, s, order=0):
        return self.spline(s, nu=order)

    def eval(self, s):
        return self.spline(s)

    def evald(self, s):
        return self.spline(s, nu=1)

    def evaldd(self, s):
        return self.spline(s, nu=2)

    @property
    def duration(self):
        return self.path_interval[1] - self.path_interval[0]


def _velocity_constraint(spline, vmax):
    """toppra ``xbound`` constraint ``ṡ² <= min_j vmax_j² / p_j'(s_i)²`` at every gridpoint.

    Same bound as toppra's ``JointVelocityConstraint`` (without its per-call string
    formatting); the interior of each interval gets velocity rows in :func:`_dense_constraints`.
    A rigorous variant (largest ``|p'|`` over both neighbouring intervals) was measured 3-6 %
    slower than Drake's ``Toppra`` at 100 gridpoints on random Panda paths, against 1-2.5 %
    faster for rows at interior check points followed by the certification's time scaling.
    """
    from toppra.constraint import LinearConstraint

    class _Velocity(LinearConstraint):
        def __init__(self):
            super().__init__()
            self.dof = spline.c.shape[2]

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            ps = np.abs(spline(gridpoints, nu=1))
            with np.errstate(divide="ignore"):
                xmax = np.min(np.where(ps > 0, vmax ** 2 / ps ** 2, np.inf), axis=1)
            xbound = np.column_stack([np.zeros(len(gridpoints)), np.minimum(xmax, 1e16)])
            return None, None, None, None, None, None, xbound

    return _Velocity()


def _dense_constraints(robot, spline, vmax, amax, tmax, fractions) -> list:
    """Velocity, acceleration and torque rows at several points of every gridpoint interval.

    toppra's interpolation discretization checks the second-order constraint
    ``a(s) u + b(s) x + c(s)`` at both ends of each interval, with ``x(s) = x_i + 2 u (s - s_i)``
    (constant ``s̈ = u``). The same linear rows in ``(u_i, x_i)`` hold at any ``σ`` inside:
    ``[a(σ) + 2 (σ - s_i) b(σ)] u_i + b(σ) x_i + c(σ)``. Checking at ``fractions`` of each
    interval shrinks what can be missed between check points (the certification and, if
    needed, a time scaling catch the rest). Velocity: ``a = 0``, ``b = p'²``, ``c = 0`` against
    ``v_max²``; acceleration: ``a = p'``, ``b = p''``, ``c = 0``; torque: ``a = M p'``,
    ``b = M p'' + C(p, p') p'``, ``c = g`` (gravity included).

    One toppra constraint object per fraction: toppra's seidel wrapper multiplies each
    object's ``F`` with its rows, and one object with every row (126 x 63 for the Panda) made
    OpenBLAS go multi-threaded — measured 100-200 ms per solve on a loaded 2-core machine
    instead of ~1 ms.
    """
    from toppra.constraint import DiscretizationType, LinearConstraint

    use_vel = np.any(np.isfinite(vmax))
    use_acc = np.any(np.isfinite(amax))
    use_tau = np.any(np.isfinite(tmax))
    lims = np.minimum(np.r_[vmax ** 2 if use_vel else [], amax if use_acc else [],
                            tmax if use_tau else []], 1e12)
    phi = np.asarray(fractions, dtype=float)
    m = len(lims)
    cache: dict = {}

    def rows(gridpoints):
        key = (len(gridpoints), float(gridpoints[-1]))
        if key not in cache:
            N1 = len(gridpoints)
            h = np.r_[np.diff(gridpoints), 0.0]  # stage N: only its own point
            sig = gridpoints[:, None] + phi[None, :] * h[:, None]  # (N+1, F)
            S = sig.ravel()
            P, Ps, Pss = spline(S), spline(S, nu=1), spline(S, nu=2)
            A, B, C = [], [], []
            if use_vel:
                A.append(np.zeros_like(Ps)), B.append(Ps ** 2), C.append(np.zeros_like(Ps))
            if use_acc:
                A.append(Ps), B.append(Pss), C.append(np.zeros_like(Ps))
            if use_tau:
                a, b, c = batch_dynamics(robot).path_coefficients(P, Ps, Pss)
                A.append(a), B.append(b), C.append(c)
            A, B, C = (np.hstack(x) for x in (A, B, C))  # (N1*F, m)
            off = (2.0 * (sig - gridpoints[:, None])).ravel()[:, None]
            cache.clear()
            cache[key] = ((A + off * B).reshape(N1, len(phi), m), B.reshape(N1, len(phi), m),
                          C.reshape(N1, len(phi), m))
        return cache[key]

    class _Rows(LinearConstraint):
        def __init__(self, k):
            super().__init__()
            self.k = k
            self.dof = robot.nq
            self.identical = True
            self.discretization_type = DiscretizationType.Interpolation

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            a, b, c = rows(gridpoints)
            F = np.vstack([np.eye(m), -np.eye(m)])
            return a[:, self.k], b[:, self.k], c[:, self.k], F, np.r_[lims, lims], None, None

    return [_Rows(k) for k in range(len(phi))]


def _diagnose(robot, method, spline, gp, factors) -> InfeasibleTrajectory:
    """Turn a failed solve into an exception that says why (gravity or limits)."""
    if "torque" in factors:
        g = _gravity(robot, spline(gp))
        ratio = np.abs(g) / (robot.effort_limits * factors["torque"])
        if np.max(ratio) > 1.0:
            i, j = np.unravel_index(np.argmax(ratio), ratio.shape)
            return InfeasibleTrajectory(
                method, f"holding the arm against gravity at s = {gp[i]:.4g} needs "
                f"{g[i, j]:.4g} N·m on joint {robot.joint_names[j]!r}, above its effort limit "
                f"{robot.effort_limits[j] * factors['torque']:.4g} N·m (after scaling); the path "
                "cannot be followed at any speed: change the path or the payload")
    return InfeasibleTrajectory(method, "no feasible path parameterization (empty controllable set); "
                                "check the limits and the path")


def _check_gravity_on_segments(W, robot, torque_scale: float, samples: int = 64) -> None:
    """ruckig moves rest-to-rest along straight joint segments: if holding the arm anywhere on
    them needs more than the effort limit, no slow-down helps, so say so before solving."""
    u = np.linspace(0.0, 1.0, samples)[:, None]
    Q = np.concatenate([W[k] + u * (W[k + 1] - W[k]) for k in range(len(W) - 1)])
    g = _gravity(robot, Q)
    ratio = np.abs(g) / (robot.effort_limits * torque_scale)
    if np.max(ratio) > 1.0:
        i, j = np.unravel_index(np.argmax(ratio), ratio.shape)
        raise InfeasibleTrajectory(
            "ruckig", f"holding the arm against gravity on segment {i // samples} needs {g[i, j]:.4g} N·m "
            f"on joint {robot.joint_names[j]!r}, above its effort limit {robot.effort_limits[j] * torque_scale:.4g} "
            "N·m (after scaling); the path cannot be followed at any speed: change the path or the payload")


def _toppra_like(W, robot, method, factors, gridpoints, bc_type, check_points) -> Trajectory:
    spline, s_way = joint_path(W, robot, method, bc_type=bc_type)
    gp = _gridpoints(spline, s_way, gridpoints)
    vmax = robot.velocity_limits * factors.get("velocity", np.inf)
    amax = robot.acceleration_limits * factors.get("acceleration", np.inf)
    tmax = robot.effort_limits * factors.get("torque", np.inf)
    if method == "toppra":
        import toppra.algorithm as algo

        cons = []
        if "velocity" in factors:
            cons.append(_velocity_constraint(spline, vmax))
        if factors:
            cons += _dense_constraints(robot, spline, vmax, amax, tmax,
                                       np.linspace(0.0, 1.0, int(check_points) + 2))
        instance = algo.TOPPRA(cons, _ToppraPath(spline), gridpoints=gp, solver_wrapper="seidel",
                               parametrizer="ParametrizeConstAccel")
        sdd, sd, _ = instance.compute_parameterization(0.0, 0.0)
        if sd is None:
            raise _diagnose(robot, method, spline, gp, factors)
        timing = timing_from_gridpoints(gp, sd)
    else:
        timing = _drake_toppra(robot, spline, gp, factors, vmax, amax, tmax)
    return Trajectory(spline, timing, tuple(robot.joint_names), method,
                      {"gridpoints": len(gp), "path_knots": len(spline.x)})


def _drake_toppra(robot, spline, gp, factors, vmax, amax, tmax) -> PPoly:
    from pydrake.multibody.optimization import Toppra
    from pydrake.trajectories import PiecewisePolynomial

    knots = spline.x
    drake_path = PiecewisePolynomial.CubicHermite(knots, spline(knots).T, spline(knots, nu=1).T)
    solver = Toppra(drake_path, robot.plant, gp)
    if "velocity" in factors:
        solver.AddJointVelocityLimit(-vmax, vmax)
    if "acceleration" in factors:
        solver.AddJointAccelerationLimit(-amax, amax)
    if "torque" in factors:
        solver.AddJointTorqueLimit(-tmax, tmax)
    s_traj = solver.SolvePathParameterization()
    if s_traj is None:
        raise _diagnose(robot, "drake-toppra", spline, gp, factors)
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
