"""One verification for every motion planner: the planner's own flags are never read.

A path ``(M, nq)`` succeeds when

1. it is finite, inside the joint limits, starts at ``q_start`` (1e-9 rad) and ends at a goal
   configuration (1e-6 rad) or, for a pose goal, reaches the pose (1 mm / 0.01 rad, Drake FK);
2. the piecewise-linear joint-space motion through it is **certified** collision-free with the
   problem's clearances (:func:`drake_mh.scene.segments.certify_path`: every configuration on
   every segment, not only the waypoints);
3. it retimes into a trajectory certified against the robot's velocity, acceleration and torque
   limits (:func:`drake_mh.trajectories.retime`: toppra, else ruckig; or the one method asked for
   with ``retime="toppra"`` / ``"ruckig"``) whose *executed* motion is certified too.

   toppra's trajectory is ``q(t) = p(s(t))``: its cubic spline ``p`` through the waypoints
   (:func:`drake_mh.trajectories.paths.joint_path`) leaves the chords, but whatever the timing it
   passes only through the spline's configurations. So the spline is certified *before* toppra
   solves (:func:`spline_clearance`): sampled in its parameter ``s``, piece by piece, the
   straight segments between the samples are certified, and between two samples a joint
   deviates from that segment by at most ``δ_j = Δs² a_j / 8`` (the linear-interpolation error
   bound), ``a_j`` the largest ``|p_j''|`` on the piece (linear on a cubic piece: the larger end
   value). A sphere then moves at most ``max_c Σ_j reach[c, j] δ_j``
   (:attr:`~drake_mh.scene.batch.CollisionModel.reach`) from the certified segments; ``Δs`` is
   chosen so that this is :data:`TRAJECTORY_SHIFTS` (1 mm, finer if needed), and the spline's
   certified clearance is the segments' minus it. A spline that is not clear is refused without
   timing it (ruckig is tried next); an accepted one gives its clearance to the trajectory once
   the trajectory is checked to run on exactly that spline with a time law whose range
   (Bernstein bounds) stays in its domain (:func:`timed_on_spline`). Any other trajectory is
   sampled in time the same way (:func:`trajectory_clearance`: ``a_j`` the certified bound of
   its acceleration). ruckig's trajectories move exactly along the certified straight segments,
   so they take the path's certificate (:data:`ON_PATH_ALLOWANCE`) without sampling.

Jerk: toppra's time law has piecewise-constant ``s̈``, so its acceleration steps at every
gridpoint and its jerk is unbounded there. On a robot that declares jerk limits (the Panda:
Franka's 3,750-10,000 rad/s³) such a trajectory is certified against velocity, acceleration and
torque but **not** against jerk: :attr:`MotionResult.jerk_limited` is then False and
``max_jerk`` is ``inf``. ``retime="ruckig"`` gives jerk-limited motions (exactly on the
certified straight segments, at rest at every waypoint, so longer for paths with many
waypoints).
"""

from __future__ import annotations

import numpy as np

from drake_mh.planning.problem import POSE_ORIENTATION_TOLERANCE, POSE_POSITION_TOLERANCE, MotionProblem
from drake_mh.planning.result import MotionResult

REPORT_TOLERANCE = 1e-3
"""[m] the certified minimum clearance is refined to within this of the smallest value seen."""

VERIFY_PARTS = ("path_certification", "retiming", "limit_certification", "trajectory_clearance")
"""The parts of ``verify_time`` timed in ``info["verify_parts"]`` ([s] each, every retimer tried
summed): the path's collision certificate; the retimers' solves (a failed one included); the
certification of their trajectories against the robot's limits; the certified clearance of the
executed trajectory."""

TRAJECTORY_SHIFTS = (1e-3, 1e-4, 1e-5)
"""[m] largest sphere displacement allowed between a retimed trajectory and its sampled chords:
1 mm first, then finer (about 3x more samples each) where a path certified close to its
clearance cannot absorb it."""


