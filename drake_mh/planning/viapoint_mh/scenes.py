"""Panda test scenes built from boxes (table, shelf, bins) and start/goal pairs checked by us.

Used by the tests and by ``studies/viapoint_mh.py`` to measure the ``mh_*`` planners. They
are modelled on MotionBenchMaker's "table pick", "bookshelf" and "box" sets (primitives only,
sizes ours), not copies of them:

* ``table``: a table top in front of the arm (its surface at z = 0, the arm's base height) and
  a 0.5 m high divider board on it between the left and the right half;
* ``shelf``: a bookshelf 0.58-0.98 m in front of the arm, two compartments (boards at
  z = 0.3, 0.64, 0.98 m, 2 cm thick), side walls at y = ±0.45 m, a back wall, on the floor
  (a flange pointing forward at x = 0.68 m reaches z ≈ 0.45-0.8 m only, so the lowest board
  is high and the targets sit at z = 0.5 and 0.8 m; an upper-left target was dropped: no IK
  answer clear of the boards);
* ``bins``: the table top and two open-top bins (0.42 × 0.42 m, 0.15 m high) at y = ±0.33 m;
  the flange goes from inside one (z = 0.1 m, pointing down) into the other.

Goal and start configurations come from collision-free IK (:func:`drake_mh.solve_ik`,
``hybrid``, seeds 0, 1, ...) of end-effector poses (flange pointing down over the table,
pointing forward into the shelf; a weak pull towards the home configuration keeps the elbow
up), kept when certified free with 1 cm of clearance under the sphere model. 14 of the 15
pairs have a blocked straight joint-space line (``shelf:front_low->upper_right`` does not).
"""

from __future__ import annotations

import numpy as np

SCENES = ("table", "shelf", "bins")

DOWN = np.diag([1.0, -1.0, -1.0])
"""``R_WE`` of a flange pointing down (z_E = -z_W)."""

FORWARD = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
"""``R_WE`` of a flange pointing forward (z_E = +x_W)."""

#: named end-effector targets per scene: position [m] and orientation
TARGETS = {
    "table": {
        "left_low": ((0.45, 0.35, 0.25), DOWN), "right_low": ((0.45, -0.35, 0.25), DOWN),
        "left_far": ((0.65, 0.3, 0.3), DOWN), "right_far": ((0.65, -0.3, 0.3), DOWN),
        "left_near": ((0.35, 0.45, 0.35), DOWN), "right_near": ((0.35, -0.45, 0.35), DOWN),
    },
    "bins": {
        "bin_left": ((0.5, 0.33, 0.1), DOWN), "bin_right": ((0.5, -0.33, 0.1), DOWN),
        "bin_left_far": ((0.58, 0.3, 0.1), DOWN), "bin_right_near": ((0.42, -0.3, 0.1), DOWN),
    },
    "shelf": {
        "lower_left": ((0.68, 0.2, 0.5), FORWARD), "lower_right": ((0.68, -0.2, 0.5), FORWARD),
        "upper_right": ((0.68, -0.2, 0.8), FORWARD),
        "front_low": ((0.4, 0.0, 0.5), FORWARD), "front_high": ((0.4, 0.0, 0.8), FORWARD),
    },
}

#: start -> goal pairs per scene
PAIRS = {
    "table": [("left_low", "right_low"), ("left_far", "right_far"), ("left_near", "right_near"),
              ("right_low", "left_far"), ("left_low", "right_near")],
    "bins": [("bin_left", "bin_right"), ("bin_left_far", "bin_right_near"), ("bin_right", "bin_left_far"),
             ("bin_right_near", "bin_left")],
    "shelf": [("lower_left", "upper_right"), ("lower_right", "upper_right"), ("front_low", "upper_right"),
              ("front_high", "lower_left"), ("front_high", "lower_right"), ("upper_right", "lower_left")],
}


def build_scene(robot, kind: str):
    """The :class:`drake_mh.scene.Scene` ``kind`` (one of :data:`SCENES`) for ``robot``."""
    from drake_mh.errors import InvalidArgument
    from drake_mh.scene import Box, Scene

    scene = Scene(robot)
    if kind == "table":
        scene.add("table_top", Box((0.8, 1.4, 0.04)), [0.65, 0.0, -0.02])
        scene.add("divider", Box((0.5, 0.03, 0.5)), [0.6, 0.0, 0.25])
    elif kind == "shelf":
        x, depth, width = 0.78, 0.4, 0.9
        for i, z in enumerate((0.3, 0.64, 0.98)):
            scene.add(f"board{i}", Box((depth, width, 0.02)), [x, 0.0, z])
        for side in (-1, 1):
            scene.add(f"wall{'lr'[side > 0]}", Box((depth, 0.02, 0.99)), [x, side * (width / 2 + 0.01), 0.495])
        scene.add("back", Box((0.02, width, 0.99)), [x + depth / 2 + 0.01, 0.0, 0.495])
    elif kind == "bins":
        scene.add("table_top", Box((0.8, 1.4, 0.04)), [0.65, 0.0, -0.02])
        h, w = 0.15, 0.42  # open-top bins w x w x h, centred at (0.5, ±0.33)
        for side, y in (("left", 0.33), ("right", -0.33)):
            for name, centre, size in (("near", (0.5 - w / 2, y, h / 2), (0.02, w, h)),
                                       ("far", (0.5 + w / 2, y, h / 2), (0.02, w, h)),
                                       ("in", (0.5, y - np.sign(y) * w / 2, h / 2), (w, 0.02, h)),
                                       ("out", (0.5, y + np.sign(y) * w / 2, h / 2), (w, 0.02, h))):
                scene.add(f"bin_{side}_{name}", Box(size), list(centre))
    else:
        raise InvalidArgument(f"scene kind must be one of {SCENES}, got {kind!r}")
    return scene


def target_configuration(robot, scene, position, R_WE, clearance: float = 0.01, tries: int = 4,
                         timeout: float = 1.0) -> np.ndarray | None:
    """A collision-free IK answer of the pose, or ``None``: the first of seeds 0, 1, ... of IK
    without obstacles (pulled weakly towards home), then of IK with the scene, that is
    certified free with ``clearance`` under the sphere model."""
    from drake_mh.ik import IKProblem, solve_ik

    X = np.eye(4)
    X[:3, :3], X[:3, 3] = R_WE, position
    for with_scene in (False, True):  # the obstacle-free answer near home first: the natural posture
        ik = IKProblem(robot, X, scene=scene if with_scene else None, clearance=clearance, q_ref=robot.home,
                       ref_weight=0.05)
        for seed in range(tries):
            answer = solve_ik(ik, "hybrid", seed=seed, timeout=timeout)
            if answer.success and scene.collision_free(answer.q, clearance):
                return answer.q
    return None


def problems(robot, kind: str, clearance: float = 0.0) -> list:
    """The :class:`~drake_mh.planning.MotionProblem` of every pair of ``kind`` whose start and
    goal have an IK answer (named ``"<kind>:<start>-><goal>"``)."""
    from drake_mh.planning import MotionProblem

    scene = build_scene(robot, kind)
    q = {name: target_configuration(robot, scene, p, R) for name, (p, R) in TARGETS[kind].items()}
    out = []
    for a, b in PAIRS[kind]:
        if q[a] is not None and q[b] is not None:
            out.append(MotionProblem(robot, scene, q[a], q[b], clearance=clearance, name=f"{kind}:{a}->{b}"))
    return out
