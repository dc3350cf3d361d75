"""The motion planners of :func:`~drake_mh.planning.solve_motion`: one explicit table, each planner
imported on first use (:class:`~drake_mh._support.registry.Registry`).

A planner is a function ``plan(problem, goals (G, nq), rng, deadline, budget, **options) ->
(path (M, nq) | None, info)`` (:mod:`drake_mh.planning.solve`), with an optional
``plan.prepare(problem, **options)`` that loads what it needs before the clock starts. OMPL's
planners are an optional peer: where ``ompl`` cannot be imported they are absent (a study then
reports them as unavailable). One ``mh_<optimizer>`` method per optimizer of
:func:`drake_mh.optim.available_methods` (added when the table is first read: it imports the
optimizers).
"""

from __future__ import annotations

from drake_mh._support.registry import Registry

__all__ = ["METHODS", "VIAPOINT_PREFIX"]

_OMPL = ("ompl.base", "ompl.geometric", "ompl.util")
VIAPOINT_PREFIX = "mh_"
"""``mh_<optimizer>``: via-point trajectory optimization with that optimizer."""


def _add_viapoint_methods(registry: Registry) -> None:
    from drake_mh.optim import available_methods

    for name in available_methods():
        registry.add(f"{VIAPOINT_PREFIX}{name}", load="drake_mh.planning.viapoint_mh:method", args=(name,),
                     description=f"via-point trajectory optimization (ABC paper's fitness, K via configurations) "
                                 f"with {name}")


METHODS = Registry("motion planning method", extend=_add_viapoint_methods)
"""name -> planner function, in the order of :func:`~drake_mh.planning.available_motion_methods`."""
METHODS.add("straight", load="drake_mh.planning.straight:plan",
            description="the straight joint-space line to the nearest goal configuration (baseline)")
METHODS.add("rrt_connect", load="drake_mh.planning.rrt_connect:plan",
            description="RRT-Connect (Kuffner & LaValle 2000) with a dynamic domain, compiled, batched state checks "
                        "with early exit, every edge certified, 32 random shortcut draws")
METHODS.add("rrt_connect_smooth", load="drake_mh.planning.rrt_connect:plan_smooth",
            description="rrt_connect with 192 random shortcut draws (shorter paths)")
METHODS.add("lazy_prm_star", load="drake_mh.planning.lazy_prm_star:plan",
            description="informed lazy PRM* (asymptotically optimal), warm-started by rrt_connect, every edge "
                        "certified; 1,000 samples or the deadline")
METHODS.add("drake_kto", load="drake_mh.planning.drake_kto:plan",
            description="Drake KinematicTrajectoryOptimization + SNOPT (B-spline, 10 control points, minimum "
                        "distance at 25 samples) from the straight line to the nearest goal")
METHODS.add("drake_kto_warm", load="drake_mh.planning.drake_kto:plan_warm",
            description="drake_kto warm-started from the rrt_connect path (its time included)")
METHODS.add("ompl_rrtconnect", load="drake_mh.planning.ompl_peer.planners:plan_rrtconnect", requires=_OMPL,
            description="OMPL 2.0.1 RRT-Connect with our checker (per-state Python callback, certified motion "
                        "validator), simplified (optional peer)")
METHODS.add("ompl_bitstar", load="drake_mh.planning.ompl_peer.planners:plan_bitstar", requires=_OMPL,
            description="OMPL 2.0.1 BIT* (anytime, path length; 1 s after its first solution) with our checker, "
                        "simplified (optional peer)")
