"""Algorithm 2 of the framework paper (§3.4.2): windows of 3·nC points, nearest obstacle-free points."""

import numpy as np
import pytest

from drake_mh.errors import InvalidArgument, UnknownMethod
from drake_mh.reactive.follower.replan import (ReplanConfig, collision_runs, colliding_path_points,
                                               path_point_clearance, replan_points, replan_windows)


def test_collision_runs_groups_consecutive_indices():
    assert collision_runs([9, 3, 4, 5, 12, 13]) == [(3, 5), (9, 9), (12, 13)]
    assert collision_runs([]) == []


def test_windows_take_nc_before_and_after_each_run():
    # one run of nC = 3 points: 3 before + 3 colliding + 3 after = 3·nC
    (w,) = replan_windows([10, 11, 12], lo=0, hi=49)
    assert w.tolist() == list(range(7, 16)) and w.size == 9


def test_windows_are_clipped_and_merged():
    # run (3, 5) -> [0, 8] (clipped at lo=1 -> [1, 8]); run (9, 9) -> [8, 10]: they overlap -> merged
    windows = replan_windows([3, 4, 5, 9], lo=1, hi=49)
    assert [w.tolist() for w in windows] == [list(range(1, 11))]
    # far apart runs stay separate; the end of the path clips the last window
    windows = replan_windows([5, 30, 48], lo=0, hi=49)
    assert [w.tolist() for w in windows] == [[4, 5, 6], [29, 30, 31], [47, 48, 49]]


def test_config_validation():
    with pytest.raises(UnknownMethod, match="available"):
        ReplanConfig(method="nope")
    with pytest.raises(InvalidArgument, match="1e-4"):
        ReplanConfig(tool_clearance=0.0)
    with pytest.raises(InvalidArgument, match="budget"):
        ReplanConfig(budget=1)
    assert ReplanConfig().optimizer("drake_snopt") == "pso"
    assert ReplanConfig().optimizer("e3gsa") == "e3gsa"
    assert ReplanConfig(method="DE").optimizer("e3gsa") == "de"


@pytest.fixture(scope="module")
def line_scene():
    import drake_mh
    from drake_mh.scene import Scene, Sphere

    robot = drake_mh.load_robot("seed000_6dof")
    scene = Scene(robot)
    scene.add("ball", Sphere(0.08), [0.6, 0.0, 0.3])
    points = np.column_stack([np.linspace(0.3, 0.9, 31), np.full(31, 0.02), np.full(31, 0.3)])
    return scene, points


@pytest.mark.parametrize("method", ["pso", "e3gsa", "de"])
def test_replanned_points_keep_the_tool_clearance_and_free_points_stay(line_scene, method):
    scene, points = line_scene
    config = ReplanConfig(tool_clearance=0.05, budget=1500)
    hits = colliding_path_points(points, scene, config.tool_clearance)
    assert hits.size > 0
    (window,) = replan_windows(hits, 0, len(points) - 1)
    result = replan_points(points, window, scene, config, method=method, seed=3, colliding=hits)
    assert np.all(result.tool_clearance >= config.tool_clearance)
    assert np.allclose(path_point_clearance(result.new_points, scene), result.tool_clearance)
    free = path_point_clearance(points[window], scene) >= config.tool_clearance + 1e-3
    assert np.array_equal(result.new_points[free], points[window][free])   # their own nearest free point
    assert set(result.moved.tolist()) <= set(window.tolist()) and result.moved.size >= hits.size
    # nearest: no new point is farther from its input point than the obstacle's far side
    assert np.linalg.norm(result.new_points - points[window], axis=1).max() < 0.08 + 0.05 + 0.02


def test_replan_is_deterministic(line_scene):
    scene, points = line_scene
    hits = colliding_path_points(points, scene, 0.05)
    (window,) = replan_windows(hits, 0, len(points) - 1)
    a = replan_points(points, window, scene, ReplanConfig(tool_clearance=0.05, budget=500), method="pso", seed=7)
    b = replan_points(points, window, scene, ReplanConfig(tool_clearance=0.05, budget=500), method="pso", seed=7)
    assert np.array_equal(a.new_points, b.new_points)
