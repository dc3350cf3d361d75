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

Which limits: a trajectory made by :func:`~drake_mh.trajectories.retime.retime` carries the
limits it enforced (``info["enforced_limits"]``: declared, derived, default, scaled) and its
certificate; certifying it again (``certify(traj, robot)``) checks those same limits, the same
quantities and the same ``scale`` unless ``limits=`` / ``enforced=`` / ``scale=`` say otherwise
(``limits=robot.limits`` checks the robot's own table).

Besides the ratios, :attr:`Certificate.bounds` holds absolute maxima per joint of ``|q̇|``,
``|q̈|``, ``|q⃛|`` (Bernstein bounds: no point of the trajectory exceeds them, whether or not a
limit is declared) and of ``|τ|`` (a refined sample: torque is not a polynomial).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import InvalidArgument, LimitViolation
from drake_mh.robot.limits import limits_of
from drake_mh.trajectories.bound import MAX_LEVELS, SLACK, kinematic_bound, piece_degree, sample_bound_nodes

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
            ``scale x`` the limits (:attr:`limits`; positions always to the full range).
        enforced: the quantities the trajectory's maker enforced (``None``: unknown, every
            certified quantity counts); the others are reported only.
        limited: quantity -> ``(nq,)`` whether a finite limit applies there.
        limits: the :class:`~drake_mh.robot.limits.JointLimits` the ratios refer to (values
            and sources; ``None`` for certificates made before it existed).
        bounds: quantity -> ``(nq,)`` largest absolute value [rad/s, rad/s², rad/s³, N·m] of
            ``velocity``, ``acceleration``, ``jerk`` (bounds) and ``torque`` (refined sample),
            for the quantities certified; jerk is ``inf`` at acceleration steps.
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
    limits: object = None
    bounds: dict = field(default_factory=dict)

    def max_ratio(self, quantities=None) -> float:
        """Largest ratio over joints and the given quantities (default all certified ones)."""
        largest = self._largest
        return max((largest[q] for q in self._quantities(quantities)), default=0.0)

    @functools.cached_property
    def _largest(self) -> dict:
        """quantity -> its largest ratio over the joints (read by every :meth:`ok`)."""
        return {q: float(np.max(r)) for q, r in self.ratios.items()}

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


def maker_limits(trajectory, robot):
    """``(limits, enforced, scale)`` of the retiming that made ``trajectory`` (its
    ``info["enforced_limits"]`` and certificate), or ``None`` when it carries none for these joints."""
    table, cert = trajectory.info.get("enforced_limits"), trajectory.info.get("certificate")
    if table is None or tuple(table.joint_names) != tuple(robot.joint_names):
        return None
    if cert is not None:
        return table, cert.enforced, cert.scale
    enforced = None if table.enforced is None else ("position",) + tuple(
        "torque" if q == "effort" else q for q in table.enforced)
    return table, enforced, 1.0


def sample_times(trajectory, samples_per_piece: int = 8, min_samples: int = 1000):
    """Sample layout used by :func:`certify`: per piece ``(t0, t1, tau)``, one-sided at the ends."""
    breaks = trajectory.breaks
    pieces = len(breaks) - 1
    k = max(int(samples_per_piece), int(np.ceil(min_samples / max(pieces, 1))), 2)
    return breaks, np.linspace(0.0, 1.0, k)


