"""``solve_ik``: one entry point for every IK method, one verification for all.

Methods (:func:`available_ik_methods`):

* every optimizer of :func:`drake_mh.optim.available_methods` (``pso``, ``bat``, ``gsa``,
  ``e3gsa``, ``woa``, ``woa_greedy``, ``ao``, ``ga``, ``abc``, ``aro``, ``cmaes``, ``de``, ``random``):
  metaheuristic IK (framework paper, Algorithm 1), :mod:`drake_mh.ik.metaheuristic`;
* ``hybrid``: global population search + batched Levenberg–Marquardt, :mod:`drake_mh.ik.hybrid`;
* ``pinv``, ``dls``: Jacobian baselines with random restarts, :mod:`drake_mh.ik.jacobian`;
* ``drake_snopt``, ``drake_ipopt``: Drake's ``InverseKinematics``, :mod:`drake_mh.ik.drake`.

The methods are one explicit table, :data:`METHODS` (name -> :class:`IKMethod`).

A target that is provably out of reach (:meth:`IKProblem.unreachable_reason`) returns
``success=False`` at once with both distances in the message, for every method.

A ``timeout`` measures solving, not loading: before the clock starts, :func:`prepare` loads
what the method needs on this robot, frame and kind of problem (numba kernels, which cost
0.3-1 s once per process, Drake's IK program, the reach bound) by one small untimed solve,
once per process; the time it took is reported as ``IKResult.prepare_time``.
"""

from __future__ import annotations

import dataclasses
import importlib
import numbers
import time
import weakref
from collections.abc import Callable

from drake_mh._support.registry import Registry
from drake_mh.errors import InvalidArgument, InvalidIKProblem
from drake_mh.ik.problem import IKProblem
from drake_mh.ik.result import IKResult, verify
from drake_mh.optim import available_methods
from drake_mh.optim.base import MAX_BUDGET, check_timeout, make_rng

__all__ = ["solve_ik", "prepare", "available_ik_methods", "METHODS", "IKMethod", "GRADIENT_METHODS",
           "DEFAULT_LOCAL_BUDGET"]

#: configurations evaluated by ``hybrid``, ``pinv`` and ``dls`` when neither budget nor timeout is given
DEFAULT_LOCAL_BUDGET = 200_000


#: keys of what :func:`prepare` has loaded, per robot (weakly: a dropped robot drops its entry)
_PREPARED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclasses.dataclass(frozen=True)
class IKMethod:
    """A method of :func:`solve_ik` (an entry of :data:`METHODS`).

    Attributes:
        solve: ``solve(problem, name, seed, budget, timeout, config, start, params) -> IKResult``,
            its clock started at ``start`` (``budget``/``timeout`` as :func:`solve_ik` got them).
        config: ``"module:Class"`` of its configuration object (``solve_ik(config=...)``);
            ``None``: it takes optimizer options as keywords instead (the metaheuristics).
        prepare_budget: the budget of :func:`prepare`'s small solve (``None``: two generations).
    """

    solve: Callable
    config: str | None = None
    prepare_budget: int | None = None

    def config_class(self) -> type:
        """The class named by :attr:`config`."""
        module, _, name = self.config.partition(":")
        return getattr(importlib.import_module(module), name)


def _solve_metaheuristic(problem, name, seed, budget, timeout, config, start, params):
    from drake_mh.ik.metaheuristic import solve_metaheuristic

    return solve_metaheuristic(problem, name, seed, budget, timeout, start=start, **params)


def _solve_hybrid(problem, name, seed, budget, timeout, config, start, params):
    from drake_mh.ik.hybrid import solve_hybrid

    if budget is None and timeout is None:
        budget = DEFAULT_LOCAL_BUDGET
    return solve_hybrid(problem, seed, budget, timeout, config, start=start)


def _solve_jacobian(problem, name, seed, budget, timeout, config, start, params):
    from drake_mh.ik.jacobian import solve_jacobian

    if budget is None and timeout is None:
        budget = DEFAULT_LOCAL_BUDGET
    return solve_jacobian(problem, name, seed, budget, timeout, config, start=start)


def _solve_drake(problem, name, seed, budget, timeout, config, start, params):
    from drake_mh.ik.drake import solve_drake

    return solve_drake(problem, name, seed, budget, timeout, config, start=start)


