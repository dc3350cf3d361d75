"""retime: certified toppra / Drake Toppra / ruckig trajectories, infeasible requests, ruckig positions."""

from __future__ import annotations

import numpy as np
import pytest
from traj_helpers import random_waypoints, sampled_ratios
from scipy.interpolate import PPoly

import drake_mh
from drake_mh.errors import InfeasibleTrajectory, InvalidArgument, LimitViolation, UnknownMethod
from drake_mh.trajectories import certify, retime, ruckig_state_to_state
from drake_mh.trajectories.retime import timing_from_gridpoints


@pytest.mark.parametrize("method", ["toppra", "drake-toppra", "ruckig"])
def test_retime_is_certified_and_passes_through_waypoints(panda, method):
    """The certificate holds, and so does an independent check: the trajectory's positions
    sampled at 3,000 random times, their finite differences and Drake's inverse dynamics with
    gravity on a fresh plant stay within every enforced limit (tests/trajectories/traj_helpers.py),
    and the motion is time-optimal enough to come near one of them."""
    W = random_waypoints(panda, np.random.default_rng(0), k=5)
    traj = retime(W, panda, method, gridpoints=200)
    cert = traj.info["certificate"]
    assert cert.ok(("position",) + traj.info["limits"])
    enforced = traj.info["limits"]
    assert {"velocity", "acceleration"} <= set(enforced) and ("jerk" in enforced) == (method == "ruckig")
    sampled = sampled_ratios(traj, panda, enforced)
    assert sampled["position"] <= 1e-9, sampled
    for quantity in enforced:
        assert sampled[quantity] <= 1 + (1e-4 if quantity == "torque" else 1e-5), (quantity, sampled)
    assert max(sampled[q] for q in enforced) >= 0.9, sampled
    assert traj.method == method and traj.duration > 0
    assert np.allclose(traj(0.0), W[0], atol=1e-9) and np.allclose(traj(traj.duration), W[-1], atol=1e-9)
    assert np.allclose(traj(0.0, 1), 0.0, atol=1e-9) and np.allclose(traj(traj.duration, 1), 0.0, atol=1e-6)
    # every waypoint is visited: distance from each waypoint to the densely sampled trajectory
    _, Q = traj.sample_uniform(4000)
    assert max(np.min(np.linalg.norm(Q - w, axis=1)) for w in W) < 5e-3


def test_torque_from_retime_respects_limits_by_drake(panda):
    """toppra at 100 gridpoints: velocity, acceleration and torque (Drake's inverse dynamics with
    gravity on a fresh plant, at the sampled positions' differences) within the limits."""
    W = random_waypoints(panda, np.random.default_rng(1), k=4)
    traj = retime(W, panda, "toppra", gridpoints=100)
    assert "torque" in traj.info["limits"]
    sampled = sampled_ratios(traj, panda, ("velocity", "acceleration", "torque"), seed=2)
    assert sampled["torque"] <= 1 + 1e-4, sampled
    assert sampled["velocity"] <= 1 + 1e-5 and sampled["acceleration"] <= 1 + 1e-5, sampled


def test_torque_limit_binds_and_is_respected(panda):
    """With effort limits tight enough to bind, toppra slows down and stays within them."""
    W = random_waypoints(panda, np.random.default_rng(4), k=3)
    free = retime(W, panda, "toppra", limits=("velocity", "acceleration"), gridpoints=150)
    tau_free = free.info["certificate"].ratios["torque"]
    # choose a scale so that the free motion needs 30 % more torque than allowed on its worst joint
    scale = float(np.max(tau_free)) / 1.3
    # gravity alone (the path crawled 1000x slower) stays well below the scaled limit on this path
    assert sampled_ratios(free.time_scaled(1e-3), panda, ("torque",))["torque"] < 0.9 * scale
    assert sampled_ratios(free, panda, ("torque",))["torque"] > 1.2 * scale  # and the free motion breaks it
    slow = retime(W, panda, "toppra", limits=("velocity", "acceleration", "torque"), scale=scale,
                  gridpoints=150)
    assert slow.duration > free.duration
    assert slow.info["certificate"].max_ratio(("torque",)) <= 1 + 1e-6  # relative to scale x limits
    assert slow.info["certificate"].scale == scale
    assert certify(slow, panda, quantities=("torque",)).max_ratio() <= 1 + 1e-6      # the maker's scale
    assert certify(slow, panda, quantities=("torque",), scale=1.0).max_ratio() <= scale * (1 + 1e-6)
    assert sampled_ratios(slow, panda, ("torque",))["torque"] <= scale * (1 + 1e-4)


