"""``solve_motion``: one entry point for every motion planner, one verification for all.

The planners are one explicit table, :data:`drake_mh.planning.methods.METHODS` (one folder or
module each under :mod:`drake_mh.planning`, imported on first use); :func:`available_motion_methods`
lists them and :func:`register` adds one of your own. A method's
``plan.prepare(problem, **options)``, if it has one, loads what it needs (compiled kernels,
and, with a warm-start option, the warm-start planner's) before the clock starts: a timeout
measures planning, not loading (``info["prepare_time"]``). It gets the same options as the plan
(a ``prepare`` without ``**options`` gets those it names; :func:`prepare_motion_method`). A method is a function
``plan(problem, goals (G, nq), rng, deadline, budget, **options) -> (path (M, nq) | None, info)``
that plans from ``problem.q_start`` to any row of ``goals``; it may use ``problem.is_free`` and
``problem.scene.certify_segments`` as it likes, but its answer is verified by
:func:`drake_mh.planning.verify.verify_motion`, never by its own flags.

A pose goal is turned into goal configurations here, once per problem (collision-free IK, the
same answers for every method; their time is reported apart, as ``goal_time``).
"""

from __future__ import annotations

import numbers
import time

import numpy as np

from drake_mh._support.compilation import compile_seconds
from drake_mh.errors import InvalidArgument, InvalidMotionProblem
from drake_mh.planning.methods import METHODS
from drake_mh.planning.problem import MotionProblem
from drake_mh.planning.result import MotionResult
from drake_mh.planning.verify import check_retime, check_scaling, verify_motion


def register(name: str, description: str):
    """Decorator: add a planner of your own to :data:`~drake_mh.planning.methods.METHODS` under
    ``name`` (see the module docstring for what a planner is)."""
    return METHODS.register(name, description)


def available_motion_methods() -> dict:
    """``{name: one-line description}`` of the planners present here (an optional peer that
    cannot be imported is absent)."""
    return METHODS.available()


def get_motion_method(name: str):
    """The planner ``plan(problem, goals, rng, deadline, budget, **options)`` named
    ``name`` (e.g. to warm-start one planner from another).

    Raises:
        UnknownMethod: no such method.
    """
    return METHODS.get(name)


def prepare_motion_method(method, problem: MotionProblem, **options) -> float:
    """Run a method's ``prepare(problem, **options)`` (nothing if it has none): what
    :func:`solve_motion` does before its clock starts.

    A ``prepare`` that takes ``**options`` gets every option; one that names some gets those
    (so an option of the plan never breaks a ``prepare`` that does not use it).

    Args:
        method: a registered name, or the planner function itself.
        problem: the problem about to be solved.
        **options: the options the plan will get.

    Returns:
        The seconds it took.

    Raises:
        UnknownMethod: no such method.
    """
    import inspect

    function = get_motion_method(method) if isinstance(method, str) else method
    prepare = getattr(function, "prepare", None)
    start = time.perf_counter()
    if prepare is not None:
        parameters = inspect.signature(prepare).parameters
        if not any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()):
            options = {k: v for k, v in options.items() if k in parameters}
        prepare(problem, **options)
    return time.perf_counter() - start


def goal_configurations(problem: MotionProblem, count: int = 4, timeout: float | None = 5.0) -> np.ndarray:
    """The problem's goal configurations; for a pose goal, up to ``count`` collision-free IK
    answers (hybrid IK with the scene, seeds 0, 1, ..., each verified with Drake, then
    certified free under the sphere model with the problem's clearances), computed once per
    problem and shared by every method (their time is :attr:`MotionResult.goal_time`, not
    planning time).

    Raises:
        InvalidMotionProblem: no collision-free IK answer for the pose.
    """
    if problem.goal_pose is None:
        return problem.goal_configurations
    cached = problem.__dict__.get("_goal_cache")
    if cached is not None:
        return cached
    from drake_mh.ik import IKProblem, solve_ik

    ik = IKProblem(problem.robot, problem.goal_pose, scene=problem.scene, clearance=problem.clearance,
                   frame=problem.frame)
    found = []
    for seed in range(3 * count):
        answer = solve_ik(ik, "hybrid", seed=seed, timeout=timeout)
        if answer.success and problem.is_free(answer.q):
            if not found or min(np.max(np.abs(answer.q - q)) for q in found) > 1e-3:
                found.append(answer.q)
        if len(found) >= count:
            break
    if not found:
        raise InvalidMotionProblem("no collision-free IK answer for the goal pose: it may be out of reach or "
                                   "inside an obstacle; check it with drake_mh.solve_ik")
    goals = np.asarray(found)
    object.__setattr__(problem, "_goal_cache", goals)
    return goals


