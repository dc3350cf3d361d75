"""The framework paper's dynamic-obstacle scenario (§4, Tables 2-3, Figs. 12-13) as one function.

The 6-link arm of Table 2 (``seed000_6dof``) follows Table 3's closed path (50 points,
trapezoidal speed, :func:`drake_mh.paths.trapezoidal_path`). "The initial solutions are
generated with the obstacle in the position (0.2, 0.2, 0.6)"; while the arm runs the obstacle
is moved to (0.1, 0.15, 0.4) and the solutions that would collide are regenerated (§3.4.1).

Choices the paper leaves open (also in ``docs/follower.md``):

* **Obstacle**: a sphere of radius 0.2 m (size and shape are not given). Moved to
  (0.1, 0.15, 0.4) it reaches into the space above the arm's shoulder, where elbow-up
  solutions pass, while at (0.2, 0.2, 0.6) it clears the path. Whether it hits the plan depends
  on the IK branch the initial plan took (seed and method): with e3GSA, seeds 2-5 of 0-5
  need regeneration (3 to 27 points), seeds 0 and 1 do not (measured) — the record says how many points
  collided (``event1_colliding``), 0 included.
* **When**: the move is *announced* when the arm reaches point ``move_at`` (default 1,
  t ≈ 0.35 s: right after the start) and the obstacle *jumps* to its new position when the
  arm reaches the next point (a scripted jump, as a user moves it in the paper's simulation;
  a straight-line transit would sweep the 0.2 m sphere through the arm, 0.8 m for the path
  event). The follower regenerates against the new position at once, so the points from
  ``move_at + 1`` on may change. Why not a jump onto the configuration the arm occupies: for some initial
  plans the moved sphere swallows that configuration (e3GSA seed 5: 7.4 cm deep) — a
  collision the obstacle makes and no planner can avoid. The paper never re-checks the
  current configuration either: its regeneration acts on the points ahead. The record keeps
  that configuration's clearance against the new position (``clearance_at_move``) so the
  difference stays visible.
* **Optional §3.4.2 event** (``path_event=(at, target)``): when the arm reaches point ``at``
  the obstacle moves to cut the path at point ``target``: its centre is put 3 cm less than its
  radius away from that point, horizontally and away from the base (the side the arm does not
  come from), so the path point lies 3 cm outside the sphere, inside the tool clearance, and
  Algorithm 2 re-plans the points around it.

The follower certifies each motion between two points before it executes it, against the
obstacle where it is during that motion (:mod:`drake_mh.reactive.follower.motion`): at the
announcement the follower sees the new position and regenerates for it, the motion to the next
point is then executed with the obstacle still at the old one, and it jumps on arrival. Where
a straight joint-space line is not certified the follower detours through via configurations,
or halts (the run then fails and says where and why).

Independent checks afterwards: every executed configuration with Drake's exact signed
distance against the obstacle pose of that moment; every executed motion (detours included)
certified again with :meth:`drake_mh.scene.Scene.certify_path` against the obstacle where it
was during it (``motion_certified``, ``motion_min_clearance``: a certified lower bound of the
clearance of the whole motion, tolerance 1 mm); and, for comparison, Drake's exact distance
at ``substeps`` interior samples of each straight piece (``min_distance_swept``).
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["run_framework_scenario", "OBSTACLE_START", "OBSTACLE_MOVED", "OBSTACLE_RADIUS", "MOVE_AT",
           "PATH_EVENT"]

#: framework paper §4: obstacle position while the initial solutions are generated [m]
OBSTACLE_START = (0.2, 0.2, 0.6)
#: framework paper §4 / Fig. 12(b): where it is moved while the arm runs [m]
OBSTACLE_MOVED = (0.1, 0.15, 0.4)
#: [m] our choice (module docstring)
OBSTACLE_RADIUS = 0.2
#: point at which the obstacle is moved (our choice)
MOVE_AT = 1
#: the optional §3.4.2 event used by the study: at point 30, cut the path at point 45
PATH_EVENT = (30, 45)


def _path_cut_position(points: np.ndarray, target: int, radius: float) -> np.ndarray:
    p = points[target]
    u = np.array([p[0], p[1], 0.0])
    norm = np.linalg.norm(u)
    u = np.array([1.0, 0.0, 0.0]) if norm < 1e-9 else u / norm
    return p + (radius + 0.03) * u


def run_framework_scenario(method: str = "e3gsa", seed: int = 0, *, budget: int | None = None,
                           n_points: int = 50, obstacle_radius: float = OBSTACLE_RADIUS, move_at: int = MOVE_AT,
                           path_event: tuple[int, int] | None = None, config=None, substeps: int = 4) -> dict:
    """Runs the framework paper's scenario with any IK method; returns a flat record + arrays.

    Args:
        method: any name of :func:`drake_mh.ik.available_ik_methods` (the paper used e3GSA).
        seed: seed of the initial plan and of every regeneration.
        budget: per IK solve, as in :func:`drake_mh.ik.solve_ik` (``None``: its default).
        n_points: points of the Table 3 path (the paper: 50).
        obstacle_radius: [m] of the spherical obstacle.
        move_at: point at which the obstacle moves from (0.2, 0.2, 0.6) to (0.1, 0.15, 0.4).
        path_event: ``(at, target)``: also move the obstacle onto the path (§3.4.2), or ``None``.
        config: a :class:`~drake_mh.reactive.follower.follower.FollowerConfig` (its method and budget
            are replaced by ``method`` and ``budget``).
        substeps: interior samples per joint-space segment in the swept-motion check.

    Returns:
        A flat dict: scalars (``success``: every point reached, executed motion certified
        collision-free, points clear by Drake and on the path, nothing failed;
        ``time`` = total regeneration time [s], ``motion_certified``, ``motion_min_clearance`` [m],
        ``motion_first_failure`` (segment, -1 if none) and ``motion_failure_reason``, ``halted``,
        ``halted_at``, ``halt_reason``, the detour counts and costs of
        :meth:`~drake_mh.reactive.follower.motion.CertifiedMotion.detour_summary`,
        ``points_regenerated``, ``event1_*`` per event, ``max_step_plan`` / ``max_step_executed``
        [rad], ``min_distance_executed`` / ``min_distance_swept`` / ``min_distance_unregenerated``
        / ``clearance_at_move`` (the configuration occupied when the move is seen, against the
        new position) /
        ``min_distance_after_move`` [m], ``max_position_error`` [m] ...) and arrays ``traj_t (N,)`` [s], ``traj_q (N, 6)``
        (executed, Fig. 13(b)), ``plan_q (N, 6)`` (initial plan, Fig. 13(a)), ``final_q``,
        ``path_initial (N, 3)``, ``path_final (N, 3)``, ``obstacle_p (N, 3)``, ``regenerated (N,)``,
        ``event_index (E,)``, ``event_time (E,)``, ``event_points (E,)``, ``joint_steps (N-1,)``,
        ``clearance (N,)`` [m] (each executed configuration against the obstacle of its moment),
        ``motion_lower (N-1,)`` [m] (certified clearance of each executed motion), ``traj_vias
        (N-1,)`` (detour vias per motion), ``motion_q (M, 6)`` (the executed polyline, vias
        included). After a halt the arrays hold NaN for the points not reached.

    Raises:
        UnknownMethod: ``method`` is not an IK method.
        InvalidArgument: ``move_at`` / ``path_event`` outside the path, bad radius.
    """
    import dataclasses

    import drake_mh
    from drake_mh.paths import joint_steps, trapezoidal_path
    from drake_mh.reactive.follower.follower import FollowerConfig, RegeneratingFollower, largest_joint_step
    from drake_mh.scene import Scene, Sphere

    base = config if config is not None else FollowerConfig()
    config = dataclasses.replace(base, method=method, budget=budget)
    if not 0 <= move_at < n_points - 1:
        raise InvalidArgument(f"move_at must be a point index in [0, {n_points - 2}], got {move_at!r}")
    if path_event is not None and not (0 <= path_event[0] < path_event[1] < n_points):
        raise InvalidArgument(f"path_event must be (at, target) with 0 <= at < target < {n_points}, got {path_event!r}")
    if not (np.isfinite(obstacle_radius) and obstacle_radius > 0):
        raise InvalidArgument(f"obstacle_radius must be a positive length [m], got {obstacle_radius!r}")
    robot = drake_mh.load_robot("seed000_6dof")
    path = trapezoidal_path(n_points=n_points)
    scene = Scene(robot)
    scene.add("obstacle", Sphere(obstacle_radius), OBSTACLE_START)
    start = time.perf_counter()
    follower = RegeneratingFollower.plan(robot, scene, path, config, seed=seed)
    plan_time = time.perf_counter() - start
    plan_q = follower.Q.copy()
    schedule = {move_at: np.array(OBSTACLE_MOVED, dtype=float)}
    if path_event is not None:
        schedule[path_event[0]] = _path_cut_position(path.points, path_event[1], obstacle_radius)
    N = n_points
    obstacle_p = np.zeros((N, 3))
    unregenerated = np.inf
    clearance_at_move = np.nan
    for k in range(N):
        obstacle_p[k] = scene.obstacles["obstacle"].position   # where it is while the arm is at point k
        if k == N - 1:
            break
        if k in schedule:
            old = obstacle_p[k].copy()
            scene.move("obstacle", schedule[k])                # announced now ...
            if k == move_at:  # what the old plan would have met, and what a jump onto the arm would hit
                unregenerated = float(scene.exact_min_distance(plan_q[k + 1:]).min())
                clearance_at_move = float(scene.min_distance(follower.executed[k]))
            follower.react()
            scene.move("obstacle", old)                        # ... still here during the motion to k + 1
            follower.advance()
            scene.move("obstacle", schedule[k])                # ... there on arrival
        else:
            follower.advance()
        if follower.index != k + 1:                            # no certified motion: the arm stays
            obstacle_p[k + 1:] = obstacle_p[k]
            break
    executed = follower.executed
    reached = follower.index
    halted = follower.halted
    # independent checks: each executed configuration against the obstacle of its moment (Drake),
    # each executed motion certified against the obstacle where it was during it, and Drake's
    # exact distance at interior samples of each straight piece
    from drake_mh.reactive.follower.detour import certify_chains
    from drake_mh.reactive.follower.motion import polyline

    distances = np.full(N, np.nan)
    swept = np.full(N - 1, np.nan)
    motion_lower = np.full(N - 1, np.nan)
    motion_ok = np.zeros(N - 1, dtype=bool)
    first_failure, failure_reason = -1, ""
    fractions = np.arange(1, substeps + 1) / (substeps + 1)
    chains = follower.executed_chains()
    for k in range(reached + 1):
        if k > 0:   # the obstacle jumps on arrival at point k: before that it is where it was at k - 1
            scene.move("obstacle", obstacle_p[k - 1])
            chain = chains[k - 1]
            cert = certify_chains(scene, [chain], tolerance=1e-3)
            motion_ok[k - 1], motion_lower[k - 1] = cert.all_certified, cert.lower[0]
            if not cert.all_certified and first_failure < 0:
                first_failure, failure_reason = k - 1, cert.reason(0)
            Q_mid = np.vstack([a + fractions[:, None] * (b - a) for a, b in zip(chain[:-1], chain[1:])])
            swept[k - 1] = scene.exact_min_distance(Q_mid).min()
        scene.move("obstacle", obstacle_p[k])
        distances[k] = scene.min_distance(executed[k])
    done = reached == N - 1
    motion_certified = bool(reached > 0 and motion_ok[:reached].all())
    pieces = np.vstack([np.abs(np.diff(c, axis=0)) for c in chains]) if chains else np.zeros((0, 6))
    p_WE = np.array([robot.fk_drake(q)[:3, 3] for q in executed[:reached + 1]])  # verified with Drake
    position_error = np.linalg.norm(p_WE - follower.points[:reached + 1], axis=1)
    events = follower.events
    record = {
        "method": config.method, "seed": int(seed), "n_points": N, "obstacle_shape": "sphere",
        "obstacle_radius": float(obstacle_radius), "move_at": int(move_at),
        "path_event": path_event is not None,
        "plan_time": plan_time, "plan_failed": int(follower.plan_failed.size),
        "max_step_plan": largest_joint_step(plan_q), "max_step_executed": largest_joint_step(executed[:reached + 1]),
        "min_distance_plan": float(scene_min(robot, plan_q, OBSTACLE_START, obstacle_radius)),
        "min_distance_unregenerated": unregenerated,
        "min_distance_executed": float(np.nanmin(distances)),
        # the configuration occupied when the move is seen, against the new position: what an
        # instantaneous jump would have hit (informative; the obstacle arrives one point later)
        "clearance_at_move": clearance_at_move,
        "min_distance_after_move": (float(np.nanmin(distances[move_at + 1:])) if reached > move_at
                                    else float("nan")),
        "min_distance_swept": float(np.nanmin(swept)) if reached else float("nan"),
        # the executed motion between the points, certified (a lower bound, every configuration on it)
        "motion_certified": motion_certified,
        "motion_min_clearance": float(np.min(motion_lower[:reached])) if motion_certified else float("nan"),
        "motion_first_failure": int(first_failure),
        "motion_failure_reason": failure_reason,
        "reached": int(reached),
        "halted": halted is not None,
        "halted_at": int(reached) if halted is not None else -1,
        "halt_reason": halted or "",
        "max_step_executed_motion": float(pieces.max()) if len(pieces) else 0.0,
        **follower.detour_summary(),
        "max_position_error": float(position_error.max()),
        "n_events": len(events),
        "points_regenerated": int(sum(e.regenerated.size for e in events)),
        "points_failed": int(sum(e.failed.size for e in events)),
        "points_spread": int(sum(e.spread.size for e in events)),   # continuity repair (config.spread_step)
        "time": float(sum(e.time for e in events)),
        "error": float(position_error.max()),
    }
    for i, e in enumerate(events, start=1):
        record.update({
            f"event{i}_index": int(e.index), f"event{i}_time": e.time, f"event{i}_detect_time": e.detect_time,
            f"event{i}_colliding": int(e.colliding.size), f"event{i}_path_colliding": int(e.path_colliding.size),
            f"event{i}_replanned": int(e.replanned.size), f"event{i}_regenerated": int(e.regenerated.size),
            f"event{i}_failed": int(e.failed.size), f"event{i}_spread": int(e.spread.size), f"event{i}_max_step_before": e.max_step_before,
            f"event{i}_max_step_after": e.max_step_after, f"event{i}_ms_per_point":
                1e3 * e.time / max(1, e.regenerated.size),
        })
    record["success"] = bool(done and motion_certified and record["min_distance_executed"] >= 0
                             and record["min_distance_swept"] >= 0
                             and record["max_position_error"] <= config.position_tolerance
                             and record["points_failed"] == 0 and record["plan_failed"] == 0)
    record.update({
        "traj_t": path.times.copy(), "traj_q": executed.copy(), "plan_q": plan_q, "final_q": follower.Q.copy(),
        "clearance": distances, "motion_lower": motion_lower,
        "traj_vias": np.array([len(c) - 2 for c in chains] + [0] * (N - 1 - len(chains)), dtype=int),
        "motion_q": polyline(chains) if chains else executed[:1].copy(),
        "path_initial": path.points.copy(), "path_final": follower.points.copy(), "obstacle_p": obstacle_p,
        "regenerated": follower.regenerated_mask.copy(),
        "event_index": np.array([e.index for e in events], dtype=int),
        "event_time": np.array([e.time for e in events]),
        "event_points": np.array([e.regenerated.size for e in events], dtype=int),
        "joint_steps": joint_steps(executed[:reached + 1]),
    })
    return record


def scene_min(robot, Q, position, radius) -> float:
    """Smallest exact distance [m] of ``Q (N, nq)`` to a sphere of ``radius`` at ``position`` (Drake)."""
    from drake_mh.scene import Scene, Sphere

    scene = Scene(robot)
    scene.add("obstacle", Sphere(radius), position)
    return float(scene.exact_min_distance(Q).min())