def test_drake_toppra_agrees_with_toppra(panda):
    W = random_waypoints(panda, np.random.default_rng(5), k=7)
    ours = retime(W, panda, "toppra", gridpoints=300)
    drake = retime(W, panda, "drake-toppra", gridpoints=300)
    assert abs(ours.duration / drake.duration - 1) < 0.05


def test_infeasible_gravity_raises_with_reason(panda):
    W = random_waypoints(panda, np.random.default_rng(6), k=3)
    with pytest.raises(InfeasibleTrajectory, match="gravity") as info:
        retime(W, panda, "toppra", scale=1e-3, gridpoints=50)
    assert info.value.method == "toppra"
    with pytest.raises(InfeasibleTrajectory, match="gravity"):
        retime(W, panda, "drake-toppra", scale=1e-3, gridpoints=50)
    with pytest.raises(InfeasibleTrajectory, match="gravity") as info:   # not a LimitViolation at t = 904 s
        retime(W, panda, "ruckig", scale=1e-3, limits=("velocity", "acceleration", "jerk", "torque"))
    assert info.value.method == "ruckig"


@pytest.mark.parametrize("options", [dict(scale="0.5"), dict(gridpoints="abc"), dict(check_points=-3),
                                     dict(bc_type="bogus"), dict(tol=np.nan), dict(max_attempts=0)])
def test_bad_options_are_named(panda, options):
    with pytest.raises(InvalidArgument, match=next(iter(options))):
        retime(np.array([panda.home, panda.home + 0.3]), panda, **options)


def test_bad_requests(panda):
    W = random_waypoints(panda, np.random.default_rng(7), k=3)
    with pytest.raises(UnknownMethod, match="ruckig"):
        retime(W, panda, "magic")
    with pytest.raises(InvalidArgument, match="ruckig"):
        retime(W, panda, "toppra", limits=("jerk",))
    with pytest.raises(InvalidArgument, match="shape"):
        retime(W[:, :3], panda)
    with pytest.raises(InvalidArgument, match="scale"):
        retime(W, panda, scale=0.0)
    outside = W.copy()
    outside[1, 3] = 0.5  # Panda joint 4 is always negative
    with pytest.raises(InfeasibleTrajectory, match="panda_joint4"):
        retime(outside, panda)
    with pytest.raises(InfeasibleTrajectory, match="equal"):
        retime(np.vstack([W[0], W[0]]), panda)


def test_spline_overshoot_is_refined_inside_the_limits(planar2r):
    """Waypoints near the limit: the plain spline overshoots (exact extrema), the refined one does not."""
    from scipy.interpolate import CubicSpline

    from drake_mh.trajectories.paths import piece_extrema

    W = np.array([[0.0, 0.0], [2.0, 0.5], [3.14, 0.6], [3.1, 0.7], [0.0, 1.0]])
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(W, axis=0), axis=1))]
    plain = CubicSpline(s, W)
    lo, hi = piece_extrema(plain)
    x = np.linspace(0, s[-1], 20001)
    assert np.allclose(hi.max(0), plain(x).max(0), atol=1e-6) and np.allclose(lo.min(0), plain(x).min(0), atol=1e-6)
    assert hi.max() > planar2r.upper[0]  # the plain spline leaves [-pi, pi]
    traj = retime(W, planar2r, "toppra", gridpoints=200)
    _, Q = traj.sample_uniform(5000)
    assert np.all(Q <= planar2r.upper + 1e-9)
    assert traj.info["path_knots"] > len(W)


def test_ruckig_matches_ruckig_sampling(panda):
    from ruckig import InputParameter, Ruckig, Synchronization
    from ruckig import Trajectory as RT

    rng = np.random.default_rng(8)
    q0, q1 = random_waypoints(panda, rng, k=2)
    v0 = rng.uniform(-0.3, 0.3, 7)
    traj = ruckig_state_to_state(panda, q0, q1, v0=v0, synchronization="time")
    inp = InputParameter(7)
    inp.current_position, inp.current_velocity, inp.target_position = q0, v0, q1
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = (panda.velocity_limits, panda.acceleration_limits,
                                                            panda.jerk_limits)
    inp.synchronization = Synchronization.Time
    out = RT(7)
    Ruckig(7).calculate(inp, out)
    assert traj.duration == pytest.approx(out.duration)
    for t in np.linspace(0, out.duration, 13):
        p, v, a = out.at_time(t)
        assert np.allclose(traj(t), p, atol=1e-9)
        assert np.allclose(traj(t, 1), v, atol=1e-9)
        assert np.allclose(traj(t, 2), a, atol=1e-8)


