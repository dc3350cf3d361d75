"""Collision-free IK among a mesh and a point cloud: a reported success is free of the mesh's
original surface and of every cloud point (the robot geometry's closed-form distances, not the
scene's own)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from drake_mh.ik import IKProblem, solve_ik
from drake_mh.scene import Mesh, PointCloud, Scene

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scene"))
from obstacle_reference import PointDistance, surface_samples  # noqa: E402

DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.mark.parametrize("method", ["hybrid", "dls"])
def test_reported_success_is_free_of_mesh_and_cloud(panda, method):
    rng = np.random.default_rng(0)
    scene = Scene(panda)
    scene.add("bracket", Mesh(DATA / "bracket.obj", scale=1.5), [0.35, 0.2, 0.45], rpy=[0.3, 0, 0])
    scene.add("cloud", PointCloud(rng.uniform([0.3, -0.35, 0.1], [0.5, -0.05, 0.35], (2000, 3)), 0.01))
    points = np.vstack([surface_samples(scene.obstacles["bracket"].shape, scene.obstacles["bracket"].X_WO),
                        scene.obstacles["cloud"].shape.points])
    reference = PointDistance(panda)
    Q = panda.random_configurations(400, 1)
    targets = panda.batch.fk(Q[scene.batch_min_distance(Q) > 0.03][:4])
    successes = 0
    for i, X in enumerate(targets):
        result = solve_ik(IKProblem(panda, X[:3, 3], scene=scene, clearance=0.01), method, seed=i, budget=20000)
        if result.success:
            successes += 1
            # the cloud's balls have radius 0.01: its points must be 0.02 away, the mesh's 0.01
            assert reference(result.q, points[:-2000]) >= 0.01 - 1e-9
            assert reference(result.q, points[-2000:]) >= 0.02 - 1e-9
    assert successes >= 2
