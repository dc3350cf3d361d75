"""lazy_prm_star in the compiled core (drake_mh._native.MotionPlanner.prm, C++): its searches equal
the numba kernel's (drake_mh/planning/lazy_prm_star/search.py prm_kernel) for the same seed (same
path, outcome, goal and counts) on the Panda with primitives and self-collision pairs, meshes and a
point cloud, from scratch and from a warm start; what it returns is free by Drake's distances on a
dense sampling; the planner reaches no numba kernel through the core."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from test_native_rrt import PANDA, dense, drake_reference, motions, planner, scene_of

from drake_mh.planning import MotionProblem, solve_motion
from drake_mh.planning.lazy_prm_star import search as K
from drake_mh.planning.lazy_prm_star.planner import LazyPRMStarConfig
from drake_mh.planning.motion import stats as S
from drake_mh.planning.rrt_connect.planner import _CLOCK
from drake_mh.scene.compiled_check import ENVIRONMENT

pytestmark = pytest.mark.skipif(importlib.util.find_spec("drake_mh._native") is None,
                                reason="the compiled core drake_mh._native is not built (pip install . builds it)")

COUNTS = [i for i in range(K.N_STATS) if not (S.T_SAMPLE <= i < len(S.STAT_NAMES))]  # every count, no seconds


@pytest.mark.slow
@pytest.mark.parametrize("form", ["primitives", "10 mixed as meshes", "10 mixed as a point cloud"])
def test_searches_equal_the_numba_kernel(form):
    scene = scene_of(form)
    native, (ints, floats, v_WO, reach, lower, upper) = planner(scene)
    reference = drake_reference(scene)
    QA, _ = motions(scene, 12, 3, 0.01)
    options = LazyPRMStarConfig(batch=60).vector()
    options[11] = _CLOCK  # (the numba kernel reads its clock there; the compiled core does not)
    found, searched = 0, 0
    for i in range(3):
        q0, goals = QA[i], np.ascontiguousarray(QA[4 + 2 * i:6 + 2 * i])
        for init in (np.empty((0, PANDA.nq)), np.ascontiguousarray([q0, goals[0]])):
            if len(init) and not reference(dense(q0, goals[0])).min() >= 0.01:
                continue  # a warm start must be a certified path: only the straight motion where it is free
            numba_stats, native_stats = np.zeros(K.N_STATS), np.zeros(K.N_STATS)
            seed = 40 + i
            expected = K.prm_kernel(q0, goals, init, 0, lower, upper, ints, floats, v_WO, reach, 0.01, 0.01,
                                    np.uint64(seed), 600, np.inf, options, numba_stats)
            got = native.prm(q0, goals, init, 0, lower, upper, 0.01, 0.01, seed, 600, np.inf, options, native_stats)
            assert got[1:] == expected[1:]
            assert got[0].shape == expected[0].shape
            np.testing.assert_allclose(got[0], expected[0], rtol=0, atol=1e-9)
            np.testing.assert_array_equal(native_stats[COUNTS], numba_stats[COUNTS])
            searched += numba_stats[K.SEARCHES] > 1
            if got[1] == S.FOUND:
                found += 1
                path = got[0]
                assert np.array_equal(path[0], q0) and any(np.array_equal(path[-1], g) for g in goals)
                for a, b in zip(path[:-1], path[1:]):
                    assert reference(dense(a, b)).min() >= 0.01 - 1e-9
    assert found >= 3 and searched >= 2


@pytest.mark.slow
def test_lazy_prm_star_plans_through_the_compiled_core(monkeypatch):
    """solve_motion("lazy_prm_star") through the compiled core never reaches the numba kernel
    (replaced by None) and gives the numba planner's path and counts for the same seed."""
    results = {}
    for switch in ("1", "0"):
        monkeypatch.setenv(ENVIRONMENT, switch)
        scene = scene_of("primitives")
        QA, _ = motions(scene, 4, 11, 0.01)
        problem = MotionProblem(PANDA, scene, QA[0], QA[1], clearance=0.01)
        with monkeypatch.context() as patch:
            if switch == "1":
                patch.setattr(K, "prm_kernel", None)
            results[switch] = solve_motion(problem, "lazy_prm_star", seed=4, budget=800, retime=False)
    core, numba = results["1"], results["0"]
    assert core.success and numba.success
    np.testing.assert_allclose(core.path, numba.path, rtol=0, atol=1e-9)
    for name in ("samples", "free_samples", "edges_checked", "edges_invalid", "searches", "improvements"):
        assert core.info[name] == numba.info[name], name
