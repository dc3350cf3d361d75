"""Via-point polynomials (ABC paper eqs. 4-17) and the fitness terms (eqs. 18, 20)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.robot import Robot
from drake_mh.trajectories.viapoint import (ViaPointFitness, ViaPointProblem, evaluate, segment_coefficients,
                                            viapoint_trajectory)

START, GOAL = (-np.pi / 2, 0.0), (0.0, 0.0)


@settings(max_examples=30, deadline=None)
@given(mp=st.integers(1, 3), n=st.integers(1, 3), seed=st.integers(0, 10_000))
def test_continuity_at_via_points_and_rest_at_the_ends(mp, n, seed):
    rng = np.random.default_rng(seed)
    q0, qg = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)
    qv, vv = rng.uniform(-2, 2, (mp, n)), rng.uniform(-1, 1, (mp, n))
    T = rng.uniform(0.2, 3.0, mp + 1)
    traj = viapoint_trajectory(q0, qv, vv, qg, T)
    breaks = np.r_[0.0, np.cumsum(T)]
    assert np.allclose(traj(0.0), q0) and np.allclose(traj(0.0, 1), 0) and np.allclose(traj(0.0, 2), 0)
    end = breaks[-1]
    assert np.allclose(traj(end), qg, atol=1e-8) and np.allclose(traj(end, 1), 0, atol=1e-8)
    assert np.allclose(traj(end, 2), 0, atol=1e-7)
    for i in range(mp):  # position, velocity (= the design's), acceleration continuous at every via
        b, eps = breaks[i + 1], 1e-9
        for order, tol in ((0, 1e-7), (1, 1e-6), (2, 1e-5)):
            left, right = traj(b - eps, order), traj(b + eps, order)
            # the next derivative moves the value by up to eps * |slope| on each side (accelerations
            # of ~600 rad/s^2 moved the velocity by 1.3e-6 across the 2e-9 gap)
            slope = max(np.abs(traj(b - eps, order + 1)).max(), np.abs(traj(b + eps, order + 1)).max())
            assert np.allclose(left, right, atol=tol * max(1.0, np.abs(left).max()) + 2 * eps * slope)
        assert np.allclose(traj(b), qv[i]) and np.allclose(traj(b, 1), vv[i])
    # degrees: 4 for the via segments, 5 for the last (the PPoly pads to 5; the 5th coefficient is 0)
    c = traj.path.c
    assert np.allclose(c[0, :mp], 0.0) and np.any(np.abs(c[0, mp]) > 0)


def test_population_evaluation_matches_the_trajectory():
    rng = np.random.default_rng(1)
    P, mp, n = 5, 2, 2
    qv, vv = rng.uniform(-2, 2, (P, mp, n)), rng.uniform(-1, 1, (P, mp, n))
    T = rng.uniform(0.2, 2.0, (P, mp + 1))
    coeffs = segment_coefficients(START, qv, vv, GOAL, T)
    assert [c.shape[1] for c in coeffs] == [5, 5, 6]
    t, q, qd, qdd = evaluate(coeffs, T, 9)
    for p in range(P):
        traj = viapoint_trajectory(START, qv[p], vv[p], GOAL, T[p])
        inner = np.r_[t[p, :-1] + 1e-12, t[p, -1]]  # segment ends belong to the next piece in PPoly
        assert np.allclose(traj(t[p]), q[p], atol=1e-9)
        assert np.allclose(traj(inner, 1), qd[p], atol=1e-6)
        assert np.allclose(traj(inner, 2), qdd[p], atol=1e-5)


@pytest.fixture(scope="module")
def arm():
    return drake_mh.load_robot("planar2r")


def test_fitness_terms_of_the_quarter_swing(arm):
    """Stretched arm swinging a quarter turn: f_q = π/2 rad, f_c = π ft (radius 2 ft), t_T = ΣT."""
    prob = ViaPointProblem(arm, START, GOAL)
    x = np.array([-np.pi / 4, 0.0, np.pi / 4, 0.0, 1.0, 1.0])  # monotone in q1
    terms = {k: float(v[0]) for k, v in prob.terms(x).items()}
    assert terms["f_q"] == pytest.approx(np.pi / 2, rel=1e-9)
    assert terms["f_c"] == pytest.approx(np.pi, rel=1e-3)
    assert terms["t_T"] == pytest.approx(2.0)
    assert terms["f_ot"] == 0.0  # 175 g links never need 45 / 20 N·m at this pace
    assert terms["fitness"] == pytest.approx(terms["f_q"] * 2 + terms["f_c"] * 2 + 2.0, rel=1e-12)
    metres = ViaPointProblem(arm, START, GOAL, fitness=ViaPointFitness(length_unit=1.0)).terms(x)["f_c"][0]
    assert metres == pytest.approx(np.pi / 2 * 0.6096, rel=1e-3)
    assert prob.dimension == 6 and prob.bounds.shape == (6, 2)
    assert np.allclose(prob.bounds[2:4], [[-np.pi / 4, np.pi / 4]] * 2)  # eq. (22)
    assert np.allclose(prob.bounds[4:], [[0.1, 8.0]] * 2)  # eq. (23)


def test_torque_excess_term(arm):
    """f_ot = Σ_j ∫ max(0, |τ_j| - τ_max) dt: zero within the limits, positive with weak motors."""
    weak = Robot(arm.urdf.replace('effort="45"', 'effort="0.5"').replace('effort="20"', 'effort="0.1"'))
    x = np.array([-np.pi / 4, 0.0, np.pi / 4, 0.0, 0.5, 0.5])
    strong_terms = ViaPointProblem(arm, START, GOAL).terms(x)
    weak_terms = ViaPointProblem(weak, START, GOAL).terms(x)
    assert strong_terms["f_ot"][0] == 0.0 and weak_terms["f_ot"][0] > 0.0
    # by hand from Drake's inverse dynamics on a fine grid
    traj = ViaPointProblem(weak, START, GOAL).trajectory(x)
    t = np.linspace(0, traj.duration, 4001)
    q, v, a = traj.derivatives(t, 2)
    tau = np.array([weak.inverse_dynamics(*s) for s in zip(q, v, a)])
    ref = np.trapezoid(np.maximum(np.abs(tau) - weak.effort_limits, 0).sum(1), t)
    assert weak_terms["f_ot"][0] == pytest.approx(ref, rel=2e-2)


def test_obstacle_factor(arm):
    """f_ob = 1 when clear, < 1 through the obstacle, also for a swing too fast to be sampled inside it."""
    centre = (0.5 * np.cos(np.pi / 4), 0.0, -0.5 * np.sin(np.pi / 4))
    prob = ViaPointProblem(arm, START, GOAL, obstacles=((centre, 0.05),))
    through = np.array([-np.pi / 4, 0.0, np.pi / 4, 0.0, 1.0, 1.0])
    t = prob.terms(through)
    assert t["f_ob"][0] < 0.1 and t["fitness"][0] == pytest.approx(t["f_f"][0] / t["f_ob"][0])
    assert prob.exact_min_distance(through) < 0
    # wait at the start, then swing in 0.1 s: few samples land inside the obstacle
    fast = np.array([-np.pi / 2, 0.0, 0.0, 0.0, 2.0, 0.1])
    assert prob.terms(fast)["f_ob"][0] < 0.5
    # elbow folded out of the way: no collision, f_ob = 1, f = f_f
    far = ViaPointProblem(arm, START, GOAL, obstacles=(((2.0, 0.0, 2.0), 0.05),))
    assert far.terms(through)["f_ob"][0] == 1.0
    assert far.terms(through)["fitness"][0] == far.terms(through)["f_f"][0]


def test_problem_validation(arm):
    with pytest.raises(InvalidArgument, match="q_start"):
        ViaPointProblem(arm, (0.0,), GOAL)
    with pytest.raises(InvalidArgument, match="n_via"):
        ViaPointProblem(arm, START, GOAL, n_via=0)
    with pytest.raises(InvalidArgument, match="positive"):
        ViaPointProblem(arm, START, GOAL, time_bounds=(0.0, 1.0))
    for bad in ([[0.0], [0.0, 1.0]], (0.1j, 0.0)):  # ragged: numpy's ValueError; complex: the real part kept
        with pytest.raises(InvalidArgument, match="q_start"):
            ViaPointProblem(arm, bad, GOAL)


def test_problem_keeps_copies_of_start_and_goal(arm):
    start = np.array(START, dtype=float)
    prob = ViaPointProblem(arm, start, GOAL)
    x = prob.bounds.mean(axis=1)[None]
    before = prob.terms(x)["fitness"][0]
    start[:] += 1.0  # the validated problem must not follow
    assert np.array_equal(prob.q_start, np.array(START, dtype=float))
    assert prob.terms(x)["fitness"][0] == before


def test_minimize_finds_the_free_optimum(arm):
    """Free workspace: the swing in the shortest allowed time (0.1 + 0.1 s) with q2 = 0."""
    prob = ViaPointProblem(arm, START, GOAL)
    res = drake_mh.minimize(prob, prob.bounds, method="de", budget=3000, seed=0)
    terms = {k: float(v[0]) for k, v in prob.terms(res.x).items()}
    assert terms["t_T"] < 0.3 and terms["f_q"] == pytest.approx(np.pi / 2, rel=1e-2)


def test_optimized_motion_is_certified_at_every_instant(arm):
    """The ABC result's whole motion is certified collision-free (not its samples), and Drake's exact
    distance at dense samples never contradicts the certified bound."""
    centre = (0.5 * np.cos(np.pi / 4), 0.0, -0.5 * np.sin(np.pi / 4))
    prob = ViaPointProblem(arm, START, GOAL, obstacles=((centre, 0.05),))
    res = drake_mh.minimize(prob, prob.bounds, method="abc", budget=2000, seed=0)
    motion = prob.certify_motion(res.x)
    assert motion["motion_certified"] and motion["motion_min_clearance"] >= 0
    assert 0 < motion["motion_margin"] <= 1e-3 and motion["motion_chords"] >= 2 * 16
    _, Q = prob.trajectory(res.x).sample_uniform(50 * motion["motion_chords"] // 2)
    assert prob._scene.exact_min_distance(Q).min() >= motion["motion_min_clearance"]
    # through the obstacle: refused, with where and why
    through = prob.certify_motion(np.array([-np.pi / 4, 0.0, np.pi / 4, 0.0, 1.0, 1.0]))
    assert not through["motion_certified"] and np.isnan(through["motion_min_clearance"])
    assert 0 < through["motion_failure_time"] < 2.0 and "blocked" in through["motion_failure_reason"]
    # a 0.1 s swing between the fitness's samples is caught too
    fast = prob.certify_motion(np.array([-np.pi / 2, 0.0, 0.0, 0.0, 2.0, 0.1]))
    assert not fast["motion_certified"]
    assert ViaPointProblem(arm, START, GOAL).certify_motion(res.x)["motion_certified"]   # no obstacle
