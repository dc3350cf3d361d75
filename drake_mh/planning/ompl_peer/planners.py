"""OMPL's RRT-Connect and BIT* on a :class:`~drake_mh.planning.MotionProblem`.

Set-up, per solve (OMPL objects are not reused between problems):

* state space: ``RealVectorStateSpace(nq)`` bounded by the joint limits;
* validity: ``problem.is_free(q)`` — :meth:`drake_mh.scene.Scene.collision_free` on one
  configuration with the problem's clearances (a per-state Python callback: OMPL cannot use
  the batched checker, which is what makes it slower than ``rrt_connect`` here);
* motions, ``motion="certified"`` (default): a Python ``MotionValidator`` whose
  ``checkMotion(a, b)`` is :meth:`~drake_mh.scene.Scene.segment_free` — the same certified
  segment check as the verification, so every edge OMPL keeps (tree, connection, shortcut) is
  certified; ``motion="sampled"``: OMPL's own ``DiscreteMotionValidator``, which checks states
  ``resolution · extent`` apart (L2 in joint space) and can miss a collision between two of
  them. Its resolution is chosen so that no sphere of the model moves more than ``max_step``
  [m] (default: the sphere model's bound, ~9.5 mm for the Panda) between checked states:
  ``step = max_step / max_c ||reach_c||₂`` (a sphere moves at most ``Σ_j reach[c, j] |Δq_j|
  <= ||reach_c||₂ ||Δq||₂``, :attr:`~drake_mh.scene.batch.CollisionModel.reach`), i.e. about
  0.04 % of the Panda's extent against OMPL's default 1 %. Either way the verification's
  certification decides, never OMPL's flags;
* the goal: one ``GoalState``, or ``GoalStates`` holding every goal configuration;
* seeding: ``ompl.util.RNG.setSeed`` before any OMPL object of the solve is created, with a
  seed drawn from the method's ``rng``: the same seed gives the same path when the run ends
  by success (OMPL logs an error the second time a process seeds, which is silenced here:
  measured, the next instances' random streams do follow the new seed);
* time: ``solve`` until the deadline (no deadline: ``time_limit``, 10 s); RRT-Connect stops
  at its first exact solution; BIT* (anytime) stops at its first solution
  (``setStopOnSolnImprovement``: BIT* hands its solution to the problem definition only when
  ``solve`` returns, so OMPL's exact-solution termination condition never fires inside it),
  then resumes, improving until ``optimize_time`` (1 s) after the start or the deadline,
  whichever comes first;
* simplification on (``simplifySolution``: vertex reduction, shortcuts, B-spline smoothing
  with our motion validator) for ``simplify_time`` (1 s) at most, within the deadline;
* past the deadline the certified motion validator refuses every motion unchecked during the
  solve and the simplification (:class:`_CertifiedMotion`), so both stop soon after it (OMPL's
  simplifier checks its own time only between whole rounds: 0.55 s and 2.2 s spent against
  0.12 s given, measured on the Panda with its hand). A simplification cut that way can end with
  OMPL "repairing" the path into segments no check accepted (it then warns that the path "may
  touch an invalid region"; silenced): the simplified path is kept only if every segment of it
  was certified by the validator (remembered), otherwise the solution before simplification
  is returned (``info["simplification"]`` says so);
* ``budget`` is not used (OMPL has no iteration budget in this API).

Only an exact solution is returned (an approximate one ends elsewhere: reported as a failure).
"""

from __future__ import annotations

import time

import numpy as np
import ompl.base as ob
import ompl.geometric as og
import ompl.util as ou

from drake_mh.errors import InvalidArgument

OMPL_VERSION = "2.0.1"
"""The OMPL wheel these planners were written and measured against."""

PLANNERS = {"rrtconnect": og.RRTConnect, "bitstar": og.BITstar}
ANYTIME = frozenset({"bitstar"})
DEFAULTS = {"motion": "certified", "max_step": None, "time_limit": 10.0, "optimize_time": 1.0, "simplify": True,
            "simplify_time": 1.0}

