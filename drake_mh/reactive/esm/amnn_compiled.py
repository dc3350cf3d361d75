"""Compiled AMNN step: all L layers of one control step in one numba call.

AMNN (ESM paper, Xie et al., eqs. (12)-(21)) is ARO (Wang et al., "Artificial rabbits
optimization", Eng. Appl. Artif. Intell. 114:105082, 2022) arranged as L layers of P agent
neurons. The Python path (:class:`drake_mh.reactive.esm.amnn.AMNN` with ``compiled=False``)
runs it through the ask/tell loop of :func:`drake_mh.optim.base.run`, which pays per layer
~20-25 us of Python (ask/tell bookkeeping, argument checks, one call per kernel), more than
the layer's compiled work at P = 32 (~13-15 us; ``studies/amnn_speed.py``). Here one
compiled function runs layer 0 and, for ``l = 1 .. L``:

* the agent update of eqs. (12)-(18) and the box projection of eq. (19):
  :func:`drake_mh.optim.aro.rabbit_moves` (the same kernel ``ARO(variant="amnn")`` calls), with the
  uniforms drawn inside the kernel from the optimizer's ``numpy.random.Generator``
  (``gen.random((P, 8 + D))`` per layer: the same stream, in the same order, as
  ``ARO._ask`` draws);
* the obstacle rows of eq. (9): ``"reject"``: a candidate violating ``A θ <= c`` (within
  ``feasibility_tol``) or the box gets ``F = +inf``
  (:func:`~drake_mh.reactive.esm.kernels.feasible_columns`, the verdicts of ``feasible``);
  ``"repair"``: it is evaluated at its projection
  (:func:`~drake_mh.reactive.esm.kernels.repair`), the agent keeps the unrepaired point, and
  an unrepairable candidate gets ``+inf``;
* the objective of eq. (10) of the other candidates: :func:`drake_mh.kinematics.kernels.fk_jacobian`
  on the transposed layer (the layout ``BatchKinematics`` uses), then
  :func:`drake_mh.reactive.esm.kernels.esm_values`. A rejected candidate skips the
  kinematics (11-22 % of them in the study's scenarios, 30-44 % while an obstacle row is
  active) but still counts as an evaluation: a step reports ``(L + 1) P``, as the Python path;
* the greedy selection of eq. (20) (strict improvement, as ``ARO._tell``: a rejected
  candidate never replaces ``θ_i(l)``) and the best-so-far point of the ask/tell protocol
  (first minimum of each layer, strict improvement).

Layer 0 (the warm-start population) and the optimizer's seed come from the same
``ARO`` object the Python path builds, so both paths draw identical random numbers and, the
objective being the same kernels on the same arrays, return bit-identical steps
(``tests/reactive/esm/test_amnn_compiled.py``).

Numba's on-disk cache keys a function by its own file only: a cached kernel that calls
kernels of other files would silently keep their old code after they change. The step
kernel is therefore built by :func:`_build` as a closure over a fingerprint of the source
files it calls into; numba hashes closure variables into the cache key, so an edit of any of
those files compiles it again.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numba
import numpy as np

from drake_mh.kinematics import kernels as _kernels
from drake_mh.errors import InvalidArgument
from drake_mh.kinematics.kernels import fk_jacobian as _fk_jacobian
from drake_mh.optim import aro
from drake_mh.optim.aro import rabbit_moves
from drake_mh.reactive.esm import kernels as esm_kernels
from drake_mh.reactive.esm.kernels import esm_values as _esm_values
from drake_mh.reactive.esm.kernels import feasible_columns as _feasible_columns
from drake_mh.reactive.esm.kernels import repair as _repair

_DEPENDENCIES = (_kernels, esm_kernels, aro)   # the files of the kernels above


def _fingerprint() -> int:
    """A non-negative int64 hash of the source files whose kernels the step kernel calls."""
    h = hashlib.sha256()
    for module in _DEPENDENCIES:
        h.update(Path(module.__file__).read_bytes())
    return int.from_bytes(h.digest()[:8], "little") >> 1


def _build(fingerprint: int):
    """The step kernel, cached on disk under ``fingerprint`` (module docstring).

    The kernels it calls are module globals, not closure variables: numba pickles closure
    variables into the cache key, and a dispatcher pickles differently in every process.
    """

    @numba.njit(cache=True)
    def amnn_layers(X, gen, T, lower, upper, A, c, tol, sweeps, kin, anchor, ER, Ep, on_path, r_d, h1, h2):
        """Runs layer 0 and layers ``1 .. T`` of one step (see the module docstring).

        Args:
            X: ``(P, D)`` layer 0 (inside the box); overwritten by the last layer.
            gen: the optimizer's ``numpy.random.Generator`` (advanced in place).
            T: number of layers after layer 0 (L, the horizon of eqs. (12), (14)).
            lower, upper: the box of eq. (11).
            A, c, tol: the obstacle rows ``A θ <= c + tol`` of eq. (9).
            sweeps: ``< 0``: reject infeasible candidates; ``>= 0``: repair with that many
                sweeps of cyclic projection.
            kin: the chain arrays ``(parent, KR, Kp, perm, kind, qidx)`` of
                ``BatchKinematics``; anchor, ER, Ep, on_path: the end-effector frame.
            r_d, h1, h2: target and weights of eq. (10).

        Returns:
            ``(F, best_x, best_f)``: the last layer's values ``(P,)``, the best candidate
            evaluated (``NaN`` row and ``inf`` when none was feasible) and its value.
        """
        _ = fingerprint  # part of the cache key
        parent, KR, Kp, perm, kind, qidx = kin
        P, D = X.shape
        QT = np.empty((D, P))
        F = np.empty(P)
        Fn = np.empty(P)
        Fv = np.empty(P)
        e = np.empty(P)
        mu = np.empty(P)
        ok = np.empty(P, dtype=np.bool_)
        idx = np.empty(P, dtype=np.int64)
        Xr = np.empty((P, D))
        no_normals = np.empty((2, 0))
        best_x = np.full(D, np.nan)
        best_f = np.inf
        for t in range(T + 1):
            Xn = X if t == 0 else rabbit_moves(X, gen.random((P, 8 + D)), no_normals, t, T, True, lower, upper)
            Xe = Xn
            if sweeps >= 0:
                Xr[:] = Xn
                _repair(Xr, A, c, lower, upper, sweeps, tol, ok)
                Xe = Xr
            for i in range(P):
                for d in range(D):
                    QT[d, i] = Xe[i, d]
            if sweeps < 0:
                _feasible_columns(QT, A, c, lower, upper, tol, ok)
            n = 0                                         # kinematics of the feasible candidates only
            for i in range(P):
                if ok[i]:
                    idx[n] = i
                    n += 1
            QTf = np.empty((D, n))
            for d in range(D):
                for m in range(n):
                    QTf[d, m] = QT[d, idx[m]]
            Tp = np.empty((n, 4, 4))
            J = np.empty((n, 6, D))
            _fk_jacobian(QTf, parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path, True, Tp, J)
            _esm_values(Tp, J, r_d, h1, h2, Fv, e, mu)
            Fn[:] = np.inf                                # eq. (19): rejected candidates
            for m in range(n):
                if Fv[m] == Fv[m]:                        # NaN counts as worst
                    Fn[idx[m]] = Fv[m]
            k = 0
            for i in range(1, P):
                if Fn[i] < Fn[k]:
                    k = i
            if Fn[k] < best_f:                            # best so far, as Optimizer.tell
                best_f = Fn[k]
                best_x[:] = Xn[k]
            if t == 0:
                F[:] = Fn
            else:
                for i in range(P):                        # eq. (20), greedy per agent
                    if Fn[i] < F[i]:
                        X[i] = Xn[i]
                        F[i] = Fn[i]
        return F, best_x, best_f

    return amnn_layers


_amnn_layers = _build(_fingerprint())


def run_layers(robot, step, opt, handling: str):
    """Runs one AMNN step on the ``ARO(variant="amnn")`` optimizer ``opt`` in compiled code.

    Equivalent to ``drake_mh.optim.base.run(opt, ESMObjective(robot, step, handling))``
    (same random numbers, same evaluations; no callback, no target), without the Python
    ask/tell loop.

    Args:
        robot: the robot (its end-effector frame is the tracked point).
        step: the :class:`drake_mh.reactive.esm.problem.ESMStep`.
        opt: a fresh ``ARO(step.bounds, budget=(L + 1) P, pop_size=P, variant="amnn", ...)``.
        handling: ``"reject"`` or ``"repair"``.

    Returns:
        ``(best_x, best_f, X, F)``: the best candidate (unrepaired), its value, and the last
        layer ``(P, D)`` with its values ``(P,)``.

    Raises:
        InvalidArgument: ``opt`` is not a fresh ARO of variant ``"amnn"``, or an unknown
            ``handling``.
    """
    if not (isinstance(opt, aro.ARO) and opt.amnn and opt.nfe == 0):
        raise InvalidArgument("run_layers needs a fresh drake_mh.optim.ARO(..., variant='amnn') (no ask/tell yet)")
    if handling not in ("reject", "repair"):
        raise InvalidArgument(f"the compiled AMNN step supports handling 'reject' or 'repair'; got {handling!r}")
    cfg = step.config
    batch = robot.batch
    anchor, ER, Ep, on_path = batch.frame_arrays(None)      # the kernel arguments of BatchKinematics._run
    X = np.ascontiguousarray(opt.initial_population())
    sweeps = int(cfg.repair_sweeps) if handling == "repair" else -1
    F, best_x, best_f = _amnn_layers(X, opt.rng, int(opt.T), opt.lower, opt.upper, np.ascontiguousarray(step.A),
                                     np.ascontiguousarray(step.c), float(cfg.feasibility_tol), sweeps,
                                     tuple(batch.chain_arrays), anchor, ER, Ep, on_path,
                                     np.ascontiguousarray(step.r_d, dtype=float), float(cfg.h1), float(cfg.h2))
    return best_x, float(best_f), X, F
