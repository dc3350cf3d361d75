"""IK along a Cartesian path: warm start, joint-displacement penalty, largest joint step."""

from __future__ import annotations

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.paths import ik_along_path, trapezoidal_path
from references import FreshDrake, dense_path


@pytest.fixture(scope="module")
def arm6():
    return drake_mh.load_robot("seed000_6dof")


def test_table3_path_with_drake_ik_is_continuous(arm6):
    path = trapezoidal_path()  # 50 points
    jp = ik_along_path(arm6, path, method="drake_snopt", seed=0, budget=5)
    assert jp.all_success and jp.q.shape == (50, 6)
    assert np.max(jp.position_error) <= 1e-3
    drake = FreshDrake(arm6)  # independent FK check: Drake on a fresh plant
    for q, p in zip(jp.q, path.points):
        assert np.linalg.norm(drake.fk(q, arm6.ee_frame_name)[:3, 3] - p) <= 1e-3
    # the reported largest step is the real one, on the named joint
    steps = np.abs(np.diff(jp.q, axis=0)).max(axis=1)
    assert jp.max_step == pytest.approx(steps.max()) and jp.max_step_index == int(np.argmax(steps))
    k = jp.max_step_index
    assert jp.max_step_joint == arm6.joint_names[int(np.argmax(np.abs(jp.q[k + 1] - jp.q[k])))]
    assert jp.max_step < 0.5  # consecutive points 5 cm apart at most: no branch jump


def test_metaheuristic_warm_start_and_penalty_keep_the_branch(arm6):
    path = trapezoidal_path([[0.9, 0.2, 0.3], [0.8, 0.4, 0.3]], 6)
    start = ik_along_path(arm6, path.points[:1], method="drake_snopt", seed=1, budget=5).q[0]
    jp = ik_along_path(arm6, path, method="pso", seed=3, q_start=start, budget=4000, first_budget=4000)
    assert jp.all_success
    assert jp.max_step < 1.0  # PSO lands anywhere within 1 mm: its steps are rougher
    assert jp.method == "pso" and jp.nfe > 0
    smooth = ik_along_path(arm6, path, method="hybrid", seed=3, q_start=start, budget=2000)
    assert smooth.all_success and smooth.max_step < 0.2


@pytest.mark.parametrize("method", ["dls", "hybrid"])
def test_search_boxes_and_tidying_keep_the_branch(arm6, method):
    # measured on Table 3: without the search boxes (one whole-range attempt) dls jumped 5.97 rad
    # and hybrid 6.20 rad on the ±2π joints; with them 0.21 and 0.11 rad
    path = trapezoidal_path()
    jp = ik_along_path(arm6, path, method=method, seed=0)
    assert jp.all_success and jp.max_step < 0.5
    free = ik_along_path(arm6, path, method=method, seed=0, search_radii=(None,))
    assert free.all_success and free.max_step > 2.0      # the test can fail: the boxes are what keeps it


def test_bad_input(arm6):
    with pytest.raises(InvalidArgument, match="points"):
        ik_along_path(arm6, np.zeros((3, 2)))
    with pytest.raises(InvalidArgument, match="ref_weight"):
        ik_along_path(arm6, np.zeros((2, 3)), ref_weight=-1.0)
    with pytest.raises(InvalidArgument, match="search_radii"):
        ik_along_path(arm6, np.zeros((2, 3)), search_radii=(0.3, -1.0))
    for seed in ("abc", -1, 1.5, True):  # numpy's TypeError / ValueError before
        with pytest.raises(InvalidArgument, match="seed must be an integer >= 0"):
            ik_along_path(arm6, np.zeros((2, 3)), seed=seed)


def test_motion_through_the_solutions_is_certified(arm6):
    from drake_mh.scene import Scene, Sphere

    scene = Scene(arm6)
    scene.add("ball", Sphere(0.2), (0.2, 0.2, 0.6))              # the framework scenario's obstacle
    path = trapezoidal_path(n_points=24)
    jp = ik_along_path(arm6, path, method="hybrid", seed=0, scene=scene, clearance=0.015)
    assert jp.motion_certified and jp.all_success and jp.motion_first_failure is None
    assert 0 <= jp.motion_min_clearance <= scene.exact_min_distance(jp.q).min()
    # the exact distance (tested against Drake in tests/scene/test_exact.py), sampled at 2 mrad of
    # the fastest joint, never below the certified clearance
    assert scene.exact_min_distance(dense_path(jp.q, 0.002)).min() >= jp.motion_min_clearance - 1e-9
    assert ik_along_path(arm6, path, method="hybrid", seed=0).motion_certified is None   # no scene: no verdict


def test_motion_not_certified_is_reported_and_fails(arm6):
    from drake_mh.scene import Scene, Sphere

    scene = Scene(arm6)
    path = trapezoidal_path(n_points=24)
    free = ik_along_path(arm6, path, method="hybrid", seed=0)
    # a ball that reaches the tool's path half-way through the motion, moving with the path's times
    k = 12
    p_mid = 0.5 * (arm6.fk(free.q[k])[:3, 3] + arm6.fk(free.q[k + 1])[:3, 3])
    t_mid = 0.5 * (path.times[k] + path.times[k + 1])
    velocity = np.array([0.0, 0.0, -0.5])
    scene.add("ball", Sphere(0.05), p_mid - velocity * t_mid, velocity=velocity)
    jp = ik_along_path(arm6, path, method="hybrid", seed=0, scene=scene)
    assert np.all(jp.success)                                      # every point is clear where the ball is now
    assert jp.motion_certified is False and not jp.all_success     # the motion is not
    assert jp.motion_first_failure is not None and "segment" in jp.motion_failure_reason
    assert np.isnan(jp.motion_min_clearance)
