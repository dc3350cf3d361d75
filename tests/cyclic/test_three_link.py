"""Closed-form 3-link IK (eqs. (7)-(12), (19)-(20)) against Drake's forward kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_mh.cyclic.three_link import reachable_orientation, three_link_ik

L = np.array([0.30, 0.30, 0.30])


def _link_frame_W(robot, q, frame):
    """(x, y, absolute orientation) of a link frame computed by Drake (Robot.fk)."""
    X = robot.fk(q, frame=frame)
    return X[0, 3], X[1, 3], np.arctan2(X[1, 0], X[0, 0])


@pytest.mark.parametrize("root", [1, -1])
def test_fixed_base_ik_matches_drake_fk(planar12, root):
    rng = np.random.default_rng(0)
    targets = rng.uniform(-0.8, 0.8, (40, 2))
    theta_g = rng.uniform(-np.pi, np.pi, 40)
    t1, t2, t3, c2 = three_link_ik(targets, theta_g, L, root)
    ok = np.abs(c2) <= 1
    assert ok.sum() > 10
    assert np.all(np.sign(t2[ok]) * root >= 0)  # root +1: θ2 in [0, π]; -1: [-π, 0]
    for i in np.flatnonzero(ok):
        q = np.zeros(12)
        q[:3] = t1[i], t2[i], t3[i]
        x, y, phi = _link_frame_W(planar12, q, "link4")  # link 4's frame sits at the tip of link 3
        assert abs(x - targets[i, 0]) < 1e-12 and abs(y - targets[i, 1]) < 1e-12
        assert abs(np.angle(np.exp(1j * (phi - theta_g[i])))) < 1e-12


@pytest.mark.parametrize("root", [1, -1])
def test_moving_base_ik_matches_drake_fk(planar12, root):
    """Component 2 (joints 4-6) about the tip of component 1, eq. (19): θ4 = θ1s - Σ previous."""
    rng = np.random.default_rng(1)
    checked = 0
    for _ in range(30):
        q = np.zeros(12)
        q[:3] = rng.uniform(-2, 2, 3)
        bx, by, phi_prev = _link_frame_W(planar12, q, "link4")
        target = np.array([bx, by]) + rng.uniform(-0.8, 0.8, 2)
        theta_g = rng.uniform(-np.pi, np.pi)
        t1s, t2s, t3s, c2 = three_link_ik(target - [bx, by], theta_g, L, root)
        if abs(c2) > 1:
            continue
        q[3:6] = t1s - phi_prev, t2s, t3s
        x, y, phi = _link_frame_W(planar12, q, "link7")
        assert np.hypot(x - target[0], y - target[1]) < 1e-12
        assert abs(np.angle(np.exp(1j * (phi - theta_g)))) < 1e-12
        # the batched kernel (compiled from the plant) agrees
        _, p = planar12.batch.moving_frames(q[None])
        assert np.allclose(p[0, 6, :2], target, atol=1e-12)
        checked += 1
    assert checked > 5


@settings(max_examples=60, deadline=None)
@given(st.floats(-0.9, 0.9), st.floats(-0.9, 0.9), st.floats(-np.pi, np.pi),
       st.lists(st.floats(0.05, 0.4), min_size=3, max_size=3))
def test_reachable_band_equals_eq8_condition(x, y, theta_g, lengths):
    """θg inside eqs. (13)-(15)'s band (minus the hole) <=> |c2| <= 1 of eq. (8a)."""
    p = np.array([[x, y]])
    lo, hi, hlo, hhi = reachable_orientation(p, lengths)
    c2 = three_link_ik(p, np.array([theta_g]), lengths)[3][0]
    if abs(abs(c2) - 1) < 1e-9:
        return  # on the boundary
    if np.isnan(lo[0]):
        assert abs(c2) > 1
        return
    g = lo[0] + np.mod(theta_g - lo[0], 2 * np.pi)  # θg moved into [lo, lo + 2π)
    inside = g <= hi[0] and not (not np.isnan(hlo[0]) and hlo[0] < g < hhi[0])
    assert inside == (abs(c2) <= 1)
