"""examples/plan_and_export.py: a shipped URDF to a controller-ready JSON, checked independently."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from references import FreshPlant
from robot_fixtures import erd_root

from drake_mh.trajectories.export import load_trajectory

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plan_and_export.py"


def _example_module():
    spec = importlib.util.spec_from_file_location("plan_and_export", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_the_example_writes_a_json_within_limits_and_clear_of_the_cell(tmp_path):
    erd_root()
    out = subprocess.run([sys.executable, str(EXAMPLE), "--out", str(tmp_path), "--rate", "1000"],
                         capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "straight joint-space line free: False" in out.stdout
    assert "declared (panda.urdf) on all 7 joints" in out.stdout and "bounded through the torque limits" in out.stdout
    assert (tmp_path / "motion.html").stat().st_size > 100_000
    samples = load_trajectory(tmp_path / "motion.json")
    example = _example_module()
    robot = example.load_panda()
    assert samples.joint_names == tuple(robot.joint_names) and len(samples) > 200
    np.testing.assert_allclose(samples.q[0], example.START, atol=1e-12)
    np.testing.assert_allclose(samples.q[-1], example.GOAL, atol=1e-9)
    # within the limits the file states, which are the URDF's as shipped
    limits = samples.metadata["limits"]
    assert limits["velocity"]["values"] == robot.velocity_limits.tolist()
    assert limits["effort"]["values"] == robot.effort_limits.tolist()
    assert np.all(samples.q >= robot.lower) and np.all(samples.q <= robot.upper)
    assert np.all(np.abs(samples.qd) <= robot.velocity_limits * (1 + 1e-6))
    reference = FreshPlant(robot, [(kind, size, centre) for _, kind, size, centre in example.CELL])
    tau = reference.torques(samples.q, samples.qd, samples.qdd)  # Drake's, not the file's
    np.testing.assert_allclose(samples.tau, tau, rtol=0, atol=1e-8)
    assert np.all(np.abs(tau) <= robot.effort_limits * (1 + 1e-6))
    # clear of the cell: Drake's signed distances on the fresh plant, every 1 ms of the motion
    distances = np.array([reference.min_distance(q) for q in samples.q])
    assert np.min(distances) > 0.0, np.min(distances)
