"""The fixed scenes the collision benchmarks share (``studies/collision_speed.py``,
``studies/exact_distance.py``): one ball in front of the arm, or ten mixed obstacles — as
primitives, as meshes of the same shapes, or as a point cloud sampled from their surfaces; and
any scene of primitives in those three forms (:func:`scene_form`)."""

from __future__ import annotations

import numpy as np

BENCHMARK_SCENES = ("1 sphere", "10 mixed", "10 mixed as meshes", "10 mixed as a point cloud")

CLOUD_POINTS = 50_000
"""Points of the cloud scene (sampled evenly over the ten surfaces by area)."""


def primitive_mesh(shape, sections: int = 32):
    """A ``trimesh.Trimesh`` of a primitive (cylinders and capsules with ``sections`` sides, so
    slightly inside the true shape: a benchmark stand-in, not a cover)."""
    import trimesh

    from drake_mh.scene import Box, Capsule, Cylinder, Sphere

    if isinstance(shape, Sphere):
        return trimesh.creation.icosphere(subdivisions=2, radius=shape.radius)
    if isinstance(shape, Box):
        return trimesh.creation.box(extents=shape.size)
    if isinstance(shape, Cylinder):
        return trimesh.creation.cylinder(radius=shape.radius, height=shape.length, sections=sections)
    if isinstance(shape, Capsule):
        return trimesh.creation.capsule(radius=shape.radius, height=shape.length, count=[sections, sections])
    raise TypeError(f"no mesh for {type(shape).__name__}")


def _mixed(rng_seed: int = 1) -> list:
    from drake_mh.scene import Box, Capsule, Cylinder, Sphere

    shapes = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4), Capsule(0.04, 0.3)]
    rng = np.random.default_rng(rng_seed)
    return [(f"o{i}", shapes[i % 4], rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.0]), rng.uniform(-3, 3, 3))
            for i in range(10)]


def benchmark_scene(robot, kind: str):
    """A :class:`drake_mh.scene.Scene` of ``robot``: ``"1 sphere"`` (a 10 cm ball at
    (0.5, 0, 0.5) m) or ``"10 mixed"`` (spheres, boxes, cylinders and capsules drawn once from
    seed 1 in [-0.8, 0.8]² x [0, 1] m, tilted at random; about 18 % of random Panda
    configurations collide); ``"10 mixed as meshes"`` (the same shapes as triangle meshes,
    written once to the cache), ``"10 mixed as a point cloud"`` (:data:`CLOUD_POINTS` points
    sampled on their surfaces, radius 0)."""
    import trimesh

    from drake_mh.errors import InvalidArgument
    from drake_mh.scene import Mesh, PointCloud, Scene, Sphere

    if kind not in BENCHMARK_SCENES:
        raise InvalidArgument(f"unknown benchmark scene {kind!r}; choose from {BENCHMARK_SCENES}")
    scene = Scene(robot)
    if kind == BENCHMARK_SCENES[0]:
        scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
        return scene
    mixed = _mixed()
    if kind == BENCHMARK_SCENES[1]:
        for name, shape, p, rpy in mixed:
            scene.add(name, shape, p, rpy=rpy)
        return scene
    if kind == BENCHMARK_SCENES[2]:
        for name, shape, p, rpy in mixed:
            scene.add(name, Mesh(mesh_file(shape)), p, rpy=rpy)
        return scene
    from pydrake.math import RollPitchYaw

    meshes = [primitive_mesh(shape) for _, shape, _, _ in mixed]
    areas = np.array([m.area for m in meshes])
    counts = np.maximum(1, np.round(CLOUD_POINTS * areas / areas.sum()).astype(int))
    points = []
    for (name, _, p, rpy), mesh, n in zip(mixed, meshes, counts):
        local, _ = trimesh.sample.sample_surface(mesh, int(n), seed=1)
        points.append(np.asarray(local) @ RollPitchYaw(rpy).ToRotationMatrix().matrix().T + p)
    scene.add("cloud", PointCloud(np.vstack(points), 0.0))
    return scene


FORMS = ("primitives", "meshes", "point cloud")
"""The three forms of a scene's obstacles that :func:`scene_form` builds."""