def reaches_goal(problem, q_end: np.ndarray) -> tuple[int | None, str]:
    """``(index of the goal configuration reached, "")``, or ``(None, how far it is)``: within
    1e-6 rad of a goal configuration, or the goal pose within 1 mm / 0.01 rad (Drake FK; index 0)."""
    if problem.goal_pose is None:
        errors = np.max(np.abs(problem.goal_configurations - q_end), axis=1)
        i = int(np.argmin(errors))
        if errors[i] <= 1e-6:
            return i, ""
        return None, f"the path ends {errors[i]:.3g} rad from the nearest goal configuration"
    X_WE = problem.robot.fk_drake(q_end, problem.frame) if problem.frame else problem.robot.fk_drake(q_end)
    X_WG = problem.goal_pose
    position = float(np.linalg.norm(X_WE[:3, 3] - X_WG[:3, 3]))
    cos = (np.trace(X_WG[:3, :3].T @ X_WE[:3, :3]) - 1.0) / 2.0
    angle = float(np.arccos(np.clip(cos, -1.0, 1.0)))
    if position <= POSE_POSITION_TOLERANCE and angle <= POSE_ORIENTATION_TOLERANCE:
        return 0, ""
    return None, f"the path ends {position * 1e3:.2f} mm / {angle:.4f} rad from the goal pose (Drake FK)"


RETIME_CHOICES = {True: ("toppra", "ruckig"), "toppra": ("toppra",), "ruckig": ("ruckig",)}
"""``retime`` argument -> retimers tried in order (``False``: no trajectory)."""


def check_retime(retime) -> None:
    """Raise :class:`~drake_mh.errors.InvalidArgument` unless ``retime`` is a key of
    :data:`RETIME_CHOICES` or ``False``."""
    from drake_mh.errors import InvalidArgument

    if retime is not False and (not isinstance(retime, (bool, str)) or retime not in RETIME_CHOICES):
        raise InvalidArgument(f"retime must be True, False, 'toppra' or 'ruckig', got {retime!r}")


def _jerk_limited(trajectory) -> bool | None:
    """Whether the trajectory is certified within the robot's declared jerk limits (None: the
    robot declares none)."""
    cert = trajectory.info.get("certificate")
    if cert is None or "jerk" not in cert.ratios:
        return None
    return bool(cert.ok(("jerk",)))


def _max_jerk(trajectory) -> float:
    """Largest joint jerk [rad/s³]: the certificate's bound (Bernstein coefficients of every piece:
    no point exceeds it, exact for piecewise-constant jerk; ``inf`` at acceleration steps, as
    toppra's), else, for a trajectory certified without jerk, the largest of 2,001 samples."""
    cert = trajectory.info.get("certificate")
    if cert is not None and "jerk" in cert.bounds:
        return float(np.max(cert.bounds["jerk"], initial=0.0))
    t = np.linspace(trajectory.start_time, trajectory.end_time, 2001)
    try:
        return float(np.max(np.abs(trajectory.jerk(t))))
    except Exception:  # a trajectory without a jerk accessor: report unknown
        return float("nan")


