"""The ESM control loop: one step of eq. (11) per Δt, obstacles moving, every step verified.

Timeline of step k (k = 1 .. N, ``t_k = k Δt``): the obstacles are at their ``t_{k-1}``
state; Drake's exact closest points at ``θ_{k-1}`` give the rows of eq. (9)
(:func:`drake_mh.reactive.esm.problem.build_step`); the solver returns ``θ_k`` for the target
``r_d(t_k)``; the step is checked with Drake (:func:`drake_mh.reactive.esm.verify.check_step`);
the obstacles move to ``t_k``; the exact clearance, tracking error (Drake FK) and
manipulability (Drake Jacobian) at ``(θ_k, t_k)`` are recorded.

Compute time of a step = the distance query at ``θ_{k-1}`` + building the rows + the solve;
verification and moving the obstacles (the simulation) are not counted.

The samples say nothing about the motion between them: with ``verify`` the whole executed
motion (straight in joint space from ``θ_{k-1}`` to ``θ_k`` during ``[t_{k-1}, t_k]``, the
obstacles moving with their velocities, split where a velocity changes) is certified
collision-free with :meth:`drake_mh.scene.Scene.certify_segments` (:func:`certify_esm_motion`;
``ESMRun.motion_certified``, ``motion_min_clearance``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from drake_mh.reactive.esm.problem import build_step
from drake_mh.reactive.esm.scenarios import ESMScenario
from drake_mh.reactive.esm.verify import check_step


@dataclass(frozen=True)
class ESMRun:
    """Time series of one closed-loop run (``N`` steps, ``N + 1`` samples).

    Attributes:
        scenario, solver, budget: names / budget label.
        t: ``(N+1,)`` [s].
        theta: ``(N+1, nq)`` [rad].
        r_d: ``(N+1, 3)`` target [m].
        error: ``(N+1,)`` tracking error ``||r(θ) - r_d||`` from Drake FK [m].
        mu: ``(N+1,)`` translational manipulability from Drake's Jacobian.
        min_distance: ``(N+1,)`` exact clearance robot-obstacles (Drake, every link) [m].
        closest_link: ``(N+1,)`` link of the closest pair.
        threshold: d [m].
        F: ``(N,)`` objective value of each accepted step.
        step_time, query_time, build_time, solve_time: ``(N,)`` compute time per step [s].
        nfe: ``(N,)`` evaluations per step.
        solver_feasible: ``(N,)`` the solver's own feasibility claim.
        joint_violation, velocity_violation, inequality_violation, jacobian_error: ``(N,)``
            Drake checks of every accepted step (:class:`drake_mh.reactive.esm.verify.StepCheck`).
        active_rows: ``(N,)`` obstacle inequalities with less than 1e-3 m/s of slack at the answer.
        relaxed_rows: ``(N,)`` rows nothing in the box satisfied (relaxed, see ``ESMStep``).
        motion_certified: the whole executed motion certified collision-free
            (:func:`certify_esm_motion`); ``None`` when not verified.
        motion_min_clearance: its certified lower bound of the clearance [m] (NaN if not
            certified or not verified).
        motion_first_failure: first step k (``θ_{k-1} -> θ_k``, 1-based) not certified, or -1.
    """

    scenario: str
    solver: str
    budget: str
    t: np.ndarray
    theta: np.ndarray
    r_d: np.ndarray
    error: np.ndarray
    mu: np.ndarray
    min_distance: np.ndarray
    closest_link: np.ndarray
    threshold: float
    F: np.ndarray
    step_time: np.ndarray
    query_time: np.ndarray
    build_time: np.ndarray
    solve_time: np.ndarray
    nfe: np.ndarray
    solver_feasible: np.ndarray
    joint_violation: np.ndarray
    velocity_violation: np.ndarray
    inequality_violation: np.ndarray
    jacobian_error: np.ndarray
    active_rows: np.ndarray
    relaxed_rows: np.ndarray
    motion_certified: bool | None = None
    motion_min_clearance: float = float("nan")
    motion_first_failure: int = -1

    @property
    def threshold_violations(self) -> int:
        """Samples whose exact clearance is below the threshold d."""
        return int(np.sum(self.min_distance < self.threshold))

    @property
    def steps_per_second(self) -> float:
        """``1 / mean(step_time)`` [Hz]."""
        return float(1.0 / np.mean(self.step_time)) if len(self.step_time) else np.inf


def _record_state(robot, scene, theta, r_d):
    """Exact pairs (timed: they are the next step's critical points), error, μ, clearance."""
    tq = time.perf_counter()
    pairs = scene.distances(theta)
    query_time = time.perf_counter() - tq
    obstacle_pairs = [p for p in pairs if not p.is_self]
    X_WE = robot.fk_drake(theta)  # verification: Drake itself
    error = float(np.linalg.norm(X_WE[:3, 3] - r_d))
    mu = robot.manipulability(theta)
    if obstacle_pairs:
        return pairs, query_time, error, mu, obstacle_pairs[0].distance, obstacle_pairs[0].link
    return pairs, query_time, error, mu, np.inf, ""


def run_esm(robot, scenario: ESMScenario, solver, seed=0, steps: int | None = None, verify: bool = True) -> ESMRun:
    """Runs the ESM loop of a scenario with a step solver.

    Args:
        robot: the Panda (``load_robot("panda")``), or any arm the scenario fits.
        scenario: an :class:`drake_mh.reactive.esm.scenarios.ESMScenario`.
        solver: a step solver (:class:`drake_mh.reactive.esm.AMNN`, :class:`MetaheuristicSolver`,
            :class:`QPBaseline`).
        seed: seed of the run (the solver draws one seed per step from it).
        steps: number of steps (default: the scenario's duration / Δt).
        verify: check every accepted step with Drake's Jacobians (adds ~0.1 ms per row).

    Returns:
        The :class:`ESMRun`.
    """
    from drake_mh.scene import Scene

    cfg = scenario.config
    n = scenario.steps if steps is None else int(steps)
    scene = Scene(robot)
    for obstacle in scenario.obstacles:
        p, v = obstacle.state(0.0)
        scene.add(obstacle.name, obstacle.shape, p, velocity=v)
    theta = robot.check_q(np.asarray(scenario.theta0, dtype=float), "theta0")
    solver.reset(seed)

    nq = robot.nq
    t = np.arange(n + 1) * cfg.dt
    thetas, targets = np.empty((n + 1, nq)), np.empty((n + 1, 3))
    error, mu, dist = np.empty(n + 1), np.empty(n + 1), np.empty(n + 1)
    link = np.empty(n + 1, dtype=object)
    F, nfe, feas, active = np.empty(n), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=bool), np.zeros(n, dtype=np.int64)
    relaxed = np.zeros(n, dtype=np.int64)
    times = np.zeros((4, n))  # query, build, solve, total
    checks = np.zeros((4, n))

    targets[0] = scenario.target(0.0)
    pairs, query_time, error[0], mu[0], dist[0], link[0] = _record_state(robot, scene, theta, targets[0])
    thetas[0] = theta
    for k in range(1, n + 1):
        targets[k] = scenario.target(t[k])
        t0 = time.perf_counter()
        step = build_step(robot, scene, theta, targets[k], cfg, pairs)
        t1 = time.perf_counter()
        sol = solver.solve(robot, step)
        t2 = time.perf_counter()
        times[:, k - 1] = (query_time, t1 - t0, t2 - t1, query_time + t2 - t0)
        F[k - 1], nfe[k - 1], feas[k - 1] = sol.F, sol.nfe, sol.feasible
        relaxed[k - 1] = len(step.relaxed_rows)
        if len(step.c):
            slack = (step.c - step.A @ sol.theta) / cfg.dt
            active[k - 1] = int(np.sum(slack < 1e-3))
        if verify:
            c = check_step(robot, step, sol.theta)
            checks[:, k - 1] = (c.joint_limit_violation, c.velocity_violation, c.inequality_violation,
                                c.jacobian_error)
        theta = sol.theta
        thetas[k] = theta
        for obstacle in scenario.obstacles:
            p, v = obstacle.state(t[k])
            scene.move(obstacle.name, position=p, velocity=v)
        pairs, query_time, error[k], mu[k], dist[k], link[k] = _record_state(robot, scene, theta, targets[k])
    motion = {}
    if not verify:
        checks[:] = np.nan
    else:
        motion = certify_esm_motion(robot, scenario, t, thetas)
    return ESMRun(scenario.name, solver.name, solver.budget_label, t, thetas, targets, error, mu, dist,
                  link.astype(str), cfg.threshold, F, times[3], times[0], times[1], times[2], nfe, feas,
                  checks[0], checks[1], checks[2], checks[3], active, relaxed, **motion)


