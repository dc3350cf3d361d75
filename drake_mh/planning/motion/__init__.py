"""What the compiled planners share: the certified motion check, the clock, the statistics.

* :mod:`.check` — the certified straight-line motion check (probes, batched state checks, the
  certificate where a state is near);
* :mod:`.clock` — a monotonic clock read inside compiled code (deadlines without returning to
  Python);
* :mod:`.stats` — the statistics array the kernels add to.
"""
