"""Framing the Meshcat camera on a robot and its motion (reports, saved animations).

Meshcat's default camera looks from 3 m away, so a 0.5 m planar arm appears edge-on and tiny.
:func:`frame_points` collects what a view shows (geometry origins along the motion, the
end-effector path, obstacles, targets); :func:`camera_pose` puts the camera where it all fits:

* a **planar arm** (every joint axis parallel, e.g. ``planar5``, ``planar12``) is seen from above
  along that axis (tilted by about 10 degrees so that Meshcat's orbit controls stay usable);
* any other robot is seen obliquely from the front right and above.

The pose is set with ``Meshcat.SetCameraPose`` and ends up in ``Meshcat.StaticHtml()`` (a
``set_property`` of the camera position and a ``set_target``), so saved pages open framed.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FIELD_OF_VIEW_DEG", "joint_axis_normal", "frame_points", "camera_pose", "set_camera"]

FIELD_OF_VIEW_DEG = 75.0
"""Vertical field of view of Meshcat's default perspective camera [deg]."""

OBLIQUE_DIRECTION = np.array([1.0, -1.3, 0.75])
"""Direction from the target to the camera for non-planar robots (front right, above)."""

TOP_TILT = 0.18
"""Sideways component of the top view's direction (about 10 degrees off the axis)."""


def joint_axis_normal(robot, q=None, tol: float = 1e-6) -> np.ndarray | None:
    """The common axis ``n_W (3,)`` of a planar arm's joints, or ``None`` if the axes differ.

    Read from the angular rows of Drake's Jacobian at ``q`` (default ``robot.home``): a planar
    arm's columns are all parallel (prismatic joints, with zero columns, are skipped).

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        q: configuration ``(nq,)``.
        tol: largest cross product of unit axes still counted as parallel.

    Returns:
        Unit vector with a non-negative ``z`` (from above), or ``None``.
    """
    J = np.asarray(robot.jacobian(robot.home if q is None else q))[:3]
    norms = np.linalg.norm(J, axis=0)
    axes = J[:, norms > 1e-9] / norms[norms > 1e-9]
    if axes.shape[1] < 2:
        return None
    n = axes[:, 0]
    if np.max(np.linalg.norm(np.cross(n, axes.T), axis=1)) > tol:
        return None
    if n[2] < -tol or (abs(n[2]) <= tol and (n[1] > tol or (abs(n[1]) <= tol and n[0] < 0))):
        n = -n
    return n


def frame_points(geometry, Q, extra_points=None, max_frames: int = 60) -> np.ndarray:
    """Points ``(K, 3)`` [m] a view shows: every geometry origin at up to ``max_frames`` of ``Q``.

    Args:
        geometry: the :class:`drake_mh.viz.geometry.RobotGeometry` drawn.
        Q: configurations ``(N, nq)`` (a single one is fine).
        extra_points: further points ``(M, 3)`` (end-effector path, obstacles, targets).
        max_frames: configurations sampled evenly from ``Q``.
    """
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    rows = np.unique(np.linspace(0, len(Q) - 1, min(len(Q), max_frames)).round().astype(int))
    points = []
    for q in Q[rows]:
        for link, X_WB in geometry.link_poses(q).items():
            points.append(X_WB[:3, 3])
            for item in geometry.links[link]:
                points.append(X_WB[:3, :3] @ item.X_BG[:3, 3] + X_WB[:3, 3])
    if extra_points is not None and len(extra_points):
        points.extend(np.asarray(extra_points, dtype=float).reshape(-1, 3))
    return np.asarray(points, dtype=float)


def camera_pose(points_W, normal=None, margin: float = 1.2, min_radius: float = 0.15,
                aspect: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Camera position and target [m] so that every point fits the view.

    Args:
        points_W: ``(K, 3)`` points to show.
        normal: a planar arm's joint axis (see :func:`joint_axis_normal`): look along it
            from above; ``None``: oblique view (:data:`OBLIQUE_DIRECTION`).
        margin: extra room around the points (1.2 = 20 %), also for the links' thickness.
        min_radius: smallest framed radius [m] (a single point is not zoomed into).
        aspect: width / height of the viewer; the vertical field of view is the narrower
            one for ``aspect >= 1``.

    Returns:
        ``(p_WCamera (3,), p_WTarget (3,))``.
    """
    P = np.asarray(points_W, dtype=float).reshape(-1, 3)
    P = P[np.all(np.isfinite(P), axis=1)]
    if P.size == 0:
        P = np.zeros((1, 3))
    low, high = P.min(axis=0), P.max(axis=0)
    target = 0.5 * (low + high)
    if normal is not None:
        n = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
        side = np.cross([1.0, 0.0, 0.0], n)  # n = z: -y, so that +y is up and +x right on screen
        if np.linalg.norm(side) < 1e-6:
            side = np.cross(n, [0.0, 1.0, 0.0])
        side /= np.linalg.norm(side)
        in_plane = (P - target) - np.outer((P - target) @ n, n)
        radius = float(np.max(np.linalg.norm(in_plane, axis=1)))
        direction = n + TOP_TILT * side
    else:
        radius = float(np.max(np.linalg.norm(P - target, axis=1)))
        direction = OBLIQUE_DIRECTION
    direction = direction / np.linalg.norm(direction)
    radius = max(radius * margin, min_radius)
    half = np.radians(FIELD_OF_VIEW_DEG) / 2
    if aspect < 1:
        half = np.arctan(np.tan(half) * aspect)
    distance = radius / np.tan(half)  # the bounding circle fits the vertical field of view
    return target + distance * direction, target


def set_camera(meshcat, p_WC, p_WT) -> None:
    """Place Meshcat's default camera at ``p_WC`` looking at ``p_WT`` [m] (kept by StaticHtml)."""
    meshcat.SetCameraPose(np.asarray(p_WC, dtype=float), np.asarray(p_WT, dtype=float))
