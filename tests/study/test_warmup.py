"""The demo's background compilation (drake_mh/study/warmup.py): it never sinks the demo."""

import multiprocessing
import time

from drake_mh.study import warmup


def test_a_failing_compilation_is_swallowed():
    warmup._run(lambda: 1 / 0)  # logged, not raised: the study then compiles for itself


def test_wait_stops_a_compilation_that_runs_too_long():
    process = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(60,), daemon=True)
    process.start()
    start = time.monotonic()
    warmup.wait([process], timeout=0.5)
    assert not process.is_alive() and time.monotonic() - start < 20
    warmup.wait([])  # nothing started: nothing to wait for
