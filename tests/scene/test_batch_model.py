"""The sphere model as the kernels read it (scene/batch.py): every link's bounding capsule and
sphere groups contain the spheres they stand for, on the Panda with its hand (778 spheres)."""

import numpy as np
import pytest

from drake_mh.planning.problems import load_problem_robot
from drake_mh.scene import Scene


@pytest.fixture(scope="module")
def scene():
    return Scene(load_problem_robot("panda_hand_mbm"), self_collision=True)


def test_bounding_capsules_contain_their_links_spheres(scene):
    from drake_mh.scene.batch import bounding_capsules

    model = scene.collision_model
    _, _, _, start, offsets, radii = model.model_arrays
    caps = bounding_capsules(offsets, radii, start)
    for g in range(model.num_links):
        c, r = offsets[start[g]:start[g + 1]], radii[start[g]:start[g + 1]]
        a, b, radius = caps[g, :3], caps[g, 3:6], caps[g, 6]
        d = b - a
        t = np.clip((c - a) @ d / max(d @ d, 1e-300), 0.0, 1.0)
        assert np.all(np.linalg.norm(c - (a + t[:, None] * d), axis=1) + r <= radius + 1e-12)


def test_sphere_groups_hold_their_spheres(scene):
    model = scene.collision_model
    _, _, _, start, offsets, radii = model.model_arrays
    g_ustart, u_start, u_offset, u_radius = model.group_arrays
    assert g_ustart[0] == 0 and g_ustart[-1] == len(u_radius) and u_start[-1] == len(radii)
    for g in range(model.num_links):
        u0, u1 = g_ustart[g], g_ustart[g + 1]
        assert u_start[u0] == start[g] and u_start[u1] == start[g + 1]  # the link's spheres, all of them
        for u in range(u0, u1):
            s0, s1 = u_start[u], u_start[u + 1]
            assert 1 <= s1 - s0 <= 16
            d = np.linalg.norm(offsets[s0:s1] - u_offset[u], axis=1) + radii[s0:s1]
            assert np.all(d <= u_radius[u] + 1e-12)


@pytest.mark.parametrize("robot_name", ["panda", "panda_hand_mbm"])
def test_overall_clearance_is_the_smallest_per_obstacle(robot_name):
    """batch_min_distance's kernel mode over all obstacles skips (link, obstacle) pairs that
    cannot go below the smallest value so far: its values equal the per-obstacle values'
    minimum exactly, shallow and penetrating configurations alike, and batch_min_distance
    equals the corrected per-obstacle minimum."""
    import drake_mh
    from drake_mh.scene.benchmark import benchmark_scene

    robot = drake_mh.load_robot("panda") if robot_name == "panda" else load_problem_robot(robot_name)
    scene = benchmark_scene(robot, "10 mixed")
    Q = robot.random_configurations(300, rng=11)
    function = scene.collision_model.obstacle_clearance_function(scene.obstacle_arrays)
    per_obstacle, overall = function(Q), function(Q, overall=True)
    assert overall.shape == (300, 1)
    np.testing.assert_array_equal(overall[:, 0], per_obstacle.min(axis=1))
    assert 0 < np.sum(overall < 0) < 300  # both kinds of configuration are covered
    np.testing.assert_array_equal(scene.batch_min_distance(Q), scene.batch_obstacle_distances(Q).min(axis=1))
    assert function(np.full((2, robot.nq), np.nan)) is None


@pytest.mark.parametrize("prismatic_every", [0, 1, 2])
def test_reach_balls_hold_every_links_bounding_centre(prismatic_every):
    """The static gaps stand on these balls: random chains with arbitrary axes, prismatic joints
    (the root one too) and a side branch, configurations at random and at the joint limits."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from random_models import random_chain_urdf

    from drake_mh.robot import Robot

    for seed in range(3):
        robot = Robot(random_chain_urdf(5, seed, prismatic_every=prismatic_every, branch=True), ee_frame="tip")
        model = Scene(robot).collision_model
        centre, radius = model.reach_balls
        g_anchor, g_offset = model.model_arrays[:2]
        rng = np.random.default_rng(seed)
        Q = np.vstack([robot.random_configurations(500, rng=seed),
                       np.where(rng.random((500, robot.nq)) < 0.5, robot.lower, robot.upper)])
        C = robot.batch.points(Q, g_anchor, g_offset)  # (N, G, 3)
        assert np.all(np.linalg.norm(C - centre, axis=2) <= radius + 1e-9)


def test_static_gaps_change_no_answer(scene):
    """collision_free with the static gaps as built and with none (every pair tested)."""
    from drake_mh.scene.kernels import entry as E
    from drake_mh.scene.benchmark import benchmark_scene

    bench = benchmark_scene(scene.robot, "10 mixed")
    model, obstacles = bench.collision_model, bench.obstacle_arrays
    gaps = model.static_gaps(obstacles)
    assert 0.2 < np.mean(gaps > 0.0) < 1.0  # the links near the base never reach some obstacles
    Q = scene.robot.random_configurations(2048, rng=3)
    answers = []
    for skip in (True, False):
        if not skip:
            model.static_gaps = lambda obstacles: np.full(gaps.shape, -np.inf)
        ints, floats = model.packed(obstacles, model.pair_arrays)
        for clearance in (1e-12, 0.05):
            out = np.empty(len(Q), np.bool_)
            assert E.collision_free_packed(Q, clearance, 1e-12, ints, floats, out)
            answers.append(out)
    del model.static_gaps
    assert np.array_equal(answers[0], answers[2]) and np.array_equal(answers[1], answers[3])
    assert 0 < answers[0].sum() < len(Q)
