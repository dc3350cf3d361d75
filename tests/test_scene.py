"""Scene: obstacles in Drake's SceneGraph, exact distances, batched conservative distances."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh.errors import FrameNotFound, SceneError, UnknownObstacle
from drake_mh.scene import Box, Cylinder, Scene, Sphere

PANDA = drake_mh.load_robot("panda")


def make_scene(robot=PANDA, **kwargs):
    scene = Scene(robot, **kwargs)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    scene.add("box", Box((0.2, 0.3, 0.1)), [0.3, 0.35, 0.3], rpy=[0.3, 0.2, 0.1])
    scene.add("post", Cylinder(0.05, 0.6), [0.35, -0.35, 0.3], rpy=[0.2, 0.0, 0.0])
    return scene


def test_distance_pairs_are_consistent():
    scene = make_scene()
    pairs = scene.distances(PANDA.home)
    assert pairs and all(not p.is_self for p in pairs)
    assert [p.distance for p in pairs] == sorted(p.distance for p in pairs)
    for p in pairs:
        assert p.other in {"ball", "box", "post"} and p.link in PANDA.link_names()
        if p.distance > 1e-6:  # closest points are `distance` apart, along the normal
            gap = p.p_W_link - p.p_W_other
            assert np.linalg.norm(gap) == pytest.approx(p.distance, abs=1e-6)
            np.testing.assert_allclose(gap / np.linalg.norm(gap), p.nhat_W, atol=1e-5)


def test_sphere_obstacle_distance_by_hand():
    """A ball facing the flange: distance = |p_ball - p_closest_link_point| - r, by FK."""
    scene = Scene(PANDA)
    q = PANDA.home
    p_flange = PANDA.fk(q)[:3, 3]
    scene.add("ball", Sphere(0.05), p_flange + [0.0, 0.0, 0.5])
    pair = scene.distances(q)[0]
    assert pair.distance == pytest.approx(np.linalg.norm(pair.p_W_link - scene.obstacles["ball"].position) - 0.05,
                                          abs=1e-9)


def test_obstacles_move_without_rebuilding():
    scene = make_scene()
    q = PANDA.home
    before = scene.min_distance(q)
    diagram = PANDA.diagram
    scene.move("ball", [2.0, 2.0, 2.0])
    scene.move("box", [2.0, -2.0, 2.0])
    scene.move("post", [-2.0, 2.0, 2.0])
    after = scene.min_distance(q)
    assert after > before + 0.5 and PANDA.diagram is diagram
    assert scene.batch_min_distance(q[None])[0] == pytest.approx(after, abs=scene.sphere_model.bound + 1e-6)
    scene.remove("ball")
    assert set(scene.obstacles) == {"box", "post"}


def test_step_moves_obstacles_by_velocity():
    scene = Scene(PANDA)
    scene.add("ball", Sphere(0.15), [0.0, -0.4, 0.6], velocity=[0.0, 0.16, 0.0])
    for _ in range(10):
        scene.step(0.1)
    np.testing.assert_allclose(scene.obstacles["ball"].position, [0.0, -0.24, 0.6], atol=1e-12)


def test_scenes_are_independent():
    a, b = Scene(PANDA), Scene(PANDA)
    a.add("ball", Sphere(0.1), PANDA.fk(PANDA.home)[:3, 3])
    assert a.min_distance(PANDA.home) < 0 and b.min_distance(PANDA.home) == np.inf


def test_self_collision_pairs():
    scene = Scene(PANDA, self_collision=True)
    pairs = scene.distances(np.zeros(7))
    assert pairs and all(p.is_self for p in pairs)
    names = PANDA.link_names()
    adjacent = {frozenset(p) for p in zip(names, names[1:])}
    assert all(frozenset((p.link, p.other)) not in adjacent for p in pairs)
    filtered = Scene(PANDA, self_collision=True, ignore_link_pairs=[("panda_link5", "panda_link7")])
    assert all({p.link, p.other} != {"panda_link5", "panda_link7"} for p in filtered.distances(np.zeros(7)))


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_sphere_model_is_conservative_and_tight(seed):
    scene = make_scene()
    Q = PANDA.random_configurations(40, seed)
    exact = scene.exact_min_distance(Q)
    approx = scene.batch_min_distance(Q)
    clear = exact >= 0
    # never more clearance than the exact distance, at most `bound` less (Scene refines the
    # capsule-box/cylinder pairs that Drake's GJK gets up to 6.7 mm wrong; 1e-9 for round-off)
    gjk = 1e-9
    assert np.all(approx[clear] <= exact[clear] + gjk)
    assert np.all(exact[clear] - approx[clear] <= scene.sphere_model.bound + gjk)
    # every collision Drake sees, the sphere model sees
    assert np.all(approx[~clear] < 0)


def test_no_obstacles_gives_infinite_clearance():
    scene = Scene(PANDA)
    assert scene.min_distance(PANDA.home) == np.inf
    assert np.all(scene.batch_min_distance(PANDA.random_configurations(3, 0)) == np.inf)


def test_scene_errors():
    scene = make_scene()
    with pytest.raises(SceneError, match="already exists"):
        scene.add("ball", Sphere(0.1), [0, 0, 0])
    with pytest.raises(UnknownObstacle) as err:
        scene.move("bal", [0, 0, 0])
    assert "ball" in str(err.value)
    with pytest.raises(SceneError, match="3 finite numbers"):
        scene.add("x", Sphere(0.1), [0, 0])
    with pytest.raises(SceneError, match="Sphere, Box, Cylinder or Capsule"):
        scene.add("y", "sphere", [0, 0, 0])
    with pytest.raises(FrameNotFound):
        Scene(PANDA, self_collision=True, ignore_link_pairs=[("panda_link5", "gripper")])


def test_capsule_box_distances_are_exact_where_drake_gjk_is_not():
    """A configuration hypothesis found: Drake 1.51's GJK says 0.09119 m for panda_link5 vs the
    box; a 200,001-point sampling of the capsule axis gives 0.08503 m. Scene refines it."""
    scene = make_scene()
    Q = PANDA.random_configurations(40, 513056)
    exact = scene.exact_min_distance(Q)
    q = Q[np.argmin(np.abs(exact - 0.0850329465))]
    pair = [p for p in scene.distances(q) if p.link == "panda_link5" and p.other == "box"][0]
    assert pair.distance == pytest.approx(0.0850329465, abs=1e-8)
    assert np.linalg.norm(pair.p_W_link - pair.p_W_other) == pytest.approx(pair.distance, abs=1e-7)
    np.testing.assert_allclose((pair.p_W_link - pair.p_W_other) / pair.distance, pair.nhat_W, atol=1e-6)


def _rotation(rng):
    from scipy.spatial.transform import Rotation

    return Rotation.random(random_state=int(rng.integers(1 << 31))).as_matrix()


def test_segment_distance_matches_dense_sampling():
    from drake_mh.segment_distance import capsule_distance
    from drake_mh.shapes import Capsule

    rng = np.random.default_rng(4)
    for shape in (Box((0.2, 0.3, 0.1)), Cylinder(0.05, 0.6), Capsule(0.04, 0.3), Sphere(0.1)):
        for _ in range(20):
            X_WC, X_WO = np.eye(4), np.eye(4)
            X_WC[:3, :3], X_WO[:3, :3] = _rotation(rng), _rotation(rng)
            X_WC[:3, 3] = rng.uniform(-0.5, 0.5, 3)
            d, p_c, p_o, n = capsule_distance(X_WC, 0.03, 0.2, X_WO, shape)
            axis = X_WC[:3, 3] + np.outer(np.linspace(-0.1, 0.1, 100001), X_WC[:3, 2])
            sampled = shape.signed_distance(axis @ X_WO[:3, :3]).min() - 0.03
            assert d == pytest.approx(sampled, abs=1e-7)
            if d > 1e-6:
                assert np.linalg.norm(p_c - p_o) == pytest.approx(d, abs=1e-6)
