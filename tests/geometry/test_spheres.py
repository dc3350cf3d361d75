"""Sphere model: the union of the spheres contains every collision geometry (primitives, ellipsoids,
convex meshes), every sphere point lies within the stated excess of it, and models are cached."""

import numpy as np
import pytest
from scipy.optimize import nnls

import drake_mh
from drake_mh.errors import InvalidArgument, SceneError, UnsupportedGeometry
from drake_mh.geometry.shapes import Box, Capsule, ConvexPolytope, Cylinder, Ellipsoid, Sphere
from drake_mh.geometry.sphere_cover import circumscribed_polytope, cover
from drake_mh.geometry.spheres import SphereModel, cover_shape
from sphere_fixtures import mesh_arm_urdf, no_geometry_urdf, primitive_arm_urdf


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("DRAKE_MH_CACHE", str(tmp_path / "cache"))


def _stretched_icosphere():
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=2, radius=0.05)
    mesh.apply_scale([1.0, 1.6, 2.4])
    return ConvexPolytope(mesh.vertices)


def _random_hull(seed=3):
    return ConvexPolytope(np.random.default_rng(seed).normal(size=(40, 3)) * [0.03, 0.05, 0.12])


SHAPES = [Sphere(0.1), Capsule(0.06, 0.3), Capsule(0.02, 0.5), Capsule(0.05, 0.0), Cylinder(0.05, 0.2),
          Cylinder(0.1, 0.05), Box((0.1, 0.2, 0.05)), Ellipsoid(0.04, 0.06, 0.1), _stretched_icosphere(),
          _random_hull()]


def _inside(shape, pts):
    if isinstance(shape, Ellipsoid):
        return np.sum((pts / [shape.a, shape.b, shape.c]) ** 2, axis=1) <= 1.0
    if isinstance(shape, ConvexPolytope):
        return shape.halfspace_distance(pts) <= 0
    return shape.signed_distance(pts) <= 0


def _distance_to_polytope(vertices, pts):
    """Exact distance from each point to conv(vertices) (projection by non-negative least squares)."""
    w = 1e4
    A = np.vstack([vertices.T, w * np.ones(len(vertices))])
    out = []
    for p in pts:
        lam, _ = nnls(A, np.concatenate([p, [w]]))
        out.append(np.linalg.norm(vertices.T @ lam - p))
    return np.array(out)


