"""Registration of ``drake_kto`` and ``drake_kto_warm`` (see the package docstring)."""

from __future__ import annotations

import importlib
import pkgutil
import time

import numpy as np

from drake_mh.planning.drake_kto.kto import KTOConfig, plan_kto
from drake_mh.planning.solve import register

WARM_START = "rrt_connect"
"""The planner whose path warm-starts ``drake_kto_warm``."""


def _nearest(problem, goals: np.ndarray) -> int:
    return int(np.argmin(np.linalg.norm(goals - problem.q_start, axis=1)))


@register("drake_kto", "Drake KinematicTrajectoryOptimization + SNOPT (B-spline, 10 control points, "
                       "minimum distance at 25 samples) from the straight line to the nearest goal")
def plan(problem, goals, rng, deadline, budget, **options):
    config = KTOConfig.from_options(options)
    i = _nearest(problem, goals)
    path, info = plan_kto(problem, goals[i], None, deadline, budget, config)
    info["goal"] = i
    return path, info


def _registry() -> dict:
    from drake_mh.planning import solve

    return solve._METHODS


def _warm_start_registered() -> bool:
    """Whether a method named :data:`WARM_START` is registered, importing the sibling planner
    modules first (``solve_motion`` imports them all anyway; the order is alphabetical)."""
    import drake_mh.planning as package
    from drake_mh.planning import solve

    if WARM_START not in _registry():
        for module in pkgutil.iter_modules(package.__path__):
            if module.name in solve._CORE or module.name.startswith("_") or module.name == "drake_kto":
                continue
            try:
                importlib.import_module(f"drake_mh.planning.{module.name}")
            except ImportError:  # an optional peer that cannot be imported registers nothing
                continue
    return WARM_START in _registry()


def plan_warm(problem, goals, rng, deadline, budget, **options):
    """``drake_kto`` from the :data:`WARM_START` path (its time counts as planning time).

    Options: those of :class:`KTOConfig`, and ``warm_options`` (a dict) for the warm-start
    planner. ``budget`` goes to the solver (major iterations), not to the warm-start planner.
    """
    warm_options = dict(options.pop("warm_options", None) or {})
    config = KTOConfig.from_options(options)
    warm_plan = _registry()[WARM_START][0]
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
    from drake_mh.planning.solve import prepare_motion_method

    prepare_motion_method(_registry()[WARM_START][0], problem, **dict(warm_options or {}))


plan_warm.prepare = _prepare_warm

if _warm_start_registered():
    register("drake_kto_warm", "drake_kto warm-started from the rrt_connect path (its time included)")(plan_warm)
