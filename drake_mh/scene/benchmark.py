"""The fixed scenes the collision benchmarks share (``studies/collision_speed.py``,
``studies/exact_distance.py``): one ball in front of the arm, or ten mixed obstacles."""

from __future__ import annotations

import numpy as np

BENCHMARK_SCENES = ("1 sphere", "10 mixed")


def benchmark_scene(robot, kind: str):
    """A :class:`drake_mh.scene.Scene` of ``robot``: ``"1 sphere"`` (a 10 cm ball at
    (0.5, 0, 0.5) m) or ``"10 mixed"`` (spheres, boxes, cylinders and capsules drawn once from
    seed 1 in [-0.8, 0.8]² x [0, 1] m, tilted at random; about 18 % of random Panda
    configurations collide)."""
    from drake_mh.errors import InvalidArgument
    from drake_mh.scene import Box, Capsule, Cylinder, Scene, Sphere

    if kind not in BENCHMARK_SCENES:
        raise InvalidArgument(f"unknown benchmark scene {kind!r}; choose from {BENCHMARK_SCENES}")
    scene = Scene(robot)
    if kind == BENCHMARK_SCENES[0]:
        scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
        return scene
    shapes = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4), Capsule(0.04, 0.3)]
    rng = np.random.default_rng(1)
    for i in range(10):
        scene.add(f"o{i}", shapes[i % 4], rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.0]), rpy=rng.uniform(-3, 3, 3))
    return scene
