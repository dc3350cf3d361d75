"""Batched boolean collision queries on the sphere model (Scene.collision_free) and the
per-obstacle clearance kernel behind Scene.batch_obstacle_distances."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidConfiguration, SceneError
from drake_mh.scene import Box, Capsule, Cylinder, Scene, Sphere
from sphere_fixtures import no_geometry_urdf

PANDA = drake_mh.load_robot("panda")
SHAPES = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4), Capsule(0.04, 0.3)]


def cluttered(seed=1, count=10, robot=PANDA, **kwargs):
    rng = np.random.default_rng(seed)
    scene = Scene(robot, **kwargs)
    for i in range(count):
        scene.add(f"o{i}", SHAPES[i % 4], rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.0]), rpy=rng.uniform(-3, 3, 3))
    return scene


def sphere_reference(scene, Q):
    """Per-obstacle model clearance (N, K) with numpy, from the sphere centres."""
    centres = scene.sphere_centres(Q)
    out = []
    for obstacle in scene.obstacles.values():
        R, p = obstacle.X_WO[:3, :3], obstacle.X_WO[:3, 3]
        out.append((obstacle.shape.signed_distance((centres - p) @ R) - scene.sphere_model.radii).min(axis=1))
    return np.stack(out, axis=1)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_kernel_matches_numpy_reference(seed):
    scene = cluttered(seed)
    Q = np.random.default_rng(seed).uniform(PANDA.lower, PANDA.upper, (700, PANDA.nq))  # not a block multiple
    reference = sphere_reference(scene, Q)
    QT = np.ascontiguousarray(Q.T)
    per_obstacle = scene.collision_model.clearances(QT, scene.obstacle_arrays, per_obstacle=True)
    np.testing.assert_allclose(per_obstacle, reference, atol=1e-12)
    per_link = scene.collision_model.clearances(QT, scene.obstacle_arrays, per_obstacle=False)
    np.testing.assert_allclose(per_link.min(axis=1), reference.min(axis=1), atol=1e-12)
    coarse = scene.collision_model.clearances(QT, scene.obstacle_arrays, per_obstacle=False, fine_below=0.05)
    assert np.all(coarse <= per_link + 1e-12)  # bounding spheres: lower bounds
    exact_below = per_link < 0.05
    np.testing.assert_allclose(coarse[exact_below], per_link[exact_below], atol=1e-12)
    for clearance in (0.0, 0.01, 0.1):
        free = scene.collision_free(Q, clearance)
        assert free.dtype == bool and free.shape == (700,)
        # equal to the reference except where the two round differently at the boundary
        agree = free == (reference.min(axis=1) >= clearance)
        assert np.all(agree | (np.abs(reference.min(axis=1) - clearance) < 1e-9))
        assert 0 < free.sum() < 700


def test_grouped_links_match_numpy_reference():
    """The Panda with its hand (778 spheres, links of several sphere groups): the clearance
    kernel skips groups (scene/kernels/collision._groups_sd) and stays exact where it must be."""
    from drake_mh.planning.problems import load_problem_robot

    hand = load_problem_robot("panda_hand_mbm")
    scene = cluttered(5, robot=hand)
    assert np.any(np.diff(scene.collision_model.group_arrays[0]) > 1)  # some link has several groups
    Q = np.random.default_rng(5).uniform(hand.lower, hand.upper, (300, hand.nq))
    reference = sphere_reference(scene, Q)
    QT = np.ascontiguousarray(Q.T)
    model = scene.collision_model
    np.testing.assert_allclose(model.clearances(QT, scene.obstacle_arrays, per_obstacle=True), reference, atol=1e-12)
    G = model.num_links
    per_link = model.clearances(QT, scene.obstacle_arrays, per_obstacle=False)[:, :G]
    np.testing.assert_allclose(per_link.min(axis=1), reference.min(axis=1), atol=1e-12)
    for fine_below in (0.0, 0.05, 0.2):
        coarse = model.clearances(QT, scene.obstacle_arrays, per_obstacle=False, fine_below=fine_below)[:, :G]
        assert np.all(coarse <= per_link + 1e-12)  # lower bounds everywhere
        exact_below = coarse < fine_below
        np.testing.assert_allclose(coarse[exact_below], per_link[exact_below], atol=1e-12)
        assert np.all(per_link[per_link < fine_below] == coarse[per_link < fine_below])


def test_free_means_exactly_free():
    """Conservative against Drake's exact distance: free under the model => free in fact."""
    scene = cluttered(4)
    Q = np.random.default_rng(4).uniform(PANDA.lower, PANDA.upper, (150, PANDA.nq))
    exact = scene.exact_min_distance(Q)
    for clearance in (0.0, 0.02):
        free = scene.collision_free(Q, clearance)
        assert np.all(exact[free] >= clearance - 1e-9)
        # and at most the model's bound pessimistic
        assert not np.any(~free & (exact >= clearance + scene.sphere_model.bound + 1e-6))


