"""The problem sets and the robots they know: :func:`problem_set`, :func:`motionbenchmaker_set`,
:func:`load_problem_robot` (the package's face: :mod:`drake_mh.planning.problems`)."""

from __future__ import annotations

import logging

import numpy as np

from drake_mh.errors import DrakeMhError, InvalidArgument, UnknownMethod
from drake_mh.planning.problems.fixtures import FIXTURES
from drake_mh.planning.problems.generate import (check_sphere_tolerance, generate_problem, ready_configuration,
                                                  tool_transform)
from drake_mh.planning.problems.mbm import MBM_SETS, read_motionbenchmaker, to_motion_problem
from drake_mh.geometry.spheres import DEFAULT_TOLERANCE

logger = logging.getLogger(__name__)

__all__ = ["ProblemSet", "problem_set", "available_problem_sets", "motionbenchmaker_set", "load_problem_robot",
           "read_motionbenchmaker", "PROBLEM_ROBOTS", "MBM_SETS", "ready_configuration", "tool_transform",
           "UR5_ACCELERATION"]

#: robot names the problem sets know besides drake_mh.load_robot's
PROBLEM_ROBOTS = {
    "panda": "bundled Panda, capsules, no hand (flange at panda_link8)",
    "panda_hand": "example-robot-data's Panda with its hand (meshes), fingers locked open at 4 cm, Franka's "
                  "acceleration and jerk limits added",
    "panda_hand_mbm": "the same with MotionBenchMaker's fingers: 6.5 cm out from the hand's axis (past the real "
                      "4 cm stroke, as in MotionBenchMaker's model)",
    "ur5": "example-robot-data's UR5 (meshes), no tool, assumed acceleration limits added (5 rad/s², UR's "
           "MoveIt configuration)",
}

#: stable code of each set in the random streams (problem i of a set depends on seed, code, i)
SET_CODES = {name: code for code, name in enumerate(FIXTURES)}

_ROBOTS: dict = {}


class ProblemSet(list):
    """A list of :class:`~drake_mh.planning.MotionProblem` with what made them.

    Attributes:
        name: the set's name (``mbm/<set>`` for the original MotionBenchMaker problems).
        robot: the robot.
        seed: the seed (``None`` for archive problems).
        info: one dict per problem: ``straight_free`` (the straight joint-space line from start to
            goal is certified free), and for generated problems ``fixture``, ``X_WT`` (the goal's
            grasp pose), ``draws`` (fixtures drawn until one had a certified-free pair), ``site``.
        skipped: archive problems left out, as ``(index, reason)``.
        note: what to keep in mind when reading results on this set (e.g. a missing hand).
    """

    def __init__(self, problems=(), name: str = "", robot=None, seed=None, info=(), skipped=(), note: str = ""):
        super().__init__(problems)
        self.name, self.robot, self.seed = name, robot, seed
        self.info, self.skipped, self.note = list(info), list(skipped), note

    @property
    def straight_line_blocked(self) -> float:
        """Fraction of problems whose straight joint-space line is *not* certified free."""
        flags = [not i["straight_free"] for i in self.info]
        return float(np.mean(flags)) if flags else float("nan")

    def summary(self) -> dict:
        """Numbers that describe the set (for reports)."""
        obstacles = [len(p.scene.obstacles) for p in self]
        distance = [float(np.linalg.norm(p.goal_configurations[0] - p.q_start)) for p in self]
        return {"set": self.name, "robot": getattr(self.robot, "name", "?"), "problems": len(self),
                "skipped": len(self.skipped), "obstacles_mean": float(np.mean(obstacles)) if obstacles else 0.0,
                "obstacles_max": int(max(obstacles, default=0)), "straight_line_blocked": self.straight_line_blocked,
                "joint_distance_median": float(np.median(distance)) if distance else float("nan"),
                "draws_mean": float(np.mean([i.get("draws", 1) for i in self.info])) if self.info else float("nan")}

    def __repr__(self) -> str:
        return (f"ProblemSet({self.name!r}, {getattr(self.robot, 'name', '?')}, {len(self)} problems, straight line "
                f"blocked in {100 * self.straight_line_blocked:.0f} %)")


