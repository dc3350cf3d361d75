"""Drake's ``KinematicTrajectoryOptimization`` (B-spline) + SNOPT, as in Drake's examples.

The program (one per scene, clearance and :class:`KTOConfig`, cached; only the start and goal
bounds and the initial guess change between solves):

* a clamped B-spline ``q(s), s ∈ [0, 1]`` of order 4 with ``num_control_points = 10`` control
  points, and its duration ``T`` (``KinematicTrajectoryOptimization(nq, 10)``);
* ``AddPositionBounds`` (joint limits on every control point: the convex hull keeps the whole
  spline inside), ``AddVelocityBounds`` (``±robot.velocity_limits`` on the derivative's control
  points, scaled by ``T``), zero path velocity at ``s = 0`` and ``s = 1``;
* ``AddDurationConstraint(0.05, 20)``, ``AddDurationCost(1)`` and ``AddPathLengthCost(1)``
  (the costs of Drake's ``kinematic_trajectory_optimization`` example);
* the first and last control points fixed to ``q_start`` and the goal configuration (bounding
  boxes, so the solver holds them exactly);
* ``MinimumDistanceLowerBoundConstraint(clearance + margin, influence_distance)`` at
  ``num_samples = 25`` values of ``s`` (ends included), on a plant context whose SceneGraph holds
  the scene's obstacles (:func:`kto_context`, built as :func:`drake_mh.ik.drake.ik_context`
  does). Robot-robot pairs are always filtered out of Drake's query: Drake 1.51's
  capsule-capsule distance can hang (collinear axes) — self-collision is left to the
  verification.

``margin`` defaults to the sphere model's bound (``scene.sphere_model.bound``, ~9.5 mm for the
Panda): the verification certifies clearance under the sphere model, which is up to that much
more pessimistic than Drake's exact distance, so a solution resting on ``clearance`` exactly
would not verify. Drake's GJK is also optimistic for some pairs (docs/collision.md), another
reason for a margin. ``margin=0`` asks Drake for the problem's clearance only.

SNOPT (shipped with the pip wheel) solves it; where it is not available IPOPT does, and
``info["solver"]`` says so (a warning is logged once). The initial guess is the straight
joint-space line (``drake_kto``) or the ``rrt_connect`` path (``drake_kto_warm``: control
points at the Greville abscissae of the path's arc length). The solver's answer is returned
whatever its status — ``info["solver_success"]`` records its own flag — as ``waypoints = 64``
uniform samples of the optimized B-spline in time: the verification then certifies the
piecewise-linear motion through them, which is what is executed (the B-spline between the 25
constraint samples is never trusted).

The deadline: the pip wheel's SNOPT 7.4 ignores its ``Time limit`` option (measured: a solve
ran 34 s under a 2 s limit, 1000 major iterations), so the program carries a visualization
callback (``AddVisualizationCallback``: evaluated with the costs and constraints, no part of the
program, so SNOPT's iterates are unchanged) that raises once the deadline has passed; Drake
then stops SNOPT and the method returns no path (``"timeout"``), within one function
evaluation (~2-6 ms here) of the deadline. IPOPT also gets ``max_wall_time``. ``budget`` is
the solver's major iterations (IPOPT: ``max_iter``).
"""

from __future__ import annotations

import logging
import time
import weakref
from dataclasses import dataclass, fields

import numpy as np

from drake_mh.errors import InvalidArgument

logger = logging.getLogger(__name__)

__all__ = ["KTOConfig", "plan_kto", "kto_context", "solver_name"]


