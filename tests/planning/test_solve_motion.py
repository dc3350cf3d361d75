"""solve_motion's inputs and edges: what a user passes is checked and copied, the timeout bounds
the whole call (the goal IK included), every planner rejects an option it does not know, a start
that already reaches the goal gets a verified motion of zero duration, and a scene changed after
the problem was built fails at once, saying what is in collision."""

import time

import numpy as np
import pytest

from drake_mh.errors import InvalidArgument, InvalidMotionProblem
from drake_mh.planning import (MotionProblem, available_motion_methods, goal_configurations, solve_motion,
                               verify_motion)
from drake_mh.scene import Box, Scene, Sphere
from test_core import PANDA, ball_scene


def goal_q():
    q = PANDA.home.copy()
    q[0] += 1.0
    return q


def test_the_problem_keeps_copies_of_what_it_was_given():
    q_start, goal = PANDA.home.copy(), goal_q()
    problem = MotionProblem(PANDA, ball_scene(), q_start, goal)
    q_start[0], goal[0] = 100.0, -100.0  # outside the limits: the validated problem must not follow
    assert problem.q_start[0] == PANDA.home[0] and problem.goal_configurations[0, 0] == goal_q()[0]
    assert problem.goal[0] == goal_q()[0]
    pose = PANDA.fk(goal_q())
    posed = MotionProblem(PANDA, ball_scene(), PANDA.home, pose)
    pose[0, 3] += 1.0
    assert posed.goal_pose[0, 3] == PANDA.fk(goal_q())[0, 3]


@pytest.mark.parametrize("bad, what", [(PANDA.home + 0.5j, "real"), ([[1, 2], [3]], "numbers"), ("abc", "numbers"),
                                       (None, "shape")])
def test_complex_ragged_or_text_configurations_are_refused(bad, what):
    with pytest.raises(InvalidMotionProblem, match=f"q_start.*{what}"):
        MotionProblem(PANDA, ball_scene(), bad, goal_q())
    with pytest.raises(InvalidMotionProblem, match=f"goal.*{what}"):
        MotionProblem(PANDA, ball_scene(), PANDA.home, bad)


@pytest.mark.parametrize("method", sorted(available_motion_methods()))
def test_every_planner_rejects_an_unknown_option_and_lists_its_own(method):
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, goal_q())
    with pytest.raises(InvalidArgument, match=r"bogus.*(options are|known|it takes none|valid)") as error:
        solve_motion(problem, method, timeout=1.0, bogus=1)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("seed", ["abc", 1.5, -1, object(), True])
def test_bad_seeds_are_named(seed):
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, goal_q())
    with pytest.raises(InvalidArgument, match="seed"):
        solve_motion(problem, "straight", seed=seed)


@pytest.mark.parametrize("budget", [2 ** 63, 0, -1, 1.5, "10", True])
def test_bad_budgets_are_named(budget):
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, goal_q())
    with pytest.raises(InvalidArgument, match="budget"):
        solve_motion(problem, "rrt_connect", budget=budget)


@pytest.mark.parametrize("timeout", [pytest.param(10 ** 400, id="10**400"), float("inf"), float("nan"), 0, -1, "1", True])
def test_bad_timeouts_are_named(timeout):
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, goal_q())
    with pytest.raises(InvalidArgument, match="timeout") as error:
        solve_motion(problem, "straight", timeout=timeout)
    assert len(str(error.value)) < 200  # 10**400's 401 digits are not printed


@pytest.mark.parametrize("method", ["straight", "rrt_connect"])
def test_start_equal_to_goal_is_a_verified_motion_of_zero_duration(method):
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, PANDA.home)
    result = solve_motion(problem, method)
    assert result.success, result.message
    assert result.path.shape == (1, PANDA.nq) and np.array_equal(result.path[0], PANDA.home)
    trajectory = result.trajectory
    assert trajectory.duration == 0.0 and result.duration == 0.0 and result.path_length == 0.0
    assert np.array_equal(trajectory.position(np.array([0.0]))[0], PANDA.home)
    assert not np.any(trajectory.velocity(0.0)) and trajectory.info["certificate"].ok()
    # the bound is below Drake's exact distance at that configuration, which is the whole motion
    assert 0 < result.min_clearance <= ball_scene().exact_min_distance(PANDA.home[None])[0]
    assert "start is the goal" in result.message


