"""Metaheuristic IK: any optimizer of :mod:`drake_mh.optim` on the problem's objective.

Algorithm 1 of the framework paper (§3.2): a population of joint vectors within the joint
limits, forward kinematics of every individual, fitness = the 3-D distance to the target
(+ orientation and constraint terms, :meth:`IKProblem.objective`), exploration/exploitation
by the chosen metaheuristic until the stopping criterion. Here the criterion is an exact
function-evaluation ``budget`` (equal for every method in a comparison), a ``timeout``, or the
best individual meeting the tolerances (checked after each generation on the batched kernel,
with the sphere model for obstacles), whichever comes first. The returned configuration is
verified with Drake like every other method's.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.ik.problem import IKProblem
from drake_mh.ik.result import IKResult, verify

__all__ = ["solve_metaheuristic", "DEFAULT_BUDGET"]

#: function evaluations when neither a budget nor a timeout is given
DEFAULT_BUDGET = 20_000


def solve_metaheuristic(problem: IKProblem, method: str, seed=0, budget: int | None = None,
                        timeout: float | None = None, start: float | None = None,
                        pop_size: int | None = None, **params) -> IKResult:
    """Solves ``problem`` with ``drake_mh.optim.minimize(method)`` (module docstring).

    Args:
        problem: the IK problem.
        method: a name of :func:`drake_mh.optim.available_methods`.
        seed: optimizer seed (same seed, same result when the run ends by budget or tolerance).
        budget: function evaluations; ``None``: :data:`DEFAULT_BUDGET` (with a timeout:
            unlimited until the timeout, capped at 10⁹).
        timeout: [s] wall-clock limit; ``None``: none.
        start: ``time.perf_counter()`` of the caller's start.
        pop_size: population size (``None``: the method's default).
        **params: the optimizer's hyper-parameters.

    Returns:
        IKResult with the optimizer's convergence history (best objective vs evaluations).
    """
    from drake_mh.optim import minimize

    start = time.perf_counter() if start is None else start
    if budget is None:
        budget = DEFAULT_BUDGET if timeout is None else 10**9
    deadline = np.inf if timeout is None else start + timeout
    sphere_check = problem.scene is not None and bool(problem.scene.obstacles)
    tol_p, tol_o = problem.position_tolerance, problem.orientation_tolerance
    reason = {"why": ""}
    last = {"f": np.inf}

    def stop(state) -> bool:
        if time.perf_counter() > deadline:
            reason["why"] = "timeout"
            return True
        if state.best_f >= last["f"]:
            return False
        last["f"] = state.best_f
        x = state.best_x[None]
        e_p, e_o = problem.pose_errors(x)
        if e_p[0] <= tol_p and e_o[0] <= tol_o:
            if not sphere_check or problem.scene.batch_min_distance(x)[0] >= problem.clearance:
                reason["why"] = "tolerances reached"
                return True
        return False

    res = minimize(problem.objective, (problem.lower, problem.upper), method=method, budget=int(budget),
                   seed=seed, pop_size=pop_size, callback=stop, **params)
    message = f"{reason['why'] or res.message} after {res.nfe} evaluations ({res.nit} generations)"
    return verify(problem, res.x, method=method, start=start, nfe=res.nfe, message=message, history=res.history)
