"""A certified joint-space connection where the straight line between two configurations is not.

The follower executes the motion between two consecutive path points as a straight line in
joint space. Where the IK switches branch around an obstacle (framework paper §3.4.2 windows:
1-3.7 rad steps measured), that line can sweep through the obstacle although both ends are
verified (hybrid, seed 2: -0.021 m). Not in the paper: before such a line is executed, the
follower asks :func:`find_detour` for *via configurations* ``v_1 .. v_m`` (``m <= 2``) such
that every straight piece of ``q_a -> v_1 -> .. -> v_m -> q_b`` is certified collision-free by
:func:`drake_mh.scene.segments.certify_segments` (the conservative sphere model, every
configuration on the piece, obstacles moving with their velocities when a duration is given).

The search is a small randomized one (a local roadmap of at most two vias), in rounds of
growing spread:

1. ``candidates`` configurations ``q_a + s (q_b - q_a) + σ ε`` (``s ~ U(0, 1)``,
   ``ε ~ N(0, I)``, clipped to the joint limits), ``σ`` from ``spreads`` [rad]; those not
   certified free by :meth:`drake_mh.scene.Scene.collision_free` are dropped (one SIMD batch);
2. **one via**: the pieces ``q_a -> v`` and ``v -> q_b`` of every candidate are certified in
   one batch; the shortest certified chain (joint-space length) wins;
3. **two vias**: otherwise, among the candidates reachable from ``q_a`` (set A) and those that
   reach ``q_b`` (set B) of every round so far, the pieces ``a -> b`` (at most
   ``max_pairs``, shortest chains first) are certified in one batch.

The time of the whole connection is the segment's: with a ``duration`` the pieces share it in
proportion to their joint-space length, and each piece is certified against the obstacles
where they are when it starts (:func:`drake_mh.scene.segments.certify_path`), one chain at a
time. Same seed, same detour.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["Detour", "DetourConfig", "find_detour", "ChainCertificate", "certify_chains", "chain_durations",
           "obstacles_moved", "any_moving"]


@dataclass(frozen=True)
class DetourConfig:
    """Settings of :func:`find_detour`.

    Attributes:
        candidates: via candidates drawn per round (default 256: one SIMD batch is a few ms).
        spreads: ``σ`` of each round [rad] (default 0.2, 0.5, 1.0, 2.0: near the line first).
        max_vias: 1 or 2 (default 2).
        max_pairs: most two-via chains certified per round (default 4096).
    """

    candidates: int = 256
    spreads: tuple = (0.2, 0.5, 1.0, 2.0)
    max_vias: int = 2
    max_pairs: int = 4096

    def __post_init__(self):
        if isinstance(self.candidates, bool) or int(self.candidates) != self.candidates or self.candidates < 1:
            raise InvalidArgument(f"DetourConfig.candidates must be a positive integer, got {self.candidates!r}")
        spreads = tuple(self.spreads) if isinstance(self.spreads, (tuple, list)) else ()
        if not spreads or not all(isinstance(s, (int, float)) and np.isfinite(s) and s > 0 for s in spreads):
            raise InvalidArgument(f"DetourConfig.spreads must be a non-empty tuple of positive spreads [rad], "
                                  f"got {self.spreads!r}")
        object.__setattr__(self, "spreads", spreads)
        if self.max_vias not in (1, 2):
            raise InvalidArgument(f"DetourConfig.max_vias must be 1 or 2, got {self.max_vias!r}")
        if isinstance(self.max_pairs, bool) or int(self.max_pairs) != self.max_pairs or self.max_pairs < 1:
            raise InvalidArgument(f"DetourConfig.max_pairs must be a positive integer, got {self.max_pairs!r}")


@dataclass(frozen=True)
class Detour:
    """The outcome of one :func:`find_detour`.

    Attributes:
        found: a certified connection was found.
        vias: ``(m, nq)`` via configurations [rad] (``m = 0`` when not found).
        min_clearance: certified lower bound of the obstacle clearance along the connection [m]
            (NaN when not found).
        length, straight_length: joint-space length [rad] (Euclidean) of the connection and of
            the straight line ``q_a -> q_b``.
        candidates: via candidates drawn; free: of those, certified free.
        segments_checked: straight pieces certified (every batch); evaluations: configurations
            evaluated by those certificates.
        time: [s]; reason: one line (why not found).
    """

    found: bool
    vias: np.ndarray
    min_clearance: float
    length: float
    straight_length: float
    candidates: int
    free: int
    segments_checked: int
    evaluations: int
    time: float
    reason: str = ""

    @property
    def extra_length(self) -> float:
        """``length - straight_length`` [rad] (NaN when not found)."""
        return self.length - self.straight_length if self.found else float("nan")


def chain_durations(chain: np.ndarray, duration: float) -> np.ndarray:
    """``(len(chain) - 1,)`` seconds per straight piece of ``chain (m + 2, nq)``: ``duration`` shared in
    proportion to the pieces' joint-space lengths (evenly when they are all zero)."""
    lengths = np.linalg.norm(np.diff(chain, axis=0), axis=1)
    total = lengths.sum()
    if total <= 0:
        return np.full(len(lengths), duration / max(1, len(lengths)))
    return duration * lengths / total


