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
from drake_mh.scene import Box, Scene, Sphere


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


def test_objective_is_vectorized_and_matches_drake(panda):
    scene = Scene(panda)
    scene.add("ball", Sphere(0.1), [0.4, 0.0, 0.4])
    q_ref = panda.home
    problem = IKProblem(panda, [0.4, 0.2, 0.5], rpy=[np.pi, 0, 0.3], scene=scene, clearance=0.02,
                        q_ref=q_ref, ref_weight=0.1, manipulability_weight=0.5)
    Q = panda.random_configurations(50, 3)
    f = problem.objective(Q)
    assert f.shape == (50,) and np.all(np.isfinite(f))
    for q, fq in zip(Q[:10], f[:10]):  # the same terms computed one configuration at a time with Drake
        X = panda.fk(q)
        expected = np.linalg.norm(X[:3, 3] - problem.p_WT) + rotation_angle(X[:3, :3], problem.R_WT)
        expected += 100 * max(0.0, 0.02 - scene.batch_min_distance(q[None])[0])
        expected += 0.1 * np.linalg.norm(q - q_ref) - 0.5 * panda.manipulability(q)
        assert fq == pytest.approx(expected, abs=1e-9)
    e_p, e_o = problem.pose_errors(Q)
    assert e_p.shape == e_o.shape == (50,)


def test_collision_penalty_only_when_clearance_missing(panda):
    scene = Scene(panda)
    scene.add("box", Box((0.2, 0.2, 0.2)), [0.45, 0.0, 0.3])
    free = IKProblem(panda, [0.4, 0.2, 0.5])
    penalised = IKProblem(panda, [0.4, 0.2, 0.5], scene=scene)
    Q = panda.random_configurations(200, 4)
    d = scene.batch_min_distance(Q)
    diff = penalised.objective(Q) - free.objective(Q)
    assert np.allclose(diff, 100 * np.maximum(-d, 0.0))
    assert np.any(d < 0) and np.any(d > 0)


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