def test_one_configuration_and_obstacle_changes():
    scene = Scene(PANDA)
    q = PANDA.home
    assert scene.collision_free(q) is True  # no obstacle: free
    p = PANDA.fk(q)[:3, 3]
    scene.add("ball", Sphere(0.05), p)
    assert scene.collision_free(q) is False
    scene.move("ball", p + [0.0, 0.0, 0.5])
    assert scene.collision_free(q) is True
    assert scene.collision_free(q, clearance=0.6) is False
    scene.remove("ball")
    assert scene.collision_free(q, clearance=5.0) is True
    assert scene.collision_free(np.vstack([q, q])).tolist() == [True, True]


def test_self_collision_pairs_follow_drakes_filter():
    scene = Scene(PANDA, self_collision=True)
    pairs = scene.collision_model.self_pairs
    assert pairs, "the Panda has non-adjacent link pairs"
    chain = [link for link in PANDA.link_names()]
    for a, b in pairs:  # Drake filters links connected by a joint
        assert abs(chain.index(a) - chain.index(b)) != 1 or "hand" in a + b
    rng = np.random.default_rng(5)
    Q = rng.uniform(PANDA.lower, PANDA.upper, (300, PANDA.nq))
    free = scene.collision_free(Q)
    assert 0 < free.sum() < 300, "random Panda configurations: some fold onto themselves"
    for q in Q[free][:40]:
        assert scene.min_distance(q) >= -1e-9  # free under the model => no link touches another
    values = scene.collision_model.clearances(np.ascontiguousarray(Q.T), scene.obstacle_arrays, per_obstacle=False)
    G = scene.collision_model.num_links
    np.testing.assert_array_equal(free, values[:, G:].min(axis=1) >= 1e-12)


@pytest.mark.parametrize("bad", [-0.1, np.nan, np.inf, True, False, "0.1", None])
def test_bad_clearance_is_a_scene_error(bad):
    scene = cluttered(1, 2)
    with pytest.raises(SceneError, match="clearance"):
        scene.collision_free(PANDA.home, bad)
    with pytest.raises(SceneError, match="self_clearance"):
        scene.collision_free(PANDA.home, 0.0, bad)
    with pytest.raises(SceneError, match="self_clearance"):  # the batch path too
        scene.collision_free(np.vstack([PANDA.home, PANDA.home]), 0.0, bad)


def test_no_geometry_is_a_scene_error():
    scene = Scene(drake_mh.Robot(no_geometry_urdf()))
    with pytest.raises(SceneError, match="no collision geometry"):
        scene.collision_free(np.zeros(scene.robot.nq))


@pytest.mark.parametrize("self_collision", [False, True])
def test_one_configuration_path_matches_the_batch(self_collision):
    """Scene.collision_free(q) takes a scalar compiled path (collision_free_one) once the scene
    is bound; it answers as the batch kernel does, for any strides of q."""
    scene = cluttered(6, self_collision=self_collision)
    Q = np.random.default_rng(6).uniform(PANDA.lower, PANDA.upper, (400, PANDA.nq))
    for clearance in (0.0, 0.02):
        batch = scene.collision_free(Q, clearance, clearance)
        one = [scene.collision_free(q, clearance, clearance) for q in Q]
        assert all(type(v) is bool for v in one)
        np.testing.assert_array_equal(one, batch)
        assert 0 < batch.sum() < len(Q)
    strided = np.asfortranarray(Q)  # rows with stride N * 8
    assert [scene.collision_free(q) for q in strided[:50]] == scene.collision_free(Q[:50]).tolist()
    bad = Q[0].copy()
    bad[3] = np.nan
    with pytest.raises(InvalidConfiguration, match="NaN or inf"):
        scene.collision_free(bad)


def test_batch_layouts_and_bad_batches():
    """A C-contiguous float64 batch goes to the kernel as it is (finiteness checked there while
    it is transposed); any other layout or dtype is converted first, with the same answers, and a
    bad batch raises the robot's error naming the rows, changing nothing."""
    scene = cluttered(7)
    Q = np.random.default_rng(7).uniform(PANDA.lower, PANDA.upper, (300, PANDA.nq))
    free = scene.collision_free(Q)
    assert 0 < free.sum() < len(Q)
    np.testing.assert_array_equal(scene.collision_free(np.asfortranarray(Q)), free)
    np.testing.assert_array_equal(scene.collision_free(Q.tolist()), free)
    np.testing.assert_array_equal(scene.collision_free(Q.astype(np.float32).astype(float)),
                                  scene.collision_free(Q.astype(np.float32)))
    for value in (np.nan, np.inf, -np.inf):
        bad = Q.copy()
        bad[123, 4] = value
        with pytest.raises(InvalidConfiguration, match=r"NaN or inf \(rows \[123\]"):
            scene.collision_free(bad)
    with pytest.raises(InvalidConfiguration, match="shape"):
        scene.collision_free(Q[:, :5].copy())
    np.testing.assert_array_equal(scene.collision_free(Q), free)  # nothing changed