def available_problem_sets() -> dict[str, str]:
    """``{name: one line}`` of the generated sets (:func:`problem_set`)."""
    return {name: " ".join((function.__doc__ or "").strip().split("\n\n")[0].split())
            for name, function in FIXTURES.items()}


def load_problem_robot(robot="panda"):
    """A :class:`~drake_mh.robot.Robot` for the problem sets: passed through, or loaded by name
    (:data:`PROBLEM_ROBOTS`, else :func:`drake_mh.load_robot`), once per process."""
    from drake_mh.robot import Robot

    if isinstance(robot, Robot):
        return robot
    if not isinstance(robot, str):
        raise InvalidArgument(f"robot must be a drake_mh Robot or a name, got {type(robot).__name__}")
    if robot not in _ROBOTS:
        if robot in ("panda_hand", "panda_hand_mbm"):
            _ROBOTS[robot] = _panda_hand(0.04 if robot == "panda_hand" else MBM_FINGER)
        elif robot == "ur5":
            _ROBOTS[robot] = _ur5()
        else:
            import drake_mh

            _ROBOTS[robot] = drake_mh.load_robot(robot)
    return _ROBOTS[robot]


MBM_FINGER = 0.065
"""[m] MotionBenchMaker's Panda fingers: fixed 6.5 cm out from the hand's axis (VAMP's copy of its
URDF), wider than the real hand opens (4 cm per finger)."""


#: Franka's published acceleration [rad/s²] and jerk [rad/s³] limits (as in the bundled Panda),
#: which example-robot-data's URDF does not declare (added so that the benchmark's motions are timed
#: under the same limits as the bundled Panda's; as shipped, it is retimed under velocity and torque)
FRANKA_ACCELERATION = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)
FRANKA_JERK = (7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0)


UR5_ACCELERATION = 5.0
"""[rad/s²] assumed acceleration limit of every UR5 joint. Universal Robots publishes none for
the arm (its limits are on joint torque); 5 rad/s² is the value of Universal Robots' own MoveIt
configuration (``Universal_Robots_ROS2_Driver``, ``ur_moveit_config/config/joint_limits.yaml``:
"While the robot does not inherently have any limits on joint accelerations (only on torques),
MoveIt needs them for time parametrization. They were chosen conservatively"). An assumption,
not a hardware figure; no jerk limit is assumed (ruckig then runs unlimited in jerk)."""

UR5_JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
              "wrist_3_joint")


def _example_copy(name: str, limits: dict, edit=None, tag: str = ""):
    """example-robot-data's ``name`` loaded from a copy of its URDF (in the cache folder) whose
    joints get extra ``<limit>`` attributes: ``limits = {joint: 'drake:acceleration="…" …'}``;
    ``edit(text) -> text`` changes more. Returns the URDF path, the end-effector frame and the
    package root."""
    import re
    from pathlib import Path

    from drake_mh._support.cache import atomic_write_bytes, cache_dir, content_hash
    from drake_mh.errors import MeshNotFound
    from drake_mh.robot.examples import EXAMPLE_ARMS, example_robot_data_root
    from drake_mh.robot.loading import DRAKE_MH_NS, DRAKE_NS

    root = example_robot_data_root()
    if root is None:
        raise MeshNotFound("example-robot-data", ["this Python's prefixes"],
                           hint="pip install example-robot-data (in the test extra: pip install -e '.[test]')")
    rel, ee = EXAMPLE_ARMS[name]
    path = Path(root) / rel
    text = path.read_text(encoding="utf-8")
    edited = re.sub(r"<robot ", f'<robot xmlns:drake="{DRAKE_NS}" xmlns:drake_mh="{DRAKE_MH_NS}" ', text,
                    count=1)
    for joint, attributes in limits.items():
        edited, n = re.subn(rf'(<joint name="{joint}".*?<limit )', rf"\g<1>{attributes} ", edited, count=1,
                            flags=re.S)
        if n != 1:
            raise InvalidArgument(f"{path}: no <limit> of {joint} to add {attributes} to")
    if edit is not None:
        edited = edit(edited)
    copy = cache_dir("robots") / f"{tag or name}_{content_hash(edited)[:16]}" / path.name
    if not copy.is_file():
        copy.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(copy, edited.encode("utf-8"))
    return copy, ee, root


