"""Closed-form inverse kinematics of a planar 3-link component about a moving base.

Eqs. (7)-(12) of the cyclic paper (Machmudah et al.) give the 3-link planar IK for a tip
position and an orientation angle ``θg``; eq. (20) moves the base: the tip position is taken
relative to the end of the previous link, and eq. (19) turns the first (absolute) angle into
the relative joint angle of the arm (eq. (3) uses relative angles).

Readings chosen (each checked against the paper's Table IV, see ``docs/cyclic.md``):

* ``θg`` is the **absolute** orientation of the component's last link in the world
  (``θ_1s + θ_2s + θ_3s`` with ``θ_1s`` absolute), as REFERENCES.md's reproduction found;
  the paper's "total local joint angle" sentence would make it relative to the previous link.
  For the 12-DOF case both agree up to a constant (the previous ``θg`` is constant).
* Eq. (7) as printed subtracts ``l_1 (cos θg, sin θg)``; eqs. (13)-(15) use ``l_3``: the
  length of the **last** link is meant (the wrist point is the tip minus the last link).
* ``s_2 = ±sqrt(1 - c_2²)`` (eq. (8b)): ``root=+1`` gives ``θ_2s ∈ [0, π]`` (the only root
  compatible with eq. (27)'s ``0 ≤ θ ≤ π`` on the middle joint), ``root=-1`` gives ``[-π, 0]``.

All functions broadcast over leading dimensions (population × time), no Python loops.
"""

from __future__ import annotations

import numpy as np

__all__ = ["three_link_ik", "three_link_points", "reachable_orientation"]