def _distance(shape, pts):
    """Exact distance [m] from points outside ``shape`` to it (0 inside)."""
    if isinstance(shape, (Sphere, Capsule, Cylinder, Box)):
        return np.maximum(shape.signed_distance(pts), 0.0)
    return _distance_to_polytope(shape.vertices, pts)


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: type(s).__name__)
@pytest.mark.parametrize("tol", [0.01, 0.02])
def test_cover_contains_the_shape_within_its_excess(shape, tol):
    centres, radii, excess = cover(shape, tol)
    assert excess <= tol + 1e-12
    # containment: dense random points of the shape, surface-heavy (the hardest to cover)
    rng = np.random.default_rng(0)
    half = np.abs(np.vstack([centres - radii[:, None], centres + radii[:, None]])).max(axis=0)
    pts = rng.uniform(-half, half, size=(60000, 3))
    pts = pts[_inside(shape, pts)]
    assert len(pts) > 1000
    covered = np.zeros(len(pts), bool)
    for c, r in zip(centres, radii):
        covered |= np.sum((pts - c) ** 2, axis=1) <= r * r + 1e-15
    assert covered.all(), f"{np.sum(~covered)} points of the shape outside every sphere"
    # excess: the sphere points farthest out are within `excess` of the shape
    dirs = rng.normal(size=(400, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    surface = (centres[:, None, :] + radii[:, None, None] * dirs[None]).reshape(-1, 3)
    if isinstance(shape, Ellipsoid):  # measured against its circumscribed polytope (contains it)
        poly, hausdorff = circumscribed_polytope(shape, tol)
        shape, excess = poly, excess - hausdorff
    rough = shape.halfspace_distance(surface) if isinstance(shape, ConvexPolytope) else shape.signed_distance(surface)
    worst = surface[np.argsort(rough)[-60:]]
    assert _distance(shape, worst).max() <= excess + 1e-9
    if isinstance(shape, Capsule):  # capsules: excess is exactly radius - r
        assert excess == pytest.approx(radii.max() - shape.radius, abs=1e-15)


def test_capsule_covering_is_unchanged():
    """Capsule links (every bundled robot) keep the axis covering: same spheres as before."""
    centres, radii = cover_shape(Capsule(0.06, 0.3), 0.01)
    spacing = 2.0 * np.sqrt(0.07 ** 2 - 0.06 ** 2)
    n = int(np.ceil(0.3 / spacing))
    assert len(radii) == n + 1
    np.testing.assert_allclose(centres[:, 2], np.linspace(-0.15, 0.15, n + 1))
    np.testing.assert_allclose(radii, np.hypot(0.06, 0.15 / n))


def test_bundled_robots_bounds_within_tolerance():
    for name in drake_mh.available_robots():
        robot = drake_mh.load_robot(name)
        model = SphereModel.from_robot(robot)
        assert model.num_spheres > 0
        assert model.bound <= model.tolerance + 1e-12, f"{name}: bound {model.bound:.4f} m"
        assert set(model.link_bound) <= set(robot.link_names())
        assert sum(model.link_counts().values()) == model.num_spheres
        # each geometry's spheres are contiguous, in geometry order
        assert np.all(np.diff(model.geometry) >= 0) and model.geometry[-1] == len(model.geometries) - 1


def test_mesh_robot_model_and_cache(tmp_path):
    robot = drake_mh.Robot(mesh_arm_urdf(tmp_path))
    first = SphereModel.from_robot(robot)
    assert set(first.link_counts()) == {"l1", "l2", "l3"}
    assert all(0 < b <= 0.01 + 1e-12 for b in first.link_bound.values())
    assert {c.kind for c in first.geometries} == {1}  # polytope cores
    cached = SphereModel.from_robot(robot)
    np.testing.assert_array_equal(first.radii, cached.radii)
    np.testing.assert_array_equal(first.centres_B, cached.centres_B)
    files = list((tmp_path / "cache" / "spheres").glob("*.npz"))
    assert len(files) == 3
    coarse = SphereModel.from_robot(robot, tolerance=0.02)  # another key, fewer spheres
    assert len(list((tmp_path / "cache" / "spheres").glob("*.npz"))) == 6
    assert coarse.num_spheres < first.num_spheres and coarse.bound <= 0.02 + 1e-12
    # a corrupt entry is recomputed, not trusted
    for f in files:
        f.write_bytes(b"not an npz")
    again = SphereModel.from_robot(robot)
    np.testing.assert_array_equal(first.radii, again.radii)


def test_primitive_links_cylinder_box_ellipsoid(tmp_path):
    robot = drake_mh.Robot(primitive_arm_urdf())
    model = SphereModel.from_robot(robot)
    assert set(model.link_counts()) == {"cyl", "box", "ell"}
    assert model.bound <= 0.01 + 1e-12


def test_no_collision_geometry_is_an_error_not_infinite_clearance():
    robot = drake_mh.Robot(no_geometry_urdf())
    with pytest.raises(SceneError, match="no collision geometry"):
        SphereModel.from_robot(robot)


def test_bad_tolerance_and_shapes():
    robot = drake_mh.load_robot("planar2r")
    with pytest.raises(InvalidArgument):
        SphereModel.from_robot(robot, tolerance=0.0)
    with pytest.raises(InvalidArgument):
        cover(Box((0.1, 0.1, 0.1)), float("nan"))
    with pytest.raises(SceneError):
        Sphere(-1.0)
    with pytest.raises(SceneError):
        Box((0.1, 0.2))
    with pytest.raises(SceneError):
        Cylinder(0.1, float("nan"))
    with pytest.raises(SceneError):
        Ellipsoid(0.1, 0.0, 0.1)
    with pytest.raises(UnsupportedGeometry, match="no volume"):
        ConvexPolytope([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