def solve_motion(problem: MotionProblem, method: str = "rrt_connect", seed=0, timeout: float | None = 10.0,
                 budget: int | None = None, retime: bool | str = True, velocity_scaling: float | None = None,
                 acceleration_scaling: float | None = None, **options) -> MotionResult:
    """Plan a motion with any registered method; the answer is verified the same way for all.

    Args:
        problem: the :class:`MotionProblem`.
        method: a name of :func:`available_motion_methods`.
        seed: seed of the method's randomness (same seed, same path when the run ends by
            success or budget rather than by the timeout).
        timeout: [s] wall-clock limit of planning (``None``: none).
        budget: the method's own unit (tree nodes, evaluations, solver iterations).
        retime: also retime and certify a trajectory: ``True`` toppra, else ruckig; ``"toppra"``;
            ``"ruckig"`` (jerk-limited, on the straight segments, at rest at each waypoint);
            ``False`` none (:func:`~drake_mh.planning.verify_motion`). The limits are the
            robot's (``robot.limits``; a vendor URDF without acceleration limits is retimed
            under its velocity and torque limits), stated with their sources in
            :attr:`MotionResult.limits`.
        velocity_scaling, acceleration_scaling: MoveIt's scaling factors in (0, 1]: the
            fraction of the velocity / acceleration limits the trajectory may use (``None``: the
            robot's defaults, 1 unless a limits file sets them).
        **options: the method's options.

    Returns:
        A verified :class:`MotionResult` (``success`` recomputed, never the method's flag). Its
        ``info["prepare_time"]`` holds the seconds spent loading or compiling the method's kernels
        before the planning clock started, ``info["compile_time"]`` the seconds spent compiling
        kernels anywhere in the call (the first call on a machine compiles the planner's,
        the verification's and the retiming's kernels: minutes; 0 once they are cached).

    Raises:
        UnknownMethod, InvalidArgument, InvalidMotionProblem.
    """
    if not isinstance(problem, MotionProblem):
        raise InvalidArgument(f"problem must be a drake_mh.planning.MotionProblem, got {type(problem).__name__}")
    function = METHODS.get(method)
    if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, numbers.Real)
                                or not np.isfinite(timeout) or timeout <= 0):
        raise InvalidArgument(f"timeout must be a number of seconds > 0 or None, got {timeout!r}")
    if budget is not None and (isinstance(budget, bool) or not isinstance(budget, numbers.Integral) or budget < 1):
        raise InvalidArgument(f"budget must be an integer >= 1 or None, got {budget!r}")
    check_retime(retime)
    check_scaling(velocity_scaling, acceleration_scaling)
    compiled_before = compile_seconds()
    rng = np.random.default_rng(seed)
    goal_start = time.perf_counter()
    goals = goal_configurations(problem)
    goal_time = time.perf_counter() - goal_start
    # load compiled kernels (the warm-start planner's too) before the clock starts, once per process
    prepare_time = prepare_motion_method(function, problem, **dict(options))
    wall, cpu = time.perf_counter(), time.process_time()
    deadline = None if timeout is None else wall + float(timeout)
    path, info = function(problem, goals, rng, deadline, budget, **options)
    planning_time, cpu_time = time.perf_counter() - wall, time.process_time() - cpu
    result = MotionResult(method, seed=seed, info=dict(info or {}), goal_time=goal_time, planning_time=planning_time,
                          cpu_time=cpu_time)
    # a plan that prepared for itself (called without solve_motion's prepare) reports that time too
    result.info["prepare_time"] = prepare_time + float(result.info.get("prepare_time", 0.0))
    if path is None:
        result.message = result.info.pop("message", "no path found")
    else:
        result = verify_motion(problem, path, method, result, retime=retime, velocity_scaling=velocity_scaling,
                               acceleration_scaling=acceleration_scaling)
    result.info["compile_time"] = compile_seconds() - compiled_before
    return result
