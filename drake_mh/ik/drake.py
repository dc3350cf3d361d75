"""Drake's gradient-based IK as baselines: ``InverseKinematics`` solved by SNOPT or IPOPT.

The problem is translated into Drake's ``pydrake.multibody.inverse_kinematics
.InverseKinematics`` program on the robot's own plant:

* joint limits as bounds on the decision variables (``with_joint_limits=True``);
* ``AddPositionConstraint``: the end-effector origin equals ``p_WT`` (lower = upper bound);
* full pose: ``AddOrientationConstraint`` with angle bound ``θ <= orientation_tolerance / 2``
  (``orientation="constraint"``, default), or ``AddOrientationCost`` (``"cost"``); Drake's
  orientation constraint is a bound on ``trace(R_WTᵀ R_WE)``, whose slope vanishes at θ = 0,
  so a solver's feasibility tolerance ``δ`` leaves an angle of about ``√δ``: SNOPT's major
  feasibility and optimality tolerances are tightened to 1e-9 and IPOPT's ``tol`` /
  ``constr_viol_tol`` to 1e-10 / 1e-12 (measured: with the defaults most "successful"
  solves miss a 1e-5 rad tolerance);
* obstacles: ``AddMinimumDistanceLowerBoundConstraint(clearance + 1e-5)``. The constraint
  needs the obstacles in the *IK's plant context*: :func:`ik_context` builds a diagram context
  of the robot's plant + scene graph and registers the scene's obstacles in it as anchored
  proximity geometry of the robot's obstacle source (as :class:`drake_mh.scene.Scene` does in
  its own context), with the same collision filter (robot-robot pairs excluded unless the
  scene checks self-collision);
* ``q_ref`` with ``ref_weight``: ``AddQuadraticErrorCost(ref_weight · I, q_ref, q)``.

Random restarts until the timeout (or the number of attempts): the first initial guess is
``q_ref`` or the mid-range configuration, the next ones uniform within the limits. Each
solution is verified with Drake (:func:`drake_mh.ik.result.check`), never trusted from the
solver's status; the first verified one is returned. The manipulability term of a problem is
not modelled here.
"""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.ik.problem import IKProblem
from drake_mh.ik.result import IKResult, check, verify

__all__ = ["DrakeIKConfig", "solve_drake", "ik_context", "cached_ik_context", "DRAKE_SOLVERS"]

#: method name -> Drake solver class name
DRAKE_SOLVERS = {"drake_snopt": "SnoptSolver", "drake_ipopt": "IpoptSolver"}

#: [m] extra clearance asked of Drake's minimum-distance constraint (solver feasibility slack)
DISTANCE_MARGIN = 1e-5


@dataclass(frozen=True)
class DrakeIKConfig:
    """Settings of :func:`solve_drake`.

    Attributes:
        orientation: ``"constraint"`` or ``"cost"`` (module docstring).
        max_attempts: solver starts when neither a budget nor a timeout is given.
        influence_distance: [m] ``influence_distance_offset`` of the minimum-distance
            constraint (pairs farther than clearance + this are ignored by Drake).
        snopt_options, ipopt_options: solver options (``SolverOptions.SetOption``).
    """

    orientation: str = "constraint"
    max_attempts: int = 20
    influence_distance: float = 0.05
    snopt_options: tuple = (("Major feasibility tolerance", 1e-9), ("Major optimality tolerance", 1e-9))
    ipopt_options: tuple = (("print_level", 0), ("tol", 1e-10), ("constr_viol_tol", 1e-12),
                            ("bound_relax_factor", 0.0))

    def __post_init__(self):
        if self.orientation not in ("constraint", "cost"):
            raise InvalidArgument(f"orientation must be 'constraint' or 'cost', got {self.orientation!r}")
        if int(self.max_attempts) < 1:
            raise InvalidArgument(f"max_attempts must be >= 1, got {self.max_attempts}")


_CONTEXTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _scene_signature(scene) -> tuple:
    """What the IK context depends on: the obstacles (name, shape, pose) and the filter."""
    if scene is None:
        return ()
    return (scene.self_collision,) + tuple((name, repr(o.shape), o.X_WO.tobytes()) for name, o in scene.obstacles.items())


def cached_ik_context(problem: IKProblem):
    """:func:`ik_context`, reused while the robot's scene is unchanged.

    Creating a diagram context costs about 0.5–1 ms (a fifth of the TRAC-IK protocol's 5 ms
    timeout), so the Drake baselines keep one per robot (and per scene, rebuilt when its
    obstacles change) instead of paying it on every solve. Not thread-safe, like ``Robot``.
    """
    owner = problem.scene if problem.scene is not None else problem.robot
    signature = _scene_signature(problem.scene)
    entry = _CONTEXTS.get(owner)
    if entry is None or entry[0] != signature:
        entry = (signature, *ik_context(problem))
        _CONTEXTS[owner] = entry
    return entry[1], entry[2]


