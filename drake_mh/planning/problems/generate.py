"""Start/goal pairs in the fixtures of :mod:`.fixtures`, generated and checked by us.

For problem ``i`` of a set and a ``seed``, :func:`generate_problem` draws a fixture from
``numpy.random.default_rng([seed, set code, i])`` (so problem ``i`` does not depend on how many
problems are asked for), then

* the **goal** is a pre-grasp of one of the fixture's objects: the gripper's grasp point
  (:func:`tool_transform`) ``standoff`` short of the object along one of the site's approach
  directions, fingers across the approach and horizontal where that makes sense; its
  configuration comes from collision-free IK (:func:`drake_mh.solve_ik`, ``hybrid`` with a
  fixed evaluation budget and no timeout, so the answer depends on the seed only), verified with
  Drake's exact distances, then certified free under the sphere model
  (:meth:`drake_mh.scene.Scene.collision_free`) with the problem's clearances;
* the **start** is the robot's ready configuration (:func:`ready_configuration`, as in
  MotionBenchMaker), except in ``table_under_pick``, where it is a collision-free IK answer
  with the hand under the table top;
* a draw whose start or goal cannot be certified free is discarded and the fixture drawn again
  (at most ``MAX_DRAWS`` times).

The straight joint-space line from start to goal is then certified or not
(:meth:`~drake_mh.scene.Scene.segment_free`): :func:`straight_line_blocked` reports how often
it is *not* certified free, which is what makes a set worth planning on.
"""

from __future__ import annotations

import numpy as np

from drake_mh.errors import InvalidArgument, InvalidMotionProblem
from drake_mh.planning.problems.fixtures import FIXTURES
from drake_mh.geometry.spheres import DEFAULT_TOLERANCE

MAX_DRAWS = 12
"""Fixtures drawn per problem before giving up (a draw fails when no grasp is reachable)."""
IK_BUDGET = 10_000
"""Configurations evaluated per IK attempt (``hybrid``): a budget, not a timeout, for determinism."""
IK_CLEARANCE_MARGIN = 0.005
"""[m] extra clearance asked of IK, so that its answers also pass the sphere model's check."""
STANDOFF = 0.03
"""[m] from the grasp point to the object's surface (a pre-grasp: the fingers clear the object)."""
MARGIN = 0.003
"""[m] start and goal are certified free with this much more than the problem's clearances: the
verification certifies a retimed trajectory's samples with a little more than the clearance, for
the motion between them (:data:`drake_mh.planning.verify.TRAJECTORY_SHIFT`, 1 mm, refined where
needed), so a start or goal with nothing to spare could not be left or reached by a verified
motion; the sphere model's certificate is also what every planner checks against."""
#: a configuration with the arm raised in front of the base, by the robot's joint names
READY = {
    ("panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4", "panda_joint5", "panda_joint6",
     "panda_joint7"): (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785),  # MotionBenchMaker's start
    ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
     "wrist_3_joint"): (0.0, -1.571, 1.571, -1.571, -1.571, 0.0),  # UR: tool down, 0.49 m in front
}

PANDA_HAND_TCP = 0.1034
"""[m] from the Panda's flange (``panda_link8``) to the point between its fingertips."""


def _translation(z: float) -> np.ndarray:
    X = np.eye(4)
    X[2, 3] = z
    return X


def tool_transform(robot, frame: str | None = None) -> np.ndarray:
    """``X_ET (4, 4)``: the grasp point T in the end-effector frame E.

    * ``panda_link8`` (the bundled capsule Panda has no hand): the Franka hand's TCP, 10.34 cm
      along the flange's z, the hand turned -45° about it as mounted;
    * ``panda_hand_tcp`` (example-robot-data's Panda with its hand): the frame itself;
    * any other frame: 10 cm along its z axis (an unmodelled 10 cm tool, so that the arm stays
      where it would be with a gripper).
    """
    frame = frame or robot.ee_frame_name
    if frame == "panda_hand_tcp":
        return np.eye(4)
    if frame == "panda_link8":
        c = s = np.sqrt(0.5)
        X = np.eye(4)
        X[:2, :2] = [[c, s], [-s, c]]  # RotZ(-π/4)
        return X @ _translation(PANDA_HAND_TCP)
    return _translation(0.10)


def ready_configuration(robot) -> np.ndarray:
    """The robot's ready configuration (:data:`READY` by joint names), else mid-range."""
    q = READY.get(tuple(robot.joint_names))
    if q is None:
        return robot.home.copy()
    return np.clip(np.asarray(q, float), robot.lower, robot.upper)


