"""drake_kto: Drake's KinematicTrajectoryOptimization + SNOPT, verified like every planner."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.planning import MotionProblem, available_motion_methods, solve_motion
from drake_mh.planning.drake_kto import KTOConfig, solver_name
from drake_mh.planning.drake_kto import kto as kto_module
from drake_mh.scene import Scene, Sphere
from references import FreshDrake, dense_path

PANDA = drake_mh.load_robot("panda")
PLANAR = drake_mh.load_robot("planar2r")


def ball_problem():
    scene = Scene(PANDA)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.0
    return MotionProblem(PANDA, scene, PANDA.home, q_goal)


def blocked_problem():
    """planar2r: balls above and below the shoulder stop the first link both ways round (the
    joint does not wrap), so q1 = 3 cannot be reached from q1 = 0."""
    scene = Scene(PLANAR)
    scene.add("up", Sphere(0.05), [0.0, 0.0, 0.16])
    scene.add("down", Sphere(0.05), [0.0, 0.0, -0.16])
    return MotionProblem(PLANAR, scene, np.zeros(2), np.array([3.0, 0.0]))


def test_registered_with_the_solver_flag_recorded():
    assert "drake_kto" in available_motion_methods()
    problem = ball_problem()
    result = solve_motion(problem, "drake_kto", timeout=20)
    assert result.success, result.message
    assert result.info["solver"] in ("SNOPT", "IPOPT") and result.info["solver"] == solver_name()
    assert isinstance(result.info["solver_success"], bool) and result.info["solver_status"]
    # a dense sampling of the spline, starting and ending exactly where asked
    assert result.path.shape == (KTOConfig().waypoints, PANDA.nq)
    assert np.array_equal(result.path[0], problem.q_start)
    assert np.max(np.abs(result.path[-1] - problem.goal_configurations[0])) <= 1e-9
    assert np.all(result.path >= PANDA.lower - 1e-9) and np.all(result.path <= PANDA.upper + 1e-9)
    # the certified piecewise-linear motion, sampled at 5 mrad of its fastest joint, never comes
    # closer than its certified clearance by Drake's own query on a fresh plant (a ball: Drake's
    # closed form), nor the retimed trajectory, sampled at 2,000 instants, closer than asked
    drake = FreshDrake(PANDA, problem.scene)
    dense = dense_path(result.path, 0.005)
    assert len(dense) >= 200
    assert drake.min_distances(dense).min() >= result.info["certificate"].min_clearance - 1e-9
    t = np.linspace(0, result.duration, 2000)
    assert drake.min_distances(result.trajectory.position(t)).min() >= problem.clearance


def test_program_is_cached_per_scene_and_rebuilt_when_it_changes():
    problem = ball_problem()
    first = solve_motion(problem, "drake_kto", timeout=20)
    entry = kto_module._CACHE[problem.scene]
    programs = dict(entry["programs"])
    second = solve_motion(problem, "drake_kto", seed=5, timeout=20)
    assert kto_module._CACHE[problem.scene] is entry and entry["programs"] == programs
    assert np.array_equal(first.path, second.path)  # deterministic: no randomness, same program
    problem.scene.add("far_ball", Sphere(0.05), [-0.8, -0.8, 0.2])
    solve_motion(problem, "drake_kto", timeout=20)
    assert kto_module._CACHE[problem.scene] is not entry


def test_blocked_goal_fails_honestly():
    result = solve_motion(blocked_problem(), "drake_kto", timeout=10)
    assert not result.success and result.message
    assert "solver_success" in result.info or "timeout" in result.message


def shelf_problem():
    """Between two compartments of a bookshelf (studies/planning_baselines.py's scene): SNOPT runs
    into its 1000 major iterations here (~30 s on a loaded machine)."""
    from drake_mh.scene import Box

    scene = Scene(PANDA)
    scene.add("table", Box((0.6, 1.0, 0.04)), [0.6, -0.1, 0.08])
    scene.add("back", Box((0.6, 0.02, 1.0)), [0.4, 0.8, 0.5])
    scene.add("side_a", Box((0.02, 0.35, 1.0)), [0.1, 0.625, 0.5])
    scene.add("side_b", Box((0.02, 0.35, 1.0)), [0.7, 0.625, 0.5])
    for i, z in enumerate((0.1, 0.42, 0.74, 1.0)):
        scene.add(f"board{i}", Box((0.6, 0.35, 0.02)), [0.4, 0.625, z])
    return MotionProblem(PANDA, scene, [0.0972, 0.9756, 1.5217, -1.5073, 0.2653, 3.1593, 0.3317],
                         [0.0603, 1.7535, 1.5162, -1.6875, -0.3699, 3.3293, 0.1854])


def test_timeout_stops_the_solver():
    problem = shelf_problem()
    solve_motion(problem, "drake_kto", timeout=1e-3)  # builds the program: only the solve is timed below
    result = solve_motion(problem, "drake_kto", timeout=0.3)
    assert not result.success and result.path is None and "timeout" in result.message
    assert result.info["solver_success"] is False and result.info["evaluations"] >= 1
    assert result.cpu_time < 40 * 0.3  # a bound on the work; the overrun: studies/timeout_overrun.py


def test_options_and_errors():
    problem = ball_problem()
    with pytest.raises(InvalidArgument, match="unknown drake_kto option"):
        solve_motion(problem, "drake_kto", num_knots=3)
    with pytest.raises(InvalidArgument):
        KTOConfig(num_control_points=3, spline_order=4)
    with pytest.raises(InvalidArgument):
        KTOConfig(margin=-0.1)
    with pytest.raises(InvalidArgument):
        KTOConfig(solver="gurobi")
    result = solve_motion(problem, "drake_kto", timeout=20, waypoints=20, margin=0.02)
    assert result.path.shape == (20, PANDA.nq)
    assert result.info["distance_bound"] == pytest.approx(0.02)


def test_warm_variant_follows_rrt_connect():
    assert {"rrt_connect", "drake_kto_warm"} <= set(available_motion_methods())
    result = solve_motion(ball_problem(), "drake_kto_warm", timeout=20)
    assert result.success, result.message
    assert result.info["warm_time"] <= result.planning_time and "solver_success" in result.info


def test_ipopt_also_plans():
    result = solve_motion(ball_problem(), "drake_kto", timeout=30, solver="ipopt")
    assert result.info["solver"] == "IPOPT"
    assert result.success, result.message
