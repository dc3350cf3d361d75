"""rrt_connect: every returned motion verified and clear under Drake's exact distance, seeded,
bounded by its budget and deadline, and its motion check never certifies a colliding motion."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.planning import MotionProblem, available_motion_methods, solve_motion
from drake_mh.planning.rrt_connect import certify_motions, prepare
from drake_mh.scene import Box, Cylinder, Scene, Sphere

PANDA = drake_mh.load_robot("panda")
READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])  # MotionBenchMaker's start


def table_scene(self_collision: bool = False) -> Scene:
    scene = Scene(PANDA, self_collision=self_collision)
    scene.add("table", Box((0.8, 1.4, 0.05)), [0.6, 0.0, 0.1])
    scene.add("can1", Cylinder(0.04, 0.2), [0.5, 0.2, 0.225])
    scene.add("can2", Cylinder(0.04, 0.2), [0.6, -0.15, 0.225])
    scene.add("block", Box((0.1, 0.1, 0.15)), [0.45, -0.35, 0.2])
    scene.add("ball", Sphere(0.05), [0.7, 0.05, 0.175])
    return scene


def slot_scene() -> Scene:
    """Two boards 22 cm apart and a back wall: the hand must enter the slot (a narrow passage)."""
    scene = Scene(PANDA)
    scene.add("floor", Box((0.5, 0.9, 0.02)), [0.65, 0.0, 0.4])
    scene.add("roof", Box((0.5, 0.9, 0.02)), [0.65, 0.0, 0.64])
    scene.add("back", Box((0.02, 0.9, 0.6)), [0.91, 0.0, 0.5])
    return scene


def goals_in(scene, lo, hi, count, seed=0, clearance=0.0):
    """Free configurations whose flange lies in the box [lo, hi] (batched sampling)."""
    Q = PANDA.random_configurations(100_000, rng=np.random.default_rng(seed))
    p = PANDA.batch.fk(Q)[:, :3, 3]
    Q = Q[np.all((p >= lo) & (p <= hi), axis=1)]
    return Q[scene.collision_free(Q, clearance)][:count]


def dense_exact(scene, path, max_step=0.005):
    """The scene's exact distance (tested against Drake in tests/scene/test_exact.py; the
    planner decides with its certified sphere-model checks) along the piecewise-linear motion,
    sampled so that no joint moves more than ``max_step`` [rad] between samples."""
    from references import dense_path

    return scene.exact_min_distance(dense_path(path, max_step))


@pytest.fixture(scope="module")
def table_problems():
    scene = table_scene()
    prepare(MotionProblem(PANDA, scene, READY, READY))
    goals = goals_in(scene, [0.35, -0.45, 0.15], [0.8, 0.45, 0.35], 3)
    return [MotionProblem(PANDA, scene, READY, g, clearance=c) for g, c in zip(goals, (0.0, 0.01, 0.0))]


def test_registered():
    methods = available_motion_methods()
    assert "rrt_connect" in methods and "rrt_connect_smooth" in methods


def test_paths_verify_and_dense_exact_sampling_finds_no_collision(table_problems):
    for problem in table_problems:
        for method in ("rrt_connect", "rrt_connect_smooth"):
            result = solve_motion(problem, method, seed=1, timeout=5.0, retime=False)
            assert result.success, result.message
            assert result.min_clearance >= problem.clearance
            assert np.array_equal(result.path[0], problem.q_start)
            exact = dense_exact(problem.scene, result.path)
            assert exact.min() >= problem.clearance - 1e-9, (method, exact.min())
            assert result.info["nodes"] >= 0 and result.info["motions"] >= 1


def test_same_seed_same_path(table_problems):
    problem = table_problems[0]
    first = solve_motion(problem, "rrt_connect", seed=7, retime=False)
    again = solve_motion(problem, "rrt_connect", seed=7, retime=False)
    assert first.success and np.array_equal(first.path, again.path)
    assert first.info["motions"] == again.info["motions"]
    others = [solve_motion(problem, "rrt_connect", seed=s, retime=False).path for s in (8, 9, 10)]
    assert any(p.shape != first.path.shape or not np.array_equal(p, first.path) for p in others)


def test_shortcutting_shortens(table_problems):
    problem = table_problems[0]
    raw = solve_motion(problem, "rrt_connect", seed=3, retime=False, shortcut_iterations=0)
    smooth = solve_motion(problem, "rrt_connect_smooth", seed=3, retime=False)
    assert raw.success and smooth.success
    assert smooth.path_length <= raw.path_length + 1e-9


def test_shortcut_min_gain_skips_draws_that_save_little(table_problems):
    problem = table_problems[0]
    raw = solve_motion(problem, "rrt_connect", seed=3, retime=False, shortcut_iterations=0)
    every = solve_motion(problem, "rrt_connect", seed=3, retime=False, shortcut_min_gain=0.0)
    some = solve_motion(problem, "rrt_connect", seed=3, retime=False)  # 32 draws, each checked if it saves 5 %
    none = solve_motion(problem, "rrt_connect", seed=3, retime=False, shortcut_min_gain=0.999999)
    assert raw.success and every.success and some.success and none.success
    assert none.info["shortcuts_tried"] == 0 and np.array_equal(none.path, raw.path)  # no draw saves that much
    assert 0 < some.info["shortcuts_tried"] < every.info["shortcuts_tried"]
    for result in (every, some):  # (success: verified, the whole motion certified)
        assert result.path_length < 0.99 * raw.path_length
    for gain in (-0.1, 1.0, float("nan"), True, "0.2"):
        with pytest.raises(InvalidArgument, match=r"shortcut_min_gain must be in \[0, 1\)"):
            solve_motion(problem, "rrt_connect", shortcut_min_gain=gain)


def test_narrow_passage():
    scene = slot_scene()
    goal = goals_in(scene, [0.6, -0.2, 0.41], [0.8, 0.2, 0.63], 1)[0]
    problem = MotionProblem(PANDA, scene, READY, goal)
    assert not solve_motion(problem, "straight", retime=False).success  # the straight line is blocked
    result = solve_motion(problem, "rrt_connect", seed=1, timeout=10.0, retime=False)
    assert result.success, result.message
    assert dense_exact(scene, result.path).min() >= 0.0


def test_dynamic_domain_skips_samples_beyond_failed_nodes():
    """In the slot, extensions fail and their nodes' domains shrink: samples beyond them are drawn
    again without a check. Without the domain no sample is skipped; both paths are verified."""
    scene = slot_scene()
    goal = goals_in(scene, [0.6, -0.2, 0.41], [0.8, 0.2, 0.63], 1)[0]
    problem = MotionProblem(PANDA, scene, READY, goal)
    skipped = 0
    for seed in range(3):
        domain = solve_motion(problem, "rrt_connect", seed=seed, timeout=10.0, retime=False)
        off = solve_motion(problem, "rrt_connect", seed=seed, timeout=10.0, retime=False, domain_radius=0.0)
        assert domain.success and off.success
        assert off.info["out_of_domain"] == 0
        skipped += domain.info["out_of_domain"]
        for result in (domain, off):
            assert dense_exact(scene, result.path).min() >= 0.0
    assert skipped > 0
    for radius in (-1.0, float("inf"), float("nan"), True, "4"):
        with pytest.raises(InvalidArgument, match="domain_radius must be a finite number >= 0"):
            solve_motion(problem, "rrt_connect", domain_radius=radius)


def test_options_are_validated_once_per_distinct_set():
    """``solve_motion``'s keywords build one config per distinct set (not inside every plan's
    clock), and the cache never lets an invalid value pass as an equal valid one."""
    from drake_mh.planning.rrt_connect import RRTConnectConfig

    first = RRTConnectConfig.from_options({"lanes": 1, "step": 0.5})
    assert RRTConnectConfig.from_options({"step": 0.5, "lanes": 1}) is first
    assert RRTConnectConfig.from_options({"lanes": 1, "step": 0.5, "probes": 2}) is not first
    # equal to lanes=1 as keys, but not integers
    for wrong in ({"lanes": True, "step": 0.5}, {"lanes": 1.0, "step": 0.5}, {"lanes": [1]}, {"step": float("nan")}):
        with pytest.raises(InvalidArgument, match="lanes|step"):
            RRTConnectConfig.from_options(wrong)
    smooth = RRTConnectConfig.from_options({}, shortcut_iterations=192)
    assert smooth.shortcut_iterations == 192 and RRTConnectConfig.from_options({}) is not smooth


def test_several_goals_grow_one_tree():
    scene = table_scene()
    goals = goals_in(scene, [0.35, -0.45, 0.15], [0.8, 0.45, 0.35], 4, seed=5)
    problem = MotionProblem(PANDA, scene, READY, goals)
    result = solve_motion(problem, "rrt_connect", seed=0, retime=False)
    assert result.success
    assert np.any(np.all(np.abs(goals - result.path[-1]) <= 1e-12, axis=1))


def blocked_planar(planar2r):
    """Balls on link 1's circle at ±90°: no motion from 0 to 3 rad exists (q2 cannot help)."""
    scene = Scene(planar2r)
    scene.add("up", Sphere(0.05), [0.0, 0.0, 0.15])
    scene.add("down", Sphere(0.05), [0.0, 0.0, -0.15])
    return scene


