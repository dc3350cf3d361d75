"""Turning what users pass to the viewers into checked arrays.

Accepted inputs (see :func:`as_motion`):

* a configuration ``q (nq,)``, or any object with a ``.q`` attribute (an ``IKResult``);
* a trajectory: a pair ``(t (K,), Q (K, nq))``, an object with ``.t`` and ``.Q`` attributes,
  a mapping with keys ``t``/``Q`` or ``traj_t``/``traj_q`` (a study record's arrays), a
  :class:`drake_mh.trajectories.Trajectory` (anything with ``start_time``, ``end_time`` and
  ``position(t) -> (K, nq)``) or a Drake ``Trajectory`` (e.g. ``PiecewisePolynomial``); the
  last two are sampled at the animation rate.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument, InvalidConfiguration, InvalidTrajectory

__all__ = ["Motion", "as_motion", "check_trajectory", "resample", "as_point", "as_pose"]


@dataclass(frozen=True)
class Motion:
    """A checked configuration or trajectory.

    Attributes:
        t: times ``(K,)`` [s], strictly increasing; ``None`` for a single configuration.
        Q: configurations ``(K, nq)`` (``K = 1`` for a single configuration).
    """

    t: np.ndarray | None
    Q: np.ndarray

    @property
    def is_trajectory(self) -> bool:
        """Whether this is a trajectory (has times) rather than one configuration."""
        return self.t is not None

    @property
    def q(self) -> np.ndarray:
        """The first configuration ``(nq,)``."""
        return self.Q[0]


def check_trajectory(robot, t, Q) -> tuple[np.ndarray, np.ndarray]:
    """Check a sampled trajectory and return ``t (K,)``, ``Q (K, nq)`` as float arrays.

    Raises:
        InvalidTrajectory: ``t`` is not 1-D, finite and strictly increasing, or its length
            differs from the number of rows of ``Q``.
        InvalidConfiguration: ``Q`` is not ``(K, nq)`` for this robot or is not finite.
    """
    try:
        t = np.asarray(t, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidTrajectory(f"times t must be numbers [s], got {t!r}", "t") from exc
    if t.ndim != 1 or t.size == 0:
        raise InvalidTrajectory(f"times t must have shape (K,) with K >= 1, got shape {t.shape}", "t")
    if not np.all(np.isfinite(t)):
        raise InvalidTrajectory("times t contain NaN or inf", "t")
    if t.size > 1 and np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise InvalidTrajectory(
            f"times t must be strictly increasing; t[{k}] = {t[k]:g} >= t[{k + 1}] = {t[k + 1]:g} "
            "(sort the samples and drop duplicates)", "t")
    try:
        Q = np.asarray(Q, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidConfiguration("Q must be numeric, shape (K, nq)", "Q") from exc
    if Q.ndim != 2:
        raise InvalidConfiguration(
            f"Q must have shape (K, {robot.nq}) = (len(t), nq) for {robot.name}, got shape {Q.shape}",
            "Q", f"({t.size}, {robot.nq})", Q.shape)
    if Q.shape[0] != t.size:
        raise InvalidTrajectory(
            f"t has {t.size} samples but Q has {Q.shape[0]} rows; give one configuration per time "
            f"(Q of shape ({t.size}, {robot.nq}))", "Q", expected=(t.size, robot.nq), got=Q.shape)
    return t, robot.check_Q(Q, "Q")


def as_motion(robot, value, sample_rate: float = 30.0) -> Motion:
    """Interpret ``value`` as one configuration or a trajectory of ``robot`` (see module doc).

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        value: what to show.
        sample_rate: samples per second [Hz] for Drake ``Trajectory`` objects.

    Raises:
        InvalidConfiguration, InvalidTrajectory: wrong shapes or values.
        InvalidArgument: ``value`` is none of the accepted kinds.
    """
    if isinstance(value, Motion):
        return value
    if isinstance(value, Mapping):
        for kt, kq in (("t", "Q"), ("traj_t", "traj_q")):
            if kt in value and kq in value:
                return Motion(*check_trajectory(robot, value[kt], value[kq]))
        if "q" in value:
            return Motion(None, robot.check_q(value["q"])[None, :])
        raise InvalidArgument(f"a mapping to show needs keys ('t', 'Q'), ('traj_t', 'traj_q') or 'q'; "
                              f"got keys {sorted(map(str, value))}")
    if hasattr(value, "t") and hasattr(value, "Q"):
        return Motion(*check_trajectory(robot, value.t, value.Q))
    if callable(getattr(value, "position", None)) and hasattr(value, "start_time") and hasattr(value, "end_time"):
        return _from_position_function(robot, value, sample_rate)
    if hasattr(value, "vector_values") and hasattr(value, "start_time") and hasattr(value, "end_time"):
        return _from_drake_trajectory(robot, value, sample_rate)
    if hasattr(value, "q") and not isinstance(value, np.ndarray):
        return Motion(None, robot.check_q(value.q)[None, :])
    if isinstance(value, tuple) and len(value) == 2 and np.ndim(value[0]) >= 1 and np.ndim(value[1]) >= 1:
        return Motion(*check_trajectory(robot, value[0], value[1]))
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(_WHAT_TO_PASS.format(got=type(value).__name__)) from exc
    if arr.ndim == 2:
        raise InvalidTrajectory(
            f"got configurations Q {arr.shape} without times; pass (t, Q), e.g. "
            f"(numpy.linspace(0, duration, {arr.shape[0]}), Q)", "t")
    if arr.ndim == 1:
        return Motion(None, robot.check_q(arr)[None, :])
    raise InvalidArgument(_WHAT_TO_PASS.format(got=f"an array of shape {arr.shape}"))


_WHAT_TO_PASS = ("cannot show {got}: pass a configuration q (nq,), an object with .q (an IK result), "
                 "a trajectory (t (K,), Q (K, nq)), an object with .t and .Q, or a Drake Trajectory")


def _sample_times(t0: float, t1: float, sample_rate: float) -> np.ndarray:
    if not (np.isfinite(t0) and np.isfinite(t1) and t1 >= t0):
        raise InvalidTrajectory(f"the trajectory's time span [{t0}, {t1}] s is not a finite interval", "trajectory")
    n = max(2, int(np.ceil((t1 - t0) * sample_rate)) + 1)
    return np.linspace(t0, t1, n) if t1 > t0 else np.array([t0])


def _value(attribute) -> float:
    return float(attribute() if callable(attribute) else attribute)


def _from_position_function(robot, traj, sample_rate: float) -> Motion:
    """drake_mh's ``Trajectory``: ``start_time``/``end_time`` [s] and ``position(t) -> (K, nq)``."""
    t = _sample_times(_value(traj.start_time), _value(traj.end_time), sample_rate)
    Q = np.asarray(traj.position(t), dtype=float)
    if Q.shape != (t.size, robot.nq):
        raise InvalidTrajectory(
            f"trajectory.position(t) gave shape {Q.shape} for {t.size} times; expected ({t.size}, "
            f"{robot.nq}) joint positions of {robot.name}", "trajectory", (t.size, robot.nq), Q.shape)
    return Motion(*check_trajectory(robot, t, Q))


