"""Floor tables of self-collision pairs moved by one or two joints (scene/pair_table.py): every
floor is a lower bound of the pair's sphere-model clearance anywhere in its cell, on the Panda
with its hand (where link 6 against the hand and link 5 against the hand get tables)."""

import numpy as np
import pytest

from drake_mh._support.cache import temporary_cache
from drake_mh.planning.problems import load_problem_robot
from drake_mh.scene import Scene, pair_table
from drake_mh.scene.pair_table import LOWEST
from drake_mh.scene.kernels.pairs import pair_floor
from drake_mh.scene.batch import CollisionModel


@pytest.fixture(scope="module")
def scene():
    return Scene(load_problem_robot("panda_hand_mbm"), self_collision=True)


def pair_values(scene, Q, pairs) -> np.ndarray:
    """``(N, len(pairs))``: the smallest sphere-pair clearance of each link pair, with numpy."""
    centres = scene.sphere_centres(Q)
    links, radii = np.asarray(scene.sphere_model.links), scene.sphere_model.radii
    out = []
    for a, b in pairs:
        ia, ib = np.flatnonzero(links == a), np.flatnonzero(links == b)
        d = np.linalg.norm(centres[:, ia, None, :] - centres[:, None, ib, :], axis=-1)
        out.append((d - radii[ia, None] - radii[None, ib]).min(axis=(1, 2)))
    return np.stack(out, axis=1)


def floors(model, Q) -> np.ndarray:
    """``(N, P)`` :func:`pair_floor` of every pair at every configuration of ``Q``."""
    t_meta, t_grid, t_vals = model.pair_arrays[2:5]
    QT = np.ascontiguousarray(Q.T)
    return np.array([[pair_floor(i, QT, n, t_meta, t_grid, t_vals) for i in range(model.num_pairs)]
                     for n in range(len(Q))])


def test_the_expensive_neighbour_pairs_get_tables(scene):
    model = scene.collision_model
    t_meta = model.pair_arrays[2]
    dims = {frozenset(pair): int(t_meta[i, 0]) for i, pair in enumerate(model.self_pairs)}
    assert dims[frozenset(("panda_link6", "panda_hand"))] == 1  # moved by q7 alone
    assert dims[frozenset(("panda_link5", "panda_hand"))] == 2  # by q6 and q7
    assert 2 in dims.values()
    assert all(d in (0, 1, 2) for d in dims.values())


def test_floors_are_lower_bounds_everywhere_in_their_cells(scene):
    model, robot = scene.collision_model, scene.robot
    rng = np.random.default_rng(3)
    t_meta, t_grid = model.pair_arrays[2:4]
    Q = robot.random_configurations(400, rng=rng)
    # configurations on cell edges and corners of every table (read into either cell)
    edges = robot.random_configurations(400, rng=rng)
    for i in np.flatnonzero(t_meta[:, 0]):
        for axis in range(t_meta[i, 0]):
            j, n = t_meta[i, 1 + axis], t_meta[i, 3 + axis]
            lo, width = t_grid[i, 2 * axis], 1.0 / t_grid[i, 2 * axis + 1]
            rows = rng.integers(0, len(edges), 100)
            edges[rows, j] = lo + rng.integers(0, n + 1, 100) * width
    edges = np.clip(edges, robot.lower, robot.upper)
    Q = np.concatenate([Q, edges])
    truth, floor = pair_values(scene, Q, model.self_pairs), floors(model, Q)
    tabled = t_meta[:, 0] > 0
    assert np.all(floor[:, tabled] <= truth[:, tabled])
    assert np.all(floor[:, ~tabled] == -np.inf)
    gap = truth[:, tabled] - floor[:, tabled]
    assert np.median(gap) < 0.01  # and useful: within a centimetre of the value at the median
    # dense sampling of the cells where the floor is tightest
    tight = np.argsort(gap.min(axis=1))[:5]
    for n in tight:
        i = np.flatnonzero(tabled)[np.argmin(gap[n])]
        dense = np.tile(Q[n], (300, 1))
        for axis in range(t_meta[i, 0]):
            j = t_meta[i, 1 + axis]
            lo, width = t_grid[i, 2 * axis], 1.0 / t_grid[i, 2 * axis + 1]
            cell = min(int((Q[n, j] - lo) / width), t_meta[i, 3 + axis] - 1)
            dense[:, j] = lo + (cell + rng.uniform(0.0, 1.0, 300)) * width
        values = pair_values(scene, dense, [model.self_pairs[i]])[:, 0]
        assert floors(model, dense[:1])[0, i] <= values.min()