def test_blocked_goal_fails_honestly_within_budget_and_deadline(planar2r):
    """Budgets end the search by their counts; a timeout ends it and says so. Not timed here
    (studies/timeout_overrun.py measures the overrun): the planning CPU time bounds the work, 40
    times the timeout, which a search that ignored its deadline would exceed."""
    problem = MotionProblem(planar2r, blocked_planar(planar2r), [0.0, 0.0], [3.0, 0.0])
    prepare(problem)
    result = solve_motion(problem, "rrt_connect", seed=0, budget=300, timeout=None, retime=False)
    assert not result.success and "budget" in result.message and result.path is None
    assert result.info["nodes"] <= 300
    # a tiny dynamic domain draws nearly every sample again (no node added): the budget still ends it
    result = solve_motion(problem, "rrt_connect", seed=0, budget=20, timeout=None, retime=False, domain_radius=1e-3)
    assert not result.success and "budget" in result.message
    assert result.info["out_of_domain"] > 0 and result.info["iterations"] <= 20_000
    result = solve_motion(problem, "rrt_connect", seed=0, timeout=0.2, retime=False)
    assert not result.success and "timeout" in result.message
    assert result.cpu_time < 40 * 0.2


def test_reachable_goal_among_unreachable_ones(planar2r):
    problem = MotionProblem(planar2r, blocked_planar(planar2r), [0.0, 0.0], [[3.0, 0.0], [0.8, -0.5]])
    assert len(problem.goal_configurations) == 2
    result = solve_motion(problem, "rrt_connect", seed=2, retime=False)
    assert result.success and result.goal_index == 1


