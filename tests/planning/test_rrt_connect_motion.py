"""rrt_connect's motion check (drake_mh.planning.rrt_connect._motion): its workspace holds the
longest motion within the joint limits, and a motion longer than the workspace gets the same
answer from arrays of its own."""

import numba
import numpy as np

import drake_mh
from drake_mh.planning.rrt_connect import planner
from drake_mh.planning.rrt_connect._motion import certified_motion, motion_capacity, workspaces
from drake_mh.planning.rrt_connect._stats import STAT_NAMES
from drake_mh.scene import Box, Scene, Sphere
from drake_mh.scene._packing import _unpack

PANDA = drake_mh.load_robot("panda")


def shelf_scene() -> Scene:
    scene = Scene(PANDA, self_collision=True)
    scene.add("board", Box((0.4, 0.8, 0.02)), [0.55, 0.0, 0.45])
    scene.add("ball", Sphere(0.08), [0.4, 0.3, 0.7])
    return scene


def panda_reach():
    return np.ascontiguousarray(shelf_scene().collision_model.reach)


@numba.njit
def _answers(QA, QB, ints, floats, v_WO, reach, capacity, clock):
    arrays = _unpack(ints, floats)
    ws, mws = workspaces(arrays, QA.shape[1], reach.shape[0], 32, capacity)  # owned: no borrowing here
    stats, buf = np.zeros(len(STAT_NAMES)), np.zeros(2, np.int64)
    out = np.empty(QA.shape[0], np.bool_)
    for i in range(QA.shape[0]):
        out[i] = certified_motion(QA[i], QB[i], arrays, ws, mws, (8, 32), v_WO, reach, 0.0, 0.0, 16.0, 0.02, 512,
                                  None, stats, clock, buf, False)
    return out, stats


def test_the_capacity_bounds_every_motion_within_the_limits():
    reach = panda_reach()
    span = PANDA.upper - PANDA.lower
    capacity = motion_capacity(span, reach, 16.0, 0.02)
    rng = np.random.default_rng(0)
    QA, QB = PANDA.random_configurations(500, rng=rng), PANDA.random_configurations(500, rng=rng)
    dq = np.abs(QB - QA)
    n = np.maximum(np.ceil(np.linalg.norm(dq, axis=1) * 16.0), np.ceil((dq @ reach.T).max(axis=1) / 0.04))
    assert np.all(n + 1 <= capacity) and capacity < 4096
    assert motion_capacity(np.full(7, np.inf), reach, 16.0, 0.02) == 4096


def test_a_motion_longer_than_the_workspace_gets_the_same_answer():
    scene = shelf_scene()
    rng = np.random.default_rng(1)
    QA = PANDA.random_configurations(300, rng=rng)
    QA = np.ascontiguousarray(QA[scene.collision_free(QA)][:40])
    QB = np.ascontiguousarray(np.clip(QA + rng.normal(0.0, 0.5, QA.shape), PANDA.lower, PANDA.upper))
    ints, floats, v_WO, reach = planner._arguments(scene)
    big, stats_big = _answers(QA, QB, ints, floats, v_WO, reach, 4096, planner._CLOCK)
    small, stats_small = _answers(QA, QB, ints, floats, v_WO, reach, 2, planner._CLOCK)
    assert 0 < big.sum() < len(big)
    np.testing.assert_array_equal(big, small)
    np.testing.assert_array_equal(stats_big, stats_small)
    np.testing.assert_array_equal(big, planner.certify_motions(scene, QA, QB))


def test_the_bisection_refines_the_rows_that_came_near_and_never_certifies_a_collision():
    """Motions that come within their margins are refined on the rows that did (the others kept
    theirs at every state): the certified ones keep the clearance under the scene's own
    certificate and dense exact sampling, and some are rejected only by the bisection."""
    scene = shelf_scene()
    rng = np.random.default_rng(7)
    QA = PANDA.random_configurations(600, rng=rng)
    QA = np.ascontiguousarray(QA[scene.collision_free(QA)][:200])
    QB = np.ascontiguousarray(np.clip(QA + rng.normal(0.0, 0.3, QA.shape), PANDA.lower, PANDA.upper))
    ints, floats, v_WO, reach = planner._arguments(scene)
    refined, outcome = [], []
    for a, b in zip(QA, QB):
        ok, stats = _answers(a[None], b[None], ints, floats, v_WO, reach, 4096, planner._CLOCK)
        refined.append(stats[STAT_NAMES.index("refined")] > 0)
        outcome.append(ok[0])
    refined, outcome = np.array(refined), np.array(outcome)
    assert np.sum(refined & outcome) >= 3 and np.sum(refined & ~outcome) >= 1
    sure = refined & outcome
    assert np.all(scene.certify_segments(QA[sure], QB[sure], 0.0).status != 0)  # never found blocked
    t = np.linspace(0.0, 1.0, 200)[:, None]
    for a, b in zip(QA[sure][:10], QB[sure][:10]):
        assert scene.exact_min_distance(a + t * (b - a)).min() >= -1e-9
