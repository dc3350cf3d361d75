"""Metaheuristic via-point trajectory optimization as motion planners: ``mh_<optimizer>``.

The ABC paper's via-point formulation (Savsani & Jhala: via joint angles, 4th/5th-order
polynomials, fitness ``f_f / f_ob`` of torque excess, joint travel, Cartesian length and time)
and the framework paper's approach (any metaheuristic of the library, forward kinematics in
the fitness, obstacles as constraints, Algorithm 2's "replace the colliding stretch by newly
optimized points" as the repair step) generalized to n joints in 3-D:

* decision variables: ``K`` via configurations between ``q_start`` and a goal configuration
  (and, with several goal configurations, which one); with ``trajectory="polynomial"`` also the
  paper's via velocities and segment times;
* fitness: :mod:`.objective` (batched over the population: one sphere-model clearance call,
  one FK call per generation);
* the answer: certified at the end (:mod:`.planner`), repaired if needed, and verified by
  :func:`drake_mh.planning.verify_motion` like every other method.

One method per optimizer of :func:`drake_mh.optim.available_methods`, registered as
``mh_<optimizer>`` (``mh_pso``, ``mh_de``, ``mh_abc``, ...), as :func:`drake_mh.solve_ik` names
each optimizer a method: a study's grid over methods then compares the optimizers with no
extra dimension, and a record's ``method`` says which optimizer ran. Options (``solve_motion``
keywords): the fields of :class:`ViaPointMotionConfig` and the optimizer's hyper-parameters.
"""

from __future__ import annotations

import functools

from drake_mh.planning.viapoint_mh.objective import ViaPointMotion, ViaPointMotionConfig, rest_to_rest_time
from drake_mh.planning.viapoint_mh.planner import DEFAULT_BUDGET, plan, prepare, resample_via

__all__ = ["ViaPointMotion", "ViaPointMotionConfig", "plan", "prepare", "method", "resample_via", "rest_to_rest_time",
           "DEFAULT_BUDGET"]


def method(optimizer: str):
    """The planner ``mh_<optimizer>`` (:data:`drake_mh.planning.methods.METHODS`): :func:`plan` with
    that optimizer, and its ``prepare`` (``solve_motion`` compiles the kernels and starts the
    optimizer before its clock starts)."""
    function = functools.partial(plan, optimizer=optimizer)
    functools.update_wrapper(function, plan)
    function.prepare = functools.partial(prepare, optimizer=optimizer)
    return function
