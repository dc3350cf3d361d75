"""Tests of drake_mh.robot.dh: DH table -> URDF, checked against Drake and the DH products."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.all import AddMultibodyPlantSceneGraph, DiagramBuilder, Parser, SpatialInertia

from drake_mh.robot.dh import Capsule, LinkSpec, Sphere, capsule_inertia, dh_to_urdf, dh_transform
from drake_mh.errors import InvalidArgument, InvalidDHTable, InvalidLimits


def load(text: str):
    """Plant + scene graph diagram of a URDF string (pydrake only)."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    Parser(plant).AddModelsFromString(text, "urdf")
    plant.Finalize()
    return plant, scene_graph


def dh_product(a, alpha, d, theta, convention, X_WB=np.eye(4), tool=np.eye(4)):
    """Reference FK: X_WB * prod_i X_{i-1,i}(theta_i) * tool, eq. (1) of the framework paper."""
    X = np.array(X_WB, float)
    for i in range(len(a)):
        X = X @ dh_transform(a[i], alpha[i], d[i], theta[i], convention)
    return X @ tool


def X_ee(plant, q, ee="ee"):
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q)
    return plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(ee)).GetAsMatrix4()


def random_pose(rng):
    from pydrake.math import RollPitchYaw, RotationMatrix

    X = np.eye(4)
    X[:3, :3] = RotationMatrix(RollPitchYaw(rng.uniform(-3, 3, 3))).matrix()
    X[:3, 3] = rng.normal(size=3)
    return X


def test_framework_paper_two_link_example():
    """Framework paper Sec. 3.1: a = 1, alpha = 0, d = 0, theta = (30, 45) deg."""
    plant, _ = load(dh_to_urdf([1, 1], [0, 0], [0, 0]))
    p = X_ee(plant, np.radians([30, 45]))[:3, 3]
    np.testing.assert_allclose(p, [1.1248, 1.4659, 0.0], atol=1e-4)


def test_explicit_eq2_matrix():
    """dh_transform('standard') is the matrix printed as eq. (2) of the framework paper."""
    a, al, d, th = 0.3, 0.7, -0.2, 1.1
    c, s, ca, sa = math.cos(th), math.sin(th), math.cos(al), math.sin(al)
    eq2 = np.array(
        [[c, -s * ca, s * sa, a * c], [s, c * ca, -c * sa, a * s], [0, sa, ca, d], [0, 0, 0, 1]]
    )
    np.testing.assert_allclose(dh_transform(a, al, d, th), eq2, atol=1e-15)


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_fk_equals_dh_product(convention):
    """Drake's FK of 'ee' equals the product of the DH matrices to <= 1e-12."""
    rng = np.random.default_rng(7 if convention == "standard" else 8)
    for n in (1, 3, 7):
        a, d = rng.normal(size=n), rng.normal(size=n)
        alpha, offset = rng.uniform(-math.pi, math.pi, n), rng.uniform(-math.pi, math.pi, n)
        tool, X_WB = random_pose(rng), random_pose(rng)
        text = dh_to_urdf(
            a, alpha, d, offset, lower=[-7] * n, upper=[7] * n,
            convention=convention, tool=tool, X_WB=X_WB,
        )
        plant, _ = load(text)
        for _ in range(5):
            q = rng.uniform(-7, 7, n)
            expected = dh_product(a, alpha, d, q + offset, convention, X_WB, tool)
            assert np.abs(X_ee(plant, q) - expected).max() <= 1e-12


def test_axis_aligned_twists_and_zero_rows():
    """Exact pi/2 twists and all-zero rows (spherical wrists) also match."""
    a, alpha, d = [0, 0.4, 0, 0], [math.pi / 2, 0, -math.pi / 2, 0], [0.3, 0, 0, 0]
    for convention in ("standard", "modified"):
        plant, _ = load(dh_to_urdf(a, alpha, d, convention=convention))
        q = np.array([0.3, -0.2, 1.0, 2.0])
        assert np.abs(X_ee(plant, q) - dh_product(a, alpha, d, q, convention)).max() <= 1e-12


