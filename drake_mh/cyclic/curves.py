"""Periodic planar curves: end-effector paths and moving bases of the cyclic paper.

A :class:`PeriodicCurve` maps time ``t`` [s] to points ``p_W (N, 2)`` [m] in the arm's
plane (world x-y) and repeats with :attr:`PeriodicCurve.period` ``T`` [s]. The cyclic
paper's method needs every moving base to have the end-effector path's period (its
Sec. III.B, step 1a), so that constant orientation angles give periodic joint angles.

Curves given by users:

* :class:`Lissajous` — ``x = c_x + a_x sin(n_x Ω t + φ_x)``, ``y = c_y + a_y sin(n_y Ω t + φ_y)``,
  ``Ω = 2π/T`` (the paper's Table III);
* :class:`Circle` — eq. (24) of the paper (5-DOF case);
* :class:`MapleLeaf` — the Japanese maple leaf of eq. (26) (12-DOF case);
* :class:`FunctionCurve` — any vectorized callable ``t (N,) -> (N, 2)``;
* :class:`SampledCurve` — one period of samples, interpolated by a periodic cubic spline
  (``scipy.interpolate.CubicSpline(bc_type="periodic")``).

:func:`as_curve` turns a callable or an array of samples into a curve.
"""

from __future__ import annotations

import abc
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["PeriodicCurve", "Lissajous", "Circle", "MapleLeaf", "FunctionCurve", "SampledCurve", "as_curve"]


def _check_period(period: float) -> float:
    period = float(period)
    if not (math.isfinite(period) and period > 0):
        raise InvalidArgument(f"period must be a finite positive number of seconds, got {period!r}")
    return period