def test_a_start_that_already_reaches_a_goal_pose_needs_no_goal_ik():
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, PANDA.fk(PANDA.home))
    result = solve_motion(problem, "rrt_connect")
    assert result.success and result.duration == 0.0 and result.goal_time == 0.0
    assert "_goal_cache" not in problem.__dict__


def test_an_obstacle_added_on_the_goal_or_start_afterwards_fails_at_once_saying_so():
    scene = ball_scene()
    problem = MotionProblem(PANDA, scene, PANDA.home, goal_q())
    scene.add("on_goal", Sphere(0.1), PANDA.fk(goal_q())[:3, 3])
    start = time.perf_counter()
    result = solve_motion(problem, "rrt_connect", timeout=30.0)
    assert not result.success and "every goal configuration" in result.message and "now in collision" in result.message
    assert result.planning_time == 0.0
    assert time.perf_counter() - start < 10.0  # not the 30 s timeout (a wide margin on a loaded machine)
    scene.remove("on_goal")
    scene.add("on_start", Sphere(0.1), PANDA.fk(PANDA.home)[:3, 3])
    result = solve_motion(problem, "rrt_connect", timeout=30.0)
    assert not result.success and "q_start is now in collision" in result.message


def test_a_blocked_goal_among_several_leaves_the_others():
    scene = ball_scene()
    other = goal_q()
    other[0] -= 2.0
    problem = MotionProblem(PANDA, scene, PANDA.home, np.stack([goal_q(), other]))
    scene.add("on_goal", Sphere(0.1), PANDA.fk(goal_q())[:3, 3])
    result = solve_motion(problem, "straight")
    assert result.success, result.message
    assert np.array_equal(result.path[-1], other) and result.goal_index == 1


def test_the_timeout_bounds_the_goal_ik_of_an_unreachable_pose():
    """A goal pose inside a box: every IK answer collides. Before, 12 IK seeds of 5 s each ran
    outside a 0.5 s timeout (60 s) before the InvalidMotionProblem."""
    scene = Scene(PANDA)
    scene.add("box", Box((0.3, 0.3, 0.3)), [0.5, 0.0, 0.4])
    X_WG = np.eye(4)
    X_WG[:3, 3] = [0.5, 0.0, 0.4]
    problem = MotionProblem(PANDA, scene, PANDA.home, X_WG)
    solve_motion(problem, "straight", timeout=0.05)  # loads the goal IK's kernels (not counted in the timeout)
    start = time.perf_counter()
    result = solve_motion(problem, "rrt_connect", timeout=0.5)
    assert not result.success and "within the timeout" in result.message and "IK" in result.message
    assert 0.5 <= result.goal_time and result.planning_time == 0.0
    assert time.perf_counter() - start < 10.0  # not 60 s (a wide margin on a loaded machine)
    assert "_goal_cache" not in problem.__dict__  # an answer cut by the deadline is not kept


def test_goal_ik_answers_are_recomputed_after_the_obstacles_change():
    scene = ball_scene()
    problem = MotionProblem(PANDA, scene, PANDA.home, PANDA.fk(goal_q()))
    first = goal_configurations(problem)
    assert goal_configurations(problem) is first  # kept while the obstacles stay
    scene.move("ball", position=[0.5, 0.0, 0.45])
    again = goal_configurations(problem)
    assert again is not first and np.all(problem.is_free(again))


@pytest.mark.parametrize("path", [[[0.0] * 7, [1.0] * 3], "abc", np.zeros((2, 7)) + 0.5j])
def test_verify_motion_names_a_path_that_is_not_numbers(path):
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, goal_q())
    with pytest.raises(InvalidArgument, match="path must be an array of numbers"):
        verify_motion(problem, path, "x")
    with pytest.raises(InvalidArgument, match="MotionProblem"):
        verify_motion("problem", [PANDA.home], "x")
