"""The framework paper's regenerating path follower (§3.4: 3.4.1 and 3.4.2).

The arm follows a path for which a joint solution exists at every point (§3.3: IK at each
point). When an obstacle moves — a scripted motion or a slider of the interactive app —
:meth:`RegeneratingFollower.react` predicts which *remaining* configurations (the points the
arm has not reached) now collide and repairs the plan:

1. **Obstacle in the path (§3.4.2, Algorithm 2).** If remaining path points come closer than
   ``replan.tool_clearance`` to an obstacle, the ``3·nC`` points around each run of ``nC``
   colliding points are replaced by the nearest obstacle-free points found by the
   metaheuristic (:mod:`drake_mh.reactive.follower.replan`), and IK is solved again for all of them.
2. **Obstacle on the arm (§3.4.1).** Every remaining configuration whose *exact* signed
   distance (Drake, ``Scene.min_distance``) is below ``clearance`` gets a new IK solution for
   the *same* target point; the path is unchanged. A batched sphere-model pre-screen
   (``Scene.batch_min_distance``, never more than Drake's distance) skips the configurations
   that are certainly clear; every one it flags is confirmed with Drake before it counts.

Regenerated IK keeps continuity with *both* neighbours. The points of a run ``[a, b]`` of
consecutive regenerated points are solved in path order; point ``k`` gets the reference
``q_ref = Q[k-1] + (Q[b+1] - Q[k-1]) / (b - k + 2)`` — from the configuration before it (already
final; the current one for the first remaining point) a step towards the first unchanged
configuration after the run, spreading the remaining gap evenly (``Q[k-1]`` when the run
reaches the end of the path) — as the centre of the search box and of the displacement
penalty ``ref_weight · ||q - q_ref||``. (Referencing only ``Q[k-1]`` left the whole gap at the
run's end: a 0.5-0.9 rad step where the run rejoined the old plan.) The
metaheuristics get the previous configuration, the old (colliding) one and the next one in
their initial population (``x0``), the gradient methods start from ``q_ref``. A regenerated
configuration must be verified by Drake with the larger ``ik_clearance`` (hysteresis: it is not
flagged again by the next small obstacle motion). Each solve searches first within
``q_prev ± 0.3 rad`` (:class:`LocalIKProblem`), then on failure with a fresh seed within
``± 1 rad``, then over the whole joint range without the displacement penalty
(``search_radii``): continuity first, but feasibility over continuity
(:func:`drake_mh.paths.continuity.solve_near`, shared with ``ik_along_path``). After a solve,
revolute joints are shifted by 2π toward the previous configuration (the range centre for
the first point of a plan; same pose), joints the task does not see (whose reset to the
previous value keeps the tool on its target and the arm clear; the 6-DOF arm's last joint)
are reset, and the configuration is verified with Drake again. The best configuration is
kept and a point that no attempt solved is reported in ``failed``.

Not in the paper: the motion *between* two points is certified too
(:mod:`drake_mh.reactive.follower.motion`). After the plan and after every regeneration each
remaining straight joint-space segment is certified collision-free for every configuration on
it (``Scene.certify_segments``); one that is not (a branch switch around the obstacle) is replaced
by a detour through at most two via configurations whose pieces are certified
(:mod:`drake_mh.reactive.follower.detour`), and :meth:`RegeneratingFollower.advance` certifies the
motion it is about to execute against the scene as it is then: without a certified motion the
arm does not move (``halted``).

Any method of :func:`drake_mh.ik.available_ik_methods` solves the IK (optimizers, hybrid,
Jacobian and Drake baselines); Algorithm 2 runs an optimizer (the IK method when it is one).
Same seed, same plan (budget-limited runs; a ``timeout`` makes results machine-dependent).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import InvalidArgument, UnknownMethod
from drake_mh.optim.base import check_seed
from drake_mh.paths.continuity import LocalIKProblem, revolute_mask, solve_near, wrap_toward
from drake_mh.paths.ik_path import joint_steps
from drake_mh.reactive.follower.detour import DetourConfig
from drake_mh.reactive.follower.motion import CertifiedMotion
from drake_mh.reactive.follower.replan import (ReplanConfig, ReplanResult, collision_runs, colliding_path_points,
                                               replan_points, replan_windows)

logger = logging.getLogger(__name__)

__all__ = ["FollowerConfig", "RegenerationEvent", "RegeneratingFollower", "LocalIKProblem", "largest_joint_step",
           "wrap_toward", "revolute_mask"]

_EMPTY = np.zeros(0, dtype=int)


def largest_joint_step(Q) -> float:
    """``max_k max_j |Q[k+1, j] - Q[k, j]|`` [rad] of ``Q (N, nq)``; 0 for fewer than 2 rows."""
    steps = joint_steps(Q)
    return float(steps.max()) if len(steps) else 0.0


@dataclass(frozen=True)
class FollowerConfig:
    """Settings of the regenerating follower (module docstring).

    Attributes:
        method: IK method, any name of :func:`drake_mh.ik.available_ik_methods` (default
            ``"e3gsa"``, the framework paper's algorithm).
        budget: per IK solve, as in :func:`drake_mh.ik.solve_ik` (``None``: its default).
        timeout: [s] per IK solve (``None``: none; results then depend on the machine).
        search_radii: one IK attempt per entry [rad]: the search box is the joint limits
            intersected with ``q_prev ± radius`` (``None``: the whole range); widened on
            failure (default 0.3, 1.0, whole range). Bounds every joint step when the first
            attempt succeeds — also of joints the task does not see (the 6-DOF arm's last
            joint does not move its tool point: unbounded, it jumped 6 rad).
        clearance: [m] a configuration is predicted to collide when Drake's exact signed
            distance to an obstacle is below it (default 0.01; keep >= 1e-4, Drake's
            capsule-box GJK can be 6e-5 m optimistic).
        ik_clearance: [m] a regenerated configuration must keep this exact distance (>=
            ``clearance``; default 0.015).
        ref_weight: [m/rad] displacement penalty to the previous configuration.
        position_tolerance: [m] on the tool position (default 1 mm, the paper's position IK).
        prescreen: sphere-model pre-screen before Drake's exact check (the decision is
            Drake's either way).
        replan_path: re-plan path points the obstacle cuts (§3.4.2); ``False``: only §3.4.1.
        spread_step: [rad] optional continuity repair (``None``, the default: the paper's
            behaviour, only colliding/re-planned points change). When a regeneration leaves a
            joint step larger than this next to a regenerated point — the local searches
            failed and the whole-range search switched IK branch — the not-yet-reached points
            before it (or after it, where a run rejoins the old plan) are solved again toward
            the far side, ``ceil(step / spread_step) - 1`` of them, so the switch is spread
            over several points. Those points change although they do not collide; each is
            kept only if Drake verifies it (``RegenerationEvent.spread``).
        replan: :class:`~drake_mh.reactive.follower.replan.ReplanConfig` of Algorithm 2.
        params: optimizer options for the metaheuristic IK, as ``((name, value), ...)``.
        motion_clearance: [m] clearance certified along every executed motion between points
            (the conservative sphere model, every configuration on it; default 0: collision-free
            — the points themselves keep ``clearance`` by Drake's exact distance).
        motion_tolerance: [m] the reported certified clearance of an executed motion is within
            this of the smallest value seen on it (default 1 mm; ``inf``: a bare certificate).
        detour: :class:`~drake_mh.reactive.follower.detour.DetourConfig` of the search for a
            certified connection where the straight line is not; ``None``: no search (such a
            motion blocks the arm).
    """

    method: str = "e3gsa"
    budget: int | None = None
    timeout: float | None = None
    search_radii: tuple = (0.3, 1.0, None)
    clearance: float = 0.01
    ik_clearance: float = 0.015
    ref_weight: float = 0.05
    position_tolerance: float = 1e-3
    prescreen: bool = True
    replan_path: bool = True
    spread_step: float | None = None
    replan: ReplanConfig = field(default_factory=ReplanConfig)
    params: tuple = ()
    motion_clearance: float = 0.0
    motion_tolerance: float = 1e-3
    detour: DetourConfig | None = field(default_factory=DetourConfig)

    def __post_init__(self):
        from drake_mh.ik import available_ik_methods

        methods = available_ik_methods()
        if not isinstance(self.method, str) or self.method.lower() not in methods:
            raise UnknownMethod(str(self.method), methods, what="IK method")
        object.__setattr__(self, "method", self.method.lower())
        radii = tuple(self.search_radii) if isinstance(self.search_radii, (tuple, list)) else ()
        if not radii or not all(r is None or (isinstance(r, (int, float)) and np.isfinite(r) and r > 0)
                                for r in radii):
            raise InvalidArgument(f"search_radii must be a non-empty tuple of positive radii [rad] or None "
                                  f"(whole joint range), got {self.search_radii!r}")
        object.__setattr__(self, "search_radii", radii)
        for name in ("clearance", "ik_clearance"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v >= 1e-4):
                raise InvalidArgument(f"{name} must be >= 1e-4 m (Drake's GJK distance can be 6e-5 m "
                                      f"optimistic), got {v!r}")
        if self.ik_clearance < self.clearance:
            raise InvalidArgument(f"ik_clearance ({self.ik_clearance} m) must be >= clearance ({self.clearance} m), "
                                  "or regenerated configurations would be flagged again at once")
        if not (np.isfinite(self.ref_weight) and self.ref_weight >= 0):
            raise InvalidArgument(f"ref_weight must be >= 0, got {self.ref_weight!r}")
        if not (np.isfinite(self.position_tolerance) and self.position_tolerance > 0):
            raise InvalidArgument(f"position_tolerance must be > 0 m, got {self.position_tolerance!r}")
        if self.spread_step is not None and not (isinstance(self.spread_step, (int, float))
                                                 and np.isfinite(self.spread_step) and self.spread_step > 0):
            raise InvalidArgument(f"spread_step must be a positive joint step [rad] or None, got {self.spread_step!r}")
        if not isinstance(self.replan, ReplanConfig):
            raise InvalidArgument("replan must be a drake_mh.reactive.follower.ReplanConfig")
        if not (isinstance(self.motion_clearance, (int, float)) and np.isfinite(self.motion_clearance)
                and self.motion_clearance >= 0):
            raise InvalidArgument(f"motion_clearance must be a length >= 0 [m], got {self.motion_clearance!r}")
        if not (isinstance(self.motion_tolerance, (int, float)) and self.motion_tolerance > 0):
            raise InvalidArgument(f"motion_tolerance must be > 0 [m] (inf: no tight bound), got "
                                  f"{self.motion_tolerance!r}")
        if self.detour is not None and not isinstance(self.detour, DetourConfig):
            raise InvalidArgument("detour must be a drake_mh.reactive.follower.DetourConfig or None")
        object.__setattr__(self, "params", tuple(dict(self.params).items()))


@dataclass(frozen=True)
class RegenerationEvent:
    """What one :meth:`RegeneratingFollower.react` did.

    Attributes:
        number: event counter (0, 1, ...).
        index: the path point the arm was at (points ``> index`` could be changed).
        obstacles: ``{name: p_WO (3,)}`` obstacle positions [m] at the event.
        colliding: configuration indices predicted to collide (Drake-confirmed) before repair.
        screened: configurations the pre-screen passed to Drake (all remaining without it).
        path_colliding: path indices closer than the tool clearance to an obstacle.
        replans: the :class:`~drake_mh.reactive.follower.replan.ReplanResult` of each window.
        regenerated: indices whose IK was solved again (windows ∪ colliding).
        failed: regenerated indices whose configuration Drake did not verify.
        spread: indices solved again by the continuity repair (``FollowerConfig.spread_step``;
            not colliding, changed only where Drake verified the new configuration).
        detect_time, time: [s] prediction alone; the whole event (prediction + repair).
        max_step_before, max_step_after: largest joint step [rad] of the remaining motion
            (from the current configuration to the end) before and after.
        min_distance_after: smallest exact distance [m] of the remaining configurations after.
        nfe: IK evaluations spent.
        detours: the :class:`~drake_mh.reactive.follower.motion.DetourRecord` of each remaining
            motion between points that was not certified after the repair.
        blocked: segments k (point k -> k + 1) left without a certified motion.
        motion_certified: the remaining motion (from the current configuration to the end,
            detours included) is certified against the obstacles as they are now.
        motion_min_clearance: its certified lower bound of the clearance [m] (NaN if not
            certified).
    """

    number: int
    index: int
    obstacles: dict
    colliding: np.ndarray
    screened: int
    path_colliding: np.ndarray
    replans: tuple
    regenerated: np.ndarray
    failed: np.ndarray
    detect_time: float
    time: float
    max_step_before: float
    max_step_after: float
    min_distance_after: float
    nfe: int
    spread: np.ndarray = field(default_factory=lambda: _EMPTY)
    detours: tuple = ()
    blocked: np.ndarray = field(default_factory=lambda: _EMPTY)
    motion_certified: bool = True
    motion_min_clearance: float = float("nan")

    @property
    def replanned(self) -> np.ndarray:
        """Indices whose path point was re-planned (the windows)."""
        return np.concatenate([r.window for r in self.replans]) if self.replans else _EMPTY

    @property
    def changed(self) -> bool:
        """Whether the plan changed."""
        return self.regenerated.size > 0

    def summary(self) -> str:
        """One line for logs and the app's status."""
        if not self.changed and not self.detours:
            return f"no collision predicted ({self.screened} checked with Drake, {1e3 * self.time:.1f} ms)"
        parts = [f"{self.regenerated.size} points regenerated in {self.time:.2f} s"]
        if self.replans:
            parts.append(f"path re-planned at {self.replanned.size} points (3·nC, nC = {self.path_colliding.size})")
        if self.spread.size:
            parts.append(f"{self.spread.size} neighbours re-solved to spread a branch switch")
        if self.failed.size:
            parts.append(f"FAILED at {self.failed.tolist()}")
        found = [d.segment for d in self.detours if d.found]
        if found:
            parts.append(f"detour around the obstacle on segments {found}")
        if self.blocked.size:
            parts.append(f"NO certified motion on segments {self.blocked.tolist()}")
        parts.append(f"max step {self.max_step_after:.3f} rad")
        return "; ".join(parts)


class RegeneratingFollower(CertifiedMotion):
    """Follows a path with a joint solution per point and repairs it when obstacles move.

    Args:
        robot: the :class:`~drake_mh.robot.Robot`.
        scene: the :class:`~drake_mh.scene.Scene` whose obstacles move (``scene.move``).
        points: ``(N, 3)`` tool positions [m] (or a ``CartesianPath``, whose ``times`` are then used).
        Q: ``(N, nq)`` a joint solution per point [rad].
        config: :class:`FollowerConfig`.
        seed: base seed of every regeneration.
        index: the point the arm is at.
        times: ``(N,)`` [s] when the arm is at each point: obstacles with a velocity then move
            during the certified motions. ``None`` (and no ``points.times``): the motions are
            certified against the obstacles where they are.

    Attributes:
        points, Q: the current plan (updated by :meth:`react`).
        index: current point; ``executed`` ``(N, nq)``: the configuration each point had when
            the arm reached it (NaN ahead of the arm); ``regenerated_mask`` ``(N,)``: points
            ever regenerated; ``events``: every :class:`RegenerationEvent`.
        vias: ``{k: (m, nq)}`` via configurations of the motion from point k to k + 1 (detours);
            ``executed_vias``: those the arm executed; ``segment_lower`` ``(N - 1,)``: certified
            clearance [m] of each executed motion (NaN ahead); ``detours``: every search
            (:class:`~drake_mh.reactive.follower.motion.DetourRecord`); ``blocked``: ``{k: why}``
            motions ahead without a certificate; ``halted``: why the last :meth:`advance` did not
            move (``None`` if it did), ``halts``: every such ``(k, why)``.
    """

    def __init__(self, robot, scene, points, Q, config: FollowerConfig | None = None, seed: int = 0,
                 index: int = 0, times=None):
        P = np.array(getattr(points, "points", points), dtype=float)
        if P.ndim != 2 or P.shape[1] != 3 or len(P) < 2 or not np.all(np.isfinite(P)):
            raise InvalidArgument(f"points must be a finite (N >= 2, 3) array [m], got shape {P.shape}")
        Q = robot.check_Q(Q, "Q")
        if len(Q) != len(P):
            raise InvalidArgument(f"Q has {len(Q)} configurations for {len(P)} points: give one per point "
                                  "(e.g. drake_mh.paths.ik_along_path(robot, points).q)")
        if scene.robot is not robot:
            raise InvalidArgument("the scene belongs to another Robot object; build it with Scene(robot)")
        if isinstance(index, bool) or int(index) != index or not 0 <= index < len(P):
            raise InvalidArgument(f"index must be a point index in [0, {len(P) - 1}], got {index!r}")
        self.robot, self.scene = robot, scene
        self.config = config if config is not None else FollowerConfig()
        if not isinstance(self.config, FollowerConfig):
            raise InvalidArgument("config must be a drake_mh.reactive.follower.FollowerConfig")
        self.seed = check_seed(seed)
        self.points, self.Q = P, Q.copy()
        self.index = int(index)
        self.executed = np.full_like(self.Q, np.nan)
        self.executed[: self.index + 1] = self.Q[: self.index + 1]
        self.regenerated_mask = np.zeros(len(P), dtype=bool)
        self.events: list[RegenerationEvent] = []
        self.plan_failed = _EMPTY
        times = getattr(points, "times", None) if times is None else times
        if times is not None:
            times = np.asarray(times, dtype=float)
            if times.shape != (len(P),) or not np.all(np.isfinite(times)) or np.any(np.diff(times) < 0):
                raise InvalidArgument(f"times must be {len(P)} finite non-decreasing seconds, one per point")
        self._init_motion(times)

    # --- construction from a path ---------------------------------------------------------

    @classmethod
    def plan(cls, robot, scene, points, config: FollowerConfig | None = None, seed: int = 0, q_start=None,
             progress=None) -> RegeneratingFollower:
        """Solves IK at every point ("Generate solutions", §3.3) and returns a follower at point 0.

        Runs :func:`drake_mh.paths.ik_along_path` (each point solved near the previous
        solution: widening search boxes, displacement penalty, tidying) with the config's
        method, budget, tolerance, ``ik_clearance``, ``ref_weight`` and ``search_radii``.
        Check ``follower.plan_failed``. The motion between consecutive points is then certified
        and detoured where needed (module docstring); check ``follower.blocked``.

        Args:
            robot, scene, points, config, seed: as for the constructor (``points.times``, if any,
                are the times).
            q_start: configuration near which to solve the first point (``None``: free search).
            progress: ``progress(k, N)`` called after each point (the app's status line).
        """
        from drake_mh.paths.ik_path import ik_along_path

        config = config if config is not None else FollowerConfig()
        P = np.array(getattr(points, "points", points), dtype=float)
        if scene.robot is not robot:  # before the plan, not after it (the constructor checks the rest)
            raise InvalidArgument("the scene belongs to another Robot object; build it with Scene(robot)")
        jp = ik_along_path(robot, P, config.method, seed, q_start=q_start, ref_weight=config.ref_weight,
                           budget=config.budget, timeout=config.timeout,
                           position_tolerance=config.position_tolerance, scene=scene,
                           clearance=config.ik_clearance, search_radii=config.search_radii, progress=progress,
                           **dict(config.params))
        follower = cls(robot, scene, P, jp.q, config, seed, times=getattr(points, "times", None))
        failed = np.flatnonzero(~jp.success)
        follower.plan_failed = failed.astype(int)
        follower._secure_motion(0, "plan")
        return follower

    # --- state ------------------------------------------------------------------------------

    @property
    def n_points(self) -> int:
        """Number of path points."""
        return len(self.points)

    @property
    def q(self) -> np.ndarray:
        """The current configuration ``(nq,)``."""
        return self.Q[self.index].copy()

    @property
    def done(self) -> bool:
        """Whether the arm is at the last point."""
        return self.index >= self.n_points - 1

    def advance(self, steps: int = 1) -> np.ndarray:
        """Moves the arm ``steps`` points along the plan; returns the new configuration.

        Each motion is certified against the scene as it is now before it is executed (module
        docstring); where it is not and no detour is found the arm stays where it is and
        :attr:`halted` says why.
        """
        for _ in range(int(steps)):
            if self.done:
                break
            if not self._gate():
                logger.warning("%s", self.halted)
                break
            self.index += 1
            self.executed[self.index] = self.Q[self.index]
        return self.q

    def next_motion(self) -> np.ndarray | None:
        """The certified motion ``(m + 2, nq)`` from the current point to the next (its chain, a
        detour if needed), checked against the scene as it is now; ``None`` if there is none
        (:attr:`halted` says why) or the arm is at the end. :meth:`advance` checks it again."""
        if self.done:
            return None
        return self.chain(self.index) if self._gate() else None

    def restart(self, index: int = 0) -> None:
        """Puts the arm back at ``index`` (a closed path run again); the plan is kept."""
        self.index = int(index)
        self.executed[:] = np.nan
        self.executed[: self.index + 1] = self.Q[: self.index + 1]
        self.executed_vias.clear()
        self.segment_lower[:] = np.nan
        self.halted = None

    # --- prediction -------------------------------------------------------------------------

    def predict(self, start: int | None = None) -> tuple[np.ndarray, np.ndarray, int]:
        """Remaining configurations that collide now (Drake's exact check decides).

        Args:
            start: first index checked (default ``index + 1``).

        Returns:
            ``(indices, exact distances [m] of those, number checked with Drake)``.
        """
        start = self.index + 1 if start is None else int(start)
        idx = np.arange(start, self.n_points)
        if idx.size == 0 or not self.scene.obstacles:
            return _EMPTY, np.zeros(0), 0
        c = self.config.clearance
        if self.config.prescreen:  # conservative: >= c here means >= c for Drake too
            idx = idx[self.scene.batch_min_distance(self.Q[idx]) < c]
        exact = np.array([self.scene.min_distance(self.Q[k]) for k in idx])
        hit = exact < c
        return idx[hit], exact[hit], int(idx.size)

    def remaining_max_step(self) -> float:
        """Largest joint step [rad] from the current configuration to the end of the plan."""
        return largest_joint_step(self.Q[self.index:])

    # --- repair -----------------------------------------------------------------------------

    def _seed(self, event: int, k: int, attempt: int) -> int:
        key = [self.seed & 0xFFFFFFFF, event + 1, k + 1, attempt]  # SeedSequence takes no negatives
        return int(np.random.SeedSequence(key).generate_state(1)[0])

    def _solve_point(self, k: int, event: int, q_prev, old_q) -> tuple[object, int]:
        """IK for point ``k`` near the reference ``q_prev`` (module docstring); ``(best IKResult, nfe)``.

        The reference spreads the gap to the next unchanged configuration
        evenly over the run's remaining points.
        """
        cfg = self.config
        x0 = [q_prev, old_q]
        if old_q is not None and k + 1 < self.n_points:
            x0.append(self.Q[k + 1])
        return solve_near(self.robot, self.points[k], q_prev, cfg.method, lambda a: self._seed(event, k, a),
                          search_radii=cfg.search_radii, ref_weight=cfg.ref_weight,
                          position_tolerance=cfg.position_tolerance, scene=self.scene, clearance=cfg.ik_clearance,
                          budget=cfg.budget, timeout=cfg.timeout, x0=x0, params=dict(cfg.params))

    def react(self) -> RegenerationEvent:
        """Checks the remaining plan against the obstacles' current poses and repairs it.

        Returns:
            The :class:`RegenerationEvent` (also appended to :attr:`events`); ``changed`` is
            ``False`` when nothing collides.
        """
        start = time.perf_counter()
        cfg = self.config
        number = len(self.events)
        lo, hi = self.index + 1, self.n_points - 1
        step_before = self.remaining_max_step()
        path_hits = _EMPTY
        windows: list[np.ndarray] = []
        if cfg.replan_path and lo <= hi and self.scene.obstacles:
            path_hits = colliding_path_points(self.points, self.scene, cfg.replan.tool_clearance, start=lo)
            windows = replan_windows(path_hits, lo, hi)
        colliding, _, screened = self.predict(lo)
        detect_time = time.perf_counter() - start
        replans: list[ReplanResult] = []
        optimizer = cfg.replan.optimizer(cfg.method)
        for w, window in enumerate(windows):
            result = replan_points(self.points, window, self.scene, cfg.replan, method=optimizer,
                                   seed=self._seed(number, self.n_points + w, 0), colliding=path_hits)
            self.points[window] = result.new_points
            replans.append(result)
        todo = np.union1d(np.concatenate(windows) if windows else _EMPTY, colliding).astype(int)
        failed, nfe = self._solve_runs(todo, number, keep_failed=True)
        spread = _EMPTY
        if cfg.spread_step is not None and todo.size:
            spread, used = self._spread_steps(lo, todo, number)
            nfe += used
        self.regenerated_mask[todo] = True
        self.regenerated_mask[spread] = True
        self._forget_vias_around(np.union1d(todo, spread))
        detours = self._secure_motion(self.index, number)
        motion = self.certify_remaining()
        remaining = self.Q[lo:]
        min_after = (float(self.scene.exact_min_distance(remaining).min())
                     if remaining.size and self.scene.obstacles else np.inf)
        event = RegenerationEvent(
            number=number, index=self.index,
            obstacles={n: o.position for n, o in self.scene.obstacles.items()},
            colliding=colliding, screened=screened, path_colliding=path_hits, replans=tuple(replans),
            regenerated=todo, failed=np.array(failed, dtype=int), detect_time=detect_time,
            time=time.perf_counter() - start, max_step_before=step_before,
            max_step_after=self.remaining_max_step(), min_distance_after=min_after, nfe=nfe, spread=spread,
            detours=tuple(detours), blocked=np.array(sorted(self.blocked), dtype=int),
            motion_certified=True if motion is None else motion.all_certified,
            motion_min_clearance=np.inf if motion is None else motion.min_clearance)
        self.events.append(event)
        logger.info("event %d at point %d: %s", number, self.index, event.summary())
        return event

    def _solve_runs(self, indices: np.ndarray, number: int, keep_failed: bool) -> tuple[list[int], int]:
        """Solves IK again at ``indices`` (increasing), each run spreading the gap to its anchor.

        A run ``[a, b]`` is anchored on the first configuration after it (module docstring).
        ``keep_failed``: a point no attempt solved takes the best unverified result (and is
        returned as failed); otherwise it keeps its configuration. Returns ``(failed, nfe)``.
        """
        failed, nfe = [], 0
        anchors = {}  # k -> the first unchanged configuration after k's run (None at the path's end)
        for a, b in collision_runs(indices):
            for k in range(a, b + 1):
                anchors[k] = (b, self.Q[b + 1].copy() if b + 1 < self.n_points else None)
        for k in indices:  # increasing: Q[k-1] is final when k is solved
            k = int(k)
            b, q_after = anchors[k]
            q_ref = self.Q[k - 1] if q_after is None else self.Q[k - 1] + (q_after - self.Q[k - 1]) / (b - k + 2)
            res, used = self._solve_point(k, number, q_ref, self.Q[k].copy())
            nfe += used
            if res.success or keep_failed:
                self.Q[k] = res.q
            if not res.success:
                failed.append(k)
                if keep_failed:
                    logger.warning("point %d: no verified IK solution after %d attempts (%s)", k,
                                   len(self.config.search_radii), res.message)
        return failed, nfe

    def _spread_steps(self, lo: int, regenerated: np.ndarray, number: int) -> tuple[np.ndarray, int]:
        """Continuity repair (``FollowerConfig.spread_step``); returns ``(points changed, nfe)``.

        Scans the remaining steps ``Q[k-1] -> Q[k]`` in order. A step larger than ``spread_step``
        into a regenerated point ``k`` is spread backwards over the ``m = ceil(step / spread_step)
        - 1`` points before it (not before ``lo``), anchored on ``Q[k]``; a step out of a
        regenerated point into an old one, forwards over ``k .. k + m - 1``, anchored on the
        configuration after them (continuing the new branch at the path's end). The re-solved
        points are kept only if the largest step of the stretch they span (with one neighbour
        on each side) got smaller; else the stretch is restored.
        """
        limit = self.config.spread_step
        touched = np.zeros(self.n_points, dtype=bool)
        touched[regenerated] = True
        changed = np.zeros(self.n_points, dtype=bool)
        nfe = 0
        for k in range(lo, self.n_points):
            step = float(np.max(np.abs(self.Q[k] - self.Q[k - 1])))
            if step <= limit:
                continue
            m = int(np.ceil(step / limit)) - 1
            if touched[k]:
                run = np.arange(max(lo, k - m), k)
            elif touched[k - 1]:
                run = np.arange(k, min(self.n_points, k + m))
            else:
                continue
            if not run.size:
                continue
            stretch = slice(max(lo - 1, run[0] - 1), min(self.n_points, run[-1] + 2))
            before = self.Q[stretch].copy()
            _, used = self._solve_runs(run, number, keep_failed=False)
            nfe += used
            if largest_joint_step(self.Q[stretch]) < largest_joint_step(before):
                moved = run[np.any(self.Q[run] != before[run - stretch.start], axis=1)]
                changed[moved] = touched[moved] = True
            else:
                self.Q[stretch] = before
        return np.flatnonzero(changed), nfe
