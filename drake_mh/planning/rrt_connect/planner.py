"""``rrt_connect`` and ``rrt_connect_smooth``: the Python side of the compiled planner.

:func:`plan` reads the problem, binds the scene's compiled arrays (once per obstacle set),
and makes one call that plans, certifies and shortcuts: into the compiled core's
``MotionPlanner`` (C++, ``cpp/rrt_connect.hpp``: the same draws and checks, so the same path for
the same seed, and nothing compiled at call time) where it is built
(:func:`drake_mh.scene.compiled_check.compiled_core`, ``DRAKE_MH_COMPILED_CORE=0`` leaves it
out) and ``certify`` is ``"boolean"``, else into the numba kernel :func:`.search.plan_kernel`.
:func:`prepare` compiles (or loads from numba's cache) that kernel once per process where it
is the one called, so that no planning clock counts it.
"""

from __future__ import annotations

import dataclasses
import numbers
import time

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.planning.motion import PROBES, clock_address, scene_arguments
from drake_mh.planning.motion import stats as S
from drake_mh.planning.rrt_connect import search as K
from drake_mh.scene.compiled_check import compiled_core

_CLOCK = clock_address()

DEFAULT_MAX_NODES = 200_000
"""Tree nodes when neither ``budget`` nor a deadline bounds a run (a blocked goal then fails
after this many nodes instead of running forever)."""