ou.setLogLevel(ou.LOG_WARN)


def _seed(seed: int) -> None:
    """Seed OMPL's seed generator (every RNG created after this call draws from it)."""
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)  # "Random number generation already started" after the first seed
    try:
        ou.RNG.setSeed(int(seed))
    finally:
        ou.setLogLevel(level)


def _values(state, n: int) -> np.ndarray:
    return np.array([state[i] for i in range(n)])


class _CertifiedMotion(ob.MotionValidator):
    """``checkMotion(a, b)``: the straight segment is certified free (``Scene.segment_free``).

    Past ``end`` (the deadline; ``inf`` during simplification, module docstring) every motion
    is refused without being checked: OMPL checks its termination condition only between
    iterations, and one certified segment of a meshed robot can take a tenth of a second or
    more (a 0.19 s overrun measured on the Panda with its hand); refusing is safe in the solve
    (no edge is accepted unchecked) and lets it stop at once. Motions certified free are
    remembered, so asking again (the simplification's final check of the path) costs nothing.
    """

    def __init__(self, si, problem, end: float = np.inf):
        super().__init__(si)
        self._segment_free = problem.scene.segment_free
        self._clearance, self._self_clearance = problem.clearance, problem.self_clearance
        self._n = problem.nq
        self.end = end
        self._free: set = set()  # (a, b) bytes of the motions certified free
        self.calls = 0
        self.refused = 0

    def all_certified(self, Q: np.ndarray) -> bool:
        """Whether every segment of the path ``Q (M, nq)`` was certified free by this validator."""
        return all((a.tobytes(), b.tobytes()) in self._free for a, b in zip(Q[:-1], Q[1:]))

    def checkMotion(self, a, b):  # noqa: N802 (OMPL's name)
        qa, qb = _values(a, self._n), _values(b, self._n)
        key = (qa.tobytes(), qb.tobytes())
        if key in self._free:  # certified before (the simplification's final check re-asks them all)
            return True
        if time.perf_counter() > self.end:
            self.refused += 1
            return False
        self.calls += 1
        free = bool(self._segment_free(qa, qb, self._clearance, self._self_clearance))
        if free:
            self._free.add(key)
            self._free.add(key[::-1])
        return free


def sampled_resolution(problem, space, max_step: float | None = None) -> float:
    """OMPL's state-validity checking resolution (fraction of the space's extent) at which no
    sphere moves more than ``max_step`` [m] between checked states (module docstring)."""
    scene = problem.scene
    max_step = scene.sphere_model.bound if max_step is None else float(max_step)
    if not (np.isfinite(max_step) and max_step > 0):
        raise InvalidArgument(f"max_step must be a distance > 0 [m], got {max_step!r}")
    reach = np.asarray(scene.collision_model.reach)
    step = max_step / float(np.max(np.linalg.norm(reach, axis=1)))
    return float(min(step / space.getMaximumExtent(), 1.0))


def _state(space, q):
    state = space.allocState()
    for i, value in enumerate(q):
        state[i] = float(value)
    return state