def ik_context(problem: IKProblem):
    """A fresh ``(diagram_context, plant_context)`` of the robot with the scene's obstacles.

    The obstacles are registered as anchored proximity geometry in this context's scene graph
    (the robot's ``obstacle_source_id``), so Drake's distance queries inside
    ``InverseKinematics`` (``MinimumDistanceLowerBoundConstraint``) see them; robot-robot pairs
    are filtered out unless the scene checks self-collision (then Drake's default filter of
    adjacent links applies; a scene's extra ``ignore_link_pairs`` are not carried over).
    """
    from pydrake.geometry import (
        CollisionFilterDeclaration,
        GeometryInstance,
        GeometrySet,
        ProximityProperties,
        Role,
    )
    from pydrake.math import RigidTransform, RotationMatrix

    robot = problem.robot
    diagram_context = robot.diagram.CreateDefaultContext()
    plant_context = robot.plant.GetMyMutableContextFromRoot(diagram_context)
    scene = problem.scene
    if scene is None:
        return diagram_context, plant_context
    sg = robot.scene_graph
    sg_context = sg.GetMyMutableContextFromRoot(diagram_context)
    inspector = sg.model_inspector()
    robot_ids = [g for g in inspector.GetAllGeometryIds(Role.kProximity)
                 if inspector.GetFrameId(g) != inspector.world_frame_id()]
    if not scene.self_collision:
        sg.collision_filter_manager(sg_context).Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(robot_ids)))
    for name, obstacle in scene.obstacles.items():
        X_WO = RigidTransform(RotationMatrix(obstacle.X_WO[:3, :3]), obstacle.X_WO[:3, 3])
        instance = GeometryInstance(X_WO, obstacle.shape.to_drake(), f"obstacle::{name}")
        instance.set_proximity_properties(ProximityProperties())
        sg.RegisterGeometry(sg_context, robot.obstacle_source_id, sg.world_frame_id(), instance)
    return diagram_context, plant_context


def _program(problem: IKProblem, plant_context, config: DrakeIKConfig):
    """The ``InverseKinematics`` object of ``problem`` (constraints and costs added)."""
    from pydrake.math import RotationMatrix
    from pydrake.multibody.inverse_kinematics import InverseKinematics

    robot = problem.robot
    plant = robot.plant
    W = plant.world_frame()
    E = robot._frame(problem.frame)
    ik = InverseKinematics(plant, plant_context, with_joint_limits=True)
    ik.AddPositionConstraint(E, np.zeros(3), W, problem.p_WT, problem.p_WT)
    if problem.R_WT is not None:
        if config.orientation == "constraint":
            ik.AddOrientationConstraint(W, RotationMatrix(problem.R_WT), E, RotationMatrix(),
                                        0.5 * problem.orientation_tolerance)
        else:
            ik.AddOrientationCost(W, RotationMatrix(problem.R_WT), E, RotationMatrix(), 1.0)
    if problem.has_obstacles:
        ik.AddMinimumDistanceLowerBoundConstraint(problem.clearance + DISTANCE_MARGIN, config.influence_distance)
    if problem.q_ref is not None and problem.ref_weight > 0:
        ik.prog().AddQuadraticErrorCost(problem.ref_weight * np.eye(problem.nq), problem.q_ref, ik.q())
    return ik


def solve_drake(problem: IKProblem, method: str, seed=0, budget: int | None = None, timeout: float | None = None,
                config: DrakeIKConfig | None = None, start: float | None = None) -> IKResult:
    """Solves ``problem`` with Drake's ``InverseKinematics`` and random restarts (module docstring).

    Args:
        problem: the IK problem.
        method: ``"drake_snopt"`` or ``"drake_ipopt"``.
        seed: seed of the initial guesses.
        budget: solver starts (Drake does not report function evaluations; ``nfe`` is 0).
            ``None``: ``config.max_attempts`` when no timeout is given, else unlimited.
        timeout: [s] wall-clock limit; the last attempt gets the remaining time as the
            solver's time limit (IPOPT ``max_wall_time``; SNOPT ``Time limit``, which SNOPT
            checks coarsely).
        config: :class:`DrakeIKConfig`.
        start: ``time.perf_counter()`` of the caller's start.
    """
    from pydrake.solvers import IpoptSolver, SnoptSolver, SolverOptions

    start = time.perf_counter() if start is None else start
    config = config or DrakeIKConfig()
    snopt = method == "drake_snopt"
    solver = SnoptSolver() if snopt else IpoptSolver()
    if not solver.available():  # pragma: no cover - both ship with the pip wheel
        raise InvalidArgument(f"{DRAKE_SOLVERS[method]} is not available in this Drake build")
    rng = np.random.default_rng(seed)
    _, plant_context = cached_ik_context(problem)
    ik = _program(problem, plant_context, config)
    prog, q_vars = ik.prog(), ik.q()
    deadline = np.inf if timeout is None else start + timeout
    if budget is None:
        budget = config.max_attempts if timeout is None else np.inf
    lower, upper = problem.lower, problem.upper
    q0 = problem.q_ref if problem.q_ref is not None else 0.5 * (lower + upper)
    best_q, best_err = np.array(q0, dtype=float), np.inf
    attempts = 0
    base = config.snopt_options if snopt else config.ipopt_options
    last_status = ""
    while attempts < budget:
        remaining = deadline - time.perf_counter()
        if remaining <= 0:
            break
        options = SolverOptions()
        for key, value in base:
            options.SetOption(solver.solver_id(), key, value)
        if np.isfinite(remaining):
            options.SetOption(solver.solver_id(), "Time limit" if snopt else "max_wall_time", float(remaining))
        result = solver.Solve(prog, q0, options)
        attempts += 1
        last_status = str(result.get_solution_result()).split(".")[-1]
        q = np.asarray(result.GetSolution(q_vars), dtype=float)
        if np.all(np.isfinite(q)):
            ok, e_p, e_o = check(problem, q)[:3]
            if ok:
                return verify(problem, q, method=method, start=start, nfe=0, attempts=attempts,
                              message=f"{DRAKE_SOLVERS[method]} {last_status} on attempt {attempts}")
            err = e_p / problem.position_tolerance + e_o / problem.orientation_tolerance
            if err < best_err:
                best_q, best_err = q, err
        q0 = lower + (upper - lower) * rng.random(problem.nq)
    why = "timeout" if time.perf_counter() > deadline else "attempts exhausted"
    return verify(problem, best_q, method=method, start=start, nfe=0, attempts=attempts,
                  message=f"{why} after {attempts} {DRAKE_SOLVERS[method]} attempts (last: {last_status})")
