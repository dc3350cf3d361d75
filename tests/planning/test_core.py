"""MotionProblem, solve_motion's registry and the one verification every planner gets."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument, InvalidMotionProblem, UnknownMethod
from drake_mh.planning import MotionProblem, available_motion_methods, goal_configurations, solve_motion, verify_motion
from drake_mh.scene import Scene, Sphere

PANDA = drake_mh.load_robot("panda")


def ball_scene():
    scene = Scene(PANDA)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    return scene


def test_straight_line_is_verified_and_retimed():
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.0
    result = solve_motion(MotionProblem(PANDA, ball_scene(), PANDA.home, q_goal), "straight")
    assert result.success and result.path.shape == (2, PANDA.nq)
    assert result.trajectory is not None and result.duration > 0 and result.min_clearance > 0
    t = np.linspace(0, result.duration, 200)
    exact = ball_scene().exact_min_distance(result.trajectory.position(t))  # the executed motion
    assert exact.min() >= result.min_clearance - 1e-9
    assert "straight" in available_motion_methods()


def test_empty_scene_motion_is_verified_with_infinite_clearance():
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.0
    result = solve_motion(MotionProblem(PANDA, Scene(PANDA), PANDA.home, q_goal), "straight")
    assert result.success, result.message
    assert result.trajectory is not None and result.min_clearance == np.inf


def test_jerk_is_reported_honestly_and_ruckig_limits_it():
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.0
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, q_goal)
    toppra = solve_motion(problem, "straight")  # the Panda declares jerk limits; toppra's steps break them
    assert toppra.success and toppra.jerk_limited is False and toppra.max_jerk == np.inf
    assert toppra.record()["jerk_limited"] is False
    ruckig = solve_motion(problem, "straight", retime="ruckig")
    assert ruckig.success and ruckig.jerk_limited is True and "ruckig" in ruckig.message
    assert 0 < ruckig.max_jerk <= np.max(PANDA.jerk_limits) * (1 + 1e-6)
    traj = ruckig.trajectory  # the reported jerk is a bound: no dense sample exceeds it
    dense = np.max(np.abs(traj.jerk(np.linspace(traj.start_time, traj.end_time, 20_001))))
    assert dense <= ruckig.max_jerk * (1 + 1e-9) and ruckig.max_jerk <= dense * (1 + 1e-6)  # exact: constant per piece
    with pytest.raises(InvalidArgument, match="retime"):
        solve_motion(problem, "straight", retime="spline")


def test_ruckig_motion_takes_the_path_certificate_and_dense_drake_sampling_agrees():
    problem = MotionProblem(PANDA, _wall_scene(), PANDA.home, _around_the_wall())
    result = solve_motion(problem, "rrt_connect", seed=1, retime="ruckig")
    assert result.success and len(result.path) >= 3, result.message
    path_clearance = result.info["certificate"].min_clearance
    assert result.min_clearance == path_clearance - 1e-9  # no sampling: the motion is on the path
    t = np.linspace(0, result.duration, 3000)
    exact = _wall_scene().exact_min_distance(result.trajectory.position(t))
    assert exact.min() >= result.min_clearance - 1e-9


def test_trajectory_leaving_the_path_is_still_sampled(monkeypatch):
    from drake_mh.planning import verify

    problem = MotionProblem(PANDA, _wall_scene(), PANDA.home, _around_the_wall())
    result = solve_motion(problem, "rrt_connect", seed=1, retime="ruckig")
    W = result.trajectory.info["on_path"].copy()
    W[1, 0] += 1e-3  # not the path the trajectory was built on: no shortcut
    assert not verify._on_certified_path(result.trajectory, W)
    clearance, why = verify.trajectory_clearance(problem, result.trajectory, result.info["certificate"], W)
    assert why == ""
    # a bound on the same motion as the path certificate's, each tight to REPORT_TOLERANCE (plus the
    # sampling's shift; either may be the larger where the motion nearly touches), and below Drake's
    # exact distance along it
    t = np.linspace(0, result.duration, 3000)
    exact = _wall_scene().exact_min_distance(result.trajectory.position(t))
    assert clearance <= exact.min() + 1e-9
    assert abs(clearance - result.min_clearance) <= verify.REPORT_TOLERANCE + max(verify.TRAJECTORY_SHIFTS)


def _wall_scene():
    """A ball on the straight line from home to :func:`_around_the_wall` (at its middle)."""
    scene = Scene(PANDA)
    middle = PANDA.home.copy()
    middle[0] += 0.75
    scene.add("wall", Sphere(0.08), PANDA.fk(middle)[:3, 3])
    return scene


def _around_the_wall():
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.5
    return q_goal


def test_straight_line_through_an_obstacle_fails_honestly():
    scene = Scene(PANDA)
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.5
    middle = PANDA.home.copy()
    middle[0] += 0.75
    scene.add("wall", Sphere(0.08), PANDA.fk(middle)[:3, 3])
    result = solve_motion(MotionProblem(PANDA, scene, PANDA.home, q_goal), "straight")
    assert not result.success and "not certified" in result.message and np.isnan(result.min_clearance)


def test_pose_goal_uses_collision_free_ik_once(monkeypatch):
    """A pose goal is solved by collision-free IK on the first plan only (its calls counted);
    every goal configuration reaches the pose and is clear by Drake on a fresh plant, and the
    straight motion to one of them succeeds."""
    from scipy.spatial.transform import Rotation

    import drake_mh.ik
    from references import FreshDrake

    calls = []
    solve_ik = drake_mh.ik.solve_ik
    monkeypatch.setattr(drake_mh.ik, "solve_ik", lambda *a, **k: calls.append(a) or solve_ik(*a, **k))
    q_goal = PANDA.home.copy()
    q_goal[0] += 0.6
    X_WG = PANDA.fk(q_goal)
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, X_WG)
    first = solve_motion(problem, "straight")
    solved = len(calls)
    second = solve_motion(problem, "straight", seed=3)
    assert solved >= 1 and len(calls) == solved  # the second plan reuses the answers
    assert first.success and second.success, first.message
    drake = FreshDrake(PANDA, problem.scene)
    goals = goal_configurations(problem)  # the cached answers (no new IK call: checked below)
    assert len(calls) == solved and any(np.array_equal(first.path[-1], g) for g in goals)
    for g in goals:
        X = drake.fk(g, "panda_link8")
        assert np.linalg.norm(X[:3, 3] - X_WG[:3, 3]) <= 1e-3  # IKProblem's default tolerances
        assert Rotation.from_matrix(X[:3, :3] @ X_WG[:3, :3].T).magnitude() <= 1e-2
        assert drake.min_distance(g) >= problem.clearance


def test_verification_rejects_bad_paths():
    q_goal = PANDA.home.copy()
    q_goal[0] -= 0.8
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, q_goal)
    assert not verify_motion(problem, np.stack([PANDA.home + 0.01, q_goal]), "x").success  # wrong start
    assert not verify_motion(problem, np.stack([PANDA.home, q_goal + 0.01]), "x").success  # wrong goal
    outside = np.stack([PANDA.home, PANDA.upper + 0.1, q_goal])
    assert "limits" in verify_motion(problem, outside, "x").message
    assert not verify_motion(problem, np.full((2, 3), 0.0), "x").success
    assert verify_motion(problem, None, "x").message == "no path found"


def test_problem_errors():
    scene = ball_scene()
    with pytest.raises(InvalidMotionProblem, match="q_start"):
        MotionProblem(PANDA, scene, PANDA.upper + 1.0, PANDA.home)
    with pytest.raises(InvalidMotionProblem, match="collision"):
        blocked = Scene(PANDA)
        blocked.add("on_flange", Sphere(0.1), PANDA.fk(PANDA.home)[:3, 3])
        MotionProblem(PANDA, blocked, PANDA.home, PANDA.home)
    with pytest.raises(InvalidMotionProblem, match="scene"):
        MotionProblem(PANDA, Scene(drake_mh.load_robot("panda")), PANDA.home, PANDA.home)
    with pytest.raises(InvalidMotionProblem, match="clearance"):
        MotionProblem(PANDA, scene, PANDA.home, PANDA.home, clearance=-1)
    with pytest.raises(InvalidMotionProblem, match="goal"):
        MotionProblem(PANDA, scene, PANDA.home, np.zeros(3))
    problem = MotionProblem(PANDA, scene, PANDA.home, PANDA.home)
    with pytest.raises(UnknownMethod):
        solve_motion(problem, "nope")
    with pytest.raises(InvalidArgument):
        solve_motion(problem, "straight", timeout=-1)


def test_prepare_gets_the_options_before_the_clock(request):
    """solve_motion hands the plan's options to its prepare: a prepare with **options gets them
    all, one that names some gets those, and its work is not the plan's (counted in CPU time, which
    a loaded machine does not inflate)."""
    import time

    from drake_mh.planning import prepare_motion_method, register
    from drake_mh.planning.methods import METHODS
    from drake_mh.planning.straight import plan as straight

    seen = []

    def plan(problem, goals, rng, deadline, budget, **options):
        seen.append(("plan", options))
        return straight(problem, goals, rng, deadline, budget)

    def prepare(problem, **options):
        seen.append(("prepare", options))
        start = time.process_time()
        while time.process_time() - start < 0.2:  # 0.2 s of CPU, which the plan's CPU time must not hold
            pass

    plan.prepare = prepare
    register("test_prepared", "test")(plan)
    request.addfinalizer(lambda: METHODS.remove("test_prepared"))
    q_goal = PANDA.home.copy()
    q_goal[0] += 0.5
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, q_goal)
    result = solve_motion(problem, "test_prepared", retime=False, knob=3)
    assert seen == [("prepare", {"knob": 3}), ("plan", {"knob": 3})]
    assert result.info["prepare_time"] >= 0.2 and result.cpu_time < 0.2  # 'straight' plans in about 0.1 ms

    def named(problem, knob=None):
        seen.append(("named", knob))

    plan.prepare = named
    prepare_motion_method(plan, problem, knob=4, other=5)  # `other` is not its business
    assert seen[-1] == ("named", 4)
