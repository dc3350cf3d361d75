"""The planners ``drake_kto`` and ``drake_kto_warm`` (see the package docstring)."""

from __future__ import annotations

import time

import numpy as np

from drake_mh.planning.drake_kto.kto import KTOConfig, plan_kto
from drake_mh.planning.solve import get_motion_method, prepare_motion_method

WARM_START = "rrt_connect"
"""The planner whose path warm-starts ``drake_kto_warm``."""


def _nearest(problem, goals: np.ndarray) -> int:
    return int(np.argmin(np.linalg.norm(goals - problem.q_start, axis=1)))


def plan(problem, goals, rng, deadline, budget, **options):
    """``drake_kto`` from the straight line to the nearest goal (options: :class:`KTOConfig`)."""
    config = KTOConfig.from_options(options)
    i = _nearest(problem, goals)
    path, info = plan_kto(problem, goals[i], None, deadline, budget, config)
    info["goal"] = i
    return path, info


def plan_warm(problem, goals, rng, deadline, budget, **options):
    """``drake_kto`` from the :data:`WARM_START` path (its time counts as planning time).

    Options: those of :class:`KTOConfig`, and ``warm_options`` (a dict) for the warm-start
    planner. ``budget`` goes to the solver (major iterations), not to the warm-start planner.
    """
    warm_options = dict(options.pop("warm_options", None) or {})
    config = KTOConfig.from_options(options)
    warm_plan = get_motion_method(WARM_START)
    start = time.perf_counter()
    guess, warm_info = warm_plan(problem, goals, rng, deadline, None, **warm_options)
    info = {"warm_time": time.perf_counter() - start, "warm_info": warm_info}
    if guess is None:
        info["message"] = f"{WARM_START} found no path for the warm start: {(warm_info or {}).get('message', '')}"
        return None, info
    guess = np.asarray(guess, dtype=float)
    i = int(np.argmin(np.max(np.abs(goals - guess[-1]), axis=1)))
    path, kto_info = plan_kto(problem, goals[i], guess, deadline, budget, config)
    info.update(kto_info)
    info["goal"] = i
    return path, info


def _prepare_warm(problem, warm_options=None, **_) -> None:
    """Load the warm-start planner's compiled kernels before the clock starts (its first
    compilation on a fresh machine takes minutes; a timeout measures planning), with the
    ``warm_options`` it will get."""
    prepare_motion_method(WARM_START, problem, **dict(warm_options or {}))


plan_warm.prepare = _prepare_warm
