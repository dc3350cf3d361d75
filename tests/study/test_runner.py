import json

import pytest

from drake_mh.errors import InvalidArgument, ResultsMismatch, UnknownStudy
from drake_mh.study import load_study, run_study

from study_toys import comparable, write_toy


def test_runs_every_case_records_errors_and_reports(toy, tmp_path):
    result = run_study(toy, out=tmp_path / "out", workers=0)
    assert result.complete and result.n_cases == 24 and result.n_new == 24
    assert result.n_errors == 2
    raised = [r for r in result.records if r["status"] == "error"]
    assert {r["exception_type"] for r in raised} == {"ValueError"}
    assert all(r["exception"] == "boom on purpose" for r in raised)
    assert "Traceback" in raised[0]["traceback"]
    ok = [r for r in result.records if r["status"] == "ok"]
    assert all(r["arrays"].startswith("arrays/") for r in ok)
    assert result.summary == "toy summary: 24 records"
    assert (tmp_path / "out" / "summary.md").read_text() == result.summary
    assert result.report.name == "index.html" and result.report.is_file()


def test_every_record_carries_the_machine_beside_its_timing(toy, tmp_path):
    from drake_mh.study.machine import cpu_model, machine_line

    result = run_study(toy, out=tmp_path / "out", workers=0)
    for r in result.records:  # the cases that raised too
        assert 0.0 <= r["case_cpu_time"] <= r["wall_time"] * 1.5 + 0.05
        assert r["case_cpu_model"] == cpu_model() and r["case_load_average"] >= 0.0
    line = machine_line(result.records)
    assert line.startswith(f"Machine: {cpu_model()}; 1-minute load average") and "(24 of 24 records)" in line
    assert line in (tmp_path / "out" / "report.md").read_text()
    assert machine_line([{"key": "older record, no machine fields"}]) == ""


def test_results_do_not_depend_on_worker_count(toy, tmp_path):
    serial = run_study(toy, out=tmp_path / "serial", workers=0, report=False)
    parallel = run_study(toy, out=tmp_path / "parallel", workers=2, report=False)
    assert comparable(serial.records) == comparable(parallel.records)
    # different study seed: different draws, same instance/method structure
    other = run_study(toy, out=tmp_path / "other", workers=0, seed=11, report=False)
    assert comparable(other.records) != comparable(serial.records)


def test_first_by_runs_every_cell_once_before_any_second_replicate(toy, tmp_path):
    order = []
    first = run_study(toy, out=tmp_path / "first", workers=0, report=False, first_by="rep",
                      on_record=lambda r: order.append(r["rep"]))
    assert order == sorted(order) and order[0] == 0 and order[-1] == 3       # 6 cells x 4 replicates
    grid = run_study(toy, out=tmp_path / "grid", workers=0, report=False)
    assert comparable(first.records) == comparable(grid.records)           # the order changes nothing else
    with pytest.raises(InvalidArgument, match="first_by"):
        run_study(toy, out=tmp_path / "bad", workers=0, report=False, first_by="nope")


def test_instance_draws_are_shared_by_methods(toy, tmp_path):
    result = run_study(toy, out=tmp_path / "o", workers=0, report=False)
    by_block = {}
    for r in result.records:
        if r["status"] == "ok":
            by_block.setdefault((r["inst"], r["rep"]), set()).add(r["x"])
    assert all(len(xs) == 1 for xs in by_block.values())


def test_resume_after_interrupt_repeats_nothing(toy, tmp_path):
    out = tmp_path / "out"
    seen = []

    def stop_after_five(record):
        seen.append(record["key"])
        if len(seen) == 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(toy, out=out, workers=0, on_record=stop_after_five, report=False)
    again = []
    result = run_study(toy, out=out, workers=0, on_record=lambda r: again.append(r["key"]), report=False)
    assert result.complete and result.n_new == 19
    assert not set(seen) & set(again)
    lines = (out / "records.jsonl").read_text().splitlines()
    assert len(lines) == 24 and len({json.loads(line)["key"] for line in lines}) == 24
    reference = run_study(toy, out=tmp_path / "ref", workers=0, report=False)
    assert comparable(result.records) == comparable(reference.records)


def test_rerun_of_finished_study_runs_nothing(toy, tmp_path):
    run_study(toy, out=tmp_path / "o", workers=0, report=False)
    result = run_study(toy, out=tmp_path / "o", workers=0, report=False)
    assert result.n_new == 0 and result.complete


def test_other_settings_in_same_folder_are_refused(toy, tmp_path):
    run_study(toy, out=tmp_path / "o", workers=0, report=False, quick=True)
    with pytest.raises(ResultsMismatch, match="--out"):
        run_study(toy, out=tmp_path / "o", workers=0, report=False)
    with pytest.raises(ResultsMismatch):
        run_study(toy, out=tmp_path / "o", workers=0, report=False, quick=True, seed=9)