def test_ruckig_position_limits_are_checked(panda):
    """Community ruckig ignores position limits: braking past a limit must raise, not pass."""
    q0 = panda.home.copy()
    q0[0] = panda.upper[0] - 0.05
    q1 = q0.copy()
    q1[0] -= 0.01
    v0 = np.zeros(7)
    v0[0] = 2.0  # towards the upper limit, 5 cm away: braking needs more room
    with pytest.raises(InfeasibleTrajectory, match="panda_joint1"):
        ruckig_state_to_state(panda, q0, q1, v0=v0)
    # away from the limit it is fine
    v0[0] = -2.0
    traj = ruckig_state_to_state(panda, q0, q1, v0=v0)
    assert certify(traj, panda, quantities=("position",)).ok()


def test_ruckig_path_stops_at_waypoints_and_respects_jerk(panda):
    W = random_waypoints(panda, np.random.default_rng(9), k=4)
    traj = retime(W, panda, "ruckig")
    cert = traj.info["certificate"]
    assert cert.ok(("position", "velocity", "acceleration", "jerk"))
    assert traj.info["segments"] == 3
    # it stops at every waypoint: the velocity vanishes where the trajectory passes a waypoint
    t = np.linspace(0, traj.duration, 20001)
    Q, V = traj.derivatives(t, 1)
    for w in W:
        i = np.argmin(np.linalg.norm(Q - w, axis=1))
        assert np.linalg.norm(V[i]) < 1e-2


def _distance_to_path(Q, W):
    """``(N,)`` distance [rad] of each row of Q to the nearest segment of the path W, and the
    path parameter ``k + u`` of that nearest point."""
    best = np.full(len(Q), np.inf)
    where = np.zeros(len(Q))
    for k in range(len(W) - 1):
        d = W[k + 1] - W[k]
        u = np.clip((Q - W[k]) @ d / (d @ d), 0.0, 1.0)
        dist = np.linalg.norm(Q - (W[k] + u[:, None] * d), axis=1)
        closer = dist < best
        best[closer], where[closer] = dist[closer], k + u[closer]
    return best, where


@pytest.mark.parametrize("seed", [9, 11, 12])
def test_ruckig_path_follows_the_straight_segments_exactly(panda, seed):
    """Ruckig's phase synchronization can fall back to time synchronization, and
    segments left the straight line by up to 0.114 rad. The 1-D profile per segment cannot."""
    W = random_waypoints(panda, np.random.default_rng(seed), k=5)
    W[2, 3] = W[1, 3]  # a joint that does not move on a segment
    traj = retime(W, panda, "ruckig")
    assert traj.info["certificate"].ok(("position", "velocity", "acceleration", "jerk"))
    t = np.linspace(0.0, traj.duration, 20001)
    Q = traj.position(t)
    dist, progress = _distance_to_path(Q, W)
    assert dist.max() <= 1e-9
    assert np.all(np.diff(progress) >= -1e-9)  # never goes back along the path
    assert np.allclose(Q[0], W[0], atol=1e-12) and np.allclose(Q[-1], W[-1], atol=1e-9)


def test_ruckig_segment_is_time_optimal_along_the_line(panda):
    """On one segment the binding joint reaches its velocity (or acceleration) limit: the
    scaled 1-D limits are exactly the joints' limits along the line."""
    q_a = panda.home - 0.6
    q_b = panda.home + 0.6
    traj = retime(np.array([q_a, q_b]), panda, "ruckig")
    cert = traj.info["certificate"]
    assert max(cert.max_ratio(("velocity",)), cert.max_ratio(("acceleration",)),
               cert.max_ratio(("jerk",))) > 1 - 1e-6


def test_timing_from_gridpoints():
    ss = np.array([0.0, 0.5, 1.5, 2.0])
    sd = np.array([0.0, 1.0, 2.0, 0.0])
    timing = timing_from_gridpoints(ss, sd)
    assert isinstance(timing, PPoly)
    assert np.allclose(timing(timing.x), ss)
    assert np.allclose(timing(timing.x, nu=1), sd)
    with pytest.raises(InfeasibleTrajectory):
        timing_from_gridpoints(ss, np.array([0.0, 0.0, 1.0, 0.0]))


def test_limit_violation_names_joint_quantity_time(panda):
    W = random_waypoints(panda, np.random.default_rng(10), k=3)
    traj = retime(W, panda, "toppra", gridpoints=100)
    fast = traj.time_scaled(1.5)  # 1.5x faster: velocity x1.5, acceleration x2.25
    cert = certify(fast, panda)
    with pytest.raises(LimitViolation) as info:
        cert.check(("velocity", "acceleration"))
    err = info.value
    assert err.quantity in ("velocity", "acceleration") and err.joint in panda.joint_names
    assert 0.0 <= err.time <= fast.duration and err.ratio > 1.4
    assert err.joint in str(err) and err.quantity in str(err)


def test_top_level_exports():
    assert drake_mh.retime is retime and drake_mh.certify is certify
    assert drake_mh.Trajectory.__name__ == "Trajectory"
