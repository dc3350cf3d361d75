"""studies/fk_accuracy.py compares the batched kernel with Drake itself (its quick run is in
tests/study/test_quick_studies.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_mh.robot import Robot
from drake_mh.study import Case, load_study

STUDY = Path(__file__).resolve().parents[2] / "studies" / "fk_accuracy.py"


def _case(robot: str) -> Case:
    return Case(params={"robot": robot, "rep": 0}, key=f"robot={robot}/rep=0", case_id="test", seed=1,
                instance_seed=2, quick=True)


def test_the_reference_is_drake(monkeypatch):
    """A difference planted in Drake's answers (1 mm on the position, 1e-3 on every Jacobian
    entry) shows in the study's figures and fails the case: the reference is Drake's plant, not
    another compiled kernel (Robot.fk is one)."""
    study, _ = load_study(STUDY)
    clean = study.run(_case("planar2r"))
    assert clean["success"] and clean["error"] < 1e-12
    fk_drake, jacobian_drake = Robot.fk_drake, Robot.jacobian_drake

    def shifted_fk(self, q, frame=None):
        X = fk_drake(self, q, frame).copy()
        X[:3, 3] += 1e-3
        return X

    monkeypatch.setattr(Robot, "fk_drake", shifted_fk)
    monkeypatch.setattr(Robot, "jacobian_drake", lambda self, q, frame=None: jacobian_drake(self, q, frame) + 1e-3)
    planted = study.run(_case("planar2r"))
    assert not planted["success"]
    assert np.isclose(planted["position_error"], 1e-3, atol=1e-12)
    assert np.isclose(planted["jacobian_error"], 1e-3, atol=1e-12)
