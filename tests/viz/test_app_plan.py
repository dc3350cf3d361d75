"""The app's point-to-point planning (section 8), headless: buttons and sliders through Meshcat's API."""

import json
import subprocess
import sys
import time

import numpy as np
import pytest

from drake_mh.errors import InvalidArgument, InvalidConfiguration, UnknownMethod
from drake_mh.viz.app import AppConfig, PlannerApp

FAST = dict(method="pso", budget=4000, n_points=14)
GOAL_Q = (1.6, 0.3, 0.0, 0.0, 0.0, 0.0)        # seed000_6dof: the arm swings a quarter turn and up


@pytest.fixture
def app(meshcat, tmp_path):
    app = PlannerApp(AppConfig(status_file=str(tmp_path / "status.json"), **FAST), meshcat=meshcat, page=False)
    yield app
    app.close()


def _set_goal_q(meshcat, app, q):
    for i, v in enumerate(q):
        meshcat.SetSliderValue(f"Goal joint {i + 1}", float(v))
    app.tick(0.02)


HANG_SECONDS = 1800.0
"""[s] how long a plan may take before the test calls it hung: from an empty kernel cache the app's
first plan compiles its kernels for minutes (the wait ends as soon as planning does)."""


def _plan(app, button, seconds=HANG_SECONDS):
    """Presses a Plan button and ticks until planning ends; returns the shown configurations of the
    motion that follows (ticks of 50 ms)."""
    app.handle(button)
    return _play(app, seconds)


def _play(app, seconds=HANG_SECONDS):
    """Ticks until planning ends, then through the motion; returns the configurations shown."""
    deadline = time.monotonic() + seconds
    while app.planner.busy and time.monotonic() < deadline:
        app.tick(0.02)
        time.sleep(0.005)
    assert not app.planner.busy, "planning did not end"
    shown = []
    for _ in range(2000):
        if app.mode != "plan":
            break
        app.tick(0.05)
        shown.append(app.view.q.copy())
    return np.array(shown).reshape(-1, app.robot.nq)


def _block_the_straight_line(app, goal):
    """A small obstacle on the arm halfway along the straight joint-space line home -> goal."""
    middle = 0.5 * (app.view.q + np.asarray(goal))
    app.move_obstacle(radius=0.06)
    app.move_obstacle(position=app.robot.link_poses(middle)["link3"][:3, 3])
    assert app.scene.collision_free(np.vstack([app.view.q, goal])).all()


def test_plan_to_goal_joints_moves_along_the_certified_motion_to_the_goal(app, meshcat, tmp_path):
    start = app.view.q.copy()
    _block_the_straight_line(app, GOAL_Q)
    _set_goal_q(meshcat, app, GOAL_Q)
    np.testing.assert_allclose(app.planner.goal_q, GOAL_Q)
    app.handle("Plan to goal joints")
    assert app.planner.busy and app.mode == "planning"          # in the background: the loop goes on
    assert app.state()["planning"] and "planning with rrt_connect_smooth" in app.message
    shown = _play(app)
    state = app.state()
    plan = state["plan"]
    assert plan["success"] and plan["method"] == "rrt_connect_smooth" and plan["goal"] == "joints"
    assert plan["waypoints"] >= 3                                # a detour: the straight line is blocked
    assert plan["min_clearance"] > 0 and "certified clearance >=" in state["message"]
    assert "(bound over the whole motion), sampled minimum" in state["message"]  # each figure labelled
    assert state["message"].startswith("at the goal joints") and app.mode == "idle"
    np.testing.assert_allclose(app.view.q, GOAL_Q, atol=1e-12)  # the shown robot ends at the goal
    np.testing.assert_allclose(state["q"], GOAL_Q, atol=1e-12)
    # every shown configuration lies on the verified trajectory, clear of the obstacle
    assert len(shown) >= 5 and not np.allclose(shown[0], start)
    assert app.scene.collision_free(shown).all()
    assert app.scene.exact_min_distance(shown).min() >= plan["min_clearance"] - 1e-9
    app.write_status()
    written = json.loads((tmp_path / "status.json").read_text())
    assert written["plan"]["success"] and written["plan_goal_q"] == pytest.approx(list(GOAL_Q))


