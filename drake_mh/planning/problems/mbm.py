"""The original MotionBenchMaker problems, read from a downloaded archive (never downloaded here).

The ``vamp-planner`` source distribution on the package registry ships MotionBenchMaker's Panda
problems as ``resources/panda/problems.tar.bz2`` (seven sets of 100: ``table_pick``,
``table_under_pick``, ``box``, ``bookshelf_small``, ``bookshelf_tall``, ``bookshelf_thin``,
``cage``), beside its converter ``resources/problem_tar_to_pkl_json.py``. Get it once with::

    pip download vamp-planner --no-binary vamp-planner --no-deps -d /tmp/vamp

(pip then builds the package's metadata; the ``.tar.gz`` it leaves holds the archive) and pass
the path of ``problems.tar.bz2`` — or of the ``.tar.gz`` itself — to
:func:`read_motionbenchmaker` / :func:`motionbenchmaker_set`.

**Format** (what VAMP's converter reads, and so do we, without VAMP): members
``<top>/<set>_<robot>/sceneNNNN.yaml`` and ``requestNNNN.yaml``, MoveIt messages in YAML. A
scene is a planning scene, read by :func:`drake_mh.scene.files.moveit.read_planning_scene`
(the reader of planning-scene files: primitives, meshes, object poses, ``header.frame_id``);
a request's ``start_state.joint_state`` (names and positions) and
``goal_constraints[0].joint_constraints`` give start and goal by joint name. Unlike VAMP's
converter we read every primitive of an object (it reads the first).

**The hand.** Those problems were made for the Panda *with its hand* (MotionBenchMaker's model,
fingers fixed 6.5 cm out from the hand's axis in VAMP's copy): many goals put the hand between
shelf boards, a finger's width from a can. The default robot here is therefore
example-robot-data's Panda with its hand (``panda_hand``: meshes, fingers locked open at 4 cm,
their upper limit). The bundled capsule Panda has no hand: with it the problems are easier (no
hand to fit through the openings) — allowed, and said in the set's ``note``. Either way every
start and goal is re-checked under our model (sphere model, certified): a problem whose start or
goal is not certified free for the robot used is skipped and counted (``ProblemSet.skipped``).
"""

from __future__ import annotations

import re
import tarfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.geometry.spheres import DEFAULT_TOLERANCE
from drake_mh.scene.files import SceneFile

MBM_SETS = ("table_pick", "table_under_pick", "box", "bookshelf_small", "bookshelf_tall", "bookshelf_thin", "cage")
"""MotionBenchMaker's Panda sets, as named in the archive (without the ``_panda`` suffix)."""

_MEMBER = re.compile(r"(?:^|/)(?P<set>[^/]+)/(?P<kind>scene|request)(?P<index>\d+)\.ya?ml$")


@dataclass(frozen=True)
class MBMProblem:
    """One MotionBenchMaker problem as read from the archive (no robot involved yet).

    Attributes:
        set: the set's name (e.g. ``bookshelf_small``, the robot suffix removed).
        index: the problem's number in its set.
        scene: the obstacles, a :class:`drake_mh.scene.files.SceneFile` (poses in their
            ``header.frame_id``: :meth:`~drake_mh.scene.files.SceneFile.resolved` places them).
        start: ``{joint name: position}`` of the start state.
        goal: ``{joint name: position}`` of the goal's joint constraints.
    """

    set: str
    index: int
    scene: SceneFile
    start: dict
    goal: dict


def parse_request(data: dict, where: str = "request") -> tuple[dict, dict]:
    """A MoveIt motion plan request -> ``(start, goal)`` as ``{joint name: position}``."""
    try:
        state = data["start_state"]["joint_state"]
        start = {str(n): float(p) for n, p in zip(state["name"], state["position"])}
        constraints = data["goal_constraints"][0]["joint_constraints"]
        goal = {str(c["joint_name"]): float(c["position"]) for c in constraints}
    except (KeyError, IndexError, TypeError) as exc:
        raise InvalidArgument(f"MotionBenchMaker archive, {where}: not a joint-space request ({exc!r} missing)") from None
    return start, goal


