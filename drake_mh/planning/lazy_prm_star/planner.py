"""``lazy_prm_star``: the Python side of the compiled informed lazy PRM* (:mod:`.search`).

:func:`plan` starts from ``rrt_connect``'s certified path (``warm_start``), then calls
:func:`.search.prm_kernel`, which improves it batch by batch until the sample budget or the
deadline. :func:`prepare` compiles (or loads) both planners' kernels before any clock starts.
"""

from __future__ import annotations

import dataclasses
import numbers
import time

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.planning.lazy_prm_star import search as K
from drake_mh.planning.motion import clock_address, scene_arguments
from drake_mh.planning.motion import stats as S
from drake_mh.planning.rrt_connect import planner as rrt

_CLOCK = clock_address()

DEFAULT_SAMPLES = 1000
"""Samples drawn (the budget) when ``solve_motion``'s ``budget`` is None: the search then ends
by this budget or by the deadline, whichever comes first."""

_CHECK = rrt.RRTConnectConfig()  # the motion check's defaults, shared with rrt_connect
_SHARED = ("shortcut_iterations", "shortcut_min_gain", "resolution", "margin", "lanes", "block", "probes",
           "interior_probes", "max_certify_evaluations")
"""Options named and checked as ``rrt_connect``'s (:class:`~drake_mh.planning.rrt_connect.RRTConnectConfig`)."""


@dataclasses.dataclass(frozen=True)
class LazyPRMStarConfig:
    """Options of ``lazy_prm_star`` (``solve_motion`` keywords; ``budget``: samples drawn).

    Attributes:
        batch: samples drawn per batch (each batch: free samples join the graph, the graph is
            rebuilt and searched).
        k_scale: neighbours per node as a multiple of PRM*'s ``e (1 + 1/d) log n`` (Karaman &
            Frazzoli 2011; below 1 the asymptotic optimality is lost).
        warm_start: start from ``rrt_connect``'s path (its time counts, within the deadline, and
            it adds at most as many tree nodes as the sample budget): the informed sampling
            then begins at once; without it, samples are uniform until the graph holds a path.
        shortcut_iterations, shortcut_min_gain: random shortcuts of each new shortest path of the
            graph before it is compared with the best (as ``rrt_connect``'s shortcut).
        resolution, margin, lanes, block, probes, interior_probes, max_certify_evaluations: the
            motion check's (:class:`~drake_mh.planning.rrt_connect.RRTConnectConfig`).
    """

    batch: int = 100
    k_scale: float = 1.0
    warm_start: bool = True
    shortcut_iterations: int = 64
    shortcut_min_gain: float = 0.005
    resolution: float = _CHECK.resolution
    margin: float = _CHECK.margin
    lanes: int = _CHECK.lanes
    block: int = _CHECK.block
    probes: int = _CHECK.probes
    interior_probes: int = _CHECK.interior_probes
    max_certify_evaluations: int = _CHECK.max_certify_evaluations

    def __post_init__(self):
        if isinstance(self.k_scale, bool) or not isinstance(self.k_scale, numbers.Real) \
                or not np.isfinite(self.k_scale) or self.k_scale <= 0:
            raise InvalidArgument(f"lazy_prm_star: k_scale must be a finite number > 0, got {self.k_scale!r}")
        if isinstance(self.batch, bool) or not isinstance(self.batch, numbers.Integral) or self.batch < 1:
            raise InvalidArgument(f"lazy_prm_star: batch must be an integer >= 1, got {self.batch!r}")
        if not isinstance(self.warm_start, bool):
            raise InvalidArgument(f"lazy_prm_star: warm_start must be True or False, got {self.warm_start!r}")
        try:  # the options shared with rrt_connect: validated by its config, its checks not written twice
            rrt.RRTConnectConfig.from_options({name: getattr(self, name) for name in _SHARED})
        except InvalidArgument as error:
            raise InvalidArgument(str(error).replace("rrt_connect:", "lazy_prm_star:", 1)) from None

    def vector(self) -> np.ndarray:
        """The kernel's ``options`` (:data:`.search.OPTION_NAMES`)."""
        values = {**dataclasses.asdict(self), "clock": _CLOCK}
        return np.array([float(values[name]) for name in K.OPTION_NAMES])

    @classmethod
    def from_options(cls, options: dict) -> "LazyPRMStarConfig":
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(options) - names)
        if unknown:
            raise InvalidArgument(f"lazy_prm_star: unknown option(s) {unknown}; options are {sorted(names)}")
        return cls(**options)


