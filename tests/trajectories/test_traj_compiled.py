"""The compiled core's trajectory evaluation and certification sampling against the numpy paths.

``Trajectory.derivatives`` and :func:`certify`'s sampling and refinement run in the compiled
core where it is built (``timed_derivatives``, ``certify_samples``); the reference is the same
trajectory evaluated by scipy's ``PPoly`` and refined in numpy (the core hidden from the
trajectory module only, so both use the same inverse dynamics, itself tested against Drake).
"""

import numpy as np
import pytest

from drake_mh._support.native import compiled_core
from drake_mh.trajectories import certify, retime
from drake_mh.trajectories import trajectory as trajectory_module
from drake_mh.trajectories.trajectory import Trajectory

pytestmark = pytest.mark.skipif(compiled_core() is None, reason="the compiled core is not built")


@pytest.fixture(scope="module")
def trajectories(panda):
    rng = np.random.default_rng(7)
    out = []
    for method in ("toppra", "ruckig", "drake-toppra"):
        for k in range(2):
            W = rng.uniform(0.6 * panda.lower, 0.6 * panda.upper, (3 + k, panda.nq))
            out.append(retime(W, panda, method))
    return out


def _reference(traj, monkeypatch) -> Trajectory:
    """The same trajectory evaluated without the core (a fresh object: nothing cached)."""
    monkeypatch.setattr(trajectory_module, "compiled_core", lambda: None)
    ref = Trajectory(traj.path, traj.timing, traj.joint_names, traj.method, dict(traj.info))
    ref.derivatives([traj.start_time], 0)
    monkeypatch.undo()
    return ref


def test_derivatives_equal_scipy(trajectories, monkeypatch):
    for traj in trajectories:
        ref = _reference(traj, monkeypatch)
        assert traj._compiled is not None and ref._compiled is None
        t = np.r_[np.linspace(traj.start_time, traj.end_time, 997), traj.breaks]
        for fast, slow in zip(traj.derivatives(t, 3), ref.derivatives(t, 3)):
            assert fast.shape == slow.shape
            np.testing.assert_allclose(fast, slow, rtol=1e-11, atol=1e-11 * np.max(np.abs(slow)))


def test_certificate_equals_numpy_path(trajectories, panda, monkeypatch):
    for traj in trajectories:
        ref = _reference(traj, monkeypatch)
        fast, slow = certify(traj, panda), certify(ref, panda)
        assert fast.samples == slow.samples
        for q in slow.ratios:
            finite = np.isfinite(slow.ratios[q])
            assert np.array_equal(finite, np.isfinite(fast.ratios[q])), q
            np.testing.assert_allclose(fast.ratios[q][finite], slow.ratios[q][finite], rtol=1e-9, err_msg=q)
        for q in slow.bounds:
            finite = np.isfinite(slow.bounds[q])
            np.testing.assert_allclose(fast.bounds[q][finite], slow.bounds[q][finite], rtol=1e-9, err_msg=q)
        np.testing.assert_allclose(fast.position_excess, slow.position_excess, atol=1e-12)


def test_refined_torque_reaches_dense_samples(trajectories, panda):
    """Torque is a refined sample, not a bound: the certificate's ratio must reach the largest
    ratio of a 40x denser sampling (up to the golden search's residual), and each is the torque
    at its reported time (taken one-sided there, as at a break where the acceleration jumps). ``scale=0.2`` puts the peaks
    above the refinement's threshold (0.9)."""
    from drake_mh.trajectories.dynamics import batch_dynamics

    for traj in trajectories:
        cert = certify(traj, panda, quantities=("torque",), scale=0.2)
        t = np.linspace(traj.start_time, traj.end_time, 40 * cert.samples + 1)
        D = traj.derivatives(t, 2)
        dense = np.max(np.abs(batch_dynamics(panda).inverse_dynamics(*D)) / (cert.scale * cert.limits["torque"]), axis=0)
        refined = dense >= 0.9
        assert np.any(refined)
        assert np.all(cert.ratios["torque"][refined] >= dense[refined] - 1e-7), cert.ratios["torque"] - dense
        eps = 1e-8 * traj.duration
        t_j = np.clip(np.r_[cert.times["torque"] - eps, cert.times["torque"] + eps], traj.start_time, traj.end_time)
        at = np.abs(batch_dynamics(panda).inverse_dynamics(*traj.derivatives(t_j, 2))) / (0.2 * cert.limits["torque"])
        seen = np.maximum(at[:panda.nq], at[panda.nq:])[np.arange(panda.nq), np.arange(panda.nq)]
        np.testing.assert_allclose(cert.ratios["torque"], seen, rtol=1e-5)
