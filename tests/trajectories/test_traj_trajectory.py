"""Trajectory evaluation: only within its time span (no silent extrapolation)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from drake_mh.errors import InvalidArgument
from drake_mh.trajectories import Trajectory


def _line():
    return Trajectory(CubicSpline([0.0, 1.0, 2.0], np.c_[[0.0, 1.0, 4.0], [0.0, -1.0, 0.0]]))


def test_evaluation_past_the_end_is_refused():
    traj = _line()
    with pytest.raises(InvalidArgument, match="within the trajectory"):
        traj.position(5.0)
    with pytest.raises(InvalidArgument, match="within the trajectory"):
        traj.velocity([-0.5, 1.0])
    with pytest.raises(InvalidArgument, match="finite"):
        traj.position(np.nan)


def test_round_off_at_the_ends_is_clipped():
    traj = _line()
    np.testing.assert_allclose(traj.position(2.0 + 1e-12), traj.position(2.0), atol=0)
    np.testing.assert_allclose(traj.position(-1e-12), [0.0, 0.0], atol=1e-12)
