"""Point-cloud obstacles in a Scene: the batched checks and segment certificates never call
free what the brute-force distance of the robot's geometry to every point shows closer; the
exact distances equal it; the structure in the kernels (a grid of distance bounds and a tree of
the points) finds the nearest point and bounds it, built by the numba kernel or by the compiled
core (a valid tree, the same table, the same answers)."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh.errors import SceneError
from drake_mh.scene import PointCloud, Scene
from obstacle_reference import PointDistance, check_certified_segments, near_configurations

PANDA = drake_mh.load_robot("panda")
REFERENCE = PointDistance(PANDA)
NATIVE = pytest.mark.skipif(importlib.util.find_spec("drake_mh._native") is None,
                            reason="the compiled core drake_mh._native is not built (pip install . builds it)")
CORES = ["0", pytest.param("1", marks=NATIVE)]
"""``DRAKE_MH_COMPILED_CORE``: the numba kernels, and the compiled core where it is built."""


def box_surface(rng, count, size, centre):
    """``count`` points on the faces of a box of full ``size`` at ``centre``."""
    points = rng.uniform(-0.5, 0.5, (count, 3)) * size
    axis = rng.integers(0, 3, count)
    points[np.arange(count), axis] = np.sign(rng.uniform(-1, 1, count)) * 0.5 * np.asarray(size)[axis]
    return points + centre


def cloud_scene(seed: int, radius: float = 0.01):
    rng = np.random.default_rng(seed)
    points = np.vstack([box_surface(rng, 3000, (0.6, 0.8, 0.04), (0.5, 0.0, 0.2)),   # a table top
                        box_surface(rng, 1500, (0.2, 0.2, 0.3), rng.uniform([0.3, -0.4, 0.4], [0.6, 0.4, 0.6]))])
    scene = Scene(PANDA)
    scene.add("cloud", PointCloud(points, radius), rpy=(0, 0, rng.uniform(-0.3, 0.3)))
    X = scene.obstacles["cloud"].X_WO
    return scene, points @ X[:3, :3].T + X[:3, 3], radius


@pytest.mark.parametrize("core", CORES)
def test_tree_finds_the_nearest_point_and_the_grid_bounds_it(core, monkeypatch):
    """Against the brute-force distance to every point: the search's nearest distance, the
    grid's lower and upper bounds (inside and outside the grid), and "free" on both sides of the
    exact distance."""
    from drake_mh.scene.kernels.cloud import cloud_bounds, cloud_floor, cloud_free, cloud_nearest2

    monkeypatch.setenv("DRAKE_MH_COMPILED_CORE", core)  # which builds the table
    rng = np.random.default_rng(0)
    for n in (1, 7, 17, 1000, 20000):
        points = rng.normal(size=(n, 3)) * [1.0, 0.3, 0.01]  # flat: one grid layer
        points[: n // 3] = points[0]  # repeated points: equal codes, split at the middle
        scene = Scene(PANDA)
        scene.add("c", PointCloud(points, 0.0))
        dims = scene.obstacle_arrays[4]
        far = rng.normal(size=(30, 3)) * 10.0  # outside the grid: bounded from the grid's faces
        for x in np.vstack([rng.normal(size=(150, 3)), far,
                            points[rng.integers(0, n, 50)] + rng.normal(0, 0.03, (50, 3))]):
            exact = np.min(np.sum((points - x) ** 2, axis=1))
            assert cloud_nearest2(0, dims, *x, np.inf) == pytest.approx(exact, rel=1e-12, abs=1e-15)
            assert cloud_nearest2(0, dims, *x, exact * 0.5) == exact * 0.5  # nothing nearer than the bound
            assert cloud_floor(0, dims, *x) <= np.sqrt(exact)  # the grid's value is a lower bound
            assert cloud_bounds(0, dims, *x)[1] >= np.sqrt(exact)  # and its upper bound one above
            for reach in (0.5 * np.sqrt(exact), 2.0 * np.sqrt(exact) + 1e-9):
                assert cloud_free(0, dims, *x, reach) == (np.sqrt(exact) >= reach)


def surface_cloud(seed: int, n: int) -> np.ndarray:
    """n points on two box surfaces (the clouds the structure is made for)."""
    rng = np.random.default_rng(seed)
    return np.vstack([box_surface(rng, n // 2, (0.6, 0.8, 0.04), (0.5, 0.0, 0.2)),
                      box_surface(rng, n - n // 2, (0.2, 0.3, 0.3), (0.4, 0.1, 0.5))])


@pytest.mark.parametrize("max_cells", [64.0, 4096.0])
def test_grid_values_bound_every_point_of_their_cell(max_cells):
    """Each cell's lower bound (its steps of h / 256) is at most the distance from its box to
    the nearest point (sampled densely in the box, corners included), and one step more + 2
    sqrt(3) h at least that distance at every sample."""
    from drake_mh.scene.kernels.cloud import STEPS, UPPER
    from drake_mh.scene.kernels.cloud_table import cloud_table

    points = surface_cloud(8, 3000)
    table, low, high = cloud_table(points, 0.0, 0.01, max_cells)
    h, shape, head = table[0, 1], table[2].astype(int), int(table[0, 2])
    steps = table[3:head].reshape(-1).view(np.uint16)[:np.prod(shape)].reshape(shape).astype(float)
    assert np.array_equal(low, points.min(axis=0)) and np.array_equal(high, points.max(axis=0))
    assert np.all(low + shape * h > high)  # the grid holds every point
    from scipy.spatial import cKDTree

    tree = cKDTree(points)
    offsets = np.stack(np.meshgrid(*[np.linspace(0.0, 1.0, 4)] * 3, indexing="ij"), -1).reshape(-1, 3)
    for cell in np.random.default_rng(9).integers(0, shape, (300, 3)):
        d = tree.query(low + (cell + offsets) * h)[0]
        u = steps[tuple(cell)]
        assert u * h / STEPS <= d.min() + 1e-12 and (u + 1) * h / STEPS + UPPER * h >= d.max() - 1e-12


@pytest.mark.parametrize("build", ["numba", pytest.param("compiled", marks=NATIVE)])
@pytest.mark.parametrize("n", [1, 2, 16, 17, 5000])
def test_table_holds_the_points_in_a_valid_tree(build, n):
    """The points once each, in Morton order; each node's two boxes are the bounding boxes of
    its children's points, its children's ranges follow each other, a leaf holds at most LEAF
    points."""
    from drake_mh.scene.kernels.cloud import COUNT_BITS, LEAF, NODE_ROWS
    from drake_mh.scene.kernels.cloud_table import cloud_table

    rng = np.random.default_rng(4)
    P = rng.normal(size=(n, 3)) * [1.0, 0.2, 0.05]
    P[n // 2: n // 2 + n // 5] = P[0]  # repeated points
    P[: n // 10, 2] = 0.0  # ties on one axis
    if build == "numba":
        table = cloud_table(P, 0.0, 0.02, 1000.0)[0]
    else:
        from drake_mh import _native

        table = _native.cloud_table(P, 0.0, 0.02, 1000.0)[0]
    first = int(table[0, 2])
    tree = table[first:first + n]
    assert np.array_equal(np.unique(tree, axis=0, return_counts=True)[1], np.unique(P, axis=0, return_counts=True)[1])
    assert np.array_equal(np.unique(tree, axis=0), np.unique(P, axis=0))  # the same points, as often
    nodes = table[first + n:]

    def check(code, lo):  # -> hi, the end of the child's range
        if code < 0:
            v = -code - 1
            assert v >> COUNT_BITS == lo and (v & 63) <= LEAF
            return lo + (v & 63)
        rows = nodes[NODE_ROWS * code: NODE_ROWS * code + NODE_ROWS]
        mid = check(int(rows[4, 0]), lo)
        hi = check(int(rows[4, 1]), mid)
        for side, (a, b) in enumerate(((lo, mid), (mid, hi))):
            if b > a:
                assert np.array_equal(rows[2 * side], tree[a:b].min(axis=0))
                assert np.array_equal(rows[2 * side + 1], tree[a:b].max(axis=0))
        return hi

    assert check(0, 0) == n
    assert len(nodes) % NODE_ROWS == 0


@NATIVE
def test_compiled_table_equals_numbas():
    from drake_mh import _native
    from drake_mh.scene.kernels.cloud_table import cloud_table

    rng = np.random.default_rng(5)
    for P in (rng.normal(size=(20001, 3)), rng.integers(0, 4, (3000, 3)).astype(float), np.zeros((1, 3)),
              surface_cloud(6, 30000)):
        for cells in (1.0, 65536.0):
            for mine, theirs in zip(_native.cloud_table(P, 0.01, 0.02, cells), cloud_table(P, 0.01, 0.02, cells)):
                assert np.array_equal(mine, theirs)  # the same steps on the same values
    with pytest.raises(ValueError, match="finite"):
        _native.cloud_table(np.array([[0.0, np.nan, 1.0]]), 0.0, 0.02, 10.0)


def test_grid_distance_transform_equals_scipys():
    from scipy import ndimage

    from drake_mh.scene.kernels.cloud_table import distance_transform

    rng = np.random.default_rng(3)
    for shape, share in (((1, 1, 1), 1.0), ((5, 1, 9), 0.1), ((17, 12, 8), 0.02), ((30, 31, 29), 0.001)):
        zero = rng.random(shape) < share
        zero.flat[rng.integers(zero.size)] = True
        assert np.allclose(distance_transform(zero), ndimage.distance_transform_edt(~zero), rtol=0, atol=1e-12)
    assert np.all(distance_transform(np.zeros((3, 4, 5), bool)) == np.inf)


@NATIVE
def test_collision_free_answers_alike_with_and_without_the_compiled_core(monkeypatch):
    rng = np.random.default_rng(6)
    Q = rng.uniform(PANDA.lower, PANDA.upper, (400, PANDA.nq))
    answers = []
    for core in ("0", "1"):
        monkeypatch.setenv("DRAKE_MH_COMPILED_CORE", core)  # the tree's build and the check
        scene, _, _ = cloud_scene(7)
        answers.append((scene.collision_free(Q), [scene.collision_free(q) for q in Q[:40]]))
    assert np.array_equal(answers[0][0], answers[1][0]) and answers[0][1] == answers[1][1]
    assert 0 < np.count_nonzero(answers[0][0]) < len(Q)  # both answers occur


@settings(max_examples=4, deadline=None)
@given(seed=st.integers(0, 10_000), radius=st.sampled_from([0.0, 0.01, 0.03]))
def test_batched_check_never_calls_a_touching_configuration_free(seed, radius):
    scene, points, rho = cloud_scene(seed, radius)
    Q = near_configurations(scene, seed)
    for clearance in (0.0, 0.02):
        free = scene.collision_free(Q, clearance)
        for q in Q[free]:
            assert REFERENCE(q, points) - rho >= clearance - 1e-9
    model = scene.batch_min_distance(Q)
    bound = scene.sphere_model.bound
    for q, m in zip(Q[:40], model[:40]):
        exact = REFERENCE(q, points) - rho
        assert m <= exact + 1e-9
        if exact >= 0:
            assert m >= exact - bound - 1e-9
        assert scene.min_distance(q) == pytest.approx(exact, abs=1e-9)


@settings(max_examples=3, deadline=None)
@given(seed=st.integers(0, 10_000), fine_below=st.sampled_from([0.0, 0.03, 0.1, np.inf]))
def test_link_values_are_exact_below_fine_below_and_lower_bounds_above(seed, fine_below):
    """Per link (the certified segments' values), against the brute-force distance of every
    sphere of the link to every point: exact below ``fine_below``, a lower bound of at least
    ``fine_below`` above it (where the searches stop)."""
    scene, points, rho = cloud_scene(seed)
    Q = near_configurations(scene, seed, 60)
    model = scene.collision_model
    values = model.clearances(np.ascontiguousarray(Q.T), scene.obstacle_arrays, per_obstacle=False,
                              fine_below=fine_below)[:, :model.num_links]
    spheres = scene.sphere_model
    centres = scene.sphere_centres(Q)  # (N, S, 3)
    nearest = np.array([[np.sqrt(np.min(np.sum((points - c) ** 2, axis=1))) for c in row] for row in centres])
    per_sphere = nearest - spheres.radii - rho
    links = np.asarray(spheres.links)
    for g, name in enumerate(model.link_names):
        exact = per_sphere[:, links == name].min(axis=1)
        assert np.all(values[:, g] <= exact + 1e-9)
        below = exact < fine_below
        assert np.allclose(values[below, g], exact[below], rtol=0, atol=1e-9)
        assert np.all(values[~below, g] >= fine_below - 1e-9)


@settings(max_examples=3, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_certified_segments_hold_under_dense_sampling(seed):
    scene, points, rho = cloud_scene(seed)
    check_certified_segments(scene, points, rho, seed)


def test_distances_and_drake_point_query():
    scene, points, rho = cloud_scene(2)
    q = near_configurations(scene, 2, 2)[0]
    pairs = [p for p in scene.distances(q) if p.other == "cloud"]
    assert pairs and pairs[0].distance == pytest.approx(scene.min_distance(q), abs=1e-12)
    # the link's witness lies on the link: Drake's own point query agrees there
    context = PANDA.diagram.CreateDefaultContext()
    PANDA.plant.SetPositions(PANDA.plant.GetMyMutableContextFromRoot(context), q)
    query = PANDA.scene_graph.get_query_output_port().Eval(PANDA.scene_graph.GetMyContextFromRoot(context))
    for pair in pairs[:5]:
        on_surface = min(abs(d.distance) for d in query.ComputeSignedDistanceToPoint(pair.p_W_link, 1.0))
        assert on_surface < 1e-6  # on the surface of a geometry (links overlap: maybe inside another)
        assert np.linalg.norm(pair.p_W_link - pair.p_W_other) == pytest.approx(max(pair.distance, 0), abs=1e-6)


def test_robot_points_removed_and_crop():
    scene = Scene(PANDA)
    q = np.zeros(PANDA.nq)
    q[3], q[5] = -1.5, 1.5
    rng = np.random.default_rng(1)
    centres = scene.sphere_centres(q.reshape(1, -1))[0]
    on_robot = centres[rng.integers(0, len(centres), 300)] + rng.normal(0, 0.01, (300, 3))
    far = rng.uniform([-1, -1, 0], [1, 1, 1], (2000, 3))
    cloud = PointCloud(np.vstack([on_robot, far]), 0.005)
    cleaned = cloud.without_robot(PANDA, q, margin=0.01)
    assert len(cleaned) < len(cloud)
    assert REFERENCE(q, cleaned.points) >= 0.01 - 1e-9  # no point left within the margin
    kept_far = far[[REFERENCE(q, x.reshape(1, 3)) >= 0.01 for x in far]]
    assert len(cleaned) >= len(kept_far)  # a point off the robot is never removed
    cropped = cloud.cropped_to_reach(scene, margin=0.05)
    assert len(cropped) <= len(cloud)
    dropped = np.array([x for x in cloud.points if not (cropped.points == x).all(axis=1).any()]).reshape(-1, 3)
    if len(dropped):  # no configuration brings the robot within 5 cm of a dropped point
        Q = rng.uniform(PANDA.lower, PANDA.upper, (50, PANDA.nq))
        assert min(REFERENCE(qq, dropped) for qq in Q) >= 0.05


def test_failed_add_changes_nothing():
    scene = Scene(PANDA)
    with pytest.raises(SceneError):
        scene.add("c", PointCloud(np.zeros((3, 3)), 0.01), [np.inf, 0, 0])
    assert not scene.obstacles and len(scene.obstacle_arrays[0]) == 0