def verify_motion(problem, path, method: str, result: MotionResult | None = None,
                  retime: bool | str = True, velocity_scaling: float | None = None,
                  acceleration_scaling: float | None = None) -> MotionResult:
    """Verify ``path`` for ``problem`` and fill a :class:`MotionResult` (see module docstring).

    Args:
        retime: ``True`` (toppra, else ruckig), ``"toppra"``, ``"ruckig"`` (jerk-limited), or
            ``False`` (the path only, no trajectory).
        velocity_scaling, acceleration_scaling: MoveIt's scaling factors in (0, 1] for the
            retiming (:func:`drake_mh.trajectories.retime`; ``None``: the robot's defaults).

    ``info["certificate"]`` is the path's :class:`~drake_mh.scene.segments.PathCertificate`;
    its clearance is refined to :data:`REPORT_TOLERANCE` where it is the reported
    ``min_clearance`` (no trajectory, one on the certified segments, a stationary one), else it
    is a valid, coarser bound (the sampled trajectory's certificate is then the one refined).
    ``info["verify_parts"]``: the seconds of each of :data:`VERIFY_PARTS`.

    A one-row path (the start already reaches the goal) gets a stationary trajectory of zero
    duration, certified like any other (no velocity, acceleration or jerk; the torque that holds
    the robot against gravity).

    Raises:
        InvalidArgument: another ``retime``, or a scaling factor outside (0, 1];
            ``problem`` not a MotionProblem; ``path`` not an array of numbers (ragged rows,
            text, complex values). A numeric path of the wrong shape, non-finite or outside the
            limits is a failed result, not an error.
    """
    import time

    from drake_mh.errors import InvalidArgument
    from drake_mh.scene.segments import refine_path

    check_retime(retime)
    check_scaling(velocity_scaling, acceleration_scaling)
    if not isinstance(problem, MotionProblem):
        raise InvalidArgument(f"problem must be a drake_mh.planning.MotionProblem, got {type(problem).__name__}")

    start = time.perf_counter()
    result = result or MotionResult(method)
    robot, scene = problem.robot, problem.scene
    if path is None:
        result.success, result.message = False, result.message or "no path found"
        return result
    try:
        P = None if np.iscomplexobj(path) else np.asarray(path, dtype=float)
    except (TypeError, ValueError):  # ragged rows, text
        P = None
    if P is None:
        raise InvalidArgument(f"path must be an array of numbers (M, {robot.nq}) [rad], got {str(path)[:80]!r}")
    if P.ndim != 2 or P.shape[1] != robot.nq or len(P) < 1 or not np.all(np.isfinite(P)):
        result.success, result.message = False, f"the method returned an invalid path of shape {P.shape}"
        return result
    result.path = P
    result.path_length = float(np.sum(np.linalg.norm(np.diff(P, axis=0), axis=1)))
    outside = (P < robot.lower - 1e-9) | (P > robot.upper + 1e-9)
    if np.any(outside):
        row, j = np.argwhere(outside)[0]
        result.success, result.message = False, f"waypoint {row} leaves joint {robot.joint_names[j]!r}'s limits"
        return result
    if np.max(np.abs(P[0] - problem.q_start)) > 1e-9:
        result.success, result.message = False, "the path does not start at q_start"
        return result
    goal_index, why = reaches_goal(problem, P[-1])
    if goal_index is None:
        result.success, result.message = False, why
        return result
    result.goal_index = goal_index if result.goal_index is None else result.goal_index
    parts = result.info["verify_parts"] = dict.fromkeys(VERIFY_PARTS, 0.0)
    tick = time.perf_counter()
    cert = scene.certify_path(P, problem.clearance, problem.self_clearance)  # tightened where it is reported
    parts["path_certification"] = time.perf_counter() - tick
    result.info["certificate"] = cert
    if not cert.certified:
        result.success = False
        result.message = f"motion not certified collision-free: segment {cert.first_failure}: " \
                         f"{cert.segments.reason(cert.first_failure)}"
        result.verify_time = time.perf_counter() - start
        return result

    refined = []

    def tight():
        """The path's certificate with its clearance refined to :data:`REPORT_TOLERANCE`
        (computed once, where a reported clearance is the path's)."""
        if not refined:
            tick = time.perf_counter()
            refined.append(refine_path(scene, P, cert, REPORT_TOLERANCE))
            result.info["certificate"] = refined[0]
            parts["path_certification"] += time.perf_counter() - tick
        return refined[0]

    result.success, result.message = True, "certified"
    if not retime:
        result.min_clearance = tight().min_clearance
    else:
        trajectory, message = _retime(problem, P, RETIME_CHOICES[retime], tight, velocity_scaling,
                                      acceleration_scaling, parts)
        if trajectory is None:
            result.min_clearance = tight().min_clearance
            result.success, result.message = False, message
        else:
            result.trajectory, result.duration = trajectory, float(trajectory.end_time - trajectory.start_time)
            result.limits = trajectory.info.get("enforced_limits")
            result.max_jerk = _max_jerk(trajectory)
            result.jerk_limited = _jerk_limited(trajectory)
            result.min_clearance = trajectory.info["certified_clearance"]
            result.message = ("certified; the start is the goal: a stationary trajectory of zero duration"
                              if trajectory.method == "stationary" else f"certified; retimed with {trajectory.method}")
    result.verify_time = time.perf_counter() - start
    return result


