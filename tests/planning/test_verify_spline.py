"""The executed clearance of toppra's trajectories from their geometric spline, certified before
any timing: checked against dense sampling of the motion on a fresh Drake plant."""

import numpy as np
import pytest
from scipy.interpolate import PPoly

import drake_mh
from drake_mh.planning import MotionProblem, solve_motion, verify, verify_motion
from drake_mh.scene import Scene, Sphere
from drake_mh.trajectories import Trajectory
from drake_mh.trajectories.paths import joint_path
from tests.references import FreshDrake

PANDA = drake_mh.load_robot("panda")


def _wall_problem():
    """A ball on the straight line from home to a goal 1.5 rad away in joint 1."""
    scene = Scene(PANDA)
    middle, goal = PANDA.home.copy(), PANDA.home.copy()
    middle[0] += 0.75
    goal[0] += 1.5
    scene.add("wall", Sphere(0.08), PANDA.fk(middle)[:3, 3])
    return MotionProblem(PANDA, scene, PANDA.home, goal)


def _corner():
    """A corner (joint 1, then joint 2) whose spline cuts it, and a small ball the straight
    segments pass but the spline hits (found by a search, checked in the tests)."""
    A = PANDA.home.copy()
    B = A.copy()
    B[0] += 1.2
    C = B.copy()
    C[1] += 0.6
    scene = Scene(PANDA)
    scene.add("ball", Sphere(0.03), [0.242, 0.401, 0.919])
    return MotionProblem(PANDA, scene, A, C), np.array([A, B, C])


@pytest.mark.slow
def test_spline_bound_is_below_dense_drake_distances_along_the_spline():
    problem = _wall_problem()
    result = solve_motion(problem, "rrt_connect", seed=1, retime=False)
    assert result.success and len(result.path) >= 3, result.message
    spline, _ = joint_path(result.path, PANDA)
    bound, why = verify.spline_clearance(problem, spline)
    assert why == "" and problem.clearance <= bound < np.inf
    s = np.linspace(spline.x[0], spline.x[-1], 1500)
    exact = FreshDrake(PANDA, problem.scene).min_distances(spline(s))
    assert exact.min() >= bound - 1e-9
    assert bound >= exact.min() - 0.05  # a bound of the same motion, not a trivial one


def test_a_spline_that_leaves_the_clear_segments_is_refused_before_any_timing(monkeypatch):
    import drake_mh.trajectories as trajectories

    problem, W = _corner()
    assert problem.scene.certify_path(W).certified  # the straight segments are clear
    spline, _ = joint_path(W, PANDA)
    s = np.linspace(spline.x[0], spline.x[-1], 2001)
    assert not np.all(problem.scene.collision_free(spline(s)))  # the spline is not
    bound, why = verify.spline_clearance(problem, spline)
    assert np.isnan(bound) and "spline" in why and "closer than the clearance" in why

    called, retime = [], trajectories.retime
    monkeypatch.setattr(trajectories, "retime", lambda W, robot, method, **kw: called.append(method)
                        or retime(W, robot, method, **kw))
    result = verify_motion(problem, W, "given")
    assert result.success and result.trajectory.method == "ruckig", result.message
    assert called == ["ruckig"]  # toppra never solved a spline it could not keep
    only = verify_motion(problem, W, "given", retime="toppra")
    assert not only.success and "toppra: the spline through the waypoints" in only.message


@pytest.mark.slow
def test_toppra_trajectory_takes_its_spline_certificate_and_dense_drake_agrees():
    problem = _wall_problem()
    result = solve_motion(problem, "rrt_connect", seed=1)
    assert result.success and result.trajectory.method == "toppra", result.message
    trajectory = result.trajectory
    spline, _ = joint_path(result.path[np.r_[True, np.any(np.diff(result.path, axis=0) != 0, axis=1)]], PANDA)
    step = verify.timed_on_spline(trajectory, spline)
    assert step is not None and np.max(step) <= 1e-6
    bound, _ = verify.spline_clearance(problem, spline)
    assert result.min_clearance <= bound
    t = np.linspace(0.0, result.duration, 1500)
    exact = FreshDrake(PANDA, problem.scene).min_distances(trajectory.position(t))
    assert exact.min() >= result.min_clearance - 1e-9


def test_only_a_time_law_inside_the_splines_domain_keeps_its_certificate():
    W = np.array([PANDA.home, PANDA.home + 0.3, PANDA.home + np.r_[0.5, 0.1, 0.0, -0.2, 0.0, 0.4, 0.0]])
    W = np.clip(W, PANDA.lower, PANDA.upper)
    spline, _ = joint_path(W, PANDA)
    end = spline.x[-1]
    timing = PPoly(np.array([[end / 4, end / 4], [0.0, end / 2], [0.0, end / 4]]), [0.0, 1.0, 2.0])
    t = np.linspace(0.0, 2.0, 4001)
    assert abs(timing(2.0) - end) < 1e-12 and np.all(np.diff(timing(t)) >= -1e-15)
    lo, hi = verify._range_bounds(timing)
    assert lo <= timing(t).min() + 1e-12 and hi >= timing(t).max() - 1e-12  # a bound: dense samples inside
    assert hi - lo <= end * (1 + 1e-9)
    step = verify.timed_on_spline(Trajectory(spline, timing), spline)
    assert step is not None and np.max(step) <= 1e-9
    over = PPoly(timing.c * 1.001, timing.x)  # runs past the spline's end
    assert verify.timed_on_spline(Trajectory(spline, over), spline) is None
    other, _ = joint_path(W[::-1], PANDA)
    assert verify.timed_on_spline(Trajectory(other, timing), spline) is None
    assert verify.timed_on_spline(Trajectory(spline, None), spline) is None


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_end_derivatives_are_scipys(degree):
    """The derivatives at a spline's ends that bound a time law's overshoot, from its first and
    last pieces' coefficients: scipy's values (splines of degree 1 to 3, several pieces)."""
    rng = np.random.default_rng(degree)
    x = np.r_[0.0, np.cumsum(rng.uniform(0.2, 1.5, 4))]
    spline = PPoly(rng.normal(size=(degree + 1, 4, 3)), x)
    first, last = verify.end_derivatives(spline)
    for k in (1, 2, 3):
        np.testing.assert_allclose(first[k - 1], spline(x[0], nu=k), rtol=0, atol=1e-12)
        np.testing.assert_allclose(last[k - 1], spline(x[-1], nu=k), rtol=0, atol=1e-11)
