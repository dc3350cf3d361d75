"""Trapezoidal-velocity Cartesian paths through stop points (framework paper §3.3, Table 3).

The framework paper generates "the 3D path ... using trapezoidal velocity profile ... based
on the start / end point, and the intermediate points" with a user-given total number of
points (§3.3, §4, GUI part 2), and calls the intermediate points "intermediate stop points"
(§3.4.2). Our reading, stated here and in ``docs/trajectories.md``:

* the points are visited in the order start → intermediate 1 → intermediate 2 → ... → end;
  in Table 3 "Start / End Point" (0.2, 0.8, 0.3) is one point that is both the start and the
  end, so the path is a closed loop start → (1.0, 0.2, 0.2) → (0.5, 0.4, 0.1) → start;
* consecutive points are joined by straight segments, and the tool **stops** at every
  intermediate point: each segment has its own rest-to-rest trapezoidal speed profile
  (accelerate at ``a_max``, cruise at ``v_max``, decelerate; a triangle when the segment is
  too short to reach ``v_max``) — the paper gives no speed or acceleration, the defaults are
  our choices;
* the ``N`` points sample time: each segment gets a share of the ``N - 1`` intervals
  proportional to its duration (largest remainders, at least one), uniformly in time within
  the segment, so that every start/intermediate/end point is itself one of the ``N`` points
  and the spacing follows the trapezoidal speed (dense where the tool is slow).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["TrapezoidalProfile", "CartesianPath", "trapezoidal_path", "TABLE3_POINTS"]

#: framework paper, Table 3: start/end, intermediate 1, intermediate 2 (metres, see docs/robots.md)
TABLE3_POINTS = ((0.2, 0.8, 0.3), (1.0, 0.2, 0.2), (0.5, 0.4, 0.1), (0.2, 0.8, 0.3))


@dataclass(frozen=True)
class TrapezoidalProfile:
    """Rest-to-rest trapezoidal speed profile along one straight segment of length ``L`` [m].

    Attributes:
        v_max: cruise speed [m/s] (default 0.25, our choice).
        a_max: acceleration and deceleration [m/s²] (default 0.5, our choice).
    """

    v_max: float = 0.25
    a_max: float = 0.5

    def __post_init__(self):
        for name in ("v_max", "a_max"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise InvalidArgument(f"{name} must be a positive number, got {v!r}")

    def duration(self, length: float) -> float:
        """Time [s] to travel ``length`` [m] from rest to rest."""
        if length <= 0:
            return 0.0
        if length >= self.v_max ** 2 / self.a_max:  # trapezoid: reaches v_max
            return length / self.v_max + self.v_max / self.a_max
        return 2.0 * np.sqrt(length / self.a_max)  # triangle

    def distance(self, t, length: float) -> np.ndarray:
        """Distance travelled ``s(t)`` [m] at times ``t ∈ [0, duration]`` (clipped outside)."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration(length))
        if length <= 0:
            return np.zeros_like(t)
        v = min(self.v_max, np.sqrt(length * self.a_max))  # peak speed
        ta = v / self.a_max
        T = self.duration(length)
        return np.where(t < ta, 0.5 * self.a_max * t ** 2,
                        np.where(t <= T - ta, 0.5 * v * ta + v * (t - ta),
                                 length - 0.5 * self.a_max * (T - t) ** 2))

    def speed(self, t, length: float) -> np.ndarray:
        """Speed ``ṡ(t)`` [m/s]."""
        T = self.duration(length)
        t = np.clip(np.asarray(t, dtype=float), 0.0, T)
        if length <= 0:
            return np.zeros_like(t)
        v = min(self.v_max, np.sqrt(length * self.a_max))
        return np.minimum(np.minimum(self.a_max * t, v), self.a_max * (T - t))


