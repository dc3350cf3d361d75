"""Jerk-limited motions with ruckig (Berscheid & Kröger, "Jerk-limited real-time trajectory
generation with arbitrary target states", RSS 2021; community edition).

* :func:`ruckig_state_to_state`: one state-to-state motion of every joint (online use).
* :func:`_ruckig_path` (``retime(..., method="ruckig")``): rest-to-rest motions exactly along the
  straight joint-space segments of a path, one 1-D profile of the segment parameter per segment.

Each ruckig profile (brake pre-phase + 7 constant-jerk phases) is converted exactly to cubic
``PPoly`` pieces (:func:`_profile_ppoly`).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PPoly

from drake_mh.errors import InfeasibleTrajectory, InvalidArgument
from drake_mh.trajectories.trajectory import Trajectory, merge_ppolys

__all__ = ["ruckig_state_to_state"]


def _profile_ppoly(profile, t_start: float, duration: float) -> PPoly:
    """Exact cubic ``PPoly`` of one ruckig DOF profile (brake pre-phase + 7 jerk phases)."""
    phases = []
    brake = profile.brake
    if brake.duration > 0:
        phases += [row for row in zip(brake.t, brake.j, brake.a, brake.v, brake.p) if row[0] > 0]
    phases += [row for row in zip(profile.t, profile.j, profile.a, profile.v, profile.p) if row[0] > 0]
    if getattr(profile, "accel", None) is not None and profile.accel.duration > 0:
        raise InfeasibleTrajectory("ruckig", "ruckig returned an acceleration pre-profile, which "
                                   "drake_mh does not convert; start from within the limits")
    x = [t_start]
    c = []
    for dt, j, a, v, p in phases:
        c.append([j / 6.0, a / 2.0, v, p])
        x.append(x[-1] + dt)
    if not phases:  # this DOF does not move
        c.append([0.0, 0.0, 0.0, profile.p[-1]])
        x.append(t_start + duration)
    # a DOF that finishes early (time synchronization) rests at its target until `duration`
    if x[-1] < t_start + duration - 1e-12:
        vf = profile.vf
        c.append([0.0, 0.0, vf if abs(vf) > 0 else 0.0, profile.pf])
        x.append(t_start + duration)
    x[-1] = t_start + duration
    return PPoly.construct_fast(np.array(c).T.copy(), np.array(x))  # increasing breaks by construction


def ruckig_state_to_state(robot, q0, q1, v0=None, a0=None, v1=None, a1=None, *, factors=None,
                          synchronization: str = "phase") -> Trajectory:
    """One jerk-limited state-to-state motion with ruckig (online use: call again every cycle).

    Ruckig's community edition ignores ``min_position``/``max_position``; the returned motion's
    position extrema are checked here against the robot's position limits.

    Args:
        robot: limits (velocity, acceleration, jerk; ``inf`` jerk is replaced by a large value).
        q0, q1: start and target positions ``(nq,)`` [rad].
        v0, a0, v1, a1: start/target velocities and accelerations (default 0).
        factors: quantity -> fraction of the limit to use (default 1).
        synchronization: ``"phase"`` (straight line in joint space where ruckig can: it falls
            back to time synchronization otherwise, and the motion then leaves the line, by up
            to 0.11 rad measured on random Panda segments; rest to rest along an exact line:
            ``retime(..., method="ruckig")``), ``"time"`` (ruckig's default) or ``"none"``.

    Returns:
        A :class:`Trajectory` (``method="ruckig"``), not yet certified.

    Raises:
        InfeasibleTrajectory: ruckig reports an error, or the motion leaves the position limits
            (e.g. braking from ``v0`` needs more room than the limit leaves).
    """
    from ruckig import InputParameter, Result, Ruckig, Synchronization
    from ruckig import Trajectory as RTrajectory

    nq = robot.nq
    factors = factors or {}
    zeros = np.zeros(nq)
    q0, q1 = robot.check_q(q0, "q0"), robot.check_q(q1, "q1")
    inp = InputParameter(nq)
    inp.current_position = q0
    inp.current_velocity = zeros if v0 is None else robot.check_q(v0, "v0")
    inp.current_acceleration = zeros if a0 is None else robot.check_q(a0, "a0")
    inp.target_position = q1
    inp.target_velocity = zeros if v1 is None else robot.check_q(v1, "v1")
    inp.target_acceleration = zeros if a1 is None else robot.check_q(a1, "a1")

    def lim(arr, q, big):
        out = np.where(np.isfinite(arr), arr, big) * factors.get(q, 1.0)
        return out

    inp.max_velocity = lim(robot.velocity_limits, "velocity", 1e3)
    inp.max_acceleration = lim(robot.acceleration_limits, "acceleration", 1e4)
    inp.max_jerk = lim(robot.jerk_limits, "jerk", 1e6)
    sync = {"phase": Synchronization.Phase, "time": Synchronization.Time, "none": Synchronization.No}
    if synchronization not in sync:
        raise InvalidArgument(f"synchronization must be one of {sorted(sync)}, got {synchronization!r}")
    inp.synchronization = sync[synchronization]
    otg = Ruckig(nq)
    out = RTrajectory(nq)
    try:
        result = otg.calculate(inp, out)
    except RuntimeError as exc:  # ruckig raises on invalid input (limits, states)
        raise InfeasibleTrajectory("ruckig", str(exc)) from exc
    if result not in (Result.Working, Result.Finished):
        raise InfeasibleTrajectory("ruckig", f"ruckig returned {result}")
    traj = _from_ruckig(out, robot)
    ext = out.position_extrema
    lo = np.array([e.min for e in ext])
    hi = np.array([e.max for e in ext])
    bad = ((lo < robot.lower - 1e-12) | (hi > robot.upper + 1e-12)) & ~robot.continuous
    if np.any(bad):
        j = int(np.argmax(bad))
        raise InfeasibleTrajectory(
            "ruckig", f"the jerk-limited motion takes joint {robot.joint_names[j]!r} to "
            f"[{lo[j]:.6g}, {hi[j]:.6g}], outside [{robot.lower[j]:.6g}, {robot.upper[j]:.6g}] "
            "(ruckig's community edition ignores position limits): start with less velocity "
            "towards the limit or choose a target further from it")
    return traj


def _from_ruckig(out, robot, t_start: float = 0.0) -> Trajectory:
    duration = out.duration
    profiles = out.profiles[0]
    polys = [_profile_ppoly(profiles[j], t_start, duration) for j in range(robot.nq)]
    return Trajectory(merge_ppolys(polys), None, tuple(robot.joint_names), "ruckig", {})


_BIG = {"velocity": 1e3, "acceleration": 1e4, "jerk": 1e6}
"""stand-ins for an undeclared (infinite) limit, as :func:`ruckig_state_to_state` uses them."""


def _line_limits(limits: dict, deltas: np.ndarray, factors) -> np.ndarray:
    """Limits ``(M, 3)`` of the segment parameter ``s`` for ``q = q_a + s·Δ`` per row of
    ``deltas (M, nq)``: ``|q̇_j| = |ṡ||Δ_j| <= v_j`` for every j  ⇔  ``|ṡ| <= min_j v_j / |Δ_j|``
    (the same for ``s̈`` and the jerk), columns velocity, acceleration, jerk.
    ``limits``: ``{"velocity", "acceleration", "jerk"}`` -> ``(nq,)``."""
    size = np.abs(deltas)
    out = np.empty((len(deltas), 3))
    with np.errstate(divide="ignore"):
        for k, q in enumerate(("velocity", "acceleration", "jerk")):
            arr = np.asarray(limits[q], dtype=float)
            lim = np.where(np.isfinite(arr), arr, _BIG[q]) * factors.get(q, 1.0)
            out[:, k] = np.min(np.where(size > 0.0, lim / size, np.inf), axis=1)
    return out


def _ruckig_line(line_limits: np.ndarray, q_a: np.ndarray, q_b: np.ndarray) -> PPoly:
    """Rest-to-rest, jerk-limited, time-optimal motion along the straight segment ``q_a -> q_b``.

    A one-dimensional ruckig profile of ``s: 0 -> 1`` under ``line_limits`` (the velocity,
    acceleration and jerk limits of ``s``, :func:`_line_limits`), composed with
    ``q(t) = q_a + s(t) (q_b - q_a)``: every configuration lies on the segment (exactly, up to
    rounding), and no motion along the segment is faster under the joints' box limits (they
    become exactly the limits of ``s``). Rest to rest, the profile is monotone, so ``s`` stays
    in ``[0, 1]``.
    """
    from ruckig import InputParameter, Result, Ruckig
    from ruckig import Trajectory as RTrajectory

    delta = q_b - q_a
    inp = InputParameter(1)
    inp.current_position, inp.target_position = [0.0], [1.0]
    inp.current_velocity = inp.current_acceleration = inp.target_velocity = inp.target_acceleration = [0.0]
    vs, as_, js = (float(x) for x in line_limits)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [vs], [as_], [js]
    out = RTrajectory(1)
    try:
        result = Ruckig(1).calculate(inp, out)
    except RuntimeError as exc:  # ruckig raises on invalid input (limits, states)
        raise InfeasibleTrajectory("ruckig", str(exc)) from exc
    if result not in (Result.Working, Result.Finished):
        raise InfeasibleTrajectory("ruckig", f"ruckig returned {result} on a straight segment")
    s = _profile_ppoly(out.profiles[0][0], 0.0, out.duration)  # cubic pieces of s(t)
    c = s.c[:, :, None] * delta[None, None, :]
    c[-1] += q_a  # constant term: q_a + s_0 Δ
    return PPoly.construct_fast(c, s.x)


def _ruckig_path(W, robot, factors, limits: dict) -> Trajectory:
    """Rest-to-rest straight segments through every waypoint (:func:`_ruckig_line`) under
    ``limits`` (``{"velocity", "acceleration", "jerk"}`` -> ``(nq,)``), concatenated in time."""
    xs, cs = [], []
    t = 0.0
    line_limits = _line_limits(limits, np.diff(W, axis=0), factors)
    for k in range(len(W) - 1):
        pp = _ruckig_line(line_limits[k], W[k], W[k + 1])
        xs.append(pp.x + t)
        cs.append(pp.c)
        t += pp.x[-1] - pp.x[0]
    x = np.concatenate([xs[0]] + [x_k[1:] for x_k in xs[1:]])
    c = np.concatenate(cs, axis=1)
    times = np.array([0.0] + [x_k[-1] for x_k in xs])
    return Trajectory(PPoly(c, x), None, tuple(robot.joint_names), "ruckig",
                      {"segments": len(xs), "on_path": np.array(W, dtype=float), "waypoint_times": times})
