"""``drake-mh retime``: a path from a CSV file, retimed, certified, written for a controller."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

import drake_mh
from drake_mh.trajectories.export import load_trajectory


def _retime(*args):
    return subprocess.run([sys.executable, "-m", "drake_mh", "retime", *args], capture_output=True, text=True,
                          timeout=300)


def test_retime_reads_a_csv_with_a_header_and_writes_each_format(tmp_path):
    robot = drake_mh.load_robot("panda")
    W = np.array([robot.home, robot.home + 0.3, robot.home - 0.2])
    order = [2, 0, 1, 3, 4, 5, 6]  # columns out of the robot's order: matched by name
    lines = ["# a path", ",".join(robot.joint_names[i] for i in order)]
    lines += [",".join(repr(float(row[i])) for i in order) for row in W]
    path = tmp_path / "path.csv"
    path.write_text("\n".join(lines) + "\n")
    limits = tmp_path / "joint_limits.yaml"
    limits.write_text("joint_limits:\n  panda_joint1:\n    has_velocity_limits: true\n    max_velocity: 0.5\n")
    for suffix, method in ((".json", "toppra"), (".csv", "ruckig"), (".yaml", "toppra")):
        target = tmp_path / f"motion{suffix}"
        out = _retime(str(path), "--robot", "panda", "--method", method, "--limits", str(limits), "--out", str(target))
        assert out.returncode == 0, out.stderr
        assert f"retimed with {method}: 3 waypoints" in out.stdout and "collisions not checked" in out.stdout
        assert "user (joint_limits.yaml) on panda_joint1" in out.stdout
        samples = load_trajectory(target)
        np.testing.assert_allclose(samples.q[0], W[0], atol=1e-12)
        np.testing.assert_allclose(samples.q[-1], W[-1], atol=1e-9)
        assert np.max(np.abs(samples.qd[:, 0])) <= 0.5 * (1 + 1e-6)       # the file's limit, not the model's
        assert np.all(np.abs(samples.qd) <= robot.velocity_limits * (1 + 1e-6))
        assert np.all(np.abs(samples.tau) <= robot.effort_limits * (1 + 1e-6))
        if method == "ruckig":  # rests at the middle waypoint: it passes through it
            assert np.min(np.max(np.abs(samples.q - W[1]), axis=1)) < 1e-2


def test_bad_input_exits_2_with_one_line(tmp_path):
    path = tmp_path / "path.csv"
    path.write_text("0,0,0,-1.5,0,1.5,0\n0.1,0,0,-1.5,0,1.5\n")
    cases = [
        ((str(path), "--robot", "panda", "--out", str(tmp_path / "o.json")), "line 2: 6 values for 7 joints"),
        ((str(tmp_path / "none.csv"), "--robot", "panda", "--out", str(tmp_path / "o.json")), "cannot read the waypoints"),
        ((str(path), "--robot", "panda", "--out", str(tmp_path / "o.txt")), "unknown file type '.txt'"),
        ((str(path), "--robot", "panda", "--out", str(path / "o.json")), "is a file, not a folder"),
        ((str(path), "--robot", "panda", "--out", str(tmp_path / "o.json"), "--rate", "-5"), "rate_hz"),
    ]
    for args, words in cases:
        out = _retime(*args)
        assert out.returncode == 2 and words in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr
    header = tmp_path / "header.csv"
    header.write_text("a,b,c,d,e,f,g\n0,0,0,-1.5,0,1.5,0\n0.1,0,0,-1.5,0,1.5,0\n")
    out = _retime(str(header), "--robot", "panda", "--out", str(tmp_path / "o.json"))
    assert out.returncode == 2 and "unknown: ['a'" in out.stderr
