"""The hybrid IK method: population-based global search + batched Levenberg–Marquardt.

A memetic algorithm in the spirit of bio_ik (Ruppel, Hendrich, Starke, Zhang 2018: species of
parents and children, gradient refinement, restarts until the timeout):

1. **Global phase** — a population of ``population`` configurations (uniform within the joint
   limits, the reference configuration ``q_ref`` when given, and, from the second generation
   on, Gaussian children of the best refined individuals) is scored with the problem's full
   objective (:meth:`IKProblem.objective`: pose error + obstacle penalty on the sphere model +
   optional displacement and manipulability terms), vectorized over the population.
2. **Local phase** — the best ``candidates`` individuals are refined *together* by batched
   Levenberg–Marquardt (:mod:`drake_mh.ik.lm`; joint limits by projection, ``q_ref`` pulled in
   the task null space). A refined individual that stalls is replaced by the next one of the
   ranked population (Lamarckian: its refined point becomes a parent of the next generation).
3. As soon as one candidate meets the tolerances it is checked against the obstacles with the
   sphere model (conservative: never more clearance than Drake), then **verified with Drake**
   (:func:`drake_mh.ik.result.verify`); only the winner is sent to Drake. Otherwise the loop
   goes on until the budget (configurations evaluated) or the timeout is spent.

Determinism: with a ``budget`` and no ``timeout`` the result depends on the seed only; under a
timeout the number of restarts depends on the machine (as for TRAC-IK and bio_ik).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from drake_mh.ik.lm import STALLED, BatchLM, LMSettings
from drake_mh.ik.problem import IKProblem
from drake_mh.ik.result import IKResult, verify

__all__ = ["HybridConfig", "solve_hybrid"]


@dataclass(frozen=True)
class HybridConfig:
    """Settings of :func:`solve_hybrid` (defaults tuned on the TRAC-IK protocol, Panda; see
    ``studies/ik_benchmark.py``).

    Attributes:
        population: individuals scored per generation of the global phase.
        candidates: individuals refined together by LM (the batch size K).
        children: fraction of a generation (after the first) made of Gaussian children of the
            best refined individuals; the rest is drawn uniformly within the limits.
        mutation: standard deviation of the children, as a fraction of each joint's range.
        lm: :class:`LMSettings` of the local phase.
    """

    population: int = 48
    candidates: int = 12
    children: float = 0.5
    mutation: float = 0.05
    lm: LMSettings = field(default_factory=lambda: LMSettings(stall_iters=3, ref_gain=0.5))


def _generation(problem: IKProblem, rng: np.random.Generator, config: HybridConfig, parents: np.ndarray | None,
                first: bool, P: int) -> np.ndarray:
    """A new ranked population ``(P, nq)``, best first by the problem's objective."""
    nq = problem.nq
    lower, upper = problem.lower, problem.upper
    Q = lower + (upper - lower) * rng.random((P, nq))
    if first and problem.q_ref is not None:
        Q[0] = problem.q_ref
    if parents is not None and len(parents) and config.children > 0:
        n_children = int(round(config.children * P))
        picks = parents[rng.integers(0, len(parents), n_children)]
        sigma = config.mutation * (upper - lower)
        Q[P - n_children:] = np.clip(picks + sigma * rng.standard_normal((n_children, nq)), lower, upper)
    f = problem.objective(Q)
    return Q[np.argsort(f, kind="stable")]


def solve_hybrid(problem: IKProblem, seed=0, budget: int | None = None, timeout: float | None = None,
                 config: HybridConfig | None = None, start: float | None = None) -> IKResult:
    """Solves ``problem`` with the memetic hybrid (module docstring).

    Args:
        problem: the IK problem.
        seed: seed of ``numpy.random.default_rng``.
        budget: configurations evaluated (objective evaluations in the global phase plus FK +
            Jacobian evaluations in the local phase); ``None``: unlimited (then a timeout is
            needed).
        timeout: [s] wall-clock limit; ``None``: none.
        config: :class:`HybridConfig`.
        start: ``time.perf_counter()`` of the caller's start (default now).

    Returns:
        IKResult: verified with Drake; ``nfe`` counts configurations evaluated.
    """
    start = time.perf_counter() if start is None else start
    config = config or HybridConfig()
    rng = np.random.default_rng(seed)
    deadline = np.inf if timeout is None else start + timeout
    budget = np.inf if budget is None else budget
    P = int(min(config.population, budget))  # a tiny budget is never exceeded
    K = min(config.candidates, P)
    lm = BatchLM(problem, K, config.lm)
    sphere_check = problem.scene is not None and bool(problem.scene.obstacles)

    pool = _generation(problem, rng, config, None, first=True, P=P)
    nfe = len(pool)
    lm.start(slice(0, K), pool[:K])
    cursor = K
    attempts = K
    rejected = 0
    best_q, best_f = pool[0].copy(), np.inf
    while True:
        if nfe + K > budget or time.perf_counter() > deadline:
            break
        row = lm.iterate()
        nfe += K
        if row >= 0:
            q = lm.Qa[row].copy()
            clear = (not sphere_check) or problem.scene.batch_min_distance(q[None])[0] >= problem.clearance
            if clear:
                result = verify(problem, q, method="hybrid", start=start, nfe=nfe, attempts=attempts,
                                message=f"converged after {attempts} starts")
                if result.success:
                    return result
            rejected += 1
            lm.status[row] = STALLED
        stalled = np.flatnonzero(lm.status == STALLED)
        if stalled.size:
            k = int(stalled[np.argmin(lm.fa[stalled])])
            if lm.fa[k] < best_f:
                best_q, best_f = lm.Qa[k].copy(), lm.fa[k]
            if cursor + stalled.size > len(pool):
                if nfe + P > budget:
                    break
                pool = _generation(problem, rng, config, lm.Qa, first=False, P=P)
                nfe += len(pool)
                cursor = 0
            lm.start(stalled, pool[cursor:cursor + stalled.size])
            cursor += stalled.size
            attempts += stalled.size
    k = lm.best_row()
    if lm.fa[k] < best_f:  # fa is inf for rows never evaluated
        best_q = lm.Qa[k].copy()
    why = "timeout" if time.perf_counter() > deadline else "budget exhausted"
    extra = f", {rejected} converged candidates rejected (sphere model or Drake)" if rejected else ""
    return verify(problem, best_q, method="hybrid", start=start, nfe=nfe, attempts=attempts,
                  message=f"{why} after {attempts} starts{extra}")