_PREPARED = False
#: (name, index) of the counts in ``info``: the search's, and those the motion check adds to
_COUNTS = tuple((name, S.STAT_NAMES.index(name)) for name in (
    "motions", "states", "certified_by_margin", "refined", "refine_evals", "rejected", "rejected_by_probes",
    "shortcuts_tried", "shortcuts_kept")) + tuple((name, len(S.STAT_NAMES) + i)
                                                  for i, name in enumerate(K.PRM_STAT_NAMES))


def prepare(problem, **options) -> float:
    """Bind the problem's scene and, where the numba kernels are the ones called (no compiled
    core, or ``DRAKE_MH_COMPILED_CORE=0``), compile or load ``rrt_connect``'s kernel and this one
    (once per process); seconds taken. From an empty numba cache this kernel compiles in about
    3.5 minutes, from the cache it loads in about 0.15 s; the compiled core compiles nothing."""
    global _PREPARED
    start = time.perf_counter()
    rrt.prepare(problem)
    if not _PREPARED and rrt.compiled_planner(problem.scene) is None:  # (the compiled core compiles nothing)
        _kernel_call(problem, problem.q_start[None], np.empty((0, len(problem.q_start))), 0, 0, 1, 1.0,
                     LazyPRMStarConfig(batch=1, shortcut_iterations=0))
        _PREPARED = True
    return time.perf_counter() - start


def _kernel_call(problem, goals, init_path, init_goal, seed, samples, time_limit, config):
    ints, floats, v_WO, reach, lower, upper = scene_arguments(problem.scene)
    stats = np.zeros(K.N_STATS)
    native = rrt.compiled_planner(problem.scene)
    if native is not None:  # the compiled core: the same search, nothing compiled at call time
        path, outcome, goal = native.prm(
            np.ascontiguousarray(problem.q_start, dtype=float), np.ascontiguousarray(goals, dtype=float),
            np.ascontiguousarray(init_path, dtype=float).reshape(-1, len(problem.q_start)), int(init_goal), lower,
            upper, float(problem.clearance), float(problem.self_clearance), int(seed) % 2**64, int(samples),
            float(time_limit), config.vector(), stats)
        return path, outcome, int(goal), stats
    path, outcome, goal = K.prm_kernel(
        np.ascontiguousarray(problem.q_start, dtype=float), np.ascontiguousarray(goals, dtype=float),
        np.ascontiguousarray(init_path, dtype=float), int(init_goal), lower, upper, ints, floats, v_WO, reach,
        float(problem.clearance), float(problem.self_clearance), np.uint64(seed), int(samples), float(time_limit),
        config.vector(), stats)
    return path, outcome, int(goal), stats


def plan(problem, goals, rng, deadline, budget, **options):
    """Informed lazy PRM* from ``problem.q_start`` to any row of ``goals`` (module docstring of
    :mod:`drake_mh.planning.lazy_prm_star`); ``budget``: samples drawn (default
    :data:`DEFAULT_SAMPLES`)."""
    config = LazyPRMStarConfig.from_options(options)
    begin = time.perf_counter()
    prepare_time = prepare(problem) if not _PREPARED else 0.0
    limit = (lambda: np.inf) if deadline is None else (lambda: deadline + prepare_time - time.perf_counter())
    samples = DEFAULT_SAMPLES if budget is None else budget
    init, init_goal, warm_info = np.empty((0, goals.shape[1])), 0, {}
    if config.warm_start:  # bounded by the budget too (tree nodes), not only by the deadline
        path, warm_info = rrt.plan(problem, goals, rng, None if deadline is None else deadline + prepare_time,
                                   samples)
        if path is not None:
            init, init_goal = path, warm_info["goal"]
    warm_time = time.perf_counter() - begin - prepare_time
    seed = rng.bit_generator.random_raw()
    path, outcome, goal, stats = _kernel_call(problem, goals, init, init_goal, seed, samples, limit(), config)
    info = {name: int(stats[i]) for name, i in _COUNTS}
    found = len(init) > 0 or stats[S.T_FOUND] > 0
    # (numpy, not the kernel's _length: a first call of a numba function from Python loads it, ~2 ms in the clock)
    warm_length = float(np.linalg.norm(np.diff(init, axis=0), axis=1).sum()) if len(init) else float("nan")
    info.update(warm_start_time=warm_time, warm_start_length=warm_length,
                t_first=(warm_time if len(init) else warm_time + stats[S.T_FOUND]) if found else float("nan"),
                t_search=stats[S.T_TOTAL], prepare_time=prepare_time)
    if outcome == S.FOUND:
        info["goal"] = goal
        return path, info
    why = "budget" if outcome == S.BUDGET else "timeout"
    info["message"] = (f"no path: {why} reached after {info['samples']} samples ({info['free_samples']} free) and "
                       f"{info['edges_checked']} edges checked"
                       + ("" if not config.warm_start else f"; the warm start found none ({warm_info.get('message')})"))
    return None, info
