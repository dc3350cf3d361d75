"""``drake-mh plan``: one motion from the command line, verified, printed, animated on request."""

import json
import subprocess
import sys

import numpy as np
import viz_html

import drake_mh

GOAL_Q = [1.6, 0.3, 0.0, 0.0, 0.0, 0.0]


def _blocking_sphere():
    """A ball on seed000_6dof's link3 halfway along the straight joint-space line home -> GOAL_Q."""
    robot = drake_mh.load_robot("seed000_6dof")
    p = robot.link_poses(0.5 * (robot.home + np.array(GOAL_Q)))["link3"][:3, 3]
    return [f"{v:.4f}" for v in (*p, 0.06)]


def _plan(*args):
    return subprocess.run([sys.executable, "-m", "drake_mh", "plan", "--robot", "seed000_6dof", *args],
                          capture_output=True, text=True, timeout=1800)


def _drake_clearance_along(robot, path, sphere) -> float:
    """Smallest distance along the printed piecewise-linear motion (2 mrad of its fastest joint)
    by Drake's own query on a fresh plant with the ball anchored in it (capsules and a sphere
    against a ball: Drake's closed forms)."""
    from references import FreshDrake, dense_path

    from drake_mh.scene import Sphere

    X_WO = np.eye(4)
    X_WO[:3, 3] = sphere[:3]
    drake = FreshDrake(robot, [(Sphere(sphere[3]), X_WO)])
    return float(drake.min_distances(dense_path(np.asarray(path), 0.002)).min())


def test_plans_around_the_obstacle_prints_json_and_writes_the_animation(tmp_path):
    """The printed path starts at home, ends at the goal and, sampled densely, is clear of the
    ball by Drake's own query (not the planner's). (Its certified clearance is not printed: the
    printed one is the toppra motion's, a spline through the waypoints, measured 10 mm farther
    from the ball than the polyline here.)"""
    page = tmp_path / "motion.html"
    sphere = _blocking_sphere()
    out = _plan("--goal-q", *map(str, GOAL_Q), "--sphere", *sphere, "--method", "rrt_connect",
                "--json", "--html", str(page))
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["success"] and data["method"] == "rrt_connect" and data["waypoints"] >= 3
    assert data["min_clearance"] > 0 and data["obstacles"] == ["sphere0"]
    robot = drake_mh.load_robot("seed000_6dof")
    np.testing.assert_allclose(data["path"][-1], GOAL_Q, atol=1e-9)
    np.testing.assert_allclose(data["path"][0], data["q_start"])
    np.testing.assert_allclose(data["q_start"], robot.home)
    assert len(data["path"]) == data["waypoints"]
    assert _drake_clearance_along(robot, data["path"], [float(v) for v in sphere]) > 0.0
    assert "certified clearance >=" in data["caption"] and "animation written" in out.stderr
    assert viz_html.animation(page.read_text()) is not None


def test_an_uncertified_motion_exits_1_and_says_why():
    out = _plan("--goal-q", *map(str, GOAL_Q), "--sphere", *_blocking_sphere(), "--method", "straight")
    assert out.returncode == 1, out.stdout + out.stderr
    assert out.stdout.startswith("FAILED: straight: not certified")


def test_bad_input_exits_2_with_one_line():
    out = _plan("--goal-q", "1.6", "0.3")
    assert out.returncode == 2 and "goal must be configuration(s) of 6 joints" in out.stderr
    out = _plan("--goal-q", *map(str, GOAL_Q), "--method", "teleport")
    assert out.returncode == 2 and "available:" in out.stderr and "rrt_connect" in out.stderr
    out = _plan()
    assert out.returncode == 2 and "give the goal" in out.stderr
    out = _plan("--goal-q", *map(str, GOAL_Q), "--sphere", "0", "0", "0", "0.3")  # the start is inside it
    assert out.returncode == 2 and "q_start is in collision" in out.stderr


def test_show_plays_it_in_meshcat_until_max_seconds():
    out = _plan("--goal-q", *map(str, GOAL_Q), "--sphere", *_blocking_sphere(), "--show", "--max-seconds", "1")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0].startswith("verified: rrt_connect_smooth: planned in")
    assert lines[-1].startswith("showing the motion at http://localhost:") and "listening" not in out.stderr