CLOUD_DENSITY = 1e4
"""[points / m²] sampled on the obstacles' surfaces by :func:`scene_form` (1 per cm²)."""

CLOUD_RADIUS = 0.0025
"""[m] radius of the sampled points' balls (VAMP's point radius)."""


def _empty_like(scene):
    from drake_mh.scene import Scene

    return Scene(scene.robot, self_collision=scene.self_collision, sphere_tolerance=scene._sphere_tolerance)


def mesh_file(shape) -> str:
    """Path of an OBJ file of :func:`primitive_mesh` ``(shape)`` in the cache, written once
    (named by the SHA-256 of its bytes, so equal shapes share a file)."""
    import hashlib

    from drake_mh._support.cache import atomic_write_bytes, cache_dir
    from drake_mh.geometry.obj_files import obj_bytes

    mesh = primitive_mesh(shape)
    data = obj_bytes(mesh.vertices, mesh.faces, f"benchmark {type(shape).__name__}")
    path = cache_dir("benchmark_meshes") / f"{hashlib.sha256(data).hexdigest()[:24]}.obj"
    if not path.is_file():
        atomic_write_bytes(path, data)
    return str(path)


def surface_points(scene, density: float = CLOUD_DENSITY, seed: int = 1) -> np.ndarray:
    """``(N, 3)`` [m] points in W sampled uniformly on the surfaces of ``scene``'s primitive
    obstacles (:func:`primitive_mesh`), ``ceil(area * density)`` per obstacle (``density`` in
    points per m²)."""
    import trimesh

    points = []
    for obstacle in scene.obstacles.values():
        mesh = primitive_mesh(obstacle.shape)
        count = int(np.ceil(mesh.area * density))
        local, _ = trimesh.sample.sample_surface(mesh, count, seed=seed)
        points.append(np.asarray(local) @ obstacle.X_WO[:3, :3].T + obstacle.X_WO[:3, 3])
    return np.vstack(points) if points else np.zeros((0, 3))


def scene_form(scene, form: str, density: float = CLOUD_DENSITY, radius: float = CLOUD_RADIUS,
               margin: float = 0.0):
    """A new :class:`drake_mh.scene.Scene` of the same robot with ``scene``'s primitive
    obstacles given as ``form`` (:data:`FORMS`): ``"primitives"`` (copies), ``"meshes"``
    (each one a :class:`drake_mh.scene.Mesh` of :func:`mesh_file`, at the obstacle's pose,
    decomposed as any mesh is), ``"point cloud"`` (one :class:`drake_mh.scene.PointCloud` of
    :func:`surface_points` with balls of ``radius`` [m], cropped to the robot's reach for
    clearances up to ``margin`` [m]).

    Raises:
        InvalidArgument: an unknown form or a scene with an obstacle that is not a primitive.
    """
    from pydrake.math import RotationMatrix

    from drake_mh.errors import InvalidArgument, SceneError
    from drake_mh.scene import Box, Capsule, Cylinder, Mesh, PointCloud, Sphere

    if form not in FORMS:
        raise InvalidArgument(f"unknown obstacle form {form!r}; choose from {FORMS}")
    for name, obstacle in scene.obstacles.items():
        if not isinstance(obstacle.shape, (Sphere, Box, Cylinder, Capsule)):
            raise InvalidArgument(f"obstacle {name!r} is a {type(obstacle.shape).__name__}, not a primitive; "
                                  "scene_form converts scenes of spheres, boxes, cylinders and capsules")
    out = _empty_like(scene)
    if form == "point cloud":
        if scene.obstacles:
            try:
                cloud = PointCloud(surface_points(scene, density), radius).cropped_to_reach(out, margin=margin)
            except SceneError:  # no point within the robot's reach: nothing to add
                return out
            out.add("cloud", cloud)
        return out
    for name, obstacle in scene.obstacles.items():
        rpy = RotationMatrix(obstacle.X_WO[:3, :3]).ToRollPitchYaw().vector()
        shape = obstacle.shape if form == "primitives" else Mesh(mesh_file(obstacle.shape))
        out.add(name, shape, obstacle.X_WO[:3, 3], rpy=rpy)
    return out