def test_no_floor_outside_the_joint_limits(scene):
    model, robot = scene.collision_model, scene.robot
    t_meta = model.pair_arrays[2]
    i = int(np.flatnonzero(t_meta[:, 0])[0])
    q = robot.home.copy() if hasattr(robot, "home") else np.zeros(robot.nq)
    q[t_meta[i, 1]] = robot.upper[t_meta[i, 1]] + 0.1
    assert floors(model, q[None])[0, i] == -np.inf


def test_answers_do_not_depend_on_the_tables(scene):
    robot = scene.robot
    rng = np.random.default_rng(5)
    Q = robot.random_configurations(900, rng=rng)
    Q[::3, 5] = rng.uniform(robot.upper[5] - 0.8, robot.upper[5], len(Q[::3]))  # the hand near link 5
    QT = np.ascontiguousarray(Q.T)
    with_tables = scene.collision_model
    without = CollisionModel(robot, scene.sphere_model, with_tables.self_pairs, pair_tables=False)
    obstacles = scene.obstacle_arrays
    for self_clearance in (0.0, 0.002, 0.005):
        a = with_tables.free(Q, obstacles, 0.0, self_clearance)
        b = without.free(Q, obstacles, 0.0, self_clearance)
        np.testing.assert_array_equal(a, b)
        assert 0 < a.sum() < len(Q)
    G = with_tables.num_links
    a = with_tables.clearances(QT, obstacles, per_obstacle=False, fine_below=0.03)[:, G:]
    b = without.clearances(QT, obstacles, per_obstacle=False, fine_below=0.03)[:, G:]
    below = b < 0.03
    np.testing.assert_array_equal(a[below], b[below])  # exact below fine_below, as before
    assert np.all(a[~below] >= 0.03)
    truth = pair_values(scene, Q[:300], with_tables.self_pairs)
    assert np.all(a[:300][~below[:300]] <= truth[~below[:300]] + 1e-12)


def test_tables_are_cached_on_disk(scene):
    robot, pairs = scene.robot, scene.collision_model.self_pairs
    with temporary_cache() as folder:
        pair_table._CACHE.clear()
        first = CollisionModel(robot, scene.sphere_model, pairs).pair_arrays
        assert len(list((folder / "pair_tables").glob("*.npy"))) == int(np.sum(first[2][:, 0] > 0))
        pair_table._CACHE.clear()
        again = CollisionModel(robot, scene.sphere_model, pairs).pair_arrays
        for x, y in zip(first, again):
            np.testing.assert_array_equal(x, y)


def test_segments_certified_through_tables_are_clear_everywhere(scene):
    """certify_segments lets a pair's table certify it along a segment: dense sampling of the
    certified segments never finds that pair (or any other) below the self-clearance, nor below
    the reported ``lower_self``."""
    robot = scene.robot
    rng = np.random.default_rng(8)
    QA = robot.random_configurations(60, rng=rng)
    QA[::2, 5] = rng.uniform(robot.upper[5] - 0.8, robot.upper[5], 30)  # the hand near link 5
    QA = QA[scene.collision_free(QA, 0.0, 0.002)][:30]
    QB = np.clip(QA + rng.normal(0.0, 0.3, QA.shape), robot.lower, robot.upper)
    cert = scene.certify_segments(QA, QB, 0.0, 0.002)
    assert cert.certified.sum() >= 5
    t = np.linspace(0.0, 1.0, 101)
    for i in np.flatnonzero(cert.certified):
        dense = QA[i] + t[:, None] * (QB[i] - QA[i])
        values = pair_values(scene, dense, scene.collision_model.self_pairs)
        assert values.min() >= 0.002
        assert values.min() >= cert.lower_self[i] - 1e-12



def test_the_lowest_floor_bounds_every_configuration(scene):
    """``t_grid[:, 4]``: each table's smallest floor (rrt_connect certifies a pair along any motion
    by it), at most the pair's clearance anywhere within the joint limits; -inf without a table."""
    model, robot = scene.collision_model, scene.robot
    t_meta, t_grid, t_vals = model.pair_arrays[2:5]
    tabled = t_meta[:, 0] > 0
    assert np.all(np.isneginf(t_grid[~tabled, LOWEST]))
    for i in np.flatnonzero(tabled):
        size = t_meta[i, 3] * (t_meta[i, 4] if t_meta[i, 0] == 2 else 1)
        assert t_grid[i, LOWEST] == t_vals[t_meta[i, 5]:t_meta[i, 5] + size].min()
    Q = robot.random_configurations(300, rng=np.random.default_rng(5))
    values = pair_values(scene, Q, [model.self_pairs[i] for i in np.flatnonzero(tabled)])
    assert np.all(values >= t_grid[tabled, LOWEST])
    assert np.any(t_grid[tabled, LOWEST] >= 0.0) and np.any(t_grid[tabled, LOWEST] < 0.0)  # both kinds on this robot