ON_PATH_ALLOWANCE = 1e-9
"""[m] subtracted from the path's certified clearance for a trajectory that moves exactly along
the certified straight segments (ruckig's, :func:`drake_mh.trajectories.retime`): its
configurations are ``q_a + s(t) (q_b - q_a)`` with ``s`` in ``[0, 1]`` up to floating-point
rounding of the polynomial (3e-15 rad measured), which moves a sphere by far less than this."""


def _on_certified_path(trajectory, W: np.ndarray) -> bool:
    """Whether ``trajectory`` is ruckig's motion along exactly the straight segments through
    ``W`` (its construction; its waypoints checked at their times to 1e-9 rad)."""
    on_path, times = trajectory.info.get("on_path"), trajectory.info.get("waypoint_times")
    if trajectory.method != "ruckig" or on_path is None or times is None or on_path.shape != W.shape:
        return False
    if not np.array_equal(on_path, W):
        return False
    return bool(np.max(np.abs(trajectory.position(np.asarray(times)) - W)) <= 1e-9)


def trajectory_clearance(problem, trajectory, path_certificate=None, W=None) -> tuple[float, str]:
    """Certified lower bound of the obstacle clearance along ``trajectory``'s executed motion [m]
    (NaN and the reason where it cannot be certified with the problem's clearances).

    A trajectory along exactly the certified straight segments through ``W`` (ruckig's) gets the
    ``path_certificate``'s clearance less :data:`ON_PATH_ALLOWANCE`, without sampling. Otherwise
    the trajectory is sampled (module docstring); the finer levels of
    :data:`TRAJECTORY_SHIFTS` are skipped once a sampled configuration itself is not free at the
    problem's clearances under the sphere model (no finer sampling can certify it then).
    """
    scene = problem.scene
    if path_certificate is not None and W is not None and _on_certified_path(trajectory, W):
        return path_certificate.min_clearance - ON_PATH_ALLOWANCE, ""
    cert = trajectory.info.get("certificate")
    if cert is None or "acceleration" not in getattr(cert, "bounds", {}):
        return float("nan"), "the trajectory has no certified acceleration bound"
    a_bound = np.asarray(cert.bounds["acceleration"], dtype=float)
    if not np.all(np.isfinite(a_bound)):
        return float("nan"), "the trajectory's acceleration bound is not finite"
    reach = scene.collision_model.reach  # (C, nq)
    per_dt2 = float(np.max(reach @ (a_bound / 8.0)))  # sphere shift per Δt²
    duration = float(trajectory.end_time - trajectory.start_time)
    why = ""
    for target in TRAJECTORY_SHIFTS:  # finer sampling only where a coarse one cannot certify
        dt = np.sqrt(target / per_dt2) if per_dt2 > 0 else duration
        n = max(2, int(np.ceil(duration / max(dt, 1e-9))) + 1)
        t = np.linspace(trajectory.start_time, trajectory.end_time, n)
        shift = per_dt2 * (t[1] - t[0]) ** 2
        Q = trajectory.position(t)
        path = scene.certify_path(Q, problem.clearance + shift, problem.self_clearance + shift,
                                  tolerance=REPORT_TOLERANCE)
        if path.certified:
            return path.min_clearance - shift, ""
        if not np.all(scene.collision_free(Q, problem.clearance, problem.self_clearance)):
            return float("nan"), (f"the retimed trajectory ({trajectory.method}) passes configurations closer "
                                  f"than the clearance ({problem.clearance * 1e3:.1f} mm) under the sphere model")
        why = (f"the retimed trajectory ({trajectory.method}) is not certified at {problem.clearance * 1e3:.1f} mm "
               f"+ {shift * 1e3:.3f} mm between its {n} samples: {path.segments.reason(path.first_failure)}")
    return float("nan"), why


