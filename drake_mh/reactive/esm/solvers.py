"""Step solvers of the ESM scheme: any ``drake_mh.optim`` method, warm-started step to step.

A *step solver* turns an :class:`drake_mh.reactive.esm.problem.ESMStep` into the next joint
angles. It keeps its state (the last population) between the steps of one run; ``reset``
starts a run with a seed. The QP baseline (:mod:`drake_mh.reactive.esm.qp_baseline`) and AMNN
(:mod:`drake_mh.reactive.esm.amnn`) implement the same two methods.

Warm start (every metaheuristic): the first layer of a step is the previous step's final
population, clipped into the new box of eq. (11) and repaired onto the new obstacle
inequalities, with row 0 replaced by (the repair of) ``θ_prev`` itself, so the step's answer
is never worse than standing still when standing still is feasible. Per step the optimizer
gets a fresh seed drawn from the run's ``numpy.random.Generator``: a run is deterministic
per seed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import make_rng
from drake_mh.reactive.esm.config import CONSTRAINT_HANDLINGS
from drake_mh.reactive.esm.problem import ESMObjective, ESMStep


@dataclass(frozen=True)
class StepSolution:
    """Outcome of one control step.

    Attributes:
        theta: the new joint angles ``θ(t)`` ``(nq,)`` [rad] (always inside the box of eq. (11)).
        F: objective value at ``theta`` (eq. (10)).
        feasible: ``theta`` satisfies the obstacle inequalities (solver's own check; the
            controller re-checks with Drake).
        nfe: objective evaluations (metaheuristics) or QP iterations (baseline).
        time: wall-clock time of the solve [s] (constraint building excluded).
        message: solver status.
    """

    theta: np.ndarray
    F: float
    feasible: bool
    nfe: int
    time: float
    message: str = ""


class StepSolver:
    """Base class: ``reset(seed)`` once per run, then ``solve(robot, step)`` once per step."""

    name = "solver"

    def reset(self, seed=None) -> None:
        """Starts a new run (forgets the warm-start state).

        Raises:
            InvalidArgument: ``seed`` is not ``None``, an integer >= 0 or a numpy seed object.
        """
        self.rng = make_rng(seed, "seed")

    def solve(self, robot, step: ESMStep) -> StepSolution:  # pragma: no cover - interface
        raise NotImplementedError

    @property
    def budget_label(self) -> str:
        """Human-readable budget per step (e.g. ``"L=300 x P=32"``)."""
        return ""


def warm_start_rows(step: ESMStep, population: np.ndarray | None, population_f: np.ndarray | None = None,
                    immigrants: float = 0.0, rng: np.random.Generator | None = None) -> np.ndarray:
    """The first layer of a step: ``(K, nq)`` rows inside the new feasible set, row 0 = ``θ_prev``.

    Args:
        step: the current step.
        population: the previous step's final population ``(P, nq)`` or ``None``.
        population_f: its objective values ``(P,)`` (under the previous step's objective).
        immigrants: fraction of the population (the worst by ``population_f``) replaced by
            uniform samples in the new box ("random immigrants"): difference-based methods
            (DE, GA, ABC) stall on a warm start whose members have collapsed onto one point.
        rng: generator of the immigrants.

    Returns:
        The rows, clipped into the box of eq. (11) and repaired onto eq. (9).
    """
    if population is None:
        return step.repair(step.theta_prev[None])[0]
    rows = np.array(population, dtype=float, copy=True)
    n_new = int(round(immigrants * len(rows)))
    if n_new > 0 and rng is not None:
        order = np.argsort(population_f) if population_f is not None else np.arange(len(rows))
        worst = order[len(rows) - n_new:]
        rows[worst] = step.lower + rng.random((n_new, rows.shape[1])) * (step.upper - step.lower)
    best = int(np.argmin(population_f)) if population_f is not None else 0
    rows[[0, best]] = rows[[best, 0]]          # keep the previous best, put it first ...
    rows[0] = step.theta_prev                  # ... and replace it by θ_prev (= the answer)
    return step.repair(rows)[0]


class MetaheuristicSolver(StepSolver):
    """Any :func:`drake_mh.optim.available_methods` optimizer as an ESM step solver.

    Args:
        method: optimizer name (``"pso"``, ``"de"``, ``"aro"`` ...).
        budget: objective evaluations per control step.
        pop_size: population size (``None``: the method's default).
        handling: ``"repair"`` (default for methods that are not greedy per agent) or
            ``"reject"`` (see :mod:`drake_mh.reactive.esm.problem`).
        warm_start: start each step from the previous population (module docstring);
            ``False`` starts from ``θ_prev`` plus a uniform population in the box.
        immigrants: fraction of the warm-start population replaced by uniform samples
            (:func:`warm_start_rows`); default 0.25.
        **params: the optimizer's hyper-parameters.

    Raises:
        UnknownMethod: unknown method (lists the names).
        InvalidArgument: bad budget, handling or parameters.
    """

    def __init__(self, method: str, budget: int, pop_size: int | None = None, handling: str = "repair",
                 warm_start: bool = True, immigrants: float = 0.25, **params):
        from drake_mh.optim import get_method
        from drake_mh.optim.base import check_budget

        self.cls = get_method(method)
        self.method = self.cls.name
        self.name = self.method
        self.budget = check_budget(budget)
        if handling not in CONSTRAINT_HANDLINGS:
            raise InvalidArgument(f"handling must be one of {CONSTRAINT_HANDLINGS}; got {handling!r}")
        self.handling = handling
        self.pop_size = pop_size
        self.warm_start = bool(warm_start)
        if not (isinstance(immigrants, (int, float)) and 0.0 <= immigrants < 1.0):
            raise InvalidArgument(f"immigrants must be a fraction in [0, 1); got {immigrants!r}")
        self.immigrants = float(immigrants)
        self.params = dict(params)
        self.cls._make_config(self.params)  # unknown parameters fail now, not at the first step
        self.population = self.population_f = None
        self.reset(None)

    def reset(self, seed=None) -> None:
        super().reset(seed)
        self.population = self.population_f = None

    @property
    def budget_label(self) -> str:
        return f"{self.budget} evaluations (P={self.pop_size or 'default'})"

    def _first_layer(self, step: ESMStep) -> np.ndarray:
        """The warm-start rows of this step (:func:`warm_start_rows`); row 0 is the fallback."""
        if self.warm_start:
            return warm_start_rows(step, self.population, self.population_f, self.immigrants, self.rng)
        return warm_start_rows(step, None)

    def _optimizer(self, step: ESMStep, x0: np.ndarray):
        seed = int(self.rng.integers(2**63 - 1))
        return self.cls(step.bounds, budget=self.budget, seed=seed, pop_size=self.pop_size, x0=x0, **self.params)

    def solve(self, robot, step: ESMStep) -> StepSolution:
        from drake_mh.optim.base import run

        t0 = time.perf_counter()
        objective = ESMObjective(robot, step, self.handling)
        x0 = self._first_layer(step)
        opt = self._optimizer(step, x0[: opt_pop(self.cls, self.pop_size, step.lower.size)])
        result = run(opt, objective)
        if result.population is not None and len(result.population) > 1:
            self.population, self.population_f = result.population, result.population_f
        theta, F, feasible = _answer(robot, step, objective, result.x, result.f, x0[0])
        return StepSolution(theta, F, feasible, result.nfe, time.perf_counter() - t0, result.message)


def opt_pop(cls, pop_size: int | None, dim: int) -> int:
    """Population size an optimizer class will use."""
    return cls.default_pop_size(dim) if pop_size is None else int(pop_size)


def _answer(robot, step: ESMStep, objective: ESMObjective, x, f: float, fallback: np.ndarray):
    """The configuration a run stands for; ``fallback`` (repaired ``θ_prev``) if none is feasible."""
    if np.isfinite(f):
        theta = objective.resolve(x)
        return theta, float(f), True
    theta = np.asarray(fallback, dtype=float).copy()
    F = float(objective.values(theta[None])[0][0])
    return theta, F, bool(step.feasible(theta[None])[0])
