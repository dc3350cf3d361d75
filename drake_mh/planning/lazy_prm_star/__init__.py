"""``lazy_prm_star``: an asymptotically optimal planner, compiled, every edge certified.

Method of :func:`drake_mh.planning.solve_motion`:

* ``lazy_prm_star`` — informed lazy PRM*: ``rrt_connect``'s certified path first (its time
  counts; at most ``budget`` tree nodes), then batches of ``batch`` samples drawn in the informed set of the best path
  (Gammell, Barfoot, Srinivasa, "Informed sampling for asymptotically optimal path planning",
  T-RO 2018), each node joined to its ``e (1 + 1/d) log n`` nearest (PRM*: Karaman & Frazzoli,
  "Sampling-based algorithms for optimal motion planning", IJRR 2011), the shortest path of the
  graph found by A* and only its edges certified (lazy PRM: Bohlin & Kavraki, "Path planning
  using lazy PRM", ICRA 2000), until the sample budget (``budget``, default 1,000) or the
  deadline. Each new shortest path of the graph is shortcut (64 draws at a gain of 0.5 %, as
  ``rrt_connect``'s shortcut) and replaces the best path when shorter.

Design: the search (:func:`.search.prm_kernel`) is one numba call, like ``rrt_connect``'s
plan, with the same motion check (:func:`drake_mh.planning.motion.check.certified_motion`);
samples are checked free by the scene's batched state check. Nodes that cannot lie on a
shorter path than the best are dropped at each batch (their straight-line distance through them
already exceeds it).

What "optimal" means here: the shortest path, in joint-space length, among those whose
straight edges the motion check certifies (a conservative check: an edge that it cannot
certify within ``max_certify_evaluations`` counts as blocked). With more samples the best
path's length converges to that optimum (PRM*'s property, kept by informed sampling and by
dropping nodes that cannot improve); any finite run is an approximation.
"""

from __future__ import annotations

from drake_mh.planning.lazy_prm_star.planner import DEFAULT_SAMPLES, LazyPRMStarConfig, plan, prepare

__all__ = ["LazyPRMStarConfig", "plan", "prepare", "DEFAULT_SAMPLES"]

plan.prepare = prepare  # solve_motion loads the kernels before its clock starts