def _ur5():
    """example-robot-data's UR5 from a copy of its URDF with :data:`UR5_ACCELERATION` on every
    joint (the limits of UR's MoveIt configuration; as shipped, it is retimed under velocity and
    torque)."""
    import drake_mh

    copy, ee, root = _example_copy("ur5", {j: f'drake:acceleration="{UR5_ACCELERATION}"' for j in UR5_JOINTS})
    return drake_mh.load_robot(copy, ee_frame=ee, packages={"example-robot-data": str(root)})


def _panda_hand(finger: float):
    """example-robot-data's Panda with its hand, both fingers locked ``finger`` [m] out, loaded
    from a copy of its URDF (in the cache folder) that adds Franka's published acceleration and
    jerk limits to the arm's joints and, past the 4 cm stroke, widens the fingers' limit."""
    import re

    import drake_mh

    def widen(text: str) -> str:
        if finger <= 0.04:
            return text
        text, n = re.subn(r'(<joint name="panda_finger_joint[12]".*?upper=")0\.04(")', rf"\g<1>{finger}\g<2>",
                          text, flags=re.S)
        if n != 2:
            raise InvalidArgument("no finger joint limits of 0.04 to widen for MotionBenchMaker's fingers")
        return text

    limits = {f"panda_joint{k}": f'drake:acceleration="{a}" drake_mh:jerk="{j}"'
              for k, (a, j) in enumerate(zip(FRANKA_ACCELERATION, FRANKA_JERK), start=1)}
    copy, ee, root = _example_copy("panda_hand", limits, widen, tag="panda_hand")
    locked = {"panda_finger_joint1": finger, "panda_finger_joint2": finger}
    return drake_mh.load_robot(copy, ee_frame=ee, locked=locked, packages={"example-robot-data": str(root)})


def check_count(count, what: str = "count", unit: str = "a whole number of problems") -> int:
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
        raise InvalidArgument(f"{what} must be {unit} >= 0, got {count!r}")
    return int(count)


def _check_clearances(clearance, self_clearance) -> tuple[float, float]:
    """Both as lengths >= 0 [m], checked before any problem is made (the generator asks IK for a
    margin more, which a message must not show)."""
    from drake_mh.scene.segments import check_clearance

    try:
        return check_clearance(clearance, "clearance"), check_clearance(self_clearance, "self_clearance")
    except DrakeMhError as exc:
        raise InvalidArgument(str(exc)) from None


def problem_set(name: str, robot="panda", count: int = 10, seed: int = 0, clearance: float = 0.0,
                self_clearance: float = 0.0, self_collision: bool = True, first: int = 0,
                sphere_tolerance: float = DEFAULT_TOLERANCE) -> ProblemSet:
    """``count`` motion problems of a generated set (:mod:`.generate`), deterministic per seed.

    Args:
        name: a name of :func:`available_problem_sets`.
        robot: a Robot or a name (module docstring).
        count: number of problems.
        seed: the set's seed; problem ``i`` depends only on ``(seed, name, i)`` and the robot
            (the first 3 of ``count=10`` are those of ``count=3``).
        clearance, self_clearance: the problems' clearances [m]; start and goal are certified
            free with them.
        self_collision: check the robot's links against each other too (as MotionBenchMaker does).
        first: index of the first problem (``first=5, count=2``: problems 5 and 6).
        sphere_tolerance: covering tolerance [m] of the scenes' sphere model
            (:class:`drake_mh.geometry.spheres.SphereModel`, default 1 cm), what start and goal are
            certified with and planners check against. Coarser is fewer spheres, so faster
            checks, but more pessimistic: configurations near obstacles are no longer certified
            free, narrow passages close (docs/planning.md, "Sphere tolerance"). Problem ``i`` may differ between tolerances (a draw certified at one may
            not be at another).

    Returns:
        A :class:`ProblemSet` (a list of :class:`~drake_mh.planning.MotionProblem`).

    Raises:
        UnknownMethod: an unknown set name (the message lists them).
        InvalidArgument: ``count``, ``first`` or ``seed`` not an integer >= 0, a clearance not a
            length >= 0, or a non-positive ``sphere_tolerance``.
        InvalidMotionProblem: no certified-free pair found for a problem (the robot cannot
            reach into this fixture).
    """
    if name not in FIXTURES:
        raise UnknownMethod(name, list(FIXTURES), what="problem set")
    count = check_count(count)
    first = check_count(first, "first", "an integer (the first problem's index)")
    seed = check_count(seed, "seed", "an integer")
    clearance, self_clearance = _check_clearances(clearance, self_clearance)
    sphere_tolerance = check_sphere_tolerance(sphere_tolerance)
    robot = load_problem_robot(robot)
    problems, info = [], []
    for index in range(first, first + count):
        problem, data = generate_problem(name, robot, index, seed=seed, clearance=clearance,
                                         self_clearance=self_clearance, self_collision=self_collision,
                                         code=SET_CODES[name], sphere_tolerance=sphere_tolerance)
        problems.append(problem)
        info.append(data)
    return ProblemSet(problems, name=name, robot=robot, seed=seed, info=info)


