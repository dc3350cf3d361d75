"""Penetration lower bounds: exact where the module docstring says so, never above the truth."""

import numpy as np
import pytest

from drake_mh.scene.penetration import polytope_lower_bound, segment_lower_bound
from drake_mh.scene import Obstacle
from drake_mh.geometry.shapes import Box, Capsule, Cylinder, Sphere
from drake_mh.geometry.spheres import POLYTOPE, _core


def _obstacle(shape, p=(0.0, 0.0, 0.0), R=np.eye(3)):
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = R, p
    return Obstacle("o", shape, X)


def _pts(R_WG, p_WG):
    """Origin and unit-axis tips of G in W, ``(1, 4, 3)``."""
    return np.array([[p_WG, p_WG + R_WG[:, 0], p_WG + R_WG[:, 1], p_WG + R_WG[:, 2]]])


def test_capsule_core_exact_against_ball_capsule_and_box():
    one = np.ones(1)
    # capsule (r 0.05, half length 0.2) along z at the origin
    pts = _pts(np.eye(3), np.zeros(3))
    ball = _obstacle(Sphere(0.03), (0.0, 0.01, 0.05))  # centre 1 cm off the axis
    assert segment_lower_bound(0.2 * one, 0.05 * one, pts, ball)[0] == pytest.approx(0.01 - 0.05 - 0.03, abs=1e-9)
    rod = _obstacle(Capsule(0.02, 0.4), (0.1, 0.0, 0.0), R=np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]))
    assert segment_lower_bound(0.2 * one, 0.05 * one, pts, rod)[0] == pytest.approx(0.1 - 0.05 - 0.02, abs=1e-9)
    # a box the axis enters: minus the exact depth (push out along x: 0.05 + 0.04 - (0.0 - ...))
    box = _obstacle(Box((0.1, 0.6, 0.6)), (0.02, 0.0, 0.0))  # x in [-0.03, 0.07]
    assert segment_lower_bound(0.2 * one, 0.05 * one, pts, box)[0] == pytest.approx(-(0.03 + 0.05), abs=1e-9)


def test_polytope_core_exact_depth_for_boxes():
    core = _core("l", np.eye(4), Box((0.2, 0.2, 0.2)), 0.01, 0.01)  # cube [-0.1, 0.1]^3
    assert core.kind == POLYTOPE
    I3, p0 = np.eye(3)[None], np.zeros((1, 3))
    ball = _obstacle(Sphere(0.05), (0.07, 0.0, 0.0))  # centre 3 cm inside the +x face
    assert polytope_lower_bound(core, I3, p0, ball, np.array([-0.05]))[0] == pytest.approx(-0.08, abs=1e-12)
    outside = _obstacle(Sphere(0.05), (0.12, 0.0, 0.0))  # centre outside: spheres suffice
    assert polytope_lower_bound(core, I3, p0, outside, np.array([-0.05]))[0] == np.inf
    slab = _obstacle(Box((0.1, 1.0, 1.0)), (0.13, 0.0, 0.0))  # x in [0.08, 0.18]: 2 cm overlap
    # the spheres' value stands where the bound cannot lower it (inf), else the exact depth
    assert polytope_lower_bound(core, I3, p0, slab, np.array([-0.05]))[0] == np.inf
    assert polytope_lower_bound(core, I3, p0, slab, np.array([-0.001]))[0] == pytest.approx(-0.02, abs=1e-12)
    # a box turned 45 degrees about z, its vertical edge 5 mm from the +x face: separated
    R = np.array([[np.cos(np.pi / 4), -np.sin(np.pi / 4), 0], [np.sin(np.pi / 4), np.cos(np.pi / 4), 0], [0, 0, 1]])
    near = _obstacle(Box((0.2, 0.2, 0.2)), (0.1 + 0.005 + 0.1 * np.sqrt(2), 0.0, 0.0), R=R)
    assert polytope_lower_bound(core, I3, p0, near, np.array([-0.002]))[0] == np.inf
    into = _obstacle(Box((0.2, 0.2, 0.2)), (0.1 - 0.005 + 0.1 * np.sqrt(2), 0.0, 0.0), R=R)  # 5 mm in
    assert polytope_lower_bound(core, I3, p0, into, np.array([-0.002]))[0] == pytest.approx(-0.005, abs=1e-12)


def test_lower_bounds_never_exceed_the_sampled_truth():
    """Random poses: every bound is <= the exact distance measured by dense sampling of the link
    (points of a cube link vs the obstacle's signed distance)."""
    rng = np.random.default_rng(0)
    core = _core("l", np.eye(4), Box((0.1, 0.1, 0.3)), 0.01, 0.01)
    grid = np.stack(np.meshgrid(*[np.linspace(-h, h, 15) for h in (0.05, 0.05, 0.15)], indexing="ij"), -1).reshape(-1, 3)
    from scipy.spatial.transform import Rotation

    for shape in (Sphere(0.06), Box((0.1, 0.2, 0.15)), Cylinder(0.05, 0.3), Capsule(0.04, 0.2)):
        for _ in range(30):
            R = Rotation.random(random_state=int(rng.integers(1 << 31))).as_matrix()
            obstacle = _obstacle(shape, rng.uniform(-0.12, 0.12, 3), R)
            # the deepest sampled point of the link in O bounds the exact distance from above
            # (pushing the link out moves every point out). Given that (+1 um) as the spheres' value,
            # a bound is either below it or inf ("the spheres' value stands"), and inf is only
            # right for a ball centred, or a capsule axis, outside the link (module docstring)
            depth = shape.signed_distance((grid - obstacle.X_WO[:3, 3]) @ obstacle.X_WO[:3, :3]).min()
            if depth >= 0:
                continue
            v = polytope_lower_bound(core, np.eye(3)[None], np.zeros((1, 3)), obstacle, np.array([depth + 1e-6]))[0]
            if not (np.isinf(v) and isinstance(shape, (Sphere, Capsule))):
                assert v <= depth + 1e-9  # minus the penetration depth >= the deepest point's depth