@dataclass(frozen=True)
class KTOConfig:
    """Settings of :func:`plan_kto` (every one is also a keyword option of ``solve_motion``).

    Attributes:
        num_control_points: B-spline control points (Drake's examples: 10).
        spline_order: B-spline order (4: cubic).
        num_samples: values of ``s`` (uniform in [0, 1], ends included) at which the
            minimum-distance constraint is imposed (Drake's example: 25).
        waypoints: uniform samples (in time) of the optimized spline returned as the path.
        margin: [m] asked of Drake beyond the problem's clearance; ``None``: the scene's
            sphere-model bound (module docstring).
        influence_distance: [m] ``influence_distance_offset`` of the constraint (pairs farther
            than the bound plus this are ignored by Drake).
        duration_bounds: ``(min, max)`` duration [s].
        duration_cost, path_length_cost: weights of ``AddDurationCost`` / ``AddPathLengthCost``.
        solver: ``"snopt"`` (IPOPT where SNOPT is unavailable) or ``"ipopt"``.
        snopt_options, ipopt_options: extra ``(name, value)`` solver options.
    """

    num_control_points: int = 10
    spline_order: int = 4
    num_samples: int = 25
    waypoints: int = 64
    margin: float | None = None
    influence_distance: float = 0.05
    duration_bounds: tuple = (0.05, 20.0)
    duration_cost: float = 1.0
    path_length_cost: float = 1.0
    solver: str = "snopt"
    snopt_options: tuple = ()
    ipopt_options: tuple = (("print_level", 0),)

    def __post_init__(self):
        if self.solver not in ("snopt", "ipopt"):
            raise InvalidArgument(f"solver must be 'snopt' or 'ipopt', got {self.solver!r}")
        for name in ("num_control_points", "spline_order", "num_samples", "waypoints"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 2:
                raise InvalidArgument(f"{name} must be an integer >= 2, got {value!r}")
        if self.num_control_points < self.spline_order:
            raise InvalidArgument(f"num_control_points ({self.num_control_points}) must be >= spline_order "
                                  f"({self.spline_order})")
        if self.margin is not None and not (np.isfinite(self.margin) and self.margin >= 0):
            raise InvalidArgument(f"margin must be a distance >= 0 [m] or None, got {self.margin!r}")
        lo, hi = self.duration_bounds
        if not (0 < lo < hi < np.inf):
            raise InvalidArgument(f"duration_bounds must be 0 < min < max, got {self.duration_bounds!r}")

    @classmethod
    def from_options(cls, options: dict) -> KTOConfig:
        """A config from ``solve_motion``'s keyword options (``config=`` or field names)."""
        options = dict(options)
        config = options.pop("config", None) or cls()
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(options) - names)
        if unknown:
            raise InvalidArgument(f"unknown drake_kto option(s) {unknown}; known: {sorted(names | {'config'})}")
        if options:
            config = cls(**{**{f.name: getattr(config, f.name) for f in fields(cls)}, **options})
        return config


_WARNED: set = set()


def solver_name(config: KTOConfig | None = None) -> str:
    """``"SNOPT"`` or ``"IPOPT"``: the solver :func:`plan_kto` uses with ``config``."""
    from pydrake.solvers import IpoptSolver, SnoptSolver

    config = config or KTOConfig()
    if config.solver == "snopt" and SnoptSolver().available() and SnoptSolver().enabled():
        return "SNOPT"
    if config.solver == "snopt" and "snopt" not in _WARNED:
        _WARNED.add("snopt")
        logger.warning("SNOPT is not available in this Drake build: drake_kto falls back to IPOPT")
    if not IpoptSolver().available():  # pragma: no cover - both ship with the pip wheel
        raise InvalidArgument("neither SNOPT nor IPOPT is available in this Drake build")
    return "IPOPT"


DEADLINE_MARK = "drake_mh: planning deadline reached"


class _Deadline(Exception):
    pass


# --- the scene's context and the cached programs ---------------------------------------------

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _signature(scene) -> tuple:
    return tuple((name, repr(o.shape), o.X_WO.tobytes()) for name, o in scene.obstacles.items())


def kto_context(problem):
    """A fresh ``(diagram_context, plant_context)`` of the robot with the scene's obstacles as
    anchored proximity geometry (:func:`drake_mh.ik.drake.ik_context`), robot-robot pairs
    filtered out (module docstring)."""
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet, Role

    from drake_mh.ik.drake import ik_context

    diagram_context, plant_context = ik_context(problem)  # reads problem.robot and problem.scene
    robot = problem.robot
    sg = robot.scene_graph
    inspector = sg.model_inspector()
    robot_ids = [g for g in inspector.GetAllGeometryIds(Role.kProximity)
                 if inspector.GetFrameId(g) != inspector.world_frame_id()]
    sg_context = sg.GetMyMutableContextFromRoot(diagram_context)
    sg.collision_filter_manager(sg_context).Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(robot_ids)))
    return diagram_context, plant_context


