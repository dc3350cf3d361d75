"""The constant-k search of one 3-link component: objective, feasibility, boundary.

The cyclic paper keeps each 3-link component's orientation angle constant, ``θg(t) = k``
(eq. (17)), and searches ``k`` inside the local orientation-angle boundary with a
metaheuristic, minimizing the joint path length (eq. (1)) with collisions infeasible
(eq. (21)). :class:`ThreeLinkProblem` is that search for one component given where its base
goes (the previous component's tip) and where its tip must go (the next moving base, or the
end-effector path), both over one period ``r = t/T ∈ [0, 1]``.

Eq. (21) as printed gives fitness **0** to a colliding candidate, which a minimizer would
prefer: the evident intent (and what we do) is that a collision, like an unreachable target or
a joint-limit violation, makes the candidate infeasible: ``+inf`` (the library's optimizers
treat ``+inf`` as the worst value).

Joint angles are made continuous in time (unwrapped) and each joint's trajectory is placed in
the 2π window ``[lower, lower + 2π)`` by its value at r = 0; a trajectory then satisfies the
limits iff some 2π shift of it does. The angles the paper's formulas give directly
(``atan2`` in (-π, π], eq. (19)'s difference) jump by 2π where a joint passes ±π: such a
trajectory violates ±π limits and is infeasible here.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from drake_mh.cyclic.fitness import converged_path_length, matlab_path_length
from drake_mh.cyclic.obstacles import CircleObstacle, segment_clearance
from drake_mh.cyclic.three_link import reachable_orientation, three_link_ik, three_link_points
from drake_mh.errors import InfeasibleComponent, InvalidArgument

__all__ = ["ThreeLinkProblem", "Evaluation", "Boundary", "InfeasibleComponent"]

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class Evaluation:
    """Everything computed for a population of ``P`` values of ``k`` (arrays over P).

    Attributes:
        k: ``(P,)`` [rad]. theta: ``(P, N, 3)`` continuous relative joint angles [rad].
        reachable: ``(P,)`` every sample has ``|c2| <= 1``.
        limit_excess: ``(P,)`` largest excursion beyond the joint limits [rad] (0: within).
        clearance: ``(P,)`` smallest link-obstacle clearance [m] (``inf`` without obstacles).
        closure: ``(P,)`` ``max |θ(1) - θ(0)|`` [rad] (0 for a cyclic trajectory).
        fitness: ``(P,)`` eq. (1) on the sample grid (MATLAB style); finite even if infeasible.
        feasible: ``(P,)`` reachable, within limits, collision-free, cyclic.
    """

    k: np.ndarray
    theta: np.ndarray
    reachable: np.ndarray
    limit_excess: np.ndarray
    clearance: np.ndarray
    closure: np.ndarray
    fitness: np.ndarray
    feasible: np.ndarray


@dataclass(frozen=True)
class Boundary:
    """The local orientation-angle boundary over one period (the paper's Figs. 2a and 3).

    Attributes:
        r: ``(N,)`` time-scale samples. theta_g_min, theta_g_max: ``(N,)`` reachable band
            from eqs. (13)-(15) [rad], continuous in r (NaN where unreachable).
        hole_min, hole_max: ``(N,)`` unreachable gap inside the band (NaN where none).
        grid: ``(G,)`` θg values [rad] of the per-sample feasibility map.
        feasible: ``(N, G)`` posture at (r, θg) reachable, within the limits that can be
            judged at one instant and collision-free (the shrunk boundary).
        shrunk_min, shrunk_max: ``(N,)`` envelope of ``feasible`` per sample (NaN: none).
        k_intervals: feasible intervals of the constant k over the whole period.
    """

    r: np.ndarray
    theta_g_min: np.ndarray
    theta_g_max: np.ndarray
    hole_min: np.ndarray
    hole_max: np.ndarray
    grid: np.ndarray
    feasible: np.ndarray
    shrunk_min: np.ndarray
    shrunk_max: np.ndarray
    k_intervals: list


def _copy3(value) -> np.ndarray:
    """A new float array of ``value``'s numbers (shape ``(0,)`` where it holds none: the callers'
    shape checks then name it)."""
    try:
        return np.zeros(0) if np.iscomplexobj(value) else np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):  # text, ragged nested lists
        return np.zeros(0)


class ThreeLinkProblem:
    """Constant-k planning of one 3-link component (eqs. (1), (7)-(12), (17)-(21)).

    Args:
        lengths: ``(3,)`` link lengths [m].
        base: ``base(r (N,)) -> (p_WB (N, 2) [m], phi_prev (N,) [rad])``: the component's base
            (end of the previous link; the origin for the first component) and the absolute
            orientation of the previous link (0 for a fixed base), over ``r = t/T ∈ [0, 1]``.
        target: ``target(r (N,)) -> p_WT (N, 2)`` [m]: where the tip must be.
        lower, upper: ``(3,)`` joint limits [rad] (``upper - lower <= 2π``).
        obstacles: circles the three links must not touch (eq. (6)).
        root: sign of eq. (8b), ``+1`` or ``-1``.
        n_samples: samples of one period, both ends included (the paper: 1000).
        link_radius: link half-thickness for the obstacle test [m] (0: the paper's lines).
        name: for messages.
    """

    def __init__(self, lengths, base: Callable, target: Callable, lower, upper,
                 obstacles: Sequence[CircleObstacle] = (), root: int = 1, n_samples: int = 1000,
                 link_radius: float = 0.0, name: str = "component"):
        self.lengths, self.lower, self.upper = (_copy3(v) for v in (lengths, lower, upper))  # copies
        if self.lengths.shape != (3,) or np.any(self.lengths <= 0):
            raise InvalidArgument(f"{name}: lengths must be 3 positive link lengths [m], got {lengths!r}")
        if (self.lower.shape != (3,) or self.upper.shape != (3,) or np.any(self.lower > self.upper)
                or np.any(self.upper - self.lower > TWO_PI + 1e-12)):
            raise InvalidArgument(f"{name}: lower/upper must be (3,) limits with lower <= upper <= lower + 2π, "
                                  f"got {lower!r}, {upper!r}")
        if root not in (1, -1):
            raise InvalidArgument(f"{name}: root must be +1 or -1 (the sign of eq. (8b)), got {root!r}")
        if isinstance(n_samples, bool) or not isinstance(n_samples, numbers.Integral) or n_samples < 8:
            raise InvalidArgument(f"{name}: n_samples must be an integer >= 8, got {n_samples!r}")
        self.base = base
        self.target = target
        self.obstacles = tuple(obstacles)
        self.root = int(root)
        self.link_radius = float(link_radius)
        self.name = name
        self.r = np.linspace(0.0, 1.0, int(n_samples))
        self.p_WB, self.phi_prev = self._base_at(self.r)
        self.p_WT = self._target_at(self.r)
        self._centres = np.array([o.centre for o in self.obstacles], dtype=float).reshape(-1, 2)
        self._radii = np.array([o.radius for o in self.obstacles], dtype=float) + self.link_radius

    # --- sampling ---------------------------------------------------------------------------

    def _base_at(self, r):
        p_WB, phi_prev = self.base(r)
        p_WB = np.asarray(p_WB, dtype=float).reshape(len(r), 2)
        phi_prev = np.broadcast_to(np.asarray(phi_prev, dtype=float), (len(r),)).copy()
        return p_WB, phi_prev

    def _target_at(self, r):
        return np.asarray(self.target(r), dtype=float).reshape(len(r), 2)

    def raw_angles(self, k, r=None):
        """Closed-form angles for ``k (P,)`` at ``r`` (default: the sample grid).

        Returns:
            ``(theta (P, N, 3), c2 (P, N), points (P, N, 4, 2))``: joint angles straight from
            eqs. (9), (11), (12), (19) (first joint wrapped to (-π, π], not yet continuous),
            eq. (8a)'s cosine, and base/elbow/wrist/tip positions [m].
        """
        k = np.atleast_1d(np.asarray(k, dtype=float)).reshape(-1)
        if r is None:
            p_WB, phi_prev, p_WT = self.p_WB, self.phi_prev, self.p_WT
        else:
            r = np.atleast_1d(np.asarray(r, dtype=float))
            (p_WB, phi_prev), p_WT = self._base_at(r), self._target_at(r)
        theta_g = np.broadcast_to(k[:, None], (len(k), len(p_WB)))
        t1s, t2s, t3s, c2 = three_link_ik((p_WT - p_WB)[None], theta_g, self.lengths, self.root)
        points = three_link_points(p_WB[None], t1s, t2s, theta_g, self.lengths)
        q1 = np.mod(t1s - phi_prev[None] + np.pi, TWO_PI) - np.pi  # eq. (19), wrapped to [-π, π)
        return np.stack([q1, t2s, t3s], axis=-1), c2, points

    def continuous(self, theta: np.ndarray) -> np.ndarray:
        """Unwraps ``theta (P, N, 3)`` along N and shifts each joint's trajectory by 2π·m so
        that its first sample lies in ``[lower, lower + 2π)``."""
        theta = np.unwrap(theta, axis=1)
        first = theta[:, :1, :]
        shift = TWO_PI * np.floor((first - self.lower) / TWO_PI)
        return theta - shift

    # --- evaluation ---------------------------------------------------------------------------

    def evaluate(self, k) -> Evaluation:
        """Feasibility and fitness of every ``k`` of a population ``(P,)`` (vectorized)."""
        k = np.atleast_1d(np.asarray(k, dtype=float)).reshape(-1)
        raw, c2, points = self.raw_angles(k)
        theta = self.continuous(raw)
        reachable = np.all(np.abs(c2) <= 1.0 + 1e-12, axis=1)
        excess = np.maximum(np.max(theta - self.upper, axis=1), np.max(self.lower - theta, axis=1))
        limit_excess = np.maximum(np.max(excess, axis=-1), 0.0)
        clearance = np.min(segment_clearance(points, self.obstacles, self.link_radius), axis=1) \
            if self.obstacles else np.full(len(k), np.inf)
        closure = np.max(np.abs(theta[:, -1, :] - theta[:, 0, :]), axis=-1)
        fitness = matlab_path_length(theta, self.r)
        feasible = reachable & (limit_excess <= 0.0) & (clearance > 0.0) & (closure < 1e-6)
        return Evaluation(k, theta, reachable, limit_excess, clearance, closure, fitness, feasible)

    def evaluate_fast(self, k) -> tuple[np.ndarray, np.ndarray]:
        """``(feasible (P,), fitness (P,))`` by the fused numba kernel (no joint angles kept).

        Same numbers as :meth:`evaluate` (tested), about 5x faster: the optimizers' path.
        """
        from drake_mh.cyclic.evaluation import evaluate_population

        k = np.ascontiguousarray(np.atleast_1d(np.asarray(k, dtype=float)).reshape(-1))
        P = len(k)
        reachable = np.empty(P, dtype=np.bool_)
        excess, clearance, closure, fitness = (np.empty(P) for _ in range(4))
        evaluate_population(k, self.p_WB, self.phi_prev, self.p_WT, self.lengths, self.root, self.lower,
                            self.upper, self._centres, self._radii, self.r, reachable, excess, clearance,
                            closure, fitness)
        feasible = reachable & (excess <= 0.0) & (clearance > 0.0) & (closure < 1e-6)
        return feasible, fitness

    def feasible(self, k) -> np.ndarray:
        """``(P,)`` bool: ``k`` keeps the component feasible over the whole period."""
        return self.evaluate_fast(k)[0]

    def objective(self, X) -> np.ndarray:
        """The optimizers' objective ``f(X (P, 1)) -> (P,)``: eq. (1) (MATLAB style) where
        feasible, ``+inf`` where not (eq. (21) read as "collision = infeasible")."""
        X = np.asarray(X, dtype=float)
        feasible, fitness = self.evaluate_fast(X.reshape(len(X), -1)[:, 0])
        return np.where(feasible, fitness, np.inf)

    def converged_fitness(self, k: float, n: int = 8192):
        """Eq. (1) as an integral at one ``k`` (see :func:`converged_path_length`).

        Returns ``(value, error_estimate)``.
        """
        def theta_of_r(r):
            raw, _, _ = self.raw_angles([k], r)
            return raw[0]
        return converged_path_length(theta_of_r, n)

    # --- boundary -------------------------------------------------------------------------------

    def feasible_intervals(self, resolution: int = 720, tol: float = 1e-10) -> list[tuple[float, float]]:
        """Intervals of constant ``k`` that keep the component feasible over the period.

        A grid of ``resolution`` values over one turn ``[-π, π)`` is tested, then every edge is
        refined by bisection to ``tol``. Feasible sets narrower than the grid step
        (2π/resolution) can be missed.

        Returns:
            Sorted ``[(lo, hi), ...]`` [rad] with ``-π <= lo < hi``; an interval through ±π is
            returned once with ``hi > π``. ``lo`` and ``hi`` are feasible and ``lo - tol``,
            ``hi + tol`` are not; inside, every grid value is feasible (an infeasible gap
            narrower than the grid step could be missed; the tests sample inside at random).
        """
        grid = -np.pi + TWO_PI * np.arange(int(resolution)) / int(resolution)
        ok = np.concatenate([self.feasible(chunk) for chunk in np.array_split(grid, max(1, len(grid) // 256))])
        if ok.all():
            return [(-np.pi, np.pi)]
        if not ok.any():
            return []
        step = grid[1] - grid[0]
        start = int(np.argmin(ok))  # an infeasible index: rotate so the sequence starts there
        order = (np.arange(len(grid)) + start) % len(grid)
        okr = ok[order]
        kr = grid[order] + np.where(order < start, TWO_PI, 0.0)  # continuous, increasing
        okr = np.append(okr, False)  # okr[0] is infeasible: close the circle
        kr = np.append(kr, kr[-1] + step)
        edges = np.flatnonzero(np.diff(okr.astype(int)))
        rises = [i for i in edges if not okr[i]]  # infeasible at i, feasible at i+1
        falls = [i for i in edges if okr[i]]       # feasible at i, infeasible at i+1
        lo_bad = np.array([kr[i] for i in rises] + [kr[i] + step for i in falls])
        lo_good = np.array([kr[i] + step for i in rises] + [kr[i] for i in falls])
        bad, good = lo_bad.copy(), lo_good.copy()
        while np.max(np.abs(good - bad)) > tol:
            mid = 0.5 * (bad + good)
            f = self.feasible(mid)
            good = np.where(f, mid, good)
            bad = np.where(f, bad, mid)
        lows, highs = good[: len(rises)], good[len(rises):]
        intervals = []
        for lo in lows:
            hi = min(h for h in highs if h > lo)
            while lo >= np.pi:
                lo, hi = lo - TWO_PI, hi - TWO_PI
            intervals.append((float(lo), float(hi)))
        return sorted(intervals)

    def boundary(self, n_grid: int = 721, resolution: int = 720) -> Boundary:
        """The orientation-angle boundary: reachable band (eqs. (13)-(15)) and its shrinking.

        Per sample, ``θg`` on a grid over the reachable band is kept where the posture is
        reachable, collision-free and satisfies the limits of the middle and last joint and the
        first joint's limits when they are narrower than ±π (a first joint's ±π window can only
        be judged over the whole trajectory, see :meth:`feasible_intervals`).
        """
        lo, hi, hole_lo, hole_hi = reachable_orientation(self.p_WT - self.p_WB, self.lengths)
        start, stop = np.nanmin(lo), np.nanmax(hi)
        grid = np.linspace(start, stop, int(n_grid))
        theta_g = np.broadcast_to(grid[None, :], (len(self.r), len(grid)))
        p_BT = (self.p_WT - self.p_WB)[:, None, :]
        t1s, t2s, t3s, c2 = three_link_ik(p_BT, theta_g, self.lengths, self.root)
        q = np.stack([np.angle(np.exp(1j * (t1s - self.phi_prev[:, None]))), t2s,
                      np.angle(np.exp(1j * t3s))], -1)
        within = np.all((q >= self.lower - 1e-12) & (q <= self.upper + 1e-12), axis=-1)
        points = three_link_points(self.p_WB[:, None, :], t1s, t2s, theta_g, self.lengths)
        free = segment_clearance(points, self.obstacles, self.link_radius) > 0.0
        feasible = (np.abs(c2) <= 1.0) & within & free
        with np.errstate(invalid="ignore"):
            gmin = np.where(feasible.any(1), np.min(np.where(feasible, grid, np.inf), axis=1), np.nan)
            gmax = np.where(feasible.any(1), np.max(np.where(feasible, grid, -np.inf), axis=1), np.nan)
        return Boundary(self.r, lo, hi, hole_lo, hole_hi, grid, feasible, gmin, gmax,
                        self.feasible_intervals(resolution))