class PeriodicCurve(abc.ABC):
    """A planar curve ``p_W(t)`` with period :attr:`period` [s], in metres."""

    period: float

    @abc.abstractmethod
    def position(self, t) -> np.ndarray:
        """Points ``p_W (N, 2)`` [m] at times ``t (N,)`` [s] (a scalar gives ``(1, 2)``)."""

    def velocity(self, t) -> np.ndarray:
        """Velocities ``v_W (N, 2)`` [m/s]; default: 4th-order central differences."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        h = 1e-4 * self.period
        return (8 * (self.position(t + h) - self.position(t - h))
                - (self.position(t + 2 * h) - self.position(t - 2 * h))) / (12 * h)

    def __call__(self, t) -> np.ndarray:
        return self.position(t)

    def sample(self, n: int = 1000) -> tuple[np.ndarray, np.ndarray]:
        """``n`` samples over one period, both ends included: ``t (n,)`` [s], ``p_W (n, 2)`` [m]."""
        t = np.linspace(0.0, self.period, int(n))
        return t, self.position(t)


@dataclass(frozen=True)
class Lissajous(PeriodicCurve):
    """``x = cx + ax sin(nx Ω t + phx)``, ``y = cy + ay sin(ny Ω t + phy)``, ``Ω = 2π/period``.

    The moving bases of the paper's Table III are Lissajous curves (with the leaf's period);
    e.g. moving base I is ``Lissajous(ax=0.12, nx=2, cx=0.40, ay=0.12, ny=1, cy=0.30)`` in
    metres.

    Attributes:
        ax, ay: amplitudes [m]; nx, ny: integer frequency multiples (so that the curve has
        the period); phx, phy: phases [rad]; cx, cy: centre [m]; period: T [s].
    """

    ax: float
    nx: int
    cx: float
    ay: float
    ny: int
    cy: float
    phx: float = 0.0
    phy: float = 0.0
    period: float = 2 * math.pi

    def __post_init__(self):
        _check_period(self.period)
        for name in ("nx", "ny"):
            value = getattr(self, name)
            if int(value) != value:
                raise InvalidArgument(f"Lissajous.{name} must be an integer (got {value!r}): otherwise "
                                      "the curve does not repeat with the period")

    def position(self, t) -> np.ndarray:
        w = 2 * math.pi / self.period * np.atleast_1d(np.asarray(t, dtype=float))
        return np.stack([self.cx + self.ax * np.sin(self.nx * w + self.phx),
                         self.cy + self.ay * np.sin(self.ny * w + self.phy)], axis=-1)

    def velocity(self, t) -> np.ndarray:
        omega = 2 * math.pi / self.period
        w = omega * np.atleast_1d(np.asarray(t, dtype=float))
        return np.stack([self.ax * self.nx * omega * np.cos(self.nx * w + self.phx),
                         self.ay * self.ny * omega * np.cos(self.ny * w + self.phy)], axis=-1)


@dataclass(frozen=True)
class Circle(PeriodicCurve):
    """``p = centre + radius (cos(Ω t + phase), sin(Ω t + phase))``, ``Ω = 2π/period``.

    Eq. (24) of the cyclic paper (cm, T = 2π s) is ``Circle((-0.25, 0.30), 0.30, phase=3)``
    in metres.
    """

    centre: tuple[float, float]
    radius: float
    phase: float = 0.0
    period: float = 2 * math.pi

    def __post_init__(self):
        _check_period(self.period)
        if len(self.centre) != 2:
            raise InvalidArgument(f"Circle.centre must be (x, y) [m], got {self.centre!r}")

    def position(self, t) -> np.ndarray:
        w = 2 * math.pi / self.period * np.atleast_1d(np.asarray(t, dtype=float)) + self.phase
        return np.stack([self.centre[0] + self.radius * np.cos(w), self.centre[1] + self.radius * np.sin(w)], -1)

    def velocity(self, t) -> np.ndarray:
        omega = 2 * math.pi / self.period
        w = omega * np.atleast_1d(np.asarray(t, dtype=float)) + self.phase
        return np.stack([-self.radius * omega * np.sin(w), self.radius * omega * np.cos(w)], -1)


@dataclass(frozen=True)
class MapleLeaf(PeriodicCurve):
    """Japanese maple leaf, eq. (26): ``ρ = s (1 + sin Ωt)(1 + 0.3 cos 8Ωt)(1 + 0.1 cos 24Ωt)``.

    The point is ``centre + ρ (cos Ωt, sin Ωt)`` (polar angle Ωt). The paper prints neither
    the scale ``s`` nor the centre; REFERENCES.md's reproduction found s = 10 cm and centre
    (180, 50) cm, which reproduce Table IV (``tests/cyclic/test_reproduction.py``): defaults
    0.1 m and (1.8, 0.5) m.
    """

    scale: float = 0.10
    centre: tuple[float, float] = (1.80, 0.50)
    period: float = 2 * math.pi

    def __post_init__(self):
        _check_period(self.period)

    def _rho(self, w):
        return self.scale * (1 + np.sin(w)) * (1 + 0.3 * np.cos(8 * w)) * (1 + 0.1 * np.cos(24 * w))

    def position(self, t) -> np.ndarray:
        w = 2 * math.pi / self.period * np.atleast_1d(np.asarray(t, dtype=float))
        rho = self._rho(w)
        return np.stack([self.centre[0] + rho * np.cos(w), self.centre[1] + rho * np.sin(w)], -1)

    def velocity(self, t) -> np.ndarray:
        omega = 2 * math.pi / self.period
        w = omega * np.atleast_1d(np.asarray(t, dtype=float))
        a, b, c = 1 + np.sin(w), 1 + 0.3 * np.cos(8 * w), 1 + 0.1 * np.cos(24 * w)
        drho = self.scale * (np.cos(w) * b * c - 2.4 * a * np.sin(8 * w) * c - 2.4 * a * b * np.sin(24 * w))
        rho = self.scale * a * b * c
        return omega * np.stack([drho * np.cos(w) - rho * np.sin(w), drho * np.sin(w) + rho * np.cos(w)], -1)


class FunctionCurve(PeriodicCurve):
    """A user curve from a vectorized callable ``fn(t (N,)) -> (N, 2)`` [m] with period [s].

    Args:
        fn: the curve; must return the same point at ``t`` and ``t + period``.
        period: T [s].
        velocity: optional ``(N,) -> (N, 2)`` derivative [m/s]; else central differences.

    Raises:
        InvalidArgument: ``fn`` does not return ``(N, 2)`` or is not periodic to 1e-9 m.
    """

    def __init__(self, fn: Callable[[np.ndarray], np.ndarray], period: float,
                 velocity: Callable[[np.ndarray], np.ndarray] | None = None):
        self.fn = fn
        self.period = _check_period(period)
        self._velocity = velocity
        t = np.linspace(0.0, self.period, 7)
        p = self.position(t)
        if not np.allclose(p[0], p[-1], atol=1e-9, rtol=0):
            raise InvalidArgument(f"the curve is not periodic: p(0) = {p[0]} but p(T) = {p[-1]} "
                                  f"(T = {self.period}); give the curve's true period")

    def position(self, t) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        p = np.asarray(self.fn(t), dtype=float)
        if p.shape != (t.size, 2):
            raise InvalidArgument(f"the curve function must map t (N,) to (N, 2) points; got shape "
                                  f"{p.shape} for N = {t.size}")
        return p

    def velocity(self, t) -> np.ndarray:
        if self._velocity is None:
            return super().velocity(t)
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return np.asarray(self._velocity(t), dtype=float).reshape(t.size, 2)


class SampledCurve(PeriodicCurve):
    """A curve from samples over one period, interpolated by a periodic cubic spline.

    Args:
        points: ``(M, 2)`` points [m] at times ``j T / M``, ``j = 0..M-1`` (the last sample
            is *not* repeated); or ``(M + 1, 2)`` with the last equal to the first.
        period: T [s].

    Raises:
        InvalidArgument: fewer than 4 samples, wrong shape, non-finite values.
    """

    def __init__(self, points, period: float):
        from scipy.interpolate import CubicSpline

        self.period = _check_period(period)
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 4 or not np.all(np.isfinite(pts)):
            raise InvalidArgument(f"points must be a finite (M, 2) array with M >= 4, got shape {pts.shape}")
        if not np.allclose(pts[0], pts[-1], atol=1e-12, rtol=0):
            pts = np.vstack([pts, pts[:1]])
        pts = pts.copy()
        pts[-1] = pts[0]
        self.points = pts
        self._spline = CubicSpline(np.linspace(0.0, self.period, len(pts)), pts, bc_type="periodic")

    def position(self, t) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return self._spline(np.mod(t, self.period))

    def velocity(self, t) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return self._spline(np.mod(t, self.period), 1)


def as_curve(curve, period: float | None = None) -> PeriodicCurve:
    """A :class:`PeriodicCurve` from a curve, a callable (needs ``period``) or ``(M, 2)`` samples.

    Raises:
        InvalidArgument: a callable or samples without ``period``, or an unsupported type.
    """
    if isinstance(curve, PeriodicCurve):
        return curve
    if period is None:
        raise InvalidArgument("give period= [s] with a callable or sampled curve "
                              "(it must equal the end-effector path's period)")
    if callable(curve):
        return FunctionCurve(curve, period)
    try:
        return SampledCurve(curve, period)
    except InvalidArgument:
        raise
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"cannot make a periodic curve from {type(curve).__name__}: give a "
                              "PeriodicCurve, a callable t (N,) -> (N, 2) or an (M, 2) array") from exc