def test_quick_grid_and_default_folder(toy, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run_study(toy, quick=True, workers=0, report=False)
    assert result.n_cases == 4
    assert result.folder.as_posix() == "results/toy-quick"


def test_load_by_name_from_studies_env(tmp_path, monkeypatch):
    folder = tmp_path / "mystudies"
    folder.mkdir()
    write_toy(folder, name="toy_by_name.py")
    monkeypatch.setenv("DRAKE_MH_STUDIES", str(folder))
    study, source = load_study("toy_by_name")
    assert study.name == "toy" and source.path.endswith("toy_by_name.py")
    with pytest.raises(UnknownStudy, match="toy_by_name"):
        load_study("no_such_study")


def test_study_object_and_bad_arguments(toy, tmp_path):
    study, _ = load_study(toy)
    result = run_study(study, out=tmp_path / "o", workers=2, report=False, quick=True)
    assert result.complete
    with pytest.raises(InvalidArgument, match="dask://"):
        run_study(study, out=tmp_path / "p", executor="carrier-pigeon", report=False)
    with pytest.raises(InvalidArgument, match="workers"):
        run_study(study, out=tmp_path / "q", workers=-2, report=False)


def test_bad_return_value_is_recorded_not_raised(tmp_path):
    path = tmp_path / "odd.py"
    path.write_text(
        "from drake_mh.study import Study\n"
        "def run(case):\n"
        "    return {'ok': 1} if case['i'] else {'obj': object()}\n"
        "study = Study(name='odd', run=run, grid={'i': [0, 1]})\n"
    )
    result = run_study(path, out=tmp_path / "o", workers=0)
    status = {r["i"]: r["status"] for r in result.records}
    assert status == {0: "error", 1: "ok"}
    assert "obj" in result.records[0]["exception"]


def test_a_case_that_kills_its_worker_is_isolated_and_recorded(tmp_path):
    path = tmp_path / "crash.py"
    path.write_text(
        "import os, time\n"
        "from drake_mh.study import Study\n"
        "def run(case):\n"
        "    time.sleep(0.05)\n"
        "    if case['i'] == 3:\n"
        "        os._exit(3)  # like a C++ abort in Drake\n"
        "    return {'error': float(case['i'])}\n"
        "study = Study(name='crash', run=run, grid={'i': list(range(8))})\n"
    )
    result = run_study(path, out=tmp_path / "o", workers=2, report=False)
    assert result.complete
    raised = {r["i"]: r["exception_type"] for r in result.records if r["status"] == "error"}
    assert raised == {3: "WorkerDied"}


def test_worker_processes_use_one_blas_thread(monkeypatch):
    import os

    from drake_mh.study.executors import BLAS_THREAD_VARIABLES, open_executor

    for name in BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("MKL_NUM_THREADS", "3")                       # a user's choice is kept
    with open_executor("local", 1) as (pool, _):
        seen = pool.submit(os.getenv, "OPENBLAS_NUM_THREADS").result(), pool.submit(os.getenv, "MKL_NUM_THREADS").result()
    assert seen == ("1", "3")
    assert "OPENBLAS_NUM_THREADS" not in os.environ                    # the parent's environment is restored


def test_unstorable_result_is_that_cases_error_and_the_study_goes_on(tmp_path):
    path = tmp_path / "dates.py"
    path.write_text(
        "import numpy as np\n"
        "from drake_mh.study import Study\n"
        "def run(case):\n"
        "    if case['i'] == 1:\n"
        "        return {'when': np.datetime64('2026-01-01')}\n"
        "    return {'value': float(case['i'])}\n"
        "study = Study(name='dates', run=run, grid={'i': range(3)})\n")
    result = run_study(path, out=tmp_path / "out", workers=0, report=False)
    assert result.complete and result.n_errors == 1
    bad = [r for r in result.records if r["status"] == "error"][0]
    assert bad["i"] == 1 and "datetime64" in bad["exception"]
    again = run_study(path, out=tmp_path / "out", workers=0, report=False)   # a re-run works too
    assert again.n_new == 0 and again.complete


def test_second_run_into_the_same_folder_is_refused(toy, tmp_path):
    from drake_mh.errors import ResultsLocked
    from drake_mh.study.store import RecordStore

    holder = RecordStore(tmp_path / "out")
    holder.prepare({"name": "toy"})            # another process writing (same lock)
    with pytest.raises(ResultsLocked):
        run_study(toy, out=tmp_path / "out", workers=0, report=False)
    holder.close()