def test_retime_ruckig_limits_the_jerk_toppra_says_it_does_not():
    base = [sys.executable, "-m", "drake_mh", "plan", "--goal-q", "1", "0", "0", "-2", "0", "2", "0.5",
            "--sphere", "0.5", "0.3", "0.3", "0.1"]
    toppra = subprocess.run(base, capture_output=True, text=True, timeout=1800)
    ruckig = subprocess.run(base + ["--retime", "ruckig", "--json"], capture_output=True, text=True, timeout=1800)
    assert toppra.returncode == 0 and "jerk not limited" in toppra.stdout, toppra.stderr
    assert ruckig.returncode == 0, ruckig.stderr
    data = json.loads(ruckig.stdout)
    assert data["jerk_limited"] is True and 0 < data["max_jerk"] <= 10000 * (1 + 1e-6)
    panda = drake_mh.load_robot("panda")
    np.testing.assert_allclose(data["path"][-1], [1, 0, 0, -2, 0, 2, 0.5], atol=1e-9)
    # ruckig moves along the printed polyline itself: its certified clearance is the polyline's
    assert _drake_clearance_along(panda, data["path"], [0.5, 0.3, 0.3, 0.1]) >= data["min_clearance"] - 1e-9


def test_out_writes_the_trajectory_and_the_limits_are_printed(tmp_path):
    from drake_mh.trajectories.export import load_trajectory

    out_file = tmp_path / "motion.json"
    out = _plan("--goal-q", *map(str, GOAL_Q), "--sphere", *_blocking_sphere(), "--method", "rrt_connect",
                "--out", str(out_file), "--rate", "50", "--velocity-scaling", "0.5")
    assert out.returncode == 0, out.stderr
    assert "limits enforced" in out.stdout and "velocity [rad/s]:" in out.stdout and "(x 0.5 scaling)" in out.stdout
    assert f"trajectory written to {out_file}" in out.stdout
    samples = load_trajectory(out_file)
    robot = drake_mh.load_robot("seed000_6dof")
    assert samples.joint_names == tuple(robot.joint_names) and samples.metadata["rate_hz"] == 50
    np.testing.assert_allclose(samples.q[-1], GOAL_Q, atol=1e-9)
    assert np.all(np.abs(samples.qd) <= 0.5 * robot.velocity_limits * (1 + 1e-6))
    assert np.all(np.abs(samples.tau) <= robot.effort_limits * (1 + 1e-6))


def test_unwritable_outputs_exit_2_before_planning(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    for option, target in (("--html", blocker / "x.html"), ("--out", blocker / "x.json"),
                           ("--out", tmp_path / "motion.txt"), ("--html", tmp_path)):
        out = _plan("--goal-q", *map(str, GOAL_Q), option, str(target))
        assert out.returncode == 2, (option, target, out.stdout, out.stderr)
        assert out.stdout == "" and len(out.stderr.strip().splitlines()) == 1 and option in out.stderr, out.stderr
    out = _plan("--goal-q", *map(str, GOAL_Q), "--acceleration-scaling", "0")
    assert out.returncode == 2 and "acceleration_scaling must be a number in (0, 1]" in out.stderr


def test_scene_file_obstacles_join_the_problem(tmp_path):
    """--scene FILE adds the file's obstacles (with --sphere); a bad file or --scene with --set exits 2
    with one line naming the file and the entry."""
    from pathlib import Path

    cell = Path(__file__).resolve().parents[1] / "data" / "scenes" / "cell.yaml"
    out = _plan("--goal-q", *map(str, GOAL_Q), "--scene", str(cell), "--sphere", "2", "2", "2", "0.1",
                "--method", "rrt_connect", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["success"] and data["obstacles"] == ["table", "ball", "post", "rail", "sphere0"]
    bad = tmp_path / "bad.yaml"
    bad.write_text("obstacles:\n  - {name: lamp, shape: sphere, radius: 0.1}\n")
    out = _plan("--goal-q", *map(str, GOAL_Q), "--scene", str(bad))
    assert out.returncode == 2 and f"scene file {bad}, obstacle 1 ('lamp'): a sphere needs position" in out.stderr
    assert "Traceback" not in out.stderr
    out = _plan("--set", "cage", "--scene", str(cell))
    assert out.returncode == 2 and "--scene does not combine with --set" in out.stderr
