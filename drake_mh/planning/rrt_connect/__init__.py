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

* **one compiled call**: sampling, nearest neighbours (linear scan: trees stay small), motion
  checks, path extraction and shortcutting run without Python in the loop, in the compiled
  core's C++ planner where it is built (``drake_mh._native.MotionPlanner``, ``cpp/rrt_connect.hpp``:
  nothing compiled at call time; the same draws and checks as the numba kernel, so the same
  path for a seed), else in the numba kernel :func:`.search.plan_kernel` (also with
  ``DRAKE_MH_COMPILED_CORE=0``, and for ``certify="bisection"``); the deadline is read inside the kernel from the
  monotonic clock (:mod:`drake_mh.planning.motion.clock`), the budget counts tree nodes; randomness is splitmix64
  seeded from the caller's generator (same seed, same path). Python calls it through the
  compiled entry point of its one signature, the options in one vector and the scene's arrays
  bound once (:func:`.planner._binding`): a plan is often called after other work, with its
  code and data out of the CPU's caches, where every Python step costs microseconds;
* **batched motion checks with early exit** (the scene's
  :func:`drake_mh.scene.kernels.states.check_states`): the interpolated states of a motion go
  through the scene's sphere model in SIMD blocks, the first block spread over the whole
  motion ("rake" order), and a block stops at the first sphere found in collision;
* **every edge certified** (:func:`drake_mh.planning.motion.check.certified_motion`): each constraint row (a link against
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

  scene                   success  median ms wall (CPU)  p95 ms wall (CPU)   nodes   states
  ======================  =======  ====================  ==================  ======  =========
  table (75 % straight)   100 %    0.08 (0.08)           0.39 (0.39)         0       121
  shelf                   100 %    0.61 (0.57)           5.0 (1.9)           5       522
  slot (narrow passage)   100 %    1.16 (1.13)           8.4 (4.7)           8       1,618
  table, self-collision   100 %    1.54 (1.30)           7.6 (6.5)           0       121
  ======================  =======  ====================  ==================  ======  =========

* the MotionBenchMaker-like sets of :mod:`drake_mh.planning.problems` (table pick, table under
  pick, bookshelf small / tall / thin, box, cage; 15 problems each, 2 seeds): 100 % verified,
  median 0.98 ms CPU (1.08 wall), p95 3.5 ms CPU, without self-collision (load 2.6-4);
  re-measured with the scene's public state check
  (:func:`drake_mh.scene.kernels.states.check_states`) and with the kernel before it, run after
  run on the same 105 problems x 2 seeds (identical paths): at load 2.0, median 0.43-0.45 ms
  CPU (before: 0.44-0.46), p95 3.0-3.1 ms (before: 3.4); at load 1.5 both 0.50-0.52 ms. With self-collision (load 2.6-4): 1.25 ms with the link pairs of MoveIt's Panda
  SRDF ignored; 4.9 ms with every pair Drake's filter keeps (there link1-link3 and link5-link7
  are 1-3 mm apart in every configuration under the sphere model, so every motion needs the
  bisection). Median path 5.9 rad (7.1 unshortcut).
* where the time goes (profiled, MotionBenchMaker-like, mean): batched checks 76 %,
  certification of motions within their margins 13 %, shortcutting 11 % (its checks
  included in those), nearest neighbours 1.4 %, sampling 0.4 %; 90 % of the motions checked
  are rejected (a collision), at about 700 ns per state checked including the per-motion
  costs. The target of the issue (median 0.5 ms) is met at load 2 (0.43-0.45 ms), at the edge
  at load 1.5 (0.50-0.52 ms, machine state varies) and missed under heavier load: the batched check costs 300-400 ns per Panda state against these 7-12
  obstacles (VAMP: 60-130 ns).
* the original MotionBenchMaker problems with the Panda's meshed hand (778 spheres, 66 problems,
  ``drake-mh study motion_benchmark``, docs/planning.md): 66/66 verified, median 0.52 ms CPU, of
  which the shortcut step 0.08 ms (``info["t_found"]``: 0.43 ms to the first certified path).
* cold compilation (empty numba cache, no compiled core): :func:`prepare` takes about 1 minute
  of CPU time (``plan_kernel`` and its callees; ``check_states`` alone 5 s); with the compiled
  core nothing compiles.
* the independent verification (:func:`drake_mh.planning.verify_motion` without retiming)
  takes 3-17 ms per path, 6.7 ms median, of which 0.24 ms is the certificate and the rest the
  1 mm refinement of the reported clearance.
:func:`prepare` binds the scene and, without the compiled core, loads the kernel once per
process (from numba's on-disk cache; after a change of the kernels the first call compiles them,
a minute or two); :func:`certify_motions` exposes the
motion check. Options and the figures that chose their defaults: :class:`RRTConnectConfig` and
docs/planning.md; measured results: docs/benchmarks.md.
"""

from __future__ import annotations

from drake_mh.planning.rrt_connect.planner import (DEFAULT_MAX_NODES, RRTConnectConfig, certify_motions, plan,
                                                   plan_smooth, prepare)

__all__ = ["RRTConnectConfig", "plan", "plan_smooth", "prepare", "certify_motions", "DEFAULT_MAX_NODES"]

plan.prepare = prepare  # for a runner that loads methods before starting its clock
plan_smooth.prepare = prepare