def test_motion_check_never_certifies_what_dense_exact_sampling_finds_in_collision():
    scene = table_scene()
    rng = np.random.default_rng(4)
    QA = PANDA.random_configurations(400, rng=rng)
    QA = QA[scene.collision_free(QA)][:60]
    QB = np.clip(QA + rng.normal(0.0, 0.6, QA.shape), PANDA.lower, PANDA.upper)
    for certify in ("boolean", "bisection"):
        ok = certify_motions(scene, QA, QB, 0.005, certify=certify)
        assert 0 < ok.sum() < len(ok)  # both outcomes occur
        reference = scene.certify_segments(QA[ok], QB[ok], 0.005)
        assert not np.any(reference.status == 0)  # the scene's bisection never finds them blocked
        for a, b in zip(QA[ok][:15], QB[ok][:15]):
            assert dense_exact(scene, np.stack([a, b])).min() >= 0.005 - 1e-9


def test_self_collision_scene():
    """A motion planned with self-collision: Drake's own query on a fresh plant (the scene's
    checked link pairs, the table's obstacles) finds no pair in contact anywhere along it,
    sampled at 5 mrad of the fastest joint (one-sided for the boxes and cans, where Drake's
    GJK may be optimistic)."""
    from references import FreshDrake, dense_path

    scene = table_scene(self_collision=True)
    goal = goals_in(scene, [0.35, -0.45, 0.15], [0.8, 0.45, 0.35], 1, seed=2)[0]
    problem = MotionProblem(PANDA, scene, READY, goal)
    result = solve_motion(problem, "rrt_connect", seed=0, timeout=10.0, retime=False)
    assert result.success, result.message
    drake = FreshDrake(PANDA, scene, self_collision=True, ignore_link_pairs=scene.always_close_pairs)
    Q = dense_path(result.path, 0.005)
    assert len(Q) >= 100
    assert drake.min_distances(Q, max_distance=0.05).min() >= 0.0