def _chord_samples(spline, per_piece_ds2: np.ndarray, target: float) -> tuple[np.ndarray, float]:
    """Parameters ``s`` sampling every piece of ``spline`` so finely that the sphere shift
    ``per_piece_ds2[i] · Δs²`` between two samples is at most ``target`` [m]; both ends of every
    piece included. Returns ``(s, largest shift)``."""
    x = np.asarray(spline.x, dtype=float)
    h = np.diff(x)
    n = np.maximum(1, np.ceil(h * np.sqrt(per_piece_ds2 / target))).astype(int)
    piece = np.repeat(np.arange(len(h)), n)
    step = np.repeat(h / n, n)
    first = np.repeat(np.cumsum(n) - n, n)
    s = np.r_[x[piece] + (np.arange(len(piece)) - first) * step, x[-1]]
    return s, float(np.max(per_piece_ds2 * (h / n) ** 2))


def spline_clearance(problem, spline) -> tuple[float, str]:
    """Certified lower bound of the obstacle clearance over **every configuration of the cubic
    joint spline** ``s -> q`` on its whole domain ``[spline.x[0], spline.x[-1]]`` [m] (NaN and
    the reason where it cannot be certified with the problem's clearances).

    A retimed trajectory ``q(t) = spline(s(t))`` whose time law keeps ``s(t)`` in that domain
    passes only through these configurations, whatever its timing, so the bound is its executed
    motion's (:func:`timed_on_spline`). Sampling is in ``s``, piece by piece: on a piece the
    second derivative of a cubic is linear, so ``|p_j''| <= a_ij``, the larger of its two end
    values, and between samples ``Δs`` apart joint ``j`` deviates from the straight chord by at
    most ``δ_j = Δs² a_ij / 8`` (the linear-interpolation error bound). A sphere then moves at
    most ``max_c Σ_j reach[c, j] δ_j`` (:attr:`~drake_mh.scene.batch.CollisionModel.reach`, rows
    of links and of link pairs) from the certified chords; each piece's ``Δs`` keeps this within
    :data:`TRAJECTORY_SHIFTS` (1 mm, finer if needed), and the clearance is the chords' certified
    one (refined to :data:`REPORT_TOLERANCE`) less the largest shift. The samples themselves are
    checked first, in one batch: a sample that is not free at the problem's clearances under the
    sphere model refuses the spline at once (no finer sampling can certify it).

    Raises:
        InvalidArgument: ``spline`` is not a cubic (or lower degree) ``PPoly`` of ``(nq,)``.
    """
    from drake_mh.errors import InvalidArgument

    scene = problem.scene
    c = np.asarray(getattr(spline, "c", np.empty(0)), dtype=float)
    if c.ndim != 3 or c.shape[0] > 4 or c.shape[2] != problem.robot.nq:
        raise InvalidArgument(f"spline must be a cubic PPoly s -> q ({problem.robot.nq},), got coefficients {c.shape}")
    c = _as_cubic(c)  # c[0] y³ + c[1] y² + c[2] y + c[3]
    h = np.diff(np.asarray(spline.x, dtype=float))[:, None]
    a_bound = np.maximum(np.abs(2.0 * c[1]), np.abs(6.0 * c[0] * h + 2.0 * c[1]))  # (pieces, nq)
    per_ds2 = np.max((a_bound / 8.0) @ scene.collision_model.reach.T, axis=1)  # sphere shift per Δs²
    why = ""
    for target in TRAJECTORY_SHIFTS:
        s, shift = _chord_samples(spline, per_ds2, target)
        Q = spline(s)
        if not np.all(scene.collision_free(Q, problem.clearance, problem.self_clearance)):  # cheap: first
            return float("nan"), (f"the spline through the waypoints passes configurations closer than the "
                                  f"clearance ({problem.clearance * 1e3:.1f} mm) under the sphere model")
        path = scene.certify_path(Q, problem.clearance + shift, problem.self_clearance + shift,
                                  tolerance=REPORT_TOLERANCE)
        if path.certified:
            return path.min_clearance - shift, ""
        why = (f"the spline through the waypoints is not certified at {problem.clearance * 1e3:.1f} mm + "
               f"{shift * 1e3:.3f} mm between its {len(s)} samples: {path.segments.reason(path.first_failure)}")
    return float("nan"), why


