"""OMPL as an optional peer (the ``peers`` extra): skipped where ``ompl`` is not installed,
except the check that nothing is registered then."""

import subprocess
import sys

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.planning import MotionProblem, available_motion_methods, solve_motion
from drake_mh.scene import Scene, Sphere
from references import FreshDrake, dense_path

PANDA = drake_mh.load_robot("panda")


@pytest.fixture(scope="module")
def ompl():
    """The optional peer, by name (skips the tests that take it where it is not installed)."""
    return pytest.importorskip("ompl", reason="OMPL is an optional peer: pip install ompl (the peers extra)")


def ball_problem(goal=None):
    scene = Scene(PANDA)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    if goal is None:
        goal = PANDA.home.copy()
        goal[0] += 1.0
    return MotionProblem(PANDA, scene, PANDA.home, goal)


def wall_problem():
    """The straight line from home to joint 1 + 1.5 rad runs through a ball."""
    scene = Scene(PANDA)
    middle = PANDA.home.copy()
    middle[0] += 0.75
    scene.add("ball", Sphere(0.08), PANDA.fk(middle)[:3, 3])
    goal = PANDA.home.copy()
    goal[0] += 1.5
    return MotionProblem(PANDA, scene, PANDA.home, goal)


def test_nothing_is_registered_without_ompl():
    code = ("import sys; sys.modules['ompl'] = None\n"  # makes `import ompl` raise ImportError
            "from drake_mh.planning import available_motion_methods\n"
            "from drake_mh.planning.ompl_peer import OMPL_AVAILABLE\n"
            "names = [m for m in available_motion_methods() if m.startswith('ompl')]\n"
            "assert not OMPL_AVAILABLE and not names, names\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]


@pytest.mark.parametrize("method", ["ompl_rrtconnect", "ompl_bitstar"])
def test_plans_around_an_obstacle_and_verifies(ompl, method):
    assert method in available_motion_methods()
    problem = wall_problem()
    assert not solve_motion(problem, "straight").success
    result = solve_motion(problem, method, timeout=10, optimize_time=0.2)
    assert result.success, result.message
    assert result.info["exact"] and result.info["motions_checked"] > 0
    # the certified piecewise-linear motion, sampled at 5 mrad of its fastest joint, never comes
    # closer than its certified clearance by Drake's own query on a fresh plant (a ball: Drake's
    # closed form), nor the retimed trajectory, sampled at 2,000 instants, closer than asked
    drake = FreshDrake(PANDA, problem.scene)
    assert drake.min_distances(dense_path(result.path, 0.005)).min() >= result.info["certificate"].min_clearance - 1e-9
    t = np.linspace(0, result.duration, 2000)
    assert drake.min_distances(result.trajectory.position(t)).min() >= problem.clearance


def test_same_seed_same_path(ompl):
    problem = wall_problem()
    first = solve_motion(problem, "ompl_rrtconnect", seed=3, timeout=10)
    again = solve_motion(problem, "ompl_rrtconnect", seed=3, timeout=10)
    other = solve_motion(problem, "ompl_rrtconnect", seed=4, timeout=10)
    assert first.success and again.success and other.success
    assert np.array_equal(first.path, again.path)
    assert first.info["seed"] != other.info["seed"]


def test_several_goals_and_sampled_motions(ompl):
    goals = np.stack([PANDA.home, PANDA.home]) + np.array([[1.0] + [0] * 6, [-1.0] + [0] * 6])
    problem = ball_problem(goals)
    result = solve_motion(problem, "ompl_rrtconnect", timeout=10, motion="sampled")
    assert result.success, result.message
    assert result.info["motion"] == "sampled" and 0 < result.info["resolution"] < 0.01
    assert result.goal_index in (0, 1)


def test_blocked_goal_times_out_honestly(ompl):
    robot = drake_mh.load_robot("planar2r")
    scene = Scene(robot)
    scene.add("up", Sphere(0.05), [0.0, 0.0, 0.16])  # the first link cannot turn past either ball
    scene.add("down", Sphere(0.05), [0.0, 0.0, -0.16])
    problem = MotionProblem(robot, scene, np.zeros(2), np.array([3.0, 0.0]))
    for method in ("ompl_rrtconnect", "ompl_bitstar"):
        result = solve_motion(problem, method, timeout=0.3)
        assert not result.success and result.path is None and "timeout" in result.message
        assert result.cpu_time < 40 * 0.3  # a bound on the work; the overrun: studies/timeout_overrun.py


def test_unknown_option(ompl):
    with pytest.raises(InvalidArgument, match="unknown OMPL option"):
        solve_motion(ball_problem(), "ompl_rrtconnect", range=0.1)
    with pytest.raises(InvalidArgument, match="motion"):
        solve_motion(ball_problem(), "ompl_rrtconnect", motion="exact")


def test_certified_motion_validator_remembers_and_refuses_past_the_deadline(ompl):
    """Past the deadline no motion is checked (OMPL looks at its clock only between rounds);
    motions certified before are remembered, both ways (the simplification re-asks them)."""
    import ompl.base as ob

    from drake_mh.planning.ompl_peer.planners import _CertifiedMotion, _state

    problem = ball_problem()
    space = ob.RealVectorStateSpace(PANDA.nq)
    bounds = ob.RealVectorBounds(PANDA.nq)
    for j in range(PANDA.nq):
        bounds.setLow(j, float(PANDA.lower[j]))
        bounds.setHigh(j, float(PANDA.upper[j]))
    space.setBounds(bounds)
    validator = _CertifiedMotion(ob.SpaceInformation(space), problem)
    q_a, q_b, q_c = PANDA.home, PANDA.home + 0.05, PANDA.home - 0.05
    a, b, c = (_state(space, q) for q in (q_a, q_b, q_c))
    assert validator.checkMotion(a, b) and validator.calls == 1
    assert validator.checkMotion(b, a) and validator.calls == 1  # remembered, both ways
    assert validator.all_certified(np.stack([q_a, q_b, q_a])) and not validator.all_certified(np.stack([q_a, q_c]))
    validator.end = 0.0  # the deadline has passed
    assert not validator.checkMotion(a, c) and validator.refused == 1 and validator.calls == 1
    assert validator.checkMotion(a, b)  # what was certified stays certified