def _from_drake_trajectory(robot, traj, sample_rate: float) -> Motion:
    t0, t1 = float(traj.start_time()), float(traj.end_time())
    if traj.rows() != robot.nq or traj.cols() != 1:
        raise InvalidTrajectory(
            f"the Drake trajectory has values of shape ({traj.rows()}, {traj.cols()}); "
            f"expected ({robot.nq}, 1) joint positions of {robot.name}", "trajectory")
    t = _sample_times(t0, t1, sample_rate)
    Q = np.asarray(traj.vector_values(t)).T.reshape(t.size, robot.nq)
    return Motion(*check_trajectory(robot, t, Q))


def resample(t: np.ndarray, Q: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """Sample a trajectory at ``fps`` [Hz] from ``t[0]``, joint-wise linear in between.

    Returns:
        ``times (F,)`` relative to ``t[0]`` (``0, 1/fps, ...``, the last one is ``t[-1] - t[0]``)
        and ``Q_frames (F, nq)``. Meshcat interpolates between key frames link by link, which
        is not forward kinematics; sampling every frame keeps the animation exact at the
        frame rate.
    """
    duration = float(t[-1] - t[0])
    n = int(np.floor(duration * fps + 1e-9)) + 1
    times = np.arange(n) / fps
    if times[-1] < duration - 1e-9:
        times = np.append(times, duration)
    Q_frames = np.column_stack([np.interp(times + t[0], t, Q[:, j]) for j in range(Q.shape[1])])
    return times, Q_frames


def as_point(value, what: str) -> np.ndarray:
    """``p (3,)`` from a point, or the translation of a pose ``(4, 4)``; raises InvalidArgument."""
    arr = _finite(value, what)
    if arr.shape == (4, 4):
        return arr[:3, 3].copy()
    if arr.shape != (3,):
        raise InvalidArgument(f"{what} must be a point (3,) or a pose (4, 4) [m], got shape {arr.shape}")
    return arr


def as_pose(value, what: str) -> np.ndarray:
    """``X (4, 4)`` from a pose or a point ``(3,)`` (identity rotation); raises InvalidArgument."""
    arr = _finite(value, what)
    if arr.shape == (3,):
        X = np.eye(4)
        X[:3, 3] = arr
        return X
    if arr.shape != (4, 4):
        raise InvalidArgument(f"{what} must be a pose (4, 4) or a point (3,) [m], got shape {arr.shape}")
    return arr


def _finite(value, what: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{what} must be numbers, got {value!r}") from exc
    if not np.all(np.isfinite(arr)):
        raise InvalidArgument(f"{what} contains NaN or inf")
    return arr
