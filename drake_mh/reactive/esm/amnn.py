"""AMNN: the ESM paper's accelerated multi-agent recurrent neural network (eqs. (12)-(21)).

AMNN is ARO (Wang et al. 2022) arranged as a network: each agent neuron is a rabbit, each
layer a generation. drake_mh builds it on ``drake_mh.optim.ARO(variant="amnn")`` (the
agent update of eqs. (12)-(18) and the projection onto the box of eq. (19), vectorized over
the P agents) and adds the ESM specifics here:

* **Layers.** ``L + 1`` layers of ``P`` agents per control step (the paper: "L + 1 layers,
  each except the last containing P agent neurons; the first performs initialization"):
  layer 0 is the initial layer (the warm-start population evaluated under this step's
  objective), layers ``l = 1 .. L`` are ARO generations ``t = l`` with ``T = L`` in eqs.
  (12) and (14). The evaluation budget of a step is therefore ``(L + 1) P``.
* **Eq. (19), obstacle inequality.** With ``handling="reject"`` (default) a candidate that
  violates eq. (9) gets ``F = +inf``; ARO's greedy selection (eq. (20)) then keeps
  ``θ_i(l)``: exactly the paper's "``p_Ωi(l+1) = θ_i(l)`` if not (9)", without re-evaluating
  ``θ_i(l)``. The box part of eq. (19) is ARO-amnn's clip; the box itself is eq. (11).
* **Eq. (21).** The output is the best agent of the last layer (the paper writes arg max of
  F; the minimum is meant, F being minimized).
* **Recurrence.** The last layer of step k is the first layer of step k + 1 (warm start,
  :func:`drake_mh.reactive.esm.solvers.warm_start_rows`).

Two implementations of the same step: ``compiled=True`` runs all layers in one numba call
(:mod:`drake_mh.reactive.esm.amnn_compiled`); ``compiled=False`` runs ARO-amnn through the Python
ask/tell loop. Both draw the same random numbers and return bit-identical steps.

The paper runs L = 1000, P = 128 on a GPU at 30 Hz; the rates on one CPU core
(``studies/amnn_speed.py``) are in docs/benchmarks.md.
"""

from __future__ import annotations

import time

from drake_mh.errors import InvalidArgument
from drake_mh.reactive.esm import amnn_compiled
from drake_mh.reactive.esm.problem import ESMObjective, ESMStep
from drake_mh.reactive.esm.solvers import MetaheuristicSolver, StepSolution, _answer

PAPER_LAYERS = 1000
PAPER_AGENTS = 128


class AMNN(MetaheuristicSolver):
    """AMNN step solver: ``L`` layers x ``P`` agents of ARO-amnn per control step.

    Args:
        layers: L, the number of layers after the initial one (paper: 1000).
        agents: P, agent neurons per layer (paper: 128).
        handling: ``"reject"`` (eq. (19), default) or ``"repair"``.
        warm_start: the previous step's last layer seeds this step's first layer.
        immigrants: fraction of that layer re-drawn uniformly in the box (0: the paper's
            recurrence, the last layer passed on unchanged).
        compiled: run the layers in one compiled call (:mod:`drake_mh.reactive.esm.amnn_compiled`)
            instead of the Python ask/tell loop; same result.

    Raises:
        InvalidArgument: ``layers < 1``, ``agents < 2`` or ``compiled`` not a bool.
    """

    def __init__(self, layers: int = 200, agents: int = 32, handling: str = "reject", warm_start: bool = True,
                 immigrants: float = 0.0, compiled: bool = True):
        if not (isinstance(layers, int) and layers >= 1):
            raise InvalidArgument(f"AMNN layers L must be an integer >= 1; got {layers!r}")
        if not (isinstance(agents, int) and agents >= 2):
            raise InvalidArgument(f"AMNN agents P must be an integer >= 2 (eq. (15) needs j != i); got {agents!r}")
        if not isinstance(compiled, bool):
            raise InvalidArgument(f"AMNN compiled must be True or False; got {compiled!r}")
        super().__init__("aro", budget=(layers + 1) * agents, pop_size=agents, handling=handling,
                         warm_start=warm_start, immigrants=immigrants, variant="amnn")
        self.layers = layers
        self.agents = agents
        self.compiled = compiled
        self.name = "amnn"

    def solve(self, robot, step: ESMStep) -> StepSolution:
        if not self.compiled:
            return super().solve(robot, step)
        t0 = time.perf_counter()
        x0 = self._first_layer(step)
        opt = self._optimizer(step, x0[: self.agents])
        best_x, best_f, self.population, self.population_f = amnn_compiled.run_layers(robot, step, opt, self.handling)
        objective = ESMObjective(robot, step, self.handling)
        theta, F, feasible = _answer(robot, step, objective, best_x, best_f, x0[0])
        return StepSolution(theta, F, feasible, self.budget, time.perf_counter() - t0, "budget exhausted")

    @property
    def budget_label(self) -> str:
        return f"L={self.layers} x P={self.agents}"
