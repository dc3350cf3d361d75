"""Helpers of the trajectory tests (fixtures are in conftest.py)."""

from __future__ import annotations

import numpy as np


def random_waypoints(robot, rng, k: int = 7, spread: float = 0.8) -> np.ndarray:
    """``(k, nq)`` waypoints uniform in the central ``spread`` fraction of the joint ranges."""
    mid = 0.5 * (robot.lower + robot.upper)
    half = 0.5 * (robot.upper - robot.lower)
    return mid + rng.uniform(-spread, spread, size=(k, robot.nq)) * half


def sampled_ratios(traj, robot, quantities, *, samples: int = 3000, seed: int = 0) -> dict:
    """Largest ratio to the robot's limit of each quantity, found by sampling the trajectory's
    *positions* only, independently of its derivatives and its certificate.

    Velocity, acceleration and jerk are central differences of positions at ``samples`` random
    times (each an average of the derivative over a few microseconds or milliseconds, so never
    above its peak: a ratio above 1 is a real excess); torque is Drake's inverse dynamics with
    gravity on a fresh plant (``M a + C v - τ_g``) at those times, with the differenced velocity
    and acceleration (an average too, up to the change of ``M(q)`` within microseconds).
    ``position`` is the largest excess over the joint range [rad] (0 inside it).
    """
    from references import FreshDrake, finite_differences

    rng = np.random.default_rng(seed)
    T = traj.duration
    h, h_jerk = 1e-5, 1e-3  # round-off: about 3e-5 rad/s^2 and 5e-6 rad/s^3 at these steps
    t = np.sort(np.r_[rng.uniform(2 * h_jerk, T - 2 * h_jerk, samples), 2 * h_jerk, T - 2 * h_jerk])
    position = traj.position
    Q = position(np.r_[0.0, t, T])
    out = {"position": float(max(np.max(Q - robot.upper), np.max(robot.lower - Q), 0.0))}
    V = finite_differences(position, t, h, 1)
    A = finite_differences(position, t, h, 2)
    limits = {"velocity": (V, robot.velocity_limits), "acceleration": (A, robot.acceleration_limits)}
    if "jerk" in quantities:
        limits["jerk"] = (finite_differences(position, t, h_jerk, 3), robot.jerk_limits)
    for quantity, (values, limit) in limits.items():
        out[quantity] = float(np.max(np.abs(values) / limit))
    if "torque" in quantities:
        drake = FreshDrake(robot)
        tau = np.array([drake.inverse_dynamics(q, v, a) for q, v, a in zip(position(t), V, A)])
        out["torque"] = float(np.max(np.abs(tau) / robot.effort_limits))
    return out
