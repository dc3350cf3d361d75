"""Live Meshcat visualisation and exported animations (import explicitly: ``import drake_mh.viz``).

::

    import drake_mh, drake_mh.viz
    robot = drake_mh.load_robot("panda")
    view = drake_mh.viz.show(robot, q_or_traj, scene=scene)   # prints/returns view.url
    html = view.html()                                           # self-contained page

Meshcat runs as a websocket server on ``localhost`` (first free port from 7000), one per
process (strictly: per thread that uses it, a Drake requirement). Nothing here is imported by
``import drake_mh``, and pydrake's Meshcat is only imported when something is drawn.

Names:
    :func:`show`, :func:`animation_html`, :func:`save_animation` — two-line entry points.
    :func:`show_motion`, :func:`motion_html`, :func:`motion_caption` — a verified planned motion
    (:class:`drake_mh.planning.MotionResult`) animated with its certified clearance.
    :class:`View` — a robot in Meshcat with obstacles, paths, targets, ghosts, closest-point
    lines, animations and HTML export.
    :func:`get_meshcat`, :func:`meshcat_url`, :func:`close_meshcat` — the shared server.
    :class:`RobotGeometry` — a robot's SceneGraph geometry drawn at any configuration.
"""

from __future__ import annotations

from drake_mh.viz.geometry import RobotGeometry
from drake_mh.viz.inputs import Motion, as_motion
from drake_mh.viz.motion import motion_caption, motion_html, show_motion
from drake_mh.viz.server import close_meshcat, get_meshcat, meshcat_url
from drake_mh.viz.show import animation_html, save_animation, show
from drake_mh.viz.view import COLOURS, View

__all__ = [
    "show", "animation_html", "save_animation", "show_motion", "motion_html", "motion_caption", "View", "COLOURS",
    "RobotGeometry",
    "get_meshcat", "meshcat_url", "close_meshcat", "Motion", "as_motion",
]
