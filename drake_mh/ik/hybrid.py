"""The hybrid IK method: compiled LM restarts, then population search + batched Levenberg–Marquardt.

A memetic algorithm in the spirit of bio_ik (Ruppel, Hendrich, Starke, Zhang 2018: species of
parents and children, gradient refinement, restarts until the timeout), preceded by the cheap
phase that wins most 6-D targets (robotics-toolbox-python's ``ik_LM``, Haviland & Corke 2023,
and TRAC-IK's KDL thread are Levenberg–Marquardt / Newton iterations with random restarts):

0. **First phase** — ``first_starts`` starting points (``q_ref`` first when given, then
   uniform within the limits) are refined by Levenberg–Marquardt (:mod:`drake_mh.ik.lm`;
   joint limits by projection, ``q_ref`` pulled in the task null space), ``first_chains`` at
   a time, a stalled chain restarting from the next point, *inside one compiled call*
   (:func:`drake_mh.ik.lm.lm_run`): no Python between iterations. Most targets end here
   (measured on the TRAC-IK protocol, Panda: ~5 starts, ~60 configurations, ~40 µs).
1. **Global phase** (when the first phase runs out of starts: the target is hard, or
   obstacles reject its solutions) — a population of ``population`` configurations (uniform
   within the joint limits, the reference configuration ``q_ref`` when given, and, from the
   second generation on, Gaussian children of the best refined individuals) is scored with the
   problem's full objective (:meth:`IKProblem.objective`: pose error + obstacle penalty on the
   sphere model + optional displacement and manipulability terms), vectorized over the
   population.
2. **Local phase** — the best ``candidates`` individuals are refined *together* by batched
   LM, in ranked order, in compiled calls that return when one converges or the generation is
   used up (Lamarckian: refined points become the parents of the next generation).
3. As soon as one candidate meets the tolerances (half the problem's, ``LMSettings.tol_factor``)
   it is checked against the obstacles with the sphere model (conservative: never more
   clearance than Drake), then **verified with Drake** (:func:`drake_mh.ik.result.verify`:
   Drake's FK, the limits, Drake's exact distances); only that candidate is sent to Drake,
   and a candidate Drake rejects is abandoned like a stalled one. Otherwise the search goes
   on until the budget (configurations evaluated) or the timeout is spent.

Determinism: with a ``budget`` and no ``timeout`` the result depends on the seed only; under a
timeout the number of restarts depends on the machine (as for TRAC-IK and bio_ik). The clock
is read between compiled calls, which evaluate at most ``chunk`` configurations (~0.15 ms).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from drake_mh.ik.lm import STALLED, BatchLM, LMSettings
from drake_mh.ik.problem import IKProblem
from drake_mh.ik.result import IKResult, verify

__all__ = ["HybridConfig", "solve_hybrid"]


@dataclass(frozen=True)
class HybridConfig:
    """Settings of :func:`solve_hybrid` (defaults chosen by measurement on the TRAC-IK protocol,
    Panda and seed000_6dof; see ``studies/ik_benchmark.py`` and ``docs/ik.md``).

    Attributes:
        population: individuals scored per generation of the global phase.
        candidates: individuals refined together by LM (the batch size K).
        children: fraction of a generation (after the first) made of Gaussian children of the
            best refined individuals; the rest is drawn uniformly within the limits.
        mutation: standard deviation of the children, as a fraction of each joint's range.
        lm: :class:`LMSettings` of the local phase.
        first_starts: LM starts of the first phase before the population search (0: none).
            Measured on the TRAC-IK protocol: restarts beat the population even on the hard
            targets (the hardest Panda target of 1000 took a median of 73 starts, 1,200
            configurations, where the population phase needed ~15,000), so the default runs
            the first phase through most of a 5 ms timeout.
        first_starts_obstacles: the same with obstacles in the scene. The first phase ignores
            them (its converged points are checked on the sphere model, then by Drake) while
            the population ranks its starts with the obstacle penalty; default 0 (the
            population straight away) because the first phase's answers, valid as they are,
            lie on other IK branches: the framework paper's follower scenario (hybrid, seeds
            0-7) succeeded 5 of 8 times with 8 first starts, 8 of 8 with none.
        first_share: most of the budget and of the timeout the first phase may spend; the
            rest is left to the population search (which also gives failures a better best
            answer: free iterates leave the limits).
        first_chains: chains iterated together in the first phase (1 measured fastest: a
            second chain costs as much as it saves in restarts).
        first_lm: :class:`LMSettings` of the first phase: every step taken, damped by
            ``0.1 |e_w|²`` (Chan & Lawrence's error damping, as robotics-toolbox's ``ik_LM``),
            at most 20 iterations per start, free iterates (``project_limits=False``).
            Measured on 600 TRAC-IK targets (configurations evaluated per target, mean): Panda
            41 against 61 with adaptive damping (λ₀ = 1e-2) and 63 with adaptive projected
            steps; seed000_6dof 20 against 26 and 65. Projection is used instead when the
            problem's search box is narrower than the joint limits
            (``paths.continuity.LocalIKProblem``).
        chunk: most configurations evaluated per compiled call; the timeout is checked
            between calls.

    A problem with ``q_ref`` and a ``ref_weight`` (continuity along a path) gets at most the
    start at ``q_ref`` in the first phase: the population ranks its starts by the distance to
    ``q_ref``, uniform restarts do not.
    """

    population: int = 48
    candidates: int = 12
    children: float = 0.5
    mutation: float = 0.05
    lm: LMSettings = field(default_factory=lambda: LMSettings(stall_iters=3, ref_gain=0.5))
    first_starts: int = 1000
    first_starts_obstacles: int = 0
    first_share: float = 0.5
    first_chains: int = 1
    first_lm: LMSettings = field(default_factory=lambda: LMSettings(
        adaptive=False, error_damping=True, lam0=0.1, max_iter=20, stall_iters=3, ref_gain=0.5, project_limits=False))
    chunk: int = 256


#: the default configuration (built once: a dataclass with factories costs ~3 µs per call)
_DEFAULT = HybridConfig()


class _NoStart(dict):
    """``(0, nq)`` empty start arrays, one per nq (the first phase's explicit starts when there is no q_ref)."""

    def __missing__(self, nq: int) -> np.ndarray:
        self[nq] = np.empty((0, nq))
        return self[nq]


_NO_START = _NoStart()


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


class _Search:
    """Bookkeeping shared by the phases: budget, clock, obstacle check, Drake verification."""

    def __init__(self, problem: IKProblem, budget, timeout, start: float, chunk: int):
        self.problem = problem
        self.start = start
        self.deadline = np.inf if timeout is None else start + timeout
        self.budget = np.inf if budget is None else budget
        self.chunk = chunk
        self.nfe = 0
        self.attempts = 0
        self.rejected = 0
        self.sphere_check = problem.scene is not None and bool(problem.scene.obstacles)
        self.best_q, self.best_f = None, np.inf

    def out_of_time(self) -> bool:
        return self.nfe >= self.budget or time.perf_counter() > self.deadline

    def run(self, lm: BatchLM, starts: np.ndarray, cursor: int, n_starts: int | None = None,
            gen_seed: int = 0) -> tuple[IKResult | None, int]:
        """Runs ``lm`` on its starts until a verified solution, no start left, or no budget/time.

        Args:
            lm, starts, cursor, n_starts, gen_seed: as :meth:`BatchLM.run`.

        Returns:
            ``(result, cursor)``: the verified result or None, and the next unused start.
        """
        problem = self.problem
        n_starts = len(starts) if n_starts is None else n_starts
        while True:
            if self.out_of_time():
                return None, cursor
            before = cursor
            row, evals, cursor = lm.run(starts, cursor, min(self.chunk, self.budget - self.nfe), n_starts, gen_seed)
            self.nfe += evals
            self.attempts += cursor - before
            if row < 0:
                if evals == 0 or (cursor >= n_starts and (lm.status == STALLED).any()):
                    return None, cursor  # out of starts (or of budget for one more step)
                continue
            q = lm.Qa[row].copy()
            if not self.sphere_check or problem.scene.batch_min_distance(q[None])[0] >= problem.clearance:
                result = verify(problem, q, method="hybrid", start=self.start, nfe=self.nfe,
                                attempts=self.attempts, message=f"converged after {self.attempts} starts")
                if result.success:
                    return result, cursor
            self.rejected += 1
            lm.status[row] = STALLED

    def keep_best(self, lm: BatchLM) -> None:
        """Remembers the best accepted point of ``lm`` (its abandoned starts and live rows)."""
        if lm._run_args is not None and lm.best_f[0] < self.best_f:
            self.best_q, self.best_f = lm.best_q.copy(), float(lm.best_f[0])
        k = lm.best_row()
        q = lm.Qa[k]
        inside = bool(((q >= self.problem.lower) & (q <= self.problem.upper)).all())  # free iterates may leave
        if lm.fa[k] < self.best_f and inside:  # fa is inf for rows never evaluated
            self.best_q, self.best_f = q.copy(), float(lm.fa[k])


def solve_hybrid(problem: IKProblem, seed=0, budget: int | None = None, timeout: float | None = None,
                 config: HybridConfig | None = None, start: float | None = None) -> IKResult:
    """Solves ``problem`` with the hybrid (module docstring).

    Args:
        problem: the IK problem.
        seed: an integer >= 0 seeds the first phase's starts (:func:`drake_mh._support.random.uniform_at`)
            and ``numpy.random.default_rng`` of the population phase; anything else
            ``default_rng`` accepts (``None``, a ``Generator``, a ``SeedSequence``) seeds the
            generator, whose first draw seeds the starts.
        budget: configurations evaluated (objective evaluations in the global phase plus FK +
            Jacobian evaluations in the local phases); ``None``: unlimited (then a timeout is
            needed).
        timeout: [s] wall-clock limit; ``None``: none.
        config: :class:`HybridConfig`.
        start: ``time.perf_counter()`` of the caller's start (default now).

    Returns:
        IKResult: verified with Drake; ``nfe`` counts configurations evaluated, ``attempts``
        LM starts.
    """
    start = time.perf_counter() if start is None else start
    config = config or _DEFAULT
    search = _Search(problem, budget, timeout, start, max(int(config.chunk), 1))
    lower, upper, nq = problem.lower, problem.upper, problem.nq
    rng = None
    if type(seed) is int and seed >= 0:
        gen_seed = seed
    else:  # None, a Generator, a SeedSequence...: one draw seeds the first phase
        rng = np.random.default_rng(seed)
        gen_seed = int(rng.integers(0, 2**63))

    n_first = int(config.first_starts_obstacles if search.sphere_check else config.first_starts)
    if problem.q_ref is not None and problem.ref_weight > 0:
        n_first = min(n_first, 1)  # near q_ref asked for: the population ranks by that distance, restarts do not
    if n_first > 0:  # phase 0: compiled LM restarts
        starts = _NO_START[nq] if problem.q_ref is None else problem.q_ref[None, :].copy()
        K = max(min(int(config.first_chains), n_first), 1)
        settings = config.first_lm
        if not settings.project_limits and (lower is not problem.robot.lower or upper is not problem.robot.upper):
            # a search box inside the limits (paths.continuity.LocalIKProblem): free iterates
            # would mostly converge outside it
            settings = dataclasses.replace(settings, project_limits=True)
        lm = BatchLM(problem, K, settings)
        lm.status[:] = STALLED
        budget, deadline = search.budget, search.deadline
        share = min(max(float(config.first_share), 0.0), 1.0)
        search.budget = share * budget  # the rest is the population's
        search.deadline = start + share * (deadline - start)
        result, _ = search.run(lm, starts, 0, n_starts=n_first, gen_seed=gen_seed)
        search.budget, search.deadline = budget, deadline
        if result is not None:
            return result
        search.keep_best(lm)

    rng = np.random.default_rng(seed) if rng is None else rng
    P = int(min(config.population, search.budget))  # a tiny budget is never exceeded
    if P >= 1 and not search.out_of_time() and search.nfe + P <= search.budget:
        K = min(config.candidates, P)
        lm = BatchLM(problem, K, config.lm)
        lm.status[:] = STALLED
        parents = None
        first = True
        while not search.out_of_time() and search.nfe + P <= search.budget:
            pool = _generation(problem, rng, config, parents, first=first, P=P)
            search.nfe += len(pool)
            first = False
            result, _ = search.run(lm, np.ascontiguousarray(pool), 0)
            if result is not None:
                return result
            parents = lm.Qa
        search.keep_best(lm)

    best_q = search.best_q if search.best_q is not None else 0.5 * (lower + upper)
    why = "timeout" if time.perf_counter() > search.deadline else "budget exhausted"
    extra = (f", {search.rejected} converged candidates rejected (sphere model or Drake)"
             if search.rejected else "")
    return verify(problem, best_q, method="hybrid", start=start, nfe=search.nfe, attempts=search.attempts,
                  message=f"{why} after {search.attempts} starts{extra}")