def certify(trajectory, robot, quantities=QUANTITIES, samples_per_piece: int = 8,
            min_samples: int = 1000, torque_backend: str = "rnea", scale: float | None = None,
            enforced=None, limits=None) -> Certificate:
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
            (a safety margin); ``None``: the maker's (module docstring), else 1.
        enforced: quantities the trajectory's maker enforced, checked by
            :meth:`Certificate.check` and labelled in :meth:`Certificate.table`; ``None``: the
            maker's when the trajectory carries them, else all of ``quantities``.
        limits: the :class:`~drake_mh.robot.limits.JointLimits` to certify against; ``None``:
            the maker's (``trajectory.info["enforced_limits"]``) when the trajectory carries
            them, else ``robot.limits``.

    Returns:
        A :class:`Certificate` (never raises for a violation; call ``.check()`` for that).

    Raises:
        InvalidArgument: unknown quantity, joint count mismatch or backend.
    """
    quantities = tuple(quantities)
    maker = maker_limits(trajectory, robot) if limits is None else None
    if maker is not None:
        limits = maker[0]
        enforced = maker[1] if enforced is None else enforced
        scale = maker[2] if scale is None else scale
    limits = limits_of(robot) if limits is None else limits
    scale = 1.0 if scale is None else scale
    unknown = [q for q in quantities if q not in QUANTITIES]
    if unknown:
        raise InvalidArgument(f"unknown quantities {unknown}; choose from {QUANTITIES}")
    if trajectory.nq != robot.nq:
        raise InvalidArgument(f"trajectory has {trajectory.nq} joints, robot {robot.name} has {robot.nq}")
    if tuple(limits.joint_names) != tuple(robot.joint_names):
        raise InvalidArgument(f"limits are for joints {list(limits.joint_names)}, robot {robot.name} has "
                              f"{list(robot.joint_names)}")
    if not (0.0 < scale <= 1.0):
        raise InvalidArgument(f"scale must be in (0, 1], got {scale}")
    if enforced is not None:
        enforced = tuple(enforced)
        if any(q not in QUANTITIES for q in enforced):
            raise InvalidArgument(f"enforced must be a subset of {QUANTITIES}, got {enforced}")
    if torque_backend not in ("rnea", "drake"):
        raise InvalidArgument(f"torque_backend must be 'rnea' or 'drake', got {torque_backend!r}")
    breaks, tau = sample_times(trajectory, samples_per_piece, min_samples)
    P, K = len(breaks) - 1, len(tau)
    nq = robot.nq
    ratios, times, bounds = {}, {}, {}
    excess = np.zeros(nq)
    norms = [_normal(robot, limits, quantity, scale) for quantity in quantities]
    core = trajectory._compiled if torque_backend == "rnea" and quantities else None
    if core is not None:  # the compiled core: the same samples and refinement in one call
        worst, when, D, bounded = _compiled_samples(core, trajectory, robot, quantities, norms, tau)
        jobs = [(q, None, norm, worst[i], when[i]) for i, (q, norm) in enumerate(zip(quantities, norms))]
        times = {q: when[i] for i, q in enumerate(quantities)}
    else:
        h = np.diff(breaks)
        eps = 1e-9 * h
        lo, hi = breaks[:-1] + eps, breaks[1:] - eps  # one-sided: each piece's own polynomial
        T = np.clip(breaks[:-1, None] + tau[None, :] * h[:, None], lo[:, None], hi[:, None])  # (P, K)
        D = trajectory.derivatives(T.ravel(), max(_ORDER[q] for q in quantities))  # once for every quantity
        jobs, bounded = [], ()
        for quantity, norm in zip(quantities, norms):
            r = _normalized(D, robot, quantity, norm, torque_backend).reshape(P, K, nq)
            flat = r.reshape(P * K, nq)
            idx = np.argmax(flat, axis=0)
            times[quantity] = T.ravel()[idx].copy()
            jobs.append((quantity, r, norm, flat[idx, np.arange(nq)].copy(), times[quantity]))
        _refine(trajectory, robot, jobs, T, lo, hi, torque_backend)
    for quantity, _, norm, worst, _ in jobs:
        if quantity != "torque" and quantity not in bounded:  # polynomial between breaks: a bound (bound.py)
            worst = np.maximum(worst, kinematic_bound(trajectory, _ORDER[quantity], norm, breaks[:-1], breaks[1:],
                                                      worst, samples=(tau, D[_ORDER[quantity]].reshape(P, K, nq))))
        if quantity == "position":
            ratios[quantity] = worst
            if np.max(np.where(robot.continuous, 0.0, worst)) > 1.0 - 1e-9:  # else the bound keeps it inside
                Q = np.vstack([D[0], trajectory.derivatives(times[quantity], 0)[0]])  # the samples and the peaks
                excess = np.max(np.maximum(np.maximum(Q - robot.upper, robot.lower - Q), 0.0), axis=0)
                excess = np.where(robot.continuous, 0.0, excess)
            continue
        limited = np.isfinite(limits[quantity])
        ratios[quantity] = np.where(limited, worst, 0.0)  # where unlimited, `worst` is the value itself
        bounds[quantity] = worst * norm[1]
        if quantity == "jerk":  # impulses at acceleration jumps
            tb, jumps = trajectory.acceleration_jumps()
            a_lim = limits["acceleration"]
            big = jumps > 1e-6 * np.where(np.isfinite(a_lim), a_lim, 1.0)
            for j in np.flatnonzero(big.any(axis=0)):
                bounds[quantity][j] = np.inf
                if limited[j]:
                    ratios[quantity][j] = np.inf
                    times[quantity][j] = tb[np.argmax(jumps[:, j])]
    limited = {q: ~robot.continuous if q == "position" else np.isfinite(limits[q]) for q in quantities}
    return Certificate(tuple(robot.joint_names), ratios, times, excess, P * K, trajectory.duration,
                       float(scale), enforced, limited, limits, bounds)


_ORDER = {"position": 0, "velocity": 1, "acceleration": 2, "jerk": 3, "torque": 2}


def _normalized(D, robot, quantity: str, norm, backend: str) -> np.ndarray:
    """``|x - centre| / half`` from precomputed derivatives ``D = [q, q', ...]`` (each ``(M, nq)``)."""
    centre, half = norm
    if quantity == "torque":
        if backend == "rnea":
            tq = _batch_dynamics(robot).inverse_dynamics(D[0], D[1], D[2])
        else:
            tq = np.array([robot.inverse_dynamics(q, v, a) for q, v, a in zip(D[0], D[1], D[2])])
        return np.abs(tq) / half
    return np.abs(D[_ORDER[quantity]] - centre) / half


def _normal(robot, limits, quantity: str, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """``(centre, half)`` per joint: ``|x - centre| / half`` is the ratio of a value ``x`` to its
    limit (position: to the range; ``scale x`` the limit otherwise) where one is declared, and
    ``|x|`` itself where none is (``half = 1``: the certificate's absolute bounds)
    (:func:`~drake_mh.trajectories.bound.kinematic_bound`)."""
    if quantity == "position":
        centre, half = 0.5 * (robot.upper + robot.lower), 0.5 * (robot.upper - robot.lower)
        return centre, np.where(robot.continuous, np.inf, half)
    limit = scale * np.asarray(limits[quantity], dtype=float)
    return np.zeros_like(limit), np.where(np.isfinite(limit), limit, 1.0)


_GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)
_KIND = {"position": 0, "velocity": 1, "acceleration": 2, "jerk": 3, "torque": 4}
"""quantity codes of the compiled core's ``certify_samples``."""


def _compiled_samples(core, trajectory, robot, quantities, norms, tau):
    """The samples and :func:`_refine` of :func:`certify` in the compiled core
    (``certify_samples``, the same threshold, ranking and search), and in the same call the
    :func:`~drake_mh.trajectories.bound.kinematic_bound` of every position, velocity, acceleration
    and jerk whose Bernstein nodes are among the samples: ``(worst (nQ, nq), when (nQ, nq), D,
    the quantities bounded)``."""
    nq = robot.nq
    kinds = np.array([_KIND[q] for q in quantities], dtype=np.int64)
    centre = np.array([c for c, _ in norms], dtype=float).reshape(len(norms), nq)  # each (nq,)
    half = np.array([h for _, h in norms], dtype=float).reshape(len(norms), nq)
    ints, floats = _batch_dynamics(robot).packed if "torque" in quantities else (None, None)
    orders = tuple(-1 if q == "torque" else _ORDER[q] for q in quantities)
    n1, picks, mats = sample_bound_nodes(tau, piece_degree(trajectory), orders)
    worst, when, D = core[0].certify_samples(*core[1:], np.ascontiguousarray(trajectory.breaks, dtype=float),
                                             np.ascontiguousarray(tau, dtype=float), kinds, centre, half,
                                             _THRESHOLD, _PER_JOINT, _ITERATIONS, ints, floats, n1, picks, mats,
                                             SLACK, MAX_LEVELS)
    return worst, when, list(D), {q for q, n in zip(quantities, n1) if n > 0}


_THRESHOLD, _PER_JOINT, _ITERATIONS = 0.9, 8, 8
"""refinement: sampled peaks at least this ratio, the best so many per joint, golden steps."""


def _refine(trajectory, robot, jobs, T, lo, hi, backend, threshold: float = _THRESHOLD,
            per_joint: int = _PER_JOINT, iterations: int = _ITERATIONS) -> None:
    """Sharpen the ratios between samples (golden-section search around local maxima).

    Dense samples miss a peak's top by ``O(c Δt²)`` (seen: 9e-6 at 20 gridpoints). Sampled
    local maxima reaching ``threshold`` are ranked by the vertex of the parabola through the
    sample and its two neighbours (what the peak's top is likely to be, not what a sample
    happened to hit), and the ``per_joint`` highest are bracketed by their neighbouring samples
    (inside the piece) and refined; the error then drops by ``0.618^(2·iterations)``. Ranking
    by sampled value is not enough: a 1.001x peak whose samples fall on its flanks reads 0.999
    and ranks below two 0.9995x peaks sampled at their tops (test
    ``test_peak_sampled_on_its_flanks_is_found``).

    ``jobs``: one ``(quantity, r (P, K, nq) sampled ratios, norm, best (nq,), best_t (nq,))``
    per quantity; every quantity's searches run together (one evaluation of the trajectory per
    step for all), each exactly as it would alone. Updates each ``best``/``best_t`` in place.
    """
    P, K, nq = T.shape[0], T.shape[1], robot.nq
    found = []  # per quantity: (quantity, norm, best, best_t, J, a, b)
    for quantity, r, norm, best, best_t in jobs:
        left = np.concatenate([np.full((P, 1, nq), -np.inf), r[:, :-1]], axis=1)
        right = np.concatenate([r[:, 1:], np.full((P, 1, nq), -np.inf)], axis=1)
        is_peak = (r >= left) & (r >= right)
        is_peak &= (r >= threshold) & np.isfinite(r)
        p_idx, k_idx, J = np.nonzero(is_peak)  # candidate peaks: piece, sample, joint
        if not J.size:
            continue
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
        found.append((quantity, norm, best, best_t, J, a, b))
    if not found:
        return
    J = np.concatenate([x[4] for x in found])
    a, b = np.concatenate([x[5] for x in found]), np.concatenate([x[6] for x in found])
    ends = np.cumsum([0] + [len(x[4]) for x in found])
    order = max(_ORDER[x[0]] for x in found)

    c, fc, d, fd = _search(trajectory, robot, found, J, a, b, ends, order, backend, iterations)
    for (_, _, best, best_t, *_), i0, i1 in zip(found, ends[:-1], ends[1:]):
        Jq = J[i0:i1]
        for t_best, f_best in ((c[i0:i1], fc[i0:i1]), (d[i0:i1], fd[i0:i1])):
            for j in np.unique(Jq):
                mine = np.flatnonzero(Jq == j)
                i = mine[np.argmax(f_best[mine])]
                if f_best[i] > best[j]:
                    best[j], best_t[j] = f_best[i], t_best[i]


def _search(trajectory, robot, found, J, a, b, ends, order, backend, iterations):
    """Golden-section search of every candidate of :func:`_refine` at once, in numpy:
    ``(c, f(c), d, f(d))``, the last two probes of each bracket and their ratios."""

    def f(t):
        D = trajectory.derivatives(t, order)
        out = np.empty(len(t))
        for (quantity, norm, *_), i0, i1 in zip(found, ends[:-1], ends[1:]):
            part = [d[i0:i1] for d in D]
            out[i0:i1] = _normalized(part, robot, quantity, norm, backend)[np.arange(i1 - i0), J[i0:i1]]
        return out

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
    return c, fc, d, fd


def _batch_dynamics(robot):
    """One :class:`BatchDynamics` per robot object (compiled once, kept while the robot lives)."""
    from drake_mh.trajectories.dynamics import batch_dynamics

    return batch_dynamics(robot)
