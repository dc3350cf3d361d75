"""Joint trajectories ``q(t)`` with exact derivatives up to jerk.

One class covers every trajectory the library returns:

* a time-parameterized path ``q(t) = p(s(t))`` (toppra, Drake ``Toppra``): ``p`` is a
  piecewise polynomial in the path parameter ``s`` (a cubic spline through the waypoints)
  and ``s(t)`` a piecewise polynomial in time (quadratic for toppra's constant-acceleration
  parameterization, cubic for Drake's);
* a piecewise polynomial directly in time (ruckig's jerk-limited profiles, the ABC paper's
  via-point polynomials): ``timing`` is ``None`` and ``s = t``.

Derivatives come from the chain rule (no finite differences), so :func:`certify` can sample
velocity, acceleration and jerk anywhere:

    q'   = p' s'
    q''  = p'' s'^2 + p' s''
    q''' = p''' s'^3 + 3 p'' s' s'' + p' s'''

Times where a derivative may jump (segment ends of ``p`` mapped to time, segment ends of
``s``) are :attr:`Trajectory.breaks`; one-sided values there are available with
:meth:`Trajectory.evaluate_piece`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import PPoly

from drake_mh._support.native import compiled_core
from drake_mh.errors import InvalidArgument
from drake_mh.trajectories.polynomials import shift_coefficients

__all__ = ["Trajectory", "merge_ppolys"]


def _as_ppoly(poly, what: str) -> PPoly:
    if not isinstance(poly, PPoly):
        raise InvalidArgument(f"{what} must be a scipy.interpolate.PPoly (or CubicSpline), got {type(poly)!r}")
    return poly


def merge_ppolys(polys: list[PPoly]) -> PPoly:
    """Stack scalar piecewise polynomials with different breakpoints into one vector ``PPoly``.

    Every polynomial is re-expanded exactly on the union of the breakpoints (used for ruckig,
    whose degrees of freedom switch phases at different times).

    Args:
        polys: ``n`` scalar ``PPoly`` over the same interval ``[x0, x1]``.

    Returns:
        ``PPoly`` with values ``(n,)`` and the union of the breakpoints.
    """
    x0, x1 = polys[0].x[0], polys[0].x[-1]
    breaks = np.unique(np.concatenate([p.x for p in polys]))
    # drop breaks closer than 1e-12 s (they come from rounding of the same switch time)
    keep = np.r_[True, np.diff(breaks) > 1e-12]
    breaks = breaks[keep]
    breaks[0], breaks[-1] = x0, x1
    k = max(p.c.shape[0] for p in polys) - 1
    c = np.zeros((k + 1, len(breaks) - 1, len(polys)))
    mids = 0.5 * (breaks[:-1] + breaks[1:])
    for j, p in enumerate(polys):
        idx = np.clip(np.searchsorted(p.x, mids, side="right") - 1, 0, len(p.x) - 2)
        ck = np.zeros((k + 1, len(idx)))
        ck[k + 1 - p.c.shape[0]:] = p.c[:, idx]
        shift = breaks[:-1] - p.x[idx]
        for i in range(len(idx)):
            c[:, i, j] = shift_coefficients(ck[:, i], shift[i])
    return PPoly(c, breaks)


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A joint trajectory ``q(t) = path(s(t))``, ``t ∈ [0, duration]``.

    Attributes:
        path: ``PPoly`` ``s -> q (nq,)`` [rad]; its first three derivatives are used.
        timing: ``PPoly`` ``t -> s`` (non-decreasing), or ``None`` when ``path`` is already a
            function of time [s].
        joint_names: ``(nq,)`` names, for messages.
        method: how it was made (``"toppra"``, ``"ruckig"``, ``"drake-toppra"``, ``"viapoint"``).
        info: extra data (solver times, gridpoints, the certificate ...). Mutable on purpose.
    """

    path: PPoly
    timing: PPoly | None = None
    joint_names: tuple[str, ...] = ()
    method: str = ""
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        _as_ppoly(self.path, "path")
        if self.timing is not None:
            _as_ppoly(self.timing, "timing")
        if self.path.c.ndim != 3:
            raise InvalidArgument("path must be vector valued: PPoly with coefficients (k, m, nq)")
        if not self.joint_names:
            object.__setattr__(self, "joint_names", tuple(f"joint{i + 1}" for i in range(self.nq)))
        elif len(self.joint_names) != self.nq:
            raise InvalidArgument(f"{len(self.joint_names)} joint names for a path with {self.nq} joints")

    # --- basic properties -----------------------------------------------------------------------

    @functools.cached_property
    def nq(self) -> int:
        """Number of joints."""
        return int(self.path.c.shape[2])

    @functools.cached_property
    def start_time(self) -> float:
        """Start time [s] (0 for every trajectory the library makes)."""
        return float((self.timing or self.path).x[0])

    @functools.cached_property
    def end_time(self) -> float:
        """End time [s]."""
        return float((self.timing or self.path).x[-1])

    @property
    def duration(self) -> float:
        """``end_time - start_time`` [s]."""
        return self.end_time - self.start_time

    @functools.cached_property
    def breaks(self) -> np.ndarray:
        """Times [s] where derivatives may be discontinuous, both ends included, sorted."""
        if self.timing is None:
            return self.path.x.copy()
        t = [self.timing.x]
        s_at = self.timing(self.timing.x)
        knots = self.path.x[(self.path.x > s_at[0]) & (self.path.x < s_at[-1])]
        # path knots that are already timing breaks (toppra's gridpoints include them) are skipped
        j = np.clip(np.searchsorted(s_at, knots), 1, len(s_at) - 1)
        near = np.minimum(np.abs(s_at[j] - knots), np.abs(s_at[j - 1] - knots))
        knots = knots[near > 1e-12 * max(1.0, abs(s_at[-1]))]
        if len(knots):
            t.append(self._invert_timing(knots))
        out = np.unique(np.concatenate(t))
        return out[np.r_[True, np.diff(out) > 1e-12]]

    def time_scaled(self, factor: float) -> Trajectory:
        """The same path run ``factor`` times as fast: ``q_new(t) = q(factor t)``.

        ``factor < 1`` slows down: velocity scales by ``factor``, acceleration by ``factor²``,
        jerk by ``factor³``; the torque ``factor² (M q̈ + C q̇) + g`` stays between its old
        value and the gravity torque, so a slowed-down trajectory never needs more torque
        than the larger of the two.
        """
        if not (factor > 0 and np.isfinite(factor)):
            raise InvalidArgument(f"factor must be positive and finite, got {factor}")
        pp = self.path if self.timing is None else self.timing
        k = pp.c.shape[0] - 1
        powers = factor ** np.arange(k, -1, -1, dtype=float)  # c[m] multiplies y^(k-m)
        shape = (k + 1,) + (1,) * (pp.c.ndim - 1)
        scaled = PPoly(pp.c * powers.reshape(shape), pp.x / factor)
        info = dict(self.info)
        info.pop("certificate", None)
        if "waypoint_times" in info:  # ruckig's rests at the waypoints come 1 / factor later
            info["waypoint_times"] = np.asarray(info["waypoint_times"], dtype=float) / factor
        if self.timing is None:
            return Trajectory(scaled, None, self.joint_names, self.method, info)
        return Trajectory(self.path, scaled, self.joint_names, self.method, info)

    def _invert_timing(self, s: np.ndarray) -> np.ndarray:
        """First times where the (non-decreasing) timing reaches each ``s`` (bisection, vectorized)."""
        lo = np.full(len(s), self.start_time)
        hi = np.full(len(s), self.end_time)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            below = self.timing(mid) < s
            lo = np.where(below, mid, lo)
            hi = np.where(below, hi, mid)
        return 0.5 * (lo + hi)

    # --- evaluation -------------------------------------------------------------------------------

    def _check_times(self, t) -> np.ndarray:
        """``t`` as a float array within ``[start_time, end_time]``, or :class:`InvalidArgument`.

        A polynomial evaluated past its last piece extrapolates (measured: -48,000 rad a few
        seconds after a toppra trajectory's end), so times outside the trajectory are refused;
        round-off of ``1e-9 · duration`` beyond an end is clipped onto it.
        """
        try:
            t = np.atleast_1d(np.asarray(t, dtype=float))
        except (TypeError, ValueError):
            raise InvalidArgument(f"times must be numbers [s], got {t!r}") from None
        if not t.size:
            return t
        low, high = t.min(), t.max()  # NaN in t makes both NaN
        if not (np.isfinite(low) and np.isfinite(high)):
            raise InvalidArgument("times must be finite numbers [s]")
        t0, t1 = self.start_time, self.end_time
        if low >= t0 and high <= t1:
            return t
        slack = 1e-9 * max(t1 - t0, 1.0)
        if low < t0 - slack or high > t1 + slack:
            raise InvalidArgument(
                f"times must lie within the trajectory [{t0:g}, {t1:g}] s; got {low:g} .. {high:g} s "
                "(hold the end state yourself, e.g. traj(min(t, traj.end_time)), if that is meant)")
        return np.clip(t, t0, t1)

    @functools.cached_property
    def _compiled(self):
        """``(core, path c, path x, timing c, timing x)`` as contiguous float64 arrays for the
        compiled core's ``timed_derivatives``, or ``None`` (no core, or breakpoints not increasing)."""
        core = compiled_core()
        polys = (self.path,) if self.timing is None else (self.path, self.timing)
        if core is None or any(not np.all(np.diff(p.x) > 0) for p in polys):
            return None
        arrays = [np.ascontiguousarray(a, dtype=float) for p in polys for a in (p.c, p.x)]
        return (core, *arrays) if self.timing is not None else (core, *arrays, None, None)

    def derivatives(self, t, order: int = 3) -> list[np.ndarray]:
        """``[q, q', ..., q^(order)]``, each ``(len(t), nq)``, at times ``t`` [s].

        At a break the value of the piece to the right is returned (scipy's convention);
        use :meth:`evaluate_piece` for one-sided values. Evaluated in the compiled core where it
        is built (the same pieces and chain rule as scipy's ``PPoly``), else by scipy.
        """
        t = self._check_times(t)
        if order < 0 or order > 3:
            raise InvalidArgument(f"order must be 0..3, got {order}")
        core = self._compiled
        if core is not None:  # the compiled core: the same pieces and chain rule, one pass
            return list(core[0].timed_derivatives(*core[1:], t, int(order)))
        if self.timing is None:
            return [self.path(t, nu=k) for k in range(order + 1)]
        s = [self.timing(t, nu=k) for k in range(order + 1)]
        p = [self.path(s[0], nu=k) for k in range(order + 1)]
        out = [p[0]]
        if order >= 1:
            out.append(p[1] * s[1][:, None])
        if order >= 2:
            out.append(p[2] * (s[1] ** 2)[:, None] + p[1] * s[2][:, None])
        if order >= 3:
            out.append(p[3] * (s[1] ** 3)[:, None] + 3.0 * p[2] * (s[1] * s[2])[:, None]
                       + p[1] * s[3][:, None])
        return out

    def __call__(self, t, derivative: int = 0) -> np.ndarray:
        """``q^(derivative)(t)``: ``(nq,)`` for a scalar ``t``, else ``(len(t), nq)``."""
        scalar = np.ndim(t) == 0
        value = self.derivatives(t, derivative)[derivative]
        return value[0] if scalar else value

    def position(self, t) -> np.ndarray:
        """``q(t)`` [rad]."""
        return self(t, 0)

    def velocity(self, t) -> np.ndarray:
        """``q'(t)`` [rad/s]."""
        return self(t, 1)

    def acceleration(self, t) -> np.ndarray:
        """``q''(t)`` [rad/s²]."""
        return self(t, 2)

    def jerk(self, t) -> np.ndarray:
        """``q'''(t)`` [rad/s³] (within pieces; see :meth:`acceleration_jumps`)."""
        return self(t, 3)

    def evaluate_piece(self, t0: float, t1: float, tau, order: int = 3) -> list[np.ndarray]:
        """Derivatives on one piece ``[t0, t1]`` at ``t0 + tau (t1 - t0)``, ends taken one-sided.

        Args:
            t0, t1: consecutive :attr:`breaks` [s].
            tau: ``(K,)`` fractions in ``[0, 1]``.
            order: highest derivative.
        """
        tau = np.clip(np.asarray(tau, dtype=float), 0.0, 1.0)
        h = t1 - t0
        # pull the ends inside the piece by a relative 1e-9 so the piece's own polynomial is used
        eps = 1e-9 * h
        t = np.clip(t0 + tau * h, t0 + eps, t1 - eps)
        return self.derivatives(t, order)

    def sample_uniform(self, n: int = 200) -> tuple[np.ndarray, np.ndarray]:
        """``(t (n,), q (n, nq))`` at ``n`` evenly spaced times, both ends included (for plots
        and studies; :meth:`sample` for a controller)."""
        t = np.linspace(self.start_time, self.end_time, int(n))
        return t, self.derivatives(t, 0)[0]

    def sample(self, rate_hz: float = 100.0, robot=None):
        """Samples at ``rate_hz`` [Hz] for a controller: a
        :class:`~drake_mh.trajectories.export.TrajectorySamples` of ``t (N,)`` [s] from 0 (the
        last exactly at the end), ``q, qd, qdd (N, nq)`` and, with the ``robot``, the torques
        ``tau (N, nq)`` [N·m], gravity included (:func:`~drake_mh.trajectories.export.sample_trajectory`).

        Raises:
            InvalidArgument: a rate that is not a positive number.
        """
        from drake_mh.trajectories.export import sample_trajectory

        return sample_trajectory(self, rate_hz, robot)

    def save(self, path, robot=None, rate_hz: float = 100.0):
        """Write the samples at ``rate_hz`` to ``path`` by its extension: ``.json`` / ``.yaml``
        (ROS 2 ``JointTrajectory`` shape), ``.csv``; checked against the certified limits first
        (:func:`~drake_mh.trajectories.export.save_trajectory`). Returns the samples.

        Raises:
            InvalidArgument: unknown extension or bad rate.
            LimitViolation: a sample exceeds a certified limit.
        """
        from drake_mh.trajectories.export import save_trajectory

        return save_trajectory(self, path, robot, rate_hz)

    def to_drake(self):
        """This trajectory as a pydrake ``PiecewisePolynomial`` made of its exact polynomial
        pieces (:func:`~drake_mh.trajectories.export.to_drake`)."""
        from drake_mh.trajectories.export import to_drake

        return to_drake(self)

    def acceleration_jumps(self) -> tuple[np.ndarray, np.ndarray]:
        """Acceleration discontinuities: ``(times (B,), |Δq''| (B, nq))`` at the interior breaks.

        A jump makes the jerk a Dirac impulse there (toppra's constant-acceleration
        parameterization jumps at every gridpoint; ruckig and the via-point polynomials do not).
        """
        b = self.breaks[1:-1]
        if len(b) == 0:
            return b, np.zeros((0, self.nq))
        eps = 1e-12 * max(self.duration, 1.0)  # jerk x 2 eps stays far below a real jump
        left = self.derivatives(b - eps, 2)[2]
        right = self.derivatives(b + eps, 2)[2]
        return b, np.abs(right - left)

    def __repr__(self) -> str:
        return (f"Trajectory(method={self.method!r}, nq={self.nq}, duration={self.duration:.6g} s, "
                f"{len(self.breaks) - 1} pieces)")
