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

import functools
import numbers
import time

import numpy as np

from drake_mh._support.compilation import compile_seconds
from drake_mh.errors import InvalidArgument, InvalidMotionProblem
from drake_mh.planning.methods import METHODS
from drake_mh.planning.problem import MotionProblem
from drake_mh.planning.result import MotionResult
from drake_mh.optim.base import MAX_BUDGET, check_timeout
from drake_mh.planning.verify import check_retime, check_scaling, reaches_goal, verify_motion



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
    function = get_motion_method(method) if isinstance(method, str) else method
    prepare = getattr(function, "prepare", None)
    start = time.perf_counter()
    if prepare is not None:
        try:
            names = _named_options(prepare)
        except TypeError:  # an unhashable callable: read its signature each time
            names = _named_options.__wrapped__(prepare)
        if names is not None:
            options = {k: v for k, v in options.items() if k in names}
        prepare(problem, **options)
    return time.perf_counter() - start


@functools.lru_cache(maxsize=256)
def _named_options(prepare) -> frozenset | None:
    """The parameter names of ``prepare``, or ``None`` when it takes ``**options`` (read once per
    function: ``inspect.signature`` is slow)."""
    import inspect

    parameters = inspect.signature(prepare).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()):
        return None
    return frozenset(parameters)


def _goal_ik(problem: MotionProblem):
    """The IK problem of a pose goal (built once per problem)."""
    ik = problem.__dict__.get("_goal_ik")
    if ik is None:
        from drake_mh.ik import IKProblem

        ik = IKProblem(problem.robot, problem.goal_pose, scene=problem.scene, clearance=problem.clearance,
                       frame=problem.frame)
        object.__setattr__(problem, "_goal_ik", ik)
    return ik


def goal_configurations(problem: MotionProblem, count: int = 4, timeout: float | None = 5.0,
                        deadline: float | None = None) -> np.ndarray:
    """The problem's goal configurations; for a pose goal, up to ``count`` collision-free IK
    answers (hybrid IK with the scene, seeds 0, 1, ..., each verified with Drake, then
    certified free under the sphere model with the problem's clearances), computed once per
    problem and obstacle set and shared by every method (their time is
    :attr:`MotionResult.goal_time`).

    Args:
        timeout: [s] per IK seed (``None``: none).
        deadline: ``time.perf_counter()`` value by which to stop (``None``: none); answers
            found by then are returned, and are not kept for the next call.

    Raises:
        InvalidMotionProblem: no collision-free IK answer for the pose (every seed tried), or
            none before the deadline (the message says so).
    """
    if problem.goal_pose is None:
        return problem.goal_configurations
    arrays = problem.scene.obstacle_arrays  # a new tuple after any change of the obstacles
    cached = problem.__dict__.get("_goal_cache")
    if cached is not None and cached[1] is arrays:
        return cached[0]
    from drake_mh.ik import solve_ik

    ik = _goal_ik(problem)
    found, tried = [], 0
    for seed in range(3 * count):
        limits = [t for t in (timeout, None if deadline is None else deadline - time.perf_counter()) if t is not None]
        if limits and min(limits) <= 0:
            break
        answer = solve_ik(ik, "hybrid", seed=seed, timeout=min(limits) if limits else None)
        tried += 1
        if answer.success and problem.is_free(answer.q):
            if not found or min(np.max(np.abs(answer.q - q)) for q in found) > 1e-3:
                found.append(answer.q)
        if len(found) >= count:
            break
    cut = len(found) < count and deadline is not None and time.perf_counter() >= deadline  # the deadline ended it
    if not found:
        raise InvalidMotionProblem(
            f"no collision-free IK answer for the goal pose within the timeout ({tried} IK seeds tried); raise "
            "the timeout, or check the pose with drake_mh.solve_ik" if cut else
            "no collision-free IK answer for the goal pose: it may be out of reach or inside an obstacle; check "
            "it with drake_mh.solve_ik")
    goals = np.asarray(found)
    if not cut:
        object.__setattr__(problem, "_goal_cache", (goals, arrays))
    return goals