class obstacles_moved:
    """Context: the scene's moving obstacles advanced by ``velocity · elapsed`` [s], put back on exit."""

    def __init__(self, scene, elapsed: float):
        self.scene, self.elapsed = scene, float(elapsed)
        self.start = {}

    def __enter__(self):
        if self.elapsed != 0.0:
            for name, o in self.scene.obstacles.items():
                if np.any(o.velocity_W != 0):
                    self.start[name] = o.position
                    self.scene.move(name, position=o.position + o.velocity_W * self.elapsed)
        return self.scene

    def __exit__(self, *exc):
        for name, p in self.start.items():
            self.scene.move(name, position=p)
        return False


def any_moving(scene) -> bool:
    """Whether some obstacle of ``scene`` has a velocity."""
    return any(np.any(o.velocity_W != 0) for o in scene.obstacles.values())


@dataclass(frozen=True)
class ChainCertificate:
    """The verdict on consecutive motions, each a chain of straight pieces (:func:`certify_chains`).

    Attributes:
        certified: ``(K,)`` every piece of chain k certified.
        lower: ``(K,)`` certified lower bound of the obstacle clearance along chain k [m] (NaN
            where not certified).
        path: the :class:`drake_mh.scene.segments.PathCertificate` of all pieces in order.
        piece_chain: ``(P,)`` the chain each piece belongs to.
    """

    certified: np.ndarray
    lower: np.ndarray
    path: object
    piece_chain: np.ndarray

    @property
    def all_certified(self) -> bool:
        return bool(np.all(self.certified))

    @property
    def min_clearance(self) -> float:
        """Certified lower bound over every chain [m] (NaN if one is not certified; inf if none)."""
        if not self.all_certified:
            return float("nan")
        return float(np.min(self.lower)) if len(self.lower) else float("inf")

    def reason(self, k: int) -> str:
        """One line on chain ``k`` (its first piece not certified)."""
        pieces = np.flatnonzero((self.piece_chain == k) & ~self.path.segments.certified)
        if not len(pieces):
            return self.path.segments.reason(int(np.flatnonzero(self.piece_chain == k)[0]))
        first = int(pieces[0])
        n = int(np.sum(self.piece_chain == k))
        where = f"piece {first - int(np.flatnonzero(self.piece_chain == k)[0]) + 1} of {n}: " if n > 1 else ""
        return where + self.path.segments.reason(first)


def certify_chains(scene, chains, clearance: float = 0.0, self_clearance: float = 0.0, *, durations=None,
                   tolerance: float = np.inf) -> ChainCertificate:
    """Certify consecutive motions ``chains[k] (m_k + 2, nq)`` (each straight between its rows).

    Args:
        scene: the scene, obstacles where they are when the first chain starts.
        chains: consecutive chains (chain k ends where chain k + 1 starts).
        clearance, self_clearance, tolerance: as :func:`drake_mh.scene.segments.certify_path`.
        durations: ``(K,)`` seconds per chain, shared by its pieces in proportion to their
            joint-space length (:func:`chain_durations`); used only where an obstacle moves.

    Returns:
        A :class:`ChainCertificate`.
    """
    chains = [np.asarray(c, float) for c in chains]
    poly = np.vstack([chains[0][:1]] + [c[1:] for c in chains])
    piece_chain = np.concatenate([np.full(len(c) - 1, k) for k, c in enumerate(chains)]).astype(int)
    piece_durations = None
    if durations is not None and any_moving(scene):
        piece_durations = np.concatenate([chain_durations(c, float(d)) for c, d in zip(chains, durations)])
    cert = scene.certify_path(poly, clearance, self_clearance, durations=piece_durations, tolerance=tolerance)
    seg = cert.segments
    K = len(chains)
    certified = np.array([bool(np.all(seg.certified[piece_chain == k])) for k in range(K)])
    lower = np.array([float(np.min(seg.lower[piece_chain == k])) if certified[k] else np.nan for k in range(K)])
    return ChainCertificate(certified, lower, cert, piece_chain)


