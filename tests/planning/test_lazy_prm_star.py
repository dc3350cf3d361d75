"""lazy_prm_star: every returned motion verified and clear under Drake's exact distance, never
longer than its warm start, shorter with more samples (the same seed's search continued), bounded
by its budget and deadline; bad options rejected."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.planning import MotionProblem, solve_motion
from drake_mh.planning.lazy_prm_star import prepare
from drake_mh.planning.rrt_connect import certify_motions
from drake_mh.scene import Box, Scene
from references import dense_path

PANDA = drake_mh.load_robot("panda")
READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])  # MotionBenchMaker's start


def shelf_scene() -> Scene:
    """A board with a back wall above a table: goals under the board (a detour around its edge)."""
    scene = Scene(PANDA)
    scene.add("table", Box((0.6, 1.0, 0.04)), [0.6, 0.0, 0.1])
    scene.add("board", Box((0.45, 1.0, 0.02)), [0.62, 0.0, 0.42])
    scene.add("back", Box((0.02, 1.0, 0.34)), [0.86, 0.0, 0.27])
    return scene


def goals_under_board(scene, count, seed=0):
    """Free goals under the board whose straight motion from READY is blocked."""
    Q = PANDA.random_configurations(100_000, rng=np.random.default_rng(seed))
    p = PANDA.batch.fk(Q)[:, :3, 3]
    Q = Q[np.all((p >= [0.5, -0.3, 0.2]) & (p <= [0.75, 0.3, 0.32]), axis=1)]
    Q = Q[scene.collision_free(Q, 0.01)][:50]
    return Q[~certify_motions(scene, np.repeat(READY[None], len(Q), axis=0), Q, 0.005)][:count]


@pytest.fixture(scope="module")
def problems():
    scene = shelf_scene()
    prepare(MotionProblem(PANDA, scene, READY, READY))
    return [MotionProblem(PANDA, scene, READY, g, clearance=0.005) for g in goals_under_board(scene, 3)]


def _dense_exact(scene, path, max_step=0.005):
    """The scene's exact distance (tested against Drake in tests/scene/test_exact.py) along the
    motion, sampled at ``max_step`` [rad] of its fastest joint."""
    return scene.exact_min_distance(dense_path(path, max_step))


def test_paths_verified_clear_and_never_longer_than_the_warm_start(problems):
    shorter = 0
    for k, problem in enumerate(problems):
        result = solve_motion(problem, "lazy_prm_star", seed=k, timeout=None, budget=400, retime=False)
        assert result.success, result.message
        assert _dense_exact(problem.scene, result.path).min() >= problem.clearance
        info = result.info
        assert result.path_length <= info["warm_start_length"] + 1e-9
        shorter += result.path_length < info["warm_start_length"] - 1e-6
        assert info["samples"] == 400 and 0 < info["free_samples"] <= 400
        assert info["batches"] == 4 and info["searches"] >= 1 and info["graph_nodes"] >= 2
        assert 0 < info["t_first"] <= info["warm_start_time"] + info["t_search"] + 1e-9
    assert shorter >= 1  # the search improves on rrt_connect's path somewhere


def test_more_samples_continue_the_same_search(problems):
    """A run with a larger budget passes through the smaller run's state (same seed, same
    batches): its path is never longer, and it shortens somewhere (the anytime behaviour that
    PRM*'s asymptotic optimality promises)."""
    gains = []
    for problem in problems[:2]:
        for seed in (0, 1):
            few = solve_motion(problem, "lazy_prm_star", seed=seed, timeout=None, budget=200, retime=False)
            many = solve_motion(problem, "lazy_prm_star", seed=seed, timeout=None, budget=1500, retime=False)
            assert few.success and many.success
            assert many.path_length <= few.path_length + 1e-9
            assert many.info["improvements"] >= few.info["improvements"]
            gains.append(few.path_length - many.path_length)
    assert max(gains) > 1e-3, gains


def test_several_goals_any_one_reached(problems):
    """Three goal configurations: the informed set of each goal that a shorter path could still
    reach; the path ends on the goal that ``info["goal"]`` names."""
    scene = problems[0].scene
    goals = goals_under_board(scene, 3, seed=1)
    assert len(goals) == 3
    problem = MotionProblem(PANDA, scene, READY, goals, clearance=0.005)
    result = solve_motion(problem, "lazy_prm_star", seed=2, timeout=None, budget=600, retime=False)
    assert result.success, result.message
    assert np.array_equal(result.path[-1], problem.goal_configurations[result.info["goal"]])
    assert np.array_equal(result.path[0], READY)
    assert result.path_length <= result.info["warm_start_length"] + 1e-9
    assert _dense_exact(scene, result.path).min() >= problem.clearance


def test_cold_start_finds_its_own_path(problems):
    problem = problems[0]
    result = solve_motion(problem, "lazy_prm_star", seed=3, timeout=None, budget=1500, retime=False,
                          warm_start=False)
    assert result.success, result.message
    assert np.isnan(result.info["warm_start_length"]) and result.info["improvements"] >= 1
    assert _dense_exact(problem.scene, result.path).min() >= problem.clearance


def test_budget_and_deadline_end_the_search(problems):
    problem = problems[0]
    # one sample and no warm start: no path (the straight motion is blocked), and the message says why
    failed = solve_motion(problem, "lazy_prm_star", seed=0, timeout=None, budget=1, retime=False, warm_start=False)
    assert not failed.success and failed.path is None
    assert "budget" in failed.message and "1 samples" in failed.message
    # a deadline long before the budget: the warm start's path (or better); the work bounded by
    # the planning CPU time, 40 times the timeout (the overrun: studies/timeout_overrun.py)
    timed = solve_motion(problem, "lazy_prm_star", seed=0, timeout=0.05, budget=10 ** 7, retime=False)
    assert timed.success and timed.info["samples"] < 10 ** 7
    assert timed.cpu_time < 40 * 0.05


def test_the_warm_start_obeys_the_budget_without_a_deadline():
    """No path exists: ``q1`` must pass 30° to go from -57° to 143°, where the shoulder's housing
    (the joint-2 axis, q1 + 90°) meets a post at 120°. With ``budget=100`` and no timeout the warm
    start used to grow rrt_connect's trees to 200,000 nodes (56-100 s); it adds 100 at most."""
    scene = Scene(PANDA)
    phi = np.deg2rad(120.0)
    scene.add("post", Box((0.03, 0.03, 0.12)), [0.14 * np.cos(phi), 0.14 * np.sin(phi), 0.333])
    q_start, q_goal = PANDA.home.copy(), PANDA.home.copy()
    q_start[0], q_goal[0] = -1.0, 2.5
    crossing = PANDA.random_configurations(2000, rng=0)
    crossing[:, 0] = np.deg2rad(30.0)
    assert not np.any(scene.collision_free(crossing))  # no free configuration where q1 must pass
    result = solve_motion(MotionProblem(PANDA, scene, q_start, q_goal), "lazy_prm_star", seed=0, timeout=None,
                          budget=100, retime=False)
    assert not result.success and result.path is None
    assert "the warm start found none (no path: budget reached after 100 tree nodes" in result.message
    assert result.info["samples"] == 100


@pytest.mark.parametrize("options", [{"batch": 0}, {"k_scale": -1.0}, {"warm_start": "yes"}, {"lanes": 1.5},
                                     {"shortcut_min_gain": 1.0}, {"sample_count": 5}])
def test_bad_options_are_rejected(problems, options):
    with pytest.raises(InvalidArgument):
        solve_motion(problems[0], "lazy_prm_star", seed=0, timeout=None, budget=10, **options)