def solve_motion(problem: MotionProblem, method: str = "rrt_connect", seed=0, timeout: float | None = 10.0,
                 budget: int | None = None, retime: bool | str = True, velocity_scaling: float | None = None,
                 acceleration_scaling: float | None = None, **options) -> MotionResult:
    """Plan a motion with any registered method; the answer is verified the same way for all.

    The scene is read as it is now: a start or every goal configuration that an obstacle added
    or moved since the problem was built puts in collision fails at once, saying so. A start
    that already reaches the goal (a goal configuration within 1e-6 rad, or the goal pose within
    its tolerances) is answered without planning: the one-waypoint path, verified, and a
    stationary trajectory of zero duration.

    Args:
        problem: the :class:`MotionProblem`.
        method: a name of :func:`available_motion_methods`.
        seed: seed of the method's randomness, an integer >= 0 or a numpy SeedSequence /
            Generator (same seed, same path when the run ends by success or budget rather than
            by the timeout).
        timeout: [s] wall-clock limit of the whole search, ``None``: none. It bounds the goal
            IK of a pose goal and the planning together (a pose goal with no IK answer by then
            fails, saying so). Not counted: loading compiled code before the clock starts
            (``info["prepare_time"]``), and the verification and retiming of a path found in
            time (bounded work, ``verify_time``).
        budget: the method's own unit (tree nodes, evaluations, solver iterations), an integer
            in ``[1, MAX_BUDGET]``.
        retime: also retime and certify a trajectory: ``True`` toppra, else ruckig; ``"toppra"``;
            ``"ruckig"`` (jerk-limited, on the straight segments, at rest at each waypoint);
            ``False`` none (:func:`~drake_mh.planning.verify_motion`). The limits are the
            robot's (``robot.limits``; a vendor URDF without acceleration limits is retimed
            under its velocity and torque limits), stated with their sources in
            :attr:`MotionResult.limits`.
        velocity_scaling, acceleration_scaling: MoveIt's scaling factors in (0, 1]: the
            fraction of the velocity / acceleration limits the trajectory may use (``None``: the
            robot's defaults, 1 unless a limits file sets them).
        **options: the method's options (every method rejects one it does not know, listing its
            own).

    Returns:
        A verified :class:`MotionResult` (``success`` recomputed, never the method's flag). Its
        ``info["prepare_time"]`` holds the seconds spent loading or compiling kernels (the
        goal IK's, the method's and its warm-start planner's) before the clock started,
        ``info["compile_time"]`` the seconds spent compiling kernels anywhere in the call (the
        first call on a machine compiles the planner's, the verification's and the retiming's
        kernels: minutes; 0 once they are cached).

    Raises:
        UnknownMethod, InvalidArgument, InvalidMotionProblem.
    """
    if not isinstance(problem, MotionProblem):
        raise InvalidArgument(f"problem must be a drake_mh.planning.MotionProblem, got {type(problem).__name__}")
    function = METHODS.get(method)
    seconds = check_timeout(timeout)
    if budget is not None and (isinstance(budget, bool) or not isinstance(budget, numbers.Integral)
                               or not 1 <= budget <= MAX_BUDGET):
        raise InvalidArgument(f"budget must be an integer in [1, {MAX_BUDGET:.0e}] or None, got {budget!r}")
    from drake_mh.ik.solve import prepare as ik_prepare
    from drake_mh.optim.base import make_rng

    rng = make_rng(seed, "seed")
    check_retime(retime)
    check_scaling(velocity_scaling, acceleration_scaling)
    compiled_before = compile_seconds()
    result = MotionResult(method, seed=seed, planning_time=0.0, cpu_time=0.0)
    # load compiled code (the goal IK's, the method's and its warm-start planner's) before the clock starts
    result.info["prepare_time"] = (
        (0.0 if problem.goal_pose is None else ik_prepare(_goal_ik(problem), "hybrid"))
        + prepare_motion_method(function, problem, **dict(options)))
    result = _search(problem, function, method, rng, seconds, budget, retime, velocity_scaling, acceleration_scaling,
                     result, options)
    result.info["compile_time"] = compile_seconds() - compiled_before
    return result


def _search(problem, function, method, rng, seconds, budget, retime, velocity_scaling, acceleration_scaling,
            result, options) -> MotionResult:
    """solve_motion after its checks and loading: the goal, the planning and the verification."""
    wall, cpu = time.perf_counter(), time.process_time()
    deadline = None if seconds is None else wall + seconds
    result.message = problem.blocked_now()
    if result.message:
        return result
    scaling = dict(velocity_scaling=velocity_scaling, acceleration_scaling=acceleration_scaling)
    if reaches_goal(problem, problem.q_start)[0] is not None:  # nothing to plan: stay
        return verify_motion(problem, problem.q_start[None], method, result, retime=retime, **scaling)
    try:
        goals = goal_configurations(problem, deadline=deadline)
    except InvalidMotionProblem as exc:
        if deadline is None or time.perf_counter() < deadline:
            raise
        result.message, result.goal_time = str(exc), time.perf_counter() - wall
        return result
    result.goal_time = time.perf_counter() - wall
    result.message = problem.blocked_now(goals)
    if result.message:
        return result
    goals = goals[problem.is_free(goals)]  # those an obstacle added since has not blocked
    start = time.perf_counter()
    prepared = float(result.info["prepare_time"])
    path, info = function(problem, goals, rng, deadline, budget, **options)
    result.planning_time, result.cpu_time = time.perf_counter() - start, time.process_time() - cpu
    result.info.update(info or {})
    # a plan that prepared for itself (called without solve_motion's prepare) reports that time too
    result.info["prepare_time"] = prepared + (float(info["prepare_time"]) if info and "prepare_time" in info else 0.0)
    if path is None:
        result.message = result.info.pop("message", "no path found")
        return result
    return verify_motion(problem, path, method, result, retime=retime, **scaling)
