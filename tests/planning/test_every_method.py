"""Every registered motion method on one small problem: the same seed gives the same path, the
methods expected to solve it do, and a motion the verification certifies is never found in
collision by dense sampling of the exact distance.

The problem: the capsule Panda with self-collision (always-close pairs left out, as by default)
and a ball on the middle of the straight joint-space line, so that most methods have to detour.
Runs end by success or by budget, never by a timeout (``timeout=None``), so that they are
deterministic; the anytime and simplifying peers get fixed options for the same reason.
"""

import numpy as np
import pytest

import drake_mh
from drake_mh.planning import MotionProblem, available_motion_methods, solve_motion
from drake_mh.scene import Scene, Sphere
from references import dense_path

PANDA = drake_mh.load_robot("panda")

#: options that make a run end by budget or success (not by its clock)
OPTIONS = {"ompl_bitstar": {"optimize_time": 0.0}}
#: the slower ones (SNOPT, BIT*, the meshless but long optimizers) run with the slow tests
SLOW = {"drake_kto", "drake_kto_warm", "ompl_bitstar"}
FAST_MH = {"mh_pso", "mh_de", "mh_cmaes"}
#: the methods that do not solve this problem (seed 5), and the words of their message; every other
#: method must (measured: all the others succeed). The straight line runs through the ball; SNOPT's
#: answer from rrt_connect's path (kSolutionFound) comes too close to be certified.
FAILS = {"straight": "not certified", "drake_kto_warm": "not certified"}


def _params():
    out = []
    for name in sorted(available_motion_methods()):
        slow = name in SLOW or (name.startswith("mh_") and name not in FAST_MH)
        out.append(pytest.param(name, marks=pytest.mark.slow) if slow else name)
    return out


def _wall(scene):
    middle = PANDA.home.copy()
    middle[0] += 0.75
    scene.add("wall", Sphere(0.08), PANDA.fk(middle)[:3, 3])
    return scene


def wall_problem():
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.5
    return MotionProblem(PANDA, _wall(Scene(PANDA, self_collision=True)), PANDA.home, q_goal, clearance=0.002)


OBSTACLES = _wall(Scene(PANDA))  # exact distances to the obstacle only
SELF = Scene(PANDA, self_collision=True)  # exact self-distances only (the checked pairs)


@pytest.fixture(scope="module")
def problem():
    return wall_problem()


def _solve(problem, method, seed):
    budget = 400 if method.startswith("mh_") else None
    return solve_motion(problem, method, seed=seed, timeout=None, budget=budget, **OPTIONS.get(method, {}))


@pytest.mark.parametrize("method", _params())
def test_same_seed_same_path_and_dense_exact_sampling_finds_no_collision(problem, method):
    first = _solve(problem, method, seed=5)
    again = _solve(problem, method, seed=5)
    assert (first.path is None) == (again.path is None), method
    if first.path is not None:
        assert np.array_equal(first.path, again.path), f"{method}: same seed, another path"
    assert first.success == again.success
    if method in FAILS:  # refused, and said why
        assert not first.success and FAILS[method] in first.message, (method, first.message)
        return
    assert first.success, (method, first.message)
    # the piecewise-linear motion, sampled at 2 mrad of its fastest joint: the exact distances
    # (tested against Drake in tests/scene/test_exact.py; the planners decide with certified
    # sphere-model checks) never below its certified clearance
    dense = dense_path(first.path, 0.002)
    exact = OBSTACLES.exact_min_distance(dense)
    assert exact.min() >= first.info["certificate"].min_clearance - 1e-9, method
    assert exact.min() >= problem.clearance, method
    assert SELF.exact_min_distance(dense).min() >= problem.self_clearance, method
    # the executed (retimed) trajectory: never closer than the certified lower bound it reports
    Q = first.trajectory.position(np.linspace(0.0, first.duration, 2000))
    executed = OBSTACLES.exact_min_distance(Q)
    assert executed.min() >= first.min_clearance - 1e-9 and executed.min() >= problem.clearance, method
    assert SELF.exact_min_distance(Q).min() >= problem.self_clearance, method


@pytest.mark.parametrize("method", _params())
def test_a_timeout_bounds_planning(method):
    """A goal that cannot be reached (the first link cannot turn past either ball): every method
    ends by its timeout (mh_pso once overran a 10 s timeout by a 1.3 s generation on the meshed
    Panda). Not timed here (studies/timeout_overrun.py measures the overrun): the planning CPU
    time bounds the work, 40 times the timeout, which a planner that ignored its deadline would
    exceed, and which a loaded machine does not inflate."""
    robot = drake_mh.load_robot("planar2r")
    scene = Scene(robot)
    scene.add("up", Sphere(0.05), [0.0, 0.0, 0.16])
    scene.add("down", Sphere(0.05), [0.0, 0.0, -0.16])
    problem = MotionProblem(robot, scene, np.zeros(2), np.array([3.0, 0.0]))
    solve_motion(problem, method, seed=0, timeout=0.05, retime=False)  # compiled outside the timing
    timeout = 0.3
    budget = 10 ** 7 if method.startswith("mh_") else None
    result = solve_motion(problem, method, seed=0, timeout=timeout, budget=budget, retime=False)
    assert not result.success
    assert result.cpu_time < 40 * timeout, (method, result.cpu_time)