def test_plan_to_goal_pose_reaches_the_point_keeping_the_tool_orientation(app, meshcat):
    R_start = app.robot.fk(app.view.q)[:3, :3]
    for axis, value in zip("XYZ", (0.9, 0.5, 0.3)):
        meshcat.SetSliderValue(f"Goal {axis} [m]", value)
    app.tick(0.02)
    _plan(app, "Plan to goal pose")
    state = app.state()
    assert state["plan"]["success"] and state["plan"]["goal"] == "pose", state["message"]
    X = app.robot.fk(app.view.q)
    np.testing.assert_allclose(X[:3, 3], (0.9, 0.5, 0.3), atol=2e-3)
    assert np.linalg.norm(X[:3, :3] - R_start) < 3e-2


def test_no_collision_free_goal_leaves_the_robot_where_it_was(app, meshcat):
    start = app.view.q.copy()
    app.move_obstacle(position=app.robot.link_poses(np.array(GOAL_Q))["link3"][:3, 3])
    _set_goal_q(meshcat, app, GOAL_Q)
    shown = _plan(app, "Plan to goal joints")
    state = app.state()
    assert len(shown) == 0 and app.mode == "idle" and not state["plan"]["success"]
    assert "cannot plan to the goal joints" in state["message"] and "collision" in state["message"]
    assert state["message"].endswith("the robot stays where it is")
    np.testing.assert_array_equal(app.view.q, start)


def test_an_uncertified_path_is_never_played(app, meshcat):
    """The straight line through the obstacle: found, rejected by the verification, not played."""
    start = app.view.q.copy()
    _block_the_straight_line(app, GOAL_Q)
    _set_goal_q(meshcat, app, GOAL_Q)
    while app.planner.method != "straight":
        app.handle("Next planner")
    shown = _plan(app, "Plan to goal joints")
    state = app.state()
    assert len(shown) == 0 and not state["plan"]["success"] and state["plan"]["method"] == "straight"
    assert "straight:" in state["message"] and "stays where it is" in state["message"]
    assert "not certified" in state["message"] or "no path" in state["message"]
    np.testing.assert_array_equal(app.view.q, start)


def test_stop_and_a_moved_obstacle_halt_the_motion_on_the_way(app, meshcat):
    _set_goal_q(meshcat, app, GOAL_Q)
    app.handle("Plan to goal joints")
    app.planner._thread.join(15)
    app.tick(0.02)                                               # collects the result: the motion starts
    assert app.mode == "plan"
    app.tick(0.1)
    app.handle("Stop")
    stopped = app.view.q.copy()
    assert app.mode == "idle" and "stopped" in app.message and not np.allclose(stopped, GOAL_Q)
    app.tick(0.1)
    np.testing.assert_array_equal(app.view.q, stopped)           # stays there
    # again from there; the obstacle moves while the arm is on its way: it halts
    app.handle("Plan to goal joints")
    app.planner._thread.join(15)
    app.tick(0.02)
    app.tick(0.05)
    meshcat.SetSliderValue("Obstacle Z [m]", 1.2)
    app.tick(0.05)
    halted = app.view.q.copy()
    assert app.mode == "idle" and "the obstacle moved" in app.message
    app.tick(0.1)
    np.testing.assert_array_equal(app.view.q, halted)


def test_planner_choice_timeout_and_setup_line(app, meshcat):
    first = app.planner.method
    app.handle("Next planner")
    assert app.planner.method != first and "planner" in app.message
    meshcat.SetSliderValue("Plan timeout [s]", 2.5)
    app.tick(0.02)
    assert app.state()["plan_timeout"] == 2.5
    app.run(max_seconds=0.05)
    assert any(f"planner {app.planner.method}, 2.5 s" in n for n in meshcat.GetButtonNames())


def test_next_robot_gets_its_own_joint_sliders(app, meshcat):
    app.handle("Next robot")                                     # seed000_6dof -> panda
    names = set(meshcat.GetSliderNames())
    assert {f"Goal joint {i}" for i in range(1, 8)} <= names and "Goal joint 8" not in names
    np.testing.assert_allclose(app.planner.goal_q, app.robot.home)
    assert meshcat.GetSliderValue("Goal joint 4") == pytest.approx(app.robot.home[3], abs=0.01)