def read_motionbenchmaker(path, sets=None) -> dict[str, list[MBMProblem]]:
    """Read MotionBenchMaker problems from ``problems.tar.bz2`` (or a ``vamp-planner`` sdist
    ``.tar.gz`` that contains it, or a folder with the extracted files).

    Args:
        path: the archive or folder (a local copy: nothing is downloaded).
        sets: set names to read (default all), without the robot suffix.

    Returns:
        ``{set: [MBMProblem, ...]}`` sorted by index (pairs of scene and request files).

    Raises:
        InvalidArgument: no such file, nothing in MotionBenchMaker's layout in it, or a scene
            without its request.
        SceneFileError: a scene entry that is malformed or not supported (a cone ...).
    """
    import yaml

    from drake_mh.scene.files.moveit import read_planning_scene

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    path = Path(path).expanduser()
    if not path.exists():
        raise InvalidArgument(f"{path} does not exist: download the vamp-planner source distribution first "
                              "(pip download vamp-planner --no-binary vamp-planner --no-deps -d DIR) and pass "
                              "resources/panda/problems.tar.bz2")
    wanted = None if sets is None else {str(s) for s in sets}
    files: dict = {}

    def take(name: str, read) -> None:
        m = _MEMBER.search(name)
        if m is None:
            return
        set_name = re.sub(r"_(panda|ur5|fetch|baxter)$", "", m["set"])
        if wanted is not None and set_name not in wanted:
            return
        files.setdefault(set_name, {}).setdefault(int(m["index"]), {})[m["kind"]] = (name, read())

    if path.is_dir():
        for file in sorted(path.rglob("*.yaml")):
            take(file.relative_to(path).as_posix(), file.read_bytes)
    else:
        try:
            tar = tarfile.open(path, "r:*")
        except (tarfile.TarError, OSError) as exc:
            raise InvalidArgument(f"{path} is not a readable tar archive: {exc}") from None
        with tar:
            inner = [m for m in tar.getmembers() if m.isfile() and m.name.endswith("panda/problems.tar.bz2")]
            if inner:  # the sdist: open the Panda archive inside it
                data = tar.extractfile(inner[0]).read()
                import io

                with tarfile.open(fileobj=io.BytesIO(data), mode="r:bz2") as sub:
                    for member in sub.getmembers():
                        if member.isfile():
                            take(member.name, sub.extractfile(member).read)
            else:
                for member in tar.getmembers():
                    if member.isfile():
                        take(member.name, tar.extractfile(member).read)
    if not files:
        raise InvalidArgument(f"{path}: no MotionBenchMaker problems (<set>_<robot>/sceneNNNN.yaml and "
                              f"requestNNNN.yaml) found" + (f" for sets {sorted(wanted)}" if wanted else ""))
    out: dict[str, list[MBMProblem]] = {}
    for set_name in sorted(files):
        problems = []
        for index in sorted(files[set_name]):
            pair = files[set_name][index]
            if "scene" not in pair or "request" not in pair:
                missing = "request" if "scene" in pair else "scene"
                raise InvalidArgument(f"{path}: {set_name} problem {index} has no {missing} file")
            scene_name, scene_bytes = pair["scene"]
            request_name, request_bytes = pair["request"]
            scene = read_planning_scene(yaml.load(scene_bytes, Loader=loader) or {}, f"{path}:{scene_name}", None)
            start, goal = parse_request(yaml.load(request_bytes, Loader=loader) or {}, request_name)
            problems.append(MBMProblem(set_name, index, scene, start, goal))
        out[set_name] = problems
    return out


def _configuration(robot, values: dict, what: str, where: str) -> np.ndarray:
    missing = [j for j in robot.joint_names if j not in values]
    if missing:
        raise InvalidArgument(f"{where}: the {what} has no value for joint(s) {missing} of {robot.name}; "
                              f"it names {sorted(values)}")
    return np.array([values[j] for j in robot.joint_names])


def to_motion_problem(problem: MBMProblem, robot, clearance: float = 0.0, self_clearance: float = 0.0,
                      self_collision: bool = True, sphere_tolerance: float = DEFAULT_TOLERANCE):
    """Build the :class:`~drake_mh.planning.MotionProblem` of one archive problem.

    Self-collision leaves out the robot's always-close link pairs
    (:func:`drake_mh.planning.problems.generate.always_close_pairs`). ``sphere_tolerance`` [m]:
    covering tolerance of the scene's sphere model (default 1 cm; coarser is faster but more
    pessimistic: :func:`drake_mh.planning.problems.generate.new_scene`).

    Raises:
        InvalidMotionProblem: the start or goal is outside the limits or not certified free
            for this robot (sphere model, with the clearances plus
            :data:`~drake_mh.planning.problems.generate.MARGIN`).
        InvalidArgument: a joint of the robot has no value in the request, or a non-positive
            ``sphere_tolerance``.
        SceneFileError: an obstacle posed in a frame the robot cannot place
            (:meth:`~drake_mh.scene.files.SceneFile.resolved`).
    """
    from drake_mh.planning import MotionProblem

    from drake_mh.errors import InvalidMotionProblem
    from drake_mh.planning.problems.generate import MARGIN, certified_with_margin, new_scene

    where = f"MotionBenchMaker {problem.set} {problem.index}"
    scene = new_scene(robot, self_collision, sphere_tolerance)
    scene.load(problem.scene)
    q_start = _configuration(robot, problem.start, "start state", where)
    q_goal = _configuration(robot, problem.goal, "goal", where)
    motion = MotionProblem(robot, scene, q_start, q_goal, clearance=clearance, self_clearance=self_clearance,
                           name=f"mbm/{problem.set}/{problem.index:04d}")
    for what, q in (("start", q_start), ("goal", q_goal)):
        if not certified_with_margin(scene, q, clearance, self_clearance):
            raise InvalidMotionProblem(f"the {what} is certified free, but not with {MARGIN * 1e3:.0f} mm to spare "
                                       "(no verified motion could leave it)")
    return motion