def certify_esm_motion(robot, scenario: ESMScenario, t, theta, clearance: float = 0.0,
                       tolerance: float = 1e-3) -> dict:
    """Certify the executed motion of a run: ``theta[k-1] -> theta[k]`` straight in joint space
    during ``[t[k-1], t[k]]``, the scenario's obstacles moving with their (piecewise-constant)
    velocities; a step in which a velocity changes is cut there.

    Args:
        robot: the arm; scenario: its :class:`ESMScenario`.
        t: ``(N+1,)`` [s]; theta: ``(N+1, nq)`` [rad].
        clearance: [m] required at every instant (default 0: collision-free).
        tolerance: [m] of the reported lower bound.

    Returns:
        ``{"motion_certified", "motion_min_clearance" [m], "motion_first_failure" (1-based step or -1)}``.
    """
    from drake_mh.scene import Scene

    scene = Scene(robot)
    for obstacle in scenario.obstacles:
        p, v = obstacle.state(0.0)
        scene.add(obstacle.name, obstacle.shape, p, velocity=v)
    switches = np.unique([t_from for o in scenario.obstacles for t_from, _ in o.velocities])
    lowest, first = np.inf, -1
    for k in range(1, len(t)):
        a, b = float(t[k - 1]), float(t[k])
        cuts = np.concatenate([[a], switches[(switches > a) & (switches < b)], [b]])
        for c0, c1 in zip(cuts[:-1], cuts[1:]):
            for obstacle in scenario.obstacles:
                p, v = obstacle.state(c0)
                scene.move(obstacle.name, position=p, velocity=v)
            q0 = theta[k - 1] + (c0 - a) / (b - a) * (theta[k] - theta[k - 1])
            q1 = theta[k - 1] + (c1 - a) / (b - a) * (theta[k] - theta[k - 1])
            cert = scene.certify_segments(q0, q1, clearance, tolerance=tolerance, duration=c1 - c0)
            if not cert.all_certified:
                return {"motion_certified": False, "motion_min_clearance": float("nan"), "motion_first_failure": k}
            lowest = min(lowest, float(cert.lower[0]))
    return {"motion_certified": True, "motion_min_clearance": float(lowest), "motion_first_failure": first}
