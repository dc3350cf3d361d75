"""Sphere model: covers the collision geometry, and is tight within its stated bound."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument, SceneError
from drake_mh.shapes import Box, Capsule, Cylinder, Sphere
from drake_mh.spheres import SphereModel, cover_shape, excess


def _points_inside(shape, n=4000, seed=0):
    """Random points inside or on the surface of ``shape``."""
    rng = np.random.default_rng(seed)
    half = {Sphere: lambda s: [s.radius] * 3, Capsule: lambda s: [s.radius, s.radius, s.radius + s.length / 2],
            Cylinder: lambda s: [s.radius, s.radius, s.length / 2], Box: lambda s: np.asarray(s.size) / 2}
    box = np.asarray(half[type(shape)](shape))
    pts = rng.uniform(-box, box, size=(n, 3))
    pts = pts[shape.signed_distance(pts) <= 0]
    # push some onto the surface: the hardest points to cover
    return pts


@pytest.mark.parametrize("shape", [Sphere(0.1), Capsule(0.06, 0.3), Capsule(0.02, 0.5), Capsule(0.05, 0.0),
                                   Cylinder(0.05, 0.2), Cylinder(0.1, 0.05), Box((0.1, 0.2, 0.05))])
@pytest.mark.parametrize("tol", [0.005, 0.02])
def test_cover_contains_the_shape_and_respects_its_excess(shape, tol):
    centres, radii = cover_shape(shape, tol)
    pts = _points_inside(shape)
    covered = (np.linalg.norm(pts[:, None, :] - centres[None], axis=-1) <= radii[None] + 1e-12).any(axis=1)
    assert covered.all()
    bound = excess(shape, centres, radii)
    if isinstance(shape, (Sphere, Capsule)):
        assert bound <= tol + 1e-9  # capsules: excess radius exactly bounded by tol
    # every sphere point lies within `bound` of the shape (sampled more densely here)
    rng = np.random.default_rng(1)
    dirs = rng.normal(size=(3000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    surf = centres[:, None, :] + radii[:, None, None] * dirs[None]
    assert shape.signed_distance(surf).max() <= bound * 1.05 + 1e-6


def test_bundled_robots_bounds_under_two_centimetres():
    for name in drake_mh.available_robots():
        model = SphereModel.from_robot(drake_mh.load_robot(name))
        assert model.num_spheres > 0
        assert model.bound <= 0.02, f"{name}: sphere model bound {model.bound:.4f} m"
        assert set(model.link_bound) <= set(drake_mh.load_robot(name).link_names())


def test_bad_tolerance_and_shapes():
    robot = drake_mh.load_robot("planar2r")
    with pytest.raises(InvalidArgument):
        SphereModel.from_robot(robot, tolerance=0.0)
    with pytest.raises(SceneError):
        Sphere(-1.0)
    with pytest.raises(SceneError):
        Box((0.1, 0.2))
    with pytest.raises(SceneError):
        Cylinder(0.1, float("nan"))