def grasp_pose(p_W, approach, flip: bool = False, yaw: float = 0.0) -> np.ndarray:
    """``X_WT``: grasp point at ``p_W``, its z along ``approach``, its y (the fingers' closing
    axis) horizontal — for a vertical approach, at ``yaw`` about the vertical; ``flip`` turns it
    by π about the approach (the same grasp for a parallel gripper)."""
    z = np.asarray(approach, float) / np.linalg.norm(approach)
    up = np.array([0.0, 0.0, 1.0])
    y = np.cross(z, up)
    if np.linalg.norm(y) < 1e-6:  # vertical approach
        y = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
        y -= z * (y @ z)
    y /= np.linalg.norm(y)
    if flip:
        y = -y
    X = np.eye(4)
    X[:3, 0], X[:3, 1], X[:3, 2], X[:3, 3] = np.cross(y, z), y, z, p_W
    return X


def _ik(robot, scene, X_WT, X_ET, clearance, seed, q_ref) -> np.ndarray | None:
    from drake_mh.ik import IKProblem, solve_ik

    X_WE = X_WT @ np.linalg.inv(X_ET)
    # q_ref: the first IK start (no weight in the objective), so that the answer tends to lie on
    # the branch of the configuration the motion leaves from (a UR5's ±2π joints otherwise give
    # goals several turns away)
    ik = IKProblem(robot, X_WE, scene=scene, clearance=clearance + IK_CLEARANCE_MARGIN, q_ref=q_ref)
    answer = solve_ik(ik, "hybrid", seed=int(seed), budget=IK_BUDGET, timeout=None)
    return answer.q if answer.success else None


_WORKSPACE: dict = {}


def _within_reach(robot, X_ET, p_W) -> bool:
    """Whether the grasp point can be near ``p_W`` at all: within 10 cm of one of 20,000 grasp
    points of random configurations (skips IK on targets out of reach)."""
    key = (id(robot), X_ET.tobytes())
    cloud = _WORKSPACE.get(key)
    if cloud is None:
        Q = robot.random_configurations(20_000, np.random.default_rng(0))
        X = robot.batch.fk(Q)
        cloud = _WORKSPACE[key] = X[:, :3, :3] @ X_ET[:3, 3] + X[:, :3, 3]
    return bool(np.min(np.sum((cloud - p_W) ** 2, axis=1)) < 0.1 ** 2)


def unwrap(robot, q: np.ndarray, q_ref: np.ndarray) -> np.ndarray:
    """``q`` with each revolute joint turned by whole turns (the same robot geometry) to lie as
    close to ``q_ref`` as its limits allow (a UR5's ±2π joints give IK answers turns away)."""
    q = np.array(q, dtype=float)
    turns = np.round((q_ref - q) / (2 * np.pi))
    revolute = [joint.type_name() == "revolute" for joint in robot._joints]
    for j in np.flatnonzero(turns):
        if not revolute[j]:
            continue
        for k in (turns[j], turns[j] - np.sign(turns[j])):
            candidate = q[j] + 2 * np.pi * k
            if k != 0 and robot.lower[j] <= candidate <= robot.upper[j]:
                q[j] = candidate
                break
    return q


def _reach(robot, scene, poses, X_ET, clearance, self_clearance, rng, q_ref) -> tuple:
    """The first pose of ``poses`` with a certified-free IK answer: ``(q, X_WT)`` or ``(None, None)``."""
    for X_WT in poses:
        if not _within_reach(robot, X_ET, X_WT[:3, 3]):
            continue
        q = _ik(robot, scene, X_WT, X_ET, clearance, rng.integers(2 ** 31), q_ref)
        if q is not None:
            q = unwrap(robot, q, q_ref)
        if q is not None and certified_with_margin(scene, q, clearance, self_clearance):
            return q, X_WT
    return None, None


def _site_poses(site, rng, attempts: int = 4) -> list:
    poses = []
    for approach in site.approaches:
        p = site.p_W - approach * (site.size + STANDOFF)
        poses.append(grasp_pose(p, approach, flip=bool(rng.integers(2)), yaw=rng.uniform(-np.pi, np.pi)))
    return poses[:attempts]


def _goal_order(sites, start_site, rng) -> list:
    """Goal sites in random order, another object than the start's, other shelf levels first."""
    order = [sites[i] for i in rng.permutation(len(sites))]
    if start_site is None:
        return order
    order = [s for s in order if s.name != start_site.name]
    far = [s for s in order if abs(s.p_W[2] - start_site.p_W[2]) > 0.1]
    return far + [s for s in order if s not in far]


def draw_fixture(name: str, rng: np.random.Generator):
    """One fixture of set ``name`` (:data:`.fixtures.FIXTURES`)."""
    return FIXTURES[name](rng)


def always_close_pairs(robot) -> tuple:
    """The robot's link pairs that a self-collision :class:`drake_mh.scene.Scene` leaves out by
    default: never more than 1 cm apart under the sphere model (:mod:`drake_mh.scene.always_close`;
    the capsule Panda's link1-link3 are 0.9 mm apart in every configuration)."""
    from drake_mh.scene import Scene

    return Scene(robot, self_collision=True).always_close_pairs


