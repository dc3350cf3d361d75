"""Shared fixtures of the trajectory tests."""

from __future__ import annotations

import numpy as np
import pytest

import drake_mh


@pytest.fixture(scope="session")
def panda():
    return drake_mh.load_robot("panda")


@pytest.fixture(scope="session")
def planar2r():
    return drake_mh.load_robot("planar2r")


def random_waypoints(robot, rng, k: int = 7, spread: float = 0.8) -> np.ndarray:
    """``(k, nq)`` waypoints uniform in the central ``spread`` fraction of the joint ranges."""
    mid = 0.5 * (robot.lower + robot.upper)
    half = 0.5 * (robot.upper - robot.lower)
    return mid + rng.uniform(-spread, spread, size=(k, robot.nq)) * half