def test_bad_planning_settings_say_how_to_fix():
    with pytest.raises(UnknownMethod, match="available"):
        AppConfig(plan_method="teleport")
    with pytest.raises(InvalidArgument, match="plan_timeout"):
        AppConfig(plan_timeout=0)
    with pytest.raises(InvalidArgument, match="goal must be a point"):
        AppConfig(goal=(1.0, 2.0))
    with pytest.raises(InvalidArgument, match="plan_clearance"):
        AppConfig(plan_clearance=-0.1)


def test_bad_goal_configuration(meshcat):
    with pytest.raises(InvalidConfiguration, match="goal_q"):
        PlannerApp(AppConfig(goal_q=(0.0, 1.0), **FAST), meshcat=meshcat, page=False)
    with pytest.raises(InvalidArgument, match="outside its limits"):
        PlannerApp(AppConfig(goal_q=(9.0, 0, 0, 0, 0, 0), **FAST), meshcat=meshcat, page=False)


def test_cli_plans_at_start_and_plays_the_motion(tmp_path):
    status = tmp_path / "app.json"
    out = subprocess.run([sys.executable, "-m", "drake_mh", "app", "--port", "0", "--max-seconds", "8",
                          "--method", "pso", "--plan", "joints", "--goal-q", *map(str, GOAL_Q),
                          "--plan-method", "rrt_connect", "--status-file", str(status)],
                         capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stderr
    state = json.loads(status.read_text())
    assert state["plan"]["success"] and state["plan"]["method"] == "rrt_connect", state
    np.testing.assert_allclose(state["q"], GOAL_Q, atol=1e-9, err_msg=str(state))
    assert state["mode"] == "idle" and state["message"].startswith("app stopped")


def test_a_timeout_is_told_as_such(app):
    """The verdict's wording for a planner that ran out of time (its result, as solve_motion gives it)."""
    from drake_mh.planning import MotionResult

    start = app.view.q.copy()
    app.planner.kind = "joints"
    app.planner._finish(MotionResult("mh_pso", success=False, path=None, planning_time=app.planner.timeout + 0.01,
                                     message="deadline reached"))
    assert app.message == f"mh_pso: no path within the timeout ({app.planner.timeout:g} s); the robot stays where it is"
    app.planner._finish(MotionResult("rrt_connect", success=False, path=None, planning_time=0.01,
                                     message="budget exhausted"))
    assert app.message.startswith("rrt_connect: no path found (budget exhausted)")
    assert app.mode == "idle" and app.planner.result is None
    np.testing.assert_array_equal(app.view.q, start)


def test_stop_cancels_planning_and_other_clicks_wait(app, meshcat, monkeypatch):
    """While the planner runs, 'Stop' drops its answer; another button waits until planning ends."""
    import threading

    import drake_mh.planning

    release = threading.Event()
    real = drake_mh.planning.solve_motion

    def slow(*args, **kwargs):
        release.wait(10)
        return real(*args, **kwargs)

    monkeypatch.setattr(drake_mh.planning, "solve_motion", slow)
    start, method = app.view.q.copy(), app.planner.method
    _set_goal_q(meshcat, app, GOAL_Q)
    app.handle("Plan to goal joints")
    assert app.planner.busy
    clicks = iter([["Stop", "Next planner"]])
    monkeypatch.setattr(app.controls, "clicked", lambda: next(clicks, []))   # two clicks while it plans
    app.tick(0.02)
    assert app.planner.busy and "cancelled" in app.message and app.planner.deferred == ["Next planner"]
    assert app.planner.method == method
    release.set()
    app.planner._thread.join(15)
    app.tick(0.02)                                            # the answer is dropped
    assert app.mode == "idle" and "planning cancelled with Stop" in app.message
    np.testing.assert_array_equal(app.view.q, start)
    app.tick(0.02)                                            # then the waiting click is answered
    assert app.planner.method != method and app.planner.deferred == []


def test_clicks_after_a_plan_click_wait_for_it(app, monkeypatch):
    """'Plan' then 'Next robot' in the same frame: the robot is not swapped under the planner."""
    monkeypatch.setattr(app.controls, "clicked", lambda: ["Plan to goal joints", "Next robot"])
    app.tick(0.02)
    assert app.planner.deferred == ["Next robot"] and app.robot_name == "seed000_6dof"
