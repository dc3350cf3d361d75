"""Your own robot from the shell (``drake-mh robots/ik/app --robot PATH --ee-frame --package``)
and collision-free IK on the example-robot-data arms."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import drake_mh
from drake_mh.cli import main
from robot_fixtures import ERD_ROBOTS, erd_root, write_arm


@pytest.fixture(autouse=True)
def _private_cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("DRAKE_MH_CACHE", str(tmp_path_factory.getbasetemp() / "drake_mh_cache"))


def _path(name: str) -> str:
    return str(erd_root() / ERD_ROBOTS[name][0])


def test_robots_entry_of_a_mesh_robot(capsys):
    assert main(["robots", _path("panda"), "--ee-frame", "panda_hand_tcp"]) == 0
    out = capsys.readouterr().out
    assert "DOF 7, end effector 'panda_hand_tcp'" in out
    assert "locked joints: panda_finger_joint1 = 0, panda_finger_joint2 = 0" in out
    row, = [line.split() for line in out.splitlines() if line.strip().startswith("panda_joint4 ")]
    assert row[1:3] == ["-3.0718", "-0.0698"]
    assert "collision geometry: 17 on 11 links (8 Box, 9 Convex)" in out
    assert "meshes: 9 collision (as convex hulls)" in out
    assert "sphere model:" in out  # a count and bound, or why not (sphere models of meshes)


def test_robots_bad_input_exits_2(capsys, tmp_path):
    assert main(["robots", _path("panda")]) == 2
    err = capsys.readouterr().err
    assert "3 tip links" in err and "panda_leftfinger" in err and "--ee-frame" in err
    assert main(["robots", _path("ur5"), "--ee-frame", "tool0", "--package", "nodir"]) == 2
    assert "NAME=DIR" in capsys.readouterr().err
    assert main(["robots", "--ee-frame", "tool0"]) == 2
    assert "PATH_OR_NAME" in capsys.readouterr().err
    path = write_arm(tmp_path / "arm", link_mesh="package://gone/link.stl")
    assert main(["robots", str(path), "--ee-frame", "hand"]) == 2
    err = capsys.readouterr().err
    assert "package://gone/link.stl" in err and "--package gone=DIR" in err


def test_robots_package_option(capsys):
    root = erd_root()
    assert main(["robots", _path("ur5"), "--ee-frame", "tool0", "--package",
                 f"example-robot-data={root}", "--check"]) == 0
    out = capsys.readouterr().out
    assert "DOF 6" in out and "max|ΔFK|" in out


def test_ik_command_end_to_end_on_a_mesh_robot(tmp_path):
    robot = drake_mh.load_robot(_path("panda"), ee_frame="panda_hand_tcp")
    q = robot.random_configurations(1, 7)[0]
    p = robot.fk(q)[:3, 3]
    env = {**os.environ, "DRAKE_MH_CACHE": os.environ["DRAKE_MH_CACHE"], "DRAKE_MH_NO_PROGRESS": "1"}
    result = subprocess.run(
        [sys.executable, "-m", "drake_mh", "ik", "--robot", _path("panda"), "--ee-frame",
         "panda_hand_tcp", "--position", *map(repr, p.tolist()), "--json"],
        capture_output=True, text=True, timeout=1800, env=env, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["success"] and len(data["q"]) == 7
    assert data["joint_names"] == [f"panda_joint{i}" for i in range(1, 8)]
    np.testing.assert_allclose(robot.fk(data["q"])[:3, 3], p, atol=1e-3)
    bad = subprocess.run(
        [sys.executable, "-m", "drake_mh", "ik", "--robot", _path("panda"), "--position", "0.4", "0",
         "0.5"], capture_output=True, text=True, timeout=1800, env=env, cwd=tmp_path)
    assert bad.returncode == 2 and "tip links" in bad.stderr and "Traceback" not in bad.stderr


def test_app_options_register_the_model_path(tmp_path):
    import argparse

    from drake_mh.cli import register_robot_options
    from drake_mh.errors import UnknownRobot

    path = str(write_arm(tmp_path / "arm"))
    register_robot_options(("panda", path), argparse.Namespace(ee_frame="hand", package=None))
    robot = drake_mh.load_robot(path)  # what the app does with the name
    assert robot.ee_frame_name == "hand" and robot.nq == 2
    with pytest.raises(UnknownRobot):
        register_robot_options(("nope.urdf",), argparse.Namespace(ee_frame=None, package=None))
    assert main(["app", "--robot", str(tmp_path / "missing.urdf"), "--max-seconds", "1"]) == 2


@pytest.mark.parametrize("method", ["hybrid", "drake_snopt"])
@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_collision_free_ik_on_mesh_robots(name, method):
    """IK with a sphere obstacle and 1 cm clearance must succeed, and its answer is checked by
    Pinocchio and coal reading the shipped meshes themselves (convex hulls by qhull; Drake cannot
    read STL): at least 1 cm from the ball, on the target."""
    from references import PinocchioCoal

    from drake_mh.ik import IKProblem, solve_ik
    from drake_mh.scene import Scene, Sphere

    robot = drake_mh.load_robot(_path(name), ee_frame=ERD_ROBOTS[name][1])
    rng = np.random.default_rng(3)
    scene = Scene(robot)
    # a target reached at a random configuration, an obstacle near the arm
    for _ in range(50):
        q_goal = robot.random_configurations(1, rng)[0]
        p_goal = robot.fk(q_goal)[:3, 3]
        if p_goal[2] > 0.2:
            break
    p_obstacle = 0.5 * p_goal + np.array([0.0, 0.0, 0.25])
    scene.add("ball", Sphere(0.06), p_obstacle)
    problem = IKProblem(robot, p_goal, scene=scene, clearance=0.01)
    result = solve_ik(problem, method, seed=0, timeout=10.0)
    assert result.success, result.message
    reference = PinocchioCoal(robot, package_dirs=[erd_root().parent])
    assert reference.ball_distance(result.q, p_obstacle, 0.06) >= 0.01 - 1e-9
    assert np.linalg.norm(reference.fk(result.q, ERD_ROBOTS[name][1])[:3, 3] - p_goal) <= 1e-3