class _Program:
    """One ``KinematicTrajectoryOptimization`` with its start/goal bindings (updated per solve)."""

    def __init__(self, problem, plant_context, config: KTOConfig, bound: float):
        from pydrake.multibody.inverse_kinematics import MinimumDistanceLowerBoundConstraint
        from pydrake.planning import KinematicTrajectoryOptimization

        robot = problem.robot
        nq = robot.nq
        if robot.plant.num_positions() != nq:  # sizes checked here: Drake must not see a mismatch
            raise InvalidArgument(f"drake_kto needs one position per joint: the plant has {robot.plant.num_positions()} "
                                  f"positions, the robot {nq} joints")
        trajopt = KinematicTrajectoryOptimization(nq, config.num_control_points, config.spline_order)
        prog = trajopt.get_mutable_prog()
        trajopt.AddPositionBounds(robot.lower, robot.upper)
        trajopt.AddVelocityBounds(-robot.velocity_limits, robot.velocity_limits)
        trajopt.AddPathVelocityConstraint(np.zeros(nq), np.zeros(nq), 0.0)
        trajopt.AddPathVelocityConstraint(np.zeros(nq), np.zeros(nq), 1.0)
        trajopt.AddDurationConstraint(*config.duration_bounds)
        if config.duration_cost > 0:
            trajopt.AddDurationCost(config.duration_cost)
        if config.path_length_cost > 0:
            trajopt.AddPathLengthCost(config.path_length_cost)
        cps = trajopt.control_points()
        self.start = prog.AddBoundingBoxConstraint(problem.q_start, problem.q_start, cps[:, 0])
        self.goal = prog.AddBoundingBoxConstraint(problem.q_start, problem.q_start, cps[:, -1])
        self.distance = MinimumDistanceLowerBoundConstraint(robot.plant, bound, plant_context, None,
                                                            config.influence_distance)
        for s in np.linspace(0.0, 1.0, config.num_samples):
            trajopt.AddPathPositionConstraint(self.distance, float(s))
        # the wheel's SNOPT 7.4 ignores "Time limit" (measured: 34 s under a 2 s limit): a
        # visualization callback (evaluated with the costs and constraints, no part of the
        # program) raises past the deadline, and Drake stops the solver. It holds only this
        # small state, not the program (a reference cycle through C++ would never be freed)
        self.clock = clock = {"deadline": np.inf, "evaluations": 0}

        def guard(x):
            clock["evaluations"] += 1
            if time.perf_counter() > clock["deadline"]:
                raise _Deadline(DEADLINE_MARK)

        prog.AddVisualizationCallback(guard, [trajopt.duration()])
        self.trajopt, self.prog, self.bound = trajopt, prog, bound


def _program(problem, config: KTOConfig, bound: float) -> _Program:
    """The cached :class:`_Program` of this scene, clearance bound and config."""
    scene = problem.scene
    signature = _signature(scene)
    entry = _CACHE.get(scene)
    if entry is None or entry["signature"] != signature or entry["robot"]() is not problem.robot:
        diagram_context, plant_context = kto_context(problem)
        entry = {"signature": signature, "robot": weakref.ref(problem.robot), "diagram_context": diagram_context,
                 "plant_context": plant_context, "programs": {}}
        _CACHE[scene] = entry
    key = (config, round(bound, 12))
    program = entry["programs"].get(key)
    if program is None:
        program = _Program(problem, entry["plant_context"], config, bound)
        entry["programs"][key] = program
    return program


# --- solving ---------------------------------------------------------------------------------

def _initial_control_points(path: np.ndarray, n: int, order: int) -> np.ndarray:
    """``(nq, n)`` control points at the Greville abscissae of ``path``'s arc length (a straight
    line for two rows)."""
    from pydrake.math import BsplineBasis, KnotVectorType

    basis = BsplineBasis(order, n, KnotVectorType.kClampedUniform, 0.0, 1.0)
    knots = np.asarray(basis.knots())
    greville = np.array([np.mean(knots[i + 1:i + order]) for i in range(n)])
    lengths = np.linalg.norm(np.diff(path, axis=0), axis=1)
    s = np.r_[0.0, np.cumsum(lengths)]
    if s[-1] <= 0:
        return np.repeat(path[:1].T, n, axis=1)
    s /= s[-1]
    return np.stack([np.interp(greville, s, path[:, j]) for j in range(path.shape[1])])


def _solver_options(solver, name: str, config: KTOConfig, remaining: float, budget: int | None):
    from pydrake.solvers import SolverOptions

    options = SolverOptions()
    sid = solver.solver_id()
    for key, value in (config.snopt_options if name == "SNOPT" else config.ipopt_options):
        options.SetOption(sid, key, value)
    if np.isfinite(remaining) and name == "IPOPT":  # SNOPT: the deadline guard (_Program)
        options.SetOption(sid, "max_wall_time", float(max(remaining, 1e-3)))
    if budget is not None:
        options.SetOption(sid, "Major iterations limit" if name == "SNOPT" else "max_iter", int(budget))
    return options


