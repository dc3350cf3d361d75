"""Cyclic path planning: compose the components, search each constant k, return a plan.

The paper's algorithm (its Sec. III.B and Fig. 1), component by component from the base:

1. the 2-link component's joint trajectories are known (eq. (16), stages of eq. (25));
2. each 3-link component's base is the tip of everything before it (forward kinematics,
   eq. (3)); its local orientation-angle boundary gives the feasible interval of the constant
   ``k`` (joint limits and obstacles shrink it); a metaheuristic searches ``k`` in that
   interval minimizing eq. (1);
3. the joint angles follow from eqs. (7)-(12), (19)-(20).

Components are planned in order because the first joint of a 3-link component is relative to
the previous link (eq. (19)), whose orientation the earlier ``k`` fixes; the fitness of a
component does not depend on earlier ``k`` values (a constant offset), only its first joint's
limits do.

:func:`plan` runs the search with any optimizer of :func:`drake_mh.optim.available_methods`
(the paper: GA and WOA, 20 individuals, 100 iterations); :func:`plan_with_k` composes given
``k`` values. The resulting :class:`CyclicPlan` gives ``q(t)`` at any time, exports sampled
trajectories, and is verified with Drake (:mod:`drake_mh.cyclic.verify`).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from drake_mh.cyclic.problem import InfeasibleComponent, ThreeLinkProblem
from drake_mh.cyclic.task import CyclicTask, ThreeLinkComponent, TwoLinkComponent
from drake_mh.cyclic.three_link import three_link_ik
from drake_mh.errors import InvalidArgument, NoFiniteValue
from drake_mh.optim.base import check_seed, summarize_array

logger = logging.getLogger(__name__)

__all__ = ["compose", "component_problem", "plan", "plan_with_k", "CyclicPlan", "ComponentResult"]

TWO_PI = 2.0 * np.pi


def _wrap_into(theta, lower):
    """``theta`` shifted by 2π·m into ``[lower, lower + 2π)``."""
    return theta - TWO_PI * np.floor((theta - lower) / TWO_PI)


def compose(task: CyclicTask, ks: Sequence[float], t, upto: int | None = None):
    """Joint angles of the components before ``upto`` (all by default) at times ``t``.

    Args:
        task: the task.
        ks: one constant orientation angle per 3-link component [rad] (only those before
            ``upto`` are used).
        t: ``(N,)`` times [s].
        upto: number of components to compose.

    Returns:
        ``(q (N, m), p_W (N, 2), phi (N,))``: joint angles [rad] of the first ``m`` joints, each
        wrapped into ``[lower, lower + 2π)`` (continuous for a feasible plan), the tip of the
        composed part [m] and the absolute orientation of its last link [rad].
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    upto = len(task.components) if upto is None else int(upto)
    lengths, lower = np.asarray(task.lengths), np.asarray(task.lower)
    p = np.zeros((len(t), 2))
    phi = np.zeros(len(t))
    columns = []
    k_iter = iter(ks)
    for c, sl in zip(task.components[:upto], task.joint_slices()[:upto]):
        L, lo = lengths[sl], lower[sl]
        if isinstance(c, TwoLinkComponent):
            q = c.trajectory.q(t)
            for j in range(2):
                phi = phi + q[:, j]
                p = p + L[j] * np.stack([np.cos(phi), np.sin(phi)], -1)
        else:
            k = float(next(k_iter))
            target = c.target.position(t)
            t1s, t2s, t3s, _ = three_link_ik(target - p, np.full(len(t), k), L, c.root)
            q = np.stack([_wrap_into(t1s - phi, lo[0]), _wrap_into(t2s, lo[1]), _wrap_into(t3s, lo[2])], -1)
            a1, a2 = t1s, t1s + t2s
            p = (p + L[0] * np.stack([np.cos(a1), np.sin(a1)], -1) + L[1] * np.stack([np.cos(a2), np.sin(a2)], -1)
                 + L[2] * np.stack([np.cos(k) * np.ones(len(t)), np.sin(k) * np.ones(len(t))], -1))
            phi = np.full(len(t), k)
        columns.append(q)
    q = np.concatenate(columns, axis=1) if columns else np.zeros((len(t), 0))
    return q, p, phi


def component_problem(task: CyclicTask, index: int, ks_before: Sequence[float]) -> ThreeLinkProblem:
    """The :class:`ThreeLinkProblem` of 3-link component ``index`` (an index into
    ``task.components``) given the ``k`` of the 3-link components before it."""
    comp = task.components[index]
    if not isinstance(comp, ThreeLinkComponent):
        raise InvalidArgument(f"component {index} ({type(comp).__name__}) has no k to search")
    sl = task.joint_slices()[index]
    T = task.period
    ks_before = list(ks_before)

    def base(r):
        _, p, phi = compose(task, ks_before, np.asarray(r) * T, upto=index)
        return p, phi

    return ThreeLinkProblem(
        np.asarray(task.lengths)[sl], base, lambda r: comp.target.position(np.asarray(r) * T),
        np.asarray(task.lower)[sl], np.asarray(task.upper)[sl], task.obstacles, comp.root,
        task.n_samples, task.link_radius, name=comp.name)


