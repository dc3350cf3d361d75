"""Helpers of the trajectory tests (fixtures are in conftest.py)."""

from __future__ import annotations

import numpy as np


def random_waypoints(robot, rng, k: int = 7, spread: float = 0.8) -> np.ndarray:
    """``(k, nq)`` waypoints uniform in the central ``spread`` fraction of the joint ranges."""
    mid = 0.5 * (robot.lower + robot.upper)
    half = 0.5 * (robot.upper - robot.lower)
    return mid + rng.uniform(-spread, spread, size=(k, robot.nq)) * half