def plan_kto(problem, goal: np.ndarray, guess: np.ndarray | None, deadline: float | None, budget: int | None,
             config: KTOConfig) -> tuple[np.ndarray | None, dict]:
    """Optimize a trajectory from ``problem.q_start`` to ``goal`` (module docstring).

    Args:
        problem: the :class:`~drake_mh.planning.MotionProblem`.
        goal: ``(nq,)`` goal configuration.
        guess: ``(M, nq)`` path for the initial guess (``None``: the straight line).
        deadline: ``time.perf_counter()`` value to stop at (the solver's time limit).
        budget: the solver's major iterations (``None``: its default).
        config: :class:`KTOConfig`.

    Returns:
        ``(waypoints (config.waypoints, nq), info)``; ``None`` for the path when the solver
        returned no finite trajectory (or the deadline passed before it started).
    """
    from pydrake.solvers import IpoptSolver, SnoptSolver

    name = solver_name(config)
    solver = SnoptSolver() if name == "SNOPT" else IpoptSolver()
    bound = problem.clearance + (problem.scene.sphere_model.bound if config.margin is None else config.margin)
    info = {"solver": name, "distance_bound": bound}
    build = time.perf_counter()
    program = _program(problem, config, bound)
    info["build_time"] = time.perf_counter() - build
    trajopt, prog = program.trajopt, program.prog
    q_start, goal = problem.q_start, np.asarray(goal, dtype=float)
    program.start.evaluator().set_bounds(q_start, q_start)
    program.goal.evaluator().set_bounds(goal, goal)
    path = np.stack([q_start, goal]) if guess is None else np.asarray(guess, dtype=float)
    cps = _initial_control_points(path, config.num_control_points, config.spline_order)
    cps[:, 0], cps[:, -1] = q_start, goal
    # duration guess: twice the slowest joint's time at its velocity limit (the clamped spline's
    # derivative peaks above the mean slope), within the bounds
    travel = np.sum(np.abs(np.diff(path, axis=0)), axis=0)
    lo, hi = config.duration_bounds
    T0 = float(np.clip(2.0 * np.max(travel / problem.robot.velocity_limits), max(lo, 0.1), hi))
    prog.SetInitialGuess(trajopt.control_points(), cps)
    prog.SetInitialGuess(trajopt.duration(), T0)
    remaining = np.inf if deadline is None else deadline - time.perf_counter()
    if remaining <= 0:
        info["message"] = "timeout before the solver started"
        return None, info
    solve = time.perf_counter()
    clock = program.clock
    clock["deadline"], clock["evaluations"] = (np.inf if deadline is None else deadline), 0
    try:
        result = solver.Solve(prog, None, _solver_options(solver, name, config, remaining, budget))
    except (_Deadline, RuntimeError) as exc:  # SNOPT: Drake's RuntimeError; IPOPT: ours, as raised
        if DEADLINE_MARK not in str(exc):
            raise
        info["solve_time"] = time.perf_counter() - solve
        info["evaluations"] = clock["evaluations"]
        info["solver_success"] = False
        info["solver_status"] = "timeout"
        info["message"] = f"timeout: {name} stopped at the deadline after {clock['evaluations']} evaluations"
        return None, info
    finally:
        clock["deadline"] = np.inf
    info["solve_time"] = time.perf_counter() - solve
    info["evaluations"] = clock["evaluations"]
    info["solver_success"] = bool(result.is_success())
    info["solver_status"] = str(result.get_solution_result()).split(".")[-1]
    if name == "SNOPT":
        info["snopt_info"] = int(result.get_solver_details().info)
    trajectory = trajopt.ReconstructTrajectory(result)
    times = np.linspace(trajectory.start_time(), trajectory.end_time(), config.waypoints)
    W = np.asarray(trajectory.vector_values(times), dtype=float).T
    if not np.all(np.isfinite(W)):
        info["message"] = f"{name} returned a non-finite trajectory ({info['solver_status']})"
        return None, info
    info["duration"] = float(trajectory.end_time() - trajectory.start_time())
    info["message"] = f"{name} {info['solver_status']}"
    return W, info
