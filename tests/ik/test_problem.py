"""IKProblem: inputs, vectorized objective against Drake, reach bound, rotation angle."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh.errors import FrameNotFound, InvalidConfiguration, InvalidIKProblem
from drake_mh.ik import IKProblem, reach_bound
from drake_mh.ik.problem import rotation_angle
from drake_mh.scene import Scene, Sphere


def test_position_and_pose_targets(panda):
    p = IKProblem(panda, [0.4, 0.1, 0.5])
    assert not p.full_pose and p.R_WT is None and p.position_tolerance == 1e-3
    X = panda.fk(panda.home)
    q = IKProblem(panda, X, position_tolerance=1e-5, orientation_tolerance=1e-5)
    assert q.full_pose and np.allclose(q.R_WT, X[:3, :3]) and np.allclose(q.p_WT, X[:3, 3])
    r = IKProblem(panda, [0.4, 0.1, 0.5], rpy=[np.pi, 0, 0])
    assert np.allclose(r.R_WT, np.diag([1, -1, -1]), atol=1e-12)


@pytest.mark.parametrize("kwargs, words", [
    ({"target": [1, 2]}, "position (3,) or a pose (4, 4)"),
    ({"target": "abc"}, "position (3,) or a pose (4, 4)"),
    ({"target": [0, 0, np.nan]}, "NaN"),
    ({"target": np.eye(4) * 2}, "not a rotation matrix"),
    ({"target": np.eye(4), "rpy": [0, 0, 0]}, "not both"),
    ({"target": [0.3, 0, 0.5], "rpy": [0, 0]}, "rpy must be 3"),
    ({"target": [0.3, 0, 0.5], "position_tolerance": 0}, "position_tolerance must be a positive"),
    ({"target": [0.3, 0, 0.5], "orientation_tolerance": -1}, "orientation_tolerance"),
    ({"target": [0.3, 0, 0.5], "ref_weight": -1}, "ref_weight must be a non-negative"),
    ({"target": [0.3, 0, 0.5], "clearance": np.inf}, "clearance"),
])
def test_invalid_problems_say_how_to_fix(panda, kwargs, words):
    with pytest.raises(InvalidIKProblem, match=words.replace("(", r"\(").replace(")", r"\)")):
        IKProblem(panda, **kwargs)


def test_other_input_errors(panda, six_dof):
    with pytest.raises(InvalidConfiguration, match=r"q_ref must have shape \(7,\)"):
        IKProblem(panda, [0.3, 0, 0.5], q_ref=[0, 0])
    with pytest.raises(FrameNotFound):
        IKProblem(panda, [0.3, 0, 0.5], frame="nope")
    with pytest.raises(InvalidIKProblem, match="another Robot"):
        IKProblem(panda, [0.3, 0, 0.5], scene=Scene(six_dof))


def _sphere_model_clearance(drake, model, p_WB, radius, q) -> float:
    """The sphere model's clearance to a ball at ``p_WB`` by hand: its spheres (data: link,
    centre in the link frame, radius) placed with Drake's link poses on a fresh plant."""
    poses = {link: drake.fk(q, link) for link in set(model.links)}
    centres = np.array([poses[link][:3, :3] @ c + poses[link][:3, 3] for link, c in zip(model.links, model.centres_B)])
    return float(np.min(np.linalg.norm(centres - p_WB, axis=1) - model.radii) - radius)


def test_objective_is_vectorized_and_matches_drake(panda):
    """Each term by hand from Drake on a fresh plant: the position and rotation errors from its
    FK (the angle from scipy), the collision penalty from the sphere model placed with its link
    poses, the manipulability from its Jacobian."""
    from scipy.spatial.transform import Rotation

    from references import FreshDrake

    scene = Scene(panda)
    scene.add("ball", Sphere(0.1), [0.4, 0.0, 0.4])
    q_ref = panda.home
    problem = IKProblem(panda, [0.4, 0.2, 0.5], rpy=[np.pi, 0, 0.3], scene=scene, clearance=0.15,
                        q_ref=q_ref, ref_weight=0.1, manipulability_weight=0.5)
    drake = FreshDrake(panda)
    Q = panda.random_configurations(50, 3)
    f = problem.objective(Q)
    assert f.shape == (50,) and np.all(np.isfinite(f))
    compared = penalised = 0
    for q, fq in zip(Q[:20], f[:20]):
        d = _sphere_model_clearance(drake, panda.sphere_model, np.array([0.4, 0.0, 0.4]), 0.1, q)
        if d < 0:
            continue  # a sphere penetrates: the model's value is then corrected (tested in tests/scene)
        X = drake.fk(q, "panda_link8")
        Jv = drake.jacobian(q, "panda_link8")[3:]
        angle = Rotation.from_matrix(X[:3, :3] @ problem.R_WT.T).magnitude()
        expected = np.linalg.norm(X[:3, 3] - problem.p_WT) + angle + 100 * max(0.0, 0.15 - d)
        expected += 0.1 * np.linalg.norm(q - q_ref) - 0.5 * np.sqrt(np.linalg.det(Jv @ Jv.T))
        assert fq == pytest.approx(expected, abs=1e-9)
        compared += 1
        penalised += d < 0.15
    assert compared >= 10 and penalised >= 2  # the collision term was really compared
    e_p, e_o = problem.pose_errors(Q)
    assert e_p.shape == e_o.shape == (50,)


