"""Cyclic path planning of planar hyper-redundant arms (the cyclic paper, Machmudah et al.).

The arm is split into 2-link components (periodic sixth-order polynomial stages, eqs. (16),
(25)) and 3-link components (closed-form IK about a moving base with a constant orientation
angle k, eqs. (7)-(12), (17), (19)-(20)); every moving base repeats with the end-effector
path's period, so the joint trajectories are periodic by construction. Each k is searched in
its feasible interval (local orientation-angle boundary shrunk by joint limits and circular
obstacles) by any optimizer of :mod:`drake_mh.optim`, minimizing the joint path length
(eq. (1)). See ``docs/cyclic.md``.

::

    import drake_mh
    from drake_mh.cyclic import maple_leaf_task, plan, verify

    robot = drake_mh.load_robot("planar12")
    task = maple_leaf_task(robot)                      # §V.B, lengths/limits read from Drake
    result = plan(task, method="woa", budget=2000, seed=0)
    result.ks, [c.fitness for c in result.components]  # k and eq. (1) per component
    verify(result, robot).success                      # end effector on the path (Drake), limits, obstacles
    t, Q = result.trajectory(cycles=3)                 # export (e.g. drake_mh.viz.show(robot, (t, Q)))
"""

from drake_mh.cyclic.cases import (
    LEAF_OBSTACLES,
    TABLE_I,
    TABLE_I_DRAKE_MH,
    TABLE_II,
    TABLE_III_SEARCH,
    TABLE_IV,
    circle_task,
    maple_leaf_task,
    moving_bases,
)
from drake_mh.cyclic.curves import Circle, FunctionCurve, Lissajous, MapleLeaf, PeriodicCurve, SampledCurve, as_curve
from drake_mh.cyclic.fitness import converged_path_length, matlab_path_length
from drake_mh.cyclic.obstacles import CircleObstacle, segment_clearance
from drake_mh.cyclic.pinv import PinvResult, pinv_tracking
from drake_mh.cyclic.planner import CyclicPlan, ComponentResult, component_problem, compose, plan, plan_with_k
from drake_mh.cyclic.problem import Boundary, Evaluation, InfeasibleComponent, ThreeLinkProblem
from drake_mh.cyclic.task import CyclicTask, ThreeLinkComponent, TwoLinkComponent, planar_chain
from drake_mh.cyclic.three_link import reachable_orientation, three_link_ik, three_link_points
from drake_mh.cyclic.two_link import StagedPolynomial, sixth_order_coefficients
from drake_mh.cyclic.verify import CycleReport, Verification, cycle_report, verify

__all__ = [
    "LEAF_OBSTACLES", "TABLE_I", "TABLE_I_DRAKE_MH", "TABLE_II", "TABLE_III_SEARCH", "TABLE_IV",
    "circle_task", "maple_leaf_task", "moving_bases",
    "Circle", "FunctionCurve", "Lissajous", "MapleLeaf", "PeriodicCurve", "SampledCurve", "as_curve",
    "converged_path_length", "matlab_path_length", "CircleObstacle", "segment_clearance",
    "PinvResult", "pinv_tracking", "CyclicPlan", "ComponentResult", "component_problem", "compose", "plan",
    "plan_with_k", "Boundary", "Evaluation", "InfeasibleComponent", "ThreeLinkProblem", "CyclicTask",
    "ThreeLinkComponent", "TwoLinkComponent", "planar_chain", "reachable_orientation", "three_link_ik",
    "three_link_points", "StagedPolynomial", "sixth_order_coefficients", "CycleReport", "Verification",
    "cycle_report", "verify",
]
