"""Certified straight joint-space segments and piecewise-linear paths.

A motion the library returns is executed as straight lines in joint space between its
configurations; checking its points says nothing about what it sweeps between them (the
framework follower's hybrid run, seed 2, passed 21 mm through an obstacle between two verified
points). :func:`certify_segments` proves a segment clear *for every configuration on it*, or
finds a configuration on it that is not, by the bisection of :mod:`.kernels.segments`:

* each constraint value (per link: its spheres' clearance to the obstacles; per checked link
  pair: their spheres' distance) is Lipschitz along the segment, with a constant computed from
  the joint deltas and how far each sphere can be from each joint axis (read from the plant,
  :attr:`drake_mh.scene.batch.CollisionModel.reach`);
* a link's value also curves by a bounded amount where no obstacle is a convex mesh piece (the
  distance to a convex obstacle curves by at most one over the distance, and a sphere's
  acceleration along the segment is bounded by the same reach), so on a piece it stays above
  its chord less a parabola that shrinks as the square of the piece's length;
* a piece is certified when the bound (the larger of ``(V0 + V1 - Λ h) / 2`` and the
  parabola's minimum) is at least the clearance for every value; otherwise it is cut in two,
  and all new midpoints of a level are evaluated in one SIMD batch.

The sphere model never reads more clearance than the exact geometry has
(:mod:`drake_mh.geometry.spheres`), so a certified segment is clear for the exact collision geometry
too. The converse is conservative: a segment that passes within ``sphere_model.bound`` of an
obstacle may be reported blocked.

Where the compiled core is built (:mod:`drake_mh.scene.compiled_check`), its port of that
kernel answers (``drake_mh._native.Clearances.certify_segments``: the same verdicts, nothing
compiled at call time); with ``DRAKE_MH_COMPILED_CORE=0`` or without it, the numba kernel. The
port runs all segments of a call level by level, each level's configurations in one batch, and
a segment that starts where the last one ended reads that end's values; a value above the fine
level (5 cm above the requirement) is a lower bound that may depend on its batch, so evaluations
and loose bounds can differ from the numba kernel's, never a verdict's soundness.

Moving obstacles (``durations``): an obstacle with velocity ``v`` moves ``v · duration`` during
the segment; the bound then adds its displacement to every link's Lipschitz constant, and the
configurations are evaluated against the obstacles where they are at that instant.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.errors import SceneError
from drake_mh.scene.kernels import segments as SK

MIN_PIECE = 1e-9
"""Shortest piece of a segment (in its parameter t in [0, 1]) before a piece is undecided."""

MAX_EVALUATIONS = 1 << 16
"""Most configurations evaluated per segment before it is undecided."""

RAISED_TRIES = 4
"""Certificates at a raised clearance :func:`_tighten` tries before a per-segment minimum search."""

RAISED_PROBES = 33
"""Evenly spaced configurations of a segment blocked at a raised clearance whose clearances
:func:`_tighten` reads for the next, lower, level (with the blocking configuration)."""


def check_clearance(value, what: str) -> float:
    """``value`` as a finite length >= 0 [m], or :class:`SceneError` naming ``what``."""
    if isinstance(value, (bool, str, bytes)) or not isinstance(value, (int, float, np.number)) \
            or not np.isfinite(value) or value < 0:
        raise SceneError(f"{what} must be a finite length >= 0 in metres, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class SegmentCertificate:
    """The verdict on M straight segments ``QA[i] -> QB[i]``.

    Attributes:
        status: ``(M,)`` 1 certified, 0 blocked (a configuration on it is below the clearance
            under the sphere model), -1 undecided (budget or resolution exhausted: treat as
            not certified).
        t_stop: ``(M,)`` where on the segment (0..1) the blocking configuration or the
            undecided piece is; NaN where certified.
        lower: ``(M,)`` certified lower bound of the obstacle clearance over the whole segment
            [m] (``inf`` without obstacles); NaN where not certified.
        lower_self: ``(M,)`` the same for the self-collision pairs (``inf`` without any).
        evaluations: ``(M,)`` configurations evaluated.
        clearance, self_clearance: what was required [m].
    """

    status: np.ndarray
    t_stop: np.ndarray
    lower: np.ndarray
    lower_self: np.ndarray
    evaluations: np.ndarray
    clearance: float
    self_clearance: float

    @property
    def certified(self) -> np.ndarray:
        """``(M,)`` bool."""
        return self.status == SK.CERTIFIED

    @property
    def all_certified(self) -> bool:
        return bool(np.all(self.certified))

    @property
    def min_clearance(self) -> float:
        """Certified lower bound of the obstacle clearance over every segment [m]; NaN if some
        segment is not certified."""
        return float(np.min(self.lower)) if self.all_certified and len(self.lower) else float("nan")

    def reason(self, i: int) -> str:
        """One line on segment ``i``."""
        if self.status[i] == SK.CERTIFIED:
            return f"certified: clearance >= {self.lower[i]:.4f} m along the whole segment"
        if self.status[i] == SK.BLOCKED:
            return (f"blocked at t = {self.t_stop[i]:.4f}: a configuration closer than {self.clearance} m to an "
                    f"obstacle (or {self.self_clearance} m between links) under the sphere model")
        return (f"undecided at t = {self.t_stop[i]:.4f} after {self.evaluations[i]} configurations: the motion "
                "touches the required clearance (treat as not certified)")

    def __repr__(self) -> str:
        n = len(self.status)
        ok = int(np.sum(self.certified))
        tail = f", min clearance {self.min_clearance:.4f} m" if ok == n and n else ""
        return f"SegmentCertificate({ok}/{n} certified{tail})"


def _as_rows(robot, Q, what: str) -> np.ndarray:
    try:
        return np.ascontiguousarray(robot.check_Q(Q))
    except SceneError:
        raise
    except Exception as exc:  # the robot's own error names the joint; say which argument
        raise type(exc)(f"{what}: {exc}") from None


def certify_segments(scene, QA, QB, clearance: float = 0.0, self_clearance: float = 0.0, *,
                     tolerance: float = np.inf, duration: float | None = None,
                     max_evaluations: int = MAX_EVALUATIONS) -> SegmentCertificate:
    """Certify straight joint-space segments ``QA[i] -> QB[i]`` against ``scene``.

    Args:
        scene: the :class:`drake_mh.scene.Scene` (its obstacles as they are now; with
            ``self_collision``, its link pairs too).
        QA, QB: ``(M, nq)`` start and end configurations (or one ``(nq,)`` each).
        clearance: required distance to every obstacle [m].
        self_clearance: required distance between checked link pairs [m].
        tolerance: also refine certified pieces until the reported ``lower`` is within this of
            the smallest clearance seen at evaluated configurations [m] (``inf``: stop at the
            first certificate; a report wants e.g. 1e-3). It concerns the obstacle clearance:
            link pairs are certified, and ``lower_self`` is a valid bound, not a tight one.
        duration: seconds each segment takes: obstacles then move with their velocities during
            it (from where they are now). ``None``: they stand still.
        max_evaluations: most configurations per segment before it is undecided.

    Returns:
        A :class:`SegmentCertificate`.

    Raises:
        SceneError: no collision geometry, bad clearances; the robot's errors for bad
            configurations (shape, non-finite, outside the limits).
    """
    scene._require_geometry()
    clearance = check_clearance(clearance, "clearance")
    self_clearance = check_clearance(self_clearance, "self_clearance")
    if not (isinstance(tolerance, (int, float, np.number)) and not isinstance(tolerance, bool) and tolerance > 0):
        raise SceneError(f"tolerance must be a length > 0 in metres (inf: certification only), got {tolerance!r}")
    if isinstance(max_evaluations, bool) or not isinstance(max_evaluations, (int, np.integer)) or max_evaluations < 2:
        raise SceneError(f"max_evaluations must be an integer >= 2, got {max_evaluations!r}")
    robot = scene.robot
    QA, QB = _as_rows(robot, QA, "QA"), _as_rows(robot, QB, "QB")
    if QA.shape != QB.shape:
        raise SceneError(f"QA and QB must hold the same number of configurations, got {QA.shape[0]} and {QB.shape[0]}")
    model = scene.collision_model
    kinds, R_WO, p_WO, v_WO, dims = scene.obstacle_arrays
    speed = 0.0
    if duration is not None:
        if isinstance(duration, bool) or not isinstance(duration, (int, float, np.number)) \
                or not np.isfinite(duration) or duration < 0:
            raise SceneError(f"duration must be a finite number of seconds >= 0, got {duration!r}")
        v_WO = np.array([o.velocity_W * float(duration) for o in scene.obstacles.values()]).reshape(-1, 3)
        v_WO = v_WO[scene.obstacle_owners]  # per kernel obstacle (a mesh's pieces move with it)
        speed = float(np.max(np.linalg.norm(v_WO, axis=1), initial=0.0))
    v_WO = np.ascontiguousarray(v_WO, dtype=float).reshape(-1, 3)
    compiled = model.compiled_clearances(scene.obstacle_arrays, pairs=True)
    if compiled is not None:  # the compiled core: the kernel's verdicts, nothing compiled at call time
        status, t_stop, lower, lower_self, evals = compiled.certify_segments(
            QA, QB, model.reach, v_WO, speed, clearance, self_clearance, float(tolerance), MIN_PIECE,
            int(max_evaluations))
        return SegmentCertificate(status, t_stop, lower, lower_self, evals, clearance, self_clearance)
    M = QA.shape[0]
    status, t_stop = np.empty(M, np.int64), np.empty(M)
    lower, lower_self, evals = np.empty(M), np.empty(M), np.empty(M, np.int64)
    SK.certify_segments(QA, QB, model.reach, speed, clearance, self_clearance, float(tolerance), MIN_PIECE,
                        int(max_evaluations), *model._kernel_args(), kinds, R_WO, p_WO, v_WO, dims, *model.pair_arrays,
                        status, t_stop, lower, lower_self, evals)
    return SegmentCertificate(status, t_stop, lower, lower_self, evals, clearance, self_clearance)


@dataclass(frozen=True)
class PathCertificate:
    """The verdict on a piecewise-linear joint-space motion through ``Q (M, nq)``.

    Attributes:
        segments: the :class:`SegmentCertificate` of its ``M - 1`` segments.
        certified: every segment certified (a single configuration: that it is free).
        min_clearance: certified lower bound of the obstacle clearance along the whole motion
            [m] (NaN if not certified; ``inf`` without obstacles).
        first_failure: index of the first segment not certified (None if certified).
    """

    segments: SegmentCertificate
    certified: bool
    min_clearance: float
    first_failure: int | None

    def __repr__(self) -> str:
        if self.certified:
            return f"PathCertificate(certified, min clearance {self.min_clearance:.4f} m)"
        return f"PathCertificate(segment {self.first_failure}: {self.segments.reason(self.first_failure)})"


TIGHTEN_PROBES = (0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875)
"""Fractions of a segment that may need refining where :func:`_tighten` reads the sphere-model
clearance first: the smaller the smallest value seen, the fewer raised certificates are blocked
and tried again."""


SMALLEST_BATCH = 16
"""Configurations :func:`_smallest_above` evaluates per batch, those that can hold the minimum down first."""


def _smallest_above(scene, X: np.ndarray, floor: np.ndarray) -> float:
    """``min(scene.batch_min_distance(X))`` for configurations ``X (N, nq)`` whose
    sphere-model clearances are known to be at least ``floor (N,)`` (certified bounds of segments
    they lie on), evaluating only those that can hold it down: in batches of
    :data:`SMALLEST_BATCH` by floor, lowest first, until the next floor is not below the
    smallest value found (no later one can go below it). The same value as evaluating all."""
    order, best = np.argsort(floor, kind="stable"), np.inf
    for start in range(0, len(order), SMALLEST_BATCH):
        rows = order[start:start + SMALLEST_BATCH]
        if not floor[rows[0]] < best:
            break
        best = min(best, float(np.min(scene.batch_min_distance(X[rows]))))
    return best


def _row_floors(lower: np.ndarray) -> np.ndarray:
    """``(M,)`` for a path of ``M - 1`` segments certified with bounds ``lower``: a row ends one
    or two segments, so its clearance is at least the larger of their bounds."""
    floor = np.full(len(lower) + 1, -np.inf)
    floor[:-1] = lower
    floor[1:] = np.maximum(floor[1:], lower)
    return floor


def _tighten(scene, Q: np.ndarray, cert: SegmentCertificate, clearance: float, self_clearance: float,
             tolerance: float, max_evaluations: int) -> SegmentCertificate:
    """Refine only the segments whose bound could hold the path's minimum down by more than
    ``tolerance``.

    The path's smallest clearance is at most ``U``, the sphere-model clearance at its waypoints
    and at :data:`TIGHTEN_PROBES` of every segment whose ``lower`` is below the waypoints' ``U``
    less ``tolerance`` (configurations on it; ``U`` only falls, so a segment not probed needs no
    refining). A segment certified with ``lower >= U - tolerance`` already keeps the path's bound
    within ``tolerance`` of that minimum; only the others are first certified at the raised
    clearance ``U - tolerance / 2`` (a plain certificate: pieces are cut only until their bound
    clears that level, no per-segment minimum is searched), which puts their ``lower`` within
    ``tolerance`` of ``U``. Where one is blocked
    (a configuration on it is below that level), the smallest clearance of that configuration and
    of :data:`RAISED_PROBES` evenly spaced ones of the segment is a smaller value seen: ``U``
    takes it (a segment whose ``lower`` is within ``tolerance`` of it is done) and the segments
    not yet certified try again, at most :data:`RAISED_TRIES` times. Those still not certified are certified again with
    ``tolerance`` (each then within it of its own minimum, which is at least the path's). Same
    promise as refining every segment, at a fraction of the cost where most segments keep well
    clear (measured 0.15 s instead of 7.6 s on a MotionBenchMaker path of the meshed Panda; the
    raised certificate: about 5-10 ms instead of 90-130 ms on sampled trajectories there). The
    bounds stay certified whatever ``U`` is: it only chooses what to refine and to which level.
    """
    if not cert.all_certified or not len(cert.lower) or not np.all(np.isfinite(cert.lower)):
        return cert
    upper = _smallest_above(scene, Q, _row_floors(cert.lower))
    refine = np.flatnonzero(cert.lower < upper - tolerance)
    if len(refine):  # only a segment that may need refining is probed: ``upper`` only falls
        QA, dQ = Q[:-1][refine], Q[1:][refine] - Q[:-1][refine]
        probes = np.vstack([QA + f * dQ for f in TIGHTEN_PROBES])
        upper = min(upper, float(np.min(scene.batch_min_distance(probes))))  # all: their segments are low
        refine = refine[cert.lower[refine] < upper - tolerance]
    if not len(refine):
        return cert
    lower, evaluations = cert.lower.copy(), cert.evaluations.copy()
    for _ in range(RAISED_TRIES):
        level = upper - 0.5 * tolerance
        if not len(refine) or level <= clearance:
            break
        QA, QB = Q[:-1][refine], Q[1:][refine]
        raised = certify_segments(scene, QA, QB, level, self_clearance, max_evaluations=max_evaluations)
        ok = raised.certified
        lower[refine[ok]] = np.maximum(lower[refine[ok]], raised.lower[ok])
        evaluations[refine] += raised.evaluations
        blocked = raised.status == SK.BLOCKED  # a configuration there is below the level: a new smallest seen
        refine = refine[~ok]
        if not np.any(blocked):
            break
        t = np.c_[raised.t_stop[blocked], np.tile(np.linspace(0.0, 1.0, RAISED_PROBES), (int(np.sum(blocked)), 1))]
        on = QA[blocked][:, None, :] + t[:, :, None] * (QB[blocked] - QA[blocked])[:, None, :]
        seen = float(np.min(scene.batch_min_distance(on.reshape(-1, Q.shape[1]))))
        if not seen < upper:
            break
        upper = seen
        refine = refine[lower[refine] < upper - tolerance]  # those already within it of the new smallest are done
    if len(refine):
        fine = certify_segments(scene, Q[:-1][refine], Q[1:][refine], clearance, self_clearance,
                                tolerance=tolerance, max_evaluations=max_evaluations)
        ok = fine.certified
        lower[refine[ok]] = np.maximum(lower[refine[ok]], fine.lower[ok])
        evaluations[refine] += fine.evaluations
    return SegmentCertificate(cert.status, cert.t_stop, lower, cert.lower_self, evaluations, cert.clearance,
                              cert.self_clearance)


def certify_path(scene, Q, clearance: float = 0.0, self_clearance: float = 0.0, *, tolerance: float = np.inf,
                 durations=None, max_evaluations: int = MAX_EVALUATIONS) -> PathCertificate:
    """Certify the motion through the rows of ``Q (M, nq)``, straight in joint space between them.

    Args:
        durations: ``(M - 1,)`` seconds per segment: obstacles move with their velocities from
            where they are now, segment after segment. ``None``: they stand still.
        clearance, self_clearance, max_evaluations: as :func:`certify_segments`.
        tolerance: refine until the path's ``min_clearance`` is within this of its smallest
            value [m] (``inf``: certification only). Without ``durations`` only the segments that
            can hold the minimum down are refined (:func:`_tighten`), so each segment's
            ``lower`` is a valid bound but not necessarily within ``tolerance`` of its own
            minimum; with ``durations``, every segment as in :func:`certify_segments`.

    Returns:
        A :class:`PathCertificate`.

    Raises:
        SceneError: ``Q`` holds no configuration; as :func:`certify_segments` otherwise.
    """
    robot = scene.robot
    Q = _as_rows(robot, Q, "Q")
    if Q.shape[0] == 0:
        raise SceneError(f"Q must hold at least one configuration (M, {robot.nq}) to certify, got none")
    if Q.shape[0] == 1:
        Q = np.vstack([Q, Q])  # one configuration: a zero-length segment
    if durations is None:
        cert = certify_segments(scene, Q[:-1], Q[1:], clearance, self_clearance, max_evaluations=max_evaluations)
        if np.isfinite(tolerance):
            cert = _tighten(scene, Q, cert, clearance, self_clearance, float(tolerance), max_evaluations)
    else:
        durations = np.asarray(durations, dtype=float).reshape(-1)
        if durations.shape != (Q.shape[0] - 1,) or not np.all(np.isfinite(durations)) or np.any(durations < 0):
            raise SceneError(f"durations must be {Q.shape[0] - 1} finite numbers of seconds >= 0 (one per segment)")
        parts = []
        moving = {name: o for name, o in scene.obstacles.items() if np.any(o.velocity_W != 0)}
        start = {name: o.position for name, o in moving.items()}
        elapsed = 0.0
        try:
            for i, dt in enumerate(durations):
                for name, o in moving.items():
                    scene.move(name, position=start[name] + o.velocity_W * elapsed)
                parts.append(certify_segments(scene, Q[i], Q[i + 1], clearance, self_clearance,
                                              tolerance=tolerance, duration=float(dt),
                                              max_evaluations=max_evaluations))
                elapsed += float(dt)
        finally:  # the scene as it was
            for name in moving:
                scene.move(name, position=start[name])
        cert = SegmentCertificate(*(np.concatenate([getattr(p, f) for p in parts])
                                    for f in ("status", "t_stop", "lower", "lower_self", "evaluations")),
                                  parts[0].clearance, parts[0].self_clearance)
    return _path_certificate(cert)


def _path_certificate(cert: SegmentCertificate) -> PathCertificate:
    bad = np.flatnonzero(~cert.certified)
    first = int(bad[0]) if len(bad) else None
    return PathCertificate(cert, first is None, cert.min_clearance, first)


def refine_path(scene, Q, certificate: PathCertificate, tolerance: float,
                max_evaluations: int = MAX_EVALUATIONS) -> PathCertificate:
    """``certificate``, from :func:`certify_path` on the same ``Q`` without ``durations`` or
    ``tolerance``, refined as ``certify_path(scene, Q, ..., tolerance=tolerance)`` would refine
    it (the same bounds), without certifying its segments again.

    Raises:
        SceneError: ``certificate`` is not one of ``Q``'s segments; bad ``tolerance``.
    """
    Q = _as_rows(scene.robot, Q, "Q")
    if Q.shape[0] == 1:
        Q = np.vstack([Q, Q])
    segments = certificate.segments
    if len(segments.status) != Q.shape[0] - 1:
        raise SceneError(f"the certificate holds {len(segments.status)} segments, Q {Q.shape[0] - 1}: certify Q itself")
    if not (isinstance(tolerance, (int, float, np.number)) and not isinstance(tolerance, bool) and tolerance > 0):
        raise SceneError(f"tolerance must be a length > 0 in metres, got {tolerance!r}")
    if not np.isfinite(tolerance):
        return certificate
    return _path_certificate(_tighten(scene, Q, segments, segments.clearance, segments.self_clearance,
                                      float(tolerance), max_evaluations))
