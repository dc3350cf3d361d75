"""The planner app without a browser: buttons and sliders driven through Meshcat's own API."""

import json
import os
import re
import signal
import subprocess
import sys

import numpy as np
import pytest
import viz_html

from drake_mh.errors import InvalidArgument, UnknownMethod
from drake_mh.viz.app import OBSTACLE_COLOUR, AppConfig, PlannerApp
from drake_mh.viz.app_controls import BUTTONS, MAX_GOAL_JOINTS, SECTIONS, joint_slider_name

FAST = dict(method="pso", budget=4000, n_points=14)


def _default_sigint():
    """In the app's process, before exec: Ctrl-C as in a terminal. A test run started as a
    background job (``cmd &`` in a script) ignores SIGINT, and a child would inherit that."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.fixture
def app(meshcat, tmp_path):
    app = PlannerApp(AppConfig(status_file=str(tmp_path / "status.json"), **FAST), meshcat=meshcat, page=False)
    yield app
    app.close()


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


def _rgb(material) -> np.ndarray:
    return np.array([(material["color"] >> s) & 0xFF for s in (16, 8, 0)]) / 255.0


def test_obstacle_is_translucent_red_unlike_the_robot(app, meshcat):
    app.move_obstacle(radius=0.15)                                   # redrawn: keeps its colour
    objects = {c["path"]: c["object"]["materials"][0] for c in viz_html.commands(meshcat.StaticHtml())
               if c["type"] == "set_object" and c["object"].get("materials")}
    obstacle = objects[app.view.obstacle_path("obstacle")]
    assert np.allclose(_rgb(obstacle), OBSTACLE_COLOUR[:3], atol=1 / 255)
    assert obstacle["transparent"] and obstacle["opacity"] == pytest.approx(OBSTACLE_COLOUR[3])
    red, green, blue = _rgb(obstacle)
    assert red > 0.8 and green < 0.2 and blue < 0.2
    robot = [_rgb(m) for path, m in objects.items() if "/robot/" in path]
    assert robot and min(np.linalg.norm(c - _rgb(obstacle)) for c in robot) > 0.3


def test_every_control_has_a_section_of_the_page(app):
    placed = [name for _, names in SECTIONS for name in names]
    joints = {joint_slider_name(i) for i in range(MAX_GOAL_JOINTS)}   # places for the goal joint sliders
    assert len(placed) == len(set(placed))
    assert set(placed) == set(BUTTONS) | set(app.controls.slider_names) | joints
    assert {joint_slider_name(i) for i in range(app.robot.nq)} <= set(app.controls.slider_names)


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
    page = re.search(r"open (http://localhost:\d+) in a browser", out.stdout).group(1)
    assert "app stopped after --max-seconds 3" in out.stdout
    state = json.loads(status.read_text())
    assert state["solutions"] and state["mode"] in ("run", "idle") and state["url"].startswith("http://localhost:")
    assert state["page_url"] == page != state["url"]
    assert state["message"].startswith("app stopped")


def test_ctrl_c_prints_the_apps_own_stop_line():
    app = subprocess.Popen([sys.executable, "-m", "drake_mh", "app", "--port", "0", "--method", "pso",
                            "--budget", "3000", "--n-points", "12", "--run"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           preexec_fn=_default_sigint)
    try:
        assert "open http://localhost:" in app.stdout.readline()
        app.send_signal(signal.SIGINT)
        out, err = app.communicate(timeout=120)
    finally:
        app.kill()
    assert app.returncode == 0, err
    assert "drake-mh app: app stopped by Ctrl-C" in out
    assert "run the same command again" not in out + err and "Traceback" not in err


def test_help_says_what_max_seconds_bounds():
    out = subprocess.run([sys.executable, "-m", "drake_mh", "app", "--help"], capture_output=True, text=True,
                         timeout=120, env={**os.environ, "COLUMNS": "200"})
    text = " ".join(out.stdout.split())
    assert re.search(r"--max-seconds S .*S seconds \(wall clock\) after it prints its URL.*until Ctrl-C", text)


@pytest.mark.parametrize("option, value", [("--seed", "-1"), ("--budget", "0"), ("--obstacle-radius", "nan")])
def test_cli_bad_numbers_exit_2_with_one_line(option, value):
    """``--seed -1`` gave "internal error: ValueError" once the app had started."""
    out = subprocess.run([sys.executable, "-m", "drake_mh", "app", option, value, "--max-seconds", "1"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and option.lstrip("-").split("-")[0] in lines[0] and "internal error" not in lines[0]


def test_help_says_which_url_to_open_and_which_port_the_page_takes():
    out = subprocess.run([sys.executable, "-m", "drake_mh", "app", "--help"], capture_output=True, text=True,
                         timeout=120, env={**os.environ, "COLUMNS": "200"})
    text = " ".join(out.stdout.split())
    assert "open http://localhost:PORT in a browser" in text
    assert "the first free port after Meshcat's" in text
    assert "next free port" not in text


def test_bad_seed_budget_and_obstacle_are_named():
    for kwargs, match in (({"seed": -1}, "seed"), ({"seed": 1.5}, "seed"), ({"budget": 0}, "budget"),
                          ({"obstacle": (0, 0)}, "obstacle"), ({"obstacle": (0, 0, float("nan"))}, "obstacle"),
                          ({"n_points": "12"}, "n_points"), ({"fps": "30"}, "fps")):
        with pytest.raises(InvalidArgument, match=match):
            AppConfig(**kwargs)


def test_cli_bad_method_exits_2():
    out = subprocess.run([sys.executable, "-m", "drake_mh", "app", "--method", "simplex", "--max-seconds", "1"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "available" in out.stderr


def test_the_robot_moves_only_along_certified_motion(app):
    """The plan's motion (detours included) is certified and Drake's exact distance at 50 configurations
    per piece agrees; a test run executes it with every motion certified when it starts."""
    app.handle("Generate / Regenerate solutions")
    state = app.state()
    assert state["motion_certified"] and state["motion_min_clearance"] >= 0 and state["motion_blocked"] == []
    assert "motion certified collision-free" in state["message"]
    f = app.follower
    s = np.linspace(0.0, 1.0, 50)[:, None]
    dense = np.vstack([a + s * (b - a) for k in range(f.n_points - 1) for a, b in zip(f.chain(k)[:-1], f.chain(k)[1:])])
    assert app.scene.exact_min_distance(dense).min() >= state["motion_min_clearance"]
    app.handle("Test run")
    for _ in range(400):
        app.tick(0.1)
        if app.mode == "idle":
            break
    state = app.state()
    assert state["message"].startswith("test run finished") and state["halted"] is None
    assert state["index"] == f.n_points - 1 and state["executed_min_clearance"] >= 0


def test_the_robot_stops_where_no_certified_motion_exists(app):
    app.handle("Generate / Regenerate solutions")
    app.handle("Run")
    app.tick(0.05)
    f = app.follower
    # the obstacle lands on the configuration the arm is leaving (no reaction asked): the motion
    # from there cannot be certified, so the arm stops instead of moving through it
    app.scene.move("obstacle", app.robot.link_poses(f.Q[f.index])["link3"][:3, 3])
    index = f.index
    for _ in range(40):
        app.tick(0.1)
        if app.mode == "idle":
            break
    state = app.state()
    assert app.mode == "idle" and state["index"] == index and "halted at point" in state["message"]
    assert state["halted"] and state["detours_failed"] >= 1


def test_scene_file_obstacles_stay_beside_the_movable_one(meshcat):
    """--scene: the file's obstacles are in every robot's scene, fixed while the obstacle moves."""
    from pathlib import Path

    from drake_mh.errors import SceneFileNotFound

    cell = Path(__file__).resolve().parents[1] / "data" / "scenes" / "cell.yaml"
    app = PlannerApp(AppConfig(robots=("panda", "seed000_6dof"), scene=str(cell), obstacle=(0.2, 0.2, 1.2), **FAST),
                     meshcat=meshcat, page=False)
    try:
        names = ["table", "ball", "post", "rail"]
        assert list(app.scene.obstacles) == names + ["obstacle"] and app.state()["scene_obstacles"] == names
        table = app.scene.obstacles["table"].X_WO.copy()
        app.move_obstacle(position=(0.3, 0.3, 1.3))
        np.testing.assert_array_equal(app.scene.obstacles["table"].X_WO, table)
        app.next_robot()
        assert app.robot.name == "seed000_6dof" and list(app.scene.obstacles) == names + ["obstacle"]
    finally:
        app.close()
    with pytest.raises(SceneFileNotFound, match="missing.yaml"):
        PlannerApp(AppConfig(scene=str(cell.with_name("missing.yaml")), **FAST), meshcat=meshcat, page=False)
