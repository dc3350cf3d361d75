"""The toppra set-up behind ``retime(method="toppra")``: its gridpoints against toppra's own."""

import numpy as np
import pytest
import toppra

import drake_mh
from drake_mh.trajectories.paths import joint_path
from drake_mh.trajectories.toppra_solve import _ToppraPath
from drake_mh.trajectories.toppra_time import propose_gridpoints

PANDA = drake_mh.load_robot("panda")


@pytest.mark.parametrize("seed", range(6))
def test_gridpoints_are_toppras_own(seed):
    rng = np.random.default_rng(seed)
    mid, half = 0.5 * (PANDA.lower + PANDA.upper), 0.5 * (PANDA.upper - PANDA.lower)
    W = mid + rng.uniform(-0.8, 0.8, (int(rng.integers(2, 12)), PANDA.nq)) * half * rng.uniform(0.05, 1.0)
    spline, _ = joint_path(W, PANDA, "toppra", bc_type="not-a-knot")
    for threshold, least in ((1e-3, 100), (1e-4, 10), (1e-2, 2)):
        reference = np.asarray(toppra.interpolator.propose_gridpoints(
            _ToppraPath(spline), max_err_threshold=threshold, min_nb_points=least))
        ours = propose_gridpoints(spline, max_err_threshold=threshold, min_nb_points=least)
        assert ours.shape == reference.shape
        np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-12)


def test_gridpoints_that_never_settle_raise_as_toppras():
    spline, _ = joint_path(np.array([PANDA.home, PANDA.home + 0.5]), PANDA, "toppra", bc_type="not-a-knot")
    with pytest.raises(ValueError, match="gridpoint"):
        propose_gridpoints(spline, max_err_threshold=1e-300, max_iteration=3)
    with pytest.raises(ValueError, match="gridpoint"):
        toppra.interpolator.propose_gridpoints(_ToppraPath(spline), max_err_threshold=1e-300, max_iteration=3)