@dataclasses.dataclass(frozen=True)
class RRTConnectConfig:
    """Options of ``rrt_connect`` (``solve_motion`` keywords).

    Defaults chosen on MotionBenchMaker's Panda problems by paired median plan time; the figure
    that set each is in docs/planning.md, the measurements in docs/benchmarks.md.

    Attributes:
        step: [rad] longest tree edge (EXTEND's range, Euclidean in joint space); 1.5 with the
            dynamic domain (0.915x the plan time of 1.0 without it).
        domain_radius: [rad] dynamic domain (Yershova et al., ICRA 2005; 0: off;
            :func:`.search.plan_kernel`): a node whose extension failed takes this radius, and
            a sample beyond its nearest node's radius is drawn again without a check. VAMP's
            value for the Panda.
        resolution: [states per rad] checked along a motion, at least (more where ``margin``
            needs them).
        margin: [m] largest extra clearance the batched check asks of a motion's states so
            that the motion between them is certified with no further work (states are
            added while ``Λ_c / 2n`` exceeds it, see :func:`drake_mh.planning.motion.check.certified_motion`); a motion
            that passes within its margins is refined (``certify``).
        probes: states of a motion checked first, before any of its setup, at the plain
            clearances (0-8; t = 1, 1/2, 1/4, 1/8, ...: :data:`drake_mh.planning.motion.check.PROBES`): they stop
            97 % of the motions that collide. They only reject; the motion's own states
            certify.
        interior_probes: the same for a motion whose two ends are known free (the direct motion
            to a goal, a motion that ends on a tree node, a shortcut between two points of the
            certified path): states inside it, middle first (0-8; t = 1/2, 1/4, 3/4, 1/8, ...:
            :data:`drake_mh.planning.motion.check.INTERIOR_PROBES`).
        lanes: states of a motion checked next, in one batched call, spread along it (VAMP's
            "rake": a collision that the probes missed is mostly found there).
        block: states per batched call after the first.
        certify: how a motion within its margins is certified: ``"boolean"`` (conservative
            advancement on the values that the batched check reports for the rows below their
            margins) or ``"bisection"`` (the scene's
            :func:`drake_mh.scene.segments.certify_segments` on clearance values). Each is a
            compiled variant of the kernel: the first ``"bisection"`` plan of a machine compiles
            its own (cached on disk after). ``"bisection"`` always runs in the numba kernel;
            ``"boolean"`` in the compiled core where it is built.
        goal_bias: probability of sampling a root of the other tree (a goal configuration when
            the start tree grows, the start when the goal tree grows) instead of a uniform
            sample.
        balance: grow the smaller tree next (VAMP), else alternate (Kuffner & LaValle).
        shortcut_iterations: random shortcut draws on the found path (0: none): two random
            points of the path, joined by a certified straight motion when it is shorter
            (Geraerts & Overmars, IJRR 2007).
        shortcut_min_gain: a draw is checked only if its straight motion would shorten the path
            by at least this fraction of the path's length (0: every draw). Shortcuts that save
            little mostly hug the path, so most of them are certified, the expensive answer.
        max_certify_evaluations: most configurations the refinement may evaluate for one
            motion before it counts as not certified.
        profile: time sampling, nearest neighbours, checks, certification and shortcutting
            inside the kernel (``info["t_sample"]`` ... ``info["t_shortcut"]``, seconds).

    Raises:
        InvalidArgument: an option of the wrong type or range (the message names it).
    """

    step: float = 1.5
    resolution: float = 16.0
    margin: float = 0.02
    probes: int = 4
    interior_probes: int = 4
    lanes: int = 64
    block: int = 64
    certify: str = "boolean"
    goal_bias: float = 0.05
    balance: bool = True
    shortcut_iterations: int = 32
    shortcut_min_gain: float = 0.05
    max_certify_evaluations: int = 4096
    profile: bool = False
    domain_radius: float = 4.0

    def __post_init__(self):
        for name in ("step", "resolution", "margin"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not np.isfinite(value) or value <= 0:
                raise InvalidArgument(f"rrt_connect: {name} must be a finite number > 0, got {value!r}")
        if isinstance(self.domain_radius, bool) or not isinstance(self.domain_radius, numbers.Real) \
                or not 0.0 <= self.domain_radius < np.inf:
            raise InvalidArgument(f"rrt_connect: domain_radius must be a finite number >= 0 (0: no dynamic domain), "
                                  f"got {self.domain_radius!r}")
        if isinstance(self.shortcut_min_gain, bool) or not isinstance(self.shortcut_min_gain, numbers.Real) \
                or not 0.0 <= self.shortcut_min_gain < 1.0:
            raise InvalidArgument(f"rrt_connect: shortcut_min_gain must be in [0, 1), got {self.shortcut_min_gain!r}")
        if self.certify not in ("boolean", "bisection"):
            raise InvalidArgument(f"rrt_connect: certify must be 'boolean' or 'bisection', got {self.certify!r}")
        if isinstance(self.goal_bias, bool) or not isinstance(self.goal_bias, numbers.Real) \
                or not 0.0 <= self.goal_bias <= 1.0:
            raise InvalidArgument(f"rrt_connect: goal_bias must be in [0, 1], got {self.goal_bias!r}")
        for name, least, most in (("shortcut_iterations", 0, None), ("max_certify_evaluations", 2, None),
                                  ("lanes", 1, None), ("block", 1, None), ("probes", 0, len(PROBES)),
                                  ("interior_probes", 0, len(PROBES))):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least \
                    or (most is not None and value > most):
                bounds = f">= {least}" if most is None else f"in [{least}, {most}]"
                raise InvalidArgument(f"rrt_connect: {name} must be an integer {bounds}, got {value!r}")
        # the kernel's options vector (.search.OPTION_NAMES), built once per config
        values = {**dataclasses.asdict(self), "clock": _CLOCK, "profile": int(self.profile),
                  "balance": int(self.balance)}
        object.__setattr__(self, "_vector", np.array([float(values[name]) for name in K.OPTION_NAMES]))

    def __getstate__(self) -> dict:
        """The options only: the kernel's vector holds this process's clock address, so a copy or
        an unpickled config (another process) builds its own (:meth:`__setstate__`)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def __setstate__(self, state: dict) -> None:
        for name, value in state.items():
            object.__setattr__(self, name, value)
        self.__post_init__()

    @classmethod
    def from_options(cls, options: dict, **defaults) -> "RRTConnectConfig":
        """The config of ``solve_motion``'s keywords over ``defaults``, built once per distinct
        set of them: building and validating one takes tens of microseconds, which a plan's clock
        would count (at most :data:`_CONFIG_CACHE` are kept)."""
        try:  # the type beside each value: True == 1, but lanes=True is an error and lanes=1 is not
            key = (tuple(sorted((name, type(value), value) for name, value in options.items())),
                   tuple(sorted(defaults.items())))
            config = _CONFIGS.get(key)
        except TypeError:  # an unhashable value: built (and rejected) below
            key, config = None, None
        if config is not None:
            return config
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(options) - names)
        if unknown:
            raise InvalidArgument(f"rrt_connect: unknown option(s) {unknown}; options are {sorted(names)}")
        config = cls(**{**defaults, **options})
        if key is not None:
            if len(_CONFIGS) >= _CONFIG_CACHE:
                _CONFIGS.clear()
            _CONFIGS[key] = config
        return config


_CONFIG_CACHE = 256
_CONFIGS: dict = {}
_DEFAULT = RRTConnectConfig()
_COUNTS = S.T_SAMPLE  # counts first, then seconds
_COUNT_NAMES = S.STAT_NAMES[:_COUNTS]
_NSTATS = len(S.STAT_NAMES)

_PREPARED = False
#: plan_kernel's entry points per the types of a binding's arrays, then per by_values (_call)
_ENTRIES: dict = {}


def _binding(scene) -> tuple:
    """``(ints, floats, v_WO, reach, lower, upper, entries, stats, native)`` of the scene's current
    obstacles: the arrays as the kernels take them (:func:`~drake_mh.planning.motion.scene_arguments`), the kernel's entry
    points for them (:func:`_call`; shared by every binding whose arrays have the same types, so
    that a new scene costs no compilation in a plan), the statistics array a plan writes
    (read at once: like the scene's Drake context, not for plans in concurrent threads) and the
    compiled core's ``MotionPlanner`` on copies of the arrays (None where the core is not built or
    ``DRAKE_MH_COMPILED_CORE=0`` when the binding is made). Kept on the scene until its obstacles
    change (:meth:`~drake_mh.scene.Scene.planner_binding`)."""
    return scene.planner_binding(_binding, _bind)


def _bind(scene) -> tuple:
    """:func:`_binding` built anew."""
    bound = scene_arguments(scene)
    core = compiled_core()
    native = None if core is None else core.MotionPlanner(bound[0], bound[1], bound[3])
    return bound + (_ENTRIES.setdefault(tuple(map(_array_type, bound)), {}), np.zeros(_NSTATS), native)


def _array_type(a: np.ndarray) -> tuple:
    """What numba's type of array ``a`` depends on (dtype, dimensions, layout, writable, aligned),
    read from its flags: ``numba.typeof`` costs about 60 µs a binding."""
    flags = a.flags
    return a.dtype.str, a.ndim, flags.c_contiguous, flags.f_contiguous, flags.writeable, flags.aligned


def compiled_planner(scene):
    """The compiled core's ``MotionPlanner`` bound to the scene's current obstacles (kept with the
    scene's binding, :func:`_binding`), or None where the core is not built or was switched off
    when the binding was made. Its ``prm`` runs ``lazy_prm_star``'s search on the same motion
    checks."""
    return _binding(scene)[8]


def _call(binding: tuple, arguments: tuple):
    """:func:`.search.plan_kernel` on ``arguments`` (which hold the ``binding``'s arrays): the
    binding's compiled-core planner where it has one and ``by_values`` is None (its ``plan`` takes
    the kernel's arguments less the arrays it holds), else the numba entry point of their types,
    kept in the binding per ``by_values`` (compiled or loaded from numba's cache on first use).
    The entry point skips numba's type dispatch (about 10 µs of a plan called after other work,
    its code and data out of the CPU's caches) and checks no type: every call for a binding must
    pass the same types (numba's entry points do not check an array's dtype or dimensions),
    which :func:`_arguments_of` guarantees."""
    native = binding[8]
    if native is not None and arguments[14] is None:
        q, goals, lower, upper = arguments[:4]
        return native.plan(q, goals, lower, upper, *arguments[8:14], arguments[15])
    entries = binding[6]
    entry = entries.get(arguments[14])
    if entry is None:
        types = [numba.typeof(a) for a in arguments]
        # q_start and goals writable or not (never written), the seed whatever its value
        types[0], types[1], types[10] = numba.float64[::1], numba.float64[:, ::1], numba.uint64
        entry = entries[arguments[14]] = K.plan_kernel.compile(tuple(types))
    return entry(*arguments)


def _arguments_of(problem, goals, binding: tuple, seed, max_nodes: int, time_limit: float, config) -> tuple:
    """:func:`.search.plan_kernel`'s arguments, each of the one type :func:`_call` expects."""
    q = np.ascontiguousarray(problem.q_start, dtype=float)
    goals = np.ascontiguousarray(goals, dtype=float)
    if q.ndim != 1 or goals.ndim != 2 or goals.shape[1] != q.shape[0]:
        raise InvalidArgument(f"rrt_connect: goals must be (G, {q.shape[0]}) for q_start ({q.shape[0]},), got "
                              f"{goals.shape} and {q.shape}")
    ints, floats, v_WO, reach, lower, upper = binding[:6]
    return (q, goals, lower, upper, ints, floats, v_WO, reach, float(problem.clearance), float(problem.self_clearance),
            int(seed), int(max_nodes), float(time_limit), config._vector, _by_values(config), binding[7])


def prepare(problem) -> float:
    """Bind the problem's scene and, where the numba kernel is the one called (no compiled core),
    compile or load it (once per process); seconds taken.

    Without it, the first :func:`plan` of a process does it (its ``info["prepare_time"]``;
    the deadline is then extended by that time: it measures planning, not loading, as
    :func:`drake_mh.solve_ik`'s timeout does). Loading from numba's cache takes about 0.2 s,
    compiling after a change of the kernels 1-2 minutes."""
    global _PREPARED
    start = time.perf_counter()
    binding = _binding(problem.scene)
    if not _PREPARED and binding[8] is None:
        config = RRTConnectConfig(max_certify_evaluations=16, shortcut_iterations=1)
        _call(binding, _arguments_of(problem, problem.q_start[None], binding, 0, 1, 1.0, config))
        _PREPARED = True
    return time.perf_counter() - start


def plan(problem, goals, rng, deadline, budget, **options):
    """RRT-Connect from ``problem.q_start`` to any row of ``goals``; every edge certified, the
    path shortcut (options: :class:`RRTConnectConfig`; ``budget``: tree nodes)."""
    config = RRTConnectConfig.from_options(options) if options else _DEFAULT
    return _run(problem, goals, rng, deadline, budget, config)


def plan_smooth(problem, goals, rng, deadline, budget, **options):
    """:func:`plan` with 192 shortcut draws at a gain of 0.005 instead of 32 at 0.05 (shorter
    paths, for more time)."""
    config = RRTConnectConfig.from_options(options, shortcut_iterations=192, shortcut_min_gain=0.005)
    return _run(problem, goals, rng, deadline, budget, config)


def _by_values(config: RRTConnectConfig):
    """The kernels' ``by_values`` argument: None for the batched check's refinement (the default), True
    for the bisection on clearance values (a compile-time choice: :func:`drake_mh.planning.motion.check.certified_motion`)."""
    return None if config.certify == "boolean" else True


def _run(problem, goals, rng, deadline, budget, config: RRTConnectConfig):
    # few Python steps here: a plan is often called after other work, with this code and its data out
    # of the CPU's caches, where each step costs microseconds (about 50 µs of Python around a 0.5 ms
    # kernel on MotionBenchMaker's problems)
    binding = _binding(problem.scene)
    prepare_time = prepare(problem) if not _PREPARED and binding[8] is None else 0.0
    # the deadline measures planning, not loading (as solve_ik's timeout)
    time_limit = np.inf if deadline is None else deadline + prepare_time - time.perf_counter()
    arguments = _arguments_of(problem, goals, binding, rng.bit_generator.random_raw(),  # the splitmix64 state
                              DEFAULT_MAX_NODES if budget is None else budget, time_limit, config)
    path, outcome, goal = _call(binding, arguments)
    values = binding[7].tolist()
    info = {name: int(value) for name, value in zip(_COUNT_NAMES, values)}
    info["t_total"] = values[S.T_TOTAL]
    info["t_found"] = values[S.T_FOUND]
    if config.profile:
        info.update(zip(S.STAT_NAMES[_COUNTS:], values[_COUNTS:]))
    info["prepare_time"] = prepare_time
    if outcome == S.FOUND:
        info["goal"] = int(goal)
        return path, info
    why = "budget" if outcome == S.BUDGET else "timeout"
    info["message"] = (f"no path: {why} reached after {info['nodes']} tree nodes and {info['motions']} motion checks"
                       + (f" (budget: tree nodes, and {K.SAMPLES_PER_NODE} samples per node; {info['out_of_domain']} "
                          f"samples drawn again by the dynamic domain)" if why == "budget" else ""))
    return None, info


def certify_motions(scene, QA, QB, clearance: float = 0.0, self_clearance: float = 0.0, **options) -> np.ndarray:
    """``(M,)`` bool: whether ``rrt_connect``'s motion check certifies each straight joint-space
    motion ``QA[i] -> QB[i]`` collision-free with these clearances (``QA[i]`` must be free: the
    planner only extends from free nodes). ``options``: those of :class:`RRTConnectConfig`
    that concern the check (``resolution``, ``margin``, ``lanes``, ``block``, ``probes``,
    ``max_certify_evaluations``, ``certify``). The compiled core's check where it is built and
    ``certify`` is ``"boolean"`` (the same answers), else the numba kernel."""
    from drake_mh.scene.segments import check_clearance

    config = RRTConnectConfig.from_options(options)
    robot = scene.robot
    QA = np.ascontiguousarray(np.atleast_2d(robot.check_Q(np.atleast_2d(QA))), dtype=float)
    QB = np.ascontiguousarray(np.atleast_2d(robot.check_Q(np.atleast_2d(QB))), dtype=float)
    if QA.shape != QB.shape:
        raise InvalidArgument(f"QA and QB must hold as many configurations, got {len(QA)} and {len(QB)}")
    clearance = check_clearance(clearance, "clearance")
    self_clearance = check_clearance(self_clearance, "self_clearance")
    binding = _binding(scene)
    stats = np.zeros(len(S.STAT_NAMES))
    if binding[8] is not None and _by_values(config) is None:
        return binding[8].certify_motions(QA, QB, clearance, self_clearance, float(config.resolution),
                                          float(config.margin), int(config.lanes), int(config.block),
                                          int(config.probes), int(config.max_certify_evaluations), stats)
    ints, floats, v_WO, reach = binding[:4]
    return K.certify_motions(QA, QB, ints, floats, v_WO, reach, clearance, self_clearance, float(config.resolution),
                             float(config.margin), int(config.lanes), int(config.block), int(config.probes),
                             int(config.max_certify_evaluations), _by_values(config), _CLOCK, stats)
