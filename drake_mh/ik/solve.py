"""``solve_ik``: one entry point for every IK method, one verification for all.

Methods (:func:`available_ik_methods`):

* every optimizer of :func:`drake_mh.optim.available_methods` (``pso``, ``bat``, ``gsa``,
  ``e3gsa``, ``woa``, ``ao``, ``ga``, ``abc``, ``aro``, ``cmaes``, ``de``, ``random``):
  metaheuristic IK (framework paper, Algorithm 1), :mod:`drake_mh.ik.metaheuristic`;
* ``hybrid``: global population search + batched Levenberg–Marquardt, :mod:`drake_mh.ik.hybrid`;
* ``pinv``, ``dls``: Jacobian baselines with random restarts, :mod:`drake_mh.ik.jacobian`;
* ``drake_snopt``, ``drake_ipopt``: Drake's ``InverseKinematics``, :mod:`drake_mh.ik.drake`.

A target that is provably out of reach (:meth:`IKProblem.unreachable_reason`) returns
``success=False`` at once with both distances in the message, for every method.
"""

from __future__ import annotations

import numbers
import time

import numpy as np

from drake_mh.errors import InvalidArgument, InvalidIKProblem, UnknownMethod
from drake_mh.ik.problem import IKProblem
from drake_mh.ik.result import IKResult, verify

__all__ = ["solve_ik", "available_ik_methods", "GRADIENT_METHODS", "DEFAULT_LOCAL_BUDGET"]

#: the non-metaheuristic methods, in report order
GRADIENT_METHODS: tuple[str, ...] = ("hybrid", "pinv", "dls", "drake_snopt", "drake_ipopt")

#: configurations evaluated by ``hybrid``, ``pinv`` and ``dls`` when neither budget nor timeout is given
DEFAULT_LOCAL_BUDGET = 200_000


def available_ik_methods() -> list[str]:
    """Names accepted by :func:`solve_ik`: the library's optimizers, then the gradient methods."""
    from drake_mh.optim import available_methods

    return list(available_methods()) + list(GRADIENT_METHODS)


def _check_limits(budget, timeout):
    if budget is not None:
        if isinstance(budget, bool) or not isinstance(budget, numbers.Real) or not float(budget).is_integer() or budget < 1:
            raise InvalidArgument(f"budget must be an integer >= 1 (evaluations, or solver starts for "
                                  f"Drake's solvers) or None; got {budget!r}")
        budget = int(budget)
    if timeout is not None:
        try:
            timeout = float(timeout)
        except (TypeError, ValueError):
            raise InvalidArgument(f"timeout must be a positive number of seconds or None; got {timeout!r}") from None
        if not np.isfinite(timeout) or timeout <= 0:
            raise InvalidArgument(f"timeout must be a positive number of seconds or None; got {timeout!r}")
    return budget, timeout


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
            timeout), solver starts for ``drake_*`` (default 20 when there is no timeout).
        timeout: [s] wall-clock limit (``None``: none); the solve stops at whichever of budget
            and timeout comes first. The very first solve on a machine also compiles the numba
            kernels (a few seconds, then cached on disk) and the first in a process loads them
            (~0.1-1 s): warm up with one untimed solve before timing tight budgets.
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
    start = time.perf_counter()
    if not isinstance(problem, IKProblem):
        raise InvalidIKProblem(f"solve_ik needs an IKProblem, got {type(problem).__name__}; "
                               "build one with drake_mh.IKProblem(robot, target, ...)")
    name = method.lower() if isinstance(method, str) else method
    methods = available_ik_methods()
    if name not in methods:
        raise UnknownMethod(str(method), methods, what="IK method")
    budget, timeout = _check_limits(budget, timeout)
    if params and name in GRADIENT_METHODS:
        raise InvalidArgument(f"{name} takes no optimizer options ({sorted(params)}); pass config=... instead")
    reason = problem.unreachable_reason()
    if reason is not None:
        q = problem.q_ref if problem.q_ref is not None else 0.5 * (problem.lower + problem.upper)
        return verify(problem, q, method=name, start=start, nfe=0, message=reason)
    if name == "hybrid":
        from drake_mh.ik.hybrid import solve_hybrid

        if budget is None and timeout is None:
            budget = DEFAULT_LOCAL_BUDGET
        return solve_hybrid(problem, seed, budget, timeout, config, start=start)
    if name in ("pinv", "dls"):
        from drake_mh.ik.jacobian import solve_jacobian

        if budget is None and timeout is None:
            budget = DEFAULT_LOCAL_BUDGET
        return solve_jacobian(problem, name, seed, budget, timeout, config, start=start)
    if name in ("drake_snopt", "drake_ipopt"):
        from drake_mh.ik.drake import solve_drake

        return solve_drake(problem, name, seed, budget, timeout, config, start=start)
    from drake_mh.ik.metaheuristic import solve_metaheuristic

    if config is not None:
        raise InvalidArgument(f"{name} takes its options as keyword arguments (pop_size=..., ...), not config")
    return solve_metaheuristic(problem, name, seed, budget, timeout, start=start, **params)
