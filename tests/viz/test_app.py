"""The planner app without a browser: buttons and sliders driven through Meshcat's own API."""

import json
import re
import subprocess
import sys

import numpy as np
import pytest

from drake_mh.errors import InvalidArgument, UnknownMethod
from drake_mh.viz.app import AppConfig, PlannerApp
from drake_mh.viz.app_controls import BUTTONS

FAST = dict(method="pso", budget=4000, n_points=14)


@pytest.fixture
def app(meshcat, tmp_path):
    return PlannerApp(AppConfig(status_file=str(tmp_path / "status.json"), **FAST), meshcat=meshcat)


def test_controls_exist(app, meshcat):
    names = meshcat.GetButtonNames()
    assert all(b in names for b in BUTTONS)
    assert {"Obstacle X [m]", "Obstacle Y [m]", "Obstacle Z [m]", "Points in path", "Point X [m]"} <= set(
        meshcat.GetSliderNames())
    app.run(max_seconds=0.05)
    assert any(n.startswith("Status: ") for n in meshcat.GetButtonNames())
    assert any(n.startswith("Setup: seed000_6dof | pso") for n in meshcat.GetButtonNames())


def test_generate_run_and_move_the_obstacle_live(app, meshcat, tmp_path):
    app.handle("Generate / Regenerate solutions")
    assert app.follower is not None and app.follower.plan_failed.size == 0
    first = app.state()["plan_hash"]
    app.handle("Run")
    for _ in range(5):
        app.tick(0.05)
    assert app.mode == "run" and app.follower.index >= 0
    # the obstacle slider moves onto the elbow of a future configuration: regeneration
    k = min(app.follower.index + 6, app.follower.n_points - 1)
    target = app.robot.link_poses(app.follower.Q[k])["link3"][:3, 3]
    for axis, value in zip("XYZ", np.round(target, 2)):
        meshcat.SetSliderValue(f"Obstacle {axis} [m]", float(value))
    app.tick(0.05)
    state = app.state()
    assert np.allclose(state["obstacle"], np.round(target, 2))
    assert state["events"] >= 1 and state["regenerated_total"] >= 1 and state["plan_hash"] != first
    app.run(max_seconds=0.05)
    written = json.loads((tmp_path / "status.json").read_text())
    assert written["events"] == state["events"] and written["solutions"]
    app.handle("Stop")
    assert app.mode == "idle"


def test_path_sliders_and_cycling_buttons(app, meshcat):
    app.handle("Generate / Regenerate solutions")
    meshcat.SetSliderValue("Points in path", 20)
    app.tick(0.05)
    assert app.follower is None and len(app.path.points) == 20       # a new path needs new solutions
    app.handle("Edit next point")
    assert app.state()["editing"] == "via 1" and meshcat.GetSliderValue("Point X [m]") == pytest.approx(1.0)
    meshcat.SetSliderValue("Point X [m]", 0.9)
    app.tick(0.05)
    assert app.points[1, 0] == pytest.approx(0.9) and 0.9 in np.round(app.path.points[:, 0], 6)
    method = app.method
    app.handle("Next algorithm")
    assert app.method != method
    app.handle("Test run")
    assert "Generate" in app.message                                # no solutions: says what to do
    app.handle("Show environment")


def test_bad_configuration_says_how_to_fix():
    with pytest.raises(UnknownMethod, match="available"):
        AppConfig(method="simplex")
    with pytest.raises(InvalidArgument, match="4 finite"):
        AppConfig(points=((0, 0, 0),))
    with pytest.raises(InvalidArgument, match="n_points"):
        AppConfig(n_points=2)


def test_cli_runs_headless_and_exits(tmp_path):
    status = tmp_path / "app.json"
    out = subprocess.run([sys.executable, "-m", "drake_mh", "app", "--port", "0", "--max-seconds", "3", "--run",
                          "--method", "pso", "--budget", "3000", "--n-points", "12", "--status-file", str(status)],
                         capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stderr
    assert re.search(r"open http://localhost:\d+ in a browser", out.stdout)
    state = json.loads(status.read_text())
    assert state["solutions"] and state["mode"] in ("run", "idle") and state["url"].startswith("http://localhost:")


def test_cli_bad_method_exits_2():
    out = subprocess.run([sys.executable, "-m", "drake_mh", "app", "--method", "simplex", "--max-seconds", "1"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "available" in out.stderr