def test_collision_penalty_only_when_clearance_missing(panda):
    """The penalty is 100 x the missing clearance of the sphere model (by hand, fresh Drake
    plant), where the model is clear of the ball; some configurations pay it, some do not."""
    from references import FreshDrake

    scene = Scene(panda)
    scene.add("ball", Sphere(0.1), [0.45, 0.0, 0.3])
    free = IKProblem(panda, [0.4, 0.2, 0.5])
    penalised = IKProblem(panda, [0.4, 0.2, 0.5], scene=scene, clearance=0.05)
    drake = FreshDrake(panda)
    Q = panda.random_configurations(200, 4)
    diff = penalised.objective(Q) - free.objective(Q)
    d = np.array([_sphere_model_clearance(drake, panda.sphere_model, np.array([0.45, 0.0, 0.3]), 0.1, q)
                  for q in Q])
    clear = d >= 0  # where no sphere penetrates (there the model's value is corrected)
    np.testing.assert_allclose(diff[clear], 100 * np.maximum(0.05 - d[clear], 0.0), atol=1e-9)
    assert np.all(diff[~clear] >= 100 * 0.05)  # in collision: at least the whole clearance is missing
    assert np.any(clear & (d < 0.05)) and np.any(d > 0.05) and np.any(~clear)


@pytest.mark.parametrize("name", drake_mh.available_robots())
def test_reach_bound_contains_the_workspace(name):
    robot = drake_mh.load_robot(name)
    bound = reach_bound(robot)
    Q = robot.random_configurations(20000, 0)
    d = np.linalg.norm(robot.batch.positions(Q) - bound.p_WO, axis=1)
    assert d.max() <= bound.radius + 1e-12
    assert d.max() >= 0.8 * bound.radius  # and it is not absurdly loose


@settings(max_examples=40, deadline=None)
@given(st.floats(1e-9, 3.1), st.integers(0, 10**6))
def test_rotation_angle_accurate_from_tiny_to_large(theta, seed):
    from pydrake.math import RotationMatrix
    from pydrake.common.eigen_geometry import AngleAxis

    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    R_WT = RotationMatrix(AngleAxis(rng.uniform(0, 3), axis[::-1] / 1.0)).matrix()
    R_WE = RotationMatrix(AngleAxis(theta, axis)).matrix() @ R_WT
    assert rotation_angle(R_WE, R_WT) == pytest.approx(theta, rel=1e-6, abs=1e-15)


@pytest.mark.parametrize("robot, target, match", [
    (None, [0.5, 0, 0.5], "robot must be"),
    ("panda", None, "real position"),
    ("panda", [0.5 + 1j, 0, 0.5], "real position"),
    ("panda", np.diag([1.0, 1.0, 1.0, 2.0]), "last row"),
    ("panda", [[1, 2], [3]], "position .3,. or a pose"),  # ragged: numpy's ValueError before
])
def test_bad_problem_inputs_are_named(panda, robot, target, match):
    from drake_mh.errors import InvalidIKProblem

    with pytest.raises(InvalidIKProblem, match=match):
        IKProblem(panda if robot == "panda" else robot, target)


def test_scene_of_the_wrong_type_is_named(panda):
    from drake_mh.errors import InvalidIKProblem

    with pytest.raises(InvalidIKProblem, match="must be a drake_mh.scene.Scene"):
        IKProblem(panda, [0.5, 0, 0.5], scene="abc")


def test_ragged_or_complex_rpy_is_named(panda):
    from drake_mh.errors import InvalidIKProblem

    for rpy in ([[0, 1], [2]], [0.1j, 0, 0], "abc"):
        with pytest.raises(InvalidIKProblem, match="rpy"):
            IKProblem(panda, [0.5, 0, 0.5], rpy=rpy)


def test_the_reference_configuration_is_copied(panda):
    q_ref = panda.home.copy()
    problem = IKProblem(panda, [0.5, 0, 0.5], q_ref=q_ref)
    q_ref[0] = 100.0  # outside the limits: the validated problem must not follow
    assert problem.q_ref[0] == panda.home[0]
