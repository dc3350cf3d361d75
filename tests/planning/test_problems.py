"""Problem sets: generated problems valid and deterministic; the MotionBenchMaker converter on a
tiny synthetic archive in the same format (the real one is never needed here)."""

from __future__ import annotations

import io
import tarfile

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument, SceneFileError, UnknownMethod
from drake_mh.planning import MotionProblem
from drake_mh.planning.problems import (
    MBM_SETS, ProblemSet, available_problem_sets, load_problem_robot, motionbenchmaker_set, problem_set,
    read_motionbenchmaker, ready_configuration, tool_transform,
)
from drake_mh.planning.problems.generate import MARGIN, always_close_pairs, grasp_pose, unwrap
from references import FreshDrake, dense_path

PANDA = load_problem_robot("panda")


def _obstacle_poses(problem) -> np.ndarray:
    return np.array([o.X_WO for o in problem.scene.obstacles.values()])


@pytest.mark.parametrize("name", list(available_problem_sets()))
def test_every_set_gives_certified_free_problems(name):
    problems = problem_set(name, PANDA, count=1, seed=5)
    assert isinstance(problems, ProblemSet) and len(problems) == 1 and problems.name == name
    problem = problems[0]
    assert isinstance(problem, MotionProblem) and problem.name == f"{name}/000"
    assert problem.scene.self_collision and len(problem.scene.obstacles) >= 7
    q_goal = problem.goal_configurations[0]
    # Drake's own query on a fresh plant with the scene's obstacles and checked self pairs
    drake = FreshDrake(PANDA, problem.scene, self_collision=True, ignore_link_pairs=problem.scene.always_close_pairs)
    for q in (problem.q_start, q_goal):
        assert PANDA.within_limits(q)
        assert problem.scene.collision_free(q, problem.clearance + MARGIN, problem.self_clearance + MARGIN)
        assert problem.scene.min_distance(q) > 0.0 and drake.min_distance(q) > 0.0
    assert np.max(np.abs(q_goal - problem.q_start)) > 1e-3
    info = problems.info[0]
    # straight_free is a certificate's verdict at clearance 0: a line it calls free has no contact
    # where Drake samples it densely (5 mrad of its fastest joint; Drake is only ever optimistic
    # here, so a contact it finds is real)
    contact = drake.min_distances(dense_path(np.stack([problem.q_start, q_goal]), 0.005), max_distance=0.0).min() < 0
    assert isinstance(info["straight_free"], bool) and not (info["straight_free"] and contact)
    # the goal is the IK answer of the recorded grasp pose (Drake FK)
    X_WE = PANDA.fk_drake(q_goal) @ tool_transform(PANDA)
    assert np.linalg.norm(X_WE[:3, 3] - info["X_WT"][:3, 3]) < 2e-3
    summary = problems.summary()
    assert summary["problems"] == 1 and summary["obstacles_max"] == len(problem.scene.obstacles)


def test_problem_sets_are_deterministic_per_seed():
    a = problem_set("bookshelf_tall", PANDA, count=2, seed=11)
    b = problem_set("bookshelf_tall", PANDA, count=2, seed=11)
    c = problem_set("bookshelf_tall", PANDA, count=1, seed=11, first=1)
    for p, q in zip(a, b):
        assert np.array_equal(p.q_start, q.q_start) and np.array_equal(p.goal_configurations, q.goal_configurations)
        assert np.array_equal(_obstacle_poses(p), _obstacle_poses(q))
    assert np.array_equal(a[1].goal_configurations, c[0].goal_configurations)  # independent of count
    other = problem_set("bookshelf_tall", PANDA, count=1, seed=12)[0]
    assert not np.array_equal(_obstacle_poses(a[0]), _obstacle_poses(other))


def test_straight_line_is_usually_blocked():
    problems = problem_set("cage", PANDA, count=3, seed=0)
    assert problems.straight_line_blocked >= 2 / 3
    assert "blocked" in repr(problems)