def plan_ompl(problem, goals, rng, deadline, budget, planner: str, **options):
    """Plan with OMPL's ``planner`` (a key of :data:`PLANNERS`); see the module docstring."""
    unknown = sorted(set(options) - set(DEFAULTS))
    if unknown:
        raise InvalidArgument(f"unknown OMPL option(s) {unknown}; known: {sorted(DEFAULTS)}")
    opts = {**DEFAULTS, **options}
    if opts["motion"] not in ("certified", "sampled"):
        raise InvalidArgument(f"motion must be 'certified' or 'sampled', got {opts['motion']!r}")
    start_time = time.perf_counter()
    end = start_time + float(opts["time_limit"]) if deadline is None else deadline
    n = problem.nq
    seed = int(rng.integers(1, 2**31 - 1))
    _seed(seed)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for j in range(n):
        bounds.setLow(j, float(problem.robot.lower[j]))
        bounds.setHigh(j, float(problem.robot.upper[j]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    counts = {"states": 0}
    is_free = problem.is_free

    def valid(state) -> bool:
        counts["states"] += 1
        return bool(is_free(_values(state, n)))

    setup.setStateValidityChecker(valid)
    si = setup.getSpaceInformation()
    motion = None
    if opts["motion"] == "certified":
        motion = _CertifiedMotion(si, problem, end)
        si.setMotionValidator(motion)
        resolution = None
    else:
        resolution = sampled_resolution(problem, space, opts["max_step"])
        si.setStateValidityCheckingResolution(resolution)
    start = _state(space, problem.q_start)
    if len(goals) == 1:
        setup.setStartAndGoalStates(start, _state(space, goals[0]))
    else:
        setup.setStartState(start)
        goal = ob.GoalStates(si)
        for q in goals:
            goal.addState(_state(space, q))
        setup.setGoal(goal)
    setup.setPlanner(PLANNERS[planner](si))
    info = {"ompl": OMPL_VERSION, "planner": planner, "seed": seed, "motion": opts["motion"],
            "resolution": resolution}
    remaining = end - time.perf_counter()
    if remaining <= 0:
        info["message"] = "timeout before OMPL started"
        return None, info
    planner_object = setup.getPlanner()
    solve = time.perf_counter()
    if planner in ANYTIME:  # BIT* publishes its solution when solve returns: stop at the first one, then go on
        planner_object.setStopOnSolnImprovement(True)
    status = setup.solve(ob.timedPlannerTerminationCondition(remaining))
    info["first_solution_time"] = time.perf_counter() - solve
    if planner in ANYTIME and setup.haveExactSolutionPath():
        more = min(float(opts["optimize_time"]) - (time.perf_counter() - start_time), end - time.perf_counter())
        if more > 0:
            planner_object.setStopOnSolnImprovement(False)
            status = setup.solve(ob.timedPlannerTerminationCondition(more))
    info["solve_time"] = time.perf_counter() - solve
    info["status"] = str(status)
    info["exact"] = bool(setup.haveExactSolutionPath())
    if not info["exact"]:
        info.update(states_checked=counts["states"], motions_checked=None if motion is None else motion.calls)
        timed_out = time.perf_counter() >= end
        info["message"] = f"OMPL {planner}: {'timeout' if timed_out else 'no exact solution'} ({status})"
        return None, info
    remaining = end - time.perf_counter()
    path = setup.getSolutionPath()
    Q = np.array([_values(path.getState(k), n) for k in range(path.getStateCount())])
    if opts["simplify"] and remaining > 0:
        simplify = time.perf_counter()
        level = ou.getLogLevel()
        if motion is not None:  # its final check warns about motions refused past the deadline
            ou.setLogLevel(ou.LOG_ERROR)
        try:
            setup.simplifySolution(min(float(opts["simplify_time"]), remaining))
        finally:
            ou.setLogLevel(level)
        info["simplify_time"] = time.perf_counter() - simplify
        path = setup.getSolutionPath()
        simplified = np.array([_values(path.getState(k), n) for k in range(path.getStateCount())])
        if motion is None or motion.all_certified(simplified):
            Q = simplified
        else:  # cut by the deadline, OMPL's "repair" left segments that no check accepted
            info["simplification"] = "dropped: cut by the deadline, not every segment certified"
    info.update(states_checked=counts["states"], motions_checked=None if motion is None else motion.calls,
                motions_refused_past_deadline=None if motion is None else motion.refused,
                message=f"OMPL {planner}: {status}")
    return Q, info


def plan_rrtconnect(problem, goals, rng, deadline, budget, **options):
    """``ompl_rrtconnect``: :func:`plan_ompl` with OMPL's RRT-Connect."""
    return plan_ompl(problem, goals, rng, deadline, budget, "rrtconnect", **options)


def plan_bitstar(problem, goals, rng, deadline, budget, **options):
    """``ompl_bitstar``: :func:`plan_ompl` with OMPL's BIT* (anytime: it keeps optimizing path length
    for ``optimize_time`` after its first solution)."""
    return plan_ompl(problem, goals, rng, deadline, budget, "bitstar", **options)