@dataclass(frozen=True)
class ComponentResult:
    """Outcome for one 3-link component.

    Attributes:
        name: component name. index: index into ``task.components``.
        k: chosen constant orientation angle [rad].
        fitness: eq. (1), MATLAB style (the paper's number). fitness_converged: the integral
            (Richardson), and fitness_error: its error estimate.
        intervals: feasible intervals of k. search: the box searched.
        result: the optimizer's :class:`~drake_mh.optim.OptimizeResult` (``None`` when k was given).
    """

    name: str
    index: int
    k: float
    fitness: float
    fitness_converged: float
    fitness_error: float
    intervals: list
    search: tuple
    result: object = None

    def __repr__(self) -> str:
        """One line: name, k, eq. (1) fitness and the optimizer's run (not its history)."""
        r = self.result
        run = "k given" if r is None else f"{r.method or 'optimizer'}: nfe {r.nfe}, {r.time:.3g} s"
        return (f"ComponentResult({self.name!r}, k = {self.k:.6g} rad, fitness = {self.fitness:.6g}, "
                f"{len(self.intervals)} feasible interval(s), {run})")


@dataclass(frozen=True)
class CyclicPlan:
    """Planned periodic joint trajectories of a :class:`CyclicTask`.

    Attributes:
        task: the task. ks: one k per 3-link component [rad]. components: their results.
    """

    task: CyclicTask
    ks: tuple
    components: tuple = field(default=())

    @property
    def period(self) -> float:
        return self.task.period

    def __repr__(self) -> str:
        """A few lines: the task, the k values, the fitness and one line per 3-link component."""
        lines = [f"CyclicPlan({self.task.name!r}: {self.task.n} joints, period {self.period:.6g} s, "
                 f"{len(self.task.obstacles)} obstacle(s))",
                 f"  fitness (eq. (1), sum) = {self.fitness:.6g}",
                 f"  ks = {summarize_array(np.asarray(self.ks, dtype=float))} rad"]
        lines += [f"  {c!r}" for c in self.components]
        return "\n".join(lines)

    __str__ = __repr__

    @property
    def fitness(self) -> float:
        """Sum of the 3-link components' eq. (1) values (MATLAB style)."""
        return float(sum(c.fitness for c in self.components))

    def q(self, t) -> np.ndarray:
        """Joint angles ``(N, n)`` [rad] at times ``t (N,)`` [s]; periodic in t by construction."""
        return compose(self.task, self.ks, t)[0]

    def ee(self, t) -> np.ndarray:
        """Planar FK of the plan's end effector ``(N, 2)`` [m] (the library's own, see verify)."""
        return compose(self.task, self.ks, t)[1]

    def trajectory(self, cycles: int = 1, samples_per_cycle: int = 200) -> tuple[np.ndarray, np.ndarray]:
        """Sampled joint trajectory over ``cycles`` periods for export / animation.

        Returns:
            ``t (cycles·samples_per_cycle + 1,)`` [s] and ``Q (len(t), n)`` [rad].
        """
        if int(cycles) < 1 or int(samples_per_cycle) < 2:
            raise InvalidArgument("cycles must be >= 1 and samples_per_cycle >= 2")
        t = np.linspace(0.0, cycles * self.period, int(cycles) * int(samples_per_cycle) + 1)
        return t, self.q(t)

    def to_piecewise_polynomial(self, cycles: int = 1, samples_per_cycle: int = 200):
        """A Drake ``PiecewisePolynomial`` (shape-preserving cubic) through :meth:`trajectory`,
        e.g. for ``drake_mh.viz.show(robot, traj)``."""
        from pydrake.trajectories import PiecewisePolynomial

        t, Q = self.trajectory(cycles, samples_per_cycle)
        return PiecewisePolynomial.CubicShapePreserving(t, Q.T, zero_end_point_derivatives=False)

    def save_npz(self, path, cycles: int = 1, samples_per_cycle: int = 200) -> None:
        """Writes ``t``, ``q``, ``ks``, ``period`` and ``lengths`` to an ``.npz`` file."""
        t, Q = self.trajectory(cycles, samples_per_cycle)
        np.savez(path, t=t, q=Q, ks=np.asarray(self.ks), period=self.period, lengths=np.asarray(self.task.lengths))


def _child_seed(seed, i: int):
    if seed is None:
        return None
    return int(np.random.SeedSequence([check_seed(seed), i]).generate_state(1)[0])


