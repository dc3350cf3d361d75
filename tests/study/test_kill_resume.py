"""A real `drake-mh study` process killed with SIGKILL mid-study, then run again."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from drake_mh.study import run_study

from study_toys import comparable, write_toy

pytestmark = pytest.mark.slow


def _lines(path):
    return path.read_text().splitlines() if path.exists() else []


def _workers_exit_by_themselves(group: int, wait: float = 15.0) -> bool:
    """Whether every process of the killed run's session is gone within ``wait`` seconds."""
    deadline = time.monotonic() + wait
    while time.monotonic() < deadline:
        try:
            os.killpg(group, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.1)
    try:
        os.killpg(group, signal.SIGKILL)  # clean up before failing
    except ProcessLookupError:
        pass
    return False


def test_sigkill_mid_study_loses_and_repeats_nothing(tmp_path):
    study = write_toy(tmp_path, sleep=0.15, reps=5)  # 30 cases
    out = tmp_path / "out"
    command = [sys.executable, "-m", "drake_mh", "study", str(study), "--workers", "2", "--out", str(out), "--quiet"]
    env = {**os.environ, "DRAKE_MH_NO_PROGRESS": "1"}
    process = subprocess.Popen(command, env=env, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    records = out / "records.jsonl"
    deadline = time.monotonic() + 60
    while len(_lines(records)) < 6 and time.monotonic() < deadline:
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait(timeout=10)
    assert _workers_exit_by_themselves(process.pid), "orphaned workers still running 15 s after the kill"
    before = _lines(records)
    assert process.returncode == -signal.SIGKILL
    assert 6 <= len(before) < 30, "the kill should land mid-study"

    finished = subprocess.run(command, env=env, capture_output=True, text=True, timeout=120)
    assert finished.returncode == 0, finished.stderr
    after = _lines(records)
    # the records from before the kill are kept unchanged, none repeated, none lost
    complete_before = [line for line in before if line.endswith("}")]
    assert after[: len(complete_before)] == complete_before
    keys = [json.loads(line)["key"] for line in after]
    assert len(keys) == 30 and len(set(keys)) == 30

    reference = run_study(study, out=tmp_path / "reference", workers=0, report=False)
    resumed = [json.loads(line) for line in after]
    assert comparable(resumed) == comparable(reference.records)
    assert (out / "index.html").is_file()