@dataclass(frozen=True)
class CartesianPath:
    """``N`` points of a trapezoidal-velocity path.

    Attributes:
        points: ``(N, 3)`` positions ``p_W`` [m].
        times: ``(N,)`` [s], non-decreasing, from 0.
        speeds: ``(N,)`` path speed [m/s] (0 at every stop point).
        segment: ``(N,)`` index of the segment each point belongs to (a stop point belongs to
            the segment it ends; the start to segment 0).
        stop_indices: ``(K,)`` indices in ``points`` of the given start / intermediate / end points.
        waypoints: ``(K, 3)`` the given points.
    """

    points: np.ndarray
    times: np.ndarray
    speeds: np.ndarray
    segment: np.ndarray
    stop_indices: np.ndarray
    waypoints: np.ndarray

    @property
    def duration(self) -> float:
        """Total time [s]."""
        return float(self.times[-1])

    @property
    def length(self) -> float:
        """Total path length [m]."""
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())

    def __len__(self) -> int:
        return len(self.points)


def _allocate(durations: np.ndarray, intervals: int) -> np.ndarray:
    """Split ``intervals`` among segments proportionally to ``durations`` (largest remainders, >= 1)."""
    share = durations / durations.sum() * intervals
    n = np.maximum(np.floor(share).astype(int), 1)
    while n.sum() > intervals:  # minimums pushed it over: take from the largest
        n[np.argmax(n)] -= 1
    rest = share - np.floor(share)
    for i in np.argsort(-rest):
        if n.sum() >= intervals:
            break
        n[i] += 1
    return n


def trapezoidal_path(points=TABLE3_POINTS, n_points: int = 50,
                     profile: TrapezoidalProfile = TrapezoidalProfile()) -> CartesianPath:
    """Straight segments through the stop points, each with a trapezoidal speed profile.

    Args:
        points: ``(K >= 2, 3)`` start, intermediate and end points [m], in visiting order
            (default: Table 3 of the framework paper, a closed loop; see the module docstring).
        n_points: total number of points ``N`` (Table 3: 50), at least ``K``.
        profile: speed and acceleration of the tool.

    Returns:
        A :class:`CartesianPath` whose points include every given point exactly.

    Raises:
        InvalidArgument: bad shapes, non-finite values, ``N < K``, or two consecutive equal points.
    """
    try:
        P = np.array(points, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument("points must be a numeric (K, 3) array") from exc
    if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 2:
        raise InvalidArgument(f"points must have shape (K >= 2, 3), got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise InvalidArgument("points contain NaN or inf")
    if isinstance(n_points, bool) or int(n_points) != n_points or n_points < len(P):
        raise InvalidArgument(f"n_points must be an integer >= the {len(P)} given points, got {n_points!r}")
    lengths = np.linalg.norm(np.diff(P, axis=0), axis=1)
    if np.any(lengths <= 1e-12):
        i = int(np.argmax(lengths <= 1e-12))
        raise InvalidArgument(f"points {i} and {i + 1} are equal: remove the repeated point")
    durations = np.array([profile.duration(L) for L in lengths])
    per_segment = _allocate(durations, int(n_points) - 1)
    pts, times, speeds, seg, stops = [P[:1]], [np.zeros(1)], [np.zeros(1)], [np.zeros(1, int)], [0]
    t0 = 0.0
    for i, (L, T, n) in enumerate(zip(lengths, durations, per_segment)):
        t = np.linspace(0.0, T, n + 1)[1:]
        u = (P[i + 1] - P[i]) / L
        s = profile.distance(t, L)
        seg_pts = P[i] + s[:, None] * u
        seg_pts[-1] = P[i + 1]  # land exactly on the stop point
        pts.append(seg_pts)
        times.append(t0 + t)
        speeds.append(profile.speed(t, L))
        seg.append(np.full(n, i))
        t0 += T
        stops.append(stops[-1] + n)
    return CartesianPath(np.vstack(pts), np.concatenate(times), np.concatenate(speeds), np.concatenate(seg),
                         np.array(stops), P)
