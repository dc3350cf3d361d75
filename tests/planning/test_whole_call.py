"""studies/whole_call.py: its record of one call (the parts of the verification) and its
before/after mode (the quick run itself is in tests/study/test_quick_studies.py)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

from drake_mh.planning.verify import VERIFY_PARTS
from drake_mh.study import load_study

STUDY = Path(__file__).resolve().parents[2] / "studies" / "whole_call.py"


def _module():
    study, _ = load_study(STUDY)
    return sys.modules[study.run.__module__]


def test_a_record_splits_the_verification_into_its_parts(monkeypatch):
    monkeypatch.delenv("DRAKE_MH_MBM_ARCHIVE", raising=False)
    module = _module()
    assert tuple(module.PARTS) == VERIFY_PARTS  # the study names the parts the library times
    for retime in ("toppra", "ruckig", "none"):
        record = module.measure("panda", "table_pick", 0, retime, count=1)
        assert record["success"], record["message"]
        parts = [record[p] for p in VERIFY_PARTS]
        assert all(p >= 0 for p in parts)
        assert sum(parts) <= record["verify"] <= record["total"]
        assert record["search"] <= record["total"]
        if retime == "none":
            assert record["retimer"] is None and parts[1:] == [0.0, 0.0, 0.0]
        else:
            assert record["retimer"] == retime and parts[1] > 0 and parts[2] > 0


@pytest.mark.slow
def test_before_and_after_of_one_checkout_run_the_same_problems(monkeypatch):
    monkeypatch.delenv("DRAKE_MH_MBM_ARCHIVE", raising=False)
    module = _module()
    table = module.compare(str(STUDY.parents[1]), problems=1)
    for name in module.GENERATED:
        for label in ("before", "after"):
            assert re.search(rf"\| panda \| {name} \| {label} \| 1/1 \|", table), table
    assert re.search(r"\| all \| all \| after \| 3/3 \|", table), table
