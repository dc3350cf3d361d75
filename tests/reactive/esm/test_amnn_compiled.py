"""Compiled AMNN step (drake_mh.reactive.esm.amnn_compiled): the same steps as the Python ask/tell
path, one layer equal to a numpy transcription of eqs. (12)-(20), the feasible set respected,
scenario 1 safe and converged."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.errors import InvalidArgument
from drake_mh.optim import ARO
from drake_mh.reactive import AMNN, ESMConfig, ESMObjective, build_step, check_step, get_scenario, run_esm
from drake_mh.reactive.esm import amnn_compiled
from drake_mh.reactive.esm.scenarios import TARGET, THETA0
from drake_mh.scene import Box, Scene, Sphere

MU_STAR = 0.16089694     # multi-start SLSQP, flange pinned at the paper's target (docs/esm.md)


def _scene(robot, shape=None, position=(0.0, -0.16, 0.6)):
    scene = Scene(robot)
    scene.add("ball", shape or Sphere(0.15), position, velocity=(0.0, 0.16, 0.0))
    return scene


@pytest.fixture(scope="module")
def close_step(panda):
    """The sphere close to the upper arm and approaching: obstacle rows active."""
    return build_step(panda, _scene(panda), np.array(THETA0), TARGET, ESMConfig(h1=10.0))


def _steps(robot, solver, scene, n=4):
    """``n`` warm-started steps from θ0 in a static scene; the solutions and the populations."""
    solver.reset(3)
    theta, out = np.array(THETA0), []
    for _ in range(n):
        step = build_step(robot, scene, theta, TARGET, ESMConfig(h1=10.0))
        sol = solver.solve(robot, step)
        out.append((step, sol, solver.population.copy(), solver.population_f.copy()))
        theta = sol.theta
    return out


@pytest.mark.parametrize("handling", ["reject", "repair"])
@pytest.mark.parametrize("where", ["sphere", "box"])
def test_compiled_steps_equal_the_python_path(panda, handling, where):
    """Same seed: bit-identical answers, values and last layers (same draws, same kernels)."""
    shape, position = (None, (0.0, -0.16, 0.6)) if where == "sphere" else (Box((0.12, 0.12, 0.12)), (0.25, -0.12, 0.62))
    scene = _scene(panda, shape, position)
    fast = _steps(panda, AMNN(layers=30, agents=16, handling=handling, compiled=True), scene)
    slow = _steps(panda, AMNN(layers=30, agents=16, handling=handling, compiled=False), scene)
    for (step, a, Xa, Fa), (_, b, Xb, Fb) in zip(fast, slow):
        assert any(r.rhs < 0.5 for r in step.rows)       # the inequality matters here
        np.testing.assert_array_equal(a.theta, b.theta)
        assert (a.F, a.feasible, a.nfe, a.message) == (b.F, b.feasible, b.nfe, b.message)
        assert a.nfe == 31 * 16
        np.testing.assert_array_equal(Xa, Xb)
        np.testing.assert_array_equal(Fa, Fb)


def _numpy_layer(X, U, t, T, lower, upper):
    """ARO-amnn candidates written out from the ESM paper's equations (numpy, per agent)."""
    P, D = X.shape
    rows = np.arange(P)
    A = 4.0 * (1.0 - t / T) * np.log(1.0 / U[:, 0])                                 # (12)
    n_dims = np.ceil(U[:, 1] * D).astype(int)                                       # (13)
    c = np.zeros((P, D), dtype=bool)
    for i in range(P):                      # n_dims distinct dimensions: partial Fisher-Yates
        perm = np.arange(D)
        for m in range(n_dims[i]):
            q = m + min(int(U[i, 8 + m] * (D - m)), D - m - 1)
            perm[[m, q]] = perm[[q, m]]
        c[i, perm[: n_dims[i]]] = True
    R = ((np.e - np.exp(((t - 1) / T) ** 2)) * np.sin(2.0 * np.pi * U[:, 2]))[:, None] * c   # (14)
    j = (rows + 1 + np.minimum((U[:, 6] * (P - 1)).astype(int), P - 2)) % P       # another agent
    detour = X + R * (X[j] - X)                                                     # (15)
    g = np.minimum((U[:, 7] * D).astype(int), D - 1)
    H = (T - t + 1) / T * U[:, 4]                                                   # (16)
    b = X.copy()
    b[rows, g] += H * X[rows, g]                                                    # (17)
    hide = X + R * (U[:, 5:6] * b - X)                                              # (18)
    return np.clip(np.where((A > 1.0)[:, None], detour, hide), lower, upper)        # (19), box