METHODS = Registry("IK method", case_sensitive=False)
"""The methods of :func:`solve_ik`: name -> :class:`IKMethod` (case-insensitive); the library's
optimizers first, then the gradient methods in report order."""
for _name in available_methods():
    METHODS.add(_name, IKMethod(_solve_metaheuristic), description=f"metaheuristic IK with the {_name} optimizer")
METHODS.add("hybrid", IKMethod(_solve_hybrid, "drake_mh.ik.hybrid:HybridConfig", 120),
            description="global population search + batched Levenberg-Marquardt")
METHODS.add("pinv", IKMethod(_solve_jacobian, "drake_mh.ik.jacobian:JacobianConfig", 20),
            description="pseudo-inverse Jacobian iterations with random restarts")
METHODS.add("dls", IKMethod(_solve_jacobian, "drake_mh.ik.jacobian:JacobianConfig", 20),
            description="damped least-squares Jacobian iterations with random restarts")
METHODS.add("drake_snopt", IKMethod(_solve_drake, "drake_mh.ik.drake:DrakeIKConfig", 1),
            description="Drake's InverseKinematics solved by SNOPT, random restarts")
METHODS.add("drake_ipopt", IKMethod(_solve_drake, "drake_mh.ik.drake:DrakeIKConfig", 1),
            description="Drake's InverseKinematics solved by IPOPT, random restarts")
del _name

#: the non-metaheuristic methods, in report order
GRADIENT_METHODS: tuple[str, ...] = tuple(name for name in METHODS.names() if METHODS.get(name).config is not None)


def available_ik_methods() -> list[str]:
    """Names accepted by :func:`solve_ik`: the library's optimizers, then the gradient methods."""
    return METHODS.names()


def _check_limits(budget, timeout):
    if budget is not None:
        try:
            whole = not isinstance(budget, bool) and isinstance(budget, numbers.Real) and float(budget).is_integer()
        except OverflowError:  # an int beyond a double
            whole = False
        if not whole or not 1 <= budget <= MAX_BUDGET:
            raise InvalidArgument(f"budget must be an integer >= 1 and <= {MAX_BUDGET:.0e} (evaluations, or solver "
                                  f"starts for Drake's solvers) or None; got {str(budget)[:40]}")
        budget = int(budget)
    return budget, check_timeout(timeout)


def _check_config(name: str, method: IKMethod, config) -> None:
    """``config`` must be ``None`` or the configuration class of method ``name``."""
    if config is None or method.config is None:
        return
    expected = method.config_class()
    if not isinstance(config, expected):
        raise InvalidArgument(f"config of {name} must be a {expected.__name__} (or None); "
                              f"got {type(config).__name__}")


def solve_ik(problem: IKProblem, method: str = "hybrid", seed=0, budget: int | None = None,
             timeout: float | None = None, config=None, **params) -> IKResult:
    """Solves an IK problem with any method; the result is verified with Drake.

    Args:
        problem: the :class:`IKProblem`.
        method: a name of :func:`available_ik_methods` (case-insensitive).
        seed: seed of the method's randomness (same seed, same result when the run ends by
            success or budget rather than by the timeout).
        budget: function evaluations for the optimizers (default 20,000), configurations
            evaluated for ``hybrid``/``pinv``/``dls`` (default 200,000 when there is no
            timeout), solver starts for ``drake_*`` (default 20 when there is no timeout); at
            most :data:`MAX_BUDGET`.
        timeout: [s] wall-clock limit (``None``: none); the solve stops at whichever of budget
            and timeout comes first. It measures solving only: loading what the method needs
            (:func:`prepare`: compiled kernels, Drake's program; once per process, or a few
            seconds of compilation the very first time on a machine) happens before the clock
            starts and is reported as ``IKResult.prepare_time``.
        config: the method's configuration object (:class:`~drake_mh.ik.hybrid.HybridConfig`,
            :class:`~drake_mh.ik.jacobian.JacobianConfig`, :class:`~drake_mh.ik.drake.DrakeIKConfig`).
        **params: optimizer options for the metaheuristics (``pop_size`` and the method's
            hyper-parameters).

    Returns:
        IKResult (``success`` recomputed with Drake's FK, exact distances and the limits).

    Raises:
        UnknownMethod: ``method`` is not a name of :func:`available_ik_methods`.
        InvalidArgument: bad budget, timeout or options.
        InvalidIKProblem: ``problem`` is not an :class:`IKProblem`.
    """
    if not isinstance(problem, IKProblem):
        raise InvalidIKProblem(f"solve_ik needs an IKProblem, got {type(problem).__name__}; "
                               "build one with drake_mh.IKProblem(robot, target, ...)")
    entry = METHODS.get(method)
    name = method.lower()
    budget, timeout = _check_limits(budget, timeout)
    if not (type(seed) is int and seed >= 0):  # ints are fine (and building a Generator costs 7 µs)
        make_rng(seed)  # a bad seed fails here, with a message, not deep inside numpy
    _check_config(name, entry, config)
    if params and entry.config is not None:
        raise InvalidArgument(f"{name} takes no optimizer options ({sorted(params)}); pass config=... instead")
    if config is not None and entry.config is None:
        raise InvalidArgument(f"{name} takes its options as keyword arguments (pop_size=..., ...), not config")
    prepare_time = prepare(problem, name, config, **params)
    result = _solve(problem, name, seed, budget, timeout, config, time.perf_counter(), params)
    return dataclasses.replace(result, prepare_time=prepare_time) if prepare_time else result


