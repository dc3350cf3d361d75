"""Scene.from_file / Scene.load / Scene.save end to end: the same cell in every format gives the
same distances, save -> load is exact, and a failed load leaves the scene as it was."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import SceneFileError, SceneFileNotFound
from drake_mh.geometry import PointCloud
from drake_mh.scene import Obstacle, Scene, Sphere
from drake_mh.scene.files import SceneFile, add_to_scene, read_scene

DATA = Path(__file__).resolve().parents[2] / "data"
SCENES = DATA / "scenes"
PANDA = drake_mh.load_robot("panda")
Q = PANDA.random_configurations(30, 11)

#: file -> {our name in cell.yaml: the file's name} for the cell's four obstacles
SAME_CELL = {
    "cell.sdf": {"table": "table::board", "ball": "ball::sphere", "post": "post::cylinder", "rail": "rail::capsule"},
    "cell.urdf": {"table": "test_cell::board", "ball": "test_cell::sphere", "post": "test_cell::cylinder",
                  "rail": "test_cell::capsule"},
    "curobo_world.yml": {k: k for k in ("table", "ball", "post", "rail")},
    "cell.scene": {k: k for k in ("table", "ball", "post")},
}


def _per_obstacle(scene, q) -> dict:
    out: dict = {}
    for pair in scene.distances(q):
        out[pair.other] = min(out.get(pair.other, np.inf), pair.distance)
    return out


@pytest.fixture(scope="module")
def cell():
    return Scene.from_file(SCENES / "cell.yaml", PANDA)


@pytest.mark.parametrize("file", list(SAME_CELL))
def test_the_same_cell_in_every_format_gives_the_same_distances(cell, file):
    other = Scene.from_file(SCENES / file, PANDA)
    for q in Q:
        ours, theirs = _per_obstacle(cell, q), _per_obstacle(other, q)
        for name, their_name in SAME_CELL[file].items():
            assert theirs[their_name] == pytest.approx(ours[name], abs=1e-12)


def test_save_then_load_gives_the_same_scene(cell, tmp_path):
    files = cell.save(tmp_path / "saved.yaml")
    assert files == [tmp_path / "saved.yaml"]
    again = Scene.from_file(files[0], PANDA)
    assert list(again.obstacles) == list(cell.obstacles)
    for name, before in cell.obstacles.items():
        after = again.obstacles[name]
        assert after.shape == before.shape
        np.testing.assert_array_equal(after.X_WO[:3, 3], before.X_WO[:3, 3])
        np.testing.assert_allclose(after.X_WO[:3, :3], before.X_WO[:3, :3], rtol=0, atol=2e-15)
        np.testing.assert_array_equal(after.velocity_W, before.velocity_W)
    np.testing.assert_allclose(again.exact_min_distance(Q), cell.exact_min_distance(Q), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(again.collision_free(Q), cell.collision_free(Q))


def test_from_file_takes_the_scene_options_and_load_adds_to_a_scene():
    scene = Scene.from_file(SCENES / "planning_scene.yaml", PANDA, self_collision=True)
    assert scene.self_collision and list(scene.obstacles) == ["shelf_0", "shelf_1", "can"]
    added = scene.load(SCENES / "cell_old.scene")
    assert added == ["ball", "table"] and len(scene.obstacles) == 5
    assert scene.load(read_scene(SCENES / "cell.dmd.yaml")) == ["table::board", "ball::sphere"]  # a SceneFile


def _state(scene):
    return ({name: (o.shape, o.X_WO.copy(), o.velocity_W.copy()) for name, o in scene.obstacles.items()},
            scene.exact_min_distance(Q), scene.collision_free(Q))


def _assert_unchanged(scene, state):
    obstacles, exact, free = state
    assert list(scene.obstacles) == list(obstacles)
    for name, (shape, X, v) in obstacles.items():
        assert scene.obstacles[name].shape == shape
        np.testing.assert_array_equal(scene.obstacles[name].X_WO, X)
        np.testing.assert_array_equal(scene.obstacles[name].velocity_W, v)
    np.testing.assert_array_equal(scene.exact_min_distance(Q), exact)
    np.testing.assert_array_equal(scene.collision_free(Q), free)


def test_a_failed_load_changes_nothing(tmp_path):
    scene = Scene(PANDA)
    scene.add("keep", Sphere(0.1), [0.4, 0.0, 0.5])
    state = _state(scene)
    bad = tmp_path / "bad.yaml"  # the last entry is wrong: nothing of the file may stay
    bad.write_text((SCENES / "cell.yaml").read_text() + "  - {name: late, shape: sphere, radius: 0, position: [0, 0, 0]}\n")
    with pytest.raises(SceneFileError, match=r"obstacle 5 \('late'\)"):
        scene.load(bad)
    _assert_unchanged(scene, state)
    clash = tmp_path / "clash.yaml"
    clash.write_text("obstacles:\n  - {name: other, shape: sphere, radius: 0.1, position: [1, 1, 1]}\n"
                     "  - {name: keep, shape: sphere, radius: 0.1, position: [1, 1, 1]}\n")
    with pytest.raises(SceneFileError, match=r"the scene already has obstacle\(s\) named \['keep'\]"):
        scene.load(clash)
    _assert_unchanged(scene, state)
    moving = SceneFile("moving.yaml", "planning_scene", read_scene(SCENES / "cell.yaml").obstacles,
                       {"rail": "panda_link4"})
    with pytest.raises(SceneFileError, match="moves with the joints"):
        scene.load(moving)
    _assert_unchanged(scene, state)
    with pytest.raises(SceneFileNotFound):
        scene.load(tmp_path / "missing.sdf")
    _assert_unchanged(scene, state)


def test_an_obstacle_refused_midway_is_rolled_back():
    """The scene refuses the third obstacle after adding two: both are removed again."""
    scene = Scene(PANDA)
    scene.add("keep", Sphere(0.1), [0.4, 0.0, 0.5])
    state = _state(scene)
    good = read_scene(SCENES / "cell.yaml").obstacles[:2]
    refused = Obstacle("refused", "not a shape", np.eye(4), np.zeros(3))
    with pytest.raises(SceneFileError, match=r"mix\.yaml, obstacle 'refused': the scene refuses it") as err:
        add_to_scene(scene, SceneFile("mix.yaml", "drake_mh", (*good, refused)))
    assert isinstance(err.value.__cause__, drake_mh.errors.SceneError)
    _assert_unchanged(scene, state)


# --- meshes and point clouds: Scene.add takes them on the branch that adds them ------------------



@pytest.mark.parametrize("file, options", [
    pytest.param("cell_mesh_cloud.yaml", {}),
    pytest.param("cell_mesh.sdf", {}),
    pytest.param("cell_mesh.urdf", {"packages": {"cell_meshes": str(DATA)}}),
    pytest.param("cell_mesh.scene", {}),
    pytest.param("planning_scene_mesh.yaml", {}),
    pytest.param("curobo_mesh.yml", {}),
])
def test_files_with_meshes_and_clouds_load(file, options):
    expected = read_scene(SCENES / file, **options)
    scene = Scene.from_file(SCENES / file, PANDA, **options)
    assert list(scene.obstacles) == expected.names
    for obstacle in expected.obstacles:
        loaded = scene.obstacles[obstacle.name]
        np.testing.assert_allclose(loaded.X_WO, obstacle.X_WO, rtol=0, atol=1e-15)
        if isinstance(obstacle.shape, PointCloud):
            np.testing.assert_array_equal(loaded.shape.points, obstacle.shape.points)
        else:
            assert loaded.shape == obstacle.shape
    assert np.all(np.isfinite(scene.exact_min_distance(Q[:3])))


def test_save_then_load_with_meshes_and_clouds(tmp_path):
    scene = Scene.from_file(SCENES / "cell_mesh_cloud.yaml", PANDA)
    files = scene.save(tmp_path / "saved.yaml")
    again = Scene.from_file(files[0], PANDA)
    assert list(again.obstacles) == list(scene.obstacles) and len(files) == 3  # two clouds beside the YAML
    np.testing.assert_allclose(again.exact_min_distance(Q[:5]), scene.exact_min_distance(Q[:5]), rtol=0, atol=1e-12)
