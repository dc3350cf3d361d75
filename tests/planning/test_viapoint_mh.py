"""mh_<optimizer>: via-point trajectory optimization as a motion planner."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.planning import MotionProblem, available_motion_methods, solve_motion, verify_motion
from drake_mh.planning.viapoint_mh import ViaPointMotion, ViaPointMotionConfig, resample_via, rest_to_rest_time
from drake_mh.scene import Scene, Sphere
from references import dense_path

PANDA = drake_mh.load_robot("panda")


def ball_scene():
    scene = Scene(PANDA)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    return scene


def easy_problem():
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.0
    return MotionProblem(PANDA, ball_scene(), PANDA.home, q_goal)


def blocked_problem(clearance=0.0):
    """test_core's wall: a ball on the middle of the straight line (joint 1 turns 1.5 rad)."""
    scene = Scene(PANDA)
    q_goal = PANDA.home.copy()
    q_goal[0] += 1.5
    middle = PANDA.home.copy()
    middle[0] += 0.75
    scene.add("wall", Sphere(0.08), PANDA.fk(middle)[:3, 3])
    return MotionProblem(PANDA, scene, PANDA.home, q_goal, clearance=clearance)


def exact_clearance_along(problem, path, max_step=0.005):
    """Smallest exact distance (Scene's, tested against Drake in tests/scene/test_exact.py; the
    planner decides with certified sphere-model checks) along the piecewise-linear motion, sampled
    so that no joint moves more than ``max_step`` [rad] between samples."""
    return float(problem.scene.exact_min_distance(dense_path(path, max_step)).min())


def test_every_optimizer_is_a_method():
    methods = available_motion_methods()
    for name in drake_mh.optim.available_methods():
        assert f"mh_{name}" in methods


def test_easy_problem_succeeds_and_verifies():
    problem = easy_problem()
    result = solve_motion(problem, "mh_pso", seed=0, budget=1500)
    assert result.success, result.message
    assert result.info["certified_by_planner"] and result.info["nfe"] <= 1500
    assert "prepare_time" in result.info  # kernels compiled before the clock (planner.prepare)
    again = verify_motion(problem, result.path, "again", retime=False)
    assert again.success and np.array_equal(result.path[0], problem.q_start)
    assert result.trajectory is not None and result.duration > 0
    assert exact_clearance_along(problem, result.path) >= result.min_clearance - 1e-9 >= 0.0


def test_blocked_straight_line_gets_a_detour():
    """Measured: 5/5 seeds with pso at 1,500 evaluations (straight line: 0/1)."""
    problem = blocked_problem()
    assert not solve_motion(problem, "straight").success
    wins = 0
    for seed in range(5):
        result = solve_motion(problem, "mh_pso", seed=seed, budget=1500, retime=False)
        if result.success:
            wins += 1
            assert len(result.path) >= 3  # a detour, not the blocked line
            assert exact_clearance_along(problem, result.path) >= 0.0  # dense exact sampling: no collision
    assert wins >= 3


def test_clearance_is_kept_and_checked_exactly():
    problem = blocked_problem(clearance=0.02)
    result = solve_motion(problem, "mh_abc", seed=1, budget=1500, retime=False)
    assert result.success, result.message
    assert result.min_clearance >= 0.02
    assert exact_clearance_along(problem, result.path) >= 0.02


def test_same_seed_same_path():
    problem = blocked_problem()
    a = solve_motion(problem, "mh_de", seed=3, budget=800, retime=False, stall=0)
    b = solve_motion(problem, "mh_de", seed=3, budget=800, retime=False, stall=0)
    c = solve_motion(problem, "mh_de", seed=4, budget=800, retime=False, stall=0)
    assert np.array_equal(a.path, b.path) and a.info["nfe"] == b.info["nfe"]
    assert not np.array_equal(a.path, c.path)


@pytest.mark.parametrize("method", ["mh_pso", "mh_cmaes", "mh_ga"])
def test_budget_counts_every_evaluation(method, monkeypatch):
    """Main run and repair together never evaluate more individuals than the budget."""
    counted = []
    original = ViaPointMotion.terms

    def counting(self, X):
        counted.append(len(np.atleast_2d(X)))
        return original(self, X)

    monkeypatch.setattr(ViaPointMotion, "terms", counting)
    problem = blocked_problem()
    result = solve_motion(problem, method, seed=0, budget=300, retime=False, stall=0, repair_fraction=0.5)
    assert sum(counted) <= 300
    assert result.info["nfe"] == sum(counted)


