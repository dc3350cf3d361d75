"""Mesh obstacles in a Scene: the batched checks, the segment certificates and the exact
distances never call free what dense samples of the original (non-convex) mesh surface show
closer, a failed add changes nothing, and the cover excess is a bound."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh.errors import ObstacleFileError, SceneError
from drake_mh.geometry.convex_pieces import convex_pieces
from drake_mh.scene import Box, Mesh, Scene
from obstacle_reference import PointDistance, check_certified_segments, near_configurations, surface_samples

DATA = Path(__file__).resolve().parents[1] / "data"
PANDA = drake_mh.load_robot("panda")
BIN, BRACKET = Mesh(DATA / "bin.obj"), Mesh(DATA / "bracket.obj", scale=2.0)
REFERENCE = PointDistance(PANDA)


def mesh_scene(seed: int):
    """The bin and the (doubled) bracket near the Panda, posed from ``seed``; poses that leave
    the arm no free configuration among 400 random ones (an obstacle over its base) are drawn
    again."""
    rng = np.random.default_rng(seed)
    while True:
        scene = Scene(PANDA)
        scene.add("bin", BIN, rng.uniform([0.3, -0.3, 0.1], [0.6, 0.3, 0.5]), rpy=rng.uniform(-3, 3, 3))
        scene.add("bracket", BRACKET, rng.uniform([-0.6, -0.6, 0.2], [0.0, -0.2, 0.8]), rpy=rng.uniform(-3, 3, 3))
        if scene.collision_free(PANDA.random_configurations(400, rng=rng)).mean() > 0.1:
            break
    points = np.vstack([surface_samples(o.shape, o.X_WO) for o in scene.obstacles.values()])
    return scene, points


def test_cover_excess_bounds_the_surface():
    """Every surface sample of the original mesh within the excess of the pieces' union."""
    from drake_mh.geometry.convex_pieces import _exact_distances, _hull_planes

    for mesh in (BIN, BRACKET):
        pieces = convex_pieces(mesh)
        assert pieces.excess < 0.003  # the bound is small, not only valid
        samples = surface_samples(mesh, np.eye(4), 40000, seed=3)
        best = np.full(len(samples), np.inf)
        for V in pieces.vertices:
            normals, offsets, simplices = _hull_planes(V)
            inside = ((samples @ normals.T - offsets) <= 1e-12).all(axis=1)
            d = np.zeros(len(samples))
            d[~inside] = _exact_distances(samples[~inside], V, simplices)
            best = np.minimum(best, d)
        assert best.max() <= pieces.excess + 1e-12
        # the kernels' planes hold every sample (the pieces grown by the excess cover the mesh)
        assert np.all(pieces.signed_distance_bound(samples) <= 1e-12)


def test_convex_mesh_is_one_piece_without_excess():
    pieces = convex_pieces(Mesh(DATA / "cube.stl"))
    assert len(pieces) == 1 and pieces.excess == 0.0
    assert len(convex_pieces(BIN)) > 2  # a bin is not convex


@settings(max_examples=4, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_batched_check_never_calls_a_touching_configuration_free(seed):
    scene, points = mesh_scene(seed)
    Q = near_configurations(scene, seed)
    for clearance in (0.0, 0.02):
        free = scene.collision_free(Q, clearance)
        for q in Q[free]:
            assert REFERENCE(q, points) >= clearance - 1e-9
    model = scene.batch_min_distance(Q)
    for q, m in zip(Q[:60], model[:60]):
        sampled = REFERENCE(q, points)  # >= the exact distance to the surface
        assert m <= sampled + 1e-9
        assert scene.min_distance(q) <= sampled + 1e-9  # the exact distance is not optimistic
        if m >= 0:
            assert scene.min_distance(q) >= m - 1e-9


@settings(max_examples=3, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_certified_segments_hold_under_dense_sampling(seed):
    scene, points = mesh_scene(seed)
    check_certified_segments(scene, points, 0.0, seed)


def test_distances_one_pair_per_link_and_mesh():
    scene, points = mesh_scene(5)
    q = near_configurations(scene, 5, 2)[0]
    pairs = scene.distances(q)
    geometries = len(scene._robot_ids)
    assert len(convex_pieces(BIN)) > 2
    for name in ("bin", "bracket"):  # one pair per link geometry, not one per piece
        assert 0 < sum(p.other == name for p in pairs) <= geometries
    assert min(p.distance for p in pairs) == pytest.approx(scene.min_distance(q), abs=1e-12)
    per_obstacle = scene.batch_obstacle_distances(q.reshape(1, -1))
    assert per_obstacle.shape == (1, 2)


def test_moving_mesh_is_checked_where_it_will_be():
    scene = Scene(PANDA)
    scene.add("bracket", BRACKET, [0.6, 0.0, 0.5], velocity=[0.0, 0.0, -0.2])
    q = np.zeros(PANDA.nq)
    before = scene.batch_min_distance(q.reshape(1, -1))[0]
    scene.step(1.0)
    assert scene.obstacles["bracket"].position[2] == pytest.approx(0.3)
    after = scene.batch_min_distance(q.reshape(1, -1))[0]
    assert before != after


def test_failed_add_changes_nothing(monkeypatch, tmp_path):
    scene = Scene(PANDA)
    scene.add("box", Box(0.1, 0.1, 0.1), [0.5, 0, 0.5])
    count = PANDA.scene_graph.get_query_output_port().Eval(scene._sg_context).inspector().num_geometries()
    before = scene.obstacle_arrays
    with pytest.raises(SceneError):
        scene.add("box", BIN, [0, 0, 0])  # duplicate name
    with pytest.raises(SceneError):
        scene.add("bin", BIN, [0, 0, np.nan])
    import coacd

    def broken(*args, **kwargs):
        raise RuntimeError("decomposition failed")

    monkeypatch.setattr(coacd, "run_coacd", broken)
    fresh = tmp_path / "bracket.obj"  # new bytes: not in the cache
    fresh.write_text((DATA / "bracket.obj").read_text() + "# another file\n")
    with pytest.raises(ObstacleFileError, match="no convex decomposition"):
        scene.add("bin", Mesh(fresh), [0, 0, 0])
    after = PANDA.scene_graph.get_query_output_port().Eval(scene._sg_context).inspector().num_geometries()
    assert after == count and list(scene.obstacles) == ["box"]
    assert scene.obstacle_arrays is before