def test_layers_equal_a_numpy_transcription(panda, close_step):
    """Three layers from the same generator: candidates, reject (eq. 19) and greedy (eq. 20)."""
    P, D, L, seed = 24, 7, 3, 11
    x0 = close_step.repair(np.array(THETA0)[None])[0]
    opt = ARO(close_step.bounds, budget=(L + 1) * P, seed=seed, pop_size=P, x0=x0, variant="amnn")
    best_x, best_f, X_c, F_c = amnn_compiled.run_layers(panda, close_step, opt, "reject")

    objective = ESMObjective(panda, close_step, "reject")
    gen = np.random.default_rng(seed)
    lower, upper = close_step.lower, close_step.upper
    X = lower + gen.random((P, D)) * (upper - lower)
    X[0] = x0[0]
    F = objective(X)
    rejected = 0
    for t in range(1, L + 1):
        V = _numpy_layer(X, gen.random((P, 8 + D)), t, L, lower, upper)
        FV = objective(V)
        rejected += int(np.isinf(FV).sum())
        better = FV < F
        X[better], F[better] = V[better], FV[better]
    assert rejected > 0                                   # eq. (9) did reject candidates
    np.testing.assert_allclose(X_c, X, rtol=0, atol=1e-13)
    np.testing.assert_allclose(F_c, F, rtol=1e-12)
    assert best_f == pytest.approx(F.min(), rel=1e-12)
    np.testing.assert_allclose(best_x, X[np.argmin(F)], atol=1e-13)


def test_step_respects_the_box_and_the_rows(panda, close_step):
    solver = AMNN(layers=40, agents=16)
    for (step, sol, X, F) in _steps(panda, solver, _scene(panda)):
        assert sol.feasible and check_step(panda, step, sol.theta).ok()
        assert np.all(X >= step.lower) and np.all(X <= step.upper)
        finite = np.isfinite(F)
        assert finite[0] and step.feasible(X[finite]).all()         # kept agents satisfy A θ <= c
        assert np.all(step.A @ sol.theta <= step.c + step.config.feasibility_tol)


def test_deterministic_per_seed(panda):
    scenario = get_scenario("self_motion", config=ESMConfig(h1=10.0))
    solver = AMNN(layers=20, agents=8)
    a = run_esm(panda, scenario, solver, seed=5, steps=6, verify=False)
    b = run_esm(panda, scenario, solver, seed=5, steps=6, verify=False)          # reset() restarts
    c = run_esm(panda, scenario, AMNN(layers=20, agents=8), seed=6, steps=6, verify=False)
    np.testing.assert_array_equal(a.theta, b.theta)
    assert not np.array_equal(a.theta, c.theta)


def test_compiled_is_the_default_and_checked(panda, close_step):
    assert AMNN().compiled
    assert not AMNN(compiled=False).compiled
    with pytest.raises(InvalidArgument, match="compiled"):
        AMNN(compiled="yes")
    with pytest.raises(InvalidArgument, match="amnn"):
        amnn_compiled.run_layers(panda, close_step, ARO(close_step.bounds, budget=64, pop_size=8), "reject")
    opt = ARO(close_step.bounds, budget=64, pop_size=8, variant="amnn")
    with pytest.raises(InvalidArgument, match="handling"):
        amnn_compiled.run_layers(panda, close_step, opt, "penalty")


def test_cache_key_follows_the_called_files(monkeypatch, tmp_path):
    """The kernel's closure holds the fingerprint of the files it calls into; editing one changes it."""
    cell = amnn_compiled._amnn_layers.py_func.__closure__[0].cell_contents
    assert cell == amnn_compiled._fingerprint()
    other = tmp_path / "edited.py"
    other.write_text("x = 1\n")
    edited = type("Module", (), {"__file__": str(other)})
    monkeypatch.setattr(amnn_compiled, "_DEPENDENCIES", amnn_compiled._DEPENDENCIES + (edited,))
    assert amnn_compiled._fingerprint() != cell


def _assert_safe_and_converged(run):
    assert np.all(run.joint_violation <= 1e-9) and np.all(run.velocity_violation <= 1e-7)
    assert np.all(run.inequality_violation <= 1e-6) and run.solver_feasible.all()
    assert run.threshold_violations == 0
    assert run.active_rows.max() >= 1                   # the sphere did constrain the motion
    free = np.concatenate([[True], run.active_rows == 0])
    before = (run.t >= 0.5) & (run.t <= 1.0) & free     # settled, before the sphere arrives
    assert np.max(run.error[before]) < 1e-4             # the end of the convergence (docs/esm.md)
    assert np.median(run.error[before]) < 1e-6
    assert np.min(run.mu[before]) > 0.95 * MU_STAR
    assert run.error[-1] < 1e-5


def test_scenario_1_compiled_equals_python_and_is_safe(panda):
    scenario = get_scenario("self_motion", config=ESMConfig(h1=10.0))
    fast = run_esm(panda, scenario, AMNN(compiled=True), seed=0)
    _assert_safe_and_converged(fast)
    slow = run_esm(panda, scenario, AMNN(compiled=False), seed=0, verify=False)
    np.testing.assert_array_equal(fast.theta, slow.theta)
    np.testing.assert_array_equal(fast.mu, slow.mu)


@pytest.mark.slow
def test_scenario_1_paper_budget(panda):
    """L = 1000 x P = 128 (the paper's budget) on scenario 1: safe, on the target, at μ*."""
    scenario = get_scenario("self_motion", config=ESMConfig(h1=10.0))
    run = run_esm(panda, scenario, AMNN(layers=1000, agents=128), seed=0)
    _assert_safe_and_converged(run)
    assert np.all(run.nfe == 1001 * 128)
