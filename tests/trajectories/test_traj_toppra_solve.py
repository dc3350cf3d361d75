"""The compiled TOPP-RA against the toppra package on the same rows, a hand-solved case, and retime."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import PPoly
from traj_helpers import random_waypoints, sampled_ratios

from drake_mh._support.native import ENVIRONMENT, compiled_core
from drake_mh.errors import InfeasibleTrajectory, InvalidArgument
from drake_mh.trajectories import retime
from drake_mh.trajectories.paths import joint_path
from drake_mh.trajectories.toppra_solve import StageRows, solve_sd, stage_rows
from drake_mh.trajectories.toppra_time import _gridpoints, timing_from_gridpoints, toppra_like

RTOL = 1e-6
"""compiled against package: relative on every ``ṡ`` and on the duration (the port does the
package's operations in the same order, so the two agree far closer than this)."""


def _needs_core():
    if compiled_core() is None:
        pytest.skip("the compiled core drake_mh._native is not built (pip install . builds it)")


def _panda_rows(panda, seed, acceleration: bool, check_points: int = 1):
    rng = np.random.default_rng(seed)
    W = random_waypoints(panda, rng, k=int(rng.integers(3, 9)), spread=float(rng.uniform(0.2, 0.8)))
    spline, s_way = joint_path(W, panda, "toppra", bc_type="not-a-knot")
    gp = _gridpoints(spline, s_way, None)
    amax = panda.acceleration_limits * 0.99 if acceleration else np.full(panda.nq, np.inf)
    rows = stage_rows(panda, spline, gp, panda.velocity_limits * 0.99, amax, panda.effort_limits,
                      np.linspace(0.0, 1.0, check_points + 2))
    return rows, spline


@pytest.mark.parametrize("acceleration", [False, True], ids=["vendor-velocity-torque", "velocity-acc-torque"])
@pytest.mark.parametrize("seed", range(4))
def test_compiled_sd_equals_the_packages(panda, seed, acceleration):
    """Random Panda paths, the same gridpoints and rows: velocity + torque (what a vendor URDF
    declares) and velocity + acceleration + torque; both solvers' ``ṡ`` and durations agree."""
    _needs_core()
    rows, spline = _panda_rows(panda, seed, acceleration, check_points=1 + seed % 2)
    compiled, by = solve_sd(rows, spline, "compiled")
    package, by_package = solve_sd(rows, spline, "toppra")
    assert (by, by_package) == ("compiled", "toppra")
    assert compiled.shape == package.shape == rows.gridpoints.shape
    assert compiled[0] == 0 and compiled[-1] == 0 and np.all(compiled[1:-1] > 0)
    np.testing.assert_allclose(compiled, package, rtol=RTOL, atol=1e-12)
    durations = [timing_from_gridpoints(rows.gridpoints, sd).x[-1] for sd in (compiled, package)]
    assert abs(durations[0] / durations[1] - 1) < RTOL


def test_compiled_controllable_sets_and_failures(panda):
    """The core's own outputs: xs within the controllable sets K it returns; a row no (u, x)
    satisfies makes the backward pass fail at that stage (NaN speeds), as toppra's does."""
    _needs_core()
    core = compiled_core()
    rows, _ = _panda_rows(panda, 9, True)
    A, B, C, x_lo, x_hi = rows.canonical()
    stage, xs, us, K = core.topp_ra(rows.gridpoints, A, B, C, x_lo, x_hi)
    assert stage == -1 and us.shape == (len(xs) - 1,)
    assert np.all(xs >= K[:, 0] - 1e-12) and np.all(xs <= K[:, 1] + 1e-12)
    np.testing.assert_allclose(xs[1:], xs[:-1] + 2 * np.diff(rows.gridpoints) * us, rtol=2e-4, atol=1e-8)
    C = C.copy()
    C[40, 0] = 1.0  # 0 u + 0 x + 1 <= 0 at stage 40: never
    A, B = A.copy(), B.copy()
    A[40, 0] = B[40, 0] = 0.0
    stage, xs, _, K = core.topp_ra(rows.gridpoints, A, B, C, x_lo, x_hi)
    assert stage == 40 and np.all(np.isnan(xs)) and np.isnan(K[40]).any()
    with pytest.raises(ValueError, match="increasing"):
        core.topp_ra(rows.gridpoints[::-1].copy(), A, B, C, x_lo, x_hi)
    with pytest.raises(ValueError, match="finite"):
        core.topp_ra(rows.gridpoints, A * np.nan, B, C, x_lo, x_hi)


def _line(d, n: int = 21):
    """The straight path ``p(s) = s d``, ``s`` in [0, 1], and ``n`` uniform gridpoints."""
    d = np.asarray(d, dtype=float)
    return PPoly(np.stack([d[None, :], np.zeros((1, len(d)))]), np.array([0.0, 1.0])), np.linspace(0, 1, n)


@pytest.mark.parametrize("backend", ["compiled", "toppra"])
def test_two_joint_line_matches_the_hand_solution(backend):
    """``p(s) = s d`` with ``d = (0.5, -1)``, ``v = (1, 2)``, ``a = (4, 8)``: ``ṡ <= min v_j/|d_j| = 2``
    and ``|s̈| <= min a_j/|d_j| = 8``, so ``ṡ² = min(4, 16 s, 16 (1 - s))`` and the duration is
    0.25 + 0.25 + 0.25 = 0.75 s. The controllable sets are exact; the forward pass trims each
    step by toppra's ``max(x - 1e-8, 0.9999 x)``, so the speeds lie a little below."""
    if backend == "compiled":
        _needs_core()
    spline, gp = _line([0.5, -1.0])
    rows = stage_rows(None, spline, gp, np.array([1.0, 2.0]), np.array([4.0, 8.0]), np.full(2, np.inf),
                      np.linspace(0, 1, 3))
    sd, _ = solve_sd(rows, spline, backend)
    exact = np.sqrt(np.minimum(4.0, np.minimum(16 * gp, 16 * (1 - gp))))
    assert np.all(sd <= exact + 1e-12)
    np.testing.assert_allclose(sd, exact, rtol=2e-3, atol=1e-12)
    duration = timing_from_gridpoints(gp, sd).x[-1]
    assert 0.75 - 1e-12 <= duration <= 0.75 * (1 + 2e-3)
    if backend == "compiled":
        _, _, _, K = compiled_core().topp_ra(gp, *rows.canonical())
        np.testing.assert_allclose(K[:, 1], np.minimum(4.0, 16 * (1 - gp)), rtol=1e-12, atol=1e-12)


def _too_weak(panda):
    limits = {"velocity": panda.velocity_limits, "acceleration": panda.acceleration_limits,
              "torque": panda.effort_limits * 1e-3}
    W = random_waypoints(panda, np.random.default_rng(6), k=3)
    return W, limits, {"velocity": 1.0, "acceleration": 1.0, "torque": 1.0}


@pytest.mark.parametrize("backend", ["compiled", "toppra"])
def test_gravity_above_the_effort_limit_raises_the_same_error(panda, backend):
    if backend == "compiled":
        _needs_core()
    W, limits, factors = _too_weak(panda)
    with pytest.raises(InfeasibleTrajectory, match="gravity") as info:
        toppra_like(W, panda, limits, "toppra", factors, 50, "not-a-knot", 1, backend=backend)
    assert info.value.method == "toppra"
    if backend == "compiled":
        with pytest.raises(InfeasibleTrajectory) as reference:
            toppra_like(W, panda, limits, "toppra", factors, 50, "not-a-knot", 1, backend="toppra")
        assert str(reference.value) == str(info.value)


def test_unknown_or_missing_backend_is_named(panda, monkeypatch):
    spline, gp = _line([1.0, 1.0])
    rows = stage_rows(None, spline, gp, np.ones(2), np.ones(2), np.full(2, np.inf), [0.0, 1.0])
    with pytest.raises(InvalidArgument, match="backend"):
        solve_sd(rows, spline, "fast")
    monkeypatch.setenv(ENVIRONMENT, "0")
    with pytest.raises(InvalidArgument, match="compiled core"):
        solve_sd(rows, spline, "compiled")
    assert solve_sd(rows, spline, "auto")[1] == "toppra"


@pytest.mark.parametrize("seed", [0, 3])
def test_retime_certifies_with_either_solver(panda, monkeypatch, seed):
    """The whole retime: the compiled solve (where built) and the package's (core disabled by the
    environment) give the same duration, each certified (the certificate does not look at the
    solver) and within the limits when its positions are sampled and differenced."""
    _needs_core()
    W = random_waypoints(panda, np.random.default_rng(seed), k=5, spread=0.5)
    compiled = retime(W, panda, "toppra")
    monkeypatch.setenv(ENVIRONMENT, "0")
    package = retime(W, panda, "toppra")
    monkeypatch.delenv(ENVIRONMENT)
    assert compiled.info["solver"] == "compiled" and package.info["solver"] == "toppra"
    assert abs(compiled.duration / package.duration - 1) < RTOL
    enforced = compiled.info["limits"]
    assert compiled.info["certificate"].ok(("position",) + enforced)
    sampled = sampled_ratios(compiled, panda, enforced)
    for quantity in enforced:
        assert sampled[quantity] <= 1 + (1e-4 if quantity == "torque" else 1e-5), (quantity, sampled)
    assert max(sampled[q] for q in enforced) >= 0.9, sampled


def test_rows_need_no_robot_without_torque():
    """A StageRows without velocity: no bound on x (the bounds ±inf)."""
    spline, gp = _line([1.0, 2.0], n=5)
    rows = stage_rows(None, spline, gp, np.full(2, np.inf), np.ones(2), np.full(2, np.inf), [0.0, 1.0],
                      velocity_bound=False)
    assert isinstance(rows, StageRows) and rows.x_max is None and rows.a.shape == (5, 2, 2)
    A, B, C, x_lo, x_hi = rows.canonical()
    assert A.shape == (5, 8) and np.all(np.isinf(x_lo)) and np.all(np.isinf(x_hi))
    np.testing.assert_array_equal(A[:, :2], rows.a[:, 0])
    np.testing.assert_array_equal(A[:, 2:4], -rows.a[:, 0])
    np.testing.assert_array_equal(C[:, 2:4], -rows.c[:, 0] - rows.lims)


@pytest.mark.parametrize("acceleration", [False, True], ids=["vendor-velocity-torque", "velocity-acc-torque"])
@pytest.mark.parametrize("seed", range(4))
def test_rows_built_in_the_core_solve_as_the_python_rows(panda, seed, acceleration):
    """``solve_spline`` builds the rows and solves them in one compiled call: the same ``ṡ`` as
    ``stage_rows`` solved by the compiled TOPP-RA (and so as the package's, above)."""
    from drake_mh.trajectories.toppra_solve import solve_spline

    _needs_core()
    rows, spline = _panda_rows(panda, seed, acceleration, check_points=1 + seed % 2)
    amax = panda.acceleration_limits * 0.99 if acceleration else np.full(panda.nq, np.inf)
    fractions = np.linspace(0.0, 1.0, 1 + seed % 2 + 2)
    one_call, by = solve_spline(panda, spline, rows.gridpoints, panda.velocity_limits * 0.99, amax,
                                panda.effort_limits, fractions)
    reference, _ = solve_sd(rows, spline, "compiled")
    assert by == "compiled" and one_call.shape == reference.shape
    np.testing.assert_allclose(one_call, reference, rtol=1e-9, atol=1e-12)
    package, by = solve_spline(panda, spline, rows.gridpoints, panda.velocity_limits * 0.99, amax,
                               panda.effort_limits, fractions, backend="toppra")
    assert by == "toppra"
    np.testing.assert_allclose(one_call, package, rtol=RTOL, atol=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_gridpoints_from_the_core_are_the_python_ones(panda, seed, monkeypatch):
    """The core's gridpoints (toppra's passes, the knots added, near-duplicates dropped) are
    those of the Python passes on the same spline; a spline whose passes never settle raises
    the same error."""
    from drake_mh.trajectories import toppra_time

    _needs_core()
    rng = np.random.default_rng(seed)
    W = random_waypoints(panda, rng, k=int(rng.integers(2, 12)), spread=float(rng.uniform(0.05, 1.0)))
    spline, s_way = joint_path(W, panda, "toppra", bc_type="not-a-knot")
    core = _gridpoints(spline, s_way, None)
    monkeypatch.setattr(toppra_time, "compiled_core", lambda: None)
    python = _gridpoints(spline, s_way, None)
    assert core.shape == python.shape
    np.testing.assert_allclose(core, python, rtol=0, atol=1e-12 * spline.x[-1])
    with pytest.raises(ValueError, match="gridpoint"):
        compiled_core().spline_gridpoints(spline.c, spline.x, 1e-300, 3, 0.05, 100)


def test_solve_spline_refuses_bad_gridpoints_and_backends(panda):
    from drake_mh.trajectories.toppra_solve import solve_spline

    _needs_core()
    rows, spline = _panda_rows(panda, 1, True)
    limits = (panda.velocity_limits, panda.acceleration_limits, panda.effort_limits)
    with pytest.raises(ValueError, match="increasing"):
        solve_spline(panda, spline, rows.gridpoints[::-1], *limits, np.linspace(0, 1, 3))
    with pytest.raises(InvalidArgument, match="backend"):
        solve_spline(panda, spline, rows.gridpoints, *limits, np.linspace(0, 1, 3), backend="fast")