def test_structure_limits_actuators_and_geometry():
    n = 4
    text = dh_to_urdf(
        [0.1, 0.3, 0.2, 0.1], [math.pi / 2, 0, 0, 0], [0.2, 0, 0, 0],
        lower=[-1, -2, -3, -1.5], upper=[1, 2, 3, 1.5],
        velocity_limits=[1, 2, 3, 4], effort_limits=[40, 30, 20, 10],
        acceleration_limits=[5, 6, 7, 8], jerk_limits=[50, 60, 70, 80], name="arm4",
    )
    assert 'xmlns:drake="http://drake.mit.edu"' in text
    assert 'drake_mh:jerk="80"' in text and text.count("SimpleTransmission") == n
    assert "unique leaf link" in text.split("<robot")[0]
    plant, scene_graph = load(text)
    assert plant.num_positions() == n and plant.num_actuators() == n
    np.testing.assert_array_equal(plant.GetPositionLowerLimits(), [-1, -2, -3, -1.5])
    np.testing.assert_array_equal(plant.GetVelocityUpperLimits(), [1, 2, 3, 4])
    np.testing.assert_array_equal(plant.GetEffortUpperLimits(), [40, 30, 20, 10])
    np.testing.assert_array_equal(plant.GetAccelerationUpperLimits(), [5, 6, 7, 8])
    names = [plant.get_joint(i).name() for i in plant.GetJointIndices() if plant.get_joint(i).num_positions()]
    assert names == [f"joint{i}" for i in range(1, n + 1)]
    inspector = scene_graph.model_inspector()
    for i in range(1, n + 1):
        body = plant.GetBodyByName(f"link{i}")
        assert body.default_mass() > 0
        geoms = inspector.GetGeometries(plant.GetBodyFrameIdOrThrow(body.index()))
        kinds = {type(inspector.GetShape(g)).__name__ for g in geoms}
        assert kinds and kinds <= {"Capsule", "Sphere"}
    assert plant.GetBodyByName("ee").default_mass() == 0


def test_defaults_give_actuators_and_positive_limits():
    """Without velocity/effort limits the documented defaults keep Drake's actuators."""
    plant, _ = load(dh_to_urdf([0.5, 0.4], [0, 0], [0, 0]))
    np.testing.assert_allclose(plant.GetVelocityUpperLimits(), [math.pi, math.pi])
    effort = plant.GetEffortUpperLimits()
    assert effort.shape == (2,) and (effort > 0).all() and effort[0] > effort[1]
    np.testing.assert_allclose(plant.GetPositionUpperLimits(), [math.pi, math.pi])
    assert np.isinf(plant.GetAccelerationUpperLimits()).all()  # unknown -> not written


def test_default_effort_bounds_static_gravity_torque():
    """Default effort >= 2 x the gravity torque of the horizontally stretched arm."""
    X_WB = np.eye(4)
    X_WB[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]  # joint axes horizontal: gravity in the plane
    plant, _ = load(dh_to_urdf([0.5, 0.4], [0, 0], [0, 0], X_WB=X_WB))
    context = plant.CreateDefaultContext()
    worst = np.zeros(2)
    for q in np.linspace(-math.pi, math.pi, 73):
        for q2 in np.linspace(-math.pi, math.pi, 37):
            plant.SetPositions(context, [q, q2])
            worst = np.maximum(worst, np.abs(plant.CalcGravityGeneralizedForces(context)))
    assert worst.min() > 0
    assert (plant.GetEffortUpperLimits() >= 2 * worst - 1e-9).all()


def test_capsule_inertia_matches_drake():
    rng = np.random.default_rng(3)
    for length in (0.0, 0.3):
        A = rng.normal(size=3)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        m, com, I = capsule_inertia(A, A + length * u, 0.05, 1200.0)
        if length > 0:
            M = SpatialInertia.SolidCapsuleWithDensity(1200.0, 0.05, length, u)
        else:
            M = SpatialInertia.SolidSphereWithDensity(1200.0, 0.05)
        assert m == pytest.approx(M.get_mass(), rel=1e-12)
        np.testing.assert_allclose(com, A + length * u / 2, atol=1e-15)
        np.testing.assert_allclose(I, M.CalcRotationalInertia().CopyToFullMatrix3(), rtol=1e-10, atol=1e-14)


def test_link_overrides():
    """Mass, centre of mass, inertia and collision shapes can be given per link."""
    spec = LinkSpec(
        mass=2.0, com=(0.1, 0, 0), inertia=(0.02, 0, 0, 0.03, 0, 0.04),
        collision=(Sphere((0, 0, 0), 0.05), Capsule((0, 0, 0), (0.2, 0, 0), 0.03)),
    )
    text = dh_to_urdf([0.2, 0.1], [0, 0], [0, 0], links=[spec, LinkSpec(mass=0.5)])
    plant, scene_graph = load(text)
    body = plant.GetBodyByName("link1")
    assert body.default_mass() == 2.0
    np.testing.assert_allclose(body.default_com(), [0.1, 0, 0])
    assert plant.GetBodyByName("link2").default_mass() == 0.5
    inspector = scene_graph.model_inspector()
    assert len(inspector.GetGeometries(plant.GetBodyFrameIdOrThrow(body.index()))) == 4  # 2 collision + 2 visual


