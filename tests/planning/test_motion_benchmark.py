"""studies/motion_benchmark.py: its grid and its summary on synthetic records (the quick run
itself is in tests/study/test_quick_studies.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_mh.study import load_study

STUDY = Path(__file__).resolve().parents[2] / "studies" / "motion_benchmark.py"


def _module():
    study, _ = load_study(STUDY)
    import sys

    return study, sys.modules[study.run.__module__]


def _record(method, problem, success, time, robot="panda", name="cage"):
    return {"status": "ok", "robot": robot, "set": name, "problem": problem, "rep": 0, "method": method,
            "success": success, "time": time, "cpu": time / 2, "error": time if success else float("nan"),
            "path_length": 3.0 + problem, "path_length_verified": 3.0 + problem if success else float("nan"),
            "duration": 2.0, "min_clearance": 0.004, "max_jerk": 100.0, "obstacles": 8,
            "straight_free": problem == 0, "joint_distance": 2.5, "load_average": 1.5, "cpu_model": "test CPU",
            "timeout": 10.0}


def test_grids_interleave_methods_per_problem(monkeypatch):
    study, module = _module()
    quick = study.cases(quick=True)
    assert {c["set"] for c in quick} == {"table_pick"} and quick[0]["method"] == "straight"
    full = study.cases(quick=False)
    methods = module._methods()
    first = full[:len(methods)]
    assert [c["method"] for c in first] == methods and len({(c["set"], c["problem"]) for c in first}) == 1
    monkeypatch.setenv("DRAKE_MH_MOTION_METHODS", "straight,nope,rrt_connect")
    monkeypatch.setenv("DRAKE_MH_MOTION_PROBLEMS", "2")
    grid = module._grid(quick=False)
    assert {c["method"] for c in grid} <= {"straight", "rrt_connect"} and max(c["problem"] for c in grid) == 1


def test_summary_tables_ranks_and_anchors():
    _, module = _module()
    records = []
    for problem in range(4):
        records += [_record("straight", problem, problem == 0, 1e-4),
                    {**_record("rrt_connect", problem, True, 0.002), "shortcut_cpu": 2e-4 * (problem + 1)},
                    _record("mh_pso", problem, problem != 1, 1.5)]
    text = module.summarize(records)
    # cpu 1 ms each, shortcuts 0.2 ... 0.8 ms: medians 0.5 ms of shortcut, 0.5 ms to the first path
    assert "- `rrt_connect`: to the first certified path (CPU time minus the shortcut) median 0.50 ms" in text
    assert "the shortcut median 0.50 ms" in text and "`mh_pso`: to the first" not in text
    assert "test CPU" in text and "load average 1.50-1.50" in text
    assert "| cage | 4 | 8.0 | 75 |" in text  # one problem of four has a free straight line
    assert "| rrt_connect | 100 (4/4) |" in text and "| straight | 25 (1/4) |" in text
    assert "Time to a verified motion: 4 blocks" in text and "Friedman chi2" in text
    assert "| rrt_connect | 1.25 | (best) |" in text  # ranks 2, 1, 1, 1
    assert "VAMP" in text and "cuRobo" in text
    assert module.summarize([]) == "no finished case"
    assert np.isnan(module.median([float("nan")]))


def test_scene_files_join_the_grids(monkeypatch):
    _, module = _module()
    cell = Path(__file__).resolve().parents[1] / "data" / "scenes" / "cell.sdf"
    monkeypatch.setenv("DRAKE_MH_MOTION_SCENES", f"{cell}, {cell.with_name('cell.yaml')}")
    monkeypatch.setenv("DRAKE_MH_MOTION_METHODS", "straight")
    monkeypatch.setenv("DRAKE_MH_MOTION_PROBLEMS", "1")
    full = module._grid(quick=False)
    assert {c["set"] for c in full} >= {"file/cell.sdf", "file/cell.yaml", "table_pick"}
    assert module._scene_files()["file/cell.yaml"] == str(cell.with_name("cell.yaml"))
    assert {c["set"] for c in module._grid(quick=True)} == {"table_pick", "file/cell.sdf"}
