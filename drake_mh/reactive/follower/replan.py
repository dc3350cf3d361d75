"""Re-planning the part of a Cartesian path that an obstacle cuts (framework paper §3.4.2, Algorithm 2).

When an obstacle moves *onto the path itself* (not only onto the arm, §3.4.1), the framework
paper takes, around the ``nC`` path points that collide, ``3·nC`` points of the path and
replaces them with points found by the metaheuristic: for each input point, "the point which
is nearest to the i-th input point ... with the constraint that it is not colliding with the
obstacle" (Algorithm 2, steps 6-18). New joint solutions are then generated for the new points.

Our reading, stated here and in ``docs/follower.md``:

* **Colliding path point.** Point ``p_k`` collides when its signed distance to some obstacle
  is below ``tool_clearance`` [m] (closed-form point-to-shape distance, exact for spheres, boxes,
  cylinders and capsules). The clearance stands for the tool's own size and the arm's margin:
  the default 0.07 m = the 6-DOF arm's last capsule radius 0.035 m + the follower's IK
  clearance 0.015 m + the sphere model's pessimism 0.008 m (the IK objective sees obstacles
  through it) + 0.012 m. With 0.05 m the metaheuristic IK of the new points missed them by
  7 mm: its conservative sphere model saw a collision where Drake saw none. The arm's configurations are always judged
  by Drake's exact signed distance (:mod:`drake_mh.reactive.follower.follower`).
* **"3·nC points around".** Colliding points are grouped into *runs* of consecutive indices.
  A run of ``n`` points ``[a, b]`` takes the ``n`` points before it and the ``n`` points after
  it: the window ``[a - n, b + n]`` (``3n`` points, the paper's ``3·nC`` for one run; ``nC``
  colliding + ``nC`` before + ``nC`` after, an even split). The window is clipped to the points
  the arm has not reached yet and to the end of the path (then it holds fewer than ``3n``
  points). Windows that overlap or touch are merged into one (their runs then share the
  window), so every window is replaced in one pass and no point is re-planned twice.
* **Algorithm 2, one point at a time.** For input point ``p_i`` a population of 3-D points in
  the box ``p_i ± h`` (``h``: the largest obstacle circumradius + ``tool_clearance`` + 2 cm,
  enough to reach outside any obstacle) minimizes, vectorized over the population,
  ``f(x) = ||x - p_i|| + w · Σ_obstacles max(0, c - sd(x))`` — the distance to the input point
  plus an exact penalty (``w = 10 > 1``, the largest slope of the distance term, so the
  penalized minimum is the constrained one) for missing the clearance ``c = tool_clearance +
  1 mm``. The initial population contains ``p_i`` itself and the previous new point (warm
  start): a free input point is its own nearest free point (``f = 0``) and stays exactly where
  it was — the optimizer stops at once (``target=0``).

Any optimizer of :func:`drake_mh.optim.available_methods` runs Algorithm 2.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument, UnknownMethod

__all__ = ["ReplanConfig", "ReplanResult", "path_point_clearance", "colliding_path_points", "collision_runs",
           "replan_windows", "nearest_free_point", "replan_points", "obstacle_circumradius"]

#: [m] added to ``tool_clearance`` inside Algorithm 2's penalty so the optimum lands strictly outside
PENALTY_MARGIN = 1e-3
#: exact-penalty weight of Algorithm 2's objective (any value > 1 makes the penalized optimum the constrained one)
PENALTY_WEIGHT = 10.0


@dataclass(frozen=True)
class ReplanConfig:
    """Settings of Algorithm 2 (framework paper §3.4.2).

    Attributes:
        method: optimizer of :func:`drake_mh.optim.available_methods`; ``None``: the
            follower's IK method if it is an optimizer, else ``"pso"``.
        budget: function evaluations per path point (default 2,000; the objective is a few
            µs per population).
        pop_size: population size (``None``: the method's default).
        tool_clearance: [m] distance a path point must keep from every obstacle (default
            0.07; see the module docstring).
    """

    method: str | None = None
    budget: int = 2000
    pop_size: int | None = None
    tool_clearance: float = 0.07

    def __post_init__(self):
        if self.method is not None:
            from drake_mh.optim import available_methods

            if not isinstance(self.method, str) or self.method.lower() not in available_methods():
                raise UnknownMethod(str(self.method), available_methods(), what="path re-planning optimizer")
            object.__setattr__(self, "method", self.method.lower())
        if isinstance(self.budget, bool) or int(self.budget) != self.budget or self.budget < 10:
            raise InvalidArgument(f"ReplanConfig.budget must be an integer >= 10 evaluations, got {self.budget!r}")
        if not (np.isfinite(self.tool_clearance) and self.tool_clearance >= 1e-4):
            raise InvalidArgument(f"ReplanConfig.tool_clearance must be >= 1e-4 m (Drake's GJK is up to 6e-5 m "
                                  f"optimistic), got {self.tool_clearance!r}")

    def optimizer(self, ik_method: str) -> str:
        """The optimizer Algorithm 2 uses when the follower solves IK with ``ik_method``."""
        from drake_mh.optim import available_methods

        if self.method is not None:
            return self.method
        return ik_method if ik_method in available_methods() else "pso"


@dataclass(frozen=True)
class ReplanResult:
    """One window re-planned by Algorithm 2.

    Attributes:
        window: ``(n,)`` path indices replaced (increasing, contiguous).
        colliding: ``(m,)`` the colliding path indices inside the window.
        old_points, new_points: ``(n, 3)`` [m] before and after.
        tool_clearance: ``(n,)`` [m] signed distance of each new point to the nearest obstacle.
        nfe: evaluations used; time: [s].
    """

    window: np.ndarray
    colliding: np.ndarray
    old_points: np.ndarray
    new_points: np.ndarray
    tool_clearance: np.ndarray
    nfe: int
    time: float

    @property
    def moved(self) -> np.ndarray:
        """Indices of the window whose point actually moved (> 1e-12 m)."""
        return self.window[np.linalg.norm(self.new_points - self.old_points, axis=1) > 1e-12]


def obstacle_circumradius(shape) -> float:
    """Radius [m] of the smallest origin-centred sphere containing ``shape``."""
    from drake_mh.geometry.shapes import Box, Capsule, Cylinder, Sphere

    if isinstance(shape, Sphere):
        return float(shape.radius)
    if isinstance(shape, Box):
        return 0.5 * float(np.linalg.norm(shape.size))
    if isinstance(shape, Cylinder):
        return float(np.hypot(shape.radius, 0.5 * shape.length))
    if isinstance(shape, Capsule):
        return float(shape.radius + 0.5 * shape.length)
    if hasattr(shape, "circumradius"):  # a mesh, a point cloud
        return float(shape.circumradius)
    raise InvalidArgument(f"unsupported obstacle shape {type(shape).__name__}")


def path_point_clearance(points_W, scene) -> np.ndarray:
    """Signed distance ``(N,)`` [m] of each point ``points_W (N, 3)`` to the nearest obstacle.

    Closed-form point-to-shape distances (exact for the scene's primitive shapes and point
    clouds, a lower bound for meshes: their convex pieces' planes); ``inf`` without obstacles.
    """
    P = np.asarray(points_W, dtype=float).reshape(-1, 3)
    out = np.full(len(P), np.inf)
    for obstacle in scene.obstacles.values():
        R, p = obstacle.X_WO[:3, :3], obstacle.X_WO[:3, 3]
        out = np.minimum(out, obstacle.shape.signed_distance((P - p) @ R))
    return out


def colliding_path_points(points_W, scene, tool_clearance: float, start: int = 0) -> np.ndarray:
    """Indices ``k >= start`` of the path points closer than ``tool_clearance`` [m] to an obstacle."""
    P = np.asarray(points_W, dtype=float)
    d = path_point_clearance(P[start:], scene)
    return np.flatnonzero(d < tool_clearance) + int(start)


def collision_runs(indices) -> list[tuple[int, int]]:
    """Maximal runs ``[(a, b), ...]`` (inclusive) of consecutive integers in ``indices``."""
    idx = np.unique(np.asarray(indices, dtype=int))
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > 1)
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks, [idx.size - 1]])
    return [(int(idx[s]), int(idx[e])) for s, e in zip(starts, ends)]


def replan_windows(colliding, lo: int, hi: int) -> list[np.ndarray]:
    """The ``3·nC`` windows around runs of colliding path points (module docstring).

    Args:
        colliding: colliding path indices.
        lo, hi: first and last index that may be replaced (inclusive): the first point the arm
            has not reached and the last point of the path.

    Returns:
        Windows as increasing index arrays; overlapping or touching windows merged.
    """
    spans = []
    for a, b in collision_runs(colliding):
        n = b - a + 1
        spans.append([max(lo, a - n), min(hi, b + n)])
    merged: list[list[int]] = []
    for s in sorted(spans):
        if s[0] > s[1]:
            continue
        if merged and s[0] <= merged[-1][1] + 1:
            merged[-1][1] = max(merged[-1][1], s[1])
        else:
            merged.append(list(s))
    return [np.arange(a, b + 1) for a, b in merged]


def _search_half_width(scene, tool_clearance: float) -> float:
    radii = [obstacle_circumradius(o.shape) for o in scene.obstacles.values()]
    return (max(radii) if radii else 0.0) + tool_clearance + 0.02


def nearest_free_point(p_W, scene, tool_clearance: float, method: str = "pso", budget: int = 2000,
                       seed=0, x0=None, pop_size: int | None = None):
    """Algorithm 2's inner loop: the nearest point to ``p_W`` that keeps ``tool_clearance`` from every obstacle.

    Args:
        p_W: ``(3,)`` input point [m].
        scene: the :class:`drake_mh.scene.Scene` (its current obstacle poses).
        tool_clearance: [m].
        method: any optimizer of :func:`drake_mh.optim.available_methods`.
        budget: function evaluations.
        seed: optimizer seed.
        x0: extra ``(K, 3)`` points for the initial population (``p_W`` is always included).
        pop_size: population size (``None``: the method's default).

    Returns:
        ``(x (3,), OptimizeResult)``.
    """
    from drake_mh.optim import minimize

    p = np.asarray(p_W, dtype=float).reshape(3)
    c = float(tool_clearance) + PENALTY_MARGIN
    obstacles = [(o.X_WO[:3, :3].copy(), o.X_WO[:3, 3].copy(), o.shape) for o in scene.obstacles.values()]

    def objective(X):  # (P, 3) -> (P,): distance to the input point + exact clearance penalty
        f = np.linalg.norm(X - p, axis=1)
        for R, centre, shape in obstacles:
            f += PENALTY_WEIGHT * np.maximum(c - shape.signed_distance((X - centre) @ R), 0.0)
        return f

    h = _search_half_width(scene, tool_clearance)
    start = p[None] if x0 is None else np.vstack([p[None], np.clip(np.asarray(x0, dtype=float).reshape(-1, 3),
                                                                     p - h, p + h)])
    res = minimize(objective, (p - h, p + h), method=method, budget=int(budget), seed=seed, pop_size=pop_size,
                   x0=start, target=0.0)
    return np.asarray(res.x, dtype=float), res


def replan_points(points_W, window, scene, config: ReplanConfig = ReplanConfig(), method: str = "pso",
                  seed=0, colliding=()) -> ReplanResult:
    """Algorithm 2 over one window: each point replaced by the nearest obstacle-free point.

    Args:
        points_W: ``(N, 3)`` the whole path [m] (not modified).
        window: increasing path indices to replace (:func:`replan_windows`).
        scene: the scene.
        config: :class:`ReplanConfig`.
        method: the optimizer (``config.optimizer(ik_method)``).
        seed: base seed; point ``i`` of the window uses ``SeedSequence([seed, index])``.
        colliding: the colliding indices (for the record).

    Returns:
        :class:`ReplanResult`.
    """
    start = time.perf_counter()
    P = np.asarray(points_W, dtype=float)
    window = np.asarray(window, dtype=int)
    new = P[window].copy()
    nfe = 0
    previous = None
    for i, k in enumerate(window):
        seed_k = int(np.random.SeedSequence([int(seed) & 0xFFFFFFFF, int(k)]).generate_state(1)[0])
        x, res = nearest_free_point(P[k], scene, config.tool_clearance, method=method, budget=config.budget,
                                    seed=seed_k, x0=previous, pop_size=config.pop_size)
        new[i] = x
        previous = x
        nfe += int(res.nfe)
    clearance = path_point_clearance(new, scene)
    colliding = np.intersect1d(np.asarray(colliding, dtype=int), window)
    return ReplanResult(window, colliding, P[window].copy(), new, clearance, nfe, time.perf_counter() - start)