@pytest.mark.parametrize(
    "kwargs, error, words",
    [
        (dict(a=[1, 2], alpha=[0], d=[0, 0]), InvalidDHTable, "different lengths"),
        (dict(a=[1, float("nan")], alpha=[0, 0], d=[0, 0]), InvalidDHTable, "a[1]"),
        (dict(a=[1], alpha=[0], d=[math.inf]), InvalidDHTable, "not finite"),
        (dict(a=[], alpha=[], d=[]), InvalidDHTable, "empty"),
        (dict(a=[1], alpha=[0], d=[0], convention="craig"), InvalidDHTable, "convention"),
        (dict(a=[1], alpha=[0], d=[0], offset=[0, 0]), InvalidDHTable, "offset"),
        (dict(a=[1, 1], alpha=[0, 0], d=[0, 0], lower=[0, 1], upper=[1, 0]), InvalidLimits, "joint 2"),
        (dict(a=[1], alpha=[0], d=[0], velocity_limits=[-1]), InvalidLimits, "velocity_limits"),
        (dict(a=[1], alpha=[0], d=[0], effort_limits=[0]), InvalidLimits, "effort_limits"),
        (dict(a=[1], alpha=[0], d=[0], effort_limits=[1, 2]), InvalidLimits, "one value per joint"),
        (dict(a=[1], alpha=[0], d=[0], lower=[math.nan]), InvalidLimits, "lower"),
        (dict(a=[1], alpha=[0], d=[0], jerk_limits=[-5]), InvalidLimits, "jerk_limits"),
        (dict(a=[1], alpha=[0], d=[0], tool=np.ones((3, 3))), InvalidArgument, "tool"),
        (dict(a=[1], alpha=[0], d=[0], link_radius=0), InvalidArgument, "link_radius"),
        (dict(a=[1], alpha=[0], d=[0], links=[LinkSpec(inertia=(1, 0, 0, 1, 0, 1))]), InvalidArgument, "mass"),
        (dict(a=[1], alpha=[0], d=[0], links=[LinkSpec(mass=1, inertia=(1, 0, 0, 1, 0, 5))]), InvalidArgument, "triangle"),
    ],
)
def test_validation_errors(kwargs, error, words):
    with pytest.raises(error) as info:
        dh_to_urdf(**kwargs)
    assert words in str(info.value)


def test_errors_are_value_errors():
    """The exceptions keep `except ValueError` code working."""
    with pytest.raises(ValueError):
        dh_to_urdf([1], [0], [0], lower=[1], upper=[0])


def test_capsule_poses_in_drake_match_segments():
    """Drake places each capsule on its segment A-B, for axis-aligned and oblique axes."""
    directions = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1), (1, 2, -2), (-1, 0, 1e-9)]
    shapes = tuple(
        Capsule((0.1, -0.2, 0.3), tuple(0.1 * np.array(u) / np.linalg.norm(u) + [0.1, -0.2, 0.3]), 0.02)
        for u in directions
    )
    text = dh_to_urdf([0.2], [0], [0], links=[LinkSpec(collision=shapes)])
    plant, scene_graph = load(text)
    inspector = scene_graph.model_inspector()
    frame = plant.GetBodyFrameIdOrThrow(plant.GetBodyByName("link1").index())
    from pydrake.geometry import Role

    found = []
    for g in inspector.GetGeometries(frame, Role.kProximity):
        X_LG = inspector.GetPoseInFrame(g).GetAsMatrix4()
        half = inspector.GetShape(g).length() / 2
        ends = [X_LG[:3, :3] @ [0, 0, s * half] + X_LG[:3, 3] for s in (-1, 1)]
        found.append(ends)
    assert len(found) == len(shapes)
    for shape in shapes:
        A, B = np.array(shape.p_LA), np.array(shape.p_LB)
        assert any(
            min(np.abs(e[0] - A).max() + np.abs(e[1] - B).max(), np.abs(e[0] - B).max() + np.abs(e[1] - A).max())
            < 1e-12
            for e in found
        ), shape
