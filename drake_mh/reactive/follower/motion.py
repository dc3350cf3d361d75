"""The follower's executed motion, certified collision-free between its points (not in the paper).

The framework paper predicts and regenerates the configurations *at* the path points (§3.4.1)
and executes the motion between two points as it comes; a branch switch (1-3.7 rad joint
steps measured in §3.4.2 windows) then swept through the obstacle between two verified points
(hybrid, seed 2: -0.021 m). Here the motion between point ``k`` and ``k + 1`` is the *chain*
``Q[k] -> vias[k] -> Q[k + 1]`` (straight in joint space between its rows; no vias: the straight
line), and:

* **after the plan and after every regeneration** (:meth:`CertifiedMotion._secure_motion`),
  every remaining chain is certified with :func:`drake_mh.reactive.follower.detour.certify_chains`
  (the scene's conservative sphere model, every configuration on it, clearance
  ``FollowerConfig.motion_clearance``; with the path's ``times`` the obstacles move with their
  velocities during each chain). A chain that is not certified is replaced by a detour
  (:func:`drake_mh.reactive.follower.detour.find_detour`: at most two via configurations) or, if
  none is found, recorded as blocked;
* **when the arm moves** (:meth:`CertifiedMotion._gate`), the chain it is about to execute is
  certified against the scene *as it is then*, with ``motion_tolerance`` for a tight reported
  clearance; if it is not certified a detour is searched once more, and if none is found the arm
  **does not move** (``halted``, ``halts``): an uncertified line is never executed.

Every search is a :class:`DetourRecord` in ``follower.detours`` (when, which segment, found,
vias, time, evaluations, extra joint-space length, how far the tool leaves the straight line
between the two path points).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.reactive.follower.detour import any_moving, certify_chains, find_detour, obstacles_moved

__all__ = ["DetourRecord", "CertifiedMotion", "polyline"]


@dataclass(frozen=True)
class DetourRecord:
    """One detour search of the follower.

    Attributes:
        when: ``"plan"``, the event number (int) of :meth:`react`, or ``"advance"``.
        segment: k: the motion from point k to point k + 1.
        found: a certified connection was found (else the segment is blocked).
        vias: number of via configurations.
        time: [s] of the search; evaluations: configurations evaluated by its certificates.
        straight_length, extra_length: joint-space length [rad] of the straight line, and what the
            detour adds (NaN when not found).
        tool_deviation: [m] largest distance of the tool from the straight line between the two
            path points along the detour (NaN when not found; sampled, 20 per piece);
            ``straight_tool_deviation``: the same along the straight joint-space line it replaces
            (a branch switch leaves the Cartesian path either way).
        reason: why the straight line was refused (first piece not certified), and why no
            detour was found.
    """

    when: object
    segment: int
    found: bool
    vias: int
    time: float
    evaluations: int
    straight_length: float
    extra_length: float
    tool_deviation: float
    straight_tool_deviation: float
    reason: str


def _anything_to_hit(scene) -> bool:
    return bool(scene.obstacles) or bool(getattr(scene, "self_collision", False))


def polyline(chains) -> np.ndarray:
    """The rows of consecutive chains ``[(m_k + 2, nq)]`` as one ``(M, nq)`` polyline (shared ends once)."""
    chains = [np.asarray(c, float) for c in chains]
    return np.vstack([chains[0][:1]] + [c[1:] for c in chains]) if chains else np.zeros((0, 0))


class CertifiedMotion:
    """Mixin of :class:`~drake_mh.reactive.follower.follower.RegeneratingFollower`: chains, their
    certification and detours (module docstring). Expects ``robot, scene, config, points, Q, index,
    times, vias, executed_vias, segment_lower, detours, blocked, halts, halted``."""

    def _init_motion(self, times) -> None:
        n = len(self.points)
        self.times = None if times is None else np.asarray(times, dtype=float).reshape(n)
        self.vias: dict[int, np.ndarray] = {}
        self.executed_vias: dict[int, np.ndarray] = {}
        self.segment_lower = np.full(n - 1, np.nan)
        self.detours: list[DetourRecord] = []
        self.blocked: dict[int, str] = {}
        self.halts: list[tuple[int, str]] = []
        self.halted: str | None = None

    # --- chains -----------------------------------------------------------------------------

    def chain(self, k: int) -> np.ndarray:
        """``(m + 2, nq)``: the motion from point k to point k + 1 (``Q[k]``, its vias, ``Q[k + 1]``)."""
        vias = self.vias.get(int(k))
        return np.vstack([self.Q[k], *([] if vias is None else [vias]), self.Q[k + 1]])

    def executed_chains(self) -> list[np.ndarray]:
        """The chains the arm has executed, from point 0 to its current point."""
        out = []
        for k in range(self.index):
            vias = self.executed_vias.get(k, np.zeros((0, self.robot.nq)))
            out.append(np.vstack([self.executed[k], vias, self.executed[k + 1]]))
        return out

    def _durations(self, ks) -> np.ndarray | None:
        if self.times is None:
            return None
        ks = np.asarray(ks, dtype=int)
        return self.times[ks + 1] - self.times[ks]

    def _elapsed(self, k: int) -> float:
        """Seconds from now (the arm at ``index``) until chain k starts (0 without times)."""
        return 0.0 if self.times is None else float(self.times[k] - self.times[self.index])

    def certify_remaining(self, tolerance: float | None = None):
        """The :class:`~drake_mh.reactive.follower.detour.ChainCertificate` of the chains from the
        current point to the end, against the scene as it is now (``None`` at the last point)."""
        ks = np.arange(self.index, len(self.points) - 1)
        if not ks.size or not _anything_to_hit(self.scene):
            return None
        tol = self.config.motion_tolerance if tolerance is None else tolerance
        return certify_chains(self.scene, [self.chain(k) for k in ks], self.config.motion_clearance,
                              durations=self._durations(ks), tolerance=tol)

    # --- securing the plan ------------------------------------------------------------------

    def _search(self, k: int, when, reason: str) -> DetourRecord:
        """Detour search for chain k (obstacles where they will be when it starts); sets ``vias``."""
        cfg = self.config
        duration = None if self.times is None else float(self.times[k + 1] - self.times[k])
        seed = np.random.SeedSequence([self.seed & 0xFFFFFFFF, 7, len(self.detours), k]).generate_state(1)[0]
        with obstacles_moved(self.scene, self._elapsed(k) if any_moving(self.scene) else 0.0):
            d = find_detour(self.scene, self.Q[k], self.Q[k + 1], clearance=cfg.motion_clearance,
                            duration=duration, seed=int(seed), config=cfg.detour)
        deviation, straight = float("nan"), self._tool_deviation(k, np.vstack([self.Q[k], self.Q[k + 1]]))
        if d.found:
            self.vias[k] = d.vias
            self.blocked.pop(k, None)
            deviation = self._tool_deviation(k, self.chain(k))
        else:
            self.vias.pop(k, None)
            self.blocked[k] = f"{reason}; {d.reason}"
        record = DetourRecord(when, int(k), d.found, len(d.vias), d.time, d.evaluations, d.straight_length,
                              d.extra_length, deviation, straight, reason if d.found else self.blocked[k])
        self.detours.append(record)
        return record

    def _tool_deviation(self, k: int, chain: np.ndarray) -> float:
        s = np.linspace(0.0, 1.0, 21)[:, None]
        Q = np.vstack([a + s * (b - a) for a, b in zip(chain[:-1], chain[1:])])
        p = self.robot.batch.fk(Q)[:, :3, 3]
        a, b = self.points[k], self.points[k + 1]
        ab = b - a
        t = np.clip((p - a) @ ab / max(float(ab @ ab), 1e-18), 0.0, 1.0)
        return float(np.max(np.linalg.norm(p - (a + t[:, None] * ab), axis=1)))

    def _secure_motion(self, lo: int, when) -> list[DetourRecord]:
        """Certify chains ``lo ..`` (tolerance inf: a verdict, not a report); detour or block the
        others. Returns the detour records made."""
        self.blocked = {k: r for k, r in self.blocked.items() if k < lo}
        ks = np.arange(lo, len(self.points) - 1)
        if not ks.size or not _anything_to_hit(self.scene):
            return []
        cfg = self.config
        cert = certify_chains(self.scene, [self.chain(k) for k in ks], cfg.motion_clearance,
                              durations=self._durations(ks))
        made = []
        for i in np.flatnonzero(~cert.certified):
            k = int(ks[i])
            reason = cert.reason(int(i))
            if k == self.index and not self.scene.collision_free(self.Q[k], cfg.motion_clearance):
                # the arm is already there: nothing ahead can change that chain's start; the
                # execution gate decides against the obstacles as they are when it moves
                self.blocked[k] = ("the arm's current configuration is within the motion clearance of an "
                                   "obstacle now (left to the execution gate)")
                continue
            if k in self.vias:  # an old detour that no longer holds: the straight line first
                del self.vias[k]
                if self._chain_certified(k):
                    continue
            if cfg.detour is None:
                self.blocked[k] = f"{reason}; detours are off (FollowerConfig.detour=None)"
                continue
            made.append(self._search(k, when, f"straight line {reason}"))
        return made

    def _chain_certified(self, k: int, tolerance: float = np.inf):
        """Chain k against the obstacles where they will be when it starts: ``(certified, lower, reason)``."""
        with obstacles_moved(self.scene, self._elapsed(k) if any_moving(self.scene) else 0.0):
            cert = certify_chains(self.scene, [self.chain(k)], self.config.motion_clearance,
                                  durations=self._durations([k]), tolerance=tolerance)
        return cert if cert.all_certified else None

    def _forget_vias_around(self, changed) -> None:
        """Configurations ``changed`` were solved again: the detours next to them are stale."""
        for k in np.asarray(changed, dtype=int):
            self.vias.pop(int(k) - 1, None)
            self.vias.pop(int(k), None)

    # --- executing --------------------------------------------------------------------------

    def _gate(self) -> bool:
        """Certify the chain the arm is about to execute (the scene as it is now, tight bound);
        detour once more if needed. Returns whether the arm may move (else ``halted`` says why)."""
        k = self.index
        if not _anything_to_hit(self.scene):
            self.segment_lower[k] = np.inf
            self.halted = None
            return True
        tol = self.config.motion_tolerance
        cert = self._chain_certified(k, tol)
        if cert is None and k in self.vias:
            del self.vias[k]
            cert = self._chain_certified(k, tol)
        if cert is None and self.config.detour is not None:
            first = certify_chains(self.scene, [self.chain(k)], self.config.motion_clearance,
                                   durations=self._durations([k]))
            record = self._search(k, "advance", f"straight line {first.reason(0)}")
            if record.found:
                cert = self._chain_certified(k, tol)
        if cert is None:
            reason = self.blocked.get(k) or "the motion to the next point is not certified collision-free"
            self.halted = f"halted at point {k}: {reason}"
            self.halts.append((k, self.halted))
            return False
        self.halted = None
        self.blocked.pop(k, None)
        self.segment_lower[k] = float(cert.lower[0])
        self.executed_vias[k] = self.vias.get(k, np.zeros((0, self.robot.nq))).copy()
        return True

    def detour_summary(self) -> dict:
        """Counts and costs of the detour searches so far (for records)."""
        found = [d for d in self.detours if d.found]
        return {
            "detour_searches": len(self.detours),
            "detours_found": len(found),
            "detours_failed": len(self.detours) - len(found),
            "detour_vias": int(sum(d.vias for d in found)),
            "detour_time": float(sum(d.time for d in self.detours)),
            "detour_evaluations": int(sum(d.evaluations for d in self.detours)),
            "detour_extra_length": float(sum(d.extra_length for d in found)) if found else 0.0,
            "detour_max_tool_deviation": float(max(d.tool_deviation for d in found)) if found else 0.0,
            "detour_max_straight_tool_deviation": (float(max(d.straight_tool_deviation for d in found))
                                                   if found else 0.0),
            "detours_executed": int(sum(len(v) > 0 for v in self.executed_vias.values())),
        }