def check_sphere_tolerance(sphere_tolerance) -> float:
    """``sphere_tolerance`` as a float [m], or :class:`~drake_mh.errors.InvalidArgument` when it
    is not a finite positive number."""
    try:
        value = float(sphere_tolerance)
    except (TypeError, ValueError):
        raise InvalidArgument(f"sphere_tolerance must be a positive length in metres, got {sphere_tolerance!r}") \
            from None
    if isinstance(sphere_tolerance, bool) or not np.isfinite(value) or value <= 0.0:
        raise InvalidArgument(f"sphere_tolerance must be a positive length in metres, got {sphere_tolerance!r}")
    return value


def new_scene(robot, self_collision: bool = True, sphere_tolerance: float = DEFAULT_TOLERANCE):
    """An empty :class:`drake_mh.scene.Scene`, self-collision with the default rule: the robot's
    always-close link pairs left out (:func:`always_close_pairs`, found under this scene's sphere
    model). ``sphere_tolerance`` [m] is the covering tolerance of the scene's sphere model
    (:class:`drake_mh.geometry.spheres.SphereModel`; default 1 cm): coarser is fewer spheres, so faster
    checks, but more pessimistic (docs/planning.md, "Sphere tolerance").

    Raises:
        InvalidArgument: a ``sphere_tolerance`` that is not a positive number.
    """
    from drake_mh.scene import Scene

    return Scene(robot, self_collision=bool(self_collision), sphere_tolerance=check_sphere_tolerance(sphere_tolerance))


def certified_with_margin(scene, q, clearance: float, self_clearance: float) -> bool:
    """``q`` certified free with :data:`MARGIN` more than the clearances."""
    return bool(scene.collision_free(q, clearance + MARGIN, self_clearance + MARGIN))


def build_scene(robot, fixture, self_collision: bool = True, sphere_tolerance: float = DEFAULT_TOLERANCE):
    """A :class:`drake_mh.scene.Scene` of ``robot`` (:func:`new_scene`) with the fixture's obstacles."""
    scene = new_scene(robot, self_collision, sphere_tolerance)
    for name, shape, p_W, rpy in fixture.obstacles:
        scene.add(name, shape, p_W, rpy)
    return scene


def generate_problem(name: str, robot, index: int, seed: int = 0, clearance: float = 0.0,
                     self_clearance: float = 0.0, self_collision: bool = True, code: int = 0,
                     sphere_tolerance: float = DEFAULT_TOLERANCE):
    """Problem ``index`` of set ``name`` for ``robot`` (module docstring); its scene's sphere model
    has covering tolerance ``sphere_tolerance`` [m] (:func:`new_scene`).

    Returns:
        ``(MotionProblem, info)``; ``info`` has the fixture, the goal's grasp pose ``X_WT``, the
        number of fixtures drawn and whether the straight line is certified free.

    Raises:
        InvalidMotionProblem: no certified-free start/goal pair in :data:`MAX_DRAWS` fixtures.
    """
    from drake_mh.planning import MotionProblem

    rng = np.random.default_rng([int(seed), int(code), int(index)])
    X_ET = tool_transform(robot)
    ready = ready_configuration(robot)
    for draw in range(1, MAX_DRAWS + 1):
        fixture = draw_fixture(name, rng)
        scene = build_scene(robot, fixture, self_collision, sphere_tolerance)
        q_start, start_site = ready, None
        if fixture.starts:  # start at another object, a spot on the table, under the table
            q_start = None
            for start_site in [fixture.starts[i] for i in rng.permutation(len(fixture.starts))][:2]:
                q_start, _ = _reach(robot, scene, _site_poses(start_site, rng), X_ET, clearance, self_clearance, rng,
                                    ready)
                if q_start is not None:
                    break
        elif not certified_with_margin(scene, ready, clearance, self_clearance):
            q_start = None
        if q_start is None:
            continue
        sites = _goal_order(fixture.sites, start_site, rng)
        q_goal = X_WT = None
        for site in sites[:3]:
            q_goal, X_WT = _reach(robot, scene, _site_poses(site, rng), X_ET, clearance, self_clearance, rng,
                                  q_start)
            if q_goal is not None:
                break
        if q_goal is None or np.max(np.abs(q_goal - q_start)) < 1e-3:
            continue
        problem = MotionProblem(robot, scene, q_start, q_goal, clearance=clearance, self_clearance=self_clearance,
                                name=f"{name}/{index:03d}")
        straight = bool(scene.segment_free(q_start, q_goal, clearance, self_clearance))
        return problem, {"fixture": fixture, "X_WT": X_WT, "draws": draw, "straight_free": straight,
                         "site": site.name, "start_site": None if start_site is None else start_site.name}
    raise InvalidMotionProblem(
        f"{name}: no certified-free start and goal for {robot.name} in {MAX_DRAWS} fixtures (problem {index}, "
        f"seed {seed}); the robot may not reach into this fixture: lower the clearance or use another set")
