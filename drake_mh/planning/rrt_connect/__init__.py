"""``rrt_connect``: compiled RRT-Connect whose every edge is certified collision-free.

Methods of :func:`drake_mh.planning.solve_motion`:

* ``rrt_connect`` — RRT-Connect (Kuffner & LaValle, "RRT-Connect: An efficient approach to
  single-query path planning", ICRA 2000): one tree from the start, one from *every* goal
  configuration (all roots of the goal tree), EXTEND one tree a ``step`` (1.5 rad) toward a
  sample (uniform, or with probability ``goal_bias`` a root of the other tree), CONNECT the
  other tree to the new node, grow the smaller tree next (VAMP's balancing); a dynamic domain
  (Yershova et al., ICRA 2005, VAMP's radius of 4 rad: a sample beyond the radius of its
  nearest node whose extension failed is drawn again without a check); the direct motion to
  each goal is tried first; then random shortcutting (Geraerts & Overmars, "Creating
  high-quality paths for motion planning", IJRR 2007), 32 draws, each checked only if it would
  shorten the path by 5 % of its length (``shortcut_min_gain``);
* ``rrt_connect_smooth`` — the same with 192 draws at 0.5 % (shorter paths).

Design (the one that makes VAMP fast: Thomason, Kingston, Kavraki, "Motions in Microseconds
via Vectorized Sampling-Based Planning", ICRA 2024):

* **one compiled call** (:func:`._kernels.plan_kernel`): sampling, nearest neighbours
  (linear scan: trees stay small), motion checks, path extraction and shortcutting run in
  numba without Python in the loop; the deadline is read inside the kernel from the
  monotonic clock (:mod:`._clock`), the budget counts tree nodes; randomness is splitmix64
  seeded from the caller's generator (same seed, same path). Python calls it through the
  compiled entry point of its one signature, the options in one vector and the scene's arrays
  bound once (:func:`.planner._binding`): a plan is often called after other work, with its
  code and data out of the CPU's caches, where every Python step costs microseconds;
* **batched motion checks with early exit** (the scene's
  :func:`drake_mh.scene._state_kernels.check_states`): the interpolated states of a motion go
  through the scene's sphere model in SIMD blocks, the first block spread over the whole
  motion ("rake" order), and a block stops at the first sphere found in collision;
* **every edge certified** (:func:`._motion.certified_motion`): each constraint row (a link against
  the obstacles, a checked link pair) changes along a motion no faster than
  ``Λ_c = Σ_j reach[c, j] |Δq_j|`` (the Lipschitz bound of
  :mod:`drake_mh.scene.segments`), so the same batched check, asked for each row's clearance
  plus the margin ``Λ_c / 2n``, certifies the whole motion between its ``n + 1`` states. One
  pass tells three outcomes apart: a collision (rejected at once), every state clear of its
  margins (certified: most accepted motions end here), or free but within a margin
  somewhere — then the same bound decides on the rows that came near: conservative advancement
  from both ends of each uncertain piece on the clearance values that the check reports for
  those rows (default), or the scene's :func:`~drake_mh.scene.segments.certify_segments` with
  ``certify="bisection"``. The returned path therefore consists of certified segments, and
  :func:`drake_mh.planning.verify_motion` re-certifies it independently.

:func:`prepare` loads the kernel once per process (from numba's on-disk cache; after a change of
the kernels the first call compiles them, a minute or two); :func:`certify_motions` exposes the
motion check. Options and the figures that chose their defaults: :class:`RRTConnectConfig` and
docs/planning.md; measured results: docs/benchmarks.md.
"""

from __future__ import annotations

from drake_mh.planning.rrt_connect.planner import (DEFAULT_MAX_NODES, RRTConnectConfig, certify_motions, plan,
                                                   plan_smooth, prepare)
from drake_mh.planning.solve import register

__all__ = ["RRTConnectConfig", "plan", "plan_smooth", "prepare", "certify_motions", "DEFAULT_MAX_NODES"]

plan.prepare = prepare  # for a runner that loads methods before starting its clock
plan_smooth.prepare = prepare
register("rrt_connect", "RRT-Connect (Kuffner & LaValle 2000) with a dynamic domain, compiled, batched state "
                        "checks with early exit, every edge certified, 32 random shortcut draws")(plan)
register("rrt_connect_smooth", "rrt_connect with 192 random shortcut draws (shorter paths)")(plan_smooth)
