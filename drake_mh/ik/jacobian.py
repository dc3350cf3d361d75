"""Jacobian baselines: pseudo-inverse and damped least squares with restarts.

The classic single-chain iterations, as in KDL's Newton–Raphson solver that TRAC-IK compares
against and robotics-toolbox-python's ``ik_NR``/``ik_GN``: from a start configuration, repeat
``q ← q + Δq`` with

* ``pinv``: ``Δq = J⁺ e`` (Whitney 1969), the minimum-norm Gauss–Newton step, computed as
  ``Jᵀ (J Jᵀ + ε I)⁻¹ e`` with ``ε = 1e-12`` (numerically the pseudo-inverse of a full-rank J);
* ``dls``: ``Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e`` with a fixed damping ``λ = 0.03`` (Wampler 1986;
  Nakamura & Hanafusa 1986), robust near singularities at the price of slower convergence;

every step taken (no line search). Iterates may leave the joint limits (as in
robotics-toolbox's solvers); a converged point is brought within them by whole turns of its
revolute joints, or else rejected (a new start). Measured on 300 TRAC-IK targets against
clamping every iterate onto the limits (KDL's ``ChainIkSolverPos_NR_JL``): seed000_6dof
``pinv`` 100 % / 57 configurations per target instead of 93 % / 881, ``dls`` 100 % / 51
instead of 98.7 % / 255; Panda ``pinv`` 97 instead of 125, ``dls`` 136 instead of 112 (both
99.7-100 %). A search box narrower than the limits (``paths.continuity.LocalIKProblem``)
clamps instead (``LMSettings.project_limits``). The first start is the
mid-range configuration (or ``q_ref`` when the problem has one), later starts are uniform
within the limits (random restarts, drawn by :func:`drake_mh._support.random.uniform_at` from the
seed) until the budget or the timeout is spent. Both run in the compiled restart loop of
:mod:`drake_mh.ik.lm` (:func:`~drake_mh.ik.lm.lm_run`, one candidate): Python is entered once
per converged point (for the obstacle check and Drake's verification) or per ~0.15 ms.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from drake_mh.ik.lm import STALLED, BatchLM, LMSettings
from drake_mh.ik.problem import IKProblem
from drake_mh.ik.result import IKResult, verify

__all__ = ["JacobianConfig", "solve_jacobian", "PINV", "DLS"]


@dataclass(frozen=True)
class JacobianConfig:
    """Settings of :func:`solve_jacobian`.

    Attributes:
        lm: the iteration (plain mode: every step taken, fixed damping ``lam0``; free
            iterates, see the module docstring).
        first_start: ``"mid"`` (mid-range, or ``q_ref`` when given) or ``"random"``.
    """

    lm: LMSettings = field(default_factory=lambda: LMSettings(adaptive=False, lam0=1e-12, max_iter=100, stall_iters=20,
                                                              project_limits=False))
    first_start: str = "mid"


#: most configurations evaluated per compiled call (~0.15 ms); the timeout is checked between calls
CHUNK = 256

#: the pseudo-inverse baseline
PINV = JacobianConfig()
#: the damped-least-squares baseline (λ = 0.03, λ² = 9e-4)
DLS = JacobianConfig(lm=LMSettings(adaptive=False, lam0=9e-4, max_iter=100, stall_iters=20, project_limits=False))


def solve_jacobian(problem: IKProblem, method: str, seed=0, budget: int | None = None,
                   timeout: float | None = None, config: JacobianConfig | None = None,
                   start: float | None = None) -> IKResult:
    """Solves ``problem`` with restarted pseudo-inverse / DLS iterations (module docstring).

    Args:
        problem: the IK problem.
        method: name recorded in the result (``"pinv"`` or ``"dls"``).
        seed: seed of the random restarts.
        budget: FK + Jacobian evaluations; ``None``: unlimited (then a timeout is needed).
        timeout: [s] wall-clock limit; ``None``: none.
        config: :class:`JacobianConfig` (default: :data:`PINV` or :data:`DLS` by ``method``).
        start: ``time.perf_counter()`` of the caller's start.
    """
    start = time.perf_counter() if start is None else start
    config = config or (DLS if method == "dls" else PINV)
    deadline = np.inf if timeout is None else start + timeout
    budget = np.inf if budget is None else budget
    lower, upper, nq = problem.lower, problem.upper, problem.nq
    if type(seed) is int and seed >= 0:
        gen_seed = seed
    else:  # None, a Generator, a SeedSequence...: one draw seeds the restarts
        gen_seed = int(np.random.default_rng(seed).integers(0, 2**63))
    if config.first_start == "mid":
        q0 = problem.q_ref if problem.q_ref is not None else 0.5 * (lower + upper)
        starts = np.array(q0, dtype=float).reshape(1, nq)
    else:
        starts = np.empty((0, nq))
    settings = config.lm
    if not settings.project_limits and (lower is not problem.robot.lower or upper is not problem.robot.upper):
        settings = dataclasses.replace(settings, project_limits=True)  # a narrowed search box: stay inside
    lm = BatchLM(problem, 1, settings)
    lm.status[:] = STALLED
    nfe, cursor = 0, 0
    sphere_check = problem.scene is not None and bool(problem.scene.obstacles)
    while nfe < budget and time.perf_counter() <= deadline:
        # restarts without end (the cursor runs on); one compiled call per converged point or chunk
        row, evals, cursor = lm.run(starts, cursor, min(CHUNK, budget - nfe), n_starts=2**62, gen_seed=gen_seed)
        nfe += evals
        if row < 0:
            if evals == 0:
                break  # not enough budget left for one more iteration
            continue
        q = lm.Qa[0].copy()
        # the sphere model first (microseconds, never more clearance than Drake), as hybrid does
        if not sphere_check or problem.scene.batch_min_distance(q[None])[0] >= problem.clearance:
            result = verify(problem, q, method=method, start=start, nfe=nfe, attempts=cursor,
                            message=f"converged after {cursor} starts")
            if result.success:
                return result
        lm.status[0] = STALLED  # e.g. in collision: try another start
    # the best point within the limits: of the abandoned starts, or the live one (free iterates may leave them)
    live = lm.Qa[0]
    inside = bool(((live >= lower) & (live <= upper)).all())
    if inside and lm.fa[0] < lm.best_f[0]:
        best_q = live
    elif np.isfinite(lm.best_f[0]):
        best_q = lm.best_q
    else:
        best_q = starts[0] if len(starts) else 0.5 * (lower + upper)
    why = "timeout" if time.perf_counter() > deadline else "budget exhausted"
    return verify(problem, best_q.copy(), method=method, start=start, nfe=nfe, attempts=cursor,
                  message=f"{why} after {cursor} starts")