def test_deadline_stops_the_run():
    """The deadline ends a run whose budget would last minutes, and the run says so. Not timed
    (studies/timeout_overrun.py measures the overrun): the planning CPU time bounds the work, 40
    times the timeout."""
    result = solve_motion(blocked_problem(), "mh_pso", seed=0, budget=10 ** 6, timeout=0.3, retime=False)
    assert result.info["stop"] == "deadline" and result.info["nfe"] < 10 ** 6
    assert result.cpu_time < 40 * 0.3


def test_deadline_cuts_a_long_generation():
    """mh_pso once overran a 10 s timeout by a generation (1.3 s on the meshed Panda). Here one
    generation of 2,000 individuals x 769 samples takes over a second on the capsule Panda; the
    deadline is checked between chunks of it (the count of evaluations shows the cut), and what
    was evaluated is told and kept. How promptly: studies/timeout_overrun.py."""
    problem = blocked_problem()
    solve_motion(problem, "mh_pso", seed=0, budget=50, retime=False)  # compiled outside the timing
    result = solve_motion(problem, "mh_pso", seed=0, budget=10 ** 6, timeout=0.3, retime=False,
                          pop_size=2000, samples=256)
    assert result.info["stop"] == "deadline" and result.info["generations"] == 1
    assert 0 < result.info["nfe"] < 2000  # the generation was cut
    assert result.path is not None  # the best evaluated individual, for the verification to judge


@pytest.mark.parametrize("method", [m for m in available_motion_methods() if m.startswith("mh_")])
def test_every_optimizer_stops_inside_a_generation(method):
    """A generation cut by the deadline is told as it is: every optimizer takes it."""
    result = solve_motion(blocked_problem(), method, seed=0, budget=10 ** 6, timeout=0.05, retime=False,
                          pop_size=600, samples=64)
    assert result.info["stop"] == "deadline" and result.path is not None
    assert result.info["nfe"] < 10 ** 6 and result.cpu_time < 40 * 0.05


def test_zero_penalty_means_certified():
    """Π = 0 (no margin) implies the polyline certifies: the penalty's interval bound is the
    certificate's, so a thin obstacle between two samples cannot hide."""
    problem = blocked_problem()
    scene = problem.scene
    config = ViaPointMotionConfig(n_via=2, margin=0.0, samples=16)
    objective = ViaPointMotion(PANDA, scene, problem.q_start, problem.goal_configurations, 0.0, 0.0, config)
    rng = np.random.default_rng(0)
    centre = 0.5 * (problem.q_start + problem.goal_configurations[0])
    X = np.clip(np.tile(centre, 2) + rng.normal(0, 0.6, (300, objective.dimension)),
                objective.bounds[:, 0], objective.bounds[:, 1])
    terms = objective.terms(X)
    free = np.flatnonzero(terms["penalty"] == 0)
    assert 10 < len(free) < 300  # both kinds present
    for i in free:
        assert scene.certify_path(objective.path(X[i])).certified


def test_polynomial_mode_returns_dense_samples():
    problem = easy_problem()
    result = solve_motion(problem, "mh_pso", seed=0, budget=600, trajectory="polynomial", n_via=1, samples=12,
                          retime=False)
    assert result.success, result.message
    assert len(result.path) == 2 * 12 + 1
    assert np.array_equal(result.path[0], problem.q_start)
    assert np.array_equal(result.path[-1], problem.goal_configurations[0])
    assert {"f_ot", "t_T", "f_q", "f_c"} <= set(result.info["best"])


def test_several_goals_pick_one():
    q_a = PANDA.home.copy()
    q_a[0] += 1.0
    q_b = PANDA.home.copy()
    q_b[0] -= 0.4
    problem = MotionProblem(PANDA, ball_scene(), PANDA.home, np.stack([q_a, q_b]))
    result = solve_motion(problem, "mh_pso", seed=0, budget=800, retime=False)
    assert result.success
    assert min(np.max(np.abs(result.path[-1] - g)) for g in problem.goal_configurations) == 0.0


