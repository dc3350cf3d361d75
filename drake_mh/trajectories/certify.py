"""Certification of a joint trajectory against a robot's limits (DESIGN principle 4).

:func:`certify` samples a :class:`~drake_mh.trajectories.trajectory.Trajectory` densely — every
piece between two consecutive :attr:`~Trajectory.breaks` at ``samples_per_piece`` points,
both ends taken one-sided, and at least ``min_samples`` points in all — and returns, per
joint and quantity, the largest ratio of the value to its limit and the time where it occurs:

* ``position``: ``|q - m| / h`` with ``m, h`` the centre and half-width of ``[lower, upper]``
  (1 on a limit; Panda joint 4's range is not centred on 0); :attr:`Certificate.position_excess`
  says how far outside the range [rad] the trajectory goes;
* ``velocity``, ``acceleration``, ``jerk``: ``|q'|``, ``|q''|``, ``|q'''|`` over the symmetric
  limits. An acceleration discontinuity at a break (toppra's constant-acceleration
  parameterization has one at every gridpoint) is an impulse of jerk: ratio ``inf`` there;
* ``torque``: ``|τ|`` over the effort limits, ``τ = M q̈ + C q̇ + g`` with gravity, from
  :class:`~drake_mh.trajectories.dynamics.BatchDynamics` (the RNEA compiled from the plant,
  equal to Drake's inverse dynamics to ~1e-13; ``torque_backend="drake"`` calls Drake).

Limits that the model does not declare (``inf``) give ratio 0; :meth:`Certificate.table` shows
"no limit" there. A quantity certified but not enforced by whoever made the trajectory (toppra's
jerk: :func:`~drake_mh.trajectories.retime.retime` passes ``enforced``) is labelled "not
enforced" in the table: its ``inf`` is reported, not a failed check.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import InvalidArgument, LimitViolation
from drake_mh.trajectories.bound import kinematic_bound

__all__ = ["Certificate", "certify", "QUANTITIES"]

QUANTITIES = ("position", "velocity", "acceleration", "jerk", "torque")


@dataclass(frozen=True)
class Certificate:
    """Worst limit ratios of a trajectory, per quantity and joint.

    Attributes:
        joint_names: ``(nq,)``.
        ratios: quantity -> ``(nq,)`` largest ratio over the samples (``<= 1`` is within).
        times: quantity -> ``(nq,)`` time [s] of that largest ratio.
        position_excess: ``(nq,)`` largest distance outside ``[lower, upper]`` [rad] (0 inside).
        samples: number of time samples used.
        duration: trajectory duration [s].
        scale: the ratios of velocity, acceleration, jerk and torque are relative to
            ``scale x`` the robot's limits (positions always to the full range).
        enforced: the quantities the trajectory's maker enforced (``None``: unknown, every
            certified quantity counts); the others are reported only.
        limited: quantity -> ``(nq,)`` whether the robot declares a finite limit there.
    """

    joint_names: tuple[str, ...]
    ratios: dict = field(default_factory=dict)
    times: dict = field(default_factory=dict)
    position_excess: np.ndarray = field(default_factory=lambda: np.zeros(0))
    samples: int = 0
    duration: float = 0.0
    scale: float = 1.0
    enforced: tuple | None = None
    limited: dict = field(default_factory=dict)

    def max_ratio(self, quantities=None) -> float:
        """Largest ratio over joints and the given quantities (default all certified ones)."""
        qs = self._quantities(quantities)
        return max((float(np.max(self.ratios[q])) for q in qs), default=0.0)

    def worst(self, quantities=None) -> tuple[str, str, float, float]:
        """``(quantity, joint, time [s], ratio)`` of the largest ratio."""
        best = ("", "", 0.0, -np.inf)
        for q in self._quantities(quantities):
            j = int(np.argmax(self.ratios[q]))
            if self.ratios[q][j] > best[3]:
                best = (q, self.joint_names[j], float(self.times[q][j]), float(self.ratios[q][j]))
        return best

    def ok(self, quantities=None, tol: float = 1e-6) -> bool:
        """Whether every ratio of ``quantities`` is ``<= 1 + tol``.

        ``quantities=None``: the :attr:`enforced` ones (all certified ones when unknown) — a
        quantity its maker did not enforce (toppra's jerk, infinite by construction) is
        reported, not checked; name it to check it.
        """
        return self.max_ratio(self._checked(quantities)) <= 1.0 + tol

    def check(self, quantities=None, tol: float = 1e-6, hint: str = "") -> Certificate:
        """Return ``self`` if :meth:`ok`, else raise :class:`LimitViolation` for the worst ratio."""
        quantities = self._checked(quantities)
        if not self.ok(quantities, tol):
            quantity, joint, time, ratio = self.worst(quantities)
            raise LimitViolation(joint, quantity, time, ratio, tol, hint)
        return self

    def _checked(self, quantities):
        if quantities is None and self.enforced is not None:
            return [q for q in self.ratios if q in self.enforced]
        return quantities

    def _quantities(self, quantities):
        if quantities is None:
            return list(self.ratios)
        missing = [q for q in quantities if q not in self.ratios]
        if missing:
            raise InvalidArgument(f"quantities {missing} were not certified; certified: {list(self.ratios)}")
        return list(quantities)

    def table(self) -> str:
        """Markdown table: one row per quantity, one column per joint (ratio @ time).

        A quantity outside :attr:`enforced` reads "jerk (not enforced)" (toppra's ``inf`` jerk
        is reported, not a failure); a joint without a finite limit reads "no limit".
        """
        head = "| quantity | " + " | ".join(self.joint_names) + " |"
        lines = [head, "|" + "---|" * (len(self.joint_names) + 1)]
        for q in self.ratios:
            limited = self.limited.get(q, np.ones(len(self.ratios[q]), dtype=bool))
            cells = [f"{r:.4f} @ {t:.3f} s" if ok else "no limit"
                     for r, t, ok in zip(self.ratios[q], self.times[q], limited)]
            label = q if self.enforced is None or q in self.enforced else f"{q} (not enforced)"
            lines.append(f"| {label} | " + " | ".join(cells) + " |")
        return "\n".join(lines)

    def as_dict(self) -> dict:
        """Flat scalars for study records: ``<quantity>_ratio`` (worst joint) and ``max_ratio``."""
        out = {f"{q}_ratio": float(np.max(r)) for q, r in self.ratios.items()}
        out["max_ratio"] = self.max_ratio()
        out["position_excess"] = float(np.max(self.position_excess)) if len(self.position_excess) else 0.0
        return out


def _limits(robot, quantity: str) -> np.ndarray:
    return {"velocity": robot.velocity_limits, "acceleration": robot.acceleration_limits,
            "jerk": robot.jerk_limits, "torque": robot.effort_limits}[quantity]


def sample_times(trajectory, samples_per_piece: int = 8, min_samples: int = 1000):
    """Sample layout used by :func:`certify`: per piece ``(t0, t1, tau)``, one-sided at the ends."""
    breaks = trajectory.breaks
    pieces = len(breaks) - 1
    k = max(int(samples_per_piece), int(np.ceil(min_samples / max(pieces, 1))), 2)
    return breaks, np.linspace(0.0, 1.0, k)


def certify(trajectory, robot, quantities=QUANTITIES, samples_per_piece: int = 8,
            min_samples: int = 1000, torque_backend: str = "rnea", scale: float = 1.0,
            enforced=None) -> Certificate:
    """Certify ``trajectory`` against ``robot``'s limits by dense sampling.

    Args:
        trajectory: a :class:`~drake_mh.trajectories.trajectory.Trajectory` with ``nq`` joints.
        robot: the :class:`~drake_mh.robot.Robot` whose limits apply.
        quantities: any of ``QUANTITIES``.
        samples_per_piece: samples per piece between breaks (ends one-sided, so both sides
            of every break are seen); raised so that at least ``min_samples`` are taken.
        min_samples: lower bound on the total number of samples.
        torque_backend: ``"rnea"`` (batched, compiled from the plant) or ``"drake"``
            (``robot.inverse_dynamics`` per sample, slower; the reference).
        scale: certify against ``scale x`` the velocity, acceleration, jerk and torque limits
            (a safety margin; ``retime(..., scale=...)`` passes its own).
        enforced: quantities the trajectory's maker enforced, for :meth:`Certificate.table`
            (``None``, the default: all of ``quantities``); ``retime`` passes its own.

    Returns:
        A :class:`Certificate` (never raises for a violation; call ``.check()`` for that).

    Raises:
        InvalidArgument: unknown quantity, joint count mismatch or backend.
    """
    quantities = tuple(quantities)
    unknown = [q for q in quantities if q not in QUANTITIES]
    if unknown:
        raise InvalidArgument(f"unknown quantities {unknown}; choose from {QUANTITIES}")
    if trajectory.nq != robot.nq:
        raise InvalidArgument(f"trajectory has {trajectory.nq} joints, robot {robot.name} has {robot.nq}")
    if not (0.0 < scale <= 1.0):
        raise InvalidArgument(f"scale must be in (0, 1], got {scale}")
    if enforced is not None:
        enforced = tuple(enforced)
        if any(q not in QUANTITIES for q in enforced):
            raise InvalidArgument(f"enforced must be a subset of {QUANTITIES}, got {enforced}")
    if torque_backend not in ("rnea", "drake"):
        raise InvalidArgument(f"torque_backend must be 'rnea' or 'drake', got {torque_backend!r}")
    breaks, tau = sample_times(trajectory, samples_per_piece, min_samples)
    h = np.diff(breaks)
    eps = 1e-9 * h
    lo, hi = breaks[:-1] + eps, breaks[1:] - eps  # one-sided: each piece's own polynomial
    T = np.clip(breaks[:-1, None] + tau[None, :] * h[:, None], lo[:, None], hi[:, None])  # (P, K)
    P, K = T.shape
    nq = robot.nq
    ratios, times = {}, {}
    excess = np.zeros(nq)
    order = max(_ORDER[q] for q in quantities)
    D = trajectory.derivatives(T.ravel(), order)  # once for every quantity
    for quantity in quantities:
        r = _ratio_from(D, robot, quantity, scale, torque_backend).reshape(P, K, nq)
        flat = r.reshape(P * K, nq)
        idx = np.argmax(flat, axis=0)
        ratios[quantity] = flat[idx, np.arange(nq)].copy()
        times[quantity] = T.ravel()[idx].copy()
        _refine(trajectory, robot, quantity, T, r, lo, hi, scale, torque_backend, ratios[quantity],
                times[quantity])
        if quantity != "torque":  # polynomial between breaks: a bound, not a sample (bound.py)
            ratios[quantity] = np.maximum(ratios[quantity], kinematic_bound(
                trajectory, _ORDER[quantity], _range_ratio(robot, quantity, scale), breaks[:-1], breaks[1:],
                ratios[quantity], samples=(tau, D[_ORDER[quantity]].reshape(P, K, nq))))
        if quantity == "position":
            Q = trajectory.derivatives(np.r_[T.ravel(), times[quantity]], 0)[0]
            excess = np.max(np.maximum(np.maximum(Q - robot.upper, robot.lower - Q), 0.0), axis=0)
            excess = np.where(robot.continuous, 0.0, excess)
        if quantity == "jerk":  # impulses at acceleration jumps
            tb, jumps = trajectory.acceleration_jumps()
            big = jumps > 1e-6 * np.where(np.isfinite(robot.acceleration_limits), robot.acceleration_limits, 1.0)
            for j in np.flatnonzero(big.any(axis=0)):
                if np.isfinite(robot.jerk_limits[j]):
                    ratios[quantity][j] = np.inf
                    times[quantity][j] = tb[np.argmax(jumps[:, j])]
    limited = {q: ~robot.continuous if q == "position" else np.isfinite(_limits(robot, q)) for q in quantities}
    return Certificate(tuple(robot.joint_names), ratios, times, excess, int(T.size), trajectory.duration,
                       float(scale), enforced, limited)


_ORDER = {"position": 0, "velocity": 1, "acceleration": 2, "jerk": 3, "torque": 2}


def _ratio(trajectory, robot, quantity: str, t: np.ndarray, scale: float, backend: str) -> np.ndarray:
    """``(len(t), nq)`` ratios of ``quantity`` to its (scaled) limit at times ``t``."""
    return _ratio_from(trajectory.derivatives(t, _ORDER[quantity]), robot, quantity, scale, backend)


def _ratio_from(D, robot, quantity: str, scale: float, backend: str) -> np.ndarray:
    """Ratios from precomputed derivatives ``D = [q, q', ...]`` (each ``(M, nq)``)."""
    order = _ORDER[quantity]
    if quantity == "position":
        centre, half = 0.5 * (robot.upper + robot.lower), 0.5 * (robot.upper - robot.lower)
        return np.abs(D[0] - centre) / np.where(robot.continuous, np.inf, half)
    if quantity == "torque":
        if backend == "rnea":
            tq = _batch_dynamics(robot).inverse_dynamics(D[0], D[1], D[2])
        else:
            tq = np.array([robot.inverse_dynamics(q, v, a) for q, v, a in zip(D[0], D[1], D[2])])
        return np.abs(tq) / (scale * _limits(robot, quantity))
    return np.abs(D[order]) / (scale * _limits(robot, quantity))


def _range_ratio(robot, quantity: str, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """``(centre, half)`` per joint: a value ``x`` has the ratio ``|x - centre| / half``
    (:func:`~drake_mh.trajectories.bound.kinematic_bound`)."""
    if quantity == "position":
        centre, half = 0.5 * (robot.upper + robot.lower), 0.5 * (robot.upper - robot.lower)
        return centre, np.where(robot.continuous, np.inf, half)
    limit = scale * _limits(robot, quantity)
    return np.zeros_like(limit), limit


_GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)


def _refine(trajectory, robot, quantity, T, r, lo, hi, scale, backend, best, best_t,
            threshold: float = 0.9, per_joint: int = 8, iterations: int = 8) -> None:
    """Sharpen the ratios between samples (golden-section search around local maxima).

    Dense samples miss a peak's top by ``O(c Δt²)`` (seen: 9e-6 at 20 gridpoints). Sampled
    local maxima reaching ``threshold`` are ranked by the vertex of the parabola through the
    sample and its two neighbours (what the peak's top is likely to be, not what a sample
    happened to hit), and the ``per_joint`` highest are bracketed by their neighbouring samples
    (inside the piece) and refined; the error then drops by ``0.618^(2·iterations)``. Ranking
    by sampled value is not enough: a 1.001x peak whose samples fall on its flanks reads 0.999
    and ranks below two 0.9995x peaks sampled at their tops (test
    ``test_peak_sampled_on_its_flanks_is_found``). Updates ``best``/``best_t`` in place.
    """
    P, K, nq = r.shape
    left = np.concatenate([np.full((P, 1, nq), -np.inf), r[:, :-1]], axis=1)
    right = np.concatenate([r[:, 1:], np.full((P, 1, nq), -np.inf)], axis=1)
    is_peak = (r >= left) & (r >= right)
    is_peak &= (r >= threshold) & np.isfinite(r)
    p_idx, k_idx, J = np.nonzero(is_peak)  # candidate peaks: piece, sample, joint
    if not J.size:
        return
    # parabola through (left, centre, right) samples (uniform spacing within a piece): vertex value
    r0, r1, r2 = left[p_idx, k_idx, J], r[p_idx, k_idx, J], right[p_idx, k_idx, J]
    with np.errstate(invalid="ignore", divide="ignore"):
        curvature = r0 - 2.0 * r1 + r2
        vertex = r1 - (r2 - r0) ** 2 / (8.0 * curvature)
    estimate = np.where(np.isfinite(r0) & np.isfinite(r2) & (curvature < 0), vertex, r1)
    order = np.lexsort((-estimate, J))  # by joint, highest estimate first
    rank = np.arange(order.size) - np.searchsorted(J[order], J[order])
    keep = order[rank < per_joint]
    p_idx, k_idx, J = p_idx[keep], k_idx[keep], J[keep]
    a = np.where(k_idx > 0, T[p_idx, np.maximum(k_idx - 1, 0)], lo[p_idx])
    b = np.where(k_idx < K - 1, T[p_idx, np.minimum(k_idx + 1, K - 1)], hi[p_idx])
    rows = np.arange(len(J))

    def f(t):
        return _ratio(trajectory, robot, quantity, t, scale, backend)[rows, J]

    c, d = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(iterations):
        keep_left = fc >= fd  # maximum in [a, d]
        a, b = np.where(keep_left, a, c), np.where(keep_left, d, b)
        c_new, d_new = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
        t_new = np.where(keep_left, c_new, d_new)
        f_new = f(t_new)
        fc, fd, c, d = (np.where(keep_left, f_new, fd), np.where(keep_left, fc, f_new),
                        np.where(keep_left, c_new, d), np.where(keep_left, c, d_new))
    for t_best, f_best in ((c, fc), (d, fd)):
        for j in np.unique(J):
            mine = np.flatnonzero(J == j)
            i = mine[np.argmax(f_best[mine])]
            if f_best[i] > best[j]:
                best[j], best_t[j] = f_best[i], t_best[i]


def _batch_dynamics(robot):
    """One :class:`BatchDynamics` per robot object (compiled once, kept while the robot lives)."""
    from drake_mh.trajectories.dynamics import batch_dynamics

    return batch_dynamics(robot)