def prepare(problem: IKProblem, method: str = "hybrid", config=None, **params) -> float:
    """Loads what ``method`` needs to solve problems like ``problem``, outside any clock.

    The first solve in a process pays numba's start-up and the loading of the compiled kernels
    (measured 0.3-1 s: numba initialises its typing registries, which import scipy.linalg, then
    reads each kernel from its disk cache), Drake's solvers build their program, and the
    problem computes the robot's reach bound. :func:`solve_ik` calls this before starting its
    clock, so a ``timeout`` measures solving only; call it yourself to load at a time of your
    choosing. It runs one small solve of the same method on ``problem`` (same code path, same
    kernel signatures), once per process for each robot, frame and kind of problem (pose or
    position, with or without obstacles, reference configuration, manipulability term).

    Args:
        problem: an :class:`IKProblem`.
        method: a name of :func:`available_ik_methods`.
        config, **params: as for :func:`solve_ik`.

    Returns:
        [s] the time spent; 0.0 when everything was loaded already.
    """
    name = method.lower()
    scene = problem.scene is not None and bool(problem.scene.obstacles)
    key = (name, problem.frame, problem.R_WT is not None, scene, problem.q_ref is not None,
           problem.manipulability_weight > 0, problem.ref_weight > 0, tuple(sorted(params)))
    done = _PREPARED.setdefault(problem.robot, set())
    if key in done:
        return 0.0
    start = time.perf_counter()
    problem.unreachable_reason()  # computes and caches the robot's reach bound
    # enough for each method to run its whole loop once: a generation and a few LM iterations
    # (hybrid), a few Jacobian steps, two optimizer generations, one Drake start
    budget = METHODS.get(name).prepare_budget
    if budget is None:
        budget = 2 * int(params.get("pop_size") or 50) + 1
    _solve(problem, name, 0, budget, None, config, time.perf_counter(), params, check_reach=False)
    if name == "hybrid":  # the first phase may succeed alone: load the population phase too
        from drake_mh.ik.hybrid import HybridConfig

        population_only = dataclasses.replace(config or HybridConfig(), first_starts=0)
        _solve(problem, name, 0, budget, None, population_only, time.perf_counter(), params, check_reach=False)
    done.add(key)
    return time.perf_counter() - start


def _solve(problem: IKProblem, name: str, seed, budget, timeout, config, start: float, params: dict,
           check_reach: bool = True) -> IKResult:
    """Runs method ``name`` (already validated) with its clock started at ``start``."""
    reason = (problem.unreachable_reason() or problem.obstructed_reason()) if check_reach else None
    if reason is not None:
        q = problem.q_ref if problem.q_ref is not None else 0.5 * (problem.lower + problem.upper)
        return verify(problem, q, method=name, start=start, nfe=0, message=reason)
    return METHODS.get(name).solve(problem, name, seed, budget, timeout, config, start, params)
