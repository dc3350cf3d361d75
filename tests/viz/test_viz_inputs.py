"""Interpretation of what users pass to show(): configurations vs trajectories; resampling."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.errors import InvalidTrajectory
from drake_mh.viz.inputs import as_motion, resample


def test_a_pair_of_numbers_is_a_configuration_of_a_2_joint_robot(planar2r):
    motion = as_motion(planar2r, (0.3, -0.2))
    assert not motion.is_trajectory
    np.testing.assert_allclose(motion.q, [0.3, -0.2])
    motion = as_motion(planar2r, ([0.0, 1.0], [[0.0, 0.0], [0.3, -0.2]]))
    assert motion.is_trajectory and motion.Q.shape == (2, 2)


def test_single_sample_trajectory(planar2r):
    motion = as_motion(planar2r, ([0.5], [[0.1, 0.2]]))
    times, Q = resample(motion.t, motion.Q, fps=30)
    np.testing.assert_allclose(times, [0.0])
    np.testing.assert_allclose(Q, [[0.1, 0.2]])


def test_resample_ends_on_the_last_sample():
    t = np.array([1.0, 1.25, 2.05])
    Q = np.array([[0.0], [1.0], [3.0]])
    times, Q_frames = resample(t, Q, fps=4)
    np.testing.assert_allclose(times, [0.0, 0.25, 0.5, 0.75, 1.0, 1.05])
    np.testing.assert_allclose(Q_frames[:, 0], np.interp(times + 1.0, t, Q[:, 0]))


def test_drake_trajectory_of_the_wrong_size(planar2r):
    from pydrake.trajectories import PiecewisePolynomial

    traj = PiecewisePolynomial.FirstOrderHold([0.0, 1.0], np.zeros((3, 2)))
    with pytest.raises(InvalidTrajectory, match=r"\(3, 1\).*\(2, 1\)"):
        as_motion(planar2r, traj)


class _PositionTrajectory:
    """Duck type of drake_mh.trajectories.Trajectory: time span properties and position(t)."""

    def __init__(self, nq, duration=1.0, shape=None):
        self.start_time, self.end_time, self._nq, self._shape = 0.0, duration, nq, shape

    def position(self, t):
        t = np.atleast_1d(t)
        out = 0.1 * t[:, None] * np.ones((1, self._nq))
        return out if self._shape is None else np.zeros(self._shape)


def test_position_function_trajectories_are_sampled(planar2r):
    motion = as_motion(planar2r, _PositionTrajectory(2, duration=1.0), sample_rate=10)
    np.testing.assert_allclose(motion.t, np.linspace(0, 1, 11))
    np.testing.assert_allclose(motion.Q[-1], [0.1, 0.1])
    with pytest.raises(InvalidTrajectory, match=r"gave shape \(3, 3\)"):
        as_motion(planar2r, _PositionTrajectory(2, shape=(3, 3)))


def test_drake_mh_trajectory_is_shown(planar2r):
    from scipy.interpolate import CubicSpline

    from drake_mh import trajectories

    spline = CubicSpline([0.0, 2.0], [[0.0, 0.0], [0.5, -0.5]], bc_type="clamped")  # a PPoly of time
    traj = trajectories.Trajectory(spline)
    motion = as_motion(planar2r, traj, sample_rate=5)
    assert motion.t[0] == 0.0 and motion.t[-1] == 2.0 and motion.Q.shape == (11, 2)
    np.testing.assert_allclose(motion.Q[-1], [0.5, -0.5], atol=1e-12)
