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
scene's ``world.collision_objects`` are primitives (``box``: full sides ``[x, y, z]``;
``sphere``: ``[radius]``; ``cylinder``: ``[height, radius]``) at ``primitive_poses``
(position, quaternion ``[x, y, z, w]``) composed with the object's optional ``pose``; a
request's ``start_state.joint_state`` (names and positions) and
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

MBM_SETS = ("table_pick", "table_under_pick", "box", "bookshelf_small", "bookshelf_tall", "bookshelf_thin", "cage")
"""MotionBenchMaker's Panda sets, as named in the archive (without the ``_panda`` suffix)."""

_MEMBER = re.compile(r"(?:^|/)(?P<set>[^/]+)/(?P<kind>scene|request)(?P<index>\d+)\.ya?ml$")


@dataclass(frozen=True)
class MBMProblem:
    """One MotionBenchMaker problem as read from the archive (no robot involved yet).

    Attributes:
        set: the set's name (e.g. ``bookshelf_small``, the robot suffix removed).
        index: the problem's number in its set.
        obstacles: ``[(name, shape, p_WO (3,), R_WO (3, 3))]``, shapes of :mod:`drake_mh.geometry.shapes`.
        start: ``{joint name: position}`` of the start state.
        goal: ``{joint name: position}`` of the goal's joint constraints.
    """

    set: str
    index: int
    obstacles: tuple
    start: dict
    goal: dict


def _quaternion_matrix(q) -> np.ndarray:
    if isinstance(q, dict):
        q = [q["x"], q["y"], q["z"], q["w"]]
    x, y, z, w = (float(v) for v in q)
    n = np.sqrt(x * x + y * y + z * z + w * w)
    if not np.isfinite(n) or n < 1e-9:
        raise InvalidArgument(f"MotionBenchMaker archive: a quaternion {q!r} is not a rotation")
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _pose(pose) -> np.ndarray:
    X = np.eye(4)
    if pose:
        position = pose.get("position", [0.0, 0.0, 0.0])
        if isinstance(position, dict):
            position = [position["x"], position["y"], position["z"]]
        X[:3, 3] = np.asarray(position, float)
        X[:3, :3] = _quaternion_matrix(pose.get("orientation", [0.0, 0.0, 0.0, 1.0]))
    return X


def _shape(primitive: dict, where: str):
    from drake_mh.geometry.shapes import Box, Cylinder, Sphere

    kind, dims = primitive.get("type"), [float(d) for d in primitive.get("dimensions", [])]
    if kind == "box" and len(dims) == 3:
        return Box(*dims)
    if kind == "sphere" and len(dims) >= 1:
        return Sphere(dims[0])
    if kind == "cylinder" and len(dims) == 2:
        return Cylinder(dims[1], dims[0])  # MoveIt: [height, radius]
    raise InvalidArgument(f"MotionBenchMaker archive, {where}: unsupported primitive {kind!r} with dimensions {dims}")


def parse_scene(data: dict, where: str = "scene") -> tuple:
    """A MoveIt planning scene's collision objects -> ``((name, shape, p_WO, R_WO), ...)``."""
    out = []
    for obj in (data.get("world") or {}).get("collision_objects") or []:
        X_WB = _pose(obj.get("pose"))
        primitives, poses = obj.get("primitives") or [], obj.get("primitive_poses") or []
        if len(primitives) != len(poses):
            raise InvalidArgument(f"MotionBenchMaker archive, {where}: object {obj.get('id')!r} has "
                                  f"{len(primitives)} primitives but {len(poses)} poses")
        for k, (primitive, pose) in enumerate(zip(primitives, poses)):
            X_WO = X_WB @ _pose(pose)
            name = str(obj.get("id", "object")) + (f"_{k}" if len(primitives) > 1 else "")
            out.append((name, _shape(primitive, where), X_WO[:3, 3].copy(), X_WO[:3, :3].copy()))
    return tuple(out)


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
        InvalidArgument: no such file, nothing in MotionBenchMaker's layout in it, a scene
            without its request, or an unsupported primitive.
    """
    import yaml

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
            scene = parse_scene(yaml.load(scene_bytes, Loader=loader) or {}, scene_name)
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
    """
    from pydrake.math import RollPitchYaw, RotationMatrix

    from drake_mh.planning import MotionProblem

    from drake_mh.errors import InvalidMotionProblem
    from drake_mh.planning.problems.generate import MARGIN, certified_with_margin, new_scene

    where = f"MotionBenchMaker {problem.set} {problem.index}"
    scene = new_scene(robot, self_collision, sphere_tolerance)
    for name, shape, p_WO, R_WO in problem.obstacles:
        scene.add(name, shape, p_WO, RollPitchYaw(RotationMatrix(R_WO)).vector())
    q_start = _configuration(robot, problem.start, "start state", where)
    q_goal = _configuration(robot, problem.goal, "goal", where)
    motion = MotionProblem(robot, scene, q_start, q_goal, clearance=clearance, self_clearance=self_clearance,
                           name=f"mbm/{problem.set}/{problem.index:04d}")
    for what, q in (("start", q_start), ("goal", q_goal)):
        if not certified_with_margin(scene, q, clearance, self_clearance):
            raise InvalidMotionProblem(f"the {what} is certified free, but not with {MARGIN * 1e3:.0f} mm to spare "
                                       "(no verified motion could leave it)")
    return motion