def test_ready_configuration_grasp_pose_and_always_close_pairs():
    assert np.allclose(ready_configuration(PANDA), [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
    planar = drake_mh.load_robot("planar5")
    assert np.allclose(ready_configuration(planar), planar.home)
    X = grasp_pose([0.5, 0.0, 0.3], [1.0, 0.0, 0.0])
    assert np.allclose(X[:3, 2], [1, 0, 0]) and abs(X[2, 1]) < 1e-12  # fingers close horizontally
    assert np.allclose(X[:3, :3].T @ X[:3, :3], np.eye(3))
    down = grasp_pose([0.5, 0.0, 0.3], [0.0, 0.0, -1.0], yaw=0.3)
    assert np.allclose(down[:3, 2], [0, 0, -1]) and np.isclose(np.linalg.det(down[:3, :3]), 1.0)
    # the capsule Panda's link1/link3 spheres are 0.9 mm apart in every configuration: left out,
    # by the problem sets' scenes as by any self-collision Scene
    assert ("panda_link1", "panda_link3") in always_close_pairs(PANDA)
    assert problem_set("cage", PANDA, count=1, seed=0)[0].scene.always_close_pairs == always_close_pairs(PANDA)


def test_unwrap_turns_joints_by_whole_turns_towards_the_reference():
    arm = drake_mh.Robot.from_dh([0.3, 0.3], [0.0, 0.0], [0.0, 0.0], lower=[-6.2, -6.2], upper=[6.2, 6.2])
    q = np.array([5.0, -5.5])
    near = unwrap(arm, q, np.zeros(2))
    assert np.allclose(near, [5.0 - 2 * np.pi, -5.5 + 2 * np.pi])
    assert np.allclose(arm.fk(near), arm.fk(q))  # the same geometry
    assert np.allclose(unwrap(arm, q, q), q)
    assert np.allclose(unwrap(PANDA, PANDA.home, PANDA.home + 6.0), PANDA.home)  # no room within the limits


def test_problem_set_errors():
    with pytest.raises(UnknownMethod, match="bookshelf_small"):
        problem_set("shelf", PANDA)
    with pytest.raises(InvalidArgument, match="count"):
        problem_set("cage", PANDA, count=-1)
    assert len(problem_set("cage", PANDA, count=0)) == 0
    for kwargs in ({"seed": "abc"}, {"seed": -1}, {"seed": 1.7}, {"seed": True}, {"first": -1}, {"first": 0.5}):
        name = next(iter(kwargs))
        with pytest.raises(InvalidArgument, match=f"{name} must be an integer"):
            problem_set("cage", PANDA, count=1, **kwargs)  # 1.7 was silently truncated to 1
    for name in ("clearance", "self_clearance"):
        with pytest.raises(InvalidArgument, match=rf"^{name} must be a finite length >= 0 in metres, got -1$"):
            problem_set("cage", PANDA, count=1, **{name: -1})  # said "got -0.997": the generator's margin


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["panda_hand", "ur5"])
def test_mesh_robot_problems(robot):
    from robot_fixtures import erd_root

    erd_root()
    problems = problem_set("bookshelf_small", robot, count=1, seed=0)
    problem = problems[0]
    assert len(problem.robot.collision_summary()) >= 6  # meshes (convex hulls)
    if robot == "panda_hand":  # Franka's acceleration limits added: motions can be retimed
        assert np.allclose(problem.robot.acceleration_limits, [15, 7.5, 10, 12.5, 15, 20, 20])
        assert problem.robot.locked_joints == {"panda_finger_joint1": 0.04, "panda_finger_joint2": 0.04}
    else:  # UR5: assumed acceleration limits (UR's MoveIt configuration): motions verify
        from drake_mh.planning.problems import UR5_ACCELERATION

        assert np.allclose(problem.robot.acceleration_limits, UR5_ACCELERATION)
    for q in (problem.q_start, problem.goal_configurations[0]):
        assert problem.scene.collision_free(q, MARGIN, MARGIN) and problem.scene.min_distance(q) > 0.0
    from drake_mh.planning import solve_motion

    result = solve_motion(problem, "rrt_connect", seed=0, timeout=30)
    assert result.success and result.trajectory is not None and result.duration > 0, result.message


# --- MotionBenchMaker archives --------------------------------------------------------------------

READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
GOAL = [0.8, -0.5, 0.0, -2.0, 0.0, 1.8, 0.785]

SCENE = """robot_model_name: panda
world:
  collision_objects:
    - id: shelf
      primitives:
        - type: box
          dimensions: [0.2, 0.4, 0.04]
      primitive_poses:
        - position: [{x}, 0.5, 0.3]
          orientation: [0, 0, 0.3826834, 0.9238795]
    - id: Can1
      pose:
        position: [0.0, -0.6, 0.0]
        orientation: [0, 0, 0, 1]
      primitives:
        - type: cylinder
          dimensions: [0.14, 0.03]
        - type: sphere
          dimensions: [0.05]
      primitive_poses:
        - position: [0.1, 0.0, 0.2]
          orientation: [0, 0, 0, 1]
        - position: [0.1, 0.0, 0.5]
          orientation: [0, 0, 0, 1]
"""

REQUEST = """start_state:
  joint_state:
    name: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, panda_joint5, panda_joint6, panda_joint7, panda_finger_joint1]
    position: {start}
goal_constraints:
  - joint_constraints:
{goal}
group_name: panda_arm
"""


def _request(start, goal) -> str:
    lines = "\n".join(f"      - joint_name: panda_joint{j + 1}\n        position: {v}" for j, v in enumerate(goal))
    return REQUEST.format(start=list(start) + [0.065], goal=lines)


def _add(tar: tarfile.TarFile, name: str, text: str) -> None:
    data = text.encode()
    info = tarfile.TarInfo(name)
    info.size = len(data)
    tar.addfile(info, io.BytesIO(data))


def _archive(path, blocked_goal: bool = True):
    """Two problems of ``cage_panda`` (the second's goal inside an obstacle) and one of ``box_panda``."""
    flange = drake_mh.load_robot("panda").fk(np.array(GOAL))[:3, 3]
    with tarfile.open(path, "w:bz2") as tar:
        _add(tar, "problems/cage_panda/scene0001.yaml", SCENE.format(x=0.0))
        _add(tar, "problems/cage_panda/request0001.yaml", _request(READY, GOAL))
        scene2 = SCENE.format(x=0.0) + (
            f"    - id: blocker\n      primitives:\n        - type: sphere\n          dimensions: [0.1]\n"
            f"      primitive_poses:\n        - position: {flange.tolist()}\n          orientation: [0, 0, 0, 1]\n"
            if blocked_goal else "")
        _add(tar, "problems/cage_panda/scene0002.yaml", scene2)
        _add(tar, "problems/cage_panda/request0002.yaml", _request(READY, GOAL))
        _add(tar, "problems/box_panda/scene0001.yaml", SCENE.format(x=0.1))
        _add(tar, "problems/box_panda/request0001.yaml", _request(READY, GOAL))
    return path


def test_converter_reads_the_motionbenchmaker_format(tmp_path):
    from drake_mh.geometry.shapes import Box, Cylinder, Sphere

    data = read_motionbenchmaker(_archive(tmp_path / "problems.tar.bz2"))
    assert sorted(data) == ["box", "cage"] and [p.index for p in data["cage"]] == [1, 2]
    problem = data["cage"][0]
    assert problem.scene.names == ["shelf", "Can1_0", "Can1_1"]  # every primitive of an object
    shelf, can, ball = problem.scene.obstacles
    assert shelf.shape == Box(0.2, 0.4, 0.04) and np.allclose(shelf.position, [0.0, 0.5, 0.3])
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    assert np.allclose(shelf.X_WO[:3, :3], [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-6)  # quaternion [x, y, z, w]
    assert can.shape == Cylinder(0.03, 0.14)  # MoveIt cylinders: [height, radius]
    assert np.allclose(can.position, [0.1, -0.6, 0.2])  # the object's pose composed with the primitive's
    assert ball.shape == Sphere(0.05) and np.allclose(ball.position, [0.1, -0.6, 0.5])
    assert problem.start["panda_joint4"] == -2.356 and problem.start["panda_finger_joint1"] == 0.065
    assert [problem.goal[f"panda_joint{j + 1}"] for j in range(7)] == GOAL
    assert list(read_motionbenchmaker(tmp_path / "problems.tar.bz2", sets=["box"])) == ["box"]


def test_converter_builds_problems_and_skips_invalid_ones(tmp_path):
    path = _archive(tmp_path / "problems.tar.bz2")
    problems = motionbenchmaker_set(path, "cage", robot="panda")
    assert len(problems) == 1 and problems.name == "mbm/cage"
    assert [index for index, _ in problems.skipped] == [2] and "goal" in problems.skipped[0][1]
    assert "hand" in problems.note  # the bundled Panda has no hand: said, not hidden
    problem = problems[0]
    assert np.allclose(problem.q_start, READY) and np.allclose(problem.goal_configurations[0], GOAL)
    assert len(problem.scene.obstacles) == 3 and problems.info[0]["index"] == 1
    assert len(motionbenchmaker_set(path, "cage", robot="panda", count=1)) == 1


def test_sphere_tolerance_reaches_the_scenes(tmp_path):
    """``sphere_tolerance`` is the covering tolerance of every scene's sphere model (generated and
    archive problems); the default stays 1 cm; a non-positive one is refused up front."""
    from drake_mh.geometry.spheres import DEFAULT_TOLERANCE

    coarse = problem_set("cage", PANDA, count=1, seed=5, sphere_tolerance=0.02)
    default = problem_set("cage", PANDA, count=1, seed=5)
    assert coarse[0].scene.sphere_model.tolerance == 0.02
    assert default[0].scene.sphere_model.tolerance == DEFAULT_TOLERANCE == 0.01
    assert len(coarse[0].scene.sphere_model.radii) <= len(default[0].scene.sphere_model.radii)
    path = _archive(tmp_path / "problems.tar.bz2")
    archive = motionbenchmaker_set(path, "cage", robot="panda", sphere_tolerance=0.02)
    assert len(archive) == 1 and archive[0].scene.sphere_model.tolerance == 0.02
    assert motionbenchmaker_set(path, "cage", robot="panda")[0].scene.sphere_model.tolerance == DEFAULT_TOLERANCE
    for bad in (0.0, -0.01, float("nan"), "fine", True):
        with pytest.raises(InvalidArgument, match="sphere_tolerance"):
            problem_set("cage", PANDA, count=1, sphere_tolerance=bad)
        with pytest.raises(InvalidArgument, match="sphere_tolerance"):
            motionbenchmaker_set(path, "cage", robot="panda", sphere_tolerance=bad)


def test_converter_reads_the_sdist_and_folders(tmp_path):
    inner = _archive(tmp_path / "problems.tar.bz2").read_bytes()
    sdist = tmp_path / "vamp_planner-0.0.0.tar.gz"
    with tarfile.open(sdist, "w:gz") as tar:
        info = tarfile.TarInfo("vamp_planner-0.0.0/resources/panda/problems.tar.bz2")
        info.size = len(inner)
        tar.addfile(info, io.BytesIO(inner))
    assert [p.index for p in read_motionbenchmaker(sdist)["cage"]] == [1, 2]
    folder = tmp_path / "extracted"
    with tarfile.open(tmp_path / "problems.tar.bz2") as tar:
        tar.extractall(folder, filter="data")
    assert sorted(read_motionbenchmaker(folder)) == ["box", "cage"]


def test_converter_errors(tmp_path):
    with pytest.raises(InvalidArgument, match="does not exist"):
        read_motionbenchmaker(tmp_path / "missing.tar.bz2")
    empty = tmp_path / "empty.tar.bz2"
    with tarfile.open(empty, "w:bz2") as tar:
        _add(tar, "README", "nothing")
    with pytest.raises(InvalidArgument, match="no MotionBenchMaker problems"):
        read_motionbenchmaker(empty)
    lonely = tmp_path / "lonely.tar.bz2"
    with tarfile.open(lonely, "w:bz2") as tar:
        _add(tar, "problems/cage_panda/scene0001.yaml", SCENE.format(x=0.0))
    with pytest.raises(InvalidArgument, match="no request"):
        read_motionbenchmaker(lonely)
    cone = tmp_path / "cone.tar.bz2"
    with tarfile.open(cone, "w:bz2") as tar:
        _add(tar, "problems/cage_panda/scene0001.yaml", SCENE.format(x=0.0).replace("type: box", "type: cone"))
        _add(tar, "problems/cage_panda/request0001.yaml", _request(READY, GOAL))
    with pytest.raises(SceneFileError, match=r"scene0001\.yaml, collision object 1 \('shelf'\): a cone"):
        read_motionbenchmaker(cone)
    with pytest.raises(UnknownMethod):
        motionbenchmaker_set(empty, "kitchen")
    assert "bookshelf_thin" in MBM_SETS


# --- scene files ------------------------------------------------------------------------------------


def test_scene_file_sets_draw_certified_pairs_in_the_files_cell():
    """Start and goal certified free in the file's cell, and clear by Drake's exact distance too;
    the straight line's flag recomputed; problem i independent of count; the same seed, the same set."""
    from pathlib import Path

    from drake_mh.planning.problems import scene_problem_set

    cell = Path(__file__).resolve().parents[1] / "data" / "scenes" / "cell.sdf"
    problems = scene_problem_set(cell, PANDA, count=3, seed=4)
    assert problems.name == "file/cell.sdf" and len(problems) == 3
    assert list(problems[0].scene.obstacles) == ["table::board", "ball::sphere", "post::cylinder", "rail::capsule"]
    for problem, info in zip(problems, problems.info):
        ends = np.array([problem.q_start, problem.goal_configurations[0]])
        assert problem.scene.collision_free(ends, MARGIN, MARGIN).all()
        assert (problem.scene.exact_min_distance(ends) > MARGIN).all()
        assert info["straight_free"] == problem.scene.segment_free(*ends)
    assert not all(i["straight_free"] for i in problems.info)  # a planner has work to do
    again = scene_problem_set(cell, PANDA, count=1, seed=4, first=2)
    np.testing.assert_array_equal(again[0].goal_configurations[0], problems[2].goal_configurations[0])
    other = scene_problem_set(cell, PANDA, count=1, seed=5)
    assert not np.array_equal(other[0].goal_configurations[0], problems[0].goal_configurations[0])
    with pytest.raises(SceneFileError, match="no such file"):
        scene_problem_set(cell.with_name("missing.sdf"), PANDA, count=1)
