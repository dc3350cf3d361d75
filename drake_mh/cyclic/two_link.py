"""Sixth-order polynomial joint trajectories in stages: the paper's 2-link component.

Eq. (16) of the cyclic paper: per stage and joint,
``θ(r) = a6 r⁶ + a5 r⁵ + a4 r⁴ + a3 r³ + a0`` with ``a0 = θi``, ``a5 = -3 a6 - 6 θi + 6 θf``,
``a4 = (-9 a6 - 5 a5)/2``, ``a3 = θf - θi - a6 - a5 - a4``. Whatever ``a6``, this gives
``θ(0) = θi``, ``θ(1) = θf`` and zero velocity and acceleration at both ends (checked in
``tests/cyclic/test_two_link.py``), so consecutive stages join with continuous velocity and
acceleration; ``a6 = 0`` is the quintic minimum-jerk profile ``10r³ - 15r⁴ + 6r⁵``.

Eq. (25) divides each period into stages, each with its own linear time-scale ``r ∈ [0, 1]``
(printed for four quarter-period stages of T = 2π; its second line ``t - 2/π`` is read as
``(2/π)(t - π/2)``, the only reading that maps the stage onto [0, 1]). The final angles of
stage k are the initial angles of stage k + 1, and those of the last stage the initial angles
of the first: the trajectory is periodic **by construction** (the knot table is cyclic).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["sixth_order_coefficients", "StagedPolynomial"]


def sixth_order_coefficients(theta_i, theta_f, a6=0.0) -> np.ndarray:
    """Coefficients ``[a0, a3, a4, a5, a6]`` of eq. (16), broadcast over the inputs.

    Args:
        theta_i, theta_f: initial and final joint angles of the stage [rad].
        a6: the free sixth-order coefficient [rad] (the paper uses 0 for the 5-DOF case).

    Returns:
        ``(..., 5)`` array ``[a0, a3, a4, a5, a6]``.
    """
    theta_i, theta_f, a6 = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (theta_i, theta_f, a6)))
    a0 = theta_i
    a5 = -3.0 * a6 - 6.0 * theta_i + 6.0 * theta_f
    a4 = 0.5 * (-9.0 * a6 - 5.0 * a5)
    a3 = theta_f - theta_i - a6 - a5 - a4
    return np.stack([a0, a3, a4, a5, a6], axis=-1)


@dataclass(frozen=True)
class StagedPolynomial:
    """Periodic joint trajectories made of eq. (16) polynomials over the stages of eq. (25).

    Attributes:
        knots: ``(S, J)`` joint angles [rad] at the start of each of the S stages (the paper's
            Table I "initial" rows, transposed); the last stage ends at ``knots[0]`` (cyclic by
            construction). A ``(S + 1, J)`` table whose last row equals the first is accepted.
        period: T [s] of the end-effector path.
        a6: scalar or ``(S, J)`` sixth-order coefficients [rad] (eq. (16)); default 0.
        stage_fractions: ``(S + 1,)`` increasing stage boundaries as fractions of the period,
            from 0 to 1; default: equal stages (eq. (25): quarters for S = 4).
    """

    knots: np.ndarray
    period: float = 2 * np.pi
    a6: object = 0.0
    stage_fractions: np.ndarray | None = None
    _coef: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        knots = np.array(self.knots, dtype=float)
        if knots.ndim != 2 or len(knots) < 1 or not np.all(np.isfinite(knots)):
            raise InvalidArgument(f"knots must be a finite (S, J) table of joint angles [rad], got shape {knots.shape}")
        if len(knots) >= 2 and np.allclose(knots[0], knots[-1], atol=1e-12, rtol=0):
            knots = knots[:-1]
        S, J = knots.shape
        period = float(self.period)
        if not (np.isfinite(period) and period > 0):
            raise InvalidArgument(f"period must be positive [s], got {self.period!r}")
        if self.stage_fractions is None:
            fractions = np.linspace(0.0, 1.0, S + 1)
        else:
            fractions = np.array(self.stage_fractions, dtype=float)
            if (fractions.shape != (S + 1,) or fractions[0] != 0.0 or fractions[-1] != 1.0
                    or np.any(np.diff(fractions) <= 0)):
                raise InvalidArgument(f"stage_fractions must be {S + 1} increasing values from 0 to 1 "
                                      f"(one boundary per stage, S = {S}), got {self.stage_fractions!r}")
        a6 = np.broadcast_to(np.asarray(self.a6, dtype=float), (S, J))
        closed = np.vstack([knots, knots[:1]])
        object.__setattr__(self, "knots", knots)
        object.__setattr__(self, "period", period)
        object.__setattr__(self, "stage_fractions", fractions)
        object.__setattr__(self, "_coef", sixth_order_coefficients(closed[:-1], closed[1:], a6))  # (S, J, 5)

    @property
    def n_stages(self) -> int:
        return self.knots.shape[0]

    @property
    def n_joints(self) -> int:
        return self.knots.shape[1]

    def stage_and_r(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Stage index ``(N,)`` and the stage's linear time-scale ``r ∈ [0, 1]`` ``(N,)`` (eq. (25))."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        phase = np.mod(t, self.period) / self.period
        s = np.clip(np.searchsorted(self.stage_fractions, phase, side="right") - 1, 0, self.n_stages - 1)
        f0 = self.stage_fractions[s]
        r = (phase - f0) / (self.stage_fractions[s + 1] - f0)
        return s, np.clip(r, 0.0, 1.0)

    def q(self, t) -> np.ndarray:
        """Joint angles ``(N, J)`` [rad] at times ``t (N,)`` [s]."""
        s, r = self.stage_and_r(t)
        c = self._coef[s]  # (N, J, 5)
        r = r[:, None]
        return c[..., 0] + r ** 3 * (c[..., 1] + r * (c[..., 2] + r * (c[..., 3] + r * c[..., 4])))

    def qd(self, t) -> np.ndarray:
        """Joint velocities ``(N, J)`` [rad/s]."""
        s, r = self.stage_and_r(t)
        c = self._coef[s]
        r = r[:, None]
        dtheta_dr = r ** 2 * (3 * c[..., 1] + r * (4 * c[..., 2] + r * (5 * c[..., 3] + 6 * r * c[..., 4])))
        duration = (self.stage_fractions[s + 1] - self.stage_fractions[s]) * self.period
        return dtheta_dr / duration[:, None]