def three_link_ik(p_BT, theta_g, lengths, root: int = 1):
    """Joint angles of a 3-link component whose tip is at ``p_BT`` with orientation ``theta_g``.

    Eqs. (7)-(12) with the moving base of eq. (20)::

        w = p_BT - l3 (cos θg, sin θg)                                  (7), (20)
        c2 = (|w|² - l1² - l2²) / (2 l1 l2),  s2 = root · sqrt(1 - c2²)   (8a), (8b)
        θ2s = atan2(s2, c2)                                             (9)
        s1 = ((l1 + l2 c2) w_y - l2 s2 w_x) / |w|²                       (10)
        c1 = ((l1 + l2 c2) w_x + l2 s2 w_y) / |w|²,  θ1s = atan2(s1, c1)  (11)
        θ3s = θg - θ2s - θ1s                                            (12)

    Args:
        p_BT: ``(..., 2)`` tip target relative to the component's base B, world axes [m].
        theta_g: ``(...)`` absolute orientation of the last link in the world [rad].
        lengths: ``(3,)`` link lengths l1, l2, l3 [m].
        root: ``+1`` or ``-1``, the sign of eq. (8b).

    Returns:
        ``(theta_1s, theta_2s, theta_3s, c2)``, each ``(...)``: ``theta_1s`` is the *absolute*
        angle of the first link [rad] (subtract the previous link's absolute orientation for
        the joint angle, eq. (19)); ``theta_2s``, ``theta_3s`` relative joint angles [rad];
        ``c2`` the unclipped cosine of eq. (8a): the target is reachable iff ``|c2| <= 1``
        (angles are computed with ``c2`` clipped to ``[-1, 1]``).
    """
    l1, l2, l3 = (float(v) for v in lengths)
    p_BT = np.asarray(p_BT, dtype=float)
    theta_g = np.asarray(theta_g, dtype=float)
    wx = p_BT[..., 0] - l3 * np.cos(theta_g)
    wy = p_BT[..., 1] - l3 * np.sin(theta_g)
    w2 = wx * wx + wy * wy
    c2 = (w2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    c2c = np.clip(c2, -1.0, 1.0)
    s2 = (1.0 if root >= 0 else -1.0) * np.sqrt(1.0 - c2c * c2c)
    theta_2s = np.arctan2(s2, c2c)
    a = l1 + l2 * c2c
    b = l2 * s2
    # eqs. (10)-(11); |w|² cancels inside atan2 (and w = 0 gives atan2(0, 0) = 0, not NaN)
    theta_1s = np.arctan2(a * wy - b * wx, a * wx + b * wy)
    theta_3s = theta_g - theta_2s - theta_1s
    return theta_1s, theta_2s, theta_3s, c2


def three_link_points(p_WB, theta_1s, theta_2s, theta_g, lengths):
    """World positions of the component's joints and tip, from its absolute angles.

    Args:
        p_WB: ``(..., 2)`` base positions [m]; theta_1s, theta_2s, theta_g: ``(...)`` [rad]
            (absolute first-link angle, relative middle angle, absolute last-link angle).
        lengths: ``(3,)`` [m].

    Returns:
        ``(..., 4, 2)``: base, elbow, wrist, tip [m] (eq. (3) applied to the component).
    """
    l1, l2, l3 = (float(v) for v in lengths)
    p_WB = np.asarray(p_WB, dtype=float)
    a1 = theta_1s
    a2 = theta_1s + theta_2s
    e1 = p_WB + l1 * np.stack([np.cos(a1), np.sin(a1)], -1)
    e2 = e1 + l2 * np.stack([np.cos(a2), np.sin(a2)], -1)
    tip = e2 + l3 * np.stack([np.cos(theta_g), np.sin(theta_g)], -1)
    return np.stack([np.broadcast_to(p_WB, e1.shape), e1, e2, tip], axis=-2)


def reachable_orientation(p_BT, lengths):
    """The reachable set of ``θg`` for each tip target: eqs. (13)-(15).

    Eq. (8a) written as ``c2 = A_p cos(θg - φ_p) + k_p`` with ``A_x = -l3 x/(l1 l2)``,
    ``A_y = -l3 y/(l1 l2)``, ``φ_p = atan2(A_y, A_x)``, ``k_p = (R² + l3² - l2² - l1²)/(2 l1 l2)``,
    ``R = |p_BT|``. ``|c2| <= 1`` holds on ``θg ∈ [φ_p + α, φ_p + 2π - α]`` minus the "hole"
    ``(φ_p + β, φ_p + 2π - β)`` where ``cos α = (1 - k_p)/A_p`` (wrist at the outer radius
    l1 + l2) and ``cos β = (-1 - k_p)/A_p`` (wrist at the inner radius |l1 - l2|).

    Args:
        p_BT: ``(N, 2)`` tip targets relative to the base [m] (e.g. one period of samples).
        lengths: ``(3,)`` [m].

    Returns:
        ``(theta_g_min, theta_g_max, hole_min, hole_max)``, each ``(N,)`` [rad]: the boundary of
        the paper's Fig. 3 (continuous in time: ``φ_p`` is unwrapped along the samples). Rows
        with no reachable ``θg`` (target beyond ``l1 + l2 + l3``) are NaN; ``hole_min/max`` are
        NaN where there is no hole (always when ``l1 = l2``).
    """
    l1, l2, l3 = (float(v) for v in lengths)
    p_BT = np.asarray(p_BT, dtype=float).reshape(-1, 2)
    R = np.hypot(p_BT[:, 0], p_BT[:, 1])
    A = l3 * R / (l1 * l2)
    phi = np.unwrap(np.arctan2(-p_BT[:, 1], -p_BT[:, 0]))
    kp = (R * R + l3 * l3 - l2 * l2 - l1 * l1) / (2 * l1 * l2)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # R -> 0: A -> 0, the ratios +-inf
        cos_alpha = (1.0 - kp) / A
        cos_beta = (-1.0 - kp) / A
    alpha = np.arccos(np.clip(cos_alpha, -1.0, 1.0))
    beta = np.arccos(np.clip(cos_beta, -1.0, 1.0))
    empty = (cos_alpha < -1.0) | (cos_beta > 1.0)
    lo = np.where(empty, np.nan, phi + alpha)
    hi = np.where(empty, np.nan, phi + 2 * np.pi - alpha)
    has_hole = (cos_beta > -1.0) & ~empty
    hole_lo = np.where(has_hole, phi + beta, np.nan)
    hole_hi = np.where(has_hole, phi + 2 * np.pi - beta, np.nan)
    return lo, hi, hole_lo, hole_hi
