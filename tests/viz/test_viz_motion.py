"""Animating a planned motion (MotionResult) with its certified clearance."""

from __future__ import annotations

import numpy as np
import pytest
import viz_html

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.planning import MotionProblem, solve_motion
from drake_mh.viz import motion_caption, motion_html, show_motion
from drake_mh.viz.motion import motion_samples

GOAL_Q = np.array([1.6, 0.3, 0.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def planned():
    """seed000_6dof around a small ball halfway along the straight line: a verified detour."""
    robot = drake_mh.load_robot("seed000_6dof")
    scene = drake_mh.Scene(robot)
    middle = 0.5 * (robot.home + GOAL_Q)
    scene.add("ball", drake_mh.Sphere(0.06), robot.link_poses(middle)["link3"][:3, 3])
    problem = MotionProblem(robot, scene, robot.home, GOAL_Q)
    result = solve_motion(problem, "rrt_connect", seed=0, timeout=10)
    assert result.success, result.message
    return problem, result


def test_show_motion_animates_the_retimed_trajectory_to_the_goal(meshcat, planned):
    problem, result = planned
    view = show_motion(problem, result, meshcat=meshcat, fps=20)
    anim = viz_html.animation(view.html())
    link = view.link_paths()["link3"]
    frames, p = viz_html.track(anim, link, ".position")
    expected = int(np.ceil(result.duration * 20)) + 1
    assert frames.size == expected and expected >= 10
    np.testing.assert_allclose(p[0], problem.robot.link_poses(problem.q_start)["link3"][:3, 3], atol=1e-9)
    np.testing.assert_allclose(p[-1], problem.robot.link_poses(GOAL_Q)["link3"][:3, 3], atol=1e-9)
    t, Q = motion_samples(result, 20)
    assert t.size == expected and problem.scene.collision_free(Q).all()


def test_the_clearance_is_shown_at_the_closest_frame(meshcat, planned):
    problem, result = planned
    view = show_motion(problem, result, meshcat=meshcat)
    objects = viz_html.objects(view.html())
    label = f"closest_{result.min_clearance * 1e3:.1f}_mm_certified"
    assert any(f"/ghosts/{label}/" in path for path in objects), label
    assert any("/distances/" in path for path in objects)
    t, Q = motion_samples(result)
    assert problem.scene.exact_min_distance(Q).min() >= result.min_clearance - 1e-9
    caption = motion_caption(result)
    assert caption.startswith("rrt_connect: planned in") and f"{result.min_clearance * 1e3:.1f} mm" in caption


def test_the_caption_shows_the_certified_bound_beside_the_sampled_minimum(planned):
    """"certified clearance >= 0.0 mm" alone said nothing useful about a motion that passed 8 mm
    away (the bound is the sphere model's): the sampled figure stands beside it, each labelled."""
    import re

    problem, result = planned
    caption = motion_caption(result, problem.scene)
    bound, sampled = (float(x) for x in re.search(
        r"certified clearance >= ([\d.]+) mm \(bound over the whole motion\), sampled minimum ([\d.]+) mm "
        r"\(exact distance at 60 configurations\)", caption).groups())
    t = np.linspace(result.trajectory.start_time, result.trajectory.end_time, 60)
    exact = problem.scene.exact_min_distance(result.trajectory.position(t)).min()
    assert sampled == pytest.approx(exact * 1e3, abs=0.051) and bound <= sampled
    assert "sampled" not in motion_caption(result)  # no scene: the bound alone, labelled


def test_report_page_is_recorded_without_the_shared_server(planned):
    problem, result = planned
    html = motion_html(problem, result, fps=10)
    anim = viz_html.animation(html)
    assert anim is not None and len(html) > 1_000_000


def test_uncertified_results_are_not_animated(meshcat, planned):
    problem, result = planned
    failed = drake_mh.planning.MotionResult("straight", success=False, message="segment 0 not certified")
    with pytest.raises(InvalidArgument, match="only verified motions.*segment 0 not certified"):
        show_motion(problem, failed, meshcat=meshcat)
    with pytest.raises(InvalidArgument, match="only verified motions"):
        motion_html(problem, failed)
    assert "not certified" in motion_caption(failed)
    with pytest.raises(InvalidArgument, match="MotionProblem"):
        show_motion("panda", result, meshcat=meshcat)
    with pytest.raises(InvalidArgument, match="fps"):
        motion_samples(result, fps=0)


def test_motion_benchmark_attaches_this_page(planned):
    """studies/motion_benchmark.py animates its motions with motion_html (one code path)."""
    import sys
    from pathlib import Path

    from drake_mh.study import load_study

    study, _ = load_study(Path(__file__).resolve().parents[2] / "studies" / "motion_benchmark.py")
    module = sys.modules[study.run.__module__]
    attached = {}

    class Case:
        def attach(self, name, content):
            attached[name] = content

    problem, result = planned
    assert module._animate(Case(), problem, result) == "attached"
    objects = viz_html.objects(attached["motion.html"])
    assert any("/ghosts/closest_" in path for path in objects)
