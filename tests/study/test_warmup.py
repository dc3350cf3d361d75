"""Compiling ahead (drake_mh/study/warmup.py): ``drake-mh warmup``, and the demo's background
compilation, which never sinks the demo."""

import logging
import multiprocessing
import signal
import subprocess
import sys
import time

import pytest

from drake_mh.study import warmup


def test_a_failing_compilation_is_swallowed(caplog):
    """Logged with its traceback, not raised: the study then compiles for itself."""
    with caplog.at_level(logging.DEBUG, logger="drake_mh.study.warmup"):
        assert warmup._run(lambda: 1 / 0) is None
    assert "background compilation failed" in caplog.text and "ZeroDivisionError" in caplog.text


def test_wait_stops_a_compilation_that_runs_too_long(caplog):
    """A process that would sleep a minute is stopped (SIGTERM: a negative exit code, which a
    process left to finish would not have) and the stop is logged."""
    process = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(60,), daemon=True)
    process.start()
    with caplog.at_level(logging.WARNING, logger="drake_mh.study.warmup"):
        warmup.wait([process], timeout=0.5)
    assert not process.is_alive() and process.exitcode == -signal.SIGTERM
    assert "stopping it" in caplog.text
    warmup.wait([])  # nothing started: nothing to wait for


def test_warmup_lists_its_families_and_refuses_unknown_ones(capsys):
    from drake_mh.cli import main

    assert main(["warmup", "--list"]) == 0
    listed = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert listed == list(warmup.GROUPS) and set(warmup.FIRST_PLAN) <= set(listed)
    assert main(["warmup", "no_such_family"]) == 2
    assert "no_such_family" in capsys.readouterr().err
    assert main(["warmup", "kinematics", "--jobs", "0"]) == 2


def test_a_family_that_fails_is_reported_not_raised(monkeypatch):
    monkeypatch.setitem(warmup.GROUPS, "broken", ("always fails", lambda: 1 / 0))
    result = warmup.run_group("broken")
    assert result["group"] == "broken" and "ZeroDivisionError" in result["error"]


@pytest.mark.slow
def test_warmup_compiles_a_family_in_another_process_and_exits_0(tmp_path):
    """``drake-mh warmup kinematics`` in a new process: one family done, exit code 0."""
    done = subprocess.run([sys.executable, "-m", "drake_mh", "warmup", "kinematics", "-j", "1"], capture_output=True,
                          text=True, timeout=1800)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "[1/1] kinematics:" in done.stdout and "1/1 kernel families ready" in done.stdout