def test_warm_start_from_a_registered_method():
    problem = easy_problem()
    result = solve_motion(problem, "mh_pso", seed=0, budget=600, warm_start="straight", retime=False)
    assert result.success and result.info["warm_start"]["found"]
    with pytest.raises(InvalidArgument, match="warm_start: unknown motion planning method"):
        solve_motion(problem, "mh_pso", warm_start="no_such_planner")


def test_warm_start_from_rrt_connect():
    problem = blocked_problem()
    result = solve_motion(problem, "mh_pso", seed=0, budget=600, warm_start="rrt_connect", retime=False)
    assert result.info["warm_start"]["method"] == "rrt_connect"
    assert result.success


def test_options_are_checked():
    problem = easy_problem()
    with pytest.raises(InvalidArgument):
        solve_motion(problem, "mh_pso", n_via=0)
    with pytest.raises(InvalidArgument):
        solve_motion(problem, "mh_pso", trajectory="spline")
    with pytest.raises(InvalidArgument, match=r"unknown option.*no_such_option.*via-point fields.*n_via.*w_start"):
        solve_motion(problem, "mh_pso", no_such_option=1)


def test_resample_via_keeps_a_short_polyline():
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    via = resample_via(path, 3)
    assert via.shape == (3, 2)
    full = np.vstack([path[0], via, path[-1]])
    # every via point lies on the original polyline
    for v in via:
        off = [abs((b - a)[0] * (v - a)[1] - (b - a)[1] * (v - a)[0]) for a, b in zip(path[:-1], path[1:])]
        assert min(off) < 1e-12
    assert np.isclose(np.sum(np.linalg.norm(np.diff(full, axis=0), axis=1)), 2.0)
    long = np.stack([np.linspace(0, 1, 10), np.zeros(10)], axis=1)
    assert np.allclose(resample_via(long, 1), [[0.5, 0.0]])


def test_rest_to_rest_time():
    t = rest_to_rest_time(np.array([0.0, 0.1, 10.0]), np.array([1.0, 1.0, 1.0]), np.array([2.0, 2.0, 2.0]))
    assert t[0] == 0.0
    assert np.isclose(t[1], 2 * np.sqrt(0.1 / 2.0))  # triangle
    assert np.isclose(t[2], 10.0 + 0.5)  # trapezoid: d / v + v / a


@pytest.mark.slow
def test_table_and_shelf_problems():
    """The study's Panda problems (studies/viapoint_mh.py): pso solves most of them."""
    from drake_mh.planning.viapoint_mh.scenes import problems

    wins = total = 0
    for kind in ("table", "shelf"):
        for problem in problems(PANDA, kind):
            result = solve_motion(problem, "mh_pso", seed=0, budget=4000, retime=False)
            total += 1
            if result.success:
                wins += 1
                assert exact_clearance_along(problem, result.path, 0.01) >= 0.0
    assert wins >= 0.8 * total


def test_repair_replans_a_blocked_segment():
    """The repair step (framework paper, Algorithm 2's idea: replace the colliding stretch by
    newly optimized points) turns the blocked straight line into a certified detour."""
    from drake_mh.planning.viapoint_mh.planner import _repair

    problem = blocked_problem()
    straight = np.stack([problem.q_start, problem.goal_configurations[0]])
    path, used, segments = _repair(problem, straight, np.array([0]), "pso", 800, np.random.default_rng(0), None,
                                   ViaPointMotionConfig(), {})
    assert segments == 1 and 0 < used <= 800 and len(path) == 3
    assert verify_motion(problem, path, "repaired", retime=False).success


def test_prepare_compiles_the_warm_start_planner(monkeypatch):
    """mh_<optimizer> with warm_start prepares that planner before the clock."""
    from drake_mh.planning import get_motion_method

    warm = get_motion_method("straight")
    calls = []
    monkeypatch.setattr(warm, "prepare", lambda problem, **options: calls.append(problem), raising=False)
    problem = easy_problem()
    result = solve_motion(problem, "mh_pso", seed=0, budget=300, warm_start="straight", retime=False)
    assert calls == [problem] and result.info["warm_start"]["found"]
    with pytest.raises(InvalidArgument, match="warm_start"):  # checked before the clock, too
        get_motion_method("mh_pso").prepare(problem, warm_start="mh_de")