def test_profile_and_options(table_problems):
    problem = table_problems[0]
    result = solve_motion(problem, "rrt_connect", seed=0, retime=False, profile=True)
    for key in ("t_sample", "t_nn", "t_check", "t_certify", "t_shortcut", "t_total"):
        assert result.info[key] >= 0.0
    assert result.info["t_total"] <= result.planning_time
    # the first certified path, then the shortcut inside the rest
    assert 0.0 < result.info["t_found"] <= result.info["t_total"]
    assert result.info["t_total"] - result.info["t_found"] >= result.info["t_shortcut"] - 1e-9
    with pytest.raises(InvalidArgument, match="unknown option"):
        solve_motion(problem, "rrt_connect", bogus=1)
    with pytest.raises(InvalidArgument, match="step"):
        solve_motion(problem, "rrt_connect", step=0.0)
    with pytest.raises(InvalidArgument, match="certify"):
        solve_motion(problem, "rrt_connect", certify="exact")
    for probes in (-1, 9, 2.0, True):
        with pytest.raises(InvalidArgument, match=r"probes must be an integer in \[0, 8\]"):
            solve_motion(problem, "rrt_connect", probes=probes)
    plain = solve_motion(problem, "rrt_connect", seed=0, retime=False, probes=0, interior_probes=0)
    assert plain.info["rejected_by_probes"] == 0 and plain.success
    np.testing.assert_array_equal(plain.path, result.path)  # probes only reject colliding motions: same tree


def test_plan_called_directly_takes_any_goal_layout_and_rejects_wrong_shapes(table_problems):
    """The kernel is called through a compiled entry point that checks no type, so ``plan``
    itself must convert every argument: goals as a list, a strided or a Fortran array give the same
    path as the float rows, and goals of the wrong shape raise a clear error."""
    from drake_mh.planning.rrt_connect import plan

    problem = table_problems[0]
    goals = problem.goal_configurations
    path, _ = plan(problem, goals, np.random.default_rng(0), None, None)
    for layout in (np.asfortranarray(goals), np.repeat(goals, 2, axis=0)[::2], list(map(list, goals))):
        again, _ = plan(problem, layout, np.random.default_rng(0), None, None)
        np.testing.assert_array_equal(again, path)
    for wrong in (goals[0], goals[:, :3], np.zeros((1, 1, 7))):
        with pytest.raises(InvalidArgument, match="goals must be"):
            plan(problem, wrong, np.random.default_rng(0), None, None)


def test_a_pickled_config_builds_its_own_kernel_options():
    """The kernel's options vector holds the process's clock address: a config that crosses a
    process (pickle) or is copied rebuilds it from its options instead of carrying it."""
    import copy
    import pickle

    from drake_mh.planning.rrt_connect import RRTConnectConfig
    from drake_mh.planning.rrt_connect.search import OPTION_NAMES
    from drake_mh.planning.rrt_connect.planner import _CLOCK

    config = RRTConnectConfig(step=0.5, probes=2)
    config._vector[:] = -1.0  # as if from another process
    for again in (pickle.loads(pickle.dumps(config)), copy.deepcopy(config), copy.copy(config)):
        assert again == config and again._vector is not config._vector
        option = dict(zip(OPTION_NAMES, again._vector))
        assert option["step"] == 0.5 and option["probes"] == 2 and option["clock"] == float(_CLOCK)