def _range_bounds(timing) -> tuple[float, float]:
    """Lower and upper bound of a scalar ``PPoly`` over its whole domain: the extreme Bernstein
    coefficients of its pieces (convex-hull property of the Bernstein basis)."""
    from math import comb

    c = np.asarray(timing.c, dtype=float)  # (k + 1, pieces), highest power first
    k = c.shape[0] - 1
    h = np.diff(np.asarray(timing.x, dtype=float))
    a = [c[k - m] * h ** m for m in range(k + 1)]  # power-basis coefficients on [0, 1]
    b = np.array([sum(comb(i, m) / comb(k, m) * a[m] for m in range(i + 1)) for i in range(k + 1)])
    return float(np.min(b)), float(np.max(b))


def timed_on_spline(trajectory, spline) -> np.ndarray | None:
    """Per joint ``(nq,)``, how far [rad] ``trajectory``'s executed configurations can be from
    ``spline``'s configurations on its domain; ``None`` where ``trajectory`` is not ``spline``
    under a time law.

    ``trajectory`` qualifies when its path is ``spline`` itself (the same breakpoints and
    coefficients) and its time law's range, bounded by Bernstein coefficients (plus ``1e-12`` of
    the domain's length for rounding), stays in the domain up to ``1e-9`` of its length; a
    configuration ``e`` beyond an end is within
    ``e |p'| + e² |p''| / 2 + e³ |p'''| / 6`` of the end's (Taylor, exact for a cubic end piece).
    """
    path, timing = trajectory.path, trajectory.timing
    same = path is spline or (np.array_equal(path.x, spline.x) and np.array_equal(path.c, spline.c))
    if timing is None or not same:
        return None
    x0, x1 = float(spline.x[0]), float(spline.x[-1])
    lo, hi = _range_bounds(timing)
    beyond = max(x0 - lo, hi - x1, 0.0) + 1e-12 * (x1 - x0)  # with room for rounding
    if beyond > 1e-9 * (x1 - x0):
        return None
    step = np.zeros(spline.c.shape[2])
    for d1, d2, d3 in end_derivatives(spline):
        step = np.maximum(step, beyond * np.abs(d1) + beyond ** 2 * np.abs(d2) / 2.0 + beyond ** 3 * np.abs(d3) / 6.0)
    return step


def _as_cubic(c: np.ndarray) -> np.ndarray:
    """Coefficients ``(k + 1, pieces, nq)`` of a polynomial of degree ``k <= 3`` (highest power
    first) as a cubic's ``(4, pieces, nq)``, the missing powers zero."""
    return np.concatenate([np.zeros((4 - c.shape[0],) + c.shape[1:]), c])


def end_derivatives(spline) -> tuple[np.ndarray, np.ndarray]:
    """The first three derivatives ``(3, nq)`` of a cubic (or lower degree) vector ``PPoly`` at
    the start of its domain and at its end, from the first and last pieces' coefficients."""
    c = _as_cubic(np.asarray(spline.c, dtype=float))
    h = float(spline.x[-1] - spline.x[-2])  # the last piece's length
    first = c[:3, 0][::-1] * np.array([[1.0], [2.0], [6.0]])
    last = np.array([(3.0 * c[0, -1] * h + 2.0 * c[1, -1]) * h + c[2, -1], 6.0 * c[0, -1] * h + 2.0 * c[1, -1],
                     6.0 * c[0, -1]])
    return first, last


def check_scaling(velocity_scaling, acceleration_scaling) -> None:
    """Raise :class:`~drake_mh.errors.InvalidArgument` unless both factors are ``None`` or a
    number in (0, 1]."""
    from drake_mh.trajectories.limits_for import check_scaling_factor

    check_scaling_factor(velocity_scaling, "velocity_scaling")
    check_scaling_factor(acceleration_scaling, "acceleration_scaling")


REASON_CHARACTERS = 240
"""Each retimer's reason in a failed verification's message is cut to this many characters."""


def _reason(method: str, text: str) -> str:
    text = " ".join(str(text).split())
    text = text if text.startswith(method) else f"{method}: {text}"
    return text if len(text) <= REASON_CHARACTERS else text[:REASON_CHARACTERS - 1] + "…"


