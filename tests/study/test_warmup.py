"""The demo's background compilation (drake_mh/study/warmup.py): it never sinks the demo."""

import logging
import multiprocessing
import signal
import time

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