def motionbenchmaker_set(path, name: str, robot="panda_hand_mbm", count: int | None = None, clearance: float = 0.0,
                         self_clearance: float = 0.0, self_collision: bool = True,
                         sphere_tolerance: float = DEFAULT_TOLERANCE) -> ProblemSet:
    """The original MotionBenchMaker problems of one set, from a downloaded archive (:mod:`.mbm`).

    Args:
        path: ``problems.tar.bz2`` of the ``vamp-planner`` sdist (or the sdist, or a folder).
        name: one of :data:`MBM_SETS`.
        robot: default ``"panda_hand_mbm"``, the Panda with its hand as those problems were made
            for (fingers 6.5 cm out, :data:`MBM_FINGER`); the bundled ``"panda"`` (no hand) makes
            them easier, which :attr:`ProblemSet.note` says.
        count: the first ``count`` problems by index (default all).
        clearance, self_clearance, self_collision, sphere_tolerance: as for :func:`problem_set`
            (a coarser ``sphere_tolerance`` leaves more problems out: their start or goal is no
            longer certified free).

    Returns:
        A :class:`ProblemSet`; problems whose start or goal is not certified free for this robot
        are left out and listed in ``skipped``.

    Raises:
        UnknownMethod: an unknown set name.
        InvalidArgument: a negative ``count`` or clearance, or a non-positive ``sphere_tolerance``.
    """
    from drake_mh.errors import InvalidMotionProblem

    if name not in MBM_SETS:
        raise UnknownMethod(name, list(MBM_SETS), what="MotionBenchMaker set")
    clearance, self_clearance = _check_clearances(clearance, self_clearance)  # else every problem is skipped
    sphere_tolerance = check_sphere_tolerance(sphere_tolerance)
    robot = load_problem_robot(robot)
    archive = read_motionbenchmaker(path, sets=[name]).get(name, [])
    if count is not None:
        archive = archive[:check_count(count)]
    note = ""
    if "panda_hand" not in robot.frame_names() and robot.name.startswith("panda"):
        note = ("MotionBenchMaker's problems assume the Panda with its hand; this robot has none, so its motions "
                "are easier than the originals")
        logger.warning("%s: %s", name, note)
    problems, info, skipped = [], [], []
    for item in archive:
        try:
            problem = to_motion_problem(item, robot, clearance, self_clearance, self_collision, sphere_tolerance)
        except InvalidMotionProblem as exc:
            skipped.append((item.index, str(exc).split(";")[0]))
            continue
        goal = problem.goal_configurations[0]
        straight = bool(problem.scene.segment_free(problem.q_start, goal, clearance, self_clearance))
        problems.append(problem)
        info.append({"straight_free": straight, "index": item.index})
    return ProblemSet(problems, name=f"mbm/{name}", robot=robot, info=info, skipped=skipped, note=note)