def _retime(problem, P: np.ndarray, methods: tuple, tight, velocity_scaling=None,
            acceleration_scaling=None, parts: dict | None = None) -> tuple[object, str]:
    """The first of ``methods`` that retimes ``P``; the executed motion certified (toppra: its
    spline by :func:`spline_clearance` before solving, then :func:`timed_on_spline`; otherwise
    :func:`trajectory_clearance`). ``tight()``: the path's certificate refined to
    :data:`REPORT_TOLERANCE`, asked for only where the trajectory takes the path's clearance (on
    the certified segments, or stationary). On failure: one short reason per retimer and how to
    get the certified path alone. Adds the seconds of each part to ``parts``
    (:data:`VERIFY_PARTS`)."""
    import time

    from drake_mh.errors import DrakeMhError
    from drake_mh.trajectories import retime
    from drake_mh.trajectories.paths import joint_path

    robot = problem.robot
    keep = np.r_[True, np.any(np.abs(np.diff(P, axis=0)) > 1e-12, axis=1)]  # repeated rows break splines
    W = P[keep]
    if len(W) < 2:  # the start is the goal: stay there
        return _stationary(robot, W[0], tight())
    parts = {} if parts is None else parts
    for part in VERIFY_PARTS:
        parts.setdefault(part, 0.0)
    reasons = []
    for method in methods:
        spline = spline_bound = None
        if method == "toppra":  # its geometric path first: a spline that is not clear is never timed
            tick = time.perf_counter()
            try:
                spline, _ = joint_path(W, robot, method)  # the spline retime(W, robot, "toppra") times
            except DrakeMhError as exc:
                spline, why = None, str(exc)
            else:
                spline_bound, why = spline_clearance(problem, spline)
            parts["trajectory_clearance"] += time.perf_counter() - tick
            if spline is None or np.isnan(spline_bound):
                reasons.append(_reason(method, why))
                continue
        tick = time.perf_counter()
        try:
            trajectory = retime(W, robot, method, velocity_scaling=velocity_scaling,
                                acceleration_scaling=acceleration_scaling)
        except DrakeMhError as exc:
            parts["retiming"] += time.perf_counter() - tick
            reasons.append(_reason(method, exc))
            continue
        certifying = float(trajectory.info.get("certify_time", 0.0))
        parts["retiming"] += time.perf_counter() - tick - certifying
        parts["limit_certification"] += certifying
        certificate = tight() if _on_certified_path(trajectory, W) else None  # timed as the path's
        tick = time.perf_counter()
        step = None if spline is None else timed_on_spline(trajectory, spline)
        if step is not None:  # the executed motion stays on the certified spline
            reach = problem.scene.collision_model.reach
            clearance, why = spline_bound - float(np.max(reach @ step, initial=0.0)), ""
        else:
            clearance, why = trajectory_clearance(problem, trajectory, certificate, W)
        parts["trajectory_clearance"] += time.perf_counter() - tick
        if not np.isnan(clearance):  # +inf: a scene without obstacles or checked self pairs
            trajectory.info["certified_clearance"] = clearance
            return trajectory, ""
        reasons.append(_reason(method, why))
    return None, (f"certified path ({len(W)} waypoints), but no certified trajectory: " + "; ".join(reasons)
                  + ". solve_motion(..., retime=False) returns the certified path without one")


def _stationary(robot, q: np.ndarray, path_certificate) -> tuple[object, str]:
    """The trajectory that stays at ``q``: zero duration, certified (zero velocity, acceleration
    and jerk; the torque that holds ``q`` against gravity), with the configuration's certified
    clearance."""
    from scipy.interpolate import PPoly

    from drake_mh.trajectories import Trajectory, certify

    trajectory = Trajectory(PPoly(np.array(q, dtype=float)[None, None, :], [0.0, 0.0]),
                            joint_names=tuple(robot.joint_names), method="stationary")
    cert = trajectory.info["certificate"] = certify(trajectory, robot)
    if not cert.ok():
        return None, f"the start is the goal, but holding it exceeds a limit: {cert.worst()}"
    trajectory.info["certified_clearance"] = path_certificate.min_clearance
    return trajectory, ""
