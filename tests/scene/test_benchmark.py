"""The benchmark's obstacle forms: a scene of primitives given as meshes and as a surface point
cloud keeps the obstacles where they were (closed-form surface distances of the primitives)."""

from __future__ import annotations

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.scene import Box, Mesh, PointCloud, Scene, Sphere
from drake_mh.scene.benchmark import primitive_mesh, scene_form, surface_points

PANDA = drake_mh.load_robot("panda")


def _scene() -> Scene:
    scene = Scene(PANDA)
    scene.add("table", Box((0.6, 0.8, 0.04)), [0.5, 0.0, 0.2], rpy=[0.0, 0.0, 0.3])
    scene.add("ball", Sphere(0.08), [0.4, 0.3, 0.5])
    return scene


def _surface_distance(scene: Scene, points: np.ndarray) -> np.ndarray:
    """Per point, the smallest |signed distance| to the surface of a box or sphere of ``scene``
    (closed forms in each obstacle's frame)."""
    best = np.full(len(points), np.inf)
    for obstacle in scene.obstacles.values():
        X = obstacle.X_WO
        local = (points - X[:3, 3]) @ X[:3, :3]
        if isinstance(obstacle.shape, Sphere):
            d = np.abs(np.linalg.norm(local, axis=1) - obstacle.shape.radius)
        else:
            half = 0.5 * np.asarray(obstacle.shape.size)
            q = np.abs(local) - half
            d = np.abs(np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0))
        best = np.minimum(best, d)
    return best


def _sag() -> float:
    """[m] how far the ball's icosphere facets lie inside the ball at most (their planes'
    least distance from the centre; the box's mesh is exact)."""
    mesh = primitive_mesh(Sphere(0.08))
    return 0.08 - float(np.min(np.abs(np.einsum("ij,ij->i", mesh.face_normals, mesh.triangles[:, 0]))))


def test_surface_points_lie_on_the_obstacles_at_the_density():
    scene = _scene()
    points = surface_points(scene, density=2e4)
    assert np.all(_surface_distance(scene, points) <= _sag() + 1e-9)
    area = 2 * (0.6 * 0.8 + 0.6 * 0.04 + 0.8 * 0.04) + 4 * np.pi * 0.08 ** 2
    assert len(points) == pytest.approx(2e4 * area, rel=0.03)


def test_scene_forms_keep_the_obstacles_in_place():
    scene = _scene()
    same = scene_form(scene, "primitives")
    for name, obstacle in scene.obstacles.items():
        assert same.obstacles[name].shape == obstacle.shape
        assert np.allclose(same.obstacles[name].X_WO, obstacle.X_WO, atol=1e-12)
    meshes = scene_form(scene, "meshes")
    for name, obstacle in meshes.obstacles.items():
        assert isinstance(obstacle.shape, Mesh)
        vertices = obstacle.shape.vertices @ obstacle.X_WO[:3, :3].T + obstacle.X_WO[:3, 3]
        assert np.all(_surface_distance(scene, vertices) <= 1e-9)  # icosphere and box vertices on the surfaces
    cloud = scene_form(scene, "point cloud", radius=0.003)
    (obstacle,) = cloud.obstacles.values()
    assert isinstance(obstacle.shape, PointCloud) and obstacle.shape.radius == 0.003
    assert np.all(_surface_distance(scene, obstacle.shape.points) <= _sag() + 1e-9)


def test_scene_form_refuses_unknown_forms_and_non_primitives(tmp_path):
    with pytest.raises(InvalidArgument, match="unknown obstacle form"):
        scene_form(_scene(), "voxels")
    scene = scene_form(_scene(), "meshes")
    with pytest.raises(InvalidArgument, match="not a primitive"):
        scene_form(scene, "point cloud")
