"""Approximate optimal manipulability at a target: the reference line of the ESM paper's Fig. 4(b).

``μ*(r_d) = max μ(θ)`` subject to ``r(θ) = r_d`` (the end effector pinned) and the joint
limits, by multi-start SLSQP (scipy) with the analytic position Jacobian of the batched
kernel and central-difference gradients of ``μ``. The paper computed its reference with
AMNN itself at L = 5e5, P = 1024 (eq. (25)); REFERENCES.md quotes ≈ 0.155 at
[0.6, 0.3, 0.5] m by multi-start SLSQP, drake_mh's Panda model gives 0.16090 (see
``docs/esm.md``).

Results are cached per process (``functools.lru_cache``), so a study computes each reference
once per worker.
"""

from __future__ import annotations

import functools

import numpy as np


def _slsqp(robot, target: np.ndarray, q0: np.ndarray):
    from scipy.optimize import minimize

    def neg_mu(q):
        return -robot.batch.manipulability(q[None])[0]

    def neg_mu_grad(q, h=1e-6):
        E = np.eye(robot.nq) * h
        m = robot.batch.manipulability(np.vstack([q + E, q - E]))
        return -(m[: robot.nq] - m[robot.nq:]) / (2 * h)

    def position_error(q):
        return robot.batch.positions(q[None])[0] - target

    def position_jacobian(q):
        return robot.batch.jacobian(q[None])[0][3:]

    res = minimize(neg_mu, q0, jac=neg_mu_grad, method="SLSQP", bounds=list(zip(robot.lower, robot.upper)),
                   constraints=[{"type": "eq", "fun": position_error, "jac": position_jacobian}],
                   options={"maxiter": 500, "ftol": 1e-12})
    q = np.clip(res.x, robot.lower, robot.upper)
    ok = np.linalg.norm(position_error(q)) < 1e-8
    return q, (-neg_mu(q) if ok else -np.inf)


def optimal_manipulability(robot, target, starts: int = 64, seed: int = 0, theta_hint=None):
    """``(μ*, θ*)``: best manipulability with the end effector at ``target`` (multi-start SLSQP).

    Args:
        robot: the robot.
        target: ``(3,)`` position [m].
        starts: random starts (uniform within the joint limits), plus ``theta_hint``.
        seed: seed of the starts.
        theta_hint: an extra start ``(nq,)``.

    Returns:
        ``(float, (nq,) array)``; ``μ* = -inf`` if no start reached the target.

    Raises:
        InvalidArgument: ``starts`` or ``seed`` not an integer >= 0 (1.5 is not truncated).
    """
    from drake_mh.optim.base import check_seed

    starts, seed = check_seed(starts, "starts"), check_seed(seed)
    return _cached(robot.name, robot, tuple(np.asarray(target, dtype=float).round(12)), starts, seed,
                   None if theta_hint is None else tuple(np.asarray(theta_hint, dtype=float)))


@functools.lru_cache(maxsize=64)
def _cached(_name, robot, target, starts, seed, hint):
    target = np.asarray(target)
    rng = np.random.default_rng(seed)
    initial = ([] if hint is None else [np.asarray(hint)]) + list(robot.random_configurations(starts, rng))
    best_mu, best_q = -np.inf, None
    for q0 in initial:
        q, mu = _slsqp(robot, target, q0)
        if mu > best_mu:
            best_mu, best_q = mu, q
    return float(best_mu), best_q


def optimal_manipulability_along(robot, targets, theta_start=None, starts: int = 32, restarts: int = 3,
                                 seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``μ*`` along a sequence of targets ``(N, 3)``: multi-start at the first, then continuation.

    Each later target starts SLSQP from the previous optimum and from ``restarts`` random
    configurations (the best is kept), the paper's "max manipulability of the end-effector
    position at each sampling time" (Sec. V-A).

    Returns:
        ``mu (N,)``, ``theta (N, nq)``.
    """
    targets = np.asarray(targets, dtype=float).reshape(-1, 3)
    rng = np.random.default_rng(seed)
    mu0, q = optimal_manipulability(robot, targets[0], starts=starts, seed=seed, theta_hint=theta_start)
    mus, qs = [mu0], [q]
    for target in targets[1:]:
        best_q, best_mu = _slsqp(robot, target, qs[-1])
        for q0 in robot.random_configurations(restarts, rng):
            cand, mu = _slsqp(robot, target, q0)
            if mu > best_mu:
                best_q, best_mu = cand, mu
        mus.append(best_mu)
        qs.append(best_q)
    return np.asarray(mus), np.asarray(qs)
