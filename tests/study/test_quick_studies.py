"""Every study in studies/ runs in quick mode without a case raising (what CI runs)."""

from __future__ import annotations

from pathlib import Path

import pytest

from drake_mh.study import load_study, run_study

STUDIES = sorted(p for p in (Path(__file__).resolve().parents[2] / "studies").glob("*.py") if not p.name.startswith("_"))


@pytest.mark.slow
@pytest.mark.parametrize("path", STUDIES, ids=[p.stem for p in STUDIES])
def test_study_runs_in_quick_mode(path, tmp_path, monkeypatch):
    # first_call compiles each family twice from empty caches: a small family shows the study runs
    monkeypatch.setenv("DRAKE_MH_FIRST_CALL_GROUPS", "kinematics")
    study, source = load_study(path)
    result = run_study(study, source=source, quick=True, out=tmp_path / study.name, workers=2)
    assert result.complete
    failures = [(r["key"], r.get("exception_type"), r.get("exception")) for r in result.records if r["status"] == "error"]
    assert not failures, failures
    assert result.report is not None and result.report.is_file()


@pytest.mark.parametrize("path", STUDIES, ids=[p.stem for p in STUDIES])
def test_study_runs_as_a_script(path):
    """``python studies/NAME.py`` hands the study to the shell's runner (its ``__main__`` block)."""
    text = path.read_text()
    assert 'if __name__ == "__main__":' in text, "no __main__ block"
    assert "run_script(study)" in text.split('if __name__ == "__main__":', 1)[1]
