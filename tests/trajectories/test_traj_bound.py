"""kinematic_bound: an upper bound of each joint's ratio over every piece (checked against dense
sampling of the trajectory's own derivatives), the same from the compiled core and from the numba
kernel."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline, PPoly

from drake_mh._support.native import ENVIRONMENT, compiled_core
from drake_mh.trajectories import Trajectory
from drake_mh.trajectories.bound import kinematic_bound


def _trajectory(seed: int) -> Trajectory:
    """A cubic spline through random waypoints, timed by a random increasing quadratic time law
    (degree 6 per piece, as toppra's)."""
    rng = np.random.default_rng(seed)
    path = CubicSpline(np.linspace(0.0, 1.0, 6), rng.uniform(-2.0, 2.0, (6, 3)), bc_type="clamped")
    x = np.linspace(0.0, 2.0, 5)  # t -> s, speeds > 0 at every break, s(2) = 1
    speeds = rng.uniform(0.2, 0.8, 5)
    c = np.zeros((3, 4))
    c[1], c[0] = speeds[:-1], (speeds[1:] - speeds[:-1]) / (2 * np.diff(x))
    c[2] = np.r_[0.0, np.cumsum(c[0] * np.diff(x) ** 2 + c[1] * np.diff(x))[:-1]]
    total = np.sum(c[0] * np.diff(x) ** 2 + c[1] * np.diff(x))
    timing = PPoly(c / total, x)
    return Trajectory(PPoly(path.c, path.x), timing)


@pytest.mark.parametrize("backend", ["core", "numba"])
@pytest.mark.parametrize("order", [0, 1, 2, 3])
def test_bound_holds_dense_samples_and_is_tight(monkeypatch, backend, order):
    if backend == "numba":
        monkeypatch.setenv(ENVIRONMENT, "0")
    elif compiled_core() is None:
        pytest.skip("the compiled core drake_mh._native is not built (pip install . builds it)")
    for seed in range(3):
        traj = _trajectory(seed)
        breaks = traj.breaks
        half = np.array([1.0, 2.0, 0.5])
        bound = kinematic_bound(traj, order, (np.zeros(3), half), breaks[:-1], breaks[1:], np.zeros(3))
        t = np.linspace(traj.start_time, traj.end_time, 20001)
        sampled = np.max(np.abs(traj.derivatives(t, order)[order]) / half, axis=0)
        assert np.all(bound >= sampled - 1e-9)
        assert np.all(bound <= sampled * (1 + 1e-3) + 1e-6)  # halved down to the slack


def test_core_and_numba_bounds_agree(monkeypatch):
    if compiled_core() is None:
        pytest.skip("the compiled core drake_mh._native is not built (pip install . builds it)")
    traj = _trajectory(7)
    breaks = traj.breaks
    ratio = (np.array([0.1, -0.2, 0.0]), np.array([1.0, np.inf, 0.5]))  # a joint without a limit: ratio 0
    for order in range(4):
        core = kinematic_bound(traj, order, ratio, breaks[:-1], breaks[1:], np.zeros(3), max_levels=4)
        monkeypatch.setenv(ENVIRONMENT, "0")
        numba = kinematic_bound(traj, order, ratio, breaks[:-1], breaks[1:], np.zeros(3), max_levels=4)
        monkeypatch.delenv(ENVIRONMENT)
        np.testing.assert_allclose(core, numba, rtol=1e-12, atol=1e-12)
        assert core[1] == 0.0
