"""The compiled LM machinery (drake_mh.ik.lm): single-configuration kinematics against Drake,
the restart loop (convergence verified by Drake, limits,
chunking, determinism), and the hybrid's phases."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from random_models import random_chain_urdf

from drake_mh.ik import IKProblem, solve_ik
from drake_mh.ik.hybrid import HybridConfig
from drake_mh.ik.lm import STALLED, BatchLM, LMSettings, _compiled_chain
from drake_mh.kinematics.kernels import fk_jacobian_one
from drake_mh.robot import Robot

FIRST = HybridConfig().first_lm


def _fk_one(robot, q):
    chain, _ = _compiled_chain(robot.batch, None)
    F = len(robot.batch.chain.parent)
    T, J = np.empty((4, 4)), np.empty((6, robot.nq))
    fk_jacobian_one(np.asarray(q, dtype=float), *chain, True, np.empty((F, 3, 3)), np.empty((F, 3)), T, J)
    return T, J


@pytest.mark.parametrize("prismatic", [0, 3])
def test_single_configuration_kinematics_match_drake(panda, six_dof, prismatic):
    robots = [panda, six_dof, Robot(random_chain_urdf(7, 11, prismatic_every=prismatic))]
    for robot in robots:
        for q in robot.random_configurations(20, 3):
            T, J = _fk_one(robot, q)
            assert np.abs(T - robot.fk_drake(q)).max() < 1e-12
            assert np.abs(J - robot.jacobian_drake(q)).max() < 1e-12


def _trac_ik_problem(robot, seed):
    q = robot.random_configurations(1, seed)[0]
    return IKProblem(robot, robot.fk(q), position_tolerance=1e-5, orientation_tolerance=1e-5)


@pytest.mark.parametrize("settings", [FIRST, dataclasses.replace(FIRST, project_limits=True),
                                      LMSettings(stall_iters=3, lam0=1e-2)],
                         ids=["free-chan", "projected-chan", "adaptive"])
def test_run_converges_within_limits_and_drake_agrees(panda, settings):
    """Every converged row meets the solver's tolerance by Drake's FK and lies within the limits."""
    for seed in range(12):
        problem = _trac_ik_problem(panda, seed)
        lm = BatchLM(problem, 2, settings)
        lm.status[:] = STALLED
        row, evals, cursor = lm.run(np.empty((0, 7)), 0, 50_000, n_starts=2000, gen_seed=seed)
        assert row >= 0 and 0 < evals <= 50_000 and cursor >= 2
        q = lm.Qa[row]
        assert np.all(q >= panda.lower) and np.all(q <= panda.upper)
        X = panda.fk(q)
        assert np.linalg.norm(X[:3, 3] - problem.p_WT) <= 0.5e-5  # tol_factor 0.5
        if np.isfinite(lm.best_f[0]):  # a start was abandoned: its best point is within the limits
            assert np.all(lm.best_q >= panda.lower) and np.all(lm.best_q <= panda.upper)


def test_run_is_the_same_in_chunks(panda):
    """The state carries over: many small calls give what one call gives."""
    problem = _trac_ik_problem(panda, 5)
    whole = BatchLM(problem, 1, FIRST)
    whole.status[:] = STALLED
    row, evals, cursor = whole.run(np.empty((0, 7)), 0, 100_000, n_starts=500, gen_seed=3)
    chunked = BatchLM(problem, 1, FIRST)
    chunked.status[:] = STALLED
    total, c, r = 0, 0, -1
    while r < 0:
        r, e, c = chunked.run(np.empty((0, 7)), c, 7, n_starts=500, gen_seed=3)
        assert e <= 7
        total += e
    assert (r, total, c) == (row, evals, cursor)
    assert np.array_equal(chunked.Qa[r], whole.Qa[row])


def test_run_returns_when_starts_run_out(panda):
    problem = IKProblem(panda, [0.3, 0.0, 0.6], position_tolerance=1e-300)  # below round-off
    lm = BatchLM(problem, 1, FIRST)
    lm.status[:] = STALLED
    row, evals, cursor = lm.run(np.empty((0, 7)), 0, 10**6, n_starts=5, gen_seed=0)
    assert row == -1 and cursor == 5 and 0 < evals <= 5 * FIRST.max_iter


def test_given_starts_come_first(panda):
    """A start at the solution converges at once (the q_ref start of the hybrid)."""
    q = panda.random_configurations(1, 9)[0]
    problem = IKProblem(panda, panda.fk(q), position_tolerance=1e-5, orientation_tolerance=1e-5)
    lm = BatchLM(problem, 1, FIRST)
    lm.status[:] = STALLED
    row, evals, cursor = lm.run(q[None, :].copy(), 0, 1000, n_starts=100, gen_seed=0)
    assert (row, evals, cursor) == (0, 1, 1)
    assert np.array_equal(lm.Qa[0], q)


def test_hybrid_trac_ik_targets_all_solved_in_the_first_phase(panda, six_dof):
    for robot in (panda, six_dof):
        for seed in range(25):
            result = solve_ik(_trac_ik_problem(robot, 100 + seed), "hybrid", seed=seed, budget=20_000)
            assert result.success, result.message
            assert result.nfe < 10_000  # half the budget: the first phase's share


def test_hybrid_population_phase_alone_still_solves(panda):
    config = HybridConfig(first_starts=0)
    for seed in range(3):
        result = solve_ik(_trac_ik_problem(panda, seed), "hybrid", seed=seed, budget=50_000, config=config)
        assert result.success, result.message


def test_hybrid_failure_answers_within_the_limits(panda):
    """Free first-phase iterates may leave the limits; the answer of a failure never does."""
    problem = IKProblem(panda, [0.9, 0.0, 0.6], rpy=[0.0, 0.0, 0.0], position_tolerance=1e-6)  # unreachable pose
    result = solve_ik(problem, "hybrid", seed=0, budget=3000)
    assert not result.success and result.within_limits and result.nfe <= 3000
    assert result.position_error < 0.2  # the population's best, not a projected far point


def test_hybrid_generator_seed_is_deterministic(panda):
    problem = _trac_ik_problem(panda, 1)
    a = solve_ik(problem, "hybrid", seed=np.random.default_rng(4), budget=5000)
    b = solve_ik(problem, "hybrid", seed=np.random.default_rng(4), budget=5000)
    assert a.success and np.array_equal(a.q, b.q) and a.nfe == b.nfe


@pytest.mark.parametrize("method", ["pinv", "dls"])
def test_jacobian_baselines_start_mid_range(panda, method):
    """The first start is the mid-range configuration: a target reached there is solved at once."""
    problem = IKProblem(panda, panda.fk(panda.home), position_tolerance=1e-5, orientation_tolerance=1e-5)
    result = solve_ik(problem, method, seed=0, budget=1000)
    assert result.success and result.nfe == 1 and result.attempts == 1


def _backend(monkeypatch, backend):
    if backend == "numba":
        monkeypatch.setenv("DRAKE_MH_COMPILED_CORE", "0")
    else:
        monkeypatch.delenv("DRAKE_MH_COMPILED_CORE", raising=False)


def _runs(problem, settings, backend, monkeypatch, K=3, seed=0):
    """BatchLM with one backend: the state after a first short chunk (two iterations, before any
    row is near round-off), and every call's answer until a row converges (chunks of 40
    evaluations) with the converged point."""
    _backend(monkeypatch, backend)
    lm = BatchLM(problem, K, settings)
    lm.status[:] = STALLED
    starts = problem.robot.random_configurations(2, seed + 1)
    answers = [lm.run(starts, 0, 2 * K, n_starts=400, gen_seed=seed)]
    early = [a.copy() for a in (lm.Qt, lm.Qa, lm.Ea, lm.Ja, lm.fa, lm.lam, lm.stall, lm.iters, lm.fresh, lm.status)]
    row, cursor = answers[0][0], answers[0][2]
    while row < 0 and cursor < 400:
        row, evals, cursor = lm.run(starts, cursor, 40, n_starts=400, gen_seed=seed)
        answers.append((row, evals, cursor))
    return answers, early, lm.Qa[row].copy() if row >= 0 else None


@pytest.mark.parametrize("settings", [FIRST, dataclasses.replace(FIRST, project_limits=True),
                                      LMSettings(stall_iters=3, lam0=1e-2), LMSettings(adaptive=False, ref_gain=0.5)],
                         ids=["free-chan", "projected-chan", "adaptive", "plain-ref"])
@pytest.mark.parametrize("position_only", [False, True])
def test_compiled_core_iterates_as_the_numba_kernel(panda, monkeypatch, settings, position_only):
    """The compiled core's lm_run takes the numba kernel's steps: the same state after two
    iterations (to round-off), the same answers of every call (restarts, chunks) and the same
    converged point; its lm_step gives the numba lm_step's state from the same inputs."""
    pytest.importorskip("drake_mh._native", reason="the compiled core drake_mh._native is not built")
    for seed in range(3):
        q = panda.random_configurations(1, 100 + seed)[0]
        target = panda.fk(q)[:3, 3] if position_only else panda.fk(q)
        problem = IKProblem(panda, target, position_tolerance=1e-6, orientation_tolerance=1e-6,
                            q_ref=panda.home if settings.ref_gain else None)
        core_answers, core_early, core_q = _runs(problem, settings, "core", monkeypatch, seed=seed)
        numba_answers, numba_early, numba_q = _runs(problem, settings, "numba", monkeypatch, seed=seed)
        assert core_answers == numba_answers
        for a, b in zip(core_early, numba_early):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)
        if core_q is not None:
            np.testing.assert_allclose(core_q, numba_q, atol=1e-9)
        states = []
        for backend in ("core", "numba"):  # one lm_step from the same state and the same poses
            _backend(monkeypatch, backend)
            lm = BatchLM(problem, 4, settings)
            lm.start(np.arange(4), panda.random_configurations(4, seed))
            lm.iterate()
            lm.Qt[:] = panda.random_configurations(4, seed + 7)
            states.append((lm.iterate(), [a.copy() for a in (lm.Qt, lm.Qa, lm.fa, lm.lam, lm.stall, lm.status)]))
        assert states[0][0] == states[1][0]
        for a, b in zip(states[0][1], states[1][1]):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)