def find_detour(scene, q_a, q_b, *, clearance: float = 0.0, self_clearance: float = 0.0,
                duration: float | None = None, seed=0, config: DetourConfig | None = None) -> Detour:
    """Via configurations that connect ``q_a`` to ``q_b`` with a certified motion (module docstring).

    Args:
        scene: the :class:`drake_mh.scene.Scene` (obstacles where they are when the motion starts).
        q_a, q_b: ``(nq,)`` the two configurations [rad].
        clearance, self_clearance: required along the whole connection [m].
        duration: seconds the connection takes (obstacles move with their velocities); ``None``:
            they stand still.
        seed: of the candidates (a ``numpy`` seed or ``SeedSequence`` entropy).
        config: :class:`DetourConfig`.

    Returns:
        A :class:`Detour` (``found`` False with the reason when none was found: an end that is
        not free itself, or no chain certified).
    """
    start = time.perf_counter()
    config = config if config is not None else DetourConfig()
    robot = scene.robot
    q_a, q_b = robot.check_q(q_a, "q_a"), robot.check_q(q_b, "q_b")
    nq = robot.nq
    count = {"drawn": 0, "free": 0, "checked": 0, "evaluations": 0}
    duration = float(duration) if duration is not None and any_moving(scene) else None

    def result(vias, lower, reason=""):
        chain = np.vstack([q_a, *vias, q_b])
        length = float(np.linalg.norm(np.diff(chain, axis=0), axis=1).sum())
        return Detour(bool(len(vias)), np.asarray(vias, float).reshape(-1, nq), lower,
                      length if len(vias) else float("nan"), float(np.linalg.norm(q_b - q_a)), count["drawn"],
                      count["free"], count["checked"], count["evaluations"], time.perf_counter() - start, reason)

    def pieces(QA, QB, elapsed=0.0):
        """Certify straight pieces in one batch (moving obstacles: as they are ``elapsed`` s from now,
        standing still — a screen, the chain is certified with their motion afterwards)."""
        with obstacles_moved(scene, elapsed):
            cert = scene.certify_segments(QA, QB, clearance, self_clearance)
        count["checked"] += len(QA)
        count["evaluations"] += int(cert.evaluations.sum())
        return cert.certified, cert.lower

    def moving_chain(chain):
        cert = certify_chains(scene, [chain], clearance, self_clearance, durations=[duration])
        count["checked"] += len(chain) - 1
        count["evaluations"] += int(cert.path.segments.evaluations.sum())
        return cert.all_certified, cert.min_clearance

    ends_free = np.array([scene.collision_free(q_a, clearance, self_clearance), False])
    with obstacles_moved(scene, duration or 0.0):
        ends_free[1] = scene.collision_free(q_b, clearance, self_clearance)
    if not ends_free.all():
        which = "start" if not ends_free[0] else "end"
        return result([], float("nan"), f"the {which} configuration itself is not certified free "
                                         f"(clearance {clearance} m): no motion can connect it")
    rng = np.random.default_rng(seed)
    A, A_low = np.zeros((0, nq)), np.zeros(0)   # vias certified from q_a (every round so far)
    B, B_low = np.zeros((0, nq)), np.zeros(0)   # vias certified to q_b
    for spread in config.spreads:
        V = q_a + rng.random((config.candidates, 1)) * (q_b - q_a) \
            + spread * rng.standard_normal((config.candidates, nq))
        V = np.clip(V, robot.lower, robot.upper)
        count["drawn"] += len(V)
        V = V[scene.collision_free(V, clearance, self_clearance)]
        count["free"] += len(V)
        if not len(V):
            continue
        from_a, low_a = pieces(np.broadcast_to(q_a, V.shape), V)
        to_b, low_b = pieces(V, np.broadcast_to(q_b, V.shape), 0.5 * (duration or 0.0))
        # one via, shortest chain first
        length = np.linalg.norm(V - q_a, axis=1) + np.linalg.norm(q_b - V, axis=1)
        for i in np.flatnonzero(from_a & to_b)[np.argsort(length[from_a & to_b])][:64]:
            if duration is None:
                return result([V[i]], float(min(low_a[i], low_b[i])))
            ok, low = moving_chain(np.vstack([q_a, V[i], q_b]))
            if ok:
                return result([V[i]], low)
        A, A_low = np.vstack([A, V[from_a]]), np.concatenate([A_low, low_a[from_a]])
        B, B_low = np.vstack([B, V[to_b]]), np.concatenate([B_low, low_b[to_b]])
        if config.max_vias < 2 or not len(A) or not len(B):
            continue
        # two vias: a -> b of the shortest chains q_a -> a -> b -> q_b
        total = (np.linalg.norm(A - q_a, axis=1)[:, None] + np.linalg.norm(A[:, None] - B[None], axis=2)
                 + np.linalg.norm(q_b - B, axis=1)[None])
        ia, ib = np.unravel_index(np.argsort(total, axis=None)[:config.max_pairs], total.shape)
        ok_ab, low_ab = pieces(A[ia], B[ib], 0.5 * (duration or 0.0))
        for k in np.flatnonzero(ok_ab)[:64]:   # sorted by length: the first is the shortest
            if duration is None:
                return result([A[ia[k]], B[ib[k]]], float(min(A_low[ia[k]], low_ab[k], B_low[ib[k]])))
            ok, low = moving_chain(np.vstack([q_a, A[ia[k]], B[ib[k]], q_b]))
            if ok:
                return result([A[ia[k]], B[ib[k]]], low)
    return result([], float("nan"),
                  f"no certified connection with at most {config.max_vias} vias among {count['drawn']} "
                  f"candidates ({count['free']} free), spreads {config.spreads} rad")
