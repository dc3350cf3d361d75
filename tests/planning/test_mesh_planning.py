"""Planning around a non-convex mesh obstacle (an open bin) and a point cloud: the path and the
retimed trajectory of rrt_connect are free of the original mesh surface and of every cloud
point, checked densely by the robot geometry's closed-form distances (independent of the
decomposition, the kernels and the planner)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import drake_mh
from drake_mh.planning import MotionProblem, solve_motion
from drake_mh.scene import Mesh, PointCloud, Scene

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scene"))
from obstacle_reference import PointDistance, surface_samples  # noqa: E402

DATA = Path(__file__).resolve().parents[1] / "data"
PANDA = drake_mh.load_robot("panda")
START = np.array([-1.2, 0.6, 0.0, -1.6, 0.0, 2.2, 0.8])
GOAL = np.array([1.2, 0.6, 0.0, -1.6, 0.0, 2.2, 0.8])


def _check_densely(points, path, trajectory, clearance):
    reference = PointDistance(PANDA)
    for a, b in zip(path[:-1], path[1:]):
        for t in np.linspace(0.0, 1.0, 25):
            assert reference(a + t * (b - a), points) >= clearance - 1e-9
    times = np.linspace(0.0, trajectory.duration, 300)
    for q in trajectory(times):
        assert reference(q, points) >= clearance - 1e-9


@pytest.mark.slow
def test_rrt_connect_around_a_bin_is_free_of_its_surface():
    scene = Scene(PANDA)
    scene.add("bin", Mesh(DATA / "bin.obj", scale=2.0), [0.55, 0.0, 0.45])  # 0.6 x 0.4 x 0.3 m, open on top
    problem = MotionProblem(PANDA, scene, START, GOAL, clearance=0.01)
    assert not scene.segment_free(START, GOAL, 0.01)  # the straight motion goes through the bin
    result = solve_motion(problem, "rrt_connect", seed=0, timeout=20.0)
    assert result.success, result.message
    points = surface_samples(scene.obstacles["bin"].shape, scene.obstacles["bin"].X_WO, 40000)
    _check_densely(points, result.path, result.trajectory, 0.01)


@pytest.mark.slow
def test_rrt_connect_around_a_point_cloud_is_free_of_every_point():
    rng = np.random.default_rng(0)
    wall = rng.uniform([0.45, -0.3, 0.1], [0.55, 0.3, 0.9], (4000, 3))  # a thick wall in front of the arm
    scene = Scene(PANDA)
    scene.add("wall", PointCloud(wall, 0.01))
    problem = MotionProblem(PANDA, scene, START, GOAL, clearance=0.01)
    result = solve_motion(problem, "rrt_connect", seed=0, timeout=20.0)
    assert result.success, result.message
    _check_densely(wall, result.path, result.trajectory, 0.01 + 0.01)  # the balls' radius
