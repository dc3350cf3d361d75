"""ESM: reactive joint-angle control with manipulability among moving obstacles.

The ESM paper (Xie et al., "Enhancing Safety and Manipulability of Redundant Manipulators:
Accelerated Motion Generation in Dynamic Environments"): every Δt one control step tracks a
target, maximizes the manipulability and keeps the links away from moving obstacles (eqs.
(6)-(11)). The step is solved by AMNN (ARO arranged as L layers of P agents, eqs. (12)-(21)),
any ``drake_mh.optim`` method, or a velocity-level QP baseline (OSQP). See ``docs/esm.md``.

Files:

* :mod:`.config` — :class:`ESMConfig` (weights, threshold, Δt, safeguards, tolerances);
* :mod:`.problem` — :func:`build_step` → :class:`ESMStep` (box of eq. 11, rows of eq. 9 from
  Drake's closest points, eq. 8 Jacobians) and :class:`ESMObjective`;
* :mod:`.kernels` — numba kernels: objective, feasibility test, repair by cyclic projection;
* :mod:`.solvers` — :class:`StepSolver`, :class:`MetaheuristicSolver`, warm start;
* :mod:`.amnn`, :mod:`.amnn_compiled` — :class:`AMNN`, its layers in one compiled call;
* :mod:`.qp_baseline` — :class:`QPBaseline`;
* :mod:`.verify` — :func:`check_step`: every step re-checked with Drake;
* :mod:`.controller` — :func:`run_esm` → :class:`ESMRun` (the closed loop);
* :mod:`.scenarios` — the paper's two scenarios;
* :mod:`.optimum` — the approximate optimum manipulability μ*;
* :mod:`.plots` — Fig. 4 layout (matplotlib, imported lazily).
"""

from drake_mh.reactive.esm.amnn import PAPER_AGENTS, PAPER_LAYERS, AMNN
from drake_mh.reactive.esm.config import CONSTRAINT_HANDLINGS, ESMConfig
from drake_mh.reactive.esm.controller import ESMRun, run_esm
from drake_mh.reactive.esm.optimum import optimal_manipulability, optimal_manipulability_along
from drake_mh.reactive.esm.plots import figure_png, plot_runs
from drake_mh.reactive.esm.problem import ESMObjective, ESMStep, ObstacleRow, build_step, point_jacobian
from drake_mh.reactive.esm.qp_baseline import QPBaseline, inverse_manipulability_gradient
from drake_mh.reactive.esm.scenarios import (
    SCENARIOS,
    TARGET,
    THETA0,
    ESMScenario,
    MovingObstacle,
    get_scenario,
    self_motion,
    tracking,
)
from drake_mh.reactive.esm.solvers import MetaheuristicSolver, StepSolution, StepSolver, warm_start_rows
from drake_mh.reactive.esm.verify import TOLERANCES, StepCheck, check_step, drake_point_jacobian

__all__ = [
    "AMNN", "PAPER_AGENTS", "PAPER_LAYERS", "CONSTRAINT_HANDLINGS", "ESMConfig", "ESMRun", "run_esm",
    "optimal_manipulability", "optimal_manipulability_along", "figure_png", "plot_runs",
    "ESMObjective", "ESMStep", "ObstacleRow", "build_step", "point_jacobian",
    "QPBaseline", "inverse_manipulability_gradient",
    "SCENARIOS", "TARGET", "THETA0", "ESMScenario", "MovingObstacle", "get_scenario", "self_motion", "tracking",
    "MetaheuristicSolver", "StepSolution", "StepSolver", "warm_start_rows",
    "TOLERANCES", "StepCheck", "check_step", "drake_point_jacobian",
]
