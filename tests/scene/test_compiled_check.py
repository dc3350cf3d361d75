"""Scene.collision_free through the compiled core gives the answers of the kernels it replaces
(DRAKE_MH_COMPILED_CORE=0 selects them), batched and one configuration at a time, and both
report bad input alike."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidConfiguration, SceneError
from drake_mh.scene.benchmark import benchmark_scene
from drake_mh.scene.compiled_check import ENVIRONMENT, compiled_core

PANDA = drake_mh.load_robot("panda")
BUILT = importlib.util.find_spec("drake_mh._native") is not None
needs_core = pytest.mark.skipif(not BUILT, reason="the compiled core drake_mh._native is not built (pip install . builds it)")


def test_the_environment_selects_the_kernels(monkeypatch):
    monkeypatch.setenv(ENVIRONMENT, "0")
    assert compiled_core() is None
    monkeypatch.setenv(ENVIRONMENT, "1")
    assert (compiled_core() is not None) == BUILT


@needs_core
@pytest.mark.parametrize("form", ["10 mixed", "10 mixed as meshes"])
def test_scene_check_gives_the_kernels_answers(form, monkeypatch):
    compiled = benchmark_scene(PANDA, form)
    compiled.collision_free(PANDA.home)  # binds its check (the environment is read then)
    monkeypatch.setenv(ENVIRONMENT, "0")
    kernels = benchmark_scene(PANDA, form)
    Q = np.random.default_rng(7).uniform(PANDA.lower, PANDA.upper, (400, PANDA.nq))
    for clearance in (0.0, 0.03):
        expected = kernels.collision_free(Q, clearance)
        assert 0.05 < expected.mean() < 0.95
        np.testing.assert_array_equal(compiled.collision_free(Q, clearance), expected)
        np.testing.assert_array_equal(compiled.collision_free(Q.tolist(), clearance), expected)  # checked path
        for q, free in zip(Q[:60], expected[:60]):
            answer = compiled.collision_free(q, clearance)
            assert type(answer) is bool and answer == free
    assert type(compiled._free_one[1]).__name__ == "CollisionChecker"  # the compiled core answered


@needs_core
def test_scene_check_reports_bad_input_through_the_compiled_core():
    scene = benchmark_scene(PANDA, "1 sphere")
    q = PANDA.home.copy()
    assert scene.collision_free(q) in (True, False)  # binds the one-configuration entry
    q[2] = np.nan
    with pytest.raises(InvalidConfiguration):
        scene.collision_free(q)
    with pytest.raises(InvalidConfiguration):
        scene.collision_free(np.tile(q, (3, 1)))
    with pytest.raises(SceneError):
        scene.collision_free(PANDA.home.copy(), -0.1)
    assert scene.collision_free(np.empty((0, PANDA.nq))).shape == (0,)
