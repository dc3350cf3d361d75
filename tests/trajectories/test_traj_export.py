"""Trajectories that leave Python: samples, JointTrajectory JSON/YAML, CSV, Drake polynomials."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from references import FreshPlant
from traj_helpers import random_waypoints

from drake_mh.errors import InvalidArgument, InvalidTrajectory, LimitViolation
from drake_mh.trajectories import retime
from drake_mh.trajectories.export import load_trajectory, sample_times


@pytest.fixture(scope="module", params=["toppra", "ruckig", "drake-toppra"])
def trajectory(request, panda):
    W = random_waypoints(panda, np.random.default_rng(8), k=4, spread=0.6)
    return retime(W, panda, request.param, gridpoints=60)


def test_samples_at_a_rate_end_exactly_at_the_end_with_drakes_torques(trajectory, panda):
    s = trajectory.sample(100, panda)
    assert s.t[0] == 0.0 and s.t[-1] == trajectory.duration and np.all(np.diff(s.t) > 0)
    assert np.allclose(np.diff(s.t)[:-1], 0.01, rtol=0, atol=1e-12) and np.diff(s.t)[-1] <= 0.01 + 1e-12
    assert len(s) == int(np.ceil(trajectory.duration * 100 - 1e-9)) + 1
    np.testing.assert_array_equal(s.q, trajectory.position(s.t))
    np.testing.assert_array_equal(s.qd, trajectory.velocity(s.t))
    np.testing.assert_array_equal(s.qdd, trajectory.acceleration(s.t))
    np.testing.assert_allclose(s.tau, FreshPlant(panda).torques(s.q, s.qd, s.qdd), rtol=0, atol=1e-9)
    assert s.joint_names == tuple(panda.joint_names) and trajectory.sample(50).tau is None


def test_sample_times_for_whole_and_fractional_periods():
    assert sample_times(0.03, 100).tolist() == [0.0, 0.01, 0.02, 0.03]
    t = sample_times(0.0305, 100)
    assert t.tolist() == [0.0, 0.01, 0.02, 0.03, 0.0305]
    with pytest.raises(InvalidArgument, match="rate_hz"):
        sample_times(1.0, 0)


@pytest.mark.parametrize("suffix", [".json", ".yaml", ".yml", ".csv"])
def test_every_format_round_trips(trajectory, panda, tmp_path, suffix):
    path = tmp_path / f"motion{suffix}"
    written = trajectory.save(path, panda, rate_hz=50)
    loaded = load_trajectory(path)
    assert loaded.joint_names == written.joint_names
    np.testing.assert_allclose(loaded.t, written.t, rtol=0, atol=1e-9)  # sec + nanosec: 1 ns
    for key in ("q", "qd", "qdd", "tau"):
        np.testing.assert_allclose(getattr(loaded, key), getattr(written, key), rtol=1e-15, atol=0)
    if suffix != ".csv":
        assert loaded.metadata["limits"]["velocity"]["sources"] == ["declared"] * 7
        assert loaded.metadata["robot"] == "panda" and loaded.metadata["rate_hz"] == 50


def test_the_json_is_shaped_like_a_ros2_joint_trajectory(trajectory, panda, tmp_path):
    path = tmp_path / "motion.json"
    trajectory.save(path, panda)
    data = json.loads(path.read_text())
    assert data["joint_names"] == list(panda.joint_names) and "header" not in data
    point = data["points"][-1]
    assert set(point) == {"positions", "velocities", "accelerations", "effort", "time_from_start"}
    stamp = point["time_from_start"]
    assert isinstance(stamp["sec"], int) and 0 <= stamp["nanosec"] < 10**9
    assert abs(stamp["sec"] + stamp["nanosec"] * 1e-9 - trajectory.duration) <= 0.5e-9
    assert np.allclose(point["velocities"], 0.0, atol=1e-9)  # at rest at the end
    trajectory.save(tmp_path / "motion.yaml", panda)
    assert yaml.safe_load((tmp_path / "motion.yaml").read_text())["points"][-1] == point  # the same message
    csv_path = tmp_path / "motion.csv"
    trajectory.save(csv_path, panda)
    header = csv_path.read_text().splitlines()[0].split(",")
    assert header[:2] == ["time", "panda_joint1_pos"] and header[-1] == "panda_joint7_eff" and len(header) == 29


def test_to_drake_is_the_same_trajectory(trajectory):
    pp = trajectory.to_drake()
    assert pp.start_time() == trajectory.start_time and pp.end_time() == trajectory.end_time
    t = np.random.default_rng(0).uniform(trajectory.start_time, trajectory.end_time, 400)
    for k, reference in enumerate((trajectory.position, trajectory.velocity, trajectory.acceleration)):
        drake = np.array([pp.EvalDerivative(ti, k).ravel() for ti in t])
        scale = np.max(np.abs(reference(t))) + 1.0
        np.testing.assert_allclose(drake, reference(t), rtol=0, atol=1e-10 * scale)


def test_export_refuses_samples_outside_the_certified_limits(panda, tmp_path):
    W = random_waypoints(panda, np.random.default_rng(9), k=3)
    traj = retime(W, panda, gridpoints=60)
    table = traj.info["enforced_limits"].copy()
    table.set("velocity", 0.5 * np.asarray(table["velocity"]), "user", "tightened by the test")
    traj.info["enforced_limits"] = table
    with pytest.raises(LimitViolation, match=r"velocity limit at t = .* exported samples"):
        traj.save(tmp_path / "motion.json", panda)
    assert not (tmp_path / "motion.json").exists()


def test_bad_files_and_extensions_say_what_is_wrong(trajectory, panda, tmp_path):
    with pytest.raises(InvalidArgument, match=r"unknown trajectory file extension '\.txt'.*\.json"):
        trajectory.save(tmp_path / "motion.txt", panda)
    with pytest.raises(InvalidArgument, match="unknown trajectory file extension"):
        load_trajectory(tmp_path / "motion.bin")
    cases = {"a.json": "{\"joint_names\": [\"a\"]}", "b.json": "not json",
             "c.yaml": "joint_names: [a]\npoints:\n- {positions: [1, 2], velocities: [0], accelerations: [0],"
                       " time_from_start: {sec: 0, nanosec: 0}}\n",
             "d.csv": "time,a_pos,a_vel\n0,1,2\n",
             "e.json": json.dumps({"joint_names": ["a"], "points": [
                 {"positions": [0], "velocities": [0], "accelerations": [0], "time_from_start": {"sec": 1, "nanosec": 0}},
                 {"positions": [0], "velocities": [0], "accelerations": [0], "time_from_start": {"sec": 0, "nanosec": 5}}]})}
    words = {"a.json": "'points'", "b.json": "not valid JSON", "c.yaml": "'positions' must list 1 numbers",
             "d.csv": "header", "e.json": "times must increase"}
    for name, text in cases.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(InvalidTrajectory) as err:
            load_trajectory(tmp_path / name)
        assert name in str(err.value) and words[name] in str(err.value), str(err.value)