def _finish(task, index, problem, k, intervals, search, result, converged_n) -> ComponentResult:
    ev = problem.evaluate([k])
    if not ev.feasible[0]:
        raise InfeasibleComponent(task.components[index].name,
                                  f"k = {k:.6g} is infeasible (reachable={bool(ev.reachable[0])}, limit excess "
                                  f"{ev.limit_excess[0]:.3g} rad, clearance {ev.clearance[0]:.3g} m); feasible "
                                  f"intervals: {intervals}")
    value, err = problem.converged_fitness(k, converged_n) if converged_n else (np.nan, np.nan)
    return ComponentResult(task.components[index].name, index, float(k), float(ev.fitness[0]), float(value),
                           float(err), intervals, tuple(search), result)


def plan_with_k(task: CyclicTask, ks: Sequence[float], converged_n: int = 8192,
                check: bool = True) -> CyclicPlan:
    """Composes a plan with given k values (one per 3-link component, arm order).

    Raises:
        InfeasibleComponent: with ``check``, a k makes its component infeasible.
    """
    idx = task.three_link_indices()
    ks = [float(k) for k in ks]
    if len(ks) != len(idx):
        raise InvalidArgument(f"give one k per 3-link component: {len(idx)} expected, got {len(ks)}")
    results = []
    if check:
        for j, i in enumerate(idx):
            problem = component_problem(task, i, ks[:j])
            results.append(_finish(task, i, problem, ks[j], [], (ks[j], ks[j]), None, converged_n))
    return CyclicPlan(task, tuple(ks), tuple(results))


def plan(task: CyclicTask, method: str = "woa", budget: int = 2000, seed=0, pop_size: int | None = 20,
         k_decimals: int | None = None, converged_n: int = 8192, resolution: int = 720,
         **params) -> CyclicPlan:
    """Searches every 3-link component's constant k with an optimizer of the library.

    Args:
        task: the task.
        method: a name of :func:`drake_mh.optim.available_methods` (the paper: ``"ga"``,
            ``"woa"``). CMA-ES needs D >= 2 and refuses these 1-D searches.
        budget: function evaluations per component (the paper: 100 iterations × 20 = 2000).
        seed: int seed; component i uses a seed derived from ``(seed, i)``.
        pop_size: population (the paper: 20); ``None``: the method's default.
        k_decimals: round k to this many decimals before evaluating (the paper: 4); ``None``.
        converged_n: samples for the converged fitness (0 skips it).
        resolution: grid of the feasible-interval search (see
            :meth:`ThreeLinkProblem.feasible_intervals`).
        **params: the optimizer's hyper-parameters.

    Returns:
        The :class:`CyclicPlan` (``components[i].result`` holds each optimizer result with its
        ``history`` of (nfe, best f)).

    Raises:
        InfeasibleComponent: a component has no feasible k, or the optimizer found none.
    """
    from drake_mh.optim import minimize

    if seed is not None:
        check_seed(seed)  # before any work (1.5 was truncated, "abc" was numpy's error)
    ks: list[float] = []
    results = []
    for j, i in enumerate(task.three_link_indices()):
        comp = task.components[i]
        problem = component_problem(task, i, ks)
        intervals = problem.feasible_intervals(resolution)
        if not intervals:
            raise InfeasibleComponent(comp.name, _why_infeasible(problem))
        search = comp.search or (intervals[0][0], intervals[-1][1])
        objective = problem.objective
        if k_decimals is not None:
            objective = _rounded(problem.objective, int(k_decimals))
        try:
            res = minimize(objective, [search], method=method, budget=budget, seed=_child_seed(seed, j),
                           pop_size=pop_size, **params)
        except NoFiniteValue:
            raise InfeasibleComponent(comp.name, f"{method} found no feasible k in {search} within {budget} "
                                      f"evaluations (feasible intervals: {intervals}); raise the budget") from None
        k = float(np.round(res.x[0], k_decimals)) if k_decimals is not None else float(res.x[0])
        results.append(_finish(task, i, problem, k, intervals, search, res, converged_n))
        ks.append(k)
        logger.info("%s: k = %.6f, fitness %.7f (%s)", comp.name, k, results[-1].fitness, method)
    return CyclicPlan(task, tuple(ks), tuple(results))


def _rounded(objective, decimals: int):
    def f(X):
        return objective(np.round(np.asarray(X, dtype=float), decimals))
    return f


def _why_infeasible(problem: ThreeLinkProblem) -> str:
    d = np.linalg.norm(problem.p_WT - problem.p_WB, axis=1)
    L = problem.lengths
    outer, inner = L.sum(), max(0.0, 2 * L.max() - L.sum())
    if d.max() > outer or d.min() < inner:
        return (f"the tip target is {d.min():.4g} .. {d.max():.4g} m from the component's base but its reach is "
                f"{inner:.4g} .. {outer:.4g} m: move the moving base / 2-link knots closer to the target curve")
    return ("every k violates a joint limit or an obstacle somewhere in the period: widen the limits, move "
            "the moving base, or split the component's motion differently")
